/* Modbus RTU master for a microcontroller: one request at a time, advanced
 * by polls from the main loop, never waiting on the line.
 *
 * Two layers, plain C without libc (the board image and the host tests
 * build the same file):
 *
 *  - mbm_*: the RTU link. A request is framed (address, function, data,
 *    CRC-16 low byte first), sent after the line has been silent for the
 *    3.5-character gap, with the RS-485 driver enabled from the first byte
 *    until the last has left the shift register (port->tx_done). The reply
 *    is taken byte by byte as it comes: complete at the length its function
 *    and first bytes announce; no first byte within timeout_us is a
 *    timeout, a reply that stops for byte_us is cut. Address, function,
 *    byte count, the echo of a write and the CRC are checked; an exception
 *    reply gives its code. A failed attempt is retried (retries times)
 *    after the line has been silent for the byte timeout (a late answer is
 *    read and dropped, never paired with the next request); exceptions 1
 *    and 2 (illegal function, illegal address) are not retried: the answer
 *    will not change.
 *
 *  - mbd_*: a bus of wheel drives on the profile of hal/modbus/mbprofile.h,
 *    with vehicle-fw's cycle (hal/linux/modbus_drive.h): per drive, set-up
 *    (init registers and the comm_timeout register) until done, a fault
 *    reset when asked, the enable when it changes, the target speed, then
 *    position, status and alarm in as few reads as the profile's block
 *    allows; the tick takes the latest sample (mbd_read). A drive whose
 *    cycle gets no reply is only probed every MBD_PROBE_US, one attempt,
 *    so that it does not hold up the others. Reported state as on Linux:
 *    fresh once per sample, HAL_SILENT_BUSY after exception 6,
 *    HAL_SILENT_MAP after 1 or 2 (the firmware's 202 and 213).
 *
 * Time is a free-running microsecond count (wraps; compared by
 * difference). Cost per poll: at most one frame built or MBM_ADU_MAX bytes
 * read and checked.
 */
#ifndef HAL_MODBUS_MBMASTER_H
#define HAL_MODBUS_MBMASTER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "../hal.h"
#include "mbprofile.h"

/* The longest frame: a read of MBM_READ_MAX registers (5 + 2n bytes). */
#define MBM_READ_MAX 16
#define MBM_ADU_MAX  (5 + 2 * MBM_READ_MAX)

/* How a request ended (mbm_poll, mbm_check). */
enum {
	MBM_BUSY = 0,	 /* under way */
	MBM_OK,		 /* a good reply */
	MBM_NO_REPLY,	 /* nothing within timeout_us */
	MBM_CUT,	 /* the reply stopped for byte_us before its end */
	MBM_CRC,	 /* a whole reply with a bad CRC */
	MBM_BAD,	 /* another address, function, count or echo */
	MBM_EXCEPTION,	 /* an exception reply (code in exc) */
	MBM_MORE = 0x7F, /* mbm_check: not complete yet */
};

typedef struct {
	/* The bytes received since the last call, at most max; never blocks. */
	size_t (*read)(void *ctx, uint8_t *buf, size_t max);
	/* Queues a whole frame for the transmitter (the port holds n bytes). */
	void (*write)(void *ctx, const uint8_t *buf, size_t n);
	/* Every byte written has left the line (shift register empty). */
	bool (*tx_done)(void *ctx);
	/* The RS-485 transceiver's driver enable. */
	void (*de)(void *ctx, bool on);
	void *ctx;
} mbm_port_t;

/* A board whose port is its own (-DMBM_PORT_DIRECT, mk/cortexm.mk) has
 * these, the calls of mbm_port_t without ctx: the master calls them
 * directly (mbm_init's port unused). */
#ifdef MBM_PORT_DIRECT
size_t mbm_port_read(uint8_t *buf, size_t max);
void mbm_port_write(const uint8_t *buf, size_t n);
bool mbm_port_tx_done(void);
void mbm_port_de(bool on);
#endif

