/* Frame codec, resynchronising receiver, duplicate detection, and the
 * documented layout: docs/protocol.md's opcode table and hex examples. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "../host_sim/sim.h"
#include "../proto/frame.h"

/* What a receiver reported. */
typedef struct {
	frame_t f[16];
	uint8_t payload[16][FRAME_RESP_PAYLOAD_MAX];
	unsigned n, overflow;
	uint8_t other[512];
	size_t nother;
} rec_t;

static void on_frame(void *ctx, const frame_t *f)
{
	rec_t *r = ctx;

	if (r->n >= 16) {
		r->overflow++;
		return;
	}
	r->f[r->n] = *f;
	if (f->len)
		memcpy(r->payload[r->n], f->payload, f->len);
	r->f[r->n].payload = r->payload[r->n];
	r->n++;
}

static void on_other(void *ctx, const uint8_t *d, size_t n)
{
	rec_t *r = ctx;

	if (r->nother + n > sizeof(r->other)) {
		r->nother = sizeof(r->other) + 1; /* marks overflow */
		return;
	}
	memcpy(r->other + r->nother, d, n);
	r->nother += n;
}

static rec_t R;
static frame_rx_t RX;
static uint8_t RXBUF[FRAME_RESP_MAX];

static void rx_reset(size_t max_payload)
{
	memset(&R, 0, sizeof(R));
	frame_rx_init(&RX, RXBUF, max_payload, on_frame, on_other, &R);
}

static void test_crc_check_value(void **state)
{
	(void)state;
	assert_int_equal(cmd_crc16(0xFFFF, "123456789", 9), 0x29B1);
}

static void test_encode_exact(void **state)
{
	uint8_t f[32];
	static const uint8_t pay[] = {0, 0, 0, 0, 0, 0x40, 0x7F, 0x40};
	static const uint8_t want[] = {0xA5, 0x08, 0x00, 0x02, 0x11, 0,	   0,	0,
				       0,    0,	   0x40, 0x7F, 0x40, 0x08, 0xB4};

	(void)state;
	assert_int_equal(frame_encode(f, sizeof(f), 2, 0x11, pay, 8), sizeof(want));
	assert_memory_equal(f, want, sizeof(want));
	assert_int_equal(frame_encode(f, 14, 2, 0x11, pay, 8), 0);
}

static void test_rx_good_split_and_garbage(void **state)
{
	uint8_t f[32], s[80];
	size_t n = frame_encode(f, sizeof(f), 7, 9, NULL, 0), k = 0;

	(void)state;
	rx_reset(FRAME_REQ_PAYLOAD_MAX);
	/* console text, then the frame byte by byte, then text */
	memcpy(s, "getState\n", 9);
	k = 9;
	memcpy(s + k, f, n);
	k += n;
	memcpy(s + k, "x\n", 2);
	k += 2;
	for (size_t i = 0; i < k; i++)
		frame_rx_feed(&RX, s + i, 1, 0);
	assert_int_equal(R.n, 1);
	assert_int_equal(R.f[0].status, WIRE_ST_OK);
	assert_int_equal(R.f[0].seq, 7);
	assert_int_equal(R.f[0].op, 9);
	assert_int_equal(R.f[0].len, 0);
	assert_int_equal(R.nother, 11);
	assert_memory_equal(R.other, "getState\nx\n", 11);
	assert_int_equal(RX.st.frames, 1);
	assert_false(frame_rx_busy(&RX));
}

/* A bad check costs only the sync byte: the real frame right behind a
 * damaged one is still found. */
