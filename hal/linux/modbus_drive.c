/* Wheel drives over Modbus RTU; see modbus_drive.h. */
#include "modbus_drive.h"

#include <errno.h>
#include <modbus/modbus.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "../posix/rt.h"

#define CYCLE_PAUSE_NS 1000000L /* between cycles: leaves the line idle briefly */
#define BLOCK_MAX      8
#define PROBE_US       200000u

static uint64_t mono_us(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return (uint64_t)t.tv_sec * 1000000u + (uint64_t)t.tv_nsec / 1000u;
}

int mb_bus_open(mb_bus_t *b, const bk_modbus_bus_t *cfg, char *err, size_t errlen)
{
	memset(b, 0, sizeof(*b));
	b->cfg = *cfg;
	modbus_t *m =
	    modbus_new_rtu(cfg->device, (int)cfg->baud, cfg->parity, 8, (int)cfg->stop_bits);
	if (!m) {
		snprintf(err, errlen, "modbus: %s: %s", cfg->device, modbus_strerror(errno));
		return -1;
	}
	if (modbus_connect(m) != 0) {
		snprintf(err, errlen, "modbus: %s: %s", cfg->device, modbus_strerror(errno));
		modbus_free(m);
		return -1;
	}
	modbus_set_response_timeout(m, cfg->timeout_ms / 1000u, (cfg->timeout_ms % 1000u) * 1000u);
	b->ctx = m;
	pthread_mutexattr_t a;
	pthread_mutexattr_init(&a);
	pthread_mutexattr_setprotocol(&a, PTHREAD_PRIO_INHERIT);
	pthread_mutex_init(&b->mu, &a);
	pthread_mutexattr_destroy(&a);
	return 0;
}

unsigned mb_bus_add(mb_bus_t *b, uint8_t unit, bool reverse)
{
	mb_drive_t *d = &b->d[b->nd];
	memset(d, 0, sizeof(*d));
	d->unit = unit;
	d->reverse = reverse;
	return b->nd++;
}

enum { RD_HOLDING, RD_INPUT, WR };

/* One request with retries; false when every attempt failed. */
static bool xfer_n(mb_bus_t *b, uint8_t unit, int op, int addr, int n, uint16_t *regs,
		   uint32_t retries)
{
	modbus_t *m = b->ctx;
	modbus_set_slave(m, unit);
	for (uint32_t attempt = 0; attempt <= retries; attempt++) {
		int r = op == WR	 ? (n == 1 ? modbus_write_register(m, addr, regs[0])
						   : modbus_write_registers(m, addr, n, regs))
			: op == RD_INPUT ? modbus_read_input_registers(m, addr, n, regs)
					 : modbus_read_registers(m, addr, n, regs);
		pthread_mutex_lock(&b->mu);
		b->requests++;
		if (attempt)
			b->retries++;
		if (r != n)
			b->errors++;
		pthread_mutex_unlock(&b->mu);
		if (r == n)
			return true;
		modbus_flush(m); /* a late answer must not pair with the next request */
	}
	return false;
}

static bool xfer(mb_bus_t *b, uint8_t unit, int op, int addr, int n, uint16_t *regs)
{
	return xfer_n(b, unit, op, addr, n, regs, b->cur_retries);
}

