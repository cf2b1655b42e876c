/* The console's $config: the configuration's fields read, changed at run
 * time, compared with the saved and the base ones, saved, restored.
 *
 *   $config                  the field names
 *   $config NAME             the running value ("pending" and the value a
 *                            restart brings, when one waits)
 *   $config NAME V...        every element; NAME[K] V: element K alone
 *   $config diff             the fields unsaved, changed from the base, pending
 *   $config save|defaults|reload|store
 *
 * Values are parsed by type without floating point on a board (Q32), and
 * judged by vs_config_check and the table's when column (config_keep.h).
 */
#include <stdarg.h>
#include <string.h>

#include "../firmware/config_keep.h"
#include "../firmware/config_save.h"
#include "cmdtab.h"
#include "console.h"
#include "fmt.h"
#include "numparse.h"

void console_set_keep(console_t *c, struct cfgkeep *keep)
{
	c->keep = keep;
}

/* Here, not in console.c, which calls this file: no cycle between them. */
const char *console_real3(vs_real_t v, char *tmp)
{
	np_fmt_real3(v, tmp);
	return strcmp(tmp, "-0.000") == 0 ? "0.000" : tmp;
}

/* The reply writer of console.h, here too: console.c calls this file, not
 * the other way round. */
__attribute__((format(printf, 2, 0))) static void rb_vprintf(console_out_t *r, const char *fmt,
							     va_list ap)
{
	size_t room = r->cap ? r->cap - 1 - r->len : 0;
	size_t n;

	if (!r->cap)
		return;
	/* proto/fmt.c, not vsnprintf: the console's directives only (fmt.h). */
	n = fmt_v(r->buf + r->len, room + 1, fmt, ap);
	r->len += n < room ? n : room;
	r->buf[r->len] = '\0';
}

void console_put(console_out_t *r, const char *fmt, ...)
{
	va_list ap;

	va_start(ap, fmt);
	rb_vprintf(r, fmt, ap);
	va_end(ap);
}

bool console_fail(console_out_t *r, int code, const char *fmt, ...)
{
	va_list ap;

	r->len = 0;
	if (r->cap)
		r->buf[0] = '\0';
	console_put(r, "error %d ", code);
	va_start(ap, fmt);
	rb_vprintf(r, fmt, ap);
	va_end(ap);
	if (r->errors)
		(*r->errors)++;
	return true;
}

#ifndef VS_NO_CONFIG_EXTRA
/* "ok" and " NAME" for every row of the configuration table: the list of
 * $config fits one reply (a char per byte of " NAME", as the NUL of #m). */
struct config_list_bytes {
#define CONFIG_NAME_BYTES(m, ...) char m[sizeof(#m)];
	VS_CONFIG_FIELDS(CONFIG_NAME_BYTES)
#undef CONFIG_NAME_BYTES
};
_Static_assert(2 + sizeof(struct config_list_bytes) <= CONSOLE_REPLY_MAX,
	       "$config's list fits one reply");

/* $config save writes the saved form from the console's operation scratch
 * (console.c). */
_Static_assert(sizeof(cmd_scratch_t) >= VS_CFGSAVE_MAX, "the saved form fits the scratch");

/* No row has more elements than set_field holds. */
#define ROW_FITS(m, n, ...) _Static_assert((n) <= VS_MAX_AXES, #m " fits set_field");
VS_CONFIG_FIELDS(ROW_FITS)
#undef ROW_FITS

typedef console_out_t out_t;

/* Row f's elements in c (a configuration or its rows), each after a space,
 * as the operations' replies write numbers. */
static void put_values(out_t *o, const void *c, const vs_config_field_t *f)
{
	const uint8_t *p = (const uint8_t *)c + f->off;
	for (unsigned k = 0; k < f->n; k++) {
		char tmp[NP_FIXED3_MAX];
		switch (f->type) {
		case VS_CFG_DOUBLE:
			console_put(o, " %s",
				    console_real3(((const vs_real_t *)(const void *)p)[k], tmp));
			break;
		case VS_CFG_U32:
			console_put(o, " %lu",
				    (unsigned long)((const uint32_t *)(const void *)p)[k]);
			break;
		case VS_CFG_U16:
			console_put(o, " %u", (unsigned)((const uint16_t *)(const void *)p)[k]);
			break;
		case VS_CFG_BOOL:
			console_put(o, "%s",
				    ((const bool *)(const void *)p)[k] ? " true" : " false");
			break;
		default:
			console_put(o, " %d", (int)((const vs_kinematics_t *)(const void *)p)[k]);
			break;
		}
	}
}

