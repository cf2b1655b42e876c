/* Vehicle configuration from XML (format: config_xml.h).
 *
 * One table maps every vehicle attribute to its vs_config_t field, type and
 * range, so that parsing, range errors and the mapping of a
 * vs_config_check() complaint back to the file line all come from one place.
 * Files are read whole (they are small) and parsed by expat in one call; the
 * first error stops the parser and is the one reported.
 */
#include "config_xml.h"

#include <ctype.h>
#include <errno.h>
#include <expat.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_FILE_BYTES ((size_t)1024 * 1024)

typedef enum { T_DOUBLE, T_U32, T_U16, T_BOOL, T_KIN } ftype_t;

/* Widest members first: no padding between them. */
typedef struct {
	const char *elem;
	const char *attr;
	const char *cfield; /* vs_config_t member name, as vs_config_check names it */
	size_t off;
	double min, max;
	ftype_t type;
	bool min_excl; /* value must be > min */
} field_t;

#define F(e, a, t, member, lo, hi, ex)                                                             \
	{                                                                                          \
		.elem = (e), .attr = (a), .cfield = #member, .off = offsetof(vs_config_t, member), \
		.min = (lo), .max = (hi), .type = (t), .min_excl = (ex)                            \
	}

static const field_t fields[] = {
    F("vehicle", "kinematics", T_KIN, kinematics, 0, 0, false),
    F("vehicle", "tick_hz", T_U32, tick_hz, 100, 10000, false),
    F("geometry", "wheel_diameter_mm", T_DOUBLE, wheel_diameter_mm, 10, 2000, false),
    F("geometry", "track_width_mm", T_DOUBLE, track_width_mm, 50, 5000, false),
    F("geometry", "wheel_base_mm", T_DOUBLE, wheel_base_mm, 0, 5000, false),
    F("geometry", "encoder_counts_per_rev", T_U32, encoder_counts_per_rev, 1, 16777216, false),
    F("limits", "vel_t_mm_s", T_DOUBLE, vel_limit_t_mm_s, 0, 10000, true),
    F("limits", "vel_r_deg_s", T_DOUBLE, vel_limit_r_deg_s, 0, 3600, true),
    F("limits", "acc_t_mm_s2", T_DOUBLE, acc_limit_t_mm_s2, 0, 100000, true),
    F("limits", "acc_r_deg_s2", T_DOUBLE, acc_limit_r_deg_s2, 0, 100000, true),
    F("defaults", "vel_t_mm_s", T_DOUBLE, vel_default_t_mm_s, 0, 10000, true),
    F("defaults", "vel_r_deg_s", T_DOUBLE, vel_default_r_deg_s, 0, 3600, true),
    F("defaults", "acc_t_mm_s2", T_DOUBLE, acc_default_t_mm_s2, 0, 100000, true),
    F("defaults", "acc_r_deg_s2", T_DOUBLE, acc_default_r_deg_s2, 0, 100000, true),
    F("defaults", "jog_timeout_ms", T_U16, jog_timeout_default_ms, 1, 32767, false),
    F("supervision", "wheel_kp_per_s", T_DOUBLE, wheel_kp_per_s, 0, 1000, true),
    F("drives", "axis0_lag_ms", T_DOUBLE, drive_lag_ms[0], 0, 1000, false),
    F("drives", "axis1_lag_ms", T_DOUBLE, drive_lag_ms[1], 0, 1000, false),
    F("drives", "axis2_lag_ms", T_DOUBLE, drive_lag_ms[2], 0, 1000, false),
    F("drives", "axis3_lag_ms", T_DOUBLE, drive_lag_ms[3], 0, 1000, false),
    F("supervision", "following_error_mm", T_DOUBLE, following_error_mm, 0, 10000, true),
    F("supervision", "encoder_stuck_ms", T_U32, encoder_stuck_ms, 10, 60000, false),
    F("supervision", "drive_timeout_ms", T_U32, drive_timeout_ms, 1, 60000, false),
    F("supervision", "loop_late_ms", T_U32, loop_late_ms, 1, 1000, false),
    F("supervision", "link_timeout_ms", T_U32, link_timeout_ms, 0, 60000, false),
    F("supervision", "position_window_mm", T_DOUBLE, position_window_mm, 0, 100, true),
    F("supervision", "position_window_ms", T_U32, position_window_ms, 0, 1000, false),
    F("supervision", "settle_timeout_ms", T_U32, settle_timeout_ms, 10, 60000, false),
    F("motion", "cruise_blend_mm", T_DOUBLE, cruise_blend_mm, 0, 10000, false),
    F("motion", "caution_vel_t_mm_s", T_DOUBLE, caution_vel_t_mm_s, 0, 10000, false),
    F("battery", "low_v", T_DOUBLE, battery_low_v, 0, 1000, false),
    F("battery", "critical_v", T_DOUBLE, battery_critical_v, 0, 1000, true),
    F("devices", "contact_sensor", T_BOOL, has_contact_sensor, 0, 0, false),
    F("devices", "obstacle_input", T_BOOL, has_obstacle_input, 0, 0, false),
    F("devices", "estop", T_BOOL, has_estop, 0, 0, false),
    F("devices", "joystick", T_BOOL, has_joystick, 0, 0, false),
    F("devices", "joystick_deadband", T_DOUBLE, joystick_deadband, 0, 0.5, false),
};
#define NFIELDS (sizeof(fields) / sizeof(fields[0]))

