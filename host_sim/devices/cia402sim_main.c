/* cia402-sim: CiA 402 servo drives on a SocketCAN interface, for vehicle-fw's
 * guest tests (tests/qemu/fw_cia402.sh). Written apart from the backend
 * (hal/linux/cia402.c) so that it checks it rather than mirrors it.
 *
 *   cia402-sim --if IFACE --node N [--node N]... [--missing INDEX]
 *
 * Each node: boot-up message at start, NMT (start, stop, pre-operational,
 * reset node, reset communication), an expedited SDO server for the
 * objects below (abort 0x06020000 for an unknown object, 0x06090011 for an
 * unknown sub-index, 0x06010002 for a read-only one; a PDO mapping is only
 * written while the PDO is invalid and its sub-index 0 is 0), heartbeat
 * producer (0x1017) and consumer (0x1016:01: a missed heartbeat gives EMCY
 * 0x8130 and the fault state), RPDO1/TPDO1 with the mapping written
 * (synchronous transmission types 0..240; RPDO types 254/255 apply at once),
 * the CiA 402 state machine (controlword level-triggered at each SYNC,
 * fault reset on the rising edge of bit 7, followed by EMCY 0x0000), profile
 * velocity mode (0x6060 = 3 only) integrating the target velocity (counts/s)
 * into the position (counts) with the profile acceleration 0x6083/0x6084
 * when set. --missing INDEX leaves that object out of every node.
 *
 * Prints "cia402-sim: IFACE nodes N..." when ready, then reads commands on
 * stdin, one per line, answering "ok" (or "error: ..."):
 *   fault NODE CODE [REG [MFR]]  EMCY CODE (hex), error register REG (hex,
 *                        default 01), manufacturer bytes MFR (10 hex digits,
 *                        default 0); the drive goes to fault reaction, then
 *                        fault (power stage off)
 *   silent NODE          sends nothing more (heartbeat, PDO, SDO, EMCY)
 *   talk NODE            sends again
 *   reboot NODE          restarts: position 0, switch on disabled,
 *                        communication objects to their defaults, boot-up
 *   state NODE           answers "NODE STATE pos P vel V" instead of "ok"
 *   quit
 */
#include <errno.h>
#include <getopt.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#define MAX_NODES 8

enum { RO = 0, RW = 1 };

/* The object dictionary: one row per (index, sub-index). */
typedef struct {
	uint16_t index;
	uint8_t sub;
	uint8_t size;	/* bytes */
	uint8_t access; /* RO, RW */
	bool pdo;	/* mappable */
	bool comm;	/* a communication object: back to its default on reset comm */
} od_row_t;

static const od_row_t OD[] = {
    {0x1000, 0, 4, RO, false, false}, /* device type */
    {0x1001, 0, 1, RO, true, false},  /* error register */
    {0x1016, 0, 1, RO, false, true},  {0x1016, 1, 4, RW, false, true},
    {0x1017, 0, 2, RW, false, true},  {0x1400, 0, 1, RO, false, true},
    {0x1400, 1, 4, RW, false, true},  {0x1400, 2, 1, RW, false, true},
    {0x1600, 0, 1, RW, false, true},  {0x1600, 1, 4, RW, false, true},
    {0x1600, 2, 4, RW, false, true},  {0x1600, 3, 4, RW, false, true},
    {0x1600, 4, 4, RW, false, true},  {0x1800, 0, 1, RO, false, true},
    {0x1800, 1, 4, RW, false, true},  {0x1800, 2, 1, RW, false, true},
    {0x1A00, 0, 1, RW, false, true},  {0x1A00, 1, 4, RW, false, true},
    {0x1A00, 2, 4, RW, false, true},  {0x1A00, 3, 4, RW, false, true},
    {0x1A00, 4, 4, RW, false, true},  {0x603F, 0, 2, RO, true, false}, /* error code */
    {0x6040, 0, 2, RW, true, false},				       /* controlword */
    {0x6041, 0, 2, RO, true, false},				       /* statusword */
    {0x6060, 0, 1, RW, true, false},				       /* modes of operation */
    {0x6061, 0, 1, RO, true, false},				       /* ... display */
    {0x6064, 0, 4, RO, true, false},				       /* position actual */
    {0x606C, 0, 4, RO, true, false},				       /* velocity actual */
    {0x6083, 0, 4, RW, false, false},				       /* profile acceleration */
    {0x6084, 0, 4, RW, false, false},				       /* profile deceleration */
    {0x60FF, 0, 4, RW, true, false},				       /* target velocity */
};
#define OD_ROWS (sizeof(OD) / sizeof(OD[0]))

