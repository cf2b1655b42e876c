/* Configuration defaults and validation, from the table of
 * config_fields.def.
 *
 * Runs once at init, before anything moves. With vs_api.c it is the only
 * firmware code that computes with vs_real_t (real.h): doubles on a host
 * (soft-float is fine here), Q32 on a board built with VS_REAL_Q32. Every
 * range test is written so that NaN fails it too.
 */
#include <stddef.h>

#include "config.h"
#include "fx.h"

/* The C type of each row type. */
#define VS_CFG_CTYPE_DOUBLE vs_real_t
#define VS_CFG_CTYPE_U32    uint32_t
#define VS_CFG_CTYPE_U16    uint16_t
#define VS_CFG_CTYPE_BOOL   bool
#define VS_CFG_CTYPE_KIN    vs_kinematics_t
/* A row's constant (default or bound) in its member's type. */
#define VS_CFG_CONST_DOUBLE(x) VS_REAL(x)
#define VS_CFG_CONST_U32(x)    (x)
#define VS_CFG_CONST_U16(x)    (x)
#define VS_CFG_CONST_BOOL(x)   (x)
#define VS_CFG_CONST_KIN(x)    (x)
/* Element k of row member m of type t in configuration c (const: CELEM). */
#define ELEM(c, m, t, k)  (((VS_CFG_CTYPE_##t *)(void *)&(c)->m)[k])
#define CELEM(c, m, t, k) (((const VS_CFG_CTYPE_##t *)(const void *)&(c)->m)[k])

