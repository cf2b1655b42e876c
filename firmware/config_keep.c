/* The configuration changed at run time and saved (config_keep.h). */
#include "config_keep.h"

#include "config_save.h"
#include "vehicle_priv.h"

_Static_assert(CFGKEEP_PAYLOAD_MAX >= 4 + VS_CONFIG_NFIELDS * (1 + 24 + 3) +
					  (sizeof(vs_config_t) - sizeof(((vs_config_t *)0)->io)),
	       "every field fits the saved form's buffer");

static uint32_t row_bytes(const vs_config_field_t *f)
{
	return (uint32_t)f->n * vs_config_type_size(f->type);
}

static bool row_same(const vs_config_t *a, const vs_config_t *b, const vs_config_field_t *f)
{
	const uint8_t *x = (const uint8_t *)a + f->off, *y = (const uint8_t *)b + f->off;
	for (uint32_t i = 0; i < row_bytes(f); i++)
		if (x[i] != y[i])
			return false;
	return true;
}

static void row_copy(vs_config_t *to, const vs_config_t *from, const vs_config_field_t *f)
{
	uint8_t *d = (uint8_t *)to + f->off;
	const uint8_t *s = (const uint8_t *)from + f->off;
	for (uint32_t i = 0; i < row_bytes(f); i++)
		d[i] = s[i];
}

/* Every row of from into to (the rest of to, io.xml and the version,
 * stays). */
static void rows_copy(vs_config_t *to, const vs_config_t *from)
{
	for (unsigned i = 0; i < VS_CONFIG_NFIELDS; i++)
		row_copy(to, from, &vs_config_fields[i]);
}

static cfgkeep_boot_result_t load_record(cfgkeep_t *k, vs_config_t *start)
{
	cfgstore_info_t info = {0};
	cfgstore_status_t st = cfgstore_load(k->store, k->buf, sizeof k->buf, &info);
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
	vs_config_decode_status_t ds = vs_config_decode(start, k->buf, info.len, &d);
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
	k->base = *base;
	*start = *base;
	if (store) {
		k->boot.result = (uint8_t)load_record(k, start);
		if (k->boot.result != CFGKEEP_BOOT_LOADED)
			*start = *base; /* never a part of an unreadable record */
	}
	k->saved = *start;
	k->want = *start;
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
 * and buf (to_buf: out of c). */
static void restart_rows(vs_config_t *c, uint8_t *buf, bool to_buf)
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

/* k->cand becomes the wanted configuration, if vs_config_check takes it
 * and, with the running values of its RESTART rows, the running one. */
static cfgkeep_result_t commit(cfgkeep_t *k, const char **field)
{
	vehicle_t *v = k->v;
	bool off = false, live = false;
	if (vs_config_check(&k->cand, field) != 0)
		return CFGKEEP_REJECTED;
	for (unsigned i = 0; i < VS_CONFIG_NFIELDS; i++) {
		const vs_config_field_t *f = &vs_config_fields[i];
		if (row_same(&k->cand, &v->cfg, f))
			continue;
		if (f->when == VS_CFG_WHEN_OFF && !vehicle_config_idle(v)) {
			*field = f->name;
			return CFGKEEP_NOT_IDLE;
		}
		off = off || f->when == VS_CFG_WHEN_OFF;
		live = live || f->when == VS_CFG_WHEN_ANY;
	}
	/* The running configuration: the candidate with the running values of
	 * its RESTART rows (k->buf holds the wanted ones meanwhile). */
	restart_rows(&k->cand, k->buf, true);
	restart_rows(&v->cfg, k->buf + sizeof k->buf / 2, true);
	restart_rows(&k->cand, k->buf + sizeof k->buf / 2, false);
	if (vs_config_check(&k->cand, field) != 0)
		return CFGKEEP_REJECTED;
	if (off)
		vehicle_reconfigure(v, &k->cand);
	else if (live)
		vehicle_config_live(v, &k->cand);
	k->want = k->cand;
	restart_rows(&k->want, k->buf, false);
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

cfgkeep_result_t cfgkeep_set(cfgkeep_t *k, const vs_config_field_t *f, const void *row,
			     const char **field)
{
	uint8_t *d = (uint8_t *)&k->cand + f->off;
	cfgkeep_sync(k);
	k->cand = k->want;
	for (uint32_t j = 0; j < row_bytes(f); j++)
		d[j] = ((const uint8_t *)row)[j];
	return commit(k, field);
}

cfgkeep_result_t cfgkeep_restore(cfgkeep_t *k, bool saved, const char **field)
{
	cfgkeep_sync(k);
	k->cand = k->want;
	rows_copy(&k->cand, saved ? &k->saved : &k->base);
	return commit(k, field);
}

cfgkeep_result_t cfgkeep_save(cfgkeep_t *k, const char **field)
{
	static const char *const why[] = {[CFGSTORE_TOO_BIG] = "too big",
					  [CFGSTORE_IO] = "store error",
					  [CFGSTORE_VERIFY] = "verify failed",
					  [CFGSTORE_NO_STORE] = "store unusable"};
	if (!k->store)
		return CFGKEEP_NO_STORE;
	cfgkeep_sync(k);
	size_t n = vs_config_encode(&k->want, &k->base, k->buf, sizeof k->buf);
	cfgstore_status_t st =
	    n ? cfgstore_save(k->store, k->buf, (uint32_t)n, vs_config_schema()) : CFGSTORE_TOO_BIG;
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
