/* CiA 402 drives over SocketCAN: see cia402.h. */
#include "cia402.h"

#include <errno.h>
#include <pthread.h>
#include <semaphore.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "../posix/rt.h"

/* ==== protocol (pure) ==================================================== */

co_state_t co_state_of(uint16_t sw)
{
	/* CiA 402 statusword bits 0..3, 5, 6: ready to switch on, switched on,
	 * operation enabled, fault, quick stop, switch on disabled. */
	if ((sw & 0x4Fu) == 0x00u)
		return CO_ST_NOT_READY;
	if ((sw & 0x4Fu) == 0x40u)
		return CO_ST_SWITCH_ON_DISABLED;
	if ((sw & 0x6Fu) == 0x21u)
		return CO_ST_READY;
	if ((sw & 0x6Fu) == 0x23u)
		return CO_ST_SWITCHED_ON;
	if ((sw & 0x6Fu) == 0x27u)
		return CO_ST_OP_ENABLED;
	if ((sw & 0x6Fu) == 0x07u)
		return CO_ST_QUICK_STOP;
	if ((sw & 0x4Fu) == 0x0Fu)
		return CO_ST_FAULT_REACTION;
	if ((sw & 0x4Fu) == 0x08u)
		return CO_ST_FAULT;
	return CO_ST_UNKNOWN;
}

const char *co_state_name(co_state_t s)
{
	static const char *const names[] = {
	    "unknown",	   "not ready to switch on", "switch on disabled", "ready to switch on",
	    "switched on", "operation enabled",	     "quick stop active",  "fault reaction active",
	    "fault",
	};
	return (unsigned)s < sizeof(names) / sizeof(names[0]) ? names[s] : "unknown";
}

bool co_state_is_fault(co_state_t s)
{
	return s == CO_ST_FAULT || s == CO_ST_FAULT_REACTION;
}

uint8_t co_hal_phase(co_state_t s)
{
	static const uint8_t ph[] = {
	    [CO_ST_UNKNOWN] = HAL_DRIVE_UNKNOWN,
	    [CO_ST_NOT_READY] = HAL_DRIVE_NOT_READY,
	    [CO_ST_SWITCH_ON_DISABLED] = HAL_DRIVE_SWITCH_ON_DISABLED,
	    [CO_ST_READY] = HAL_DRIVE_READY,
	    [CO_ST_SWITCHED_ON] = HAL_DRIVE_SWITCHED_ON,
	    [CO_ST_OP_ENABLED] = HAL_DRIVE_ENABLED,
	    [CO_ST_QUICK_STOP] = HAL_DRIVE_QUICK_STOP,
	    [CO_ST_FAULT_REACTION] = HAL_DRIVE_FAULT_REACTION,
	    [CO_ST_FAULT] = HAL_DRIVE_FAULT,
	};
	return (unsigned)s < sizeof(ph) ? ph[s] : (uint8_t)HAL_DRIVE_UNKNOWN;
}

uint16_t co_controlword(co_state_t s, bool enable, bool reset)
{
	switch (s) {
	case CO_ST_READY:
		return enable ? CO_CW_SWITCH_ON : CO_CW_SHUTDOWN;
	case CO_ST_SWITCHED_ON:
	case CO_ST_OP_ENABLED:
		return enable ? CO_CW_ENABLE_OP : CO_CW_SHUTDOWN;
	case CO_ST_QUICK_STOP:
	case CO_ST_FAULT_REACTION:
		return CO_CW_DISABLE_VOLTAGE;
	case CO_ST_FAULT:
		/* bit 7 low in every other controlword: each reset is a rising edge */
		return reset ? CO_CW_FAULT_RESET : CO_CW_DISABLE_VOLTAGE;
	case CO_ST_UNKNOWN:
	case CO_ST_NOT_READY:
	case CO_ST_SWITCH_ON_DISABLED:
	default:
		return CO_CW_SHUTDOWN;
	}
}

int32_t co_velocity_of_q8(int32_t q8)
{
	int64_t v = q8 >= 0 ? ((int64_t)q8 + 128) / 256 : ((int64_t)q8 - 128) / 256;
	return (int32_t)v;
}

static void put_le(uint8_t *p, uint32_t v, unsigned n)
{
	for (unsigned i = 0; i < n; i++)
		p[i] = (uint8_t)(v >> (8u * i));
}

static uint32_t get_le(const uint8_t *p, unsigned n)
{
	uint32_t v = 0;
	for (unsigned i = 0; i < n; i++)
		v |= (uint32_t)p[i] << (8u * i);
	return v;
}

void co_nmt_frame(canlink_frame_t *f, uint8_t cs, uint8_t node)
{
	memset(f, 0, sizeof(*f));
	f->id = CO_ID_NMT;
	f->dlc = 2;
	f->data[0] = cs;
	f->data[1] = node;
}

void co_sync_frame(canlink_frame_t *f)
{
	memset(f, 0, sizeof(*f));
	f->id = CO_ID_SYNC;
}

void co_heartbeat_frame(canlink_frame_t *f, uint8_t node, uint8_t state)
{
	memset(f, 0, sizeof(*f));
	f->id = CO_ID_HEARTBEAT + node;
	f->dlc = 1;
	f->data[0] = state;
}

void co_rpdo1_frame(canlink_frame_t *f, uint8_t node, uint16_t cw, int32_t vel)
{
	memset(f, 0, sizeof(*f));
	f->id = CO_ID_RPDO1 + node;
	f->dlc = 6;
	put_le(f->data, cw, 2);
	put_le(f->data + 2, (uint32_t)vel, 4);
}

bool co_tpdo1_decode(const canlink_frame_t *f, uint16_t *sw, int32_t *pos, int8_t *mode)
{
	if (f->dlc < 7)
		return false;
	*sw = (uint16_t)get_le(f->data, 2);
	*pos = (int32_t)get_le(f->data + 2, 4);
	*mode = (int8_t)f->data[6];
	return true;
}

