/* The black box (firmware/blackbox.h, proto/bbox_wire.h, docs/protocol.md
 * "Black box"): the ring alone (wrap, decimation, freeze on the first
 * fault, clear re-arms, no storage records nothing); then in lockstep on
 * the simulated plant, a wheel's encoder stuck at speed (following error
 * 204) with the trace running on the same run: the black box read out over
 * the serial link in frames equals the trace's rows for the same ticks,
 * column for column, exact; the trigger tick and fault code; frozen against
 * later ticks and faults; clear; an empty readout; bad requests NAKed and
 * changing nothing; the console's $bbox.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../firmware/vehicle_priv.h"
#include "../host_sim/sim.h"
#include "../proto/bbox_wire.h"
#include "../proto/cmdtab.h"
#include "../proto/server.h"

/* ---- the ring alone ---- */

static bbox_sample_t RING[5];

static void rec(blackbox_t *b, uint32_t tick)
{
	if (bbox_due(b)) {
		bbox_sample_t *s = bbox_slot(b);
		memset(s, 0, sizeof(*s));
		s->tick = tick;
		bbox_commit(b);
	}
}

static void ring_ticks(const blackbox_t *b, const uint32_t *want, uint16_t n)
{
	assert_int_equal(b->count, n);
	for (uint16_t i = 0; i < n; i++)
		assert_int_equal(bbox_get(b, i)->tick, want[i]);
	assert_null(bbox_get(b, n));
}

static void ring_wraps_and_keeps_the_newest(void **state)
{
	blackbox_t b;

	(void)state;
	bbox_init(&b, RING, 5, 0); /* every 0 taken as 1 */
	assert_int_equal(b.status, BBOX_ARMED);
	assert_int_equal(b.every, 1);
	ring_ticks(&b, NULL, 0);
	for (uint32_t t = 1; t <= 3; t++)
		rec(&b, t);
	ring_ticks(&b, (const uint32_t[]){1, 2, 3}, 3);
	for (uint32_t t = 4; t <= 12; t++)
		rec(&b, t);
	ring_ticks(&b, (const uint32_t[]){8, 9, 10, 11, 12}, 5);
}

static void ring_decimates_and_freezes_at_the_fault_tick(void **state)
{
	blackbox_t b;

	(void)state;
	bbox_init(&b, RING, 5, 3);
	for (uint32_t t = 1; t <= 7; t++)
		rec(&b, t);
	ring_ticks(&b, (const uint32_t[]){3, 6}, 2);
	/* a fault in tick 8 (not a turn of the decimation): its sample is
	 * kept and is the last */
	bbox_fault(&b, 204);
	bbox_fault(&b, 210); /* the second waits for nothing: the first stays */
	assert_int_equal(b.status, BBOX_ARMED);
	rec(&b, 8);
	assert_int_equal(b.status, BBOX_FROZEN);
	assert_int_equal(b.trigger, 8);
	assert_int_equal(b.fault, 204);
	for (uint32_t t = 9; t <= 30; t++)
		rec(&b, t);
	bbox_fault(&b, 211);
	rec(&b, 31);
	ring_ticks(&b, (const uint32_t[]){3, 6, 8}, 3);
	assert_int_equal(b.fault, 204);
	assert_int_equal(b.trigger, 8);
	/* clear empties and re-arms; the decimation starts over */
	bbox_clear(&b);
	assert_int_equal(b.status, BBOX_ARMED);
	assert_int_equal(b.fault, 0);
	ring_ticks(&b, NULL, 0);
	for (uint32_t t = 40; t <= 45; t++)
		rec(&b, t);
	ring_ticks(&b, (const uint32_t[]){42, 45}, 2);
	bbox_fault(&b, 205);
	rec(&b, 46);
	assert_int_equal(b.trigger, 46);
	assert_int_equal(b.fault, 205);
}

