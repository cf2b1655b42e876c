/* The Linux HAL: see lhal.h. */
#include "lhal.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#define BATTERY_PERIOD_US 200000u
#define Q8_US		  256000000LL /* counts x256 x1e6: one count in rem units */

/* One sysfs read of an IIO *_raw attribute; false on any failure. */
static bool read_iio(const char *path, double scale, uint32_t *mv)
{
	char buf[32];
	int fd = open(path, O_RDONLY | O_CLOEXEC);
	if (fd < 0)
		return false;
	ssize_t n = read(fd, buf, sizeof(buf) - 1);
	close(fd);
	if (n <= 0)
		return false;
	buf[n] = '\0';
	char *end;
	long raw = strtol(buf, &end, 10);
	if (end == buf || raw < 0)
		return false;
	double v = (double)raw * scale;
	if (v > 4e9)
		return false;
	*mv = (uint32_t)(v + 0.5);
	return true;
}

int lhal_open(lhal_t *h, const backend_cfg_t *bk, const hal_io_map_t *io, uint8_t naxes, char *err,
	      size_t errlen)
{
	memset(h, 0, sizeof(*h));
	h->joy.fd = -1; /* lhal_close on an early failure must not close fd 0 */
	h->bk = *bk;
	h->naxes = naxes;
	if (lgpio_open(&h->gpio, bk, io, err, errlen) < 0)
		return -1;
	for (unsigned n = 0; n < BK_MODBUS_BUSES; n++) {
		bool battery = bk->battery_source == BK_BATTERY_MODBUS && bk->battery_mb.bus == n;
		bool needed = battery;
		for (uint8_t i = 0; i < naxes; i++)
			needed = needed ||
				 (bk->drive_type[i] == BK_DRIVE_MODBUS && bk->drive_bus[i] == n);
		if (!needed)
			continue;
		if (mb_bus_open(&h->bus[n], &bk->bus[n], err, errlen) < 0)
			goto fail;
		for (uint8_t i = 0; i < naxes; i++)
			if (bk->drive_type[i] == BK_DRIVE_MODBUS && bk->drive_bus[i] == n)
				h->mb_index[i] =
				    (uint8_t)mb_bus_add(&h->bus[n], bk->drive_unit[i],
							bk->drive_channel[i], bk->drive_reverse[i]);
		if (battery)
			mb_bus_add_battery(&h->bus[n], &bk->battery_mb, bk->battery_scale);
		/* Started before the caller turns to SCHED_FIFO: the bus threads
		 * stay normal threads, below the tick. */
		if (mb_bus_start(&h->bus[n], err, errlen) < 0)
			goto fail;
	}
	for (unsigned n = 0; n < BK_CANOPEN_BUSES; n++) {
		bool needed = false;
		for (uint8_t i = 0; i < naxes; i++)
			needed = needed ||
				 (bk->drive_type[i] == BK_DRIVE_CIA402 && bk->drive_bus[i] == n);
		if (!needed)
			continue;
		co_bus_init(&h->can[n], n, &bk->canopen[n]);
		for (uint8_t i = 0; i < naxes; i++)
			if (bk->drive_type[i] == BK_DRIVE_CIA402 && bk->drive_bus[i] == n)
				h->co_index[i] = (uint8_t)co_bus_add(
				    &h->can[n], i, bk->drive_node[i], bk->drive_reverse[i]);
		/* SDO configuration blocks here, before the control loop. */
		if (co_bus_open(&h->can[n], err, errlen) < 0 ||
		    co_bus_start(&h->can[n], err, errlen) < 0)
			goto fail;
	}
	ljoy_init(&h->joy, &bk->joystick, 0);
	h->battery_mv = bk->battery_mv;
	if (bk->battery_source == BK_BATTERY_IIO &&
	    !read_iio(bk->battery_path, bk->battery_scale, &h->battery_mv)) {
		snprintf(err, errlen, "battery: %s: cannot read", bk->battery_path);
		goto fail;
	}
	if (bk->battery_source == BK_BATTERY_MODBUS) {
		/* The firmware samples the battery at init: give it a reading
		 * (or, after the stale bound, the 0 V of a silent battery). */
		mb_bus_t *b = &h->bus[bk->battery_mb.bus];
		mb_battery_wait_first(b);
		h->battery_mv = mb_battery_mv(b, &h->battery_errors);
	}
	return 0;
fail:
	lhal_close(h);
	return -1;
}