bool co_emcy_decode(const canlink_frame_t *f, co_emcy_t *e)
{
	memset(e, 0, sizeof(*e));
	if (f->dlc < 3)
		return false;
	e->code = (uint16_t)get_le(f->data, 2);
	e->reg = f->data[2];
	for (unsigned i = 3; i < f->dlc && i < 8; i++)
		e->mfr[i - 3] = f->data[i];
	return true;
}

void co_sdo_request_frame(canlink_frame_t *f, uint8_t node, const co_sdo_req_t *r)
{
	memset(f, 0, sizeof(*f));
	f->id = CO_ID_SDO_REQ + node;
	f->dlc = 8;
	unsigned size = r->size >= 1 && r->size <= 4 ? r->size : 4;
	if (r->upload) {
		f->data[0] = 0x40; /* initiate upload */
	} else {
		/* initiate download, expedited, size indicated: 4 - n unused bytes */
		f->data[0] = (uint8_t)(0x23u | ((4u - size) << 2));
		put_le(f->data + 4, r->value, size);
	}
	put_le(f->data + 1, r->index, 2);
	f->data[3] = r->sub;
}

int co_sdo_reply_decode(const canlink_frame_t *f, uint8_t node, const co_sdo_req_t *r,
			uint32_t *value)
{
	*value = 0;
	if (f->id != CO_ID_SDO_REPLY + node)
		return CO_SDO_NOT_OURS;
	if (f->dlc != 8)
		return CO_SDO_BAD;
	uint8_t cs = f->data[0];
	if (cs == 0x80) {
		/* One request per node is outstanding: any abort is its answer,
		 * even one whose multiplexer a device did not echo. */
		*value = get_le(f->data + 4, 4);
		return CO_SDO_ABORT;
	}
	if (get_le(f->data + 1, 2) != r->index || f->data[3] != r->sub)
		return CO_SDO_NOT_OURS;
	if (!r->upload)
		return cs == 0x60 ? CO_SDO_OK : CO_SDO_BAD;
	if ((cs & 0xE2u) != 0x42u)
		return CO_SDO_BAD; /* not an expedited upload reply (segmented: unsupported) */
	unsigned n = (cs & 0x01u) ? 4u - ((cs >> 2) & 3u) : 4u;
	*value = get_le(f->data + 4, n);
	return CO_SDO_OK;
}

const char *co_sdo_abort_text(uint32_t code)
{
	static const struct {
		uint32_t code;
		const char *text;
	} t[] = {
	    {0x05030000, "toggle bit not alternated"},
	    {0x05040000, "SDO protocol timed out"},
	    {0x05040001, "command specifier not valid or unknown"},
	    {0x05040005, "out of memory"},
	    {0x06010000, "unsupported access to an object"},
	    {0x06010001, "attempt to read a write-only object"},
	    {0x06010002, "attempt to write a read-only object"},
	    {0x06020000, "object does not exist in the object dictionary"},
	    {0x06040041, "object cannot be mapped to the PDO"},
	    {0x06040042, "mapped objects would exceed the PDO length"},
	    {0x06040043, "general parameter incompatibility"},
	    {0x06040047, "general internal incompatibility in the device"},
	    {0x06060000, "access failed due to a hardware error"},
	    {0x06070010, "data type or length does not match"},
	    {0x06070012, "data type does not match, length too high"},
	    {0x06070013, "data type does not match, length too low"},
	    {0x06090011, "sub-index does not exist"},
	    {0x06090030, "invalid value for the parameter"},
	    {0x06090031, "value written too high"},
	    {0x06090032, "value written too low"},
	    {0x06090036, "maximum value is less than minimum value"},
	    {0x08000000, "general error"},
	    {0x08000020, "data cannot be transferred or stored to the application"},
	    {0x08000021, "data cannot be transferred because of local control"},
	    {0x08000022, "data cannot be transferred in the present device state"},
	    {0x08000023, "no object dictionary present"},
	};
	for (size_t i = 0; i < sizeof(t) / sizeof(t[0]); i++)
		if (t[i].code == code)
			return t[i].text;
	return "unknown abort code";
}

static unsigned add_dl(co_sdo_req_t *out, unsigned n, uint16_t index, uint8_t sub, uint8_t size,
		       uint32_t value)
{
	if (n < CO_CFG_MAX)
		out[n] = (co_sdo_req_t){.index = index, .sub = sub, .size = size, .value = value};
	return n + 1;
}

