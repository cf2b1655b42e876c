/* The Linux HAL of vehicle-fw: per-axis drive backends, GPIO lines, relay,
 * battery source, composed into one vs_hal_ops_t table.
 *
 * lhal_pre_tick() runs once per control period before vehicle_tick(): it
 * advances the software drives, exchanges the CANopen frames of the cia402
 * drives (cia402.h) and refreshes slow sources (the IIO battery channel
 * every 200 ms; the latest value of a Modbus battery, read by its bus
 * thread), so that the ops themselves stay constant-time.
 */
#ifndef HAL_LINUX_LHAL_H
#define HAL_LINUX_LHAL_H

#include <stdbool.h>
#include <stdint.h>

#include "../hal.h"
#include "backend_cfg.h"
#include "cia402.h"
#include "gpio.h"
#include "joystick.h"
#include "modbus_drive.h"

typedef struct {
	bool enabled;
	int32_t vel_q8; /* counts/s x256 */
	int32_t pos;	/* counts, wraps */
	int64_t rem;	/* position remainder, counts x256 x1e6 */
} lhal_loop_drive_t;

typedef struct {
	backend_cfg_t bk;
	uint8_t naxes;
	lgpio_t gpio;
	lhal_loop_drive_t loop[VS_MAX_AXES];
	mb_bus_t bus[BK_MODBUS_BUSES];
	uint8_t mb_index[VS_MAX_AXES]; /* modbus axis: its drive index on the bus */
	co_bus_t can[BK_CANOPEN_BUSES];
	uint8_t co_index[VS_MAX_AXES]; /* cia402 axis: its drive index on the bus */
	ljoy_t joy;
	bool relay_cmd;
	uint32_t battery_mv;
	uint32_t battery_errors; /* failed reads (iio, modbus) */
	uint32_t now_us, last_us, battery_due_us;
	bool have_now;
} lhal_t;

extern const vs_hal_ops_t lhal_ops;

/* Opens every backend of bk. -1 with one line in err. */
int lhal_open(lhal_t *h, const backend_cfg_t *bk, const hal_io_map_t *io, uint8_t naxes, char *err,
	      size_t errlen);
void lhal_close(lhal_t *h);
/* The counters of each Modbus bus (mb_bus_counters), each after a space;
 * the length written. */
size_t lhal_modbus_counters(lhal_t *h, char *buf, size_t cap);
void lhal_pre_tick(lhal_t *h, uint32_t now_us);

#endif
