/* The saved configuration's store (firmware/cfgstore.h) on a model of a
 * microcontroller's flash: pages erased whole, words programmed once each,
 * and a power cut that may land after any single word programmed or
 * erased, or inside one (the word then half done: some of its bits
 * changed). Every save of a history is cut at every step, both ways, and
 * the store booted: it must hold the record from before the save or the one
 * it wrote, never a mix, and a completed save's record always; a save after
 * the cut must work. */
#include <setjmp.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "../firmware/cfgstore.h"
#include "../firmware/config_save.h"

#define MEM_MAX 2048

typedef struct {
	uint8_t mem[MEM_MAX];
	long steps;   /* word steps taken since the count was reset */
	long cut_at;  /* the step the power goes in (-1: never) */
	bool partial; /* that step is left half done */
	bool dead;    /* power gone: nothing more happens */
	uint32_t rng;
	bool bad_program; /* a program of a word that was not erased */
	hal_store_t hs;
} flash_t;

static uint32_t rnd(flash_t *f)
{
	f->rng = f->rng * 1664525u + 1013904223u;
	return f->rng >> 8;
}

/* A step: true to do it whole; false when the power goes here (half done
 * when partial). */
static bool step(flash_t *f, uint8_t *w, const uint8_t *target, uint32_t n, bool erase)
{
	if (f->dead)
		return false;
	if (f->steps++ == f->cut_at) {
		f->dead = true;
		if (f->partial)
			for (uint32_t i = 0; i < n; i++) {
				uint8_t m = (uint8_t)rnd(f);
				/* Erasing sets bits, programming clears them: a
				 * random part of what the step would change. */
				w[i] = erase ? (uint8_t)(w[i] | m)
					     : (uint8_t)(w[i] & (target[i] | ~m));
			}
		return false;
	}
	for (uint32_t i = 0; i < n; i++)
		w[i] = erase ? 0xFF : target[i];
	return true;
}

static bool f_read(void *ctx, uint32_t off, void *buf, uint32_t n)
{
	flash_t *f = ctx;
	if (f->dead || off + n > f->hs.pages * f->hs.page_size)
		return false;
	memcpy(buf, f->mem + off, n);
	return true;
}

static bool f_erase(void *ctx, uint32_t page)
{
	flash_t *f = ctx;
	if (page >= f->hs.pages)
		return false;
	uint32_t w = f->hs.word;
	for (uint32_t o = 0; o < f->hs.page_size; o += w)
		if (!step(f, f->mem + page * f->hs.page_size + o, NULL, w, true))
			return false;
	return true;
}

static bool f_program(void *ctx, uint32_t off, const void *buf, uint32_t n)
{
	flash_t *f = ctx;
	uint32_t w = f->hs.word;
	if (off % w || n % w || off + n > f->hs.pages * f->hs.page_size)
		return false;
	for (uint32_t o = 0; o < n; o += w) {
		uint8_t *p = f->mem + off + o;
		for (uint32_t i = 0; i < w; i++)
			if (p[i] != 0xFF) {
				f->bad_program = true;
				return false;
			}
		if (!step(f, p, (const uint8_t *)buf + o, w, false))
			return false;
	}
	return true;
}

static void flash_init(flash_t *f, uint32_t page_size, uint32_t pages, uint32_t word)
{
	memset(f, 0, sizeof *f);
	memset(f->mem, 0xFF, sizeof f->mem);
	f->cut_at = -1;
	f->rng = 12345;
	f->hs = (hal_store_t){page_size, pages, word, 0xFF, f_read, f_erase, f_program, f};
}

/* The power comes back: the next boot reads. */
static void power_on(flash_t *f)
{
	f->dead = false;
	f->cut_at = -1;
	f->steps = 0;
}

static void payload(uint8_t *p, uint32_t len, uint32_t k)
{
	for (uint32_t i = 0; i < len; i++)
		p[i] = (uint8_t)(k * 31u + i * 7u + (i >> 3));
}

typedef struct {
	bool any;
	uint8_t b[MEM_MAX];
	uint32_t len, schema;
} rec_t;

static bool same(const rec_t *r, const uint8_t *buf, uint32_t len, uint32_t schema)
{
	return r->any && r->len == len && r->schema == schema && memcmp(r->b, buf, len) == 0;
}