static void ring_without_storage_records_nothing(void **state)
{
	blackbox_t b;

	(void)state;
	bbox_init(&b, NULL, 5, 1);
	assert_int_equal(b.status, BBOX_OFF);
	assert_false(bbox_due(&b));
	bbox_fault(&b, 204);
	assert_false(b.pending);
	bbox_clear(&b);
	assert_int_equal(b.status, BBOX_OFF);
	bbox_init(&b, RING, 0, 1);
	assert_int_equal(b.status, BBOX_OFF);
	assert_int_equal(b.count, 0);
	assert_null(bbox_get(&b, 0));
}

/* ---- the text form ---- */

static void row_formats_as_the_trace(void **state)
{
	bbox_sample_t s;
	char row[BBOX_CSV_MAX];

	(void)state;
	memset(&s, 0, sizeof(s));
	s.tick = 1234;
	s.ref.x_mm = (q32_t)1 << 31;				      /* 0.5 */
	s.ref.y_mm = -((q32_t)1 << 16);				      /* -0.0000152...: "-0.0000" */
	s.ref.th_deg = ((q32_t)179 << 32) + 4294967;		      /* 179.000999... */
	s.odo.x_mm = (q32_t)12345 * 4294967296 / 10000 + 1;	      /* just over 1.2345 */
	s.odo.y_mm = (q32_t)5 * 4294967296 / 100000;		      /* 0.00005 less a bit */
	s.odo.th_deg = -((q32_t)1 << 31) - ((q32_t)1 << 32) * 100000; /* -100000.5 */
	s.cmd.vx_pt = (q32_t)1 << 31;				      /* 0.5 mm a tick */
	s.cmd.w_pt = -((q32_t)1 << 23);				      /* -1/512 deg a tick */
	s.sp_q8[0] = -256 * 17 - 2;				      /* -17.0078125 */
	s.sp_q8[1] = 32;					      /* 0.125: a tie, to even */
	s.sp_q8[2] = 96;					      /* 0.375: a tie, to even */
	s.enc[0] = -7;
	s.enc[3] = 2147483647;
	s.state = 19;
	s.queue_len = 2;
	s.alarms = 1;
	s.newest_alarm = 204;
	size_t n = bbox_csv_row(&s, 1000, 204, row, sizeof(row));
	const char *want = "1.234000,0.5000,-0.0000,179.0010,1.2345,0.0000,-100000.5000,"
			   "500.000,0.000,-1.953,-17.01,0.12,0.38,0.00,19,2,1,204,-7,0,0,"
			   "2147483647,1234,204";
	assert_string_equal(row, want);
	assert_int_equal(n, strlen(want));
	char fmt[64];
	snprintf(fmt, sizeof(fmt), "%.4f,%.4f", (double)s.odo.x_mm / 4294967296.0,
		 (double)s.odo.y_mm / 4294967296.0);
	assert_string_equal(fmt, "1.2345,0.0000");
	assert_int_equal(bbox_csv_row(&s, 1000, 0, row, BBOX_CSV_MAX - 1), 0);
}

/* ---- in lockstep on the simulated plant ---- */

typedef struct {
	uint8_t in[4096];
	size_t in_len, in_at;
	uint8_t out[1 << 16];
	size_t out_len;
} tport_t;

static tport_t P;
static sim_t U;
static server_serial_t SER;
#define CAP 2000
static bbox_sample_t BB[CAP];
static char *TR;
static size_t TR_LEN;
static FILE *TRF;
static trace_t T;
static uint8_t SEQ;

static size_t p_read(void *ctx, uint8_t *b, size_t max)
{
	tport_t *p = ctx;
	size_t k = p->in_len - p->in_at < max ? p->in_len - p->in_at : max;

	memcpy(b, p->in + p->in_at, k);
	p->in_at += k;
	return k;
}

static size_t p_write(void *ctx, const uint8_t *b, size_t n)
{
	tport_t *p = ctx;

	assert_true(p->out_len + n <= sizeof(p->out));
	memcpy(p->out + p->out_len, b, n);
	p->out_len += n;
	return n;
}

