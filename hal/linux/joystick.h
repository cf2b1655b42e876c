/* Joystick from a Linux input event device (libevdev).
 *
 * The device is opened non-blocking; ljoy_poll() (once per tick) drains the
 * pending events and never waits. A read error (the device unplugged:
 * ENODEV) closes it and reports the joystick absent, which stops a unit
 * under joystick control (the firmware). An absent device is looked for
 * again once a second; the firmware still needs setJoystick to use it.
 *
 * Closing an evdev file waits for an RCU grace period in the kernel
 * (evdev_release): milliseconds, longer than a control period. So the tick
 * never closes one: it hands the descriptor to a helper thread that does.
 */
#ifndef HAL_LINUX_JOYSTICK_H
#define HAL_LINUX_JOYSTICK_H

#include <pthread.h>
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
	/* descriptors to close, tick -> closer thread */
	bool closer;
	int close_pipe[2];
	pthread_t closer_th;
} ljoy_t;

/* Tries to open the device now; absent is not an error. Starts the closer
 * thread (with a configured joystick). */
void ljoy_init(ljoy_t *j, const bk_joystick_t *cfg, uint32_t now_us);
/* Closes the device and stops the closer thread (not from the tick). */
void ljoy_close(ljoy_t *j);
void ljoy_poll(ljoy_t *j, uint32_t now_us);
void ljoy_read(const ljoy_t *j, hal_joystick_t *js);

#endif
