/* Modbus drive profiles; see mbprofile.h. */
#include "mbprofile.h"

#include <stddef.h>

/* The shape vehicle-fw has always used (docs/linux.md, "Modbus RTU
 * drive"): int32 counts/s and counts, high word first, status bit 0,
 * servo on 1/0, fault reset 1, all holding registers. A configuration
 * gives the addresses (reg_*); these are the example map of mbdrive-sim
 * and the tests (0x100..0x107), with the communication timeout at 0x109
 * where a drive has one. */
static const mb_profile_t generic = MBP_GENERIC(0);

/* ZLAC8015D dual-channel hub-motor servo drive (Shenzhen ZLTECH), Modbus
 * RTU. Written from the register map of ZLTECH's "ZLAC8015D" user manual
 * (its RS485/Modbus chapter) as public drivers of that drive reproduce it;
 * no copy of the manual was at hand, so its version is not known here:
 * check each address against the manual of your drive before first use.
 * Certain (the same in every source read): control mode 0x200D (3 =
 * velocity), control word 0x200E (0x08 enable, 0x07 stop, 0x06 clear
 * fault), target speed 0x2088 left / 0x2089 right (int16, r/min), fault
 * code 0x20A5 left / 0x20A6 right, position 0x20A7-0x20A8 left /
 * 0x20A9-0x20AA right (int32 counts, high word first), holding registers.
 * NOT certain: 0x20A2 as the status word with bit 0 saying the power stage
 * is on (named "status word" by one source, its bits by none), and 0x2000
 * as the communication-loss time in ms (the address of that parameter in
 * ZLTECH's CANopen drives; whether the 8015D's Modbus map has it there and
 * in ms is not confirmed). speed_scale 4096/60: r/min of a motor read in
 * 4096 counts per turn (ZLTECH's hub motors); set speed_scale to your
 * motor's counts per turn / 60. */
static const mb_profile_t zlac8015d = {
    .name = "zlac8015d",
    .channels = 2,
    .block = 5, /* 0x20A5..0x20AA are all documented: alarm and position in one read */
    .reg =
	{
	    [MBP_SPEED] = {0x2088, 1, 1, MBP_SIGNED},
	    [MBP_POSITION] = {0x20A7, 2, 2, MBP_SIGNED},
	    [MBP_STATUS] = {0x20A2, 0, 1, 0},
	    [MBP_ALARM] = {0x20A5, 1, 1, 0},
	    [MBP_ENABLE] = {0x200E, 0, 1, 0},
	    [MBP_RESET] = {0x200E, 0, 1, 0},
	    [MBP_COMM_TIMEOUT] = {0x2000, 0, 1, 0},
	},
    .speed_num = 4096,
    .speed_den = 60,
    .status_mask = 0x0001,
    .enable_on = 0x0008,
    .enable_off = 0x0007,
    .reset_value = 0x0006,
    .comm_unit_ms = 1,
    .ninit = 1,
    .init = {{0x200D, 3}},
};

static const mb_profile_t *const builtins[] = {&generic, &zlac8015d};

static const char *const reg_names[MBP_REG_COUNT] = {
    "speed", "position", "status", "alarm", "enable", "reset", "comm_timeout",
};

static bool streq(const char *a, const char *b)
{
	while (*a && *a == *b) {
		a++;
		b++;
	}
	return *a == *b;
}

const mb_profile_t *mbp_builtin_at(unsigned i)
{
	return i < sizeof(builtins) / sizeof(builtins[0]) ? builtins[i] : NULL;
}

const mb_profile_t *mbp_builtin(const char *name)
{
	for (unsigned i = 0; mbp_builtin_at(i); i++)
		if (streq(builtins[i]->name, name))
			return builtins[i];
	return NULL;
}

const char *mbp_reg_name(unsigned r)
{
	return r < MBP_REG_COUNT ? reg_names[r] : "?";
}

/* a / b rounded to the nearest, halves away from zero (b > 0). */
static int64_t div_round(int64_t a, int64_t b)
{
	return a >= 0 ? (a + b / 2) / b : -((-a + b / 2) / b);
}