/* Boot after a cut: the record before the save (or none) or the new one. */
static void check_boot(flash_t *f, const rec_t *old, const rec_t *new_, long k)
{
	static uint8_t buf[MEM_MAX];
	cfgstore_info_t info;
	power_on(f);
	cfgstore_status_t st = cfgstore_load(&f->hs, buf, sizeof buf, &info);
	if (st == CFGSTORE_EMPTY && !old->any)
		return;
	if (st != CFGSTORE_OK ||
	    (!same(old, buf, info.len, info.schema) && !same(new_, buf, info.len, info.schema))) {
		fail_msg(
		    "cut at step %ld (%s): status %d, len %u, neither the old record nor the new",
		    k, f->partial ? "inside it" : "after it", st, info.len);
	}
}

static void history(uint32_t page_size, uint32_t pages, uint32_t word)
{
	static flash_t f, snap;
	flash_init(&f, page_size, pages, word);
	uint32_t cap = cfgstore_capacity(&f.hs);
	assert_int_equal(cap, (pages / 2) * page_size - CFGSTORE_HEADER);
	const uint32_t lens[] = {0, 1, 5, word * 3, 100 < cap ? 100 : cap, cap - 1, cap, 7};
	static rec_t old, cur;
	old.any = false;
	uint8_t buf[MEM_MAX];
	cfgstore_info_t info;
	assert_int_equal(cfgstore_load(&f.hs, buf, sizeof buf, &info), CFGSTORE_EMPTY);
	assert_false(info.other_torn);
	long cases = 0;
	for (uint32_t i = 0; i < sizeof lens / sizeof lens[0]; i++) {
		cur.any = true;
		cur.len = lens[i];
		cur.schema = 0x1000u + i;
		payload(cur.b, cur.len, i);
		/* The whole save once, to count its steps. */
		snap = f;
		power_on(&f);
		assert_int_equal(cfgstore_save(&f.hs, cur.b, cur.len, cur.schema), CFGSTORE_OK);
		long n = f.steps;
		assert_false(f.bad_program);
		for (long k = 0; k < n; k++)
			for (int partial = 0; partial < 2; partial++) {
				f = snap;
				f.hs.ctx = &f;
				power_on(&f);
				f.cut_at = k;
				f.partial = partial;
				f.rng = (uint32_t)(k * 2 + partial + 1);
				assert_int_not_equal(
				    cfgstore_save(&f.hs, cur.b, cur.len, cur.schema), CFGSTORE_OK);
				assert_false(f.bad_program);
				check_boot(&f, &old, &cur, k);
				/* A save after the cut works, and wins. */
				assert_int_equal(cfgstore_save(&f.hs, cur.b, cur.len, cur.schema),
						 CFGSTORE_OK);
				assert_false(f.bad_program);
				memset(buf, 0, sizeof buf);
				assert_int_equal(cfgstore_load(&f.hs, buf, sizeof buf, &info),
						 CFGSTORE_OK);
				assert_true(same(&cur, buf, info.len, info.schema));
				cases++;
			}
		/* The save done whole: its record, the sequence one on. */
		f = snap;
		f.hs.ctx = &f;
		power_on(&f);
		uint32_t seq0 = 0;
		if (old.any) {
			assert_int_equal(cfgstore_load(&f.hs, buf, sizeof buf, &info), CFGSTORE_OK);
			seq0 = info.seq;
		}
		assert_int_equal(cfgstore_save(&f.hs, cur.b, cur.len, cur.schema), CFGSTORE_OK);
		memset(buf, 0, sizeof buf);
		assert_int_equal(cfgstore_load(&f.hs, buf, sizeof buf, &info), CFGSTORE_OK);
		assert_true(same(&cur, buf, info.len, info.schema));
		assert_int_equal(info.seq, seq0 + 1);
		assert_false(info.other_torn);
		old = cur;
	}
	printf("  %u-byte pages x %u, %u-byte words: %ld cut saves booted\n", page_size, pages,
	       word, cases);
}

static void test_every_cut_4byte_words(void **state)
{
	(void)state;
	history(256, 2, 4);
}

static void test_every_cut_8byte_words_two_pages_a_slot(void **state)
{
	(void)state;
	history(128, 4, 8);
}