static void cycle_drive(mb_bus_t *b, mb_drive_t *d)
{
	const uint32_t *reg = b->cfg.reg;
	uint64_t now = mono_us();
	if (d->silent && now < d->next_probe_us)
		return;
	/* A silent drive gets one attempt per probe. */
	b->cur_retries = d->silent ? 0 : b->cfg.retries;
	int32_t cps;
	bool en;
	uint32_t reset;
	pthread_mutex_lock(&b->mu);
	/* a speed only to a stage that is on: it starts from 0, not a step */
	cps = d->cmd_enable && (d->status & 1u) ? d->cmd_cps : 0;
	en = d->cmd_enable;
	reset = d->reset_req;
	pthread_mutex_unlock(&b->mu);

	if (reset != d->reset_done) {
		uint16_t one = 1;
		if (xfer(b, d->unit, WR, (int)reg[BK_REG_FAULT_RESET], 1, &one))
			d->reset_done = reset;
	}
	if (!d->enable_sent_ok || d->enable_sent != en) {
		uint16_t v = en ? 1 : 0;
		d->enable_sent = en;
		d->enable_sent_ok = xfer(b, d->unit, WR, (int)reg[BK_REG_SERVO_ON], 1, &v);
	}
	uint16_t sp[2] = {(uint16_t)((uint32_t)cps >> 16), (uint16_t)((uint32_t)cps & 0xffffu)};
	bool ok = xfer(b, d->unit, WR, (int)reg[BK_REG_TARGET_SPEED], 2, sp);

	uint32_t lo = reg[BK_REG_POSITION], hi = reg[BK_REG_POSITION] + 1;
	for (int r = BK_REG_STATUS; r <= BK_REG_ALARM; r++) {
		lo = reg[r] < lo ? reg[r] : lo;
		hi = reg[r] > hi ? reg[r] : hi;
	}
	uint16_t pos[2] = {0, 0}, st = 0, al = 0;
	if (ok && hi - lo < BLOCK_MAX) {
		uint16_t blk[BLOCK_MAX];
		ok = xfer(b, d->unit, RD_HOLDING, (int)lo, (int)(hi - lo + 1), blk);
		pos[0] = blk[reg[BK_REG_POSITION] - lo];
		pos[1] = blk[reg[BK_REG_POSITION] + 1 - lo];
		st = blk[reg[BK_REG_STATUS] - lo];
		al = blk[reg[BK_REG_ALARM] - lo];
	} else if (ok) {
		ok = xfer(b, d->unit, RD_HOLDING, (int)reg[BK_REG_POSITION], 2, pos) &&
		     xfer(b, d->unit, RD_HOLDING, (int)reg[BK_REG_STATUS], 1, &st) &&
		     xfer(b, d->unit, RD_HOLDING, (int)reg[BK_REG_ALARM], 1, &al);
	}
	pthread_mutex_lock(&b->mu);
	if (ok) {
		d->pos = (int32_t)(((uint32_t)pos[0] << 16) | pos[1]);
		d->status = st;
		d->alarm = al;
		d->fresh = true;
		d->sampled = true;
		d->silent = false;
	} else {
		d->failures++;
		d->silent = true;
		d->next_probe_us = mono_us() + PROBE_US;
	}
	pthread_mutex_unlock(&b->mu);
}

static void publish_battery(mb_bus_t *b, bool ok, uint32_t mv)
{
	mb_battery_t *t = &b->bat;
	pthread_mutex_lock(&b->mu);
	if (ok) {
		t->mv = mv;
		t->settled = true;
	} else {
		t->errors++;
	}
	pthread_mutex_unlock(&b->mu);
}

static void cycle_battery(mb_bus_t *b)
{
	mb_battery_t *t = &b->bat;
	uint64_t now = mono_us();
	if (now >= t->due_us) {
		/* From now, not from the due time: a slow bus never bursts. */
		t->due_us = now + (uint64_t)t->cfg.period_ms * 1000u;
		b->cur_retries = t->failing ? 0 : b->cfg.retries;
		uint16_t r[2] = {0, 0};
		bool ok = xfer(b, t->cfg.unit, t->cfg.input ? RD_INPUT : RD_HOLDING, t->cfg.reg,
			       t->cfg.words, r);
		uint32_t raw = t->cfg.words == 2 ? ((uint32_t)r[0] << 16) | r[1] : r[0];
		double v = (double)raw * t->scale + 0.5;
		ok = ok && v < 4e9; /* beyond uint32 mV: a wrong register, not a voltage */
		publish_battery(b, ok, ok ? (uint32_t)v : 0);
		t->failing = !ok;
		if (ok) {
			t->good_us = now;
			if (t->stale)
				rt_log(LOG_INFO, "battery: unit %u on %s answers again: %u mV",
				       t->cfg.unit, b->cfg.device, (uint32_t)v);
			t->stale = false;
		}
	}
	if (!t->stale && now - t->good_us > MB_BATTERY_STALE_MS * 1000ull) {
		t->stale = true;
		pthread_mutex_lock(&b->mu);
		t->mv = 0;
		t->settled = true;
		pthread_mutex_unlock(&b->mu);
		rt_log(LOG_WARNING,
		       "battery: no reading from unit %u on %s for %u ms: it reads 0 V until "
		       "it answers",
		       t->cfg.unit, b->cfg.device, MB_BATTERY_STALE_MS);
	}
}

