/* Wheel drives over Modbus RTU; see modbus_drive.h. */
#include "modbus_drive.h"

#include <errno.h>
#include <modbus/modbus.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "../modbus/mbmaster.h"
#include "../modbus/mbprofile.h"
#include "../posix/rt.h"

#define CYCLE_PAUSE_NS 1000000L /* between cycles: leaves the line idle briefly */
#define BLOCK_MAX      32
#define PROBE_US       200000u

static uint64_t mono_us(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return (uint64_t)t.tv_sec * 1000000u + (uint64_t)t.tv_nsec / 1000u;
}

uint32_t mb_byte_timeout_us(uint32_t baud, char parity, uint32_t stop_bits)
{
	/* the board's master's rule (hal/modbus/mbmaster.c) */
	return mbm_byte_us(baud, 1 + 8 + (parity == 'N' ? 0 : 1) + stop_bits);
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
	b->byte_timeout_us = cfg->byte_timeout_ms
				 ? cfg->byte_timeout_ms * 1000u
				 : mb_byte_timeout_us(cfg->baud, cfg->parity, cfg->stop_bits);
	modbus_set_byte_timeout(m, b->byte_timeout_us / 1000000u, b->byte_timeout_us % 1000000u);
	b->ctx = m;
	pthread_mutexattr_t a;
	pthread_mutexattr_init(&a);
	pthread_mutexattr_setprotocol(&a, PTHREAD_PRIO_INHERIT);
	pthread_mutex_init(&b->mu, &a);
	pthread_mutexattr_destroy(&a);
	return 0;
}

unsigned mb_bus_add(mb_bus_t *b, uint8_t unit, uint8_t ch, bool reverse)
{
	mb_drive_t *d = &b->d[b->nd];
	memset(d, 0, sizeof(*d));
	d->unit = unit;
	d->ch = ch;
	d->reverse = reverse;
	return b->nd++;
}

enum { RD_HOLDING, RD_INPUT, WR };

/* How a request ended. */
enum { XF_OK, XF_NO_REPLY, XF_BUSY, XF_MAP, XF_EXCEPTION };

static void count(mb_count_t *c, int e)
{
	if (e == ETIMEDOUT)
		c->timeouts++;
	else if (e == EMBBADCRC)
		c->crc_errors++;
	else if (e >= EMBXILFUN && e <= EMBXGTAR) {
		c->exceptions++;
		c->busy += e == EMBXSBUSY;
		c->illegal += e == EMBXILFUN || e == EMBXILADD;
	} else {
		c->bad++;
	}
}

static int classify(int e)
{
	if (e == EMBXSBUSY)
		return XF_BUSY;
	if (e == EMBXILFUN || e == EMBXILADD)
		return XF_MAP;
	if (e >= EMBXILFUN && e <= EMBXGTAR)
		return XF_EXCEPTION;
	return XF_NO_REPLY;
}

static const char *op_name(int op, int n)
{
	return op == WR		? (n == 1 ? "06 (write register)" : "16 (write registers)")
	       : op == RD_INPUT ? "04 (read input registers)"
				: "03 (read holding registers)";
}

/* One request with retries; XF_OK or how the last attempt failed. An
 * illegal function or address is not retried: the answer will not
 * change. */
static int xfer_n(mb_bus_t *b, uint8_t unit, int op, int addr, int n, uint16_t *regs,
		  uint32_t retries)
{
	modbus_t *m = b->ctx;
	int res = XF_NO_REPLY;
	modbus_set_slave(m, unit);
	for (uint32_t attempt = 0; attempt <= retries; attempt++) {
		int r = op == WR	 ? (n == 1 ? modbus_write_register(m, addr, regs[0])
						   : modbus_write_registers(m, addr, n, regs))
			: op == RD_INPUT ? modbus_read_input_registers(m, addr, n, regs)
					 : modbus_read_registers(m, addr, n, regs);
		int e = r == n ? 0 : errno;
		pthread_mutex_lock(&b->mu);
		b->requests++;
		if (attempt)
			b->retries++;
		if (r != n) {
			b->errors++;
			count(&b->cnt, e);
			if (b->cur)
				count(&b->cur->cnt, e);
		}
		pthread_mutex_unlock(&b->mu);
		if (r == n)
			return XF_OK;
		res = classify(e);
		if (res == XF_MAP && b->cur && !b->cur->map_logged) {
			b->cur->map_logged = true;
			rt_log(LOG_ERR,
			       "modbus bus %s: unit %u: function %s at 0x%04X (%d register%s): %s: "
			       "the drive profile '%s' does not match the drive",
			       b->cfg.device, unit, op_name(op, n), (unsigned)addr, n,
			       n > 1 ? "s" : "", modbus_strerror(e), b->cfg.prof.name);
		}
		if (res == XF_MAP)
			return res;
		if (res == XF_NO_REPLY)
			modbus_flush(m); /* a late answer must not pair with the next request */
	}
	return res;
}