static void put_field(out_t *o, console_t *c, const vs_config_field_t *f)
{
	console_put(o, "ok %s", f->name);
	put_values(o, &c->v->cfg, f);
	if (c->keep && cfgkeep_pending(c->keep, f)) {
		console_put(o, " pending");
		put_values(o, c->keep->want.b, f);
	}
}

/* Row f by NAME or NAME[K]: the row, *elem K (or -1 for the whole). */
static const vs_config_field_t *find_field(const char *arg, int *elem)
{
	char name[40];
	size_t n = strcspn(arg, "[");
	*elem = -1;
	if (n >= sizeof name)
		return NULL;
	memcpy(name, arg, n);
	name[n] = '\0';
	if (arg[n] == '[') {
		int64_t k;
		size_t e = strlen(arg);
		char idx[8];
		if (arg[e - 1] != ']' || e - n - 2 == 0 || e - n - 2 >= sizeof idx)
			return NULL;
		memcpy(idx, arg + n + 1, e - n - 2);
		idx[e - n - 2] = '\0';
		if (np_parse_int(idx, 0, 255, &k) != NP_OK)
			return NULL;
		*elem = (int)k;
	}
	for (unsigned i = 0; i < VS_CONFIG_NFIELDS; i++) {
		const vs_config_field_t *f = &vs_config_fields[i];
		if (np_streq_nocase(name, f->name))
			return *elem < (int)f->n ? f : NULL;
	}
	return NULL;
}

/* One value of row f's type from tok into v (the member's bytes); false
 * with the error in o. */
static bool parse_value(out_t *o, const vs_config_field_t *f, const char *tok, void *v)
{
	int64_t iv = 0, hi = f->type == VS_CFG_U16 ? UINT16_MAX : (int64_t)UINT32_MAX;
	const char *why = CONSOLE_BAD_NUMBER; /* the text the console's operations share */
	int code = CONSOLE_E_NUMBER;
	np_result_t r;
	switch (f->type) {
	case VS_CFG_DOUBLE:
		if (np_parse_real(tok, (vs_real_t *)v) == NP_OK)
			return true;
		break;
	case VS_CFG_BOOL:
		if (np_parse_bool(tok, (bool *)v))
			return true;
		why = CONSOLE_BAD_BOOL;
		code = CONSOLE_E_BOOL;
		break;
	case VS_CFG_KIN:
		if (np_streq_nocase(tok, "differential") || np_streq_nocase(tok, "mecanum")) {
			*(vs_kinematics_t *)v =
			    np_streq_nocase(tok, "mecanum") ? VS_KIN_OMNI : VS_KIN_DIFF;
			return true;
		}
		if (np_parse_int(tok, 0, 1, &iv) == NP_OK) {
			*(vs_kinematics_t *)v = (vs_kinematics_t)iv;
			return true;
		}
		why = ": %s is not 0 (differential) or 1 (mecanum)";
		code = CONSOLE_E_RANGE;
		break;
	default:
		r = np_parse_int(tok, 0, hi, &iv);
		if (r == NP_OK) {
			if (f->type == VS_CFG_U16)
				*(uint16_t *)v = (uint16_t)iv;
			else
				*(uint32_t *)v = (uint32_t)iv;
			return true;
		}
		if (r == NP_RANGE) {
			why = CONSOLE_NOT_INTEGER;
			code = CONSOLE_E_RANGE;
		}
		break;
	}
	console_fail(o, code, "$config %s", f->name);
	console_put(o, why, tok, (long long)0, (long long)hi);
	return false;
}

