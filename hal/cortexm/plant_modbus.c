/* Wheel drives over RS-485 Modbus RTU on the board's second UART (CMSDK
 * UART1 on MPS2); see plant.h and hal/modbus/mbmaster.h.
 *
 * The line: 115200 baud, 8 data bits, no parity, 1 stop bit (the CMSDK
 * UART's only frame; set your drives so, or use a part whose UART has
 * parity for 8E1). The RS-485 transceiver's driver enable is FPGAIO LED0
 * bit 0; bit 1 is the drives' power line (the relay of setPower, and what a
 * fault handler drops first). Drives: units 1 and 2 (differential), 1 to 4
 * (mecanum), the generic profile (hal/modbus/mbprofile.c, the map of
 * mbdrive-sim), its communication-loss stop at 0x109 (u16, ms) set to
 * MB_COMM_STOP_MS so that a drive stops by itself when the board falls
 * silent.
 *
 * The cycle, when every drive answers: per drive a target-speed write
 * (function 16, 13 bytes, 8 back) and one read of position, status and
 * alarm (03, 8 bytes, 13 back): 42 characters of 86.8 us, and before each
 * request the 1750 us gap (MBM_GAP_US) and MBD_TURNAROUND_US for its
 * answer to start: 9.1 ms a drive, 18.3 ms for two, 36.6 ms for four
 * (mbd_cycle_us; docs/mcu.md). Each request waits MB_TIMEOUT_US for its
 * answer and is tried MB_RETRIES more times; the firmware's drive timeout
 * is MB_DRIVE_TIMEOUT_MS, and the build refuses a line that cannot fit a
 * cycle and a failed request twice in it (MBD_LINE_OK, mbd_check's rule).
 */

#include "../modbus/mbmaster.h"
#include "board.h"
#include "plant.h"
#include "wdog.h"

#ifndef BOARD_MB_UART_BASE
#define BOARD_MB_UART_BASE 0x40005000u /* CMSDK UART1 */
#endif
#ifndef BOARD_MB_BAUD
#define BOARD_MB_BAUD 115200u
#endif
#define MB_FRAME_BITS 10u /* start, 8 data, stop */
/* Per request: the answer's first byte within MB_TIMEOUT_US, its bytes at
 * most MB_BYTE_US apart, MB_RETRIES more attempts; the firmware's drive
 * timeout. Generous for a drive (which answers within a few ms) because
 * QEMU's emulated UART hands a reply to the core in bursts up to 5 ms
 * apart and starts it up to 50 ms late in the board's time; a port to a
 * part may take mbm_byte_us (4 characters, at least 5 ms) and some 20 ms.
 * The QEMU bench's test image, whose peers run on a loaded host, takes
 * longer ones (mk/cortexm.mk: MCU_TEST_DEFS). */
#ifndef BOARD_MB_TIMEOUT_US
#define BOARD_MB_TIMEOUT_US 100000u
#endif
#ifndef BOARD_MB_BYTE_US
#define BOARD_MB_BYTE_US 20000u
#endif
#ifndef BOARD_MB_RETRIES
#define BOARD_MB_RETRIES 1u
#endif
#ifndef BOARD_MB_DRIVE_TIMEOUT_MS
#define BOARD_MB_DRIVE_TIMEOUT_MS 500u
#endif
#define MB_TIMEOUT_US	    BOARD_MB_TIMEOUT_US
#define MB_BYTE_US	    BOARD_MB_BYTE_US
#define MB_RETRIES	    BOARD_MB_RETRIES
#define MB_DRIVE_TIMEOUT_MS BOARD_MB_DRIVE_TIMEOUT_MS
/* The drives' own stop when the board falls silent: the drive timeout (a
 * silent drive's probe costs the others MB_TIMEOUT_US a cycle). */
#define MB_COMM_STOP_MS MB_DRIVE_TIMEOUT_MS
#define MB_START_US	1000000u
#define MB_DRIVES	(VS_KIN_ONLY == 1 ? 4u : 2u)
/* The line must carry the cycle (mbd_check's rule, at build time: the
 * configuration is compiled in). */
#define MB_CYCLE_US                                                                                \
	MBD_CYCLE_US(MB_DRIVES, MBD_GENERIC_HALFCHARS, MBD_GENERIC_REQUESTS, BOARD_MB_BAUD,        \
		     MB_FRAME_BITS, MBD_TURNAROUND_US)
