/* Wheel drives over Modbus RTU (libmodbus), one thread per bus.
 *
 * The tick never touches the serial line: it posts setpoints and takes the
 * latest sample under a short priority-inheriting mutex. The bus thread
 * cycles over its drives: fault reset when requested, enable when it
 * changes, target speed (every cycle), then position, status and alarm
 * code (one read where the profile's block allows). The registers, their
 * form and the values written are the bus's drive profile
 * (hal/modbus/mbprofile.h); a unit id may carry several drives (channels).
 *
 * Timing: each request waits timeout_ms for the reply's first byte, then at
 * most the byte timeout between two bytes (byte_timeout_ms, or 4 character
 * times at the baud rate, at least 5 ms): a drive that stops mid-reply
 * costs that, not libmodbus's default 500 ms.
 *
 * Failures, by what came back:
 *  - nothing, a bad CRC, a malformed reply: retried (retries); a drive
 *    whose cycle fails so is then only probed every 200 ms (one attempt),
 *    so that it does not hold up the others; the firmware's drive timeout
 *    raises 202 "not answering".
 *  - exception 6 (busy): retried, and the next cycle tries again at once;
 *    still only busy after the drive timeout: 202 "not answering: busy".
 *  - exception 1 or 2 (illegal function or address): not retried, the
 *    register map does not match the drive; logged once with the function
 *    and register; after the drive timeout the firmware's 213.
 * Every request, retry, timeout, CRC error and exception is counted per
 * bus, and per drive (mb_bus_counters: `$rt`, the exit log).
 *
 * Start-up (mb_bus_start, before the loop): per drive the profile's init
 * registers and its comm_timeout register (the drive's own stop when its
 * master falls silent), unless the bus says comm_stop="none"; a drive that
 * refuses them ends the start with a message. They are written again when
 * a silent drive answers again (a drive that restarted forgot them).
 *
 * Reported state: enabled is the status register under the profile's mask
 * as last read, never the enable command; phase HAL_DRIVE_FAULT while the
 * alarm register is non-zero, else HAL_DRIVE_ENABLED when enabled, else
 * HAL_DRIVE_READY (the registers tell no more), HAL_DRIVE_UNKNOWN before
 * the first read. These registers give no sign of a drive that restarted:
 * position_lost is never set (a restarted drive's count jumps to its new
 * position register). Polarity reverse: the speed written and the position
 * read are negated here. The target speed written is 0 unless the enable is
 * commanded and the last status read says the stage is on (no step when it
 * comes on). An enable register shared by a unit's channels is written
 * enable_on only while every drive of that unit is commanded on.
 *
 * Battery (<battery source="modbus">): after each round of the drives, when
 * its period is due, the bus thread reads the battery register of its unit
 * (a drive's or a BMS of its own); the tick takes the latest value under the
 * mutex. A failed read keeps the last good value and is counted; while it
 * keeps failing the battery gets one attempt per period (no retries), so a
 * silent BMS costs the drives at most one timeout per period. Without a good
 * reading for MB_BATTERY_STALE_MS (since start or since the last good one)
 * the battery reads 0 mV: the charge is unknown, and the firmware's
 * critical-battery fault (207) stops the unit rather than let it drive on.
 * One lost reply is far inside that bound. The next good reply restores the
 * value (both transitions are logged).
 */
#ifndef HAL_LINUX_MODBUS_DRIVE_H
#define HAL_LINUX_MODBUS_DRIVE_H

#include <pthread.h>
#include <stdbool.h>
#include <stdint.h>

#include "../hal.h"
#include "../modbus/mbprofile.h"
#include "backend_cfg.h"

/* What went wrong on a bus or with one drive (bus thread, read under mu). */
typedef struct {
	uint32_t timeouts;   /* no reply, or a reply that stopped */
	uint32_t crc_errors; /* a reply with a bad CRC */
	uint32_t bad;	     /* another malformed or unexpected reply */
	uint32_t exceptions; /* exception replies, every code */
	uint32_t busy;	     /* of them: 6, busy */
	uint32_t illegal;    /* of them: 1 or 2, no such function or register */
} mb_count_t;