enum { S_NOT_READY, S_DISABLED, S_READY, S_ON, S_ENABLED, S_QUICKSTOP, S_REACTION, S_FAULT };
static const char *const state_names[] = {
    "not_ready", "switch_on_disabled", "ready",		 "switched_on",
    "enabled",	 "quick_stop",	       "fault_reaction", "fault"};
static const uint16_t state_sw[] = {0x0000, 0x0240, 0x0231, 0x0233, 0x0237, 0x0217, 0x021F, 0x0218};

typedef struct {
	int64_t pos, rem; /* counts; remainder in counts x us */
	double vel;	  /* counts/s */
	uint64_t last_us;
	uint64_t hb_due_us;
	uint64_t cons_last_us; /* consumer of one heartbeat (0x1016:01) */
	uint32_t v[OD_ROWS];
	int ds; /* drive state S_* */
	unsigned sync_count;
	uint16_t last_cw;
	uint8_t id;
	uint8_t nmt; /* 0x7F pre-operational, 0x05 operational, 0x04 stopped */
	bool silent;
	bool cons_armed;
	/* RPDO1 data waiting for the SYNC */
	bool rpdo_new;
	uint8_t rpdo_len;
	uint8_t rpdo[8];
} node_t;

static node_t nodes[MAX_NODES];
static unsigned nnodes;
static int sock = -1;
static uint16_t missing = 0xFFFF; /* --missing: 0xFFFF none */
static unsigned long tx_errors;

static uint64_t now_us(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return (uint64_t)t.tv_sec * 1000000u + (uint64_t)t.tv_nsec / 1000u;
}

static int row_of(uint16_t index, uint8_t sub, bool *index_exists)
{
	*index_exists = false;
	if (index == missing)
		return -1;
	for (unsigned i = 0; i < OD_ROWS; i++) {
		if (OD[i].index != index)
			continue;
		*index_exists = true;
		if (OD[i].sub == sub)
			return (int)i;
	}
	return -1;
}

static uint32_t *obj(node_t *n, uint16_t index, uint8_t sub)
{
	bool ex;
	int r = row_of(index, sub, &ex);
	static uint32_t dummy;
	if (r < 0) {
		dummy = 0;
		return &dummy;
	}
	return &n->v[r];
}

static void send_frame(const node_t *n, uint32_t id, const uint8_t *data, uint8_t len)
{
	struct can_frame f;
	if (n && n->silent)
		return;
	memset(&f, 0, sizeof(f));
	f.can_id = id;
	f.len = len;
	if (len)
		memcpy(f.data, data, len);
	if (write(sock, &f, sizeof(f)) != (ssize_t)sizeof(f))
		tx_errors++; /* ENETDOWN while the interface is down, ENOBUFS */
}

static void comm_defaults(node_t *n)
{
	for (unsigned i = 0; i < OD_ROWS; i++)
		if (OD[i].comm)
			n->v[i] = 0;
	*obj(n, 0x1016, 0) = 1;
	*obj(n, 0x1400, 0) = 2;
	*obj(n, 0x1800, 0) = 5;
	*obj(n, 0x1400, 1) = 0x80000200u + n->id; /* invalid until configured */
	*obj(n, 0x1800, 1) = 0x80000180u + n->id;
	*obj(n, 0x1400, 2) = 255;
	*obj(n, 0x1800, 2) = 255;
	n->cons_armed = false;
	n->rpdo_new = false;
	n->sync_count = 0;
}

static void integrate(node_t *n, uint64_t t);