static void test_rx_bad_crc_resyncs(void **state)
{
	uint8_t a[32], b[32], s[64];
	size_t na = frame_encode(a, sizeof(a), 1, 17, (const uint8_t *)"\0\0\0\0\0\x40\x7f\x40", 8);
	size_t nb = frame_encode(b, sizeof(b), 2, 9, NULL, 0);

	(void)state;
	rx_reset(FRAME_REQ_PAYLOAD_MAX);
	a[na - 1] ^= 0x01;
	memcpy(s, a, na);
	memcpy(s + na, b, nb);
	frame_rx_feed(&RX, s, na + nb, 0);
	assert_int_equal(R.n, 2);
	assert_int_equal(R.f[0].status, WIRE_ST_CRC);
	assert_true(R.f[0].header);
	assert_int_equal(R.f[0].seq, 1);
	assert_int_equal(R.f[1].status, WIRE_ST_OK);
	assert_int_equal(R.f[1].seq, 2);
	assert_int_equal(RX.st.crc_errors, 1);
	/* the damaged frame's other bytes went to the console side */
	assert_int_equal(R.nother, na - 1);

	/* A frame whose length swallows the start of the next one: once the
	 * bogus candidate fails its check, the real frame inside is found. */
	rx_reset(FRAME_REQ_PAYLOAD_MAX);
	s[0] = FRAME_SYNC;
	s[1] = 3; /* 3 + 7 bytes: the candidate completes inside b */
	s[2] = 0;
	memcpy(s + 3, b, nb);
	frame_rx_feed(&RX, s, 3 + nb, 0);
	assert_int_equal(R.n, 2);
	assert_int_equal(R.f[0].status, WIRE_ST_CRC);
	assert_int_equal(R.f[1].status, WIRE_ST_OK);
	assert_int_equal(R.f[1].seq, 2);
}

static void test_rx_oversize_and_truncated(void **state)
{
	uint8_t s[8] = {FRAME_SYNC, 65, 0, 3, 9};
	uint8_t b[16];
	size_t nb = frame_encode(b, sizeof(b), 9, 9, NULL, 0);

	(void)state;
	rx_reset(FRAME_REQ_PAYLOAD_MAX);
	/* 65 > 64: rejected as soon as the seq byte is in, which it echoes */
	frame_rx_feed(&RX, s, 3, 0);
	assert_int_equal(R.n, 0);
	frame_rx_feed(&RX, s + 3, 1, 0);
	assert_int_equal(R.n, 1);
	assert_int_equal(R.f[0].status, WIRE_ST_OVERSIZE);
	assert_false(R.f[0].header);
	assert_int_equal(R.f[0].seq, 3);
	assert_int_equal(RX.st.oversize, 1);
	assert_false(frame_rx_busy(&RX));
	/* the length alone, then silence: truncated, no seq to echo */
	rx_reset(FRAME_REQ_PAYLOAD_MAX);
	frame_rx_feed(&RX, s, 3, 0);
	frame_rx_poll(&RX, FRAME_RX_TIMEOUT_MS);
	assert_int_equal(R.n, 1);
	assert_int_equal(R.f[0].status, WIRE_ST_TRUNCATED);
	assert_int_equal(R.f[0].seq, 0);
	assert_int_equal(RX.st.oversize, 0);
	/* cut short after the seq byte: truncated with that seq */
	rx_reset(FRAME_REQ_PAYLOAD_MAX);
	frame_rx_feed(&RX, (const uint8_t[]){FRAME_SYNC, 8, 0, 0x52}, 4, 0);
	frame_rx_poll(&RX, FRAME_RX_TIMEOUT_MS);
	assert_int_equal(R.n, 1);
	assert_int_equal(R.f[0].status, WIRE_ST_TRUNCATED);
	assert_false(R.f[0].header);
	assert_int_equal(R.f[0].seq, 0x52);

	/* A frame cut short: reported after the inter-byte timeout, not before */
	rx_reset(FRAME_REQ_PAYLOAD_MAX);
	frame_rx_feed(&RX, b, nb - 1, 1000);
	frame_rx_poll(&RX, 1000 + FRAME_RX_TIMEOUT_MS - 1);
	assert_int_equal(R.n, 0);
	assert_true(frame_rx_busy(&RX));
	frame_rx_poll(&RX, 1000 + FRAME_RX_TIMEOUT_MS);
	assert_int_equal(R.n, 1);
	assert_int_equal(R.f[0].status, WIRE_ST_TRUNCATED);
	assert_true(R.f[0].header);
	assert_int_equal(R.f[0].seq, 9);
	assert_false(frame_rx_busy(&RX));
	/* and the next whole frame is received normally */
	frame_rx_feed(&RX, b, nb, 2000);
	assert_int_equal(R.n, 2);
	assert_int_equal(R.f[1].status, WIRE_ST_OK);
}