void mbp_speed_words(const mb_profile_t *p, int32_t cps, uint16_t *w)
{
	const mbp_reg_t *r = &p->reg[MBP_SPEED];
	int64_t v = div_round((int64_t)cps * p->speed_den, p->speed_num);
	bool sgn = (r->flags & MBP_SIGNED) != 0;
	int64_t lo = sgn ? (r->words == 2 ? INT32_MIN : INT16_MIN) : 0;
	int64_t hi = r->words == 2 ? (sgn ? INT32_MAX : (int64_t)UINT32_MAX)
				   : (sgn ? INT16_MAX : (int64_t)UINT16_MAX);
	v = v < lo ? lo : v > hi ? hi : v;
	mbp_put(r, (int32_t)(uint32_t)v, w);
}

int32_t mbp_speed_cps(const mb_profile_t *p, const uint16_t *w)
{
	const mbp_reg_t *r = &p->reg[MBP_SPEED];
	int64_t v = mbp_get(r, w);
	if (r->words == 2 && !(r->flags & MBP_SIGNED))
		v = (int64_t)(uint32_t)v;
	v = div_round(v * p->speed_num, p->speed_den);
	return v > INT32_MAX ? INT32_MAX : v < INT32_MIN ? INT32_MIN : (int32_t)v;
}

/* ---- the text form ---------------------------------------------------- */

/* An unsigned number (decimal, or 0x hex) up to max, ending at one of the
 * characters of stop (or the string's end); *s moves past it. */
static bool num(const char **s, uint32_t max, const char *stop, uint32_t *out)
{
	const char *p = *s;
	uint32_t base = 10, v = 0;
	if (p[0] == '0' && (p[1] == 'x' || p[1] == 'X')) {
		base = 16;
		p += 2;
	}
	const char *start = p;
	for (;; p++) {
		uint32_t d;
		if (*p >= '0' && *p <= '9')
			d = (uint32_t)(*p - '0');
		else if (base == 16 && *p >= 'a' && *p <= 'f')
			d = (uint32_t)(*p - 'a' + 10);
		else if (base == 16 && *p >= 'A' && *p <= 'F')
			d = (uint32_t)(*p - 'A' + 10);
		else
			break;
		if (d > max || v > (max - d) / base)
			return false;
		v = v * base + d;
	}
	if (p == start)
		return false;
	bool end = *p == '\0';
	for (const char *c = stop; !end && *c; c++)
		end = *p == *c;
	if (!end)
		return false;
	*s = p;
	*out = v;
	return true;
}

/* The next space-separated word of *s into w (cap bytes); false at the end
 * or when it does not fit. */
static bool word(const char **s, char *w, unsigned cap)
{
	const char *p = *s;
	while (*p == ' ')
		p++;
	unsigned n = 0;
	while (*p && *p != ' ') {
		if (n + 1 >= cap)
			return false;
		w[n++] = *p++;
	}
	w[n] = '\0';
	*s = p;
	return n > 0;
}

static const char *set_reg(mbp_reg_t *r, const char *val)
{
	static const char *const bad = "not a register: ADDR[+STEP] u16|s16|u32|s32 [hi|lo] "
				       "[holding|input], or none";
	mbp_reg_t n = {0, 0, 0, 0};
	char w[16];
	const char *s = val;
	if (!word(&s, w, sizeof w))
		return bad;
	if (streq(w, "none")) {
		if (word(&s, w, sizeof w))
			return bad;
		*r = n;
		return NULL;
	}
	const char *a = w;
	uint32_t v = 0;
	if (!num(&a, 65535, "+", &v))
		return bad;
	n.addr = (uint16_t)v;
	if (*a == '+') {
		a++;
		if (!num(&a, 255, "", &v))
			return bad;
		n.step = (uint16_t)v;
	}
	if (!word(&s, w, sizeof w))
		return bad;
	if (streq(w, "u16") || streq(w, "s16"))
		n.words = 1;
	else if (streq(w, "u32") || streq(w, "s32"))
		n.words = 2;
	else
		return bad;
	n.flags = w[0] == 's' ? MBP_SIGNED : 0;
	while (word(&s, w, sizeof w)) {
		if (streq(w, "lo") && n.words == 2)
			n.flags |= MBP_LOW_FIRST;
		else if (streq(w, "input"))
			n.flags |= MBP_INPUT;
		else if (!streq(w, "hi") && !streq(w, "holding"))
			return bad;
	}
	*r = n;
	return NULL;
}

