/* Joystick from evdev; see joystick.h. */
#include "joystick.h"

#include <errno.h>
#include <fcntl.h>
#include <libevdev/libevdev.h>
#include <string.h>
#include <unistd.h>

#define RETRY_US     1000000u
#define CLOSER_STACK ((size_t)64 * 1024)

static void *closer_main(void *arg)
{
	ljoy_t *j = arg;
	int fd;
	/* Ends when ljoy_close closes the write end. */
	while (read(j->close_pipe[0], &fd, sizeof(fd)) == (ssize_t)sizeof(fd))
		close(fd);
	return NULL;
}

static void start_closer(ljoy_t *j)
{
	if (pipe2(j->close_pipe, O_CLOEXEC) != 0)
		return;
	/* The tick never waits on the pipe (64 KiB: 16384 descriptors). */
	fcntl(j->close_pipe[1], F_SETFL, O_NONBLOCK);
	pthread_attr_t a;
	pthread_attr_init(&a);
	pthread_attr_setstacksize(&a, CLOSER_STACK);
	j->closer = pthread_create(&j->closer_th, &a, closer_main, j) == 0;
	pthread_attr_destroy(&a);
	if (!j->closer) {
		close(j->close_pipe[0]);
		close(j->close_pipe[1]);
	}
}

/* From the tick: the closer thread closes fd. Without it (it could not be
 * started), the close happens here. */
static void close_later(ljoy_t *j, int fd)
{
	if (!j->closer || write(j->close_pipe[1], &fd, sizeof(fd)) != (ssize_t)sizeof(fd))
		close(fd);
}

static void try_open(ljoy_t *j)
{
	int fd = open(j->cfg.device, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
	if (fd < 0)
		return;
	struct libevdev *dev = NULL;
	if (libevdev_new_from_fd(fd, &dev) < 0) {
		close_later(j, fd);
		return;
	}
	for (int i = 0; i < 3; i++) {
		if (j->cfg.code[i] < 0)
			continue;
		const struct input_absinfo *ai =
		    libevdev_get_abs_info(dev, (unsigned)j->cfg.code[i]);
		if (!ai || ai->maximum <= ai->minimum) {
			libevdev_free(dev);
			close_later(j, fd);
			return; /* not the device we were told about */
		}
		j->min[i] = ai->minimum;
		j->max[i] = ai->maximum;
		j->raw[i] = ai->value;
	}
	j->dev = dev;
	j->fd = fd;
	j->present = true;
}

void ljoy_init(ljoy_t *j, const bk_joystick_t *cfg, uint32_t now_us)
{
	memset(j, 0, sizeof(*j));
	j->cfg = *cfg;
	j->fd = -1;
	j->next_try_us = now_us + RETRY_US;
	if (cfg->used) {
		start_closer(j);
		try_open(j);
	}
}

/* The device is gone: absent from now on, its descriptor closed later. */
static void drop(ljoy_t *j)
{
	if (j->dev)
		libevdev_free(j->dev);
	if (j->fd >= 0)
		close_later(j, j->fd);
	j->dev = NULL;
	j->fd = -1;
	j->present = false;
}

void ljoy_close(ljoy_t *j)
{
	if (j->dev)
		libevdev_free(j->dev);
	if (j->fd >= 0)
		close(j->fd);
	j->dev = NULL;
	j->fd = -1;
	j->present = false;
	if (j->closer) {
		close(j->close_pipe[1]); /* the thread closes what is queued, then ends */
		pthread_join(j->closer_th, NULL);
		close(j->close_pipe[0]);
		j->closer = false;
	}
}

static void take(ljoy_t *j, const struct input_event *ev)
{
	if (ev->type != EV_ABS)
		return;
	for (int i = 0; i < 3; i++)
		if (j->cfg.code[i] == ev->code)
			j->raw[i] = ev->value;
}

void ljoy_poll(ljoy_t *j, uint32_t now_us)
{
	if (!j->cfg.used)
		return;
	if (!j->present) {
		if ((int32_t)(now_us - j->next_try_us) >= 0) {
			j->next_try_us = now_us + RETRY_US;
			try_open(j);
		}
		return;
	}
	/* Bounded: a flood of events cannot hold up the tick. */
	for (int n = 0; n < 256; n++) {
		struct input_event ev;
		int r = libevdev_next_event(j->dev, LIBEVDEV_READ_FLAG_NORMAL, &ev);
		if (r == LIBEVDEV_READ_STATUS_SUCCESS) {
			take(j, &ev);
		} else if (r == LIBEVDEV_READ_STATUS_SYNC) {
			/* Events were dropped: catch up on the device's state. */
			while (r == LIBEVDEV_READ_STATUS_SYNC) {
				take(j, &ev);
				r = libevdev_next_event(j->dev, LIBEVDEV_READ_FLAG_SYNC, &ev);
			}
		} else if (r == -EAGAIN) {
			return;
		} else {
			drop(j); /* ENODEV: unplugged */
			j->losses++;
			j->next_try_us = now_us + RETRY_US;
			return;
		}
	}
}

void ljoy_read(const ljoy_t *j, hal_joystick_t *js)
{
	memset(js, 0, sizeof(*js));
	js->present = j->present;
	if (!j->present)
		return;
	for (int i = 0; i < 3; i++) {
		if (j->cfg.code[i] < 0)
			continue;
		/* Centre of the range to 0, the ends to +-32767. */
		int64_t span = (int64_t)j->max[i] - j->min[i];
		int64_t v = ((2 * (int64_t)j->raw[i] - j->min[i] - j->max[i]) * 32767) / span;
		v = (int64_t)((double)v * j->cfg.scale[i]);
		if (j->cfg.invert[i])
			v = -v;
		js->axis[i] = (int16_t)(v > 32767 ? 32767 : v < -32767 ? -32767 : v);
	}
}