static void set_state(node_t *n, int ds)
{
	if (ds != S_ENABLED && n->vel != 0) {
		integrate(n, now_us());
		n->vel = 0; /* power stage off (a real one would coast or brake) */
		*obj(n, 0x606C, 0) = 0;
	}
	n->ds = ds;
	*obj(n, 0x6041, 0) = state_sw[ds];
}

static void boot(node_t *n, bool application)
{
	if (application) {
		for (unsigned i = 0; i < OD_ROWS; i++)
			n->v[i] = 0;
		*obj(n, 0x1000, 0) = 0x00020192u; /* CiA 402, servo drive */
		n->pos = n->rem = 0;
		n->vel = 0;
		n->last_cw = 0;
		set_state(n, S_DISABLED);
	}
	comm_defaults(n);
	n->nmt = 0x7F;
	uint8_t b = 0;
	send_frame(n, 0x700u + n->id, &b, 1);
	n->hb_due_us = now_us();
}

static void emcy(node_t *n, uint16_t code, uint8_t reg, const uint8_t mfr[5])
{
	uint8_t d[8] = {(uint8_t)code, (uint8_t)(code >> 8), reg, 0, 0, 0, 0, 0};
	if (mfr)
		memcpy(d + 3, mfr, 5);
	*obj(n, 0x603F, 0) = code;
	*obj(n, 0x1001, 0) = reg;
	send_frame(n, 0x80u + n->id, d, 8);
}

static void enter_fault(node_t *n, uint16_t code, uint8_t reg, const uint8_t mfr[5])
{
	emcy(n, code, reg, mfr);
	set_state(n, S_REACTION);
}

/* Position to now at the present velocity. */
static void integrate(node_t *n, uint64_t t)
{
	uint64_t dt = t - n->last_us;
	n->last_us = t;
	n->rem += (int64_t)(n->vel * (double)dt);
	int64_t whole = n->rem / 1000000;
	n->pos += whole;
	n->rem -= whole * 1000000;
	*obj(n, 0x6064, 0) = (uint32_t)(int32_t)n->pos;
}

/* The CiA 402 state machine, one evaluation of the controlword. */
static void controlword(node_t *n, uint16_t cw)
{
	bool edge = (cw & 0x80) && !(n->last_cw & 0x80);
	n->last_cw = cw;
	int s = n->ds;
	if (s == S_FAULT) {
		if (edge) {
			set_state(n, S_DISABLED);
			emcy(n, 0, 0, NULL); /* error reset */
		}
		return;
	}
	if (s == S_REACTION || s == S_NOT_READY || (cw & 0x80))
		return;
	if (!(cw & 0x02)) { /* disable voltage */
		set_state(n, S_DISABLED);
		return;
	}
	if (!(cw & 0x04)) { /* quick stop */
		set_state(n, s == S_ENABLED ? S_QUICKSTOP : S_DISABLED);
		return;
	}
	bool on = cw & 0x01, op = cw & 0x08;
	if (!on) { /* shutdown */
		if (s == S_DISABLED || s == S_ON || s == S_ENABLED)
			set_state(n, S_READY);
	} else if (!op) { /* switch on / disable operation */
		if (s == S_READY || s == S_ENABLED)
			set_state(n, S_ON);
	} else { /* enable operation */
		if (s == S_READY)
			set_state(n, S_ON);
		else if (s == S_ON || s == S_QUICKSTOP)
			set_state(n, S_ENABLED);
	}
}

/* Velocity toward the target within the profile acceleration. */
static void update_velocity(node_t *n, double dt_s)
{
	double target = 0;
	if (n->ds == S_ENABLED && (int8_t)*obj(n, 0x6061, 0) == 3)
		target = (double)(int32_t)*obj(n, 0x60FF, 0);
	double acc = (double)*obj(n, 0x6083, 0), dec = (double)*obj(n, 0x6084, 0);
	double lim = (target * target >= n->vel * n->vel ? acc : dec) * dt_s;
	if (n->ds != S_ENABLED || lim <= 0 || (target - n->vel <= lim && n->vel - target <= lim))
		n->vel = target; /* no profile ramp, or within one step */
	else
		n->vel += target > n->vel ? lim : -lim;
	*obj(n, 0x606C, 0) = (uint32_t)(int32_t)n->vel;
}