static const char *set_init(mb_profile_t *p, const char *val)
{
	static const char *const bad = "not ADDR=VALUE[,ADDR=VALUE...] (at most 4)";
	const char *s = val;
	uint16_t a16[MBP_INIT_MAX], v16[MBP_INIT_MAX];
	uint8_t n = 0;
	while (*s) {
		uint32_t a, v;
		if (n == MBP_INIT_MAX || !num(&s, 65535, "=", &a) || *s++ != '=' ||
		    !num(&s, 65535, ",", &v))
			return bad;
		a16[n] = (uint16_t)a;
		v16[n] = (uint16_t)v;
		n++;
		if (*s == ',' && *++s == '\0')
			return bad;
	}
	/* only a whole list is taken */
	for (uint8_t i = 0; i < n; i++) {
		p->init[i].addr = a16[i];
		p->init[i].value = v16[i];
	}
	p->ninit = n;
	return NULL;
}

const char *mbp_set(mb_profile_t *p, const char *key, const char *val)
{
	static const char *const bad16 = "not a number 0..65535";
	for (unsigned r = 0; r < MBP_REG_COUNT; r++)
		if (streq(key, reg_names[r]))
			return set_reg(&p->reg[r], val);
	const char *s = val;
	uint32_t v = 0, d = 1;
	if (streq(key, "speed_scale")) {
		if (!num(&s, 1000000, "/", &v) || v == 0 ||
		    (*s == '/' && (s++, !num(&s, 1000000, "", &d) || d == 0)))
			return "not N or N/D counts/s per unit, 1..1000000";
		p->speed_num = v;
		p->speed_den = d;
		return NULL;
	}
	if (streq(key, "init"))
		return set_init(p, val);
	if (streq(key, "channels")) {
		if (!num(&s, MBP_CHANNELS_MAX, "", &v) || v == 0)
			return "not 1 or 2";
		p->channels = (uint8_t)v;
		return NULL;
	}
	if (streq(key, "block")) {
		if (!num(&s, 32, "", &v) || v == 0)
			return "not a number 1..32";
		p->block = (uint8_t)v;
		return NULL;
	}
	static const struct {
		const char *key;
		size_t off;
	} u16s[] = {
	    {"status_mask", offsetof(mb_profile_t, status_mask)},
	    {"enable_on", offsetof(mb_profile_t, enable_on)},
	    {"enable_off", offsetof(mb_profile_t, enable_off)},
	    {"reset_value", offsetof(mb_profile_t, reset_value)},
	    {"comm_unit_ms", offsetof(mb_profile_t, comm_unit_ms)},
	};
	for (unsigned i = 0; i < sizeof u16s / sizeof u16s[0]; i++) {
		if (!streq(key, u16s[i].key))
			continue;
		if (!num(&s, 65535, "", &v))
			return bad16;
		*(uint16_t *)((char *)p + u16s[i].off) = (uint16_t)v;
		return NULL;
	}
	return "unknown";
}

const char *mbp_check(const mb_profile_t *p)
{
	static const uint8_t needed[] = {MBP_SPEED, MBP_POSITION, MBP_STATUS, MBP_ENABLE};
	for (unsigned i = 0; i < sizeof needed; i++)
		if (p->reg[needed[i]].words == 0)
			return "speed, position, status and enable are required";
	if (p->channels == 0 || p->channels > MBP_CHANNELS_MAX)
		return "channels: 1 or 2";
	for (unsigned r = 0; r < MBP_REG_COUNT; r++) {
		const mbp_reg_t *g = &p->reg[r];
		if (g->words &&
		    (uint32_t)g->addr + (uint32_t)g->step * (p->channels - 1u) + g->words - 1u >
			65535u)
			return "a channel's register lies beyond 65535";
		bool written = r == MBP_SPEED || r >= MBP_ENABLE;
		if (g->words && written && (g->flags & MBP_INPUT))
			return "a register the master writes cannot be an input register";
	}
	if (p->reg[MBP_SPEED].step == 0 && p->channels > 1)
		return "speed: each channel needs its own register (step)";
	if (p->reg[MBP_POSITION].step == 0 && p->channels > 1)
		return "position: each channel needs its own register (step)";
	if (p->speed_num == 0 || p->speed_den == 0)
		return "speed_scale: zero";
	if (p->status_mask == 0)
		return "status_mask: zero";
	if (p->comm_unit_ms == 0 && p->reg[MBP_COMM_TIMEOUT].words)
		return "comm_unit_ms: zero";
	if (p->block == 0)
		return "block: zero";
	return NULL;
}

/* ---- the sample's reads ------------------------------------------------ */

