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
 * stage enabled; alarm = the drive's code (0 none).
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
	/* tick -> bus */
	int32_t cmd_cps;
	bool cmd_enable;
	uint32_t reset_req;
	/* bus -> tick */
	int32_t pos;
	uint16_t status, alarm;
	bool fresh;
	uint32_t failures; /* cycles whose reads failed */
	/* bus thread only */
	bool silent;             /* last cycle failed: probe only */
	uint64_t next_probe_us;
	bool enable_sent_ok;
	bool enable_sent;
	uint32_t reset_done;
} mb_drive_t;

typedef struct {
	bk_modbus_bus_t cfg;
	void *ctx; /* modbus_t */
	pthread_t th;
	pthread_mutex_t mu;
	bool running;
	volatile bool stop;
	mb_drive_t d[VS_MAX_AXES];
	unsigned nd;
	uint32_t requests, retries, errors; /* under mu */
	uint32_t cur_retries;               /* bus thread: retries of this drive */
} mb_bus_t;

/* Opens the port (8 data bits). -1 with a message. */
int mb_bus_open(mb_bus_t *b, const bk_modbus_bus_t *cfg, char *err, size_t errlen);
/* Before mb_bus_start; returns the drive's index on the bus. */
unsigned mb_bus_add(mb_bus_t *b, uint8_t unit);
int mb_bus_start(mb_bus_t *b, char *err, size_t errlen);
/* Stops the thread, then servo off and speed 0 to every drive (best effort). */
void mb_bus_close(mb_bus_t *b);

void mb_drive_set_velocity(mb_bus_t *b, unsigned i, int32_t cps_q8);
void mb_drive_enable(mb_bus_t *b, unsigned i, bool on);
void mb_drive_reset_fault(mb_bus_t *b, unsigned i);
void mb_drive_read(mb_bus_t *b, unsigned i, hal_drive_state_t *st);

#endif