_Static_assert(MBD_LINE_OK(MB_CYCLE_US, MB_TIMEOUT_US, MB_RETRIES, MB_DRIVE_TIMEOUT_MS),
	       "the line does not carry the drive cycle: a cycle and a failed request must fit "
	       "twice in the drive timeout");
#define FPGAIO_LED (*(volatile uint32_t *)0x40028000u)
#define LED_DE	   1u
#define LED_POWER  2u

typedef struct {
	volatile uint32_t data;
	volatile uint32_t state; /* bit 0: TX full, bit 1: RX full */
	volatile uint32_t ctrl;	 /* bit 0: TX enable, bit 1: RX enable */
	volatile uint32_t intstatus;
	volatile uint32_t bauddiv;
} cmsdk_uart_t;

#define MBU	   ((cmsdk_uart_t *)BOARD_MB_UART_BASE)
#define ST_TX_FULL 1u
#define ST_RX_FULL 2u

/* The generic profile with its communication-loss stop (u16, ms), compiled
 * in: the master reads it as constants (MBD_PROFILE, mk/cortexm.mk). */
const mb_profile_t board_mb_profile = MBP_GENERIC(1);
static const uint8_t *tx_buf; /* the master's frame: it stays put until sent */
static uint8_t tx_n, tx_at;

/* What the master costs a pass of the main loop, in cycles (the drive
 * cycle's period and the bus's counters are in mbd_bus_t): read through the
 * monitor, as board_cost (tests/mcu/mcu_drives.py). */
typedef struct {
	uint32_t polls, poll_worst;
	uint32_t fault_tick; /* the unit's tick that first found a fault active (0: not yet) */
} plant_cost_t;
volatile plant_cost_t plant_cost;
static const vehicle_t *unit;
mbd_bus_t plant_bus;

/* The master's port, called directly (MBM_PORT_DIRECT, mbmaster.h). The
 * board suite's relay stops the board where p_read and p_de begin, p_de's
 * on in r1 (tests/mcu/mcu_drives.py): those two stay functions of their
 * own under those names, with the port's arguments (noipa). */
static __attribute__((noipa)) size_t p_read(void *ctx, uint8_t *buf, size_t max)
{
	(void)ctx;
	size_t n = 0;
	while (n < max && (MBU->state & ST_RX_FULL))
		buf[n++] = (uint8_t)MBU->data;
	return n;
}

size_t mbm_port_read(uint8_t *buf, size_t max)
{
	return p_read(NULL, buf, max);
}

void mbm_port_write(const uint8_t *buf, size_t n)
{
	tx_buf = buf;
	tx_n = (uint8_t)n;
	tx_at = 0;
}

/* Moves what the transmitter takes; done when all has gone and the
 * transmitter is empty (a part with a transmission-complete flag tests
 * that: the driver must stay on until the stop bit is out). */
bool mbm_port_tx_done(void)
{
	while (tx_at < tx_n && !(MBU->state & ST_TX_FULL))
		MBU->data = tx_buf[tx_at++];
	return tx_at == tx_n && !(MBU->state & ST_TX_FULL);
}

static __attribute__((noipa)) void p_de(void *ctx, bool on)
{
	(void)ctx;
	FPGAIO_LED = on ? FPGAIO_LED | LED_DE : FPGAIO_LED & ~LED_DE;
}

void mbm_port_de(bool on)
{
	p_de(NULL, on);
}

static uint32_t now_us(void)
{
	return systick_us();
}

static bool m_power_set(void *ctx, bool on)
{
	(void)ctx;
	FPGAIO_LED = on ? FPGAIO_LED | LED_POWER : FPGAIO_LED & ~LED_POWER;
	return true;
}

/* No feedback contact on this board: the line as driven. */
static bool m_power_feedback(void *ctx)
{
	(void)ctx;
	return (FPGAIO_LED & LED_POWER) != 0;
}

static bool m_io(void *ctx, uint32_t ioid, uint32_t *value)
{
	(void)ctx;
	(void)ioid;
	(void)value;
	return false;
}

static bool m_io_write(void *ctx, uint32_t ioid, uint32_t value)
{
	(void)ctx;
	(void)ioid;
	(void)value;
	return false;
}

/* No battery sensing on this board: a constant 24.0 V (a port reads its
 * ADC or the drives' bus voltage register here). */
