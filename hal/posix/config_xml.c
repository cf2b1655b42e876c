/* Vehicle configuration from XML (format: config_xml.h).
 *
 * The firmware's configuration table (firmware/config_fields.def) maps
 * every vehicle attribute to its vs_config_t field, type and range, so that
 * parsing, range errors and the mapping of a vs_config_check() complaint
 * back to the file line all come from the one place. Files are read whole
 * (they are small) and parsed by expat in one call; the vehicle file's
 * other sections (<backends>) go to their handlers in the same pass. The
 * first error stops the parser (a section's only once nothing else can be
 * reported before it) and is the one reported.
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

/* The table's XML columns and ranges, row for row with vs_config_fields
 * (name, offset, type, elements). */
typedef struct {
	const char *elem;
	const char *attr; /* '#': an array's element index, one digit */
	double min, max;
	bool min_excl; /* value must be > min */
} xml_field_t;

static const xml_field_t fields[VS_CONFIG_NFIELDS] = {
#define XML_FIELD(m, n, t, d, lo, hi, ex, wh, el, at) {(el), (at), (lo), (hi), (ex)},
    VS_CONFIG_FIELDS(XML_FIELD)
#undef XML_FIELD
};
#define NFIELDS ((size_t)VS_CONFIG_NFIELDS)

/* An array's index is one digit in its attribute. */
#define ARRAY_FITS_DIGIT(m, n, ...) _Static_assert((n) <= 10, #m ": more than 10 elements");
VS_CONFIG_FIELDS(ARRAY_FITS_DIGIT)
#undef ARRAY_FITS_DIGIT

/* Sections of the vehicle file that belong to a platform's reader: skipped
 * when no handler for them is given. */
static const char *const platform_sections[] = {"backends"};
#define NPLATFORM (sizeof(platform_sections) / sizeof(platform_sections[0]))
#define NFOREIGN  (NPLATFORM + CONFIG_MAX_SECTIONS)

struct config_reader {
	struct ctx *file;
	const config_section_t *sec;
	bool failed; /* its first error is recorded: it hears no more */
};

typedef struct ctx {
	XML_Parser p;
	const char *path;
	char *err; /* the core's first error */
	size_t errlen;
	bool failed;
	bool judged;	  /* the core's errors count (else only a file that cannot be read) */
	bool file_failed; /* the file could not be read */
	bool stopped;	  /* XML_StopParser called */
	bool is_io;
	int depth;
	int skip_depth; /* inside a foreign section: elements this deep or deeper are skipped */
	vs_config_t *cfg;
	hal_io_map_t *map;
	/* Sections of other readers: theirs, the one being read (or NULL) and
	 * the first error any of them reported. */
	config_reader_t readers[CONFIG_MAX_SECTIONS];
	size_t nreaders;
	config_reader_t *in_section;
	char *sec_err;
	bool sec_failed;
	unsigned long foreign_line[NFOREIGN];
	unsigned long field_line[NFIELDS];
	unsigned field_elem[NFIELDS];	     /* the array element set last */
	unsigned long section_line[NFIELDS]; /* by the section's first row */
	unsigned long io_line[VS_MAX_IO];
} ctx_t;

static unsigned long cur_line(ctx_t *c)
{
	return (unsigned long)XML_GetCurrentLineNumber(c->p);
}

/* Nothing more can be reported: the parse ends here. */
static void stop(ctx_t *c)
{
	if (c->p && !c->stopped) {
		XML_StopParser(c->p, XML_FALSE);
		c->stopped = true;
	}
}