/* A clear cut anywhere leaves the newest record or none. */
static void test_clear_cut(void **state)
{
	(void)state;
	static flash_t f, snap;
	flash_init(&f, 256, 2, 4);
	uint8_t a[40], b[60], buf[MEM_MAX];
	payload(a, sizeof a, 1);
	payload(b, sizeof b, 2);
	assert_int_equal(cfgstore_save(&f.hs, a, sizeof a, 7), CFGSTORE_OK);
	assert_int_equal(cfgstore_save(&f.hs, b, sizeof b, 7), CFGSTORE_OK);
	snap = f;
	power_on(&f);
	assert_int_equal(cfgstore_clear(&f.hs), CFGSTORE_OK);
	long n = f.steps;
	cfgstore_info_t info;
	assert_int_equal(cfgstore_load(&f.hs, buf, sizeof buf, &info), CFGSTORE_EMPTY);
	assert_false(info.other_torn);
	for (long k = 0; k < n; k++) {
		f = snap;
		f.hs.ctx = &f;
		power_on(&f);
		f.cut_at = k;
		f.partial = true;
		assert_int_not_equal(cfgstore_clear(&f.hs), CFGSTORE_OK);
		power_on(&f);
		cfgstore_status_t st = cfgstore_load(&f.hs, buf, sizeof buf, &info);
		if (st == CFGSTORE_OK) {
			assert_int_equal(info.len, sizeof b);
			assert_memory_equal(buf, b, sizeof b);
		} else {
			assert_int_equal(st, CFGSTORE_EMPTY);
		}
	}
}

/* Damage: both slots neither erased nor valid is CORRUPT; one record whose
 * byte flipped is not returned. */
static void test_damage(void **state)
{
	(void)state;
	static flash_t f;
	flash_init(&f, 256, 2, 4);
	uint8_t a[40], buf[MEM_MAX];
	cfgstore_info_t info;
	payload(a, sizeof a, 3);
	assert_int_equal(cfgstore_save(&f.hs, a, sizeof a, 9), CFGSTORE_OK);
	f.mem[CFGSTORE_HEADER + 5] ^= 0x10; /* a payload bit */
	assert_int_equal(cfgstore_load(&f.hs, buf, sizeof buf, &info), CFGSTORE_EMPTY);
	assert_true(info.other_torn);
	f.mem[256 + 3] = 0; /* the other slot not erased either */
	assert_int_equal(cfgstore_load(&f.hs, buf, sizeof buf, &info), CFGSTORE_CORRUPT);
	/* A save repairs it. */
	assert_int_equal(cfgstore_save(&f.hs, a, sizeof a, 9), CFGSTORE_OK);
	assert_int_equal(cfgstore_load(&f.hs, buf, sizeof buf, &info), CFGSTORE_OK);
	assert_memory_equal(buf, a, sizeof a);
	/* Too big for the caller's buffer, or for the store. */
	assert_int_equal(cfgstore_load(&f.hs, buf, 39, &info), CFGSTORE_TOO_BIG);
	assert_int_equal(cfgstore_save(&f.hs, buf, cfgstore_capacity(&f.hs) + 1, 9),
			 CFGSTORE_TOO_BIG);
	/* No store, or one with a geometry that cannot hold two slots. */
	assert_int_equal(cfgstore_load(NULL, buf, sizeof buf, &info), CFGSTORE_NO_STORE);
	f.hs.pages = 1;
	assert_int_equal(cfgstore_save(&f.hs, a, sizeof a, 9), CFGSTORE_NO_STORE);
}

/* The CRC is CRC-32/ISO-HDLC: "123456789" gives 0xCBF43926. */
static void test_crc32(void **state)
{
	(void)state;
	assert_int_equal(cfgstore_crc32(0, "123456789", 9), 0xCBF43926u);
	assert_int_equal(cfgstore_crc32(cfgstore_crc32(0, "1234", 4), "56789", 5), 0xCBF43926u);
}

/* The table's fields only (the io list is not saved). */
static void assert_fields_equal(const vs_config_t *a, const vs_config_t *b)
{
	for (unsigned i = 0; i < VS_CONFIG_NFIELDS; i++) {
		const vs_config_field_t *f = &vs_config_fields[i];
		for (unsigned k = 0; k < f->n; k++)
			if (vs_config_get(a, f, k) != vs_config_get(b, f, k))
				fail_msg("%s[%u]: %g, want %g", f->name, k, vs_config_get(a, f, k),
					 vs_config_get(b, f, k));
	}
}