static void *bus_thread(void *arg)
{
	mb_bus_t *b = arg;
	while (!b->stop) {
		for (unsigned i = 0; i < b->nd && !b->stop; i++)
			cycle_drive(b, &b->d[i]);
		if (b->bat.used && !b->stop)
			cycle_battery(b);
		struct timespec ts = {0, CYCLE_PAUSE_NS};
		nanosleep(&ts, NULL);
	}
	return NULL;
}

void mb_bus_add_battery(mb_bus_t *b, const bk_battery_modbus_t *cfg, double scale_mv)
{
	memset(&b->bat, 0, sizeof(b->bat));
	b->bat.used = true;
	b->bat.cfg = *cfg;
	b->bat.scale = scale_mv;
}

int mb_bus_start(mb_bus_t *b, char *err, size_t errlen)
{
	/* The stale bound counts from start: a battery that never answers
	 * reads 0 V after it, like one that stopped answering. */
	b->bat.good_us = mono_us();
	b->bat.due_us = b->bat.good_us;
	int r = pthread_create(&b->th, NULL, bus_thread, b);
	if (r != 0) {
		snprintf(err, errlen, "modbus: %s: thread: %s", b->cfg.device, strerror(r));
		return -1;
	}
	b->running = true;
	return 0;
}

void mb_bus_close(mb_bus_t *b)
{
	if (!b->ctx)
		return;
	if (b->running) {
		b->stop = true;
		pthread_join(b->th, NULL);
		b->running = false;
	}
	b->cur_retries = b->cfg.retries;
	for (unsigned i = 0; i < b->nd; i++) {
		uint16_t zero[2] = {0, 0};
		xfer(b, b->d[i].unit, WR, (int)b->cfg.reg[BK_REG_TARGET_SPEED], 2, zero);
		xfer(b, b->d[i].unit, WR, (int)b->cfg.reg[BK_REG_SERVO_ON], 1, zero);
	}
	modbus_close(b->ctx);
	modbus_free(b->ctx);
	b->ctx = NULL;
	pthread_mutex_destroy(&b->mu);
}

void mb_battery_wait_first(mb_bus_t *b)
{
	for (unsigned ms = 0; ms <= MB_BATTERY_STALE_MS + 200u; ms += 10) {
		pthread_mutex_lock(&b->mu);
		bool settled = b->bat.settled;
		pthread_mutex_unlock(&b->mu);
		if (settled)
			return;
		struct timespec ts = {0, 10000000L};
		nanosleep(&ts, NULL);
	}
}

uint32_t mb_battery_mv(mb_bus_t *b, uint32_t *errors)
{
	pthread_mutex_lock(&b->mu);
	uint32_t mv = b->bat.mv;
	*errors = b->bat.errors;
	pthread_mutex_unlock(&b->mu);
	return mv;
}

void mb_drive_set_velocity(mb_bus_t *b, unsigned i, int32_t cps_q8)
{
	/* counts/s, rounded to nearest */
	int32_t cps = (int32_t)(((int64_t)cps_q8 + (cps_q8 >= 0 ? 128 : -128)) / 256);
	if (b->d[i].reverse)
		cps = -cps; /* within +-2^23: no overflow */
	pthread_mutex_lock(&b->mu);
	b->d[i].cmd_cps = cps;
	pthread_mutex_unlock(&b->mu);
}

void mb_drive_enable(mb_bus_t *b, unsigned i, bool on)
{
	pthread_mutex_lock(&b->mu);
	b->d[i].cmd_enable = on;
	if (!on)
		b->d[i].cmd_cps = 0;
	pthread_mutex_unlock(&b->mu);
}

void mb_drive_reset_fault(mb_bus_t *b, unsigned i)
{
	pthread_mutex_lock(&b->mu);
	b->d[i].reset_req++;
	pthread_mutex_unlock(&b->mu);
}

void mb_drive_read(mb_bus_t *b, unsigned i, hal_drive_state_t *st)
{
	mb_drive_t *d = &b->d[i];
	pthread_mutex_lock(&b->mu);
	st->position_counts = d->reverse ? (int32_t)(0u - (uint32_t)d->pos) : d->pos;
	st->fault_code = d->alarm;
	st->enabled = (d->status & 1u) != 0;
	st->phase = !d->sampled	  ? HAL_DRIVE_UNKNOWN
		    : d->alarm	  ? HAL_DRIVE_FAULT
		    : st->enabled ? HAL_DRIVE_ENABLED
				  : HAL_DRIVE_READY;
	st->position_lost = false;
	st->fresh = d->fresh;
	d->fresh = false;
	pthread_mutex_unlock(&b->mu);
}