static int xfer(mb_bus_t *b, uint8_t unit, int op, int addr, int n, uint16_t *regs)
{
	return xfer_n(b, unit, op, addr, n, regs, b->cur_retries);
}

/* Writes one register (or a pair) of drive d. */
static int write_reg(mb_bus_t *b, const mb_drive_t *d, unsigned r, uint16_t *w)
{
	const mbp_reg_t *g = &b->cfg.prof.reg[r];
	return xfer(b, d->unit, WR, mbp_addr(g, d->ch), g->words, w);
}

/* The profile's init registers and the drive's own communication-loss
 * stop (unless the bus has none). */
static int setup_drive(mb_bus_t *b, const mb_drive_t *d)
{
	const mb_profile_t *p = &b->cfg.prof;
	for (unsigned i = 0; i < p->ninit; i++) {
		uint16_t v = p->init[i].value;
		int x = xfer(b, d->unit, WR, p->init[i].addr, 1, &v);
		if (x != XF_OK)
			return x;
	}
	if (b->cfg.comm_stop_none || p->reg[MBP_COMM_TIMEOUT].words == 0)
		return XF_OK;
	uint32_t units = (b->cfg.comm_timeout_ms + p->comm_unit_ms - 1u) / p->comm_unit_ms;
	uint16_t w[2];
	mbp_put(&p->reg[MBP_COMM_TIMEOUT], (int32_t)(units > 65535u ? 65535u : units), w);
	return write_reg(b, d, MBP_COMM_TIMEOUT, w);
}

/* The enable value for drive d: a register shared by the unit's channels
 * is on only while every drive of the unit is commanded on. Under mu. */
static bool enable_wanted(const mb_bus_t *b, const mb_drive_t *d)
{
	if (b->cfg.prof.reg[MBP_ENABLE].step != 0)
		return d->cmd_enable;
	for (unsigned i = 0; i < b->nd; i++)
		if (b->d[i].unit == d->unit && !b->d[i].cmd_enable)
			return false;
	return true;
}

/* Position, status and alarm of drive d into val, in as few reads as the
 * profile's block allows (mbp_read_plan). */
static int read_sample(mb_bus_t *b, const mb_drive_t *d, uint16_t val[MBP_REG_COUNT][2])
{
	const mb_profile_t *p = &b->cfg.prof;
	mbp_read_t rd[3];
	unsigned n = mbp_read_plan(p, d->ch, BLOCK_MAX, rd);
	for (unsigned i = 0; i < n; i++) {
		uint16_t blk[BLOCK_MAX];
		int x =
		    xfer(b, d->unit, rd[i].input ? RD_INPUT : RD_HOLDING, rd[i].addr, rd[i].n, blk);
		if (x != XF_OK)
			return x;
		mbp_take_read(p, d->ch, &rd[i], blk, val);
	}
	return XF_OK;
}

/* The cycle's requests up to the sample; XF_OK or how it failed. */
static int cycle_requests(mb_bus_t *b, mb_drive_t *d, uint16_t val[MBP_REG_COUNT][2])
{
	const mb_profile_t *p = &b->cfg.prof;
	int32_t cps;
	bool en;
	uint32_t reset;
	pthread_mutex_lock(&b->mu);
	/* a speed only to a stage that is on: it starts from 0, not a step */
	cps = d->cmd_enable && mbp_enabled(p, d->s.status) ? d->cmd_cps : 0;
	en = enable_wanted(b, d);
	reset = d->reset_req;
	pthread_mutex_unlock(&b->mu);

	int x = XF_OK;
	if (!d->setup_done) {
		x = setup_drive(b, d);
		if (x != XF_OK)
			return x;
		d->setup_done = true;
	}
	if (reset != d->reset_done && p->reg[MBP_RESET].words) {
		uint16_t w[2];
		mbp_put(&p->reg[MBP_RESET], p->reset_value, w);
		if (write_reg(b, d, MBP_RESET, w) == XF_OK)
			d->reset_done = reset;
	}
	if (!d->enable_sent_ok || d->enable_sent != en) {
		uint16_t w[2];
		mbp_put(&p->reg[MBP_ENABLE], en ? p->enable_on : p->enable_off, w);
		d->enable_sent = en;
		d->enable_sent_ok = write_reg(b, d, MBP_ENABLE, w) == XF_OK;
	}
	uint16_t sp[2];
	mbp_speed_words(p, cps, sp);
	x = write_reg(b, d, MBP_SPEED, sp);
	return x != XF_OK ? x : read_sample(b, d, val);
}