unsigned co_config_list(const co_cfg_t *c, uint8_t node, co_sdo_req_t out[CO_CFG_MAX])
{
	unsigned n = 0;
	/* A CiA 402 device at all: device type, profile number in bits 0..15. */
	out[n++] = (co_sdo_req_t){.index = 0x1000,
				  .sub = 0,
				  .size = 4,
				  .upload = true,
				  .value = CO_PROFILE_402,
				  .mask = 0xFFFF};
	/* A drive left enabled (e.g. by a previous run) stops before anything else. */
	n = add_dl(out, n, 0x6040, 0, 2, CO_CW_SHUTDOWN);
	n = add_dl(out, n, 0x60FF, 0, 4, 0);
	n = add_dl(out, n, 0x6060, 0, 1, CO_MODE_PROFILE_VELOCITY);
	/* RPDO1: invalid while mapped, synchronous (applied at the next SYNC). */
	n = add_dl(out, n, 0x1400, 1, 4, 0x80000000u | (CO_ID_RPDO1 + node));
	n = add_dl(out, n, 0x1600, 0, 1, 0);
	n = add_dl(out, n, 0x1600, 1, 4, 0x60400010u); /* controlword, 16 bits */
	n = add_dl(out, n, 0x1600, 2, 4, 0x60FF0020u); /* target velocity, 32 bits */
	n = add_dl(out, n, 0x1600, 0, 1, 2);
	n = add_dl(out, n, 0x1400, 2, 1, 1);
	n = add_dl(out, n, 0x1400, 1, 4, CO_ID_RPDO1 + node);
	/* TPDO1: sent on every SYNC. The mode display rides with each
	 * statusword: enabled means enabled in profile velocity, now. */
	n = add_dl(out, n, 0x1800, 1, 4, 0x80000000u | (CO_ID_TPDO1 + node));
	n = add_dl(out, n, 0x1A00, 0, 1, 0);
	n = add_dl(out, n, 0x1A00, 1, 4, 0x60410010u); /* statusword */
	n = add_dl(out, n, 0x1A00, 2, 4, 0x60640020u); /* position actual value */
	n = add_dl(out, n, 0x1A00, 3, 4, 0x60610008u); /* modes of operation display */
	n = add_dl(out, n, 0x1A00, 0, 1, 3);
	n = add_dl(out, n, 0x1800, 2, 1, 1);
	n = add_dl(out, n, 0x1800, 1, 4, CO_ID_TPDO1 + node);
	n = add_dl(out, n, 0x1017, 0, 2, c->heartbeat_ms);
	if (c->master_node)
		n = add_dl(out, n, 0x1016, 1, 4, ((uint32_t)c->master_node << 16) | c->consumer_ms);
	if (c->profile_accel) {
		n = add_dl(out, n, 0x6083, 0, 4, c->profile_accel);
		n = add_dl(out, n, 0x6084, 0, 4, c->profile_accel);
	}
	return n < CO_CFG_MAX ? n : CO_CFG_MAX;
}

void co_hb_arm(co_hb_t *h, uint32_t now_us)
{
	h->state = CO_HB_NONE;
	h->last_us = now_us;
}

void co_hb_rx(co_hb_t *h, uint8_t state, uint32_t now_us)
{
	h->state = state;
	h->last_us = now_us;
}

bool co_hb_alive(const co_hb_t *h, uint32_t now_us, uint32_t timeout_us)
{
	return h->state == CO_HB_OPERATIONAL && now_us - h->last_us <= timeout_us;
}

/* ==== log lines from the tick ============================================= */

/* The tick formats its log lines into a ring that a thread of normal
 * priority writes out: writing to a pipe, a terminal or syslog can wait,
 * the tick must not. One producer (the loop's thread), one consumer. A
 * full ring drops the line and counts it. Without the thread (start-up,
 * close, host tests) lines are written at once. */
#define LOG_SLOTS 32
#define LOG_LEN	  240

static struct {
	char text[LOG_SLOTS][LOG_LEN];
	int prio[LOG_SLOTS];
	atomic_uint head, tail, dropped;
	atomic_bool stop;
	sem_t sem;
	pthread_t th;
	bool running;
	unsigned users;
} lg;