typedef struct {
	uint32_t requests, retries, timeouts, crc_errors, bad, exceptions, busy, illegal;
} mbm_count_t;

typedef struct {
	mbm_count_t cnt; /* first: a monitor reads it at the struct's address */
	const mbm_port_t *port;
	uint32_t gap_us, timeout_us, byte_us;
	uint32_t quiet_us; /* silence before the next attempt: gap, or byte_us after a failure */
	uint8_t retries;
	uint8_t state, attempt, exc;
	/* the request's bytes (its reply is checked against tx), the reply's */
	uint8_t txn, rxn;
	uint32_t t_line; /* last byte on the line, or the start of the wait */
	uint8_t tx[MBM_ADU_MAX];
	uint8_t rx[MBM_ADU_MAX];
} mbm_t;

/* One character time on the line (start, 8 data, parity, stop bits), us. */
uint32_t mbm_char_us(uint32_t baud, uint32_t frame_bits);
/* CRC-16 of Modbus (poly 0xA001 reflected, init 0xFFFF). */
uint16_t mbm_crc(const uint8_t *b, size_t n);
/* A reply's bytes at most that far apart: 4 characters, at least
 * MBM_BYTE_MIN_US (vehicle-fw's rule too, hal/linux/modbus_drive.c). */
#define MBM_BYTE_MIN_US 5000u
uint32_t mbm_byte_us(uint32_t baud, uint32_t frame_bits);
/* The silence before a frame: 3.5 characters, fixed at 1750 us above 19200
 * baud (as the standard says). One formula for the master and the cycle. */
#define MBM_GAP_US(baud, bits)                                                                     \
	((baud) > 19200u ? 1750u : (7u * (((bits)*1000000u + (baud)-1u) / (baud)) + 1u) / 2u)
/* gap: MBM_GAP_US; byte_us: mbm_byte_us. The line is taken as silent since
 * now. */
void mbm_init(mbm_t *m, const mbm_port_t *port, uint32_t baud, uint32_t frame_bits,
	      uint32_t timeout_us, uint8_t retries, uint32_t now_us);
/* Starts a request (only when none is under way: false otherwise). Read:
 * function 03 (holding) or 04 (input), n registers (1..MBM_READ_MAX).
 * Write: 06 for one register, 16 for two. */
bool mbm_read(mbm_t *m, uint8_t unit, bool input, uint16_t addr, uint8_t n);
bool mbm_write(mbm_t *m, uint8_t unit, uint16_t addr, uint8_t n, const uint16_t *w);
/* Advances the request; MBM_BUSY while under way, then its result (once;
 * then idle). */
uint8_t mbm_poll(mbm_t *m, uint32_t now_us);
/* Register i of the last good read reply. */
uint16_t mbm_reg(const mbm_t *m, unsigned i);
/* A reply so far (rx, n bytes) to the request (unit, fc, addr, qty): MBM_MORE
 * while shorter than its function says, else MBM_OK, MBM_CRC, MBM_BAD or
 * MBM_EXCEPTION (*exc: the code). tx: the request as sent (a write's echo). */
uint8_t mbm_check(const uint8_t *tx, const uint8_t *rx, size_t n, uint8_t *exc);

/* ---- the drive bus ------------------------------------------------------ */

#define MBD_DRIVES   4
#define MBD_PROBE_US 200000u
/* What mbd_check allows a drive to take before its answer starts. */
#define MBD_TURNAROUND_US 1000u

typedef struct {
	uint8_t unit, ch;
	bool reverse;
	/* tick -> bus */
	int32_t cmd_cps;
	bool cmd_enable;
	uint8_t reset_req;
	/* bus -> tick */
	mbp_sample_t s;
	/* bus only */
	bool silent, setup_done, enable_ok, enable_sent;
	uint8_t reset_done;
	uint32_t probe_at, last_ok_us;
	uint32_t samples, failures;
} mbd_drive_t;