static void test_rx_random_bytes_never_overrun(void **state)
{
	uint8_t s[4096];
	uint8_t b[16];
	size_t nb = frame_encode(b, sizeof(b), 0x33, 11, NULL, 0);

	(void)state;
	srand(12345);
	for (unsigned round = 0; round < 50; round++) {
		rx_reset(FRAME_REQ_PAYLOAD_MAX);
		for (size_t i = 0; i < sizeof(s); i++)
			s[i] = (uint8_t)(i % 7 == 0 ? FRAME_SYNC : rand());
		R.nother = 0;
		for (size_t i = 0; i < sizeof(s); i += 97) {
			size_t k = sizeof(s) - i < 97 ? sizeof(s) - i : 97;

			frame_rx_feed(&RX, s + i, k, 0);
			R.n = 0;
			R.nother = 0;
			assert_true(RX.n < RX.cap);
		}
		/* quiet line, then a good frame is received */
		frame_rx_poll(&RX, 1000);
		assert_false(frame_rx_busy(&RX));
		R.n = 0;
		frame_rx_feed(&RX, b, nb, 2000);
		assert_int_equal(R.n, 1);
		assert_int_equal(R.f[0].status, WIRE_ST_OK);
		assert_int_equal(R.f[0].seq, 0x33);
	}
}

/* The hold predicate: while it says so, a sync byte is a byte of the other
 * stream (a console line of text), never the start of a frame. */
static bool HOLD;

static bool hold_fn(void *ctx)
{
	(void)ctx;
	return HOLD;
}

static void test_rx_hold_keeps_sync_in_other(void **state)
{
	static const uint8_t yen[] = {'#', ' ', 0xC2, FRAME_SYNC, ' ', 'y', 'e', 'n'};
	uint8_t b[16];
	size_t nb = frame_encode(b, sizeof(b), 0x21, 11, NULL, 0);

	(void)state;
	rx_reset(FRAME_REQ_PAYLOAD_MAX);
	frame_rx_set_hold(&RX, hold_fn, NULL);
	HOLD = true;
	frame_rx_feed(&RX, yen, sizeof(yen), 0);
	assert_int_equal(R.n, 0);
	assert_int_equal(R.nother, sizeof(yen));
	assert_memory_equal(R.other, yen, sizeof(yen));
	assert_false(frame_rx_busy(&RX));
	/* a whole frame while held: all of it is other bytes */
	frame_rx_feed(&RX, b, nb, 0);
	assert_int_equal(R.n, 0);
	assert_int_equal(R.nother, sizeof(yen) + nb);
	assert_int_equal(RX.st.other_bytes, sizeof(yen) + nb);
	/* not held: the same frame is one */
	HOLD = false;
	frame_rx_feed(&RX, b, nb, 0);
	assert_int_equal(R.n, 1);
	assert_int_equal(R.f[0].status, WIRE_ST_OK);
	assert_int_equal(R.f[0].seq, 0x21);
	assert_int_equal(RX.st.oversize + RX.st.crc_errors + RX.st.truncated, 0);
}

/* What one received byte can cause, the bound the unit's serial service
 * sizes its answer queue by (proto/server.h, SERVER_SERIAL_STEP_MAX): every
 * report (a frame or a NAK) and every line ending handed on belongs to a
 * distinct byte the receiver held, so a byte causes at most as many as the
 * receiver then holds (the timeout: as many as it held). */
static unsigned EVENTS;

static void count_frame(void *ctx, const frame_t *f)
{
	(void)ctx;
	(void)f;
	EVENTS++;
}