/* A refused change: why, for what (a field's name or the subcommand). */
static void refused(out_t *o, const char *what, cfgkeep_result_t r, const char *field)
{
	if (!field)
		field = "?";
	switch (r) {
	case CFGKEEP_REJECTED:
		console_fail(o, CONSOLE_E_EXTRA,
			     "$config %s: %s: rejected by the configuration check", what, field);
		break;
	case CFGKEEP_NOT_IDLE:
		console_fail(o, CONSOLE_E_EXTRA,
			     "$config %s: %s changes only with the servo off and no motion queued",
			     what, field);
		break;
	case CFGKEEP_NO_STORE:
		console_fail(o, CONSOLE_E_EXTRA, "$config %s: this unit has no store", what);
		break;
	default:
		console_fail(o, CONSOLE_E_EXTRA, "$config %s: store failed: %s", what, field);
		break;
	}
}

/* $config NAME V... or NAME[K] V: each element in turn, judged one at a
 * time (the first refused one stops, the earlier ones stay). */
static void set_field(out_t *o, console_t *c, const vs_config_field_t *f, int elem, char **vals,
		      unsigned nv)
{
	unsigned want = elem >= 0 ? 1u : f->n;
	/* one element each, in its type's bytes at the start (none is over 8) */
	uint64_t v[VS_MAX_AXES];
	const char *bad = NULL;
	if (nv != want) {
		console_fail(o, CONSOLE_E_ARITY, "$config %s takes %u value%s, got %u", f->name,
			     want, want == 1 ? "" : "s", nv);
		return;
	}
	for (unsigned i = 0; i < nv; i++)
		if (!parse_value(o, f, vals[i], &v[i]))
			return;
	/* All elements at once: the row's bytes of the wanted configuration. */
	uint8_t sz = vs_config_type_size(f->type);
	uint8_t row[VS_MAX_AXES * 8];
	memcpy(row, c->keep->want.b + f->off, (size_t)f->n * sz);
	for (unsigned i = 0; i < nv; i++)
		memcpy(row + (size_t)(elem >= 0 ? (unsigned)elem : i) * sz, &v[i], sz);
	cfgkeep_result_t r = cfgkeep_set(c->keep, f, row, &bad);
	if (r != CFGKEEP_OK && r != CFGKEEP_PENDING) {
		refused(o, f->name, r, bad);
		return;
	}
	put_field(o, c, f);
}

static void put_names(out_t *o, cfgkeep_t *k, const char *label,
		      bool (*differs)(const cfgkeep_t *, const vs_config_field_t *))
{
	unsigned n = 0;
	for (unsigned i = 0; i < VS_CONFIG_NFIELDS; i++)
		n += differs(k, &vs_config_fields[i]);
	console_put(o, " %s %u", label, n);
	for (unsigned i = 0; i < VS_CONFIG_NFIELDS; i++)
		if (differs(k, &vs_config_fields[i]))
			console_put(o, " %s", vs_config_fields[i].name);
}

static unsigned count_pending(cfgkeep_t *k)
{
	unsigned n = 0;
	for (unsigned i = 0; i < VS_CONFIG_NFIELDS; i++)
		n += cfgkeep_pending(k, &vs_config_fields[i]);
	return n;
}

static void put_store(out_t *o, const cfgkeep_boot_t *b)
{
	static const char *const names[] = {
	    [CFGKEEP_BOOT_NO_STORE] = "none",	[CFGKEEP_BOOT_EMPTY] = "empty",
	    [CFGKEEP_BOOT_LOADED] = "loaded",	[CFGKEEP_BOOT_CORRUPT] = "corrupt",
	    [CFGKEEP_BOOT_IO] = "unreadable",	[CFGKEEP_BOOT_MALFORMED] = "malformed",
	    [CFGKEEP_BOOT_FOREIGN] = "foreign", [CFGKEEP_BOOT_REJECTED] = "rejected",
	};
	console_put(o, "store %s", names[b->result]);
	if (b->result >= CFGKEEP_BOOT_LOADED && b->result != CFGKEEP_BOOT_CORRUPT &&
	    b->result != CFGKEEP_BOOT_IO)
		console_put(o, " seq %lu schema 0x%08lX applied %u dropped %u",
			    (unsigned long)b->seq, (unsigned long)b->schema, b->applied,
			    b->dropped);
	if (b->result == CFGKEEP_BOOT_REJECTED)
		console_put(o, " field %s", b->bad_field ? b->bad_field : "?");
	console_put(o, " table 0x%08lX%s", (unsigned long)vs_config_schema(),
		    b->other_torn ? " torn" : "");
}