/* Writes PDO data into the mapped objects. */
static void rpdo_apply(node_t *n)
{
	unsigned cnt = *obj(n, 0x1600, 0), at = 0;
	bool cw = false;
	for (unsigned k = 1; k <= cnt && k <= 4; k++) {
		uint32_t m = *obj(n, 0x1600, (uint8_t)k);
		uint16_t idx = (uint16_t)(m >> 16);
		uint8_t sub = (uint8_t)(m >> 8), bytes = (uint8_t)((m & 0xFF) / 8);
		uint32_t v = 0;
		for (unsigned i = 0; i < bytes && at + i < 8; i++)
			v |= (uint32_t)n->rpdo[at + i] << (8 * i);
		at += bytes;
		*obj(n, idx, sub) = v;
		cw = cw || idx == 0x6040;
	}
	n->rpdo_new = false;
	if (cw)
		controlword(n, (uint16_t)*obj(n, 0x6040, 0));
}

static void tpdo_send(node_t *n)
{
	uint8_t d[8] = {0};
	unsigned cnt = *obj(n, 0x1A00, 0), at = 0;
	for (unsigned k = 1; k <= cnt && k <= 4; k++) {
		uint32_t m = *obj(n, 0x1A00, (uint8_t)k);
		uint32_t v = *obj(n, (uint16_t)(m >> 16), (uint8_t)(m >> 8));
		for (unsigned i = 0; i < (m & 0xFF) / 8 && at < 8; i++)
			d[at++] = (uint8_t)(v >> (8 * i));
	}
	send_frame(n, *obj(n, 0x1800, 1) & 0x7FF, d, (uint8_t)at);
}

static void on_sync(node_t *n, uint64_t t)
{
	if (n->nmt != 0x05)
		return;
	double dt = (double)(t - n->last_us) / 1e6;
	integrate(n, t);
	if (n->ds == S_REACTION)
		set_state(n, S_FAULT);
	uint32_t rtype = *obj(n, 0x1400, 2);
	if (n->rpdo_new && rtype <= 240)
		rpdo_apply(n);
	else if (rtype <= 240)
		controlword(n, n->last_cw); /* level-triggered: e.g. 0x0F on from switched on */
	update_velocity(n, dt);
	uint32_t ttype = *obj(n, 0x1800, 2), cob = *obj(n, 0x1800, 1);
	n->sync_count++;
	if (!(cob & 0x80000000u) && ttype <= 240 && n->sync_count % (ttype ? ttype : 1) == 0)
		tpdo_send(n);
}

static void sdo_reply(node_t *n, const uint8_t *d, uint8_t cs, uint32_t value)
{
	uint8_t r[8] = {cs,
			d[1],
			d[2],
			d[3],
			(uint8_t)value,
			(uint8_t)(value >> 8),
			(uint8_t)(value >> 16),
			(uint8_t)(value >> 24)};
	send_frame(n, 0x580u + n->id, r, 8);
}

static bool mapping_ok(uint32_t m, unsigned *bits)
{
	bool ex;
	int r = row_of((uint16_t)(m >> 16), (uint8_t)(m >> 8), &ex);
	*bits = m & 0xFF;
	return r >= 0 && OD[r].pdo && OD[r].size * 8u == *bits;
}

/* Object-specific write rules; 0 or an abort code. */
static uint32_t write_check(node_t *n, uint16_t index, uint8_t sub, uint32_t v)
{
	if (index == 0x1600 || index == 0x1A00) {
		uint16_t comm = index == 0x1600 ? 0x1400 : 0x1800;
		if (!(*obj(n, comm, 1) & 0x80000000u))
			return 0x06010000; /* PDO valid: mapping locked */
		unsigned bits;
		if (sub == 0) {
			if (v > 4)
				return 0x06040042;
			unsigned total = 0;
			for (unsigned k = 1; k <= v; k++) {
				if (!mapping_ok(*obj(n, index, (uint8_t)k), &bits))
					return 0x06040041;
				total += bits;
			}
			return total > 64 ? 0x06040042 : 0;
		}
		if (*obj(n, index, 0) != 0)
			return 0x06010000; /* sub-index 0 must be 0 first */
		return mapping_ok(v, &bits) ? 0 : 0x06040041;
	}
	if ((index == 0x1400 || index == 0x1800) && sub == 1) {
		uint32_t old = *obj(n, index, 1);
		if (v & 0x20000000u)
			return 0x06090030; /* extended frames: not here */
		if (!(old & 0x80000000u) && !(v & 0x80000000u) && (old & 0x7FF) != (v & 0x7FF))
			return 0x06090030; /* a valid PDO's id changes only through invalid */
	}
	if (index == 0x6060 && v != 3)
		return 0x06090030; /* profile velocity only */
	return 0;
}