static const char *const sections[] = {"geometry",    "limits", "defaults", "drives",
				       "supervision", "motion", "battery",  "devices"};
#define NSECTIONS (sizeof(sections) / sizeof(sections[0]))

typedef struct {
	XML_Parser p;
	const char *path;
	char *err;
	size_t errlen;
	bool failed;
	bool is_io;
	int depth;
	int skip_depth; /* inside <backends>: elements at this depth or deeper are skipped */
	unsigned long backends_line;
	vs_config_t *cfg;
	hal_io_map_t *map;
	unsigned long field_line[NFIELDS];
	unsigned long section_line[NSECTIONS];
	unsigned long io_line[VS_MAX_IO];
} ctx_t;

static unsigned long cur_line(ctx_t *c)
{
	return (unsigned long)XML_GetCurrentLineNumber(c->p);
}

static int fail(ctx_t *c, unsigned long line, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* Records the first error and stops the parser. Returns -1. */
static int fail(ctx_t *c, unsigned long line, const char *fmt, ...)
{
	if (c->failed)
		return -1;
	c->failed = true;
	int n;
	if (line)
		n = snprintf(c->err, c->errlen, "%s:%lu: ", c->path, line);
	else
		n = snprintf(c->err, c->errlen, "%s: ", c->path);
	if (n >= 0 && (size_t)n < c->errlen) {
		va_list ap;
		va_start(ap, fmt);
		vsnprintf(c->err + n, c->errlen - (size_t)n, fmt, ap);
		va_end(ap);
	}
	if (c->p)
		XML_StopParser(c->p, XML_FALSE);
	return -1;
}

int config_parse_number(const char *s, double *out, const char **why)
{
	const char *q = s;
	if (*q == '+' || *q == '-')
		q++;
	if (!isdigit((unsigned char)*q) && !(*q == '.' && isdigit((unsigned char)q[1]))) {
		/* strtod would accept nan/inf: name them for what they are. */
		char *end;
		double d = strtod(s, &end);
		*why = (end != s && *end == '\0' && !isfinite(d)) ? "not finite" : "not a number";
		return -1;
	}
	for (const char *r = q; *r; r++) {
		if (!isdigit((unsigned char)*r) && *r != '.' && *r != 'e' && *r != 'E' &&
		    *r != '+' && *r != '-') {
			*why = "not a number";
			return -1;
		}
	}
	char *end;
	errno = 0;
	double d = strtod(s, &end);
	if (end == s || *end != '\0') {
		*why = "not a number";
		return -1;
	}
	if (!isfinite(d) || errno == ERANGE) {
		*why = isfinite(d) ? "out of range" : "not finite";
		return -1;
	}
	*out = d;
	return 0;
}

int config_parse_bool(const char *s, bool *out)
{
	if (!strcmp(s, "true") || !strcmp(s, "1")) {
		*out = true;
		return 0;
	}
	if (!strcmp(s, "false") || !strcmp(s, "0")) {
		*out = false;
		return 0;
	}
	return -1;
}

/* Parses a numeric attribute against [min, max] (min exclusive if asked);
 * integral if is_int. */
static int parse_ranged(ctx_t *c, const char *elem, const char *attr, const char *val, double min,
			double max, bool min_excl, bool is_int, double *out)
{
	unsigned long line = cur_line(c);
	const char *why;
	double d;
	if (config_parse_number(val, &d, &why) < 0) {
		fail(c, line, "%s.%s: %s '%s'", elem, attr, why, val);
		return -1;
	}
	if (is_int && d != floor(d)) {
		fail(c, line, "%s.%s: not an integer '%s'", elem, attr, val);
		return -1;
	}
	if ((min_excl ? d <= min : d < min) || d > max) {
		fail(c, line, "%s.%s: out of range '%s' (allowed %s%.15g..%.15g)", elem, attr, val,
		     min_excl ? ">" : "", min, max);
		return -1;
	}
	*out = d;
	return 0;
}

static int set_field(ctx_t *c, size_t i, const char *val)
{
	const field_t *f = &fields[i];
	char *base = (char *)c->cfg + f->off;
	unsigned long line = cur_line(c);
	double d;

	switch (f->type) {
	case T_KIN:
		if (!strcmp(val, "differential"))
			*(vs_kinematics_t *)(void *)base = VS_KIN_DIFF;
		else if (!strcmp(val, "mecanum"))
			*(vs_kinematics_t *)(void *)base = VS_KIN_OMNI;
		else
			return fail(c, line, "%s.%s: not differential|mecanum '%s'", f->elem,
				    f->attr, val);
		break;
	case T_BOOL: {
		bool b;
		if (config_parse_bool(val, &b) < 0)
			return fail(c, line, "%s.%s: not a boolean '%s'", f->elem, f->attr, val);
		*(bool *)(void *)base = b;
		break;
	}
	case T_DOUBLE:
		if (parse_ranged(c, f->elem, f->attr, val, f->min, f->max, f->min_excl, false, &d) <
		    0)
			return -1;
		*(double *)(void *)base = d;
		break;
	case T_U32:
		if (parse_ranged(c, f->elem, f->attr, val, f->min, f->max, f->min_excl, true, &d) <
		    0)
			return -1;
		*(uint32_t *)(void *)base = (uint32_t)d;
		break;
	case T_U16:
		if (parse_ranged(c, f->elem, f->attr, val, f->min, f->max, f->min_excl, true, &d) <
		    0)
			return -1;
		*(uint16_t *)(void *)base = (uint16_t)d;
		break;
	}
	if (c->failed)
		return -1;
	c->field_line[i] = line;
	return 0;
}

static int vehicle_attrs(ctx_t *c, const char *elem, const XML_Char **atts)
{
	for (size_t a = 0; atts[a] && !c->failed; a += 2) {
		size_t i;
		for (i = 0; i < NFIELDS; i++)
			if (!strcmp(fields[i].elem, elem) && !strcmp(fields[i].attr, atts[a]))
				break;
		if (i == NFIELDS)
			return fail(c, cur_line(c), "%s.%s: unknown attribute", elem, atts[a]);
		if (set_field(c, i, atts[a + 1]) < 0)
			return -1;
	}
	return c->failed ? -1 : 0;
}

/* src into dst[cap] with its NUL; false (dst untouched) when it does not fit. */
static bool copy_str(char *dst, size_t cap, const char *src)
{
	size_t n = strlen(src);
	if (n >= cap)
		return false;
	memcpy(dst, src, n + 1);
	return true;
}

static int io_entry(ctx_t *c, const char *elem, const XML_Char **atts)
{
	unsigned long line = cur_line(c);
	vs_config_t *cfg = c->cfg;
	if (cfg->num_io >= VS_MAX_IO)
		return fail(c, line, "%s: more than %d io entries", elem, VS_MAX_IO);

	vs_io_def_t def = {.dir = (uint8_t)(elem[0] == 'o' ? VS_IO_OUT : VS_IO_IN), .width = 1};
	hal_io_line_t m = {.dir = def.dir, .width = 1};
	bool have_id = false, have_line = false;
	double d;

	for (size_t a = 0; atts[a] && !c->failed; a += 2) {
		const char *k = atts[a], *v = atts[a + 1];
		if (!strcmp(k, "id")) {
			const char *why;
			if (config_parse_number(v, &d, &why) == 0 && d == 0)
				return fail(c, line, "%s.id: id 0 is reserved for the unit", elem);
			if (parse_ranged(c, elem, k, v, 1, 4294967295.0, false, true, &d) < 0)
				return -1;
			def.id = (uint32_t)d;
			have_id = true;
		} else if (!strcmp(k, "name")) {
			if (!copy_str(def.name, sizeof(def.name), v))
				return fail(c, line, "%s.name: longer than %d characters '%s'",
					    elem, VS_IO_NAME_MAX - 1, v);
		} else if (!strcmp(k, "width")) {
			if (parse_ranged(c, elem, k, v, 1, 32, false, true, &d) < 0)
				return -1;
			def.width = (uint8_t)d;
		} else if (!strcmp(k, "chip")) {
			if (*v == '\0' || !copy_str(m.chip, sizeof(m.chip), v))
				return fail(c, line,
					    "%s.chip: empty or longer than %d characters '%s'",
					    elem, HAL_IO_CHIP_MAX - 1, v);
		} else if (!strcmp(k, "line")) {
			if (parse_ranged(c, elem, k, v, 0, 65535, false, true, &d) < 0)
				return -1;
			m.line = (uint32_t)d;
			have_line = true;
		} else if (!strcmp(k, "active_low")) {
			if (config_parse_bool(v, &m.active_low) < 0)
				return fail(c, line, "%s.active_low: not a boolean '%s'", elem, v);
		} else {
			return fail(c, line, "%s.%s: unknown attribute", elem, k);
		}
	}
	if (c->failed)
		return -1;
	if (!have_id)
		return fail(c, line, "%s.id: missing", elem);
	if ((m.chip[0] != '\0') != have_line)
		return fail(c, line, "%s.%s: chip and line go together", elem,
			    have_line ? "chip" : "line");
	for (uint8_t i = 0; i < cfg->num_io; i++)
		if (cfg->io[i].id == def.id)
			return fail(c, line, "%s.id: duplicate id %u (first at line %lu)", elem,
				    (unsigned)def.id, c->io_line[i]);

	m.id = def.id;
	m.width = def.width;
	m.mapped = have_line;
	c->io_line[cfg->num_io] = line;
	cfg->io[cfg->num_io] = def;
	if (c->map)
		c->map->e[c->map->n++] = m;
	cfg->num_io++;
	return 0;
}

static int start_element(ctx_t *c, const XML_Char *name, const XML_Char **atts)
{
	unsigned long line = cur_line(c);
	int depth = c->depth++;
	const char *root = c->is_io ? "io" : "vehicle";

	if (c->skip_depth && depth >= c->skip_depth)
		return 0;
	if (depth == 0) {
		if (strcmp(name, root) != 0)
			return fail(c, line, "%s: unknown element (expected <%s>)", name, root);
		if (!c->is_io)
			return vehicle_attrs(c, name, atts);
		if (atts[0])
			return fail(c, line, "io.%s: unknown attribute", atts[0]);
		return 0;
	}
	if (depth == 1 && c->is_io && (!strcmp(name, "input") || !strcmp(name, "output")))
		return io_entry(c, name, atts);
	if (depth == 1 && !c->is_io && !strcmp(name, "backends")) {
		/* The Linux backends' own section, parsed by hal/linux/backend_cfg.c. */
		if (c->backends_line)
			return fail(c, line, "%s: duplicate element (first at line %lu)", name,
				    c->backends_line);
		c->backends_line = line;
		c->skip_depth = depth + 1;
		return 0;
	}
	if (depth == 1 && !c->is_io) {
		for (size_t s = 0; s < NSECTIONS; s++) {
			if (strcmp(name, sections[s]) != 0)
				continue;
			if (c->section_line[s])
				return fail(c, line, "%s: duplicate element (first at line %lu)",
					    name, c->section_line[s]);
			c->section_line[s] = line;
			return vehicle_attrs(c, name, atts);
		}
	}
	return fail(c, line, "%s: unknown element", name);
}

static void XMLCALL on_start(void *ud, const XML_Char *name, const XML_Char **atts)
{
	ctx_t *c = ud;
	if (!c->failed)
		(void)start_element(c, name, atts);
}

static void XMLCALL on_end(void *ud, const XML_Char *name)
{
	(void)name;
	ctx_t *c = ud;
	c->depth--;
	if (c->skip_depth && c->depth < c->skip_depth)
		c->skip_depth = 0;
}

static void XMLCALL on_text(void *ud, const XML_Char *s, int len)
{
	ctx_t *c = ud;
	for (int i = 0; i < len; i++)
		if (!isspace((unsigned char)s[i])) {
			fail(c, cur_line(c), "%s: unexpected text", c->is_io ? "io" : "vehicle");
			return;
		}
}

static void XMLCALL on_doctype(void *ud, const XML_Char *name, const XML_Char *sysid,
			       const XML_Char *pubid, int has_internal)
{
	(void)name, (void)sysid, (void)pubid, (void)has_internal;
	ctx_t *c = ud;
	fail(c, cur_line(c), "xml: DOCTYPE not allowed");
}

static int parse_file(ctx_t *c)
{
	FILE *f = fopen(c->path, "rb");
	if (!f) {
		fail(c, 0, "cannot open: %s", strerror(errno));
		return -1;
	}
	char *buf = malloc(MAX_FILE_BYTES + 1);
	if (!buf) {
		fclose(f);
		fail(c, 0, "out of memory");
		return -1;
	}
	size_t n = fread(buf, 1, MAX_FILE_BYTES + 1, f);
	int rerr = ferror(f);
	fclose(f);
	if (rerr || n > MAX_FILE_BYTES) {
		free(buf);
		fail(c, 0, rerr ? "read error" : "larger than %zu bytes", MAX_FILE_BYTES);
		return -1;
	}

	c->p = XML_ParserCreate(NULL);
	if (!c->p) {
		free(buf);
		fail(c, 0, "out of memory");
		return -1;
	}
	XML_SetUserData(c->p, c);
	XML_SetElementHandler(c->p, on_start, on_end);
	XML_SetCharacterDataHandler(c->p, on_text);
	XML_SetStartDoctypeDeclHandler(c->p, on_doctype);
	enum XML_Status st = XML_Parse(c->p, buf, (int)n, XML_TRUE);
	if (st == XML_STATUS_ERROR && !c->failed)
		fail(c, cur_line(c), "xml: %s", XML_ErrorString(XML_GetErrorCode(c->p)));
	XML_ParserFree(c->p);
	c->p = NULL;
	free(buf);
	return c->failed ? -1 : 0;
}

int config_load(const char *vehicle_path, const char *io_path, vs_config_t *out,
		hal_io_map_t *io_map, char *err, size_t errlen)
{
	static char dummy[1];
	if (!err || errlen == 0) {
		err = dummy;
		errlen = sizeof(dummy);
	}
	err[0] = '\0';
	vs_config_defaults(out);
	if (io_map)
		memset(io_map, 0, sizeof(*io_map));

	ctx_t vc = {.path = vehicle_path, .err = err, .errlen = errlen, .cfg = out};
	if (parse_file(&vc) < 0)
		return -1;

	ctx_t ic = {.path = io_path,
		    .err = err,
		    .errlen = errlen,
		    .cfg = out,
		    .map = io_map,
		    .is_io = true};
	if (io_path) {
		out->num_io = 0;
		memset(out->io, 0, sizeof(out->io));
		if (parse_file(&ic) < 0)
			return -1;
	}

	const char *bad = NULL;
	if (vs_config_check(out, &bad) == 0)
		return 0;
	if (!bad)
		bad = "?";
	/* Point at the attribute that set the offending field, if one did. */
	for (size_t i = 0; i < NFIELDS; i++) {
		if (strcmp(fields[i].cfield, bad) != 0)
			continue;
		vc.failed = false;
		fail(&vc, vc.field_line[i], "%s.%s: rejected by the configuration check",
		     fields[i].elem, fields[i].attr);
		return -1;
	}
	ctx_t *fc = (io_path && !strncmp(bad, "io", 2)) ? &ic : &vc;
	fc->failed = false;
	fail(fc, 0, "%s: rejected by the configuration check", bad);
	return -1;
}