static int setup_every(uint16_t every)
{
	vs_config_t cfg;
	plant_params_t pp;
	vs_link_t io = {p_read, p_write, &P};

	vs_config_defaults(&cfg);
	cfg.link_timeout_ms = 0;
	plant_params_default(&pp);
	memset(&P, 0, sizeof(P));
	if (sim_init(&U, &cfg, &pp) != 0)
		return -1;
	vehicle_blackbox(&U.vehicle, BB, CAP, every);
	server_serve_serial(&U.srv, &SER, &io);
	TRF = open_memstream(&TR, &TR_LEN);
	trace_attach(&T, TRF, 1);
	sim_set_trace(&U, &T);
	return 0;
}

static int setup(void **state)
{
	(void)state;
	return setup_every(1);
}

static int teardown(void **state)
{
	(void)state;
	trace_close(&T);
	fclose(TRF);
	free(TR);
	TR = NULL;
	return 0;
}

static void tick(void)
{
	sim_tick(&U);
	server_poll(&U.srv, (uint32_t)U.now_us);
}

static void ex(const char *line, const char *want)
{
	char rep[CONSOLE_REPLY_MAX];

	assert_true(sim_exec(&U, line, rep, sizeof(rep)));
	assert_string_equal(rep, want);
}

/* One request in a frame; the answer's status and payload (after the
 * status byte) into resp. */
static int request(uint8_t action, uint16_t index, size_t len, uint8_t *resp, size_t *n)
{
	uint8_t p[4] = {action, (uint8_t)index, (uint8_t)(index >> 8), 0};
	size_t at = P.out_len;

	P.in_len +=
	    frame_encode(P.in + P.in_len, sizeof(P.in) - P.in_len, ++SEQ, WIRE_OP_BBOX, p, len);
	server_poll(&U.srv, (uint32_t)U.now_us);
	P.in_len = P.in_at = 0;
	assert_true(P.out_len > at + FRAME_HDR);
	assert_int_equal(P.out[at], FRAME_SYNC);
	size_t plen = wire_get_u16(P.out + at + 1);
	assert_int_equal(P.out_len, at + FRAME_OVERHEAD + plen);
	assert_int_equal(P.out[at + 3], SEQ);
	assert_int_equal(P.out[at + 4], 0x80 | WIRE_OP_BBOX);
	assert_int_equal(wire_get_u16(P.out + at + FRAME_HDR + plen),
			 cmd_crc16(0xFFFF, P.out + at + 1, FRAME_HDR - 1 + plen));
	if (resp) {
		memcpy(resp, P.out + at + FRAME_HDR + 1, plen - 1);
		*n = plen - 1;
	}
	P.out_len = 0;
	return P.out[at + FRAME_HDR];
}

static void read_page(uint16_t index, bbox_page_t *pg, bbox_sample_t *s)
{
	uint8_t resp[BBOX_RESP_MAX];
	size_t n;

	assert_int_equal(request(BBOX_READ, index, BBOX_REQ_LEN, resp, &n), WIRE_ST_OK);
	assert_true(bbox_wire_decode(resp, n, pg, s));
	assert_int_equal(pg->index, index);
}

/* The whole black box over the link, page by page. */
static uint16_t read_all(bbox_page_t *pg, bbox_sample_t *out)
{
	uint16_t got = 0;

	do {
		read_page(got, pg, out + got);
		got = (uint16_t)(got + pg->n);
	} while (pg->n == BBOX_PAGE);
	assert_int_equal(got, pg->count);
	return got;
}

/* The trace's row k (tick k; the header is row 0), split at commas. */
static unsigned split(char *line, char **f, unsigned max)
{
	unsigned n = 0;

	for (char *p = line; n < max; p++) {
		f[n++] = p;
		p = strchr(p, ',');
		if (!p)
			break;
		*p = '\0';
	}
	return n;
}

static char *trace_line(uint32_t k, char *buf, size_t cap)
{
	fflush(TRF);
	const char *p = TR;
	for (uint32_t i = 0; i < k && p; i++) {
		p = strchr(p, '\n');
		p = p ? p + 1 : NULL;
	}
	assert_non_null(p);
	const char *end = strchr(p, '\n');
	assert_non_null(end);
	size_t len = (size_t)(end - p);
	assert_true(len < cap);
	memcpy(buf, p, len);
	buf[len] = '\0';
	return buf;
}

