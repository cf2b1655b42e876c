/* Joystick from a Linux input event device (libevdev).
 *
 * The device is opened non-blocking; ljoy_poll() (once per tick) drains the
 * pending events and never waits. A read error (the device unplugged:
 * ENODEV) closes it and reports the joystick absent, which stops a unit
 * under joystick control (the firmware). An absent device is looked for
 * again once a second; the firmware still needs setJoystick to use it.
 */
#ifndef HAL_LINUX_JOYSTICK_H
#define HAL_LINUX_JOYSTICK_H

#include <stdbool.h>
#include <stdint.h>

#include "../hal.h"
#include "backend_cfg.h"

struct libevdev;

typedef struct {
	bk_joystick_t cfg;
	struct libevdev *dev;
	int fd;
	int32_t min[3], max[3];
	int32_t raw[3];
	bool present;
	uint32_t next_try_us;
	uint32_t losses; /* times the device went away */
} ljoy_t;

/* Tries to open the device now; absent is not an error. */
void ljoy_init(ljoy_t *j, const bk_joystick_t *cfg, uint32_t now_us);
void ljoy_close(ljoy_t *j);
void ljoy_poll(ljoy_t *j, uint32_t now_us);
void ljoy_read(const ljoy_t *j, hal_joystick_t *js);

#endif