static void count_endings(void *ctx, const uint8_t *d, size_t n)
{
	(void)ctx;
	for (size_t i = 0; i < n; i++)
		EVENTS += d[i] == '\r' || d[i] == '\n';
}

static void test_rx_events_per_byte_bounded(void **state)
{
	static const uint8_t pick[] = {FRAME_SYNC, FRAME_SYNC, '\n', '\r', 0x00, 0x01, 0x08, 0x40};
	uint8_t buf[FRAME_REQ_MAX], d[FRAME_REQ_MAX];
	frame_rx_t rx;
	uint32_t rng = 12345;
	unsigned most = 0;

	(void)state;
	frame_rx_init(&rx, buf, FRAME_REQ_PAYLOAD_MAX, count_frame, count_endings, NULL);
	for (int i = 0; i < 400000; i++) {
		size_t held = rx.n;
		uint8_t b;

		rng = rng * 1103515245u + 12345u;
		b = (rng >> 16) % 4 ? pick[(rng >> 20) % sizeof(pick)] : (uint8_t)(rng >> 24);
		EVENTS = 0;
		frame_rx_feed(&rx, &b, 1, 0);
		assert_true(EVENTS <= held + 1);
		if (EVENTS > most)
			most = EVENTS;
		if (i % 997 == 0) {
			held = rx.n;
			EVENTS = 0;
			frame_rx_poll(&rx, FRAME_RX_TIMEOUT_MS);
			assert_true(EVENTS <= held);
		}
	}
	assert_true(most > 1);
	/* The worst: a damaged frame of the largest length whose bytes after
	 * the length are all line endings. Its last byte causes the NAK and
	 * 68 line endings, with 70 bytes held before it. */
	frame_rx_init(&rx, buf, FRAME_REQ_PAYLOAD_MAX, count_frame, count_endings, NULL);
	d[0] = FRAME_SYNC;
	d[1] = FRAME_REQ_PAYLOAD_MAX;
	d[2] = 0;
	memset(d + 3, '\n', sizeof(d) - 3);
	assert_int_not_equal(cmd_crc16(0xFFFF, d + 1, FRAME_HDR - 1 + FRAME_REQ_PAYLOAD_MAX),
			     0x0A0A);
	EVENTS = 0;
	frame_rx_feed(&rx, d, sizeof(d) - 1, 0);
	assert_int_equal(EVENTS, 0);
	assert_int_equal(rx.n, sizeof(d) - 1);
	frame_rx_feed(&rx, d + sizeof(d) - 1, 1, 0);
	assert_int_equal(EVENTS, 1 + sizeof(d) - 3);
	assert_int_equal(rx.st.crc_errors, 1);
	assert_false(frame_rx_busy(&rx));
}

/* The unit's server: NAKs, duplicate detection. */
static sim_t S;
static uint8_t OUT[4096];
static size_t NOUT;

static void out_write(void *ctx, const uint8_t *d, size_t n)
{
	(void)ctx;
	assert_true(NOUT + n <= sizeof(OUT));
	memcpy(OUT + NOUT, d, n);
	NOUT += n;
}

static void boot(void)
{
	vs_config_t cfg;
	plant_params_t pp;

	vs_config_defaults(&cfg);
	/* Time passes in lockstep waits with no request; the link watchdog
	 * has its own tests. */
	cfg.link_timeout_ms = 0;
	plant_params_default(&pp);
	assert_int_equal(sim_init(&S, &cfg, &pp), 0);
}

static void send(frame_srv_t *fs, uint8_t seq, uint8_t op, const void *p, size_t n)
{
	uint8_t f[FRAME_REQ_MAX];
	size_t k = frame_encode(f, sizeof(f), seq, op, p, n);

	assert_int_not_equal(k, 0);
	NOUT = 0;
	frame_srv_feed(fs, f, k, 0);
}