static int fail(ctx_t *c, unsigned long line, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* Records the core's first error and, when it counts, stops the parser.
 * Returns -1. */
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
	if (c->judged)
		stop(c);
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

/* attr against a row's attribute pattern: '#' matches one digit below n,
 * which goes to *k. */
static bool attr_matches(const char *pat, unsigned n, const char *attr, unsigned *k)
{
	*k = 0;
	for (; *pat; pat++, attr++) {
		if (*pat == '#' && *attr >= '0' && (unsigned)(*attr - '0') < n)
			*k = (unsigned)(*attr - '0');
		else if (*pat != *attr)
			return false;
	}
	return *attr == '\0';
}

/* Row i's value val for element k (attribute attr). */
static int set_field(ctx_t *c, size_t i, unsigned k, const char *attr, const char *val)
{
	const xml_field_t *x = &fields[i];
	const vs_config_field_t *f = &vs_config_fields[i];
	unsigned long line = cur_line(c);
	double d;

	switch (f->type) {
	case VS_CFG_KIN:
		if (!strcmp(val, "differential"))
			d = VS_KIN_DIFF;
		else if (!strcmp(val, "mecanum"))
			d = VS_KIN_OMNI;
		else
			return fail(c, line, "%s.%s: not differential|mecanum '%s'", x->elem, attr,
				    val);
		break;
	case VS_CFG_BOOL: {
		bool b;
		if (config_parse_bool(val, &b) < 0)
			return fail(c, line, "%s.%s: not a boolean '%s'", x->elem, attr, val);
		d = b;
		break;
	}
	default:
		if (parse_ranged(c, x->elem, attr, val, x->min, x->max, x->min_excl,
				 f->type != VS_CFG_DOUBLE, &d) < 0)
			return -1;
		break;
	}
	if (c->failed)
		return -1;
	vs_config_set(c->cfg, f, k, d);
	c->field_line[i] = line;
	c->field_elem[i] = k;
	return 0;
}

static int vehicle_attrs(ctx_t *c, const char *elem, const XML_Char **atts)
{
	for (size_t a = 0; atts[a] && !c->failed; a += 2) {
		size_t i;
		unsigned k = 0;
		for (i = 0; i < NFIELDS; i++)
			if (!strcmp(fields[i].elem, elem) &&
			    attr_matches(fields[i].attr, vs_config_fields[i].n, atts[a], &k))
				break;
		if (i == NFIELDS)
			return fail(c, cur_line(c), "%s.%s: unknown attribute", elem, atts[a]);
		if (set_field(c, i, k, atts[a], atts[a + 1]) < 0)
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

/* The first row of a section of the core (not the root's attributes), or -1. */
static int section_row(const char *name)
{
	if (!strcmp(name, "vehicle"))
		return -1; /* the root's own attributes */
	for (size_t i = 0; i < NFIELDS; i++)
		if (!strcmp(fields[i].elem, name))
			return (int)i;
	return -1;
}

/* A section of another reader's: the platforms' first, then those given.
 * Its index in foreign_line, or -1. */
static int foreign_section(const ctx_t *c, const char *name)
{
	for (size_t i = 0; i < NPLATFORM; i++)
		if (!strcmp(name, platform_sections[i]))
			return (int)i;
	for (size_t i = 0; i < c->nreaders; i++)
		if (!strcmp(name, c->readers[i].sec->name))
			return (int)(NPLATFORM + i);
	return -1;
}

static int start_element(ctx_t *c, const XML_Char *name, const XML_Char **atts, int depth,
			 unsigned long line)
{
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
	int s = depth == 1 && !c->is_io ? foreign_section(c, name) : -1;
	if (s >= 0) {
		/* Another reader's section (its handler, if any, has it). */
		if (c->foreign_line[s])
			return fail(c, line, "%s: duplicate element (first at line %lu)", name,
				    c->foreign_line[s]);
		c->foreign_line[s] = line;
		c->skip_depth = depth + 1;
		return 0;
	}
	s = depth == 1 && !c->is_io ? section_row(name) : -1;
	if (s >= 0) {
		if (c->section_line[s])
			return fail(c, line, "%s: duplicate element (first at line %lu)", name,
				    c->section_line[s]);
		c->section_line[s] = line;
		return vehicle_attrs(c, name, atts);
	}
	return fail(c, line, "%s: unknown element", name);
}

/* A section's handler failed: once every handler has and the core's errors
 * do not count, nothing more can be reported. */
static void section_failed(ctx_t *c)
{
	for (size_t i = 0; i < c->nreaders; i++)
		if (!c->readers[i].failed)
			return;
	if (!c->judged)
		stop(c);
}

int config_vfail(config_reader_t *r, unsigned long line, const char *fmt, va_list ap)
{
	ctx_t *c = r->file;
	if (r->failed)
		return -1;
	r->failed = true;
	if (!c->sec_failed) {
		c->sec_failed = true;
		int n = snprintf(c->sec_err, c->errlen, "%s:%lu: ", c->path, line);
		if (n >= 0 && (size_t)n < c->errlen)
			vsnprintf(c->sec_err + n, c->errlen - (size_t)n, fmt, ap);
	}
	section_failed(c);
	return -1;
}

int config_fail(config_reader_t *r, unsigned long line, const char *fmt, ...)
{
	va_list ap;
	va_start(ap, fmt);
	int rc = config_vfail(r, line, fmt, ap);
	va_end(ap);
	return rc;
}

int config_attr_uint(config_reader_t *r, unsigned long line, const char *elem, const char *attr,
		     const char *val, unsigned long min, unsigned long max, uint32_t *out)
{
	char *end;
	errno = 0;
	if (*val < '0' || *val > '9')
		return config_fail(r, line, "%s.%s: not a number '%s'", elem, attr, val);
	unsigned long n = strtoul(val, &end, 10);
	if (*end != '\0')
		return config_fail(r, line, "%s.%s: not a number '%s'", elem, attr, val);
	if (errno == ERANGE || n < min || n > max)
		return config_fail(r, line, "%s.%s: out of range %lu..%lu '%s'", elem, attr, min,
				   max, val);
	*out = (uint32_t)n;
	return 0;
}

int config_attr_number(config_reader_t *r, unsigned long line, const char *elem, const char *attr,
		       const char *val, double lo, bool lo_excl, double hi, const char *range,
		       double *out)
{
	double d;
	const char *why;
	if (config_parse_number(val, &d, &why) < 0)
		return config_fail(r, line, "%s.%s: %s '%s'", elem, attr, why, val);
	if ((lo_excl ? d <= lo : d < lo) || d > hi)
		return config_fail(r, line, "%s.%s: out of range %s '%s'", elem, attr, range, val);
	*out = d;
	return 0;
}

int config_attr_bool(config_reader_t *r, unsigned long line, const char *elem, const char *attr,
		     const char *val, bool *out)
{
	if (config_parse_bool(val, out) < 0)
		return config_fail(r, line, "%s.%s: not a boolean '%s'", elem, attr, val);
	return 0;
}

static void XMLCALL on_start(void *ud, const XML_Char *name, const XML_Char **atts)
{
	ctx_t *c = ud;
	unsigned long line = cur_line(c);
	int depth = c->depth++;

	/* Sections of other readers: every element, whatever the core makes
	 * of it. */
	if (depth == 1 && !c->is_io)
		for (size_t i = 0; i < c->nreaders && !c->in_section; i++)
			if (!strcmp(name, c->readers[i].sec->name))
				c->in_section = &c->readers[i];
	config_reader_t *r = c->in_section;
	if (r && !r->failed && r->sec->start(r->sec->ctx, r, name, atts, depth - 1, line) < 0)
		config_fail(r, line, "%s: rejected", name); /* unless it said why */
	if (!c->failed)
		(void)start_element(c, name, atts, depth, line);
}

static void XMLCALL on_end(void *ud, const XML_Char *name)
{
	ctx_t *c = ud;
	int depth = --c->depth;
	config_reader_t *r = c->in_section;

	if (r && !r->failed && r->sec->end)
		r->sec->end(r->sec->ctx, name, depth - 1);
	if (depth <= 1)
		c->in_section = NULL;
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
	c->file_failed = true; /* until the parse begins */
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
	c->file_failed = false;
	XML_SetUserData(c->p, c);
	XML_SetElementHandler(c->p, on_start, on_end);
	XML_SetCharacterDataHandler(c->p, on_text);
	XML_SetStartDoctypeDeclHandler(c->p, on_doctype);
	enum XML_Status st = XML_Parse(c->p, buf, (int)n, XML_TRUE);
	if (st == XML_STATUS_ERROR && !c->stopped) {
		/* Not well-formed: an error of the core and of every section
		 * still reading. */
		unsigned long line = cur_line(c);
		const char *what = XML_ErrorString(XML_GetErrorCode(c->p));
		fail(c, line, "xml: %s", what);
		for (size_t i = 0; i < c->nreaders; i++)
			config_fail(&c->readers[i], line, "xml: %s", what);
	}
	XML_ParserFree(c->p);
	c->p = NULL;
	free(buf);
	return c->failed ? -1 : 0;
}

/* Points a complaint of vs_config_check at the attribute that set the field,
 * if one did, else names the field. Returns -1. */
static int check_failed(ctx_t *vc, ctx_t *ic, const char *bad)
{
	if (!bad)
		bad = "?";
	for (size_t i = 0; i < NFIELDS; i++) {
		if (strcmp(vs_config_fields[i].name, bad) != 0)
			continue;
		/* the attribute, with an array's element index for its '#' */
		char attr[64];
		const char *hash = strchr(fields[i].attr, '#');
		if (hash)
			snprintf(attr, sizeof(attr), "%.*s%u%s", (int)(hash - fields[i].attr),
				 fields[i].attr, vc->field_elem[i], hash + 1);
		else
			snprintf(attr, sizeof(attr), "%s", fields[i].attr);
		vc->failed = false;
		return fail(vc, vc->field_line[i], "%s.%s: rejected by the configuration check",
			    fields[i].elem, attr);
	}
	ctx_t *fc = (ic->path && !strncmp(bad, "io", 2)) ? ic : vc;
	fc->failed = false;
	return fail(fc, 0, "%s: rejected by the configuration check", bad);
}

/* After the files: the core's error, a section's, a section's finish(). */
static int judge(ctx_t *vc, ctx_t *ic)
{
	if (vc->judged) {
		if (vc->failed)
			return -1;
		if (ic->path) {
			ic->cfg->num_io = 0;
			memset(ic->cfg->io, 0, sizeof(ic->cfg->io));
			if (parse_file(ic) < 0)
				return -1;
		}
		const char *bad = NULL;
		if (vs_config_check(vc->cfg, &bad) != 0)
			return check_failed(vc, ic, bad);
	} else if (vc->file_failed) {
		return -1;
	}
	vc->err[0] = '\0';
	for (size_t i = 0; i < vc->nreaders && !vc->sec_failed; i++) {
		config_reader_t *r = &vc->readers[i];
		if (r->sec->finish && r->sec->finish(r->sec->ctx, r) < 0)
			config_fail(r, 0, "%s: rejected", r->sec->name); /* unless it said why */
	}
	if (!vc->sec_failed)
		return 0;
	snprintf(vc->err, vc->errlen, "%s", vc->sec_err);
	return -1;
}

int config_load_sections(const char *vehicle_path, const char *io_path, vs_config_t *out,
			 hal_io_map_t *io_map, const config_section_t *sections, size_t n,
			 char *err, size_t errlen)
{
	static char dummy[1];
	vs_config_t scratch = {0};

	if (!err || errlen == 0) {
		err = dummy;
		errlen = sizeof(dummy);
	}
	err[0] = '\0';
	ctx_t vc = {.path = vehicle_path,
		    .err = err,
		    .errlen = errlen,
		    .judged = out != NULL,
		    .cfg = out ? out : &scratch};
	ctx_t ic = {.path = out ? io_path : NULL,
		    .err = err,
		    .errlen = errlen,
		    .judged = true,
		    .cfg = vc.cfg,
		    .map = out ? io_map : NULL,
		    .is_io = true};
	vs_config_defaults(vc.cfg);
	if (ic.map)
		memset(ic.map, 0, sizeof(*ic.map));
	if (n > CONFIG_MAX_SECTIONS) {
		vc.judged = true;
		return fail(&vc, 0, "more than %d sections", CONFIG_MAX_SECTIONS);
	}
	vc.nreaders = n;
	for (size_t i = 0; i < n; i++)
		vc.readers[i] = (config_reader_t){.file = &vc, .sec = &sections[i]};
	vc.sec_err = n ? calloc(1, errlen) : NULL;
	if (n && !vc.sec_err) {
		vc.judged = true;
		return fail(&vc, 0, "out of memory");
	}
	(void)parse_file(&vc);
	int rc = judge(&vc, &ic);
	free(vc.sec_err);
	return rc;
}

int config_load(const char *vehicle_path, const char *io_path, vs_config_t *out,
		hal_io_map_t *io_map, char *err, size_t errlen)
{
	return config_load_sections(vehicle_path, io_path, out, io_map, NULL, 0, err, errlen);
}