void lhal_close(lhal_t *h)
{
	for (unsigned n = 0; n < BK_MODBUS_BUSES; n++)
		mb_bus_close(&h->bus[n]);
	for (unsigned n = 0; n < BK_CANOPEN_BUSES; n++)
		co_bus_close(&h->can[n]);
	ljoy_close(&h->joy);
	lgpio_close(&h->gpio);
}

size_t lhal_modbus_counters(lhal_t *h, char *buf, size_t cap)
{
	size_t n = 0;
	for (unsigned b = 0; b < BK_MODBUS_BUSES; b++) {
		if (!h->bus[b].ctx || n + 2 >= cap)
			continue;
		buf[n++] = ' ';
		int k = mb_bus_counters(&h->bus[b], b, buf + n, cap - n);
		n += k > 0 ? (size_t)k : 0;
		n = n < cap ? n : cap - 1;
	}
	if (cap)
		buf[n < cap ? n : cap - 1] = '\0';
	return n;
}

static mb_bus_t *mb_of(lhal_t *h, uint8_t axis)
{
	return h->bk.drive_type[axis] == BK_DRIVE_MODBUS ? &h->bus[h->bk.drive_bus[axis]] : NULL;
}

static co_bus_t *co_of(lhal_t *h, uint8_t axis)
{
	return h->bk.drive_type[axis] == BK_DRIVE_CIA402 ? &h->can[h->bk.drive_bus[axis]] : NULL;
}

void lhal_pre_tick(lhal_t *h, uint32_t now_us)
{
	uint32_t dt = h->have_now ? now_us - h->last_us : 0;
	h->last_us = now_us;
	h->have_now = true;
	h->now_us = now_us;
	for (uint8_t i = 0; i < h->naxes; i++) {
		lhal_loop_drive_t *d = &h->loop[i];
		if (h->bk.drive_type[i] != BK_DRIVE_LOOPBACK || !d->enabled)
			continue;
		d->rem += (int64_t)d->vel_q8 * dt;
		int64_t whole = d->rem / Q8_US;
		d->rem -= whole * Q8_US;
		d->pos = (int32_t)((uint32_t)d->pos + (uint32_t)whole);
	}
	for (unsigned n = 0; n < BK_CANOPEN_BUSES; n++)
		co_bus_pre_tick(&h->can[n], now_us);
	ljoy_poll(&h->joy, now_us);
	if (h->bk.battery_source == BK_BATTERY_IIO && (int32_t)(now_us - h->battery_due_us) >= 0) {
		h->battery_due_us = now_us + BATTERY_PERIOD_US;
		if (!read_iio(h->bk.battery_path, h->bk.battery_scale, &h->battery_mv))
			h->battery_errors++; /* keep the last good value */
	}
	if (h->bk.battery_source == BK_BATTERY_MODBUS)
		h->battery_mv = mb_battery_mv(&h->bus[h->bk.battery_mb.bus], &h->battery_errors);
}

static void op_drive_set_velocity(void *ctx, uint8_t axis, int32_t cps_q8)
{
	lhal_t *h = ctx;
	if (axis >= h->naxes)
		return;
	mb_bus_t *b = mb_of(h, axis);
	co_bus_t *cb = co_of(h, axis);
	if (b)
		mb_drive_set_velocity(b, h->mb_index[axis], cps_q8);
	else if (cb)
		co_drive_set_velocity(cb, h->co_index[axis], cps_q8);
	else
		h->loop[axis].vel_q8 = cps_q8;
}

static void op_drive_enable(void *ctx, uint8_t axis, bool on)
{
	lhal_t *h = ctx;
	if (axis >= h->naxes)
		return;
	lgpio_set_fn(&h->gpio, BK_LINE_SERVO0 + axis, on);
	mb_bus_t *b = mb_of(h, axis);
	if (b)
		mb_drive_enable(b, h->mb_index[axis], on);
	co_bus_t *cb = co_of(h, axis);
	if (cb)
		co_drive_enable(cb, h->co_index[axis], on);
	h->loop[axis].enabled = on;
	if (!on)
		h->loop[axis].vel_q8 = 0;
}