static void test_server_duplicates(void **state)
{
	static frame_srv_t fs;
	uint8_t first[64];
	size_t nfirst;
	uint8_t qlen;
	const uint8_t on = 1, mf[8] = {0, 0, 0, 0, 0, 0x40, 0x7F, 0x40};
	vs_diag_t d;

	(void)state;
	boot();
	frame_srv_init(&fs, &S.vehicle, out_write, NULL, NULL, NULL);
	send(&fs, 1, CMD_OP_setPower, &on, 1);
	send(&fs, 2, CMD_OP_setServo, &on, 1);
	{
		static const uint8_t want[] = {0xA5, 2, 0, 2, 0x9F, 0, 1};

		assert_int_equal(NOUT, 9);
		assert_memory_equal(OUT, want, 7);
	}
	send(&fs, 3, CMD_OP_moveForward, mf, 8);
	nfirst = NOUT;
	memcpy(first, OUT, NOUT);
	vehicle_diag(&S.vehicle, &d);
	qlen = d.queue_len;
	assert_int_equal(fs.st.executed, 3);
	/* Busy now: a second moveForward would be refused with "ok false".
	 * The retransmission gets the first answer (true) and runs nothing. */
	send(&fs, 3, CMD_OP_moveForward, mf, 8);
	assert_int_equal(NOUT, nfirst);
	assert_memory_equal(OUT, first, nfirst);
	assert_int_equal(fs.st.executed, 3);
	assert_int_equal(fs.st.duplicates, 1);
	vehicle_diag(&S.vehicle, &d);
	assert_int_equal(d.queue_len, qlen);
	/* The same seq with other bytes is a new request: executed (refused:
	 * the unit is busy), answered "false". */
	send(&fs, 3, CMD_OP_moveForward, (const uint8_t[8]){0, 0, 0, 0, 0, 0x40, 0x8F, 0x40}, 8);
	assert_int_equal(fs.st.executed, 4);
	assert_int_equal(OUT[6], 0);
	/* NAKs: unknown opcode, wrong length, bad boolean */
	send(&fs, 4, 0x55, NULL, 0);
	{
		static const uint8_t want[] = {0xA5, 1, 0, 4, 0xD5, WIRE_ST_OPCODE};

		assert_int_equal(NOUT, 8);
		assert_memory_equal(OUT, want, sizeof(want));
	}
	send(&fs, 5, CMD_OP_moveForward, mf, 7);
	assert_int_equal(OUT[5], WIRE_ST_LENGTH);
	send(&fs, 6, CMD_OP_setPower, (const uint8_t[1]){2}, 1);
	assert_int_equal(OUT[5], WIRE_ST_VALUE);
	assert_int_equal(fs.st.executed, 4);
	assert_int_equal(fs.st.naks, 3);
	/* an answer frame arriving at the unit is not answered */
	{
		uint8_t f[16];
		size_t k = frame_encode_response(f, sizeof(f), 9, 9, 0, NULL, 0);

		NOUT = 0;
		frame_srv_feed(&fs, f, k, 0);
		assert_int_equal(NOUT, 0);
	}
}

/* NAKs of untrusted frames carry op 0x80 and the seq received, exactly as
 * docs/protocol.md says; opcode 0x00 is NAKed the same way. */