/* Every column of the black box's row that the trace has, equal as text;
 * returns how many were compared. */
static unsigned same_as_trace(const bbox_sample_t *s, uint32_t fault)
{
	char bh[512], th[1024], br[BBOX_CSV_MAX], tr[1024];
	char *bn[40], *tn[40], *bv[40], *tv[40];
	unsigned nb, nt, same = 0;

	strcpy(bh, bbox_csv_header);
	nb = split(bh, bn, 40);
	nt = split(trace_line(0, th, sizeof(th)), tn, 40);
	bbox_csv_row(s, U.cfg.tick_hz, fault, br, sizeof(br));
	assert_int_equal(split(br, bv, 40), nb);
	assert_int_equal(split(trace_line(s->tick, tr, sizeof(tr)), tv, 40), nt);
	for (unsigned i = 0; i < nb; i++)
		for (unsigned j = 0; j < nt; j++)
			if (strcmp(bn[i], tn[j]) == 0) {
				if (strcmp(bv[i], tv[j]) != 0)
					fail_msg("tick %lu %s: black box %s, trace %s",
						 (unsigned long)s->tick, bn[i], bv[i], tv[j]);
				same++;
			}
	return same;
}

/* Moving at 500 mm/s, then the encoder of wheel 0 stops: following error
 * 204. Returns the tick that raised it. */
static uint32_t run_into_fault(void)
{
	ex("setPower true", "ok true");
	ex("setServo true", "ok true");
	ex("moveForward 5000", "ok true");
	for (int i = 0; i < 2500; i++)
		tick();
	ex("$sim drive 0 stuck", "ok drive 0 stuck");
	while (U.vehicle.alarms.n == 0) {
		tick();
		assert_true(U.ticks < 4000);
	}
	assert_int_equal(U.vehicle.alarms.a[0].code, 204);
	return U.vehicle.ticks;
}

static bbox_sample_t GOT[CAP], AGAIN[CAP];

static void black_box_equals_the_trace(void **state)
{
	bbox_page_t pg;

	(void)state;
	uint32_t f = run_into_fault();
	assert_int_equal(U.vehicle.bbox.status, BBOX_FROZEN);
	for (int i = 0; i < 300; i++)
		tick();
	assert_int_equal(read_all(&pg, GOT), CAP);
	assert_int_equal(pg.status, BBOX_FROZEN);
	assert_int_equal(pg.cap, CAP);
	assert_int_equal(pg.every, 1);
	assert_int_equal(pg.tick_hz, 1000);
	assert_int_equal(pg.trigger, f);
	assert_int_equal(pg.fault, 204);
	/* the last 2 s up to the fault's tick, every tick */
	for (uint16_t i = 0; i < CAP; i++) {
		assert_int_equal(GOT[i].tick, f - (CAP - 1u) + i);
		assert_int_equal(same_as_trace(&GOT[i], GOT[i].tick == f ? 204 : 0), 22);
	}
	/* the trigger sample shows the fault; the one before, the motion */
	assert_int_equal(GOT[CAP - 1].state, 19);
	assert_int_equal(GOT[CAP - 1].newest_alarm, 204);
	assert_int_equal(GOT[CAP - 2].state, 17);
	assert_int_equal(GOT[CAP - 2].alarms, 0);
	assert_true(GOT[CAP - 2].cmd.vx_pt > 0);

	/* frozen: later ticks and a later fault change nothing */
	ex("$sim drive 0 ok", "ok drive 0 ok");
	ex("clearAlarm", "ok true");
	vehicle_raise_fault(&U.vehicle, 210, "test");
	for (int i = 0; i < 500; i++)
		tick();
	read_all(&pg, AGAIN);
	assert_memory_equal(GOT, AGAIN, sizeof(GOT));
	assert_int_equal(pg.trigger, f);
	assert_int_equal(pg.fault, 204);
}