typedef struct {
	uint8_t unit;
	uint8_t ch;   /* channel of a multi-channel unit */
	bool reverse; /* polarity reverse: speed and position negated */
	/* tick -> bus */
	int32_t cmd_cps;
	bool cmd_enable;
	uint32_t reset_req;
	/* bus -> tick */
	mbp_sample_t s;
	uint32_t failures; /* cycles whose reads failed */
	mb_count_t cnt;
	/* bus thread only */
	bool silent; /* last cycle had no reply: probe only */
	bool setup_done;
	bool map_logged;
	uint64_t next_probe_us;
	bool enable_sent_ok;
	bool enable_sent;
	uint32_t reset_done;
} mb_drive_t;

#define MB_BATTERY_STALE_MS 2000u

typedef struct {
	bool used;
	bk_battery_modbus_t cfg;
	double scale; /* mV per raw count */
	/* bus -> tick */
	uint32_t mv;
	bool settled;	 /* a good reading, or the stale bound passed */
	uint32_t errors; /* failed reads */
	/* bus thread only */
	uint64_t due_us, good_us;
	bool failing, stale;
} mb_battery_t;

typedef struct {
	bk_modbus_bus_t cfg;
	void *ctx; /* modbus_t */
	pthread_t th;
	pthread_mutex_t mu;
	bool running;
	volatile bool stop;
	mb_drive_t d[VS_MAX_AXES];
	unsigned nd;
	mb_battery_t bat;
	uint32_t requests, retries, errors; /* under mu */
	mb_count_t cnt;			    /* under mu */
	uint32_t byte_timeout_us;
	uint32_t cur_retries; /* bus thread: retries of this drive */
	mb_drive_t *cur;      /* bus thread: the drive of this request, or NULL */
} mb_bus_t;

/* The byte timeout for a baud rate and frame (8 data bits): 4 character
 * times, at least 5 ms. */
uint32_t mb_byte_timeout_us(uint32_t baud, char parity, uint32_t stop_bits);
/* Opens the port (8 data bits). -1 with a message. */
int mb_bus_open(mb_bus_t *b, const bk_modbus_bus_t *cfg, char *err, size_t errlen);
/* Before mb_bus_start; returns the drive's index on the bus. ch: the
 * channel of a multi-channel unit; reverse: polarity reverse (speed and
 * position negated by the master). */
unsigned mb_bus_add(mb_bus_t *b, uint8_t unit, uint8_t ch, bool reverse);
/* Before mb_bus_start: this bus also reads the battery. */
void mb_bus_add_battery(mb_bus_t *b, const bk_battery_modbus_t *cfg, double scale_mv);
/* Writes each drive's init and comm_timeout registers, then starts the
 * thread. -1 with a message. */
int mb_bus_start(mb_bus_t *b, char *err, size_t errlen);
/* Start-up only (blocks): waits for the battery's first good reading, at
 * most MB_BATTERY_STALE_MS. */
void mb_battery_wait_first(mb_bus_t *b);
/* Stops the thread, then servo off and speed 0 to every drive (best effort). */
void mb_bus_close(mb_bus_t *b);

void mb_drive_set_velocity(mb_bus_t *b, unsigned i, int32_t cps_q8);
void mb_drive_enable(mb_bus_t *b, unsigned i, bool on);
void mb_drive_reset_fault(mb_bus_t *b, unsigned i);
void mb_drive_read(mb_bus_t *b, unsigned i, hal_drive_state_t *st);
/* The latest battery value in mV (0: no reading for MB_BATTERY_STALE_MS)
 * and the count of failed reads. */
uint32_t mb_battery_mv(mb_bus_t *b, uint32_t *errors);
/* "modbus<n> DEVICE requests N retries N timeouts N crc_errors N
 * bad_replies N exceptions N busy N illegal N", then per drive " unit<u>"
 * (" unit<u>.<channel>" on a multi-channel profile) and the same six
 * counts of its own. The length written. */
int mb_bus_counters(mb_bus_t *b, unsigned n, char *buf, size_t len);

#endif
