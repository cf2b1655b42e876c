/* The configuration changed at run time and saved (config_keep.h). */
#include "config_keep.h"

#include "config_save.h"
#include "vehicle_priv.h"

_Static_assert(CFGKEEP_PAYLOAD_MAX >= 4 + VS_CONFIG_NFIELDS * (1 + 24 + 3) +
					  (sizeof(vs_config_t) - sizeof(((vs_config_t *)0)->io)),
	       "every field fits the saved form's buffer");

/* Every row lies in the keeper's rows (CFGKEEP_ROWS_BYTES). */
#define ROW_IN_ROWS(m, ...)                                                                        \
	_Static_assert(offsetof(vs_config_t, m) + sizeof(((vs_config_t *)0)->m) <=                 \
			   CFGKEEP_ROWS_BYTES,                                                     \
		       #m " lies in the keeper's rows");
VS_CONFIG_FIELDS(ROW_IN_ROWS)
#undef ROW_IN_ROWS

/* The RESTART rows' bytes together (what commit sets aside): a char
 * array a row, one byte more than the row's share (a C array has one). */
struct restart_bytes {
#define RESTART_ROW_BYTES(m, n, type, dflt, lo, hi, excl, when, ...)                               \
	char m[1u +                                                                                \
	       (VS_CFG_WHEN_##when == VS_CFG_WHEN_RESTART ? sizeof(((vs_config_t *)0)->m) : 0u)];
	VS_CONFIG_FIELDS(RESTART_ROW_BYTES)
#undef RESTART_ROW_BYTES
};
enum { RESTART_BYTES = sizeof(struct restart_bytes) - VS_CONFIG_NFIELDS };

static uint32_t row_bytes(const vs_config_field_t *f)
{
	return (uint32_t)f->n * vs_config_type_size(f->type);
}

/* a and b: a configuration or its rows (each row at its offset). */
static bool row_same(const void *a, const void *b, const vs_config_field_t *f)
{
	const uint8_t *x = (const uint8_t *)a + f->off, *y = (const uint8_t *)b + f->off;
	for (uint32_t i = 0; i < row_bytes(f); i++)
		if (x[i] != y[i])
			return false;
	return true;
}

static void row_copy(void *to, const void *from, const vs_config_field_t *f)
{
	uint8_t *d = (uint8_t *)to + f->off;
	const uint8_t *s = (const uint8_t *)from + f->off;
	for (uint32_t i = 0; i < row_bytes(f); i++)
		d[i] = s[i];
}

/* Every row of from into to (the rest of a configuration, io.xml and the
 * version, stays). */
static void rows_copy(void *to, const void *from)
{
	for (unsigned i = 0; i < VS_CONFIG_NFIELDS; i++)
		row_copy(to, from, &vs_config_fields[i]);
}

static cfgkeep_boot_result_t load_record(cfgkeep_t *k, vs_config_t *start)
{
	uint8_t buf[CFGKEEP_PAYLOAD_MAX]; /* at start: the stack is free */
	cfgstore_info_t info = {0};
	cfgstore_status_t st = cfgstore_load(k->store, buf, sizeof buf, &info);
	k->boot.other_torn = info.other_torn;
	if (st == CFGSTORE_EMPTY)
		return CFGKEEP_BOOT_EMPTY;
	if (st == CFGSTORE_IO || st == CFGSTORE_NO_STORE)
		return CFGKEEP_BOOT_IO;
	if (st != CFGSTORE_OK)
		return CFGKEEP_BOOT_CORRUPT;
	k->boot.seq = info.seq;
	k->boot.schema = info.schema;
	vs_config_decode_t d;
	vs_config_decode_status_t ds = vs_config_decode(start, buf, info.len, &d);
	k->boot.applied = d.applied;
	k->boot.dropped = d.dropped;
	if (ds != VS_CFGSAVE_OK)
		return ds == VS_CFGSAVE_FOREIGN ? CFGKEEP_BOOT_FOREIGN : CFGKEEP_BOOT_MALFORMED;
	if (vs_config_check(start, &k->boot.bad_field) != 0)
		return CFGKEEP_BOOT_REJECTED;
	return CFGKEEP_BOOT_LOADED;
}

void cfgkeep_load(cfgkeep_t *k, const vs_config_t *base, const hal_store_t *store,
		  vs_config_t *start)
{
	k->v = NULL;
	k->store = store;
	k->boot = (cfgkeep_boot_t){0};
	(void)vs_config_schema(); /* worked out now, not in a request */
	rows_copy(&k->base, base);
	*start = *base;
	if (store) {
		k->boot.result = (uint8_t)load_record(k, start);
		/* never a part of an unreadable record (from the rows: start
		 * and base may be one) */
		if (k->boot.result != CFGKEEP_BOOT_LOADED)
			rows_copy(start, &k->base);
	}
	rows_copy(&k->saved, start);
	rows_copy(&k->want, start);
}

void cfgkeep_attach(cfgkeep_t *k, vehicle_t *v)
{
	static const char *const why[] = {
	    [CFGKEEP_BOOT_CORRUPT] = "corrupt",	    [CFGKEEP_BOOT_IO] = "not readable",
	    [CFGKEEP_BOOT_MALFORMED] = "malformed", [CFGKEEP_BOOT_FOREIGN] = "foreign",
	    [CFGKEEP_BOOT_REJECTED] = "rejected",
	};
	k->v = v;
	if (k->boot.result < CFGKEEP_BOOT_CORRUPT)
		return;
	char s[VS_ALARM_SOURCE_MAX];
	size_t pos = vehicle_put_str(s, sizeof s, 0, "saved configuration ");
	pos = vehicle_put_str(s, sizeof s, pos, why[k->boot.result]);
	if (k->boot.result == CFGKEEP_BOOT_REJECTED && k->boot.bad_field) {
		pos = vehicle_put_str(s, sizeof s, pos, " (");
		pos = vehicle_put_str(s, sizeof s, pos, k->boot.bad_field);
		pos = vehicle_put_str(s, sizeof s, pos, ")");
	}
	vehicle_put_str(s, sizeof s, pos, ": base in use");
	alarm_raise(&v->alarms, ALM_W_CONFIG_STORE, s);
}

/* The RESTART rows' bytes, one after another, between a configuration
 * (or its rows) and buf (to_buf: out of c). */
static void restart_rows(void *c, uint8_t *buf, bool to_buf)
{
	uint32_t at = 0;
	for (unsigned i = 0; i < VS_CONFIG_NFIELDS; i++) {
		const vs_config_field_t *f = &vs_config_fields[i];
		uint8_t *m = (uint8_t *)c + f->off;
		if (f->when != VS_CFG_WHEN_RESTART)
			continue;
		for (uint32_t j = 0; j < row_bytes(f); j++, at++) {
			if (to_buf)
				buf[at] = m[j];
			else
				m[j] = buf[at];
		}
	}
}

/* cand becomes the wanted configuration, if vs_config_check takes it and,
 * with the running values of its RESTART rows, the running one. */
static cfgkeep_result_t commit(cfgkeep_t *k, vs_config_t *cand, const char **field)
{
	vehicle_t *v = k->v;
	bool off = false, live = false;
	uint8_t wanted[RESTART_BYTES], running[RESTART_BYTES];
	if (vs_config_check(cand, field) != 0)
		return CFGKEEP_REJECTED;
	for (unsigned i = 0; i < VS_CONFIG_NFIELDS; i++) {
		const vs_config_field_t *f = &vs_config_fields[i];
		if (row_same(cand, &v->cfg, f))
			continue;
		if (f->when == VS_CFG_WHEN_OFF && !vehicle_config_idle(v)) {
			*field = f->name;
			return CFGKEEP_NOT_IDLE;
		}
		off = off || f->when == VS_CFG_WHEN_OFF;
		live = live || f->when == VS_CFG_WHEN_ANY;
	}
	/* The running configuration: the candidate with the running values of
	 * its RESTART rows (the wanted ones set aside meanwhile). */
	restart_rows(cand, wanted, true);
	restart_rows(&v->cfg, running, true);
	restart_rows(cand, running, false);
	if (vs_config_check(cand, field) != 0)
		return CFGKEEP_REJECTED;
	if (off)
		vehicle_reconfigure(v, cand);
	else if (live)
		vehicle_config_live(v, cand);
	rows_copy(&k->want, cand);
	restart_rows(&k->want, wanted, false);
	for (unsigned i = 0; i < VS_CONFIG_NFIELDS; i++)
		if (!row_same(&k->want, &v->cfg, &vs_config_fields[i]))
			return CFGKEEP_PENDING;
	return CFGKEEP_OK;
}

void cfgkeep_sync(cfgkeep_t *k)
{
	for (unsigned i = 0; i < VS_CONFIG_NFIELDS; i++)
		if (vs_config_fields[i].when == VS_CFG_WHEN_ANY)
			row_copy(&k->want, &k->v->cfg, &vs_config_fields[i]);
}

/* The candidate: the running configuration (its io.xml and version) with
 * the wanted rows. */
static void candidate(cfgkeep_t *k, vs_config_t *cand)
{
	cfgkeep_sync(k);
	*cand = k->v->cfg;
	rows_copy(cand, &k->want);
}

cfgkeep_result_t cfgkeep_set(cfgkeep_t *k, const vs_config_field_t *f, const void *row,
			     const char **field)
{
	vs_config_t cand; /* on the stack only while judged */
	uint8_t *d = (uint8_t *)&cand + f->off;
	candidate(k, &cand);
	for (uint32_t j = 0; j < row_bytes(f); j++)
		d[j] = ((const uint8_t *)row)[j];
	return commit(k, &cand, field);
}

cfgkeep_result_t cfgkeep_restore(cfgkeep_t *k, bool saved, const char **field)
{
	vs_config_t cand;
	candidate(k, &cand);
	rows_copy(&cand, saved ? &k->saved : &k->base);
	return commit(k, &cand, field);
}

cfgkeep_result_t cfgkeep_save(cfgkeep_t *k, uint8_t *buf, size_t cap, const char **field)
{
	static const char *const why[] = {[CFGSTORE_TOO_BIG] = "too big",
					  [CFGSTORE_IO] = "store error",
					  [CFGSTORE_VERIFY] = "verify failed",
					  [CFGSTORE_NO_STORE] = "store unusable"};
	if (!k->store)
		return CFGKEEP_NO_STORE;
	cfgkeep_sync(k);
	size_t n = vs_config_encode(&k->want, &k->base, buf, cap);
	cfgstore_status_t st =
	    n ? cfgstore_save(k->store, buf, (uint32_t)n, vs_config_schema()) : CFGSTORE_TOO_BIG;
	if (st != CFGSTORE_OK) {
		*field = st < sizeof why / sizeof why[0] && why[st] ? why[st] : "store error";
		return CFGKEEP_STORE_ERROR;
	}
	k->saved = k->want;
	return CFGKEEP_OK;
}

bool cfgkeep_pending(const cfgkeep_t *k, const vs_config_field_t *f)
{
	/* an ANY row is in force at once ($watchdog, $jerk set it unseen) */
	if (f->when == VS_CFG_WHEN_ANY)
		return false;
	return !row_same(&k->want, &k->v->cfg, f);
}

bool cfgkeep_unsaved(const cfgkeep_t *k, const vs_config_field_t *f)
{
	return !row_same(&k->want, &k->saved, f);
}

bool cfgkeep_changed(const cfgkeep_t *k, const vs_config_field_t *f)
{
	return !row_same(&k->want, &k->base, f);
}