static void clear_empties_and_rearms(void **state)
{
	uint8_t resp[BBOX_RESP_MAX];
	size_t n;
	bbox_page_t pg;
	bbox_sample_t s[BBOX_PAGE];

	(void)state;
	uint32_t f = run_into_fault();
	assert_int_equal(request(BBOX_CLEAR, 0, BBOX_REQ_LEN, resp, &n), WIRE_ST_OK);
	assert_true(bbox_wire_decode(resp, n, &pg, s));
	assert_int_equal(pg.status, BBOX_ARMED);
	assert_int_equal(pg.count, 0);
	assert_int_equal(pg.n, 0);
	assert_int_equal(pg.trigger, 0);
	assert_int_equal(pg.fault, 0);
	/* an empty ring reads out as a header alone */
	read_page(0, &pg, s);
	assert_int_equal(pg.n, 0);
	assert_int_equal(pg.count, 0);
	assert_int_equal(n, BBOX_HDR_LEN);
	/* re-armed: it records from the next tick and freezes again */
	for (int i = 0; i < 3; i++)
		tick();
	read_page(0, &pg, s);
	assert_int_equal(pg.status, BBOX_ARMED);
	assert_int_equal(pg.count, 3);
	assert_int_equal(s[0].tick, f + 1);
	assert_int_equal(s[2].tick, f + 3);
	vehicle_raise_fault(&U.vehicle, 210, "test");
	tick();
	read_page(0, &pg, s);
	assert_int_equal(pg.status, BBOX_FROZEN);
	assert_int_equal(pg.count, 4);
	assert_int_equal(pg.trigger, f + 4);
	assert_int_equal(pg.fault, 210);
	assert_int_equal(s[3].tick, f + 4);
	/* a page in the middle */
	read_page(2, &pg, s);
	assert_int_equal(pg.n, 2);
	assert_int_equal(s[0].tick, f + 3);
	read_page(4, &pg, s);
	assert_int_equal(pg.n, 0);
}

static void bad_requests_are_refused(void **state)
{
	bbox_page_t pg;
	bbox_sample_t s[BBOX_PAGE];

	(void)state;
	for (int i = 0; i < 5; i++)
		tick();
	assert_int_equal(request(BBOX_READ, 6, BBOX_REQ_LEN, NULL, NULL), WIRE_ST_VALUE);
	assert_int_equal(request(BBOX_READ, 0xFFFF, BBOX_REQ_LEN, NULL, NULL), WIRE_ST_VALUE);
	assert_int_equal(request(2, 0, BBOX_REQ_LEN, NULL, NULL), WIRE_ST_VALUE);
	assert_int_equal(request(BBOX_CLEAR, 1, BBOX_REQ_LEN, NULL, NULL), WIRE_ST_VALUE);
	assert_int_equal(request(BBOX_READ, 0, 2, NULL, NULL), WIRE_ST_LENGTH);
	assert_int_equal(request(BBOX_READ, 0, 4, NULL, NULL), WIRE_ST_LENGTH);
	assert_int_equal(request(BBOX_READ, 0, 0, NULL, NULL), WIRE_ST_LENGTH);
	/* nothing changed: the five ticks, armed */
	read_page(0, &pg, s);
	assert_int_equal(pg.status, BBOX_ARMED);
	assert_int_equal(pg.count, 5);
	assert_int_equal(s[0].tick, 1);
	/* a reply too short or too long for its count is no page */
	uint8_t hdr[BBOX_HDR_LEN] = {BBOX_FROZEN, 1};
	assert_false(bbox_wire_decode(hdr, sizeof(hdr), &pg, s));
	assert_false(bbox_wire_decode(hdr, 3, &pg, s));
	hdr[1] = BBOX_PAGE + 1;
	assert_false(bbox_wire_decode(hdr, sizeof(hdr), &pg, s));
}