/* The subcommands that need the keeper; false: argv[1] is none of them. */
static bool keeper_command(out_t *o, console_t *c, char **argv, unsigned ntok, void *scratch,
			   size_t scratch_cap)
{
	static const char *const cmds[] = {"diff", "save", "defaults", "reload", "store"};
	cfgkeep_t *k = c->keep;
	unsigned i = 0;
	const char *bad = NULL;
	cfgkeep_result_t r;
	while (i < 5 && !np_streq_nocase(argv[1], cmds[i]))
		i++;
	if (i == 5)
		return false;
	if (ntok != 2) {
		console_fail(o, CONSOLE_E_ARITY, "$config %s takes 0 arguments, got %u", cmds[i],
			     ntok - 2);
		return true;
	}
	if (!k) {
		console_fail(o, CONSOLE_E_EXTRA, "$config %s: this unit keeps no configuration",
			     cmds[i]);
		return true;
	}
	cfgkeep_sync(k);
	switch (i) {
	case 0:
		console_put(o, "ok");
		put_names(o, k, "unsaved", cfgkeep_unsaved);
		put_names(o, k, "changed", cfgkeep_changed);
		put_names(o, k, "pending", cfgkeep_pending);
		return true;
	case 1:
		r = cfgkeep_save(k, scratch, scratch_cap, &bad);
		if (r != CFGKEEP_OK) {
			refused(o, cmds[i], r, bad);
		} else {
			console_put(o, "ok");
			put_names(o, k, "saved", cfgkeep_changed);
		}
		return true;
	case 2:
	case 3:
		r = cfgkeep_restore(k, i == 3, &bad);
		if (r != CFGKEEP_OK && r != CFGKEEP_PENDING)
			refused(o, cmds[i], r, bad);
		else
			console_put(o, "ok %s pending %u", cmds[i], count_pending(k));
		return true;
	default:
		console_put(o, "ok ");
		put_store(o, &k->boot);
		return true;
	}
}

void console_config_store(const struct cfgkeep *k, char *buf, size_t cap)
{
	out_t o = {buf, cap, 0, NULL};
	if (cap)
		buf[0] = '\0';
	put_store(&o, &k->boot);
}

void console_config_diag(const console_t *c, char *buf, size_t cap)
{
	out_t o = {buf, cap, 0, NULL};
	const cfgkeep_boot_t *b = c->keep ? &c->keep->boot : NULL;
	if (cap)
		buf[0] = '\0';
	if (!b || b->result < CFGKEEP_BOOT_LOADED)
		return;
	if (b->result == CFGKEEP_BOOT_LOADED && b->schema == vs_config_schema())
		return;
	console_put(&o, " config ");
	put_store(&o, b);
}

void console_config(console_t *c, char **argv, unsigned ntok, out_t *o, void *scratch,
		    size_t scratch_cap)
{
	const vs_config_field_t *f;
	int elem;
	if (ntok == 1) {
		console_put(o, "ok");
		for (unsigned i = 0; i < VS_CONFIG_NFIELDS; i++)
			console_put(o, " %s", vs_config_fields[i].name);
		return;
	}
	if (keeper_command(o, c, argv, ntok, scratch, scratch_cap))
		return;
	f = find_field(argv[1], &elem);
	if (!f) {
		console_fail(o, CONSOLE_E_EXTRA, "$config: no field %s", argv[1]);
		return;
	}
	if (ntok == 2 && elem < 0) {
		put_field(o, c, f);
		return;
	}
	if (!c->keep) {
		console_fail(o, CONSOLE_E_EXTRA, "$config %s: this unit keeps no configuration",
			     f->name);
		return;
	}
	set_field(o, c, f, elem, argv + 2, ntok - 2);
}
#endif