static uint32_t m_battery_mv(void *ctx)
{
	(void)ctx;
	return 24000u;
}

static const vs_hal_ops_t ops = {
    .drive_set_velocity = mbd_set_velocity,
    .drive_enable = mbd_enable,
    .drive_read = mbd_read,
    .drive_reset_fault = mbd_reset_fault,
    .power_set = m_power_set,
    .power_feedback = m_power_feedback,
    .io_read = m_io,
    .io_write = m_io_write,
    /* no discrete inputs, no joystick: the image is built without them
     * (-DVS_NO_INPUTS, -DVS_NO_JOYSTICK) and never calls these */
    .contact = NULL,
    .obstacle = NULL,
    .obstacle_caution = NULL,
    .estop = NULL,
    .joystick = NULL,
    .battery_mv = m_battery_mv,
};

void plant_config(vs_config_t *cfg)
{
	cfg->drive_timeout_ms = MB_DRIVE_TIMEOUT_MS;
}

vs_hal_t plant_hal(const vs_config_t *cfg)
{
	MBU->bauddiv = BOARD_CPU_HZ / BOARD_MB_BAUD;
	MBU->ctrl = 3u;
	FPGAIO_LED = 0;
	mbd_init(&plant_bus, &board_mb_profile, NULL, BOARD_MB_BAUD, MB_FRAME_BITS, MB_TIMEOUT_US,
		 MB_RETRIES, now_us());
	plant_bus.comm_timeout_ms = MB_COMM_STOP_MS;
	plant_bus.m.byte_us = MB_BYTE_US;
	for (unsigned i = 0; i < MB_DRIVES; i++)
		mbd_add(&plant_bus, (uint8_t)(i + 1u), 0, false);
	/* The drives' counts before the firmware starts (vehicle_init reads
	 * them as its origin): a drive keeps counting across the board's reset,
	 * and its count must not read as a move. At most MB_START_US; a drive
	 * silent so long is the firmware's 202 once powered. */
	systick_init(cfg->tick_hz);
	uint32_t t0 = now_us();
	for (unsigned i = 0; i < MB_DRIVES && now_us() - t0 < MB_START_US;)
		if (plant_bus.d[i].s.sampled)
			i++;
		else
			mbd_poll(&plant_bus, now_us());
	return (vs_hal_t){&ops, &plant_bus};
}

void plant_start(vehicle_t *v)
{
	unit = v;
	char s[VS_ALARM_SOURCE_MAX];
	if (wdog_restart_text(s, sizeof s))
		alarm_raise(&v->alarms, ALM_W_RESTARTED, s);
}

void plant_tick(void)
{
	wdog_feed();
	if (!plant_cost.fault_tick && alarm_any_fault(&unit->alarms))
		plant_cost.fault_tick = unit->ticks;
}

void plant_poll(void)
{
	uint32_t t0 = systick_cycles();
	mbd_poll(&plant_bus, now_us());
	uint32_t c = systick_cycles() - t0;
	plant_cost.polls++;
	if (c > plant_cost.poll_worst)
		plant_cost.poll_worst = c;
}

bool plant_extra(void *ctx, int argc, char **argv, char *reply, size_t cap)
{
	(void)ctx;
	return board_test_extra && board_test_extra(argc, argv, reply, cap);
}

/* Polled, from a handler: each byte waits for the transmitter. */
static void gap(void)
{
	/* 2 ms at 3 instructions a turn at most: the gap, and the last
	 * character out of the shift register */
	for (volatile uint32_t k = 0; k < BOARD_CPU_HZ / 3u / 500u; k++)
		;
}

static void send_now(const uint8_t *f, size_t n)
{
	gap(); /* after a frame the master may have left half sent */
	FPGAIO_LED |= LED_DE;
	for (size_t i = 0; i < n; i++) {
		while (MBU->state & ST_TX_FULL)
			;
		MBU->data = f[i];
	}
	while (MBU->state & ST_TX_FULL)
		;
	gap();
	FPGAIO_LED &= ~LED_DE;
}

void plant_emergency_off(void)
{
	uint8_t f[MBM_ADU_MAX];
	FPGAIO_LED &= ~LED_POWER;
	for (unsigned i = 0; i < plant_bus.nd; i++)
		send_now(f, mbd_off_frame(&plant_bus, i, f));
}