static void sdo_server(node_t *n, const uint8_t *d)
{
	uint8_t ccs = d[0] >> 5;
	uint16_t index = (uint16_t)(d[1] | d[2] << 8);
	uint8_t sub = d[3];
	bool ex;
	if (ccs == 4)
		return; /* abort from the client */
	if (ccs != 1 && ccs != 2) {
		sdo_reply(n, d, 0x80, 0x05040001);
		return;
	}
	int r = row_of(index, sub, &ex);
	if (r < 0) {
		sdo_reply(n, d, 0x80, ex ? 0x06090011 : 0x06020000);
		return;
	}
	unsigned size = OD[r].size;
	if (ccs == 2) {
		sdo_reply(n, d, (uint8_t)(0x43 | ((4 - size) << 2)), n->v[r]);
		return;
	}
	if (!(d[0] & 0x02)) {
		sdo_reply(n, d, 0x80, 0x05040001); /* segmented: not served */
		return;
	}
	if (OD[r].access == RO) {
		sdo_reply(n, d, 0x80, 0x06010002);
		return;
	}
	unsigned len = (d[0] & 0x01) ? 4u - ((d[0] >> 2) & 3u) : size;
	if (len != size) {
		sdo_reply(n, d, 0x80, len > size ? 0x06070012 : 0x06070013);
		return;
	}
	uint32_t v = 0;
	for (unsigned i = 0; i < len; i++)
		v |= (uint32_t)d[4 + i] << (8 * i);
	uint32_t abort_code = write_check(n, index, sub, v);
	if (abort_code) {
		sdo_reply(n, d, 0x80, abort_code);
		return;
	}
	n->v[r] = v;
	if (index == 0x6060)
		*obj(n, 0x6061, 0) = v;
	if (index == 0x6040)
		controlword(n, (uint16_t)v);
	if (index == 0x1016)
		n->cons_armed = false; /* monitoring starts with the next heartbeat */
	if (index == 0x1017)
		n->hb_due_us = now_us() + (uint64_t)v * 1000u;
	sdo_reply(n, d, 0x60, 0);
}

static void nmt(node_t *n, uint8_t cs)
{
	switch (cs) {
	case 0x01:
		n->nmt = 0x05;
		n->last_us = now_us();
		break;
	case 0x02:
		n->nmt = 0x04;
		break;
	case 0x80:
		n->nmt = 0x7F;
		break;
	case 0x81:
		boot(n, true);
		break;
	case 0x82:
		boot(n, false);
		break;
	default:
		break;
	}
}

static void on_frame(const struct can_frame *f, uint64_t t)
{
	if (f->can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG | CAN_ERR_FLAG))
		return;
	uint32_t id = f->can_id & CAN_SFF_MASK;
	for (unsigned i = 0; i < nnodes; i++) {
		node_t *n = &nodes[i];
		if (id == 0 && f->len == 2 && (f->data[1] == 0 || f->data[1] == n->id))
			nmt(n, f->data[0]);
		else if (id == 0x80 && f->len == 0)
			on_sync(n, t);
		else if (id == 0x600u + n->id && f->len == 8 && n->nmt != 0x04)
			sdo_server(n, f->data);
		else if (n->nmt == 0x05 && !(*obj(n, 0x1400, 1) & 0x80000000u) &&
			 id == (*obj(n, 0x1400, 1) & 0x7FF)) {
			memset(n->rpdo, 0, sizeof(n->rpdo));
			memcpy(n->rpdo, f->data, f->len);
			n->rpdo_len = f->len;
			n->rpdo_new = true;
			if (*obj(n, 0x1400, 2) > 240)
				rpdo_apply(n);
		} else if (id >= 0x701 && id <= 0x77F) {
			uint32_t c = *obj(n, 0x1016, 1);
			if (c && ((c >> 16) & 0x7F) == id - 0x700u) {
				n->cons_armed = true;
				n->cons_last_us = t;
			}
		}
	}
}