/* Each row's type and count match its member. */
#define ROW_SIZE(m, n, t, ...)                                                                     \
	_Static_assert(sizeof(((vs_config_t *)0)->m) == (n) * sizeof(VS_CFG_CTYPE_##t),            \
		       #m ": type or n");
VS_CONFIG_FIELDS(ROW_SIZE)
#undef ROW_SIZE
_Static_assert(sizeof(vs_config_t) <= UINT16_MAX, "offsets fit the rows");

/* The firmware's columns for readers: names, where and what. */
#define ROW(m, cnt, t, d, lo, hi, ex, w, ...)                                                      \
	{.name = #m,                                                                               \
	 .hi8 = (int32_t)((hi)*8),                                                                 \
	 .off = (uint16_t)offsetof(vs_config_t, m),                                                \
	 .lo8 = (int16_t)((lo)*8),                                                                 \
	 .type = VS_CFG_##t,                                                                       \
	 .n = (cnt),                                                                               \
	 .when = VS_CFG_WHEN_##w,                                                                  \
	 .lo_excl = (ex)},
const vs_config_field_t vs_config_fields[VS_CONFIG_NFIELDS] = {VS_CONFIG_FIELDS(ROW)};
#undef ROW

/* Element k of row f's member, as the given type. */
#ifndef VS_REAL_Q32
#define AT(type)  (((type *)(void *)((char *)c + f->off))[k])
#define CAT(type) (((const type *)(const void *)((const char *)c + f->off))[k])

double vs_config_get(const vs_config_t *c, const vs_config_field_t *f, unsigned k)
{
	switch (f->type) {
	case VS_CFG_DOUBLE:
		return CAT(double);
	case VS_CFG_U32:
		return (double)CAT(uint32_t);
	case VS_CFG_U16:
		return (double)CAT(uint16_t);
	case VS_CFG_BOOL:
		return CAT(bool) ? 1.0 : 0.0;
	default:
		return (double)CAT(vs_kinematics_t);
	}
}

void vs_config_set(vs_config_t *c, const vs_config_field_t *f, unsigned k, double v)
{
	switch (f->type) {
	case VS_CFG_DOUBLE:
		AT(double) = v;
		break;
	case VS_CFG_U32:
		AT(uint32_t) = (uint32_t)v;
		break;
	case VS_CFG_U16:
		AT(uint16_t) = (uint16_t)v;
		break;
	case VS_CFG_BOOL:
		AT(bool) = v != 0.0;
		break;
	default:
		AT(vs_kinematics_t) = (vs_kinematics_t)(int)v;
		break;
	}
}
#undef AT
#undef CAT
#endif

/* io.xml of the reference base: two inputs, two outputs; the other
 * entries zero. Whole entries copied: a loop per field and per name byte
 * took more flash than the entries' bytes. */
static void default_io(vs_config_t *c)
{
	static const vs_io_def_t io[] = {
	    {1, VS_IO_IN, 8, "din0"},
	    {2, VS_IO_IN, 1, "dock_contact"},
	    {3, VS_IO_OUT, 8, "dout0"},
	    {4, VS_IO_OUT, 1, "lamp"},
	};
	_Static_assert(sizeof io / sizeof io[0] <= VS_MAX_IO, "the reference base's io.xml fits");
	c->num_io = (uint8_t)(sizeof io / sizeof io[0]);
	for (unsigned i = 0; i < VS_MAX_IO; i++)
		c->io[i] = i < c->num_io ? io[i] : (vs_io_def_t){0};
}

/* Reference differential base: 150 mm wheels, 400 mm track, 4096-line
 * encoders read in quadrature, 24 V battery pack (the table's defaults). */
void vs_config_defaults(vs_config_t *c)
{
	/* Field by field: the struct is large and firmware has no memset. The
	 * rows expand to stores of constants, which a compiler can follow into
	 * vs_config_check. */
#define SET_DEFAULT(m, n, t, d, ...)                                                               \
	for (unsigned k = 0; k < (n); k++)                                                         \
		ELEM(c, m, t, k) = (VS_CFG_CTYPE_##t)VS_CFG_CONST_##t(d);
	VS_CONFIG_FIELDS(SET_DEFAULT)
#undef SET_DEFAULT
	c->firmware_version = NULL;
	default_io(c);
}

static bool in_range(vs_real_t x, vs_real_t lo, vs_real_t hi)
{
	return lo <= x && x <= hi;
}

/* 0 < x <= hi (NaN fails). */
FX_HELPER bool positive_upto(vs_real_t x, vs_real_t hi)
{
	return x > 0 && x <= hi;
}

/* lo <= x <= hi, or lo < x <= hi when lo_excl (NaN fails). */
static inline bool within(vs_real_t x, vs_real_t lo, vs_real_t hi, bool lo_excl)
{
	return (lo_excl ? x > lo : x >= lo) && x <= hi;
}

/* A bound in row type's terms: a real row's as vs_real_t, an integer's as
 * the integer. */
static vs_real_t bound(int32_t b8, uint8_t type)
{
#ifdef VS_REAL_Q32
	return type == VS_CFG_DOUBLE ? (vs_real_t)b8 * ((vs_real_t)1 << 29) : (vs_real_t)(b8 / 8);
#else
	(void)type;
	return b8 / 8.0;
#endif
}

/* Element k of row f as its range compares it. */
static vs_real_t element(const vs_config_t *c, const vs_config_field_t *f, unsigned k)
{
	const void *p = (const char *)c + f->off;
	switch (f->type) {
	case VS_CFG_DOUBLE:
		return ((const vs_real_t *)p)[k];
	case VS_CFG_U32:
		return (vs_real_t)((const uint32_t *)p)[k];
	case VS_CFG_U16:
		return (vs_real_t)((const uint16_t *)p)[k];
	case VS_CFG_BOOL:
		return (vs_real_t)((const bool *)p)[k];
	default:
		return (vs_real_t)((const vs_kinematics_t *)p)[k];
	}
}

/* The first row with an element out of its range, or VS_CONFIG_NFIELDS. */
static unsigned first_out_of_range(const vs_config_t *c)
{
	for (unsigned i = 0; i < VS_CONFIG_NFIELDS; i++) {
		const vs_config_field_t *f = &vs_config_fields[i];
		vs_real_t lo = bound(f->lo8, f->type), hi = bound(f->hi8, f->type);
		for (unsigned k = 0; k < f->n; k++)
			if (!within(element(c, f, k), lo, hi, f->lo_excl))
				return i;
	}
	return VS_CONFIG_NFIELDS;
}

#define ROW(m) VS_CONFIG_ROW_##m
#define PI_D   3.14159265358979323846

bool vs_jerk_fits(const vs_config_t *c, vs_real_t j, vs_real_t limit)
{
	if (j == 0)
		return true;
		/* At least 64 raw units a tick^3: the profiles keep 4 below the limit
		 * for rounding (traj.h, section 4). */
#ifdef VS_REAL_Q32
	int64_t hz = c->tick_hz; /* <= 10^4: hz^3 * 64 < 2^63 */
	bool held = j >= 64 * hz * hz * hz;
#else
	double hz = (double)c->tick_hz;
	bool held = j * 4294967296.0 / (hz * hz * hz) >= 64.0;
#endif
	return held && j <= VS_REAL(VS_JERK_MAX) && (limit == 0 || j <= limit);
}

/* Names the field for a report: returns code. */
static int report(const char **name, const char *field, int code)
{
	*name = field;
	return code;
}

/* Row row's value, a real row's (a single element). */
static vs_real_t real_at(const vs_config_t *c, unsigned row)
{
	return *(const vs_real_t *)(const void *)((const char *)c + vs_config_fields[row].off);
}

/* The rules between fields, each in its place in the order of the rows: a
 * rule "at" row m (bad >= ROW(m)) is judged before m's own range, which it
 * covers; one "after" m (bad > ROW(m)) once m is in range. bad is the first
 * row out of range: a rule placed beyond it is not judged, that row is
 * reported first. Returns -1 (out of range) or -2 (inconsistent) with the
 * field, or 0. */
static int cross_rules(const vs_config_t *c, unsigned bad, const char **name)
{
	/* Row x against row lim (0: none, row 0 being the kinematics), in the
	 * order the rules are judged; a jerk's rule is "after" its row, a
	 * default's "at" it. */
	static const struct {
		uint8_t row, lim_row;
		bool jerk;
	} pairs[] = {
	    {ROW(vel_default_t_mm_s), ROW(vel_limit_t_mm_s), false},
	    {ROW(vel_default_r_deg_s), ROW(vel_limit_r_deg_s), false},
	    {ROW(acc_default_t_mm_s2), ROW(acc_limit_t_mm_s2), false},
	    {ROW(acc_default_r_deg_s2), ROW(acc_limit_r_deg_s2), false},
	    {ROW(jerk_limit_t_mm_s3), 0, true},
	    {ROW(jerk_limit_r_deg_s3), 0, true},
	    {ROW(jerk_default_t_mm_s3), ROW(jerk_limit_t_mm_s3), true},
	    {ROW(jerk_default_r_deg_s3), ROW(jerk_limit_r_deg_s3), true},
	};
#ifdef VS_KIN_ONLY
	if (c->kinematics != VS_KIN_ONLY) /* built for the other base (the first row) */
		return report(name, "kinematics", -1);
#endif
	if (bad > ROW(wheel_base_mm) && vs_config_omni(c) && !(c->wheel_base_mm >= VS_REAL(50.0)))
		return report(name, "wheel_base_mm", -1);
	/* The defaults within their limits, the jerks held by the tick rate:
	 * one table, one loop (0.1 KiB of a board's flash). */
	for (unsigned i = 0; i < sizeof pairs / sizeof pairs[0]; i++) {
		unsigned row = pairs[i].row;
		if (bad < row + pairs[i].jerk)
			continue;
		vs_real_t x = real_at(c, row),
			  lim = pairs[i].lim_row ? real_at(c, pairs[i].lim_row) : 0;
		if (!(pairs[i].jerk ? vs_jerk_fits(c, x, lim) : positive_upto(x, lim)))
			return report(name, vs_config_fields[row].name, -2);
	}
	/* Per-tick loop gain at most 1/4 keeps the discrete loop well damped. */
	if (bad > ROW(wheel_kp_per_s) && c->wheel_kp_per_s > vs_real_int(c->tick_hz) / 4)
		return report(name, "wheel_kp_per_s", -2);
	if (bad >= ROW(caution_vel_t_mm_s) &&
	    !in_range(c->caution_vel_t_mm_s, 0, c->vel_limit_t_mm_s))
		return report(name, "caution_vel_t_mm_s", -2);
	if (bad > ROW(battery_low_v) && !(c->battery_low_v > c->battery_critical_v))
		return report(name, "battery_low_v", -2);
	return 0;
}

/* The fastest wheel setpoint (counts/s, Q8, plus the same again for the
 * position loop's correction) must fit the HAL's int32. */
static bool setpoint_fits(const vs_config_t *c)
{
	bool omni = vs_config_omni(c);
#ifdef VS_REAL_Q32
	/* The same sum in Q32, against the speed the limit allows: every term
	 * is bounded by the ranges above (the largest, vel_r * half, 2^56). */
	q32_t half = (omni ? c->wheel_base_mm + c->track_width_mm : c->track_width_mm) / 2;
	q32_t counts_per_mm = fx_div(vs_real_int(c->encoder_counts_per_rev),
				     fx_mul(VS_REAL(PI_D), c->wheel_diameter_mm));
	q32_t wheel_mm_s = c->vel_limit_t_mm_s * (omni ? 2 : 1) +
			   fx_mul(fx_mul(c->vel_limit_r_deg_s, half), VS_REAL(PI_D / 180.0));
	return !(wheel_mm_s > fx_div(VS_REAL(2147483647.0 / 512.0), counts_per_mm));
#else
	double counts_per_mm = (double)c->encoder_counts_per_rev / (PI_D * c->wheel_diameter_mm);
	double half = omni ? (c->wheel_base_mm + c->track_width_mm) / 2.0 : c->track_width_mm / 2.0;
	double wheel_mm_s =
	    c->vel_limit_t_mm_s * (omni ? 2.0 : 1.0) + c->vel_limit_r_deg_s * half * PI_D / 180.0;
	return !(wheel_mm_s * counts_per_mm * 256.0 * 2.0 > 2147483647.0);
#endif
}

/* The io.xml entries: 0, or -3 with the field. */
static int check_io(const vs_config_t *c, const char **name)
{
	for (unsigned i = 0; i < c->num_io; i++) {
		const vs_io_def_t *d = &c->io[i];
		bool terminated = false;
		if (d->id == 0)
			return report(name, "io.id", -3);
		if (d->dir != VS_IO_IN && d->dir != VS_IO_OUT)
			return report(name, "io.dir", -3);
		if (d->width < 1 || d->width > 32)
			return report(name, "io.width", -3);
		for (unsigned k = 0; k < VS_IO_NAME_MAX; k++)
			terminated = terminated || d->name[k] == '\0';
		if (!terminated)
			return report(name, "io.name", -3);
		for (unsigned j = 0; j < i; j++)
			if (c->io[j].id == d->id)
				return report(name, "io.id", -3);
	}
	return 0;
}

/* Return codes: -1 a field out of its range, -2 two fields inconsistent,
 * -3 an io.xml entry invalid or duplicated. The table's ranges, with the
 * rules between fields in their places (cross_rules), then the version
 * string, the setpoint range and io.xml. */
int vs_config_check(const vs_config_t *c, const char **field)
{
	unsigned bad = first_out_of_range(c);
	const char *name = NULL;
	int rc = cross_rules(c, bad, &name);

	if (rc == 0 && bad < VS_CONFIG_NFIELDS)
		rc = report(&name, vs_config_fields[bad].name, -1);
	if (rc == 0 && c->firmware_version) {
		unsigned k = 0;
		while (k < 32 && c->firmware_version[k] != '\0')
			k++;
		if (k == 0 || k >= 32)
			rc = report(&name, "firmware_version", -1);
	}
	if (rc == 0 && !setpoint_fits(c))
		rc = report(&name, "encoder_counts_per_rev", -2);
	if (rc == 0 && c->num_io > VS_MAX_IO)
		rc = report(&name, "num_io", -1);
	if (rc == 0)
		rc = check_io(c, &name);
	if (rc != 0 && field)
		*field = name;
	return rc;
}