static void co_log(int prio, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void co_log(int prio, const char *fmt, ...)
{
	va_list ap;
	va_start(ap, fmt);
	if (!lg.running) {
		char line[LOG_LEN];
		vsnprintf(line, sizeof(line), fmt, ap);
		rt_log(prio, "%s", line);
	} else {
		unsigned h = atomic_load_explicit(&lg.head, memory_order_relaxed);
		if (h - atomic_load_explicit(&lg.tail, memory_order_acquire) >= LOG_SLOTS) {
			atomic_fetch_add_explicit(&lg.dropped, 1u, memory_order_relaxed);
		} else {
			vsnprintf(lg.text[h % LOG_SLOTS], LOG_LEN, fmt, ap);
			lg.prio[h % LOG_SLOTS] = prio;
			atomic_store_explicit(&lg.head, h + 1, memory_order_release);
			sem_post(&lg.sem);
		}
	}
	va_end(ap);
}

static void *log_thread(void *arg)
{
	(void)arg;
	for (;;) {
		while (sem_wait(&lg.sem) != 0 && errno == EINTR)
			;
		unsigned t = atomic_load_explicit(&lg.tail, memory_order_relaxed);
		while (t != atomic_load_explicit(&lg.head, memory_order_acquire)) {
			rt_log(lg.prio[t % LOG_SLOTS], "%s", lg.text[t % LOG_SLOTS]);
			atomic_store_explicit(&lg.tail, ++t, memory_order_release);
		}
		unsigned lost = atomic_exchange_explicit(&lg.dropped, 0u, memory_order_relaxed);
		if (lost)
			rt_log(LOG_WARNING, "canopen: %u log lines dropped (more than %u at once)",
			       lost, LOG_SLOTS);
		if (atomic_load(&lg.stop))
			return NULL;
	}
}

static void log_start(void)
{
	if (lg.users++ > 0)
		return;
	atomic_store(&lg.head, 0u);
	atomic_store(&lg.tail, 0u);
	atomic_store(&lg.stop, false);
	/* created before the loop turns to SCHED_FIFO: a normal thread */
	if (sem_init(&lg.sem, 0, 0) == 0) {
		if (pthread_create(&lg.th, NULL, log_thread, NULL) == 0)
			lg.running = true;
		else
			sem_destroy(&lg.sem);
	}
}

/* Writes out what is queued, then lines go out at once again. */
static void log_stop(void)
{
	if (lg.users == 0 || --lg.users > 0 || !lg.running)
		return;
	atomic_store(&lg.stop, true);
	sem_post(&lg.sem);
	pthread_join(lg.th, NULL);
	sem_destroy(&lg.sem);
	lg.running = false;
}

/* ==== the bus ============================================================ */

static int sock_send(void *ctx, const canlink_frame_t *f)
{
	return sockcan_send(ctx, f);
}

static int sock_recv(void *ctx, canlink_frame_t *f)
{
	return sockcan_recv(ctx, f);
}

static int sock_wait(void *ctx, int timeout_ms)
{
	return sockcan_wait(ctx, timeout_ms);
}

static uint32_t mono_ms(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return (uint32_t)((uint64_t)t.tv_sec * 1000u + (uint64_t)t.tv_nsec / 1000000u);
}

void co_bus_init(co_bus_t *b, unsigned index, const bk_canopen_bus_t *cfg)
{
	memset(b, 0, sizeof(*b));
	b->index = index;
	b->cfg = *cfg;
	b->sock.fd = -1;
	b->used = true;
	if (!b->cfg.fault_reset_ms)
		b->cfg.fault_reset_ms = CO_FAULT_RESET_MS;
}

unsigned co_bus_add(co_bus_t *b, uint8_t axis, uint8_t node, bool reverse)
{
	co_drive_t *d = &b->d[b->nd];
	memset(d, 0, sizeof(*d));
	d->node = node;
	d->axis = axis;
	d->reverse = reverse;
	d->hb.state = CO_HB_NONE;
	co_cfg_t c = {.heartbeat_ms = (uint16_t)b->cfg.heartbeat_ms,
		      .master_node = (uint8_t)b->cfg.master_node,
		      .consumer_ms = (uint16_t)b->cfg.heartbeat_timeout_ms,
		      .profile_accel = b->cfg.profile_accel};
	d->ncfg = co_config_list(&c, node, d->cfg);
	return b->nd++;
}

int co_bus_open(co_bus_t *b, char *err, size_t errlen)
{
	uint32_t ids[4 * VS_MAX_AXES];
	size_t n = 0;
	for (unsigned i = 0; i < b->nd; i++) {
		ids[n++] = CO_ID_TPDO1 + b->d[i].node;
		ids[n++] = CO_ID_HEARTBEAT + b->d[i].node;
		ids[n++] = CO_ID_EMCY + b->d[i].node;
		ids[n++] = CO_ID_SDO_REPLY + b->d[i].node;
	}
	if (sockcan_open(&b->sock, b->cfg.interface, ids, n) < 0) {
		snprintf(err, errlen, "canopen bus %u (%s): cannot open: %s", b->index,
			 b->cfg.interface, strerror(errno));
		return -1;
	}
	b->io = (co_io_t){sock_send, sock_recv, sock_wait, &b->sock};
	log_start();
	b->logs = true;
	return 0;
}

static co_drive_t *drive_of(co_bus_t *b, uint32_t node)
{
	for (unsigned i = 0; i < b->nd; i++)
		if (b->d[i].node == node)
			return &b->d[i];
	return NULL;
}

static void set_down(co_bus_t *b)
{
	if (!b->down && b->started) /* at start-up the start fails with this */
		co_log(LOG_ERR,
		       "canopen bus %u (%s): interface is down: no frames go out or arrive",
		       b->index, b->cfg.interface);
	b->down = true;
}

/* One frame out; false when it did not go (counted). */
static bool tx(co_bus_t *b, const canlink_frame_t *f)
{
	int r = b->io.send(b->io.ctx, f);
	if (r > 0) {
		b->tx++;
		if (b->down)
			co_log(LOG_INFO, "canopen bus %u (%s): interface is up again", b->index,
			       b->cfg.interface);
		b->down = false;
		return true;
	}
	if (r == 0) {
		b->tx_full++;
	} else if (errno == ENETDOWN) {
		b->tx_down++;
		set_down(b);
	} else {
		b->tx_errors++;
	}
	return false;
}

#define DRV_FMT	    "canopen bus %u (%s): node %u (axis %u): "
#define DRV_ARGS(d) b->index, b->cfg.interface, (d)->node, (d)->axis

/* A drive restarted or left operational: configure and start it again.
 * Only a restart loses the count: a drive that merely left operational
 * still has its position register, which goes on counting. */
static void reconfigure(co_bus_t *b, co_drive_t *d, const char *why, bool restarted)
{
	co_log(LOG_WARNING, DRV_FMT "%s: configuring it again", DRV_ARGS(d), why);
	d->phase = CO_PHASE_CONFIG;
	d->step = 0;
	d->sdo_pending = d->sdo_got = false;
	d->retry_at_us = b->now_us;
	d->fail_logged = false;
	d->have_status = false;
	d->state = CO_ST_UNKNOWN;
	d->emcy_code = 0;
	d->mode_logged = false;
	if (restarted) {
		d->rebase = true;
		d->lost_pending = true;
	}
	d->tpdo_new = false;
	d->seen_operational = false;
	d->restarts++;
}

static void rx_heartbeat(co_bus_t *b, co_drive_t *d, uint8_t state, uint32_t now_us)
{
	if (!b->started) {
		if (state == CO_HB_BOOTUP)
			d->booted = true;
		co_hb_rx(&d->hb, state, now_us);
		return;
	}
	if (state == CO_HB_BOOTUP) {
		reconfigure(b, d, "boot-up message (the drive restarted)", true);
	} else if (state == CO_HB_PREOP && d->phase == CO_PHASE_RUN && d->seen_operational) {
		reconfigure(b, d, "pre-operational after operational", false);
	} else if (state == CO_HB_OPERATIONAL && d->phase == CO_PHASE_RUN) {
		d->seen_operational = true;
	}
	co_hb_rx(&d->hb, state, now_us);
}

static void rx_tpdo(co_bus_t *b, co_drive_t *d, const canlink_frame_t *f)
{
	uint16_t sw;
	int32_t raw;
	int8_t mode;
	if (!co_tpdo1_decode(f, &sw, &raw, &mode)) {
		b->rx_bad++;
		return;
	}
	if (d->phase != CO_PHASE_RUN)
		return; /* its mapping is being written */
	co_state_t s = co_state_of(sw);
	if (d->have_status && co_state_is_fault(d->state) && !co_state_is_fault(s))
		d->emcy_code = 0; /* that fault is over */
	if (d->rebase) {
		d->pos_offset = (int32_t)((uint32_t)d->pos - (uint32_t)raw);
		d->rebase = false;
	}
	d->raw_pos = raw;
	d->pos = (int32_t)((uint32_t)raw + (uint32_t)d->pos_offset);
	d->status = sw;
	d->state = s;
	d->mode = mode;
	if (mode == CO_MODE_PROFILE_VELOCITY)
		d->mode_logged = false; /* a later change is logged again */
	d->have_status = true;
	d->tpdo_new = true;
}

static void rx_emcy(co_bus_t *b, co_drive_t *d, const canlink_frame_t *f)
{
	co_emcy_t e;
	if (!co_emcy_decode(f, &e)) {
		b->rx_bad++;
		return;
	}
	b->emcy++;
	d->emcy_count++;
	d->emcy_code = e.code;
	if (e.code == 0)
		co_log(LOG_INFO, DRV_FMT "EMCY 0x0000 (error reset), error register 0x%02X",
		       DRV_ARGS(d), e.reg);
	else
		co_log(LOG_ERR,
		       DRV_FMT "EMCY 0x%04X, error register 0x%02X, manufacturer bytes "
			       "%02X %02X %02X %02X %02X",
		       DRV_ARGS(d), e.code, e.reg, e.mfr[0], e.mfr[1], e.mfr[2], e.mfr[3],
		       e.mfr[4]);
}

static void rx_frame(co_bus_t *b, const canlink_frame_t *f, uint32_t now_us)
{
	uint32_t fn = f->id & 0x780u;
	co_drive_t *d = drive_of(b, f->id & 0x7Fu);
	if (!d) {
		b->rx_bad++; /* not a frame of ours (the receive filters let only ours in) */
		return;
	}
	switch (fn) {
	case CO_ID_TPDO1:
		rx_tpdo(b, d, f);
		break;
	case CO_ID_HEARTBEAT:
		if (f->dlc < 1) {
			b->rx_bad++;
			break;
		}
		rx_heartbeat(b, d, f->data[0] & 0x7Fu, now_us);
		break;
	case CO_ID_EMCY:
		rx_emcy(b, d, f);
		break;
	case CO_ID_SDO_REPLY:
		d->sdo_rx = *f;
		d->sdo_got = true;
		break;
	default:
		b->rx_bad++;
		break;
	}
}

/* Drains what arrived, at most max frames. */
static void drain(co_bus_t *b, uint32_t now_us, unsigned max)
{
	canlink_frame_t f;
	for (unsigned n = 0; n < max; n++) {
		int r = b->io.recv(b->io.ctx, &f);
		if (r == 0)
			return;
		if (r < 0) {
			if (errno == ENETDOWN)
				set_down(b);
			else
				b->rx_errors++;
			return;
		}
		b->rx++;
		rx_frame(b, &f, now_us);
	}
}

/* ---- start-up (blocking) ----------------------------------------------- */

static int startup_fail(co_bus_t *b, char *err, size_t errlen, const co_drive_t *d, const char *fmt,
			...) __attribute__((format(printf, 5, 6)));
static int startup_fail(co_bus_t *b, char *err, size_t errlen, const co_drive_t *d, const char *fmt,
			...)
{
	int n = d ? snprintf(err, errlen, DRV_FMT, DRV_ARGS(d))
		  : snprintf(err, errlen, "canopen bus %u (%s): ", b->index, b->cfg.interface);
	if (n >= 0 && (size_t)n < errlen) {
		va_list ap;
		va_start(ap, fmt);
		vsnprintf(err + n, errlen - (size_t)n, fmt, ap);
		va_end(ap);
	}
	return -1;
}

/* Sends one frame, waiting out a full queue up to timeout_ms. */
static int tx_wait(co_bus_t *b, const canlink_frame_t *f, uint32_t timeout_ms, char *err,
		   size_t errlen, const co_drive_t *d)
{
	uint32_t t0 = mono_ms();
	for (;;) {
		uint32_t full = b->tx_full;
		if (tx(b, f))
			return 0;
		if (b->tx_full == full) {
			if (b->down)
				return startup_fail(b, err, errlen, NULL, "interface is down");
			return startup_fail(b, err, errlen, d, "send failed: %s", strerror(errno));
		}
		if (mono_ms() - t0 >= timeout_ms)
			return startup_fail(b, err, errlen, d, "transmit queue full for %u ms",
					    timeout_ms);
		struct timespec ts = {0, 1000000L};
		nanosleep(&ts, NULL);
	}
}

/* Waits up to the deadline for frames and handles them. */
static void wait_frames(co_bus_t *b, uint32_t deadline_ms)
{
	int32_t left = (int32_t)(deadline_ms - mono_ms());
	if (left <= 0)
		return;
	int r = b->io.wait(b->io.ctx, (int)left);
	if (r > 0) {
		drain(b, mono_ms() * 1000u, CO_RX_PER_TICK);
	} else if (r < 0) {
		struct timespec ts = {0, 1000000L};
		nanosleep(&ts, NULL); /* no busy loop on a failing poll */
	}
}

static const char *sdo_verb(const co_sdo_req_t *r)
{
	return r->upload ? "read" : "write";
}

/* One SDO exchange, blocking up to sdo_timeout_ms. */
static int sdo_blocking(co_bus_t *b, co_drive_t *d, const co_sdo_req_t *r, uint32_t *value,
			char *err, size_t errlen)
{
	canlink_frame_t f;
	co_sdo_request_frame(&f, d->node, r);
	d->sdo_got = false;
	if (tx_wait(b, &f, b->cfg.sdo_timeout_ms, err, errlen, d) < 0)
		return -1;
	uint32_t deadline = mono_ms() + b->cfg.sdo_timeout_ms;
	for (;;) {
		if (d->sdo_got) {
			d->sdo_got = false;
			int res = co_sdo_reply_decode(&d->sdo_rx, d->node, r, value);
			if (res == CO_SDO_OK)
				return 0;
			if (res == CO_SDO_ABORT)
				return startup_fail(b, err, errlen, d,
						    "SDO %s 0x%04X:%02X aborted with 0x%08X (%s)",
						    sdo_verb(r), r->index, r->sub, *value,
						    co_sdo_abort_text(*value));
			if (res == CO_SDO_BAD)
				return startup_fail(
				    b, err, errlen, d,
				    "SDO %s 0x%04X:%02X: unexpected reply (command byte 0x%02X)",
				    sdo_verb(r), r->index, r->sub, d->sdo_rx.data[0]);
			/* another object's (late) reply: keep waiting */
		}
		if ((int32_t)(deadline - mono_ms()) <= 0)
			return startup_fail(b, err, errlen, d,
					    "SDO %s 0x%04X:%02X: no reply within %u ms",
					    sdo_verb(r), r->index, r->sub, b->cfg.sdo_timeout_ms);
		wait_frames(b, deadline);
	}
}

int co_bus_start(co_bus_t *b, char *err, size_t errlen)
{
	canlink_frame_t f;
	for (unsigned i = 0; i < b->nd; i++) {
		co_nmt_frame(&f, CO_NMT_RESET_COMM, b->d[i].node);
		if (tx_wait(b, &f, b->cfg.sdo_timeout_ms, err, errlen, &b->d[i]) < 0)
			return -1;
	}
	uint32_t deadline = mono_ms() + b->cfg.boot_timeout_ms;
	for (;;) {
		co_drive_t *missing = NULL;
		for (unsigned i = 0; i < b->nd && !missing; i++)
			if (!b->d[i].booted)
				missing = &b->d[i];
		if (!missing)
			break;
		if ((int32_t)(deadline - mono_ms()) <= 0)
			return startup_fail(
			    b, err, errlen, missing,
			    "no boot-up message within %u ms of reset communication",
			    b->cfg.boot_timeout_ms);
		wait_frames(b, deadline);
	}
	for (unsigned i = 0; i < b->nd; i++) {
		co_drive_t *d = &b->d[i];
		for (unsigned k = 0; k < d->ncfg; k++) {
			const co_sdo_req_t *r = &d->cfg[k];
			uint32_t v = 0;
			if (sdo_blocking(b, d, r, &v, err, errlen) < 0)
				return -1;
			if (r->upload && (v & r->mask) != r->value)
				return startup_fail(b, err, errlen, d,
						    "device type 0x%08X is not a CiA 402 drive "
						    "(profile %u, expected 402)",
						    v, v & 0xFFFFu);
		}
	}
	for (unsigned i = 0; i < b->nd; i++) {
		co_nmt_frame(&f, CO_NMT_START, b->d[i].node);
		if (tx_wait(b, &f, b->cfg.sdo_timeout_ms, err, errlen, &b->d[i]) < 0)
			return -1;
		b->d[i].phase = CO_PHASE_RUN;
	}
	/* Each drive operational by its heartbeat, then its TPDO1 for one SYNC:
	 * the first tick starts from the drives' present positions (a servo-on
	 * before a first sample would sync the wheel loop to a position of 0). */
	deadline = mono_ms() + b->cfg.heartbeat_timeout_ms;
	for (;;) {
		co_drive_t *late = NULL;
		for (unsigned i = 0; i < b->nd && !late; i++)
			if (b->d[i].hb.state != CO_HB_OPERATIONAL)
				late = &b->d[i];
		if (!late)
			break;
		if ((int32_t)(deadline - mono_ms()) <= 0)
			return startup_fail(b, err, errlen, late,
					    "no operational heartbeat within %u ms of NMT start",
					    b->cfg.heartbeat_timeout_ms);
		wait_frames(b, deadline);
	}
	co_sync_frame(&f);
	if (tx_wait(b, &f, b->cfg.sdo_timeout_ms, err, errlen, NULL) < 0)
		return -1;
	deadline = mono_ms() + b->cfg.sdo_timeout_ms;
	for (;;) {
		co_drive_t *late = NULL;
		for (unsigned i = 0; i < b->nd && !late; i++)
			if (!b->d[i].have_status)
				late = &b->d[i];
		if (!late)
			break;
		if ((int32_t)(deadline - mono_ms()) <= 0)
			return startup_fail(b, err, errlen, late, "no TPDO1 within %u ms of SYNC",
					    b->cfg.sdo_timeout_ms);
		wait_frames(b, deadline);
	}
	b->started = true;
	char nodes[96] = "";
	size_t pos = 0;
	for (unsigned i = 0; i < b->nd && pos < sizeof(nodes); i++) {
		int w = snprintf(nodes + pos, sizeof(nodes) - pos, "%s%u (axis %u)", i ? ", " : "",
				 b->d[i].node, b->d[i].axis);
		pos += w > 0 ? (size_t)w : 0;
	}
	rt_log(LOG_INFO,
	       "canopen bus %u (%s): %s %s configured (profile velocity, heartbeat %u ms, "
	       "timeout %u ms%s) and started",
	       b->index, b->cfg.interface, b->nd > 1 ? "nodes" : "node", nodes, b->cfg.heartbeat_ms,
	       b->cfg.heartbeat_timeout_ms,
	       b->cfg.master_node ? ", master heartbeat consumed" : "");
	return 0;
}

/* ---- the tick (never blocks) ------------------------------------------- */

static void config_failed(co_bus_t *b, co_drive_t *d, const char *what, uint32_t code)
{
	const co_sdo_req_t *r = &d->cfg[d->step];
	if (!d->fail_logged) {
		if (code)
			co_log(LOG_ERR,
			       DRV_FMT "SDO %s 0x%04X:%02X %s 0x%08X (%s); again every %u ms",
			       DRV_ARGS(d), sdo_verb(r), r->index, r->sub, what, code,
			       co_sdo_abort_text(code), CO_RETRY_US / 1000u);
		else
			co_log(LOG_ERR, DRV_FMT "SDO %s 0x%04X:%02X: %s; again every %u ms",
			       DRV_ARGS(d), sdo_verb(r), r->index, r->sub, what,
			       CO_RETRY_US / 1000u);
	}
	d->fail_logged = true;
	d->step = 0;
	d->sdo_pending = false;
	d->retry_at_us = b->now_us + CO_RETRY_US;
}

/* One step of a drive's configuration in the tick: at most one SDO
 * request out, its reply checked on a later tick. */
static void config_step(co_bus_t *b, co_drive_t *d)
{
	uint32_t now = b->now_us;
	if (d->sdo_pending) {
		uint32_t v = 0;
		int res = d->sdo_got
			      ? co_sdo_reply_decode(&d->sdo_rx, d->node, &d->cfg[d->step], &v)
			      : CO_SDO_NOT_OURS;
		d->sdo_got = false;
		if (res == CO_SDO_OK) {
			const co_sdo_req_t *r = &d->cfg[d->step];
			if (r->upload && (v & r->mask) != r->value) {
				config_failed(b, d, "gave an unexpected value", 0);
				return;
			}
			d->sdo_pending = false;
			d->step++;
		} else if (res == CO_SDO_ABORT) {
			config_failed(b, d, "aborted with", v);
			return;
		} else if (res == CO_SDO_BAD) {
			config_failed(b, d, "unexpected reply", 0);
			return;
		} else if (now - d->sdo_sent_us > b->cfg.sdo_timeout_ms * 1000u) {
			config_failed(b, d, "no reply", 0);
			return;
		} else {
			return; /* waiting */
		}
	}
	if ((int32_t)(now - d->retry_at_us) < 0)
		return;
	canlink_frame_t f;
	if (d->step < d->ncfg) {
		co_sdo_request_frame(&f, d->node, &d->cfg[d->step]);
		d->sdo_got = false;
		if (tx(b, &f)) {
			d->sdo_pending = true;
			d->sdo_sent_us = now;
		}
		return;
	}
	co_nmt_frame(&f, CO_NMT_START, d->node);
	if (!tx(b, &f))
		return;
	d->phase = CO_PHASE_RUN;
	d->fail_logged = false;
	co_hb_arm(&d->hb, now);
	d->armed_us = now;
	d->hblog = CO_HBLOG_UNKNOWN;
	co_log(LOG_INFO, DRV_FMT "configured again and started", DRV_ARGS(d));
}

/* Heartbeat consumer: whether the drive counts as present, with one log
 * line per change. */
static void supervise(co_bus_t *b, co_drive_t *d)
{
	uint32_t now = b->now_us, tmo = b->cfg.heartbeat_timeout_ms * 1000u;
	d->alive = d->phase == CO_PHASE_RUN && co_hb_alive(&d->hb, now, tmo);
	if (d->phase != CO_PHASE_RUN)
		return;
	if (d->alive && d->hblog != CO_HBLOG_ALIVE) {
		co_log(LOG_INFO, DRV_FMT "operational%s", DRV_ARGS(d),
		       d->hblog == CO_HBLOG_LOST ? " again" : "");
		d->hblog = CO_HBLOG_ALIVE;
	} else if (!d->alive && d->hblog != CO_HBLOG_LOST &&
		   (d->hblog == CO_HBLOG_ALIVE || now - d->armed_us > tmo)) {
		if (d->hb.state != CO_HB_OPERATIONAL && now - d->hb.last_us <= tmo)
			co_log(LOG_ERR, DRV_FMT "lost: heartbeat says NMT state 0x%02X",
			       DRV_ARGS(d), d->hb.state);
		else
			co_log(LOG_ERR, DRV_FMT "lost: no heartbeat for more than %u ms",
			       DRV_ARGS(d), b->cfg.heartbeat_timeout_ms);
		d->hblog = CO_HBLOG_LOST;
	}
}

/* The drive is being configured again, or its heartbeat says an NMT state
 * other than operational (none heard yet: the statusword decides). */
static bool not_operational(const co_drive_t *d)
{
	return d->phase != CO_PHASE_RUN ||
	       (d->hb.state != CO_HB_OPERATIONAL && d->hb.state != CO_HB_NONE);
}

/* Enabled as the drive itself reports it: Operation enabled, in profile
 * velocity by its mode display. */
static bool reports_enabled(const co_drive_t *d)
{
	return d->have_status && d->state == CO_ST_OP_ENABLED &&
	       d->mode == CO_MODE_PROFILE_VELOCITY && !not_operational(d);
}

/* Controlword bit 7 of a fault reset. It rises once the drive is in fault
 * (it is low in every other controlword) and stays up while the drive
 * stays there: a drive still busy with its fault reaction at the edge
 * sees it held. The request ends when the drive leaves fault, or at its
 * bound; the bit is then low for at least one SYNC before another edge. */
static bool fault_reset_bit(co_bus_t *b, co_drive_t *d, co_state_t s)
{
	if (!d->reset_req)
		return false;
	if (!co_state_is_fault(s) || (int32_t)(b->now_us - d->reset_until_us) >= 0) {
		d->reset_req = false;
		return false;
	}
	return s == CO_ST_FAULT;
}

/* The drive would be enabled in a mode other than profile velocity. */
static void mode_refused(co_bus_t *b, co_drive_t *d)
{
	if (d->mode_logged)
		return;
	d->mode_logged = true;
	co_log(LOG_WARNING,
	       DRV_FMT "modes of operation display 0x6061 reads %d, not %u (profile velocity): "
		       "held switched on, not enabled",
	       DRV_ARGS(d), d->mode, CO_MODE_PROFILE_VELOCITY);
}

void co_bus_pre_tick(co_bus_t *b, uint32_t now_us)
{
	if (!b->started)
		return;
	b->now_us = now_us;
	if (!b->have_now) {
		/* Supervision runs on the tick's clock from here. */
		b->have_now = true;
		b->hb_due_us = now_us;
		for (unsigned i = 0; i < b->nd; i++) {
			uint8_t st = b->d[i].hb.state;
			co_hb_arm(&b->d[i].hb, now_us);
			b->d[i].hb.state = st == CO_HB_BOOTUP ? CO_HB_NONE : st;
			b->d[i].armed_us = now_us;
		}
	}
	drain(b, now_us, CO_RX_PER_TICK);
	for (unsigned i = 0; i < b->nd; i++) {
		co_drive_t *d = &b->d[i];
		if (d->phase == CO_PHASE_CONFIG)
			config_step(b, d);
		supervise(b, d);
	}
	canlink_frame_t f;
	if (b->cfg.master_node && (int32_t)(now_us - b->hb_due_us) >= 0) {
		co_heartbeat_frame(&f, (uint8_t)b->cfg.master_node, CO_HB_OPERATIONAL);
		tx(b, &f);
		b->hb_due_us += b->cfg.heartbeat_ms * 1000u;
		if ((int32_t)(now_us - b->hb_due_us) >= 0)
			b->hb_due_us = now_us + b->cfg.heartbeat_ms * 1000u; /* fell behind */
	}
	for (unsigned i = 0; i < b->nd; i++) {
		co_drive_t *d = &b->d[i];
		if (d->phase != CO_PHASE_RUN)
			continue;
		co_state_t s = d->have_status ? d->state : CO_ST_UNKNOWN;
		uint16_t cw = co_controlword(s, d->want_enable, fault_reset_bit(b, d, s));
		if (cw == CO_CW_ENABLE_OP && d->mode != CO_MODE_PROFILE_VELOCITY) {
			/* switched on stays there; operation enabled is disabled */
			cw = CO_CW_SWITCH_ON;
			mode_refused(b, d);
		}
		/* A setpoint only to a drive that reports enabled: one that
		 * reaches Operation enabled starts from 0, not with a step. */
		int32_t v =
		    d->want_enable && reports_enabled(d) ? co_velocity_of_q8(d->target_q8) : 0;
		co_rpdo1_frame(&f, d->node, cw, d->reverse ? -v : v);
		tx(b, &f);
	}
	co_sync_frame(&f);
	tx(b, &f);
}

/* ---- close --------------------------------------------------------------- */

void co_bus_close(co_bus_t *b)
{
	if (!b->used)
		return;
	if (b->logs)
		log_stop(); /* what the tick queued; from here lines go out at once */
	b->logs = false;
	if (b->started && b->down)
		rt_log(LOG_WARNING,
		       "canopen bus %u (%s): interface down at exit: drives not switched off",
		       b->index, b->cfg.interface);
	if (b->started && !b->down) {
		char err[256];
		unsigned done = 0;
		for (unsigned i = 0; i < b->nd; i++) {
			co_drive_t *d = &b->d[i];
			if (d->phase != CO_PHASE_RUN)
				continue;
			const co_sdo_req_t off[] = {
			    {.index = 0x6040, .sub = 0, .size = 2, .value = CO_CW_SHUTDOWN},
			    {.index = 0x60FF, .sub = 0, .size = 4, .value = 0},
			    {.index = 0x1016, .sub = 1, .size = 4, .value = 0},
			};
			/* The consumer off before the master's heartbeat stops, so the
			 * drive does not fault on a normal exit. */
			unsigned n = b->cfg.master_node ? 3 : 2;
			uint32_t v;
			bool ok = true;
			for (unsigned k = 0; k < n && ok; k++)
				ok = sdo_blocking(b, d, &off[k], &v, err, sizeof(err)) == 0;
			if (!ok)
				rt_log(LOG_WARNING, "%s", err);
			canlink_frame_t f;
			co_nmt_frame(&f, CO_NMT_PREOP, d->node);
			if (tx(b, &f) && ok)
				done++;
		}
		rt_log(LOG_INFO,
		       "canopen bus %u (%s): %u of %u drives switched off and pre-operational",
		       b->index, b->cfg.interface, done, b->nd);
	}
	sockcan_close(&b->sock);
	b->started = false;
	b->used = false;
}

int co_bus_counters(const co_bus_t *b, char *buf, size_t len)
{
	return snprintf(buf, len,
			"canopen%u %s tx %u tx_full %u tx_down %u tx_errors %u rx %u rx_errors %u "
			"emcy %u",
			b->index, b->cfg.interface, b->tx, b->tx_full, b->tx_down, b->tx_errors,
			b->rx, b->rx_errors, b->emcy);
}

/* ---- the hal operations -------------------------------------------------- */

void co_drive_set_velocity(co_bus_t *b, unsigned i, int32_t q8)
{
	b->d[i].target_q8 = q8;
}

void co_drive_enable(co_bus_t *b, unsigned i, bool on)
{
	b->d[i].want_enable = on;
	if (!on)
		b->d[i].target_q8 = 0;
}

void co_drive_reset_fault(co_bus_t *b, unsigned i)
{
	/* b->now_us: the last tick's time (a command runs between ticks) */
	b->d[i].reset_req = true;
	b->d[i].reset_until_us = b->now_us + b->cfg.fault_reset_ms * 1000u;
}

void co_drive_read(co_bus_t *b, unsigned i, hal_drive_state_t *st)
{
	co_drive_t *d = &b->d[i];
	memset(st, 0, sizeof(*st));
	st->position_counts = d->reverse ? (int32_t)(0u - (uint32_t)d->pos) : d->pos;
	if (not_operational(d))
		st->phase = HAL_DRIVE_NOT_OPERATIONAL;
	else if (d->have_status)
		st->phase = co_hal_phase(d->state);
	st->enabled = reports_enabled(d);
	/* a fault being reset reads 0 until the drive leaves it or the bound */
	if (d->have_status && co_state_is_fault(d->state) && !d->reset_req)
		st->fault_code = d->emcy_code ? d->emcy_code : (uint16_t)CO_GENERIC_FAULT;
	st->fresh = d->tpdo_new && d->alive;
	d->tpdo_new = false;
	/* with the first sample after the restart, which the firmware takes */
	if (st->fresh && d->lost_pending) {
		st->position_lost = true;
		d->lost_pending = false;
	}
}