/* Heartbeats due and consumer timeouts; returns the ms to the next event. */
static int timers(uint64_t t)
{
	uint64_t next = t + 100000;
	for (unsigned i = 0; i < nnodes; i++) {
		node_t *n = &nodes[i];
		uint32_t period = *obj(n, 0x1017, 0) * 1000u;
		if (period) {
			if (t >= n->hb_due_us) {
				send_frame(n, 0x700u + n->id, &n->nmt, 1);
				n->hb_due_us += period;
				if (n->hb_due_us <= t)
					n->hb_due_us = t + period;
			}
			if (n->hb_due_us < next)
				next = n->hb_due_us;
		}
		uint32_t c = *obj(n, 0x1016, 1), tmo = (c & 0xFFFF) * 1000u;
		if (c && tmo && n->cons_armed) {
			if (t - n->cons_last_us > tmo) {
				n->cons_armed = false;
				integrate(n, t);
				if (n->ds != S_FAULT && n->ds != S_REACTION) {
					enter_fault(n, 0x8130, 0x11, NULL); /* heartbeat error */
					set_state(n, S_FAULT);
				}
			} else if (n->cons_last_us + tmo + 1 < next) {
				next = n->cons_last_us + tmo + 1;
			}
		}
	}
	return next > t ? (int)((next - t + 999) / 1000) : 0;
}

static node_t *node_by_id(long id)
{
	for (unsigned i = 0; i < nnodes; i++)
		if (nodes[i].id == id)
			return &nodes[i];
	return NULL;
}

/* Whole-string number in [0, max]. */
static bool parse_num(const char *t, int base, unsigned long long max, unsigned long long *out)
{
	char *end;
	errno = 0;
	unsigned long long v = strtoull(t, &end, base);
	if (*t == '\0' || *t == '-' || *end != '\0' || errno || v > max)
		return false;
	*out = v;
	return true;
}

/* One command line; false on quit. */
static bool command(char *line)
{
	char *save = NULL, *tok[6];
	int nt = 0;
	for (char *t = strtok_r(line, " \t\r", &save); t && nt < 6;
	     t = strtok_r(NULL, " \t\r", &save))
		tok[nt++] = t;
	if (nt >= 1 && !strcmp(tok[0], "quit"))
		return false;
	unsigned long long id = 0;
	node_t *n = nt >= 2 && parse_num(tok[1], 10, 127, &id) ? node_by_id((long)id) : NULL;
	if (!n) {
		printf("error: COMMAND NODE ... with a node of this simulator\n");
		return true;
	}
	const char *cmd = tok[0];
	uint64_t t = now_us();
	if (!strcmp(cmd, "fault")) {
		unsigned long long code = 0, reg = 1, m = 0;
		uint8_t mfr[5];
		if (nt < 3 || !parse_num(tok[2], 16, 0xFFFF, &code) ||
		    (nt > 3 && !parse_num(tok[3], 16, 0xFF, &reg)) ||
		    (nt > 4 && !parse_num(tok[4], 16, 0xFFFFFFFFFFull, &m))) {
			printf("error: fault NODE CODE [REG [MFR]]\n");
			return true;
		}
		for (int i = 0; i < 5; i++)
			mfr[i] = (uint8_t)(m >> (8 * (4 - i)));
		enter_fault(n, (uint16_t)code, (uint8_t)reg, mfr);
	} else if (!strcmp(cmd, "silent")) {
		n->silent = true;
	} else if (!strcmp(cmd, "talk")) {
		n->silent = false;
	} else if (!strcmp(cmd, "reboot")) {
		boot(n, true);
	} else if (!strcmp(cmd, "state")) {
		integrate(n, t);
		printf("%u %s pos %lld vel %.0f\n", n->id, state_names[n->ds], (long long)n->pos,
		       n->vel);
		return true;
	} else {
		printf("error: unknown command '%s'\n", cmd);
		return true;
	}
	printf("ok\n");
	return true;
}