typedef struct {
	/* first, for a monitor (tests/mcu/mcu_drives.py): the drive cycle's
	 * last and worst period, how many, when the current one began */
	uint32_t cycle_us, cycle_worst_us, cycles, cycle_start;
	mbm_t m;
	const mb_profile_t *prof;
	uint32_t comm_timeout_ms; /* 0: the drives' own stop is not set */
	mbd_drive_t d[MBD_DRIVES];
	uint8_t nd, cur, step, sub, retries;
	uint16_t val[MBP_REG_COUNT][2];
} mbd_bus_t;

/* A board whose drives' profile is compiled in names that constant object
 * (-DMBD_PROFILE=name, mk/cortexm.mk) and hands it to mbd_init: the bus
 * then reads the profile as constants (0.46 KiB less flash). */
#ifdef MBD_PROFILE
extern const mb_profile_t MBD_PROFILE;
#endif

/* The drive cycle when every drive answers, us: each drive's speed write
 * and sample reads at baud, each request after the gap the master waits
 * (MBM_GAP_US) and turnaround_us for the drive to start its answer. */
uint32_t mbd_cycle_us(const mb_profile_t *p, unsigned ndrives, uint32_t baud, uint32_t frame_bits,
		      uint32_t turnaround_us);
/* The same at compile time, for a board whose drives all take the same
 * requests: half-characters and requests per drive (the generic profile:
 * a 16 write of 13 bytes and its 8, a 03 read of 8 and its 13:
 * MBD_GENERIC_HALFCHARS, MBD_GENERIC_REQUESTS). */
#define MBD_CYCLE_US(nd, half, reqs, baud, bits, turn_us)                                          \
	((uint32_t)(((uint64_t)(nd) * (half) * (bits)*1000000u + (uint64_t)2u * (baud)-1u) /       \
		    ((uint64_t)2u * (baud))) +                                                     \
	 (nd) * (reqs) * ((turn_us) + MBM_GAP_US(baud, bits)))
#define MBD_GENERIC_HALFCHARS 84u
#define MBD_GENERIC_REQUESTS  2u
/* The rule of mbd_check: one cycle and a request that fails with every
 * retry fit within the drive timeout twice over. */
#define MBD_LINE_OK(cycle_us, timeout_us, retries, drive_timeout_ms)                               \
	(2u * ((uint64_t)(cycle_us) + (uint64_t)(timeout_us) * (1u + (retries))) <=                \
	 (uint64_t)(drive_timeout_ms)*1000u)
/* NULL when the line carries the cycle: one cycle and a request that fails
 * with every retry fit within the firmware's drive timeout twice over;
 * else why not. */
const char *mbd_check(const mb_profile_t *p, unsigned ndrives, uint32_t baud, uint32_t frame_bits,
		      uint32_t timeout_us, uint8_t retries, uint32_t drive_timeout_ms);
void mbd_init(mbd_bus_t *b, const mb_profile_t *p, const mbm_port_t *port, uint32_t baud,
	      uint32_t frame_bits, uint32_t timeout_us, uint8_t retries, uint32_t now_us);
/* Adds a drive (unit id, channel, polarity reverse); its index. */
unsigned mbd_add(mbd_bus_t *b, uint8_t unit, uint8_t ch, bool reverse);
/* Advances the cycle; call between ticks as often as the loop can. */
void mbd_poll(mbd_bus_t *b, uint32_t now_us);

/* The tick's side, as hal/linux/modbus_drive.c: vs_hal_ops_t's drive
 * calls on ctx, an mbd_bus_t (axis: the drive's index, below nd). */
void mbd_set_velocity(void *ctx, uint8_t axis, int32_t cps_q8);
void mbd_enable(void *ctx, uint8_t axis, bool on);
void mbd_reset_fault(void *ctx, uint8_t axis);
void mbd_read(void *ctx, uint8_t axis, hal_drive_state_t *st);

/* A frame writing enable_off to drive i, for a fault handler that sends it
 * by polling the UART; its length. */
size_t mbd_off_frame(const mbd_bus_t *b, unsigned i, uint8_t *f);

#endif