static void op_drive_read(void *ctx, uint8_t axis, hal_drive_state_t *st)
{
	lhal_t *h = ctx;
	memset(st, 0, sizeof(*st));
	if (axis >= h->naxes)
		return;
	mb_bus_t *b = mb_of(h, axis);
	if (b) {
		mb_drive_read(b, h->mb_index[axis], st);
		return;
	}
	co_bus_t *cb = co_of(h, axis);
	if (cb) {
		co_drive_read(cb, h->co_index[axis], st);
		return;
	}
	/* The software drive is its own report: on as commanded. */
	st->position_counts = h->loop[axis].pos;
	st->enabled = h->loop[axis].enabled;
	st->phase = st->enabled ? HAL_DRIVE_ENABLED : HAL_DRIVE_READY;
	st->fresh = true;
}

static void op_drive_reset_fault(void *ctx, uint8_t axis)
{
	lhal_t *h = ctx;
	mb_bus_t *b = axis < h->naxes ? mb_of(h, axis) : NULL;
	if (b)
		mb_drive_reset_fault(b, h->mb_index[axis]);
	co_bus_t *cb = axis < h->naxes ? co_of(h, axis) : NULL;
	if (cb)
		co_drive_reset_fault(cb, h->co_index[axis]);
	/* a loopback drive has no faults */
}

static bool op_power_set(void *ctx, bool on)
{
	lhal_t *h = ctx;
	h->relay_cmd = on;
	if (!lgpio_has_fn(&h->gpio, BK_LINE_RELAY))
		return true;
	lgpio_set_fn(&h->gpio, BK_LINE_RELAY, on);
	if (on && h->bk.settle_ms) {
		/* Only from a command, never the tick (hal.h). */
		struct timespec ts = {0, (long)h->bk.settle_ms * 1000000L};
		while (nanosleep(&ts, &ts) != 0 && errno == EINTR)
			;
	}
	return true;
}

static bool op_power_feedback(void *ctx)
{
	lhal_t *h = ctx;
	if (lgpio_has_fn(&h->gpio, BK_LINE_RELAY_FB))
		return lgpio_get_fn(&h->gpio, BK_LINE_RELAY_FB);
	return h->relay_cmd;
}

static bool op_io_read(void *ctx, uint32_t id, uint32_t *value)
{
	lhal_t *h = ctx;
	return lgpio_io_read(&h->gpio, id, value);
}

static bool op_io_write(void *ctx, uint32_t id, uint32_t value)
{
	lhal_t *h = ctx;
	return lgpio_io_write(&h->gpio, id, value);
}

static bool op_contact(void *ctx)
{
	return lgpio_get_fn(&((lhal_t *)ctx)->gpio, BK_LINE_CONTACT);
}

static bool op_obstacle(void *ctx)
{
	return lgpio_get_fn(&((lhal_t *)ctx)->gpio, BK_LINE_OBSTACLE);
}

static bool op_obstacle_caution(void *ctx)
{
	return lgpio_get_fn(&((lhal_t *)ctx)->gpio, BK_LINE_CAUTION);
}

static bool op_estop(void *ctx)
{
	return lgpio_get_fn(&((lhal_t *)ctx)->gpio, BK_LINE_ESTOP);
}

static void op_joystick(void *ctx, hal_joystick_t *js)
{
	ljoy_read(&((lhal_t *)ctx)->joy, js);
}

static uint32_t op_battery_mv(void *ctx)
{
	return ((lhal_t *)ctx)->battery_mv;
}

const vs_hal_ops_t lhal_ops = {
    .drive_set_velocity = op_drive_set_velocity,
    .drive_enable = op_drive_enable,
    .drive_read = op_drive_read,
    .drive_reset_fault = op_drive_reset_fault,
    .power_set = op_power_set,
    .power_feedback = op_power_feedback,
    .io_read = op_io_read,
    .io_write = op_io_write,
    .contact = op_contact,
    .obstacle = op_obstacle,
    .obstacle_caution = op_obstacle_caution,
    .estop = op_estop,
    .joystick = op_joystick,
    .battery_mv = op_battery_mv,
};