static const uint8_t sample_regs[3] = {MBP_POSITION, MBP_STATUS, MBP_ALARM};

unsigned mbp_read_plan(const mb_profile_t *p, unsigned ch, unsigned max, mbp_read_t rd[3])
{
	mbp_read_t it[3] = {{0}}; /* cppcheck cannot follow the insertion sort */
	unsigned n = 0, out = 0;
	unsigned block = p->block < max ? p->block : max;
	/* unrolled: on a board's constant profile (MBD_PROFILE) the sort folds */
#pragma GCC unroll 3
	for (unsigned k = 0; k < 3; k++) {
		const mbp_reg_t *g = &p->reg[sample_regs[k]];
		if (!g->words)
			continue;
		mbp_read_t x = {mbp_addr(g, ch), g->words, (g->flags & MBP_INPUT) != 0};
		unsigned j = n++;
		/* sorted by (area, address) */
		while (j > 0 && (it[j - 1].input > x.input ||
				 (it[j - 1].input == x.input && it[j - 1].addr > x.addr))) {
			it[j] = it[j - 1];
			j--;
		}
		it[j] = x;
	}
	/* each joins the read before it when that read's area is its own and
	 * the block spans both, else starts one; unrolled as the sort */
#pragma GCC unroll 3
	for (unsigned k = 0; k < n; k++) {
		if (out && rd[out - 1].input == it[k].input &&
		    (unsigned)(it[k].addr + it[k].n - rd[out - 1].addr) <= block) {
			unsigned end = (unsigned)(it[k].addr + it[k].n) - rd[out - 1].addr;
			if (end > rd[out - 1].n)
				rd[out - 1].n = (uint8_t)end;
		} else {
			rd[out++] = it[k];
		}
	}
	return out;
}

static inline __attribute__((always_inline)) bool from_read(const mb_profile_t *p, unsigned r,
							    unsigned ch, const mbp_read_t *rd,
							    const uint16_t *regs, uint16_t *w)
{
	const mbp_reg_t *g = &p->reg[r];
	uint16_t a = mbp_addr(g, ch);
	if (!g->words || rd->input != ((g->flags & MBP_INPUT) != 0) || a < rd->addr ||
	    (unsigned)(a + g->words) > (unsigned)(rd->addr + rd->n))
		return false;
	for (unsigned k = 0; k < g->words; k++)
		w[k] = regs[(unsigned)(a - rd->addr) + k];
	return true;
}

bool mbp_from_read(const mb_profile_t *p, unsigned r, unsigned ch, const mbp_read_t *rd,
		   const uint16_t *regs, uint16_t *w)
{
	return from_read(p, r, ch, rd, regs, w);
}

void mbp_take_read(const mb_profile_t *p, unsigned ch, const mbp_read_t *rd, const uint16_t *regs,
		   uint16_t val[MBP_REG_COUNT][2])
{
	/* unrolled: on a board's constant profile (MBD_PROFILE) each folds */
#pragma GCC unroll 3
	for (unsigned k = 0; k < 3; k++)
		from_read(p, sample_regs[k], ch, rd, regs, val[sample_regs[k]]);
}

void mbp_sample_set(const mb_profile_t *p, mbp_sample_t *s, const uint16_t val[MBP_REG_COUNT][2])
{
	s->pos = mbp_get(&p->reg[MBP_POSITION], val[MBP_POSITION]);
	s->status = val[MBP_STATUS][0];
	s->alarm =
	    p->reg[MBP_ALARM].words ? (uint16_t)mbp_get(&p->reg[MBP_ALARM], val[MBP_ALARM]) : 0;
	s->fresh = true;
	s->sampled = true;
}

void mbp_report(const mb_profile_t *p, mbp_sample_t *s, bool reverse, hal_drive_state_t *st)
{
	st->position_counts = reverse ? (int32_t)(0u - (uint32_t)s->pos) : s->pos;
	st->fault_code = s->alarm;
	st->enabled = mbp_enabled(p, s->status);
	st->phase = !s->sampled	  ? HAL_DRIVE_UNKNOWN
		    : s->alarm	  ? HAL_DRIVE_FAULT
		    : st->enabled ? HAL_DRIVE_ENABLED
				  : HAL_DRIVE_READY;
	st->position_lost = false;
	st->fresh = s->fresh;
	st->silent_why = (uint8_t)(s->fresh ? HAL_SILENT_NO_REPLY : s->why & 3u);
	s->fresh = false;
}