static void test_server_naks_echo_seq(void **state)
{
	static frame_srv_t fs;
	static const uint8_t over[] = {0xA5, 1, 0, 0x53, 0x80, 2, 0x19, 0x87};
	static const uint8_t trunc[] = {0xA5, 1, 0, 0x52, 0x80, 6, 0xAD, 0xF0};
	static const uint8_t trunc0[] = {0xA5, 1, 0, 0, 0x80, 6};

	(void)state;
	boot();
	frame_srv_init(&fs, &S.vehicle, out_write, NULL, NULL, NULL);
	/* len 200, seq 0x53: oversize, answered at once with seq 0x53 */
	NOUT = 0;
	frame_srv_feed(&fs, (const uint8_t[]){0xA5, 0xC8, 0x00, 0x53, 0x0B}, 5, 0);
	assert_int_equal(NOUT, sizeof(over));
	assert_memory_equal(OUT, over, sizeof(over));
	/* len 8, seq 0x52, then silence: truncated with seq 0x52 */
	NOUT = 0;
	frame_srv_feed(&fs, (const uint8_t[]){0xA5, 0x08, 0x00, 0x52}, 4, 1000);
	frame_srv_poll(&fs, 1000 + FRAME_RX_TIMEOUT_MS - 1);
	assert_int_equal(NOUT, 0);
	frame_srv_poll(&fs, 1000 + FRAME_RX_TIMEOUT_MS);
	assert_int_equal(NOUT, sizeof(trunc));
	assert_memory_equal(OUT, trunc, sizeof(trunc));
	/* only the sync and length: nothing received to echo, seq 0 */
	NOUT = 0;
	frame_srv_feed(&fs, (const uint8_t[]){0xA5, 0x08, 0x00}, 3, 2000);
	frame_srv_poll(&fs, 2000 + FRAME_RX_TIMEOUT_MS);
	assert_int_equal(NOUT, sizeof(trunc0) + 2);
	assert_memory_equal(OUT, trunc0, sizeof(trunc0));
	/* opcode 0x00: no such operation, NAKed with op 0x80 */
	send(&fs, 0x44, 0x00, NULL, 0);
	assert_int_equal(NOUT, 8);
	assert_memory_equal(OUT, ((const uint8_t[]){0xA5, 1, 0, 0x44, 0x80, WIRE_ST_OPCODE}), 6);
	assert_int_equal(fs.st.executed, 0);
	assert_int_equal(fs.st.naks, 4);
}

/* docs/protocol.md */
static char *read_doc(void)
{
	FILE *f = fopen("docs/protocol.md", "r");
	static char buf[65536];
	size_t n;

	assert_non_null(f);
	n = fread(buf, 1, sizeof(buf) - 1, f);
	fclose(f);
	buf[n] = '\0';
	return buf;
}

static void test_doc_opcode_table(void **state)
{
	char *doc = read_doc(), *p = doc;
	unsigned rows = 0;

	(void)state;
	while ((p = strstr(p, "\n| ")) != NULL) {
		unsigned op, hex;
		char name[64], in[8], out[8];

		p++;
		if (sscanf(p, "| %u | 0x%x | `%63[A-Za-z]` | %7[a-z-] | %7[a-z-] |", &op, &hex,
			   name, in, out) != 5)
			continue;
		{
			const cmd_def_t *d = cmd_by_opcode(op);

			assert_non_null(d);
			assert_int_equal(hex, op);
			assert_string_equal(name, d->name);
			assert_string_equal(in, d->n_in ? d->in_types : "-");
			assert_string_equal(out, d->n_out ? d->out_types : "-");
			assert_int_equal(op, rows + 1);
			rows++;
		}
	}
	assert_int_equal(rows, CMD_COUNT);
	assert_non_null(strstr(doc, "now `0x1F09`"));
	assert_int_equal(cmd_table_crc(), 0x1F09);
}

/* The example block: "# title" then one hex line. */
static size_t doc_example(const char *title, uint8_t *b, size_t cap)
{
	char *doc = read_doc(), key[256], *p;
	size_t n = 0;

	snprintf(key, sizeof(key), "# %s\n", title);
	p = strstr(doc, key);
	assert_non_null(p);
	p += strlen(key);
	while (*p && *p != '\n') {
		unsigned v;
		int used;

		assert_int_equal(sscanf(p, "%2x%n", &v, &used), 1);
		assert_true(n < cap);
		b[n++] = (uint8_t)v;
		p += used;
		while (*p == ' ')
			p++;
	}
	return n;
}

/* Decodes one documented frame; exactly one good frame, nothing else. */
static const frame_t *doc_frame(const char *title)
{
	uint8_t b[256];
	size_t n = doc_example(title, b, sizeof(b));

	rx_reset(FRAME_RESP_PAYLOAD_MAX);
	frame_rx_feed(&RX, b, n, 0);
	assert_int_equal(R.n, 1);
	assert_int_equal(R.nother, 0);
	assert_int_equal(R.f[0].status, WIRE_ST_OK);
	return &R.f[0];
}