static void console_reads_and_clears(void **state)
{
	char want[CONSOLE_REPLY_MAX], row[BBOX_CSV_MAX];

	(void)state;
	ex("$bbox", "ok bbox armed samples 0 of 2000 every 1 tick_hz 1000 trigger 0 fault 0");
	ex("$bbox dump 0", "error 8 $bbox dump: 0 samples held");
	uint32_t f = run_into_fault();
	snprintf(want, sizeof(want),
		 "ok bbox frozen samples 2000 of 2000 every 1 tick_hz 1000 trigger %lu fault 204",
		 (unsigned long)f);
	ex("$bbox", want);
	snprintf(want, sizeof(want), "ok %s", bbox_csv_header);
	ex("$bbox header", want);
	bbox_csv_row(bbox_get(&U.vehicle.bbox, 1999), 1000, 204, row, sizeof(row));
	snprintf(want, sizeof(want), "ok %s", row);
	ex("$bbox dump 1999", want);
	assert_int_equal(same_as_trace(bbox_get(&U.vehicle.bbox, 1999), 204), 22);
	bbox_csv_row(bbox_get(&U.vehicle.bbox, 0), 1000, 0, row, sizeof(row));
	snprintf(want, sizeof(want), "ok %s", row);
	ex("$bbox dump 0", want);
	ex("$bbox dump 2000", "error 8 $bbox dump: 2000 samples held");
	ex("$bbox dump x", "error 8 $bbox dump: 2000 samples held");
	ex("$bbox fly", "error 8 $bbox takes nothing, clear, header or dump INDEX");
	ex("$bbox clear", "ok bbox armed");
	ex("$bbox", "ok bbox armed samples 0 of 2000 every 1 tick_hz 1000 trigger 0 fault 0");
	/* the simulator's own extras still answer after $bbox */
	ex("$wait 0", "ok wait 0");
}

/* The example of docs/protocol.md "Black box", byte for byte. */
static void documented_example(void **state)
{
	static const uint8_t req[] = {0xA5, 0x03, 0x00, 0x30, 0x7C, 0x00, 0x00, 0x00, 0xE5, 0x28};
	static const uint8_t ans[] = {0xA5, 0x15, 0x00, 0x30, 0xFC, 0x00, 0x01, 0x00, 0x00, 0x00,
				      0x00, 0x00, 0xD0, 0x07, 0x01, 0x00, 0xE8, 0x03, 0x00, 0x00,
				      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xC8, 0x41};

	(void)state;
	memcpy(P.in, req, sizeof(req));
	P.in_len = sizeof(req);
	server_poll(&U.srv, (uint32_t)U.now_us);
	assert_int_equal(P.out_len, sizeof(ans));
	assert_memory_equal(P.out, ans, sizeof(ans));
}

static int setup_every10(void **state)
{
	(void)state;
	return setup_every(10);
}

/* Decimated: every 10th tick, and the fault's tick whatever its turn. */
static void decimated_keeps_the_fault_tick(void **state)
{
	bbox_page_t pg;

	(void)state;
	uint32_t f = run_into_fault();
	uint16_t n = read_all(&pg, GOT);
	assert_int_equal(pg.every, 10);
	assert_int_equal(n, f / 10 + (f % 10 != 0));
	for (uint16_t i = 0; i + 1 < n; i++) {
		assert_int_equal(GOT[i].tick, 10u * (i + 1u));
		assert_int_equal(same_as_trace(&GOT[i], 0), 22);
	}
	assert_int_equal(GOT[n - 1].tick, f);
	assert_int_equal(pg.trigger, f);
	assert_int_equal(same_as_trace(&GOT[n - 1], 204), 22);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test(ring_wraps_and_keeps_the_newest),
	    cmocka_unit_test(ring_decimates_and_freezes_at_the_fault_tick),
	    cmocka_unit_test(ring_without_storage_records_nothing),
	    cmocka_unit_test(row_formats_as_the_trace),
	    cmocka_unit_test_setup_teardown(black_box_equals_the_trace, setup, teardown),
	    cmocka_unit_test_setup_teardown(clear_empties_and_rearms, setup, teardown),
	    cmocka_unit_test_setup_teardown(bad_requests_are_refused, setup, teardown),
	    cmocka_unit_test_setup_teardown(console_reads_and_clears, setup, teardown),
	    cmocka_unit_test_setup_teardown(documented_example, setup, teardown),
	    cmocka_unit_test_setup_teardown(decimated_keeps_the_fault_tick, setup_every10,
					    teardown),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
