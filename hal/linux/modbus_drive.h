/* Wheel drives over Modbus RTU (libmodbus), one thread per bus.
 *
 * The tick never touches the serial line: it posts setpoints and takes the
 * latest sample under a short priority-inheriting mutex. The bus thread
 * cycles over its drives: fault reset when requested, servo_on when it
 * changes, target speed (every cycle), then position, status and alarm
 * code (one read when they lie within 8 registers). Each request has its own
 * response timeout and retries. A drive whose reads fail stops producing
 * fresh samples: the firmware's drive timeout supervision raises the fault
 * and stops the unit. A drive that failed is then only probed every 200 ms
 * (one attempt), so that it does not hold up the others on the bus.
 *
 * Registers (holding, backend_cfg.h): target speed counts/s and position
 * counts as int32 in two registers, high word first; status bit 0 = power
 * stage enabled; alarm = the drive's code (0 none). The target speed
 * written is 0 unless servo on is commanded and the last status read says
 * the stage is on (no step when it comes on).
 *
 * Reported state: enabled is status bit 0 as last read, never the servo on
 * command; phase HAL_DRIVE_FAULT while the alarm register is non-zero,
 * else HAL_DRIVE_ENABLED with bit 0, else HAL_DRIVE_READY (the registers
 * tell no more), HAL_DRIVE_UNKNOWN before the first read. These registers
 * give no sign of a drive that restarted: position_lost is never set (a
 * restarted drive's count jumps to its new position register). Polarity
 * reverse: the speed written and the position read are negated here.
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
#include "backend_cfg.h"

typedef struct {
	uint8_t unit;
	bool reverse; /* polarity reverse: speed and position negated */
	/* tick -> bus */
	int32_t cmd_cps;
	bool cmd_enable;
	uint32_t reset_req;
	/* bus -> tick */
	int32_t pos;
	uint16_t status, alarm;
	bool fresh;
	bool sampled;	   /* one read succeeded since start */
	uint32_t failures; /* cycles whose reads failed */
	/* bus thread only */
	bool silent; /* last cycle failed: probe only */
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
	uint32_t cur_retries;		    /* bus thread: retries of this drive */
} mb_bus_t;

/* Opens the port (8 data bits). -1 with a message. */
int mb_bus_open(mb_bus_t *b, const bk_modbus_bus_t *cfg, char *err, size_t errlen);
/* Before mb_bus_start; returns the drive's index on the bus. reverse:
 * polarity reverse (speed and position negated by the master). */
unsigned mb_bus_add(mb_bus_t *b, uint8_t unit, bool reverse);
/* Before mb_bus_start: this bus also reads the battery. */
void mb_bus_add_battery(mb_bus_t *b, const bk_battery_modbus_t *cfg, double scale_mv);
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

#endif