static void test_doc_examples(void **state)
{
	const frame_t *f;
	wire_store_t st;
	cmd_value_t v[3];
	bool r = false;

	(void)state;
	f = doc_frame("getPosition request, seq 0x01");
	assert_int_equal(f->seq, 1);
	assert_int_equal(f->op, CMD_OP_getPosition);
	assert_int_equal(f->len, 0);

	f = doc_frame("getPosition response, seq 0x01: true, x 500, y 0, theta 90");
	assert_int_equal(f->seq, 1);
	assert_int_equal(f->op, 0x80 | CMD_OP_getPosition);
	assert_int_equal(f->payload[0], WIRE_ST_OK);
	assert_int_equal(wire_decode_response(cmd_by_opcode(CMD_OP_getPosition), f->payload + 1,
					      f->len - 1, &r, v, &st),
			 WIRE_ST_OK);
	assert_true(r);
	assert_true(v[0].d == 500.0 && v[1].d == 0.0 && v[2].d == 90.0);

	f = doc_frame("moveForward 500 request, seq 0x02");
	assert_int_equal(f->seq, 2);
	assert_int_equal(f->op, CMD_OP_moveForward);
	assert_int_equal(
	    wire_decode_request(cmd_by_opcode(CMD_OP_moveForward), f->payload, f->len, v, &st),
	    WIRE_ST_OK);
	assert_true(v[0].d == 500.0);

	f = doc_frame("moveForward response, seq 0x02: true");
	assert_int_equal(f->op, 0x80 | CMD_OP_moveForward);
	assert_int_equal(f->len, 2);
	assert_int_equal(f->payload[0], 0);
	assert_int_equal(f->payload[1], 1);

	f = doc_frame("getState response, seq 0x03: true, 16, \"Ready\"");
	assert_int_equal(f->seq, 3);
	assert_int_equal(wire_decode_response(cmd_by_opcode(CMD_OP_getState), f->payload + 1,
					      f->len - 1, &r, v, &st),
			 WIRE_ST_OK);
	assert_true(r);
	assert_int_equal(v[0].h, 16);
	assert_string_equal(v[1].s, "Ready");

	f = doc_frame("getActiveAlarm response, seq 0x04: true, 1, [120 warning \"moveTurn "
		      "refused: unit not ready\"]");
	assert_int_equal(wire_decode_response(cmd_by_opcode(CMD_OP_getActiveAlarm), f->payload + 1,
					      f->len - 1, &r, v, &st),
			 WIRE_ST_OK);
	assert_int_equal(v[0].h, 1);
	assert_int_equal(v[1].alarms.n, 1);
	assert_int_equal(v[1].alarms.a[0].code, 120);
	assert_int_equal(v[1].alarms.a[0].type, VS_ALARM_WARNING);
	assert_string_equal(v[1].alarms.a[0].source, "moveTurn refused: unit not ready");

	f = doc_frame("NAK, seq 0x05: opcode 0x55 unknown");
	assert_int_equal(f->seq, 5);
	assert_int_equal(f->op, 0xD5);
	assert_int_equal(f->len, 1);
	assert_int_equal(f->payload[0], WIRE_ST_OPCODE);

	f = doc_frame("NAK, seq 0x06: bad check");
	assert_int_equal(f->op, 0x80);
	assert_int_equal(f->len, 1);
	assert_int_equal(f->payload[0], WIRE_ST_CRC);

	f = doc_frame("protocol info request, seq 0x07");
	assert_int_equal(f->op, WIRE_OP_INFO);
	f = doc_frame("protocol info response, seq 0x07");
	assert_int_equal(f->op, 0xFF);
	assert_int_equal(f->len, 1 + WIRE_INFO_LEN);
	assert_int_equal(f->payload[1], CMD_PROTO_VERSION);
	assert_int_equal(wire_get_u16(f->payload + 2), cmd_table_crc());
	assert_int_equal(f->payload[4], CMD_COUNT);
}