static void cycle_drive(mb_bus_t *b, mb_drive_t *d)
{
	uint64_t now = mono_us();
	if (d->silent && now < d->next_probe_us)
		return;
	/* A silent drive gets one attempt per probe. */
	b->cur_retries = d->silent ? 0 : b->cfg.retries;
	b->cur = d;
	uint16_t val[MBP_REG_COUNT][2] = {{0}};
	int x = cycle_requests(b, d, val);
	b->cur = NULL;
	pthread_mutex_lock(&b->mu);
	if (x == XF_OK) {
		mbp_sample_set(&b->cfg.prof, &d->s, val);
		d->silent = false;
		d->map_logged = false;
	} else {
		d->failures++;
		/* A drive that answers (busy, an exception) is asked again in
		 * the next cycle: it costs the bus little. */
		d->s.why = x == XF_BUSY	 ? HAL_SILENT_BUSY
			   : x == XF_MAP ? HAL_SILENT_MAP
					 : HAL_SILENT_NO_REPLY;
		if (x == XF_NO_REPLY) {
			d->silent = true;
			d->setup_done = false; /* it may have restarted: set it up again */
			d->next_probe_us = mono_us() + PROBE_US;
		}
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
			       t->cfg.words, r) == XF_OK;
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
	b->cur_retries = b->cfg.retries;
	for (unsigned i = 0; i < b->nd; i++) {
		mb_drive_t *d = &b->d[i];
		if (d->setup_done)
			continue;
		b->cur = d;
		int x = setup_drive(b, d);
		b->cur = NULL;
		if (x != XF_OK) {
			snprintf(err, errlen,
				 "modbus bus %s: unit %u: the profile's start-up registers (%s, "
				 "comm_timeout) were not written: %s",
				 b->cfg.device, d->unit, b->cfg.prof.name,
				 x == XF_MAP	? "the drive has no such register"
				 : x == XF_BUSY ? "the drive answers busy"
						: "no reply");
			return -1;
		}
		d->setup_done = true;
	}
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
	const mb_profile_t *p = &b->cfg.prof;
	for (unsigned i = 0; i < b->nd; i++) {
		uint16_t w[2];
		mbp_speed_words(p, 0, w);
		write_reg(b, &b->d[i], MBP_SPEED, w);
		mbp_put(&p->reg[MBP_ENABLE], p->enable_off, w);
		write_reg(b, &b->d[i], MBP_ENABLE, w);
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
	pthread_mutex_lock(&b->mu);
	mbp_report(&b->cfg.prof, &b->d[i].s, b->d[i].reverse, st);
	pthread_mutex_unlock(&b->mu);
}

static int put_count(char *buf, size_t len, const mb_count_t *c)
{
	return snprintf(buf, len,
			"timeouts %u crc_errors %u bad_replies %u exceptions %u busy %u illegal %u",
			c->timeouts, c->crc_errors, c->bad, c->exceptions, c->busy, c->illegal);
}

int mb_bus_counters(mb_bus_t *b, unsigned n, char *buf, size_t len)
{
	pthread_mutex_lock(&b->mu);
	size_t k = (size_t)snprintf(buf, len, "modbus%u %s requests %u retries %u ", n,
				    b->cfg.device, b->requests, b->retries);
	if (k < len)
		k += (size_t)put_count(buf + k, len - k, &b->cnt);
	for (unsigned i = 0; i < b->nd && k < len; i++) {
		const mb_drive_t *d = &b->d[i];
		if (b->cfg.prof.channels > 1)
			k += (size_t)snprintf(buf + k, len - k, " unit%u.%u ", d->unit, d->ch);
		else
			k += (size_t)snprintf(buf + k, len - k, " unit%u ", d->unit);
		if (k < len)
			k += (size_t)put_count(buf + k, len - k, &d->cnt);
	}
	pthread_mutex_unlock(&b->mu);
	return (int)k;
}