int main(int argc, char **argv)
{
	const char *ifname = NULL;
	static const struct option opts[] = {{"if", required_argument, NULL, 'i'},
					     {"node", required_argument, NULL, 'n'},
					     {"missing", required_argument, NULL, 'm'},
					     {NULL, 0, NULL, 0}};
	int o;
	setvbuf(stdout, NULL, _IOLBF, 0);
	while ((o = getopt_long(argc, argv, "", opts, NULL)) != -1) {
		char *end;
		long v;
		switch (o) {
		case 'i':
			ifname = optarg;
			break;
		case 'n':
			v = strtol(optarg, &end, 0);
			if (*end || v < 1 || v > 127 || nnodes == MAX_NODES || node_by_id(v)) {
				fprintf(stderr,
					"cia402-sim: --node: 1..127, distinct, at most %d\n",
					MAX_NODES);
				return 2;
			}
			nodes[nnodes++].id = (uint8_t)v;
			break;
		case 'm':
			v = strtol(optarg, &end, 0);
			if (*end || v < 0 || v > 0xFFFE) {
				fprintf(stderr, "cia402-sim: --missing: an object index\n");
				return 2;
			}
			missing = (uint16_t)v;
			break;
		default:
			fprintf(stderr, "usage: cia402-sim --if IFACE --node N [--node N]... "
					"[--missing INDEX]\n");
			return 2;
		}
	}
	if (!ifname || !nnodes || strlen(ifname) >= IFNAMSIZ) {
		fprintf(stderr, "usage: cia402-sim --if IFACE --node N [--node N]... "
				"[--missing INDEX]\n");
		return 2;
	}
	sock = socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK, CAN_RAW);
	struct ifreq ifr;
	memset(&ifr, 0, sizeof(ifr));
	memcpy(ifr.ifr_name, ifname, strlen(ifname));
	struct sockaddr_can addr;
	memset(&addr, 0, sizeof(addr));
	addr.can_family = AF_CAN;
	if (sock < 0 || ioctl(sock, SIOCGIFINDEX, &ifr) < 0) {
		fprintf(stderr, "cia402-sim: %s: %s\n", ifname, strerror(errno));
		return 1;
	}
	addr.can_ifindex = ifr.ifr_ifindex;
	if (bind(sock, (struct sockaddr *)&addr, sizeof(addr)) < 0) {
		fprintf(stderr, "cia402-sim: bind %s: %s\n", ifname, strerror(errno));
		return 1;
	}
	printf("cia402-sim: %s nodes", ifname);
	for (unsigned i = 0; i < nnodes; i++) {
		nodes[i].last_us = now_us();
		boot(&nodes[i], true);
		printf(" %u", nodes[i].id);
	}
	printf("\n");

	char line[128];
	size_t have = 0;
	for (;;) {
		int wait_ms = timers(now_us());
		struct pollfd p[2] = {{.fd = sock, .events = POLLIN}, {.fd = 0, .events = POLLIN}};
		if (poll(p, 2, wait_ms) < 0 && errno != EINTR)
			return 1;
		if (p[0].revents) {
			struct can_frame f;
			while (read(sock, &f, sizeof(f)) == (ssize_t)sizeof(f))
				on_frame(&f, now_us());
		}
		if (p[1].revents) {
			ssize_t r = read(0, line + have, sizeof(line) - 1 - have);
			if (r <= 0)
				break; /* stdin closed */
			have += (size_t)r;
			line[have] = '\0';
			char *nl;
			while ((nl = strchr(line, '\n')) != NULL) {
				*nl = '\0';
				if (!command(line))
					goto out;
				size_t rest = have - (size_t)(nl + 1 - line);
				memmove(line, nl + 1, rest + 1);
				have = rest;
			}
			if (have == sizeof(line) - 1)
				have = 0; /* an overlong line: dropped */
		}
	}
out:
	fprintf(stderr, "cia402-sim: exit, %lu frames not sent\n", tx_errors);
	return 0;
}