static bool run_line(void *ctx, const char *line, char *reply, size_t cap)
{
	return console_exec(ctx, line, reply, cap);
}

/* Console lines in frames (WIRE_OP_CONSOLE): the documented exchange byte
 * for byte, the NAKs, a retransmission answered from the cache. */
static void test_server_console_line(void **state)
{
	static frame_srv_t fs;
	uint8_t req[64], resp[64];
	(void)state;
	boot();
	frame_srv_init(&fs, &S.vehicle, out_write, NULL, NULL, NULL);
	send(&fs, 1, WIRE_OP_CONSOLE, (const uint8_t *)"$version", 8);
	assert_int_equal(NOUT, 8);
	assert_memory_equal(OUT, ((const uint8_t[]){0xA5, 1, 0, 1, 0xFE, WIRE_ST_OPCODE}), 6);
	frame_srv_set_line(&fs, run_line, &S.srv.con);
	size_t nreq = doc_example("$config tick_hz request, seq 0x08", req, sizeof(req));
	size_t nresp = doc_example("its response: \"ok tick_hz 1000\"", resp, sizeof(resp));
	NOUT = 0;
	frame_srv_feed(&fs, req, nreq, 0);
	assert_int_equal(NOUT, nresp);
	assert_memory_equal(OUT, resp, nresp);
	/* an error reply is the answer's payload too */
	send(&fs, 2, WIRE_OP_CONSOLE, (const uint8_t *)"$config nosuch", 14);
	assert_int_equal(NOUT, 7 + 1 + 32);
	assert_memory_equal(OUT + 6, "error 8 $config: no field nosuch", 32);
	/* a comment: an empty answer */
	send(&fs, 3, WIRE_OP_CONSOLE, (const uint8_t *)"# note", 6);
	assert_int_equal(NOUT, 8);
	assert_int_equal(OUT[5], WIRE_ST_OK);
	/* once, however often it is sent again */
	send(&fs, 4, WIRE_OP_CONSOLE, (const uint8_t *)"$watchdog 300", 13);
	assert_int_equal(fs.st.executed, 4);
	send(&fs, 4, WIRE_OP_CONSOLE, (const uint8_t *)"$watchdog 300", 13);
	assert_int_equal(fs.st.executed, 4);
	assert_int_equal(fs.st.duplicates, 1);
	assert_memory_equal(OUT + 6, "ok watchdog 300", 15);
	/* not one line of 1..64 bytes: NAK value */
	send(&fs, 5, WIRE_OP_CONSOLE, NULL, 0);
	assert_int_equal(OUT[5], WIRE_ST_VALUE);
	send(&fs, 6, WIRE_OP_CONSOLE, (const uint8_t *)"getState\nstop", 13);
	assert_int_equal(OUT[5], WIRE_ST_VALUE);
	send(&fs, 7, WIRE_OP_CONSOLE, (const uint8_t *)"get\0State", 9);
	assert_int_equal(OUT[5], WIRE_ST_VALUE);
	assert_int_equal(fs.st.executed, 4);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test(test_crc_check_value),
	    cmocka_unit_test(test_encode_exact),
	    cmocka_unit_test(test_rx_good_split_and_garbage),
	    cmocka_unit_test(test_rx_bad_crc_resyncs),
	    cmocka_unit_test(test_rx_oversize_and_truncated),
	    cmocka_unit_test(test_rx_random_bytes_never_overrun),
	    cmocka_unit_test(test_rx_hold_keeps_sync_in_other),
	    cmocka_unit_test(test_rx_events_per_byte_bounded),
	    cmocka_unit_test(test_server_naks_echo_seq),
	    cmocka_unit_test(test_server_duplicates),
	    cmocka_unit_test(test_server_console_line),
	    cmocka_unit_test(test_doc_opcode_table),
	    cmocka_unit_test(test_doc_examples),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