/* What differs from the base, by name, and back: exactly. */
static void test_config_round_trip(void **state)
{
	(void)state;
	vs_config_t base, cur, out;
	uint8_t buf[1024];
	vs_config_defaults(&base);
	cur = base;
	assert_int_equal(vs_config_encode(&cur, &base, buf, sizeof buf), 4);
	assert_int_equal(buf[0], 1);
	assert_int_equal(buf[1], 'D');
	assert_int_equal(buf[2] | buf[3] << 8, 0);
	cur.wheel_diameter_mm = 160.125;
	cur.drive_lag_ms[2] = 35.5;
	cur.tick_hz = 500;
	cur.kinematics = VS_KIN_OMNI;
	size_t n = vs_config_encode(&cur, &base, buf, sizeof buf);
	/* 4 + (1 + 17 + 3 + 8) + (1 + 12 + 3 + 8) + (1 + 7 + 3 + 4) + (1 + 10 + 3 + 4) */
	assert_int_equal(n, 4 + 29 + 24 + 15 + 18);
	assert_int_equal(buf[2], 4);
	out = base;
	vs_config_decode_t info;
	assert_int_equal(vs_config_decode(&out, buf, n, &info), VS_CFGSAVE_OK);
	assert_int_equal(info.applied, 4);
	assert_int_equal(info.dropped, 0);
	assert_fields_equal(&out, &cur);
	/* Too small a buffer: nothing. */
	assert_int_equal(vs_config_encode(&cur, &base, buf, n - 1), 0);
}

/* A store written by another table: a field it no longer has, one whose
 * type changed, an element past the array, a boolean that is not 0 or 1
 * are dropped; the rest is taken. */
static void test_config_other_table(void **state)
{
	(void)state;
	vs_config_t base, out;
	vs_config_defaults(&base);
	uint8_t buf[256];
	size_t pos = 4;
	const struct {
		const char *name;
		uint8_t k, type, size;
		uint8_t v[8];
	} e[] = {
	    {"old_field", 0, VS_CFG_U32, 4, {1, 0, 0, 0}},
	    {"tick_hz", 0, VS_CFG_U16, 2, {0xF4, 0x01}},	       /* was U32 */
	    {"drive_lag_ms", 9, VS_CFG_DOUBLE, 8, {0}},		       /* past the array */
	    {"link_timeout_ms", 0, VS_CFG_U32, 4, {0xD0, 0x07, 0, 0}}, /* 2000 */
	};
	for (unsigned i = 0; i < sizeof e / sizeof e[0]; i++) {
		size_t nl = strlen(e[i].name);
		buf[pos++] = (uint8_t)nl;
		memcpy(buf + pos, e[i].name, nl);
		pos += nl;
		buf[pos++] = e[i].k;
		buf[pos++] = e[i].type;
		buf[pos++] = e[i].size;
		memcpy(buf + pos, e[i].v, e[i].size);
		pos += e[i].size;
	}
	buf[0] = 1;
	buf[1] = 'D';
	buf[2] = 4;
	buf[3] = 0;
	out = base;
	vs_config_decode_t info;
	assert_int_equal(vs_config_decode(&out, buf, pos, &info), VS_CFGSAVE_OK);
	assert_int_equal(info.applied, 1);
	assert_int_equal(info.dropped, 3);
	assert_int_equal(out.link_timeout_ms, 2000);
	assert_int_equal(out.tick_hz, base.tick_hz);
	/* Cut short anywhere: malformed, nothing applied. */
	for (size_t n = 0; n < pos; n++) {
		out = base;
		assert_int_equal(vs_config_decode(&out, buf, n, &info), VS_CFGSAVE_MALFORMED);
		assert_int_equal(out.link_timeout_ms, base.link_timeout_ms);
	}
	/* Bytes past the last entry: malformed too. */
	assert_int_equal(vs_config_decode(&out, buf, pos + 1, &info), VS_CFGSAVE_MALFORMED);
	/* Another platform's numbers, another version: foreign. */
	buf[1] = 'Q';
	assert_int_equal(vs_config_decode(&out, buf, pos, &info), VS_CFGSAVE_FOREIGN);
	buf[1] = 'D';
	buf[0] = 2;
	assert_int_equal(vs_config_decode(&out, buf, pos, &info), VS_CFGSAVE_FOREIGN);
}

/* The schema names this table: it changes when a row's name, type or
 * length does (a new firmware then says it read an older store). Update
 * the constant with the table. */
static void test_config_schema(void **state)
{
	(void)state;
	assert_int_equal(vs_config_schema(), 0x916B11C3u);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test(test_crc32),
	    cmocka_unit_test(test_every_cut_4byte_words),
	    cmocka_unit_test(test_every_cut_8byte_words_two_pages_a_slot),
	    cmocka_unit_test(test_clear_cut),
	    cmocka_unit_test(test_damage),
	    cmocka_unit_test(test_config_round_trip),
	    cmocka_unit_test(test_config_other_table),
	    cmocka_unit_test(test_config_schema),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
