/* The telemetry stream (proto/stream.h, docs/protocol.md "Telemetry
 * stream") in lockstep: the simulated unit ticked and its serial link
 * polled once per tick, the port a line of 115200 baud (11.52 bytes a
 * tick at 1 kHz) or of no speed. Exact rate, content against getPosition
 * and getState at the same tick, interleaving under a request load,
 * refusal, unsubscribe, sequence numbers and checks, the link watchdog;
 * the CAN status group and both documents against stream.def.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../host_sim/sim.h"
#include "../proto/canlink.h"
#include "../proto/cmdtab.h"
#include "../proto/server.h"
#include "../proto/stream.h"

/* ---- the port: a line of a given speed ----------------------------------- */

typedef struct {
	uint8_t in[1 << 16];
	size_t in_len, in_at;
	uint8_t out[1 << 21];
	size_t out_len;
	uint32_t credit;   /* 1/100 bytes the line may still send */
	uint32_t per_tick; /* 1/100 bytes a tick adds; 0: no limit */
} lport_t;

static lport_t P;
static sim_t U;
static server_serial_t SER;

static size_t lp_read(void *ctx, uint8_t *b, size_t max)
{
	lport_t *p = ctx;
	size_t k = p->in_len - p->in_at < max ? p->in_len - p->in_at : max;

	memcpy(b, p->in + p->in_at, k);
	p->in_at += k;
	return k;
}

static size_t lp_write(void *ctx, const uint8_t *b, size_t n)
{
	lport_t *p = ctx;

	if (p->per_tick && n > p->credit / 100u)
		n = p->credit / 100u;
	assert_true(p->out_len + n <= sizeof(p->out));
	memcpy(p->out + p->out_len, b, n);
	p->out_len += n;
	if (p->per_tick)
		p->credit -= (uint32_t)n * 100u;
	return n;
}

static int setup_wd(uint32_t link_timeout_ms)
{
	vs_config_t cfg;
	plant_params_t pp;
	vs_link_t io = {lp_read, lp_write, &P};

	vs_config_defaults(&cfg);
	cfg.link_timeout_ms = link_timeout_ms;
	plant_params_default(&pp);
	memset(&P, 0, sizeof(P));
	P.per_tick = 1152; /* 115200 baud, 10 bits a byte, 1000 ticks a second */
	if (sim_init(&U, &cfg, &pp) != 0)
		return -1;
	server_serve_serial(&U.srv, &SER, &io);
	return 0;
}

static int setup(void **state)
{
	(void)state;
	return setup_wd(0);
}

/* One period: the tick, then the link's poll, the line's time going on. */
static void tick(void)
{
	sim_tick(&U);
	if (P.per_tick && P.credit < 100000u)
		P.credit += P.per_tick;
	server_poll(&U.srv, (uint32_t)U.now_us);
}

static void host_send(uint8_t seq, uint8_t op, const void *payload, size_t len)
{
	size_t k = frame_encode(P.in + P.in_len, sizeof(P.in) - P.in_len, seq, op, payload, len);

	assert_int_not_equal(k, 0);
	P.in_len += k;
}

static void subscribe(uint8_t seq, uint16_t mask, uint16_t period_ms)
{
	uint8_t p[STREAM_REQ_LEN];

	wire_put_u16(p, mask);
	wire_put_u16(p + 2, period_ms);
	host_send(seq, WIRE_OP_STREAM, p, sizeof(p));
}

/* ---- the host's reading of the port's bytes ---------------------------- */

typedef struct {
	size_t at; /* offset of its sync byte in P.out */
	uint8_t seq, op;
	const uint8_t *payload;
	size_t len;
} rx_frame_t;

static rx_frame_t RX[40000];
static size_t NRX;

/* Every byte the unit sent is one frame with a good check (no console
 * line here); the last may still be on its way. */
static void parse_out(void)
{
	size_t at = 0;

	NRX = 0;
	while (at + FRAME_HDR < P.out_len) {
		size_t len;

		assert_int_equal(P.out[at], FRAME_SYNC);
		len = wire_get_u16(P.out + at + 1);
		if (at + FRAME_OVERHEAD + len > P.out_len)
			break;
		assert_int_equal(wire_get_u16(P.out + at + FRAME_HDR + len),
				 cmd_crc16(0xFFFF, P.out + at + 1, FRAME_HDR - 1 + len));
		assert_true(NRX < sizeof(RX) / sizeof(RX[0]));
		RX[NRX++] =
		    (rx_frame_t){at, P.out[at + 3], P.out[at + 4], P.out + at + FRAME_HDR, len};
		at += FRAME_OVERHEAD + len;
	}
}

static unsigned count_stream(void)
{
	unsigned n = 0;

	for (size_t i = 0; i < NRX; i++)
		n += RX[i].op == WIRE_OP_STREAM;
	return n;
}

/* The answer to a subscription: ok, then mask, period, frame bytes, the
 * fastest period, the tick rate. */
static void check_sub_answer(const rx_frame_t *f, uint8_t seq, uint16_t mask, uint16_t period,
			     uint16_t bytes, uint16_t min_ms)
{
	assert_int_equal(f->op, 0x80 | WIRE_OP_STREAM);
	assert_int_equal(f->seq, seq);
	assert_int_equal(f->len, 1 + STREAM_RESP_LEN);
	assert_int_equal(f->payload[0], WIRE_ST_OK);
	assert_int_equal(wire_get_u16(f->payload + 1), mask);
	assert_int_equal(wire_get_u16(f->payload + 3), period);
	assert_int_equal(wire_get_u16(f->payload + 5), bytes);
	assert_int_equal(wire_get_u16(f->payload + 7), min_ms);
	assert_int_equal(wire_get_u16(f->payload + 9), 1000);
}

/* ---- the budget rule -------------------------------------------------------- */

/* Sizes and the fastest periods at 115200 baud, as docs/protocol.md's
 * table has them. */
static void test_budget_table(void **state)
{
	(void)state;
	assert_int_equal(stream_payload_len(0), 6);
	assert_int_equal(stream_frame_bytes(1u << STREAM_G_POSE), 25);
	assert_int_equal(stream_frame_bytes(1u << STREAM_G_CMD), 19);
	assert_int_equal(stream_frame_bytes(1u << STREAM_G_MEAS), 19);
	assert_int_equal(stream_frame_bytes(1u << STREAM_G_STATE), 16);
	assert_int_equal(stream_frame_bytes(1u << STREAM_G_ALARM), 18);
	assert_int_equal(stream_frame_bytes(1u << STREAM_G_BATTERY), 15);
	assert_int_equal(stream_frame_bytes(1u << STREAM_G_IO), 17);
	assert_int_equal(stream_frame_bytes(1u << STREAM_G_QUEUE), 14);
	assert_int_equal(stream_frame_bytes(STREAM_MASK_ALL), 52);
	assert_int_equal(STREAM_FRAME_MAX, 52);
	/* 3/4 of 11,520 bytes a second: 8,640 */
	assert_int_equal(stream_min_period_ms(1u << STREAM_G_POSE, 115200), 3);
	assert_int_equal(stream_min_period_ms(0x09, 115200), 4); /* pose + state: 28 bytes */
	assert_int_equal(stream_min_period_ms(STREAM_MASK_ALL, 115200), 7);
	assert_int_equal(stream_min_period_ms(STREAM_MASK_ALL, 9600), 73);
	assert_int_equal(stream_min_period_ms(STREAM_MASK_ALL, 1000000), 1);
	assert_false(stream_fits(STREAM_MASK_ALL, 6, 115200));
	assert_true(stream_fits(STREAM_MASK_ALL, 7, 115200));
	assert_int_equal(stream_min_period_ms(0, 115200), 0);
}

/* ---- rate, sequence numbers, checks ---------------------------------------- */

/* Pose and state every 10 ms: exactly 100 frames in 1,000 ticks, the
 * first at the end of the tick after the subscription, then every 10th;
 * sequence numbers 0, 1, ... */
static void test_rate_exact(void **state)
{
	uint32_t t0;

	(void)state;
	tick();
	subscribe(0x31, 0x09, 10);
	t0 = U.vehicle.ticks;
	server_poll(&U.srv, (uint32_t)U.now_us); /* the request, between ticks */
	for (int i = 0; i < 1000; i++)
		tick();
	parse_out();
	assert_int_equal(NRX, 101);
	check_sub_answer(&RX[0], 0x31, 0x09, 10, 28, 4);
	assert_int_equal(count_stream(), 100);
	for (unsigned k = 0; k < 100; k++) {
		const rx_frame_t *f = &RX[1 + k];
		uint16_t mask;
		uint32_t t;
		stream_sample_t s;

		assert_int_equal(f->op, WIRE_OP_STREAM);
		assert_int_equal(f->seq, (uint8_t)k);
		assert_int_equal(f->len, 21);
		assert_int_equal(stream_decode(f->payload, f->len, &mask, &t, &s), 0);
		assert_int_equal(mask, 0x09);
		assert_int_equal(t, t0 + 1 + 10 * k);
	}
	assert_int_equal(server_serial_stream(&U.srv)->sent, 100);
	assert_int_equal(server_serial_stream(&U.srv)->skipped, 0);
}

/* Every group at 50 ms while the unit moves: each frame holds what
 * getPosition, getState, getActiveAlarm and the tick's speeds give at the
 * tick it was sent after. */
static void test_content_exact(void **state)
{
	char r[CONSOLE_REPLY_MAX];
	stream_sample_t want[200];
	uint32_t want_tick[200];
	unsigned nw = 0;

	(void)state;
	assert_true(sim_exec(&U, "setPower true", r, sizeof(r)));
	assert_true(sim_exec(&U, "setServo true", r, sizeof(r)));
	assert_true(sim_exec(&U, "moveForward 300", r, sizeof(r)));
	subscribe(1, STREAM_MASK_ALL, 50);
	server_poll(&U.srv, (uint32_t)U.now_us);
	for (int i = 0; i < 4000; i++) {
		size_t before = P.out_len + SER.q_len;

		sim_tick(&U);
		P.credit += P.per_tick;
		server_poll(&U.srv, (uint32_t)U.now_us);
		if (P.out_len + SER.q_len > before) {
			/* a stream frame went out this poll: the unit as it is now */
			vs_position_t pos;
			int16_t st = 0, na = 0;
			char msg[VS_STATE_MSG_MAX];
			vs_alarm_t al;
			uint16_t got = 0;

			assert_true(nw < 200);
			stream_read(&U.vehicle, &want[nw]);
			vs_getPosition(&U.vehicle, &pos);
			vs_getState(&U.vehicle, &st, msg);
			vs_getActiveAlarm(&U.vehicle, 1, &na, &al, &got);
			assert_int_equal(want[nw].x_dmm, lround(pos.x * 10));
			assert_int_equal(want[nw].y_dmm, lround(pos.y * 10));
			assert_int_equal(want[nw].theta_mdeg, lround(pos.theta * 1000));
			assert_int_equal(want[nw].state, st);
			assert_int_equal(want[nw].alarms, na);
			want_tick[nw++] = U.vehicle.ticks;
		}
	}
	parse_out();
	assert_int_equal(count_stream(), 80);
	assert_int_equal(nw, 80);
	unsigned busy = 0, moved = 0;
	for (unsigned k = 0; k < nw; k++) {
		const rx_frame_t *f = &RX[1 + k];
		stream_sample_t s;
		uint16_t mask;
		uint32_t t;

		memset(&s, 0, sizeof(s));
		assert_int_equal(f->len, STREAM_PAYLOAD_MAX);
		assert_int_equal(stream_decode(f->payload, f->len, &mask, &t, &s), 0);
		assert_int_equal(t, want_tick[k]);
		assert_memory_equal(&s, &want[k], sizeof(s));
		busy += s.state == 0x11;
		moved += s.vx_mm_s > 0 && s.mvx_mm_s > 0;
	}
	/* the run is seen: busy and moving forward (commanded and measured),
	 * then Ready */
	assert_int_equal(busy, 32);
	assert_int_equal(moved, 29);
	const rx_frame_t *last = &RX[nw];
	stream_sample_t s;
	uint16_t mask;
	uint32_t t;
	assert_int_equal(stream_decode(last->payload, last->len, &mask, &t, &s), 0);
	assert_int_equal(s.state, 0x10);
	assert_int_equal(s.x_dmm, lround(U.vehicle.odom.x_mm / 4294967296.0 * 10));
	assert_int_equal(s.queue, 0);
}

/* ---- requests under the stream ----------------------------------------------- */

/* Every group at the fastest period (7 ms) on a 115200 line, and the host
 * sending getState as fast as answers come (one outstanding) for 3 s:
 * every request is answered, in order; no answer has more than one stream
 * frame ahead of it that was not yet sent when its request was read; the
 * stream keeps its rate, none skipped (the requests stay in the reserve). */
static void test_interleave_under_load(void **state)
{
	enum { TICKS = 3000 };
	static size_t read_at[4096]; /* bytes on the line when request k was read */
	unsigned sent = 0, answered = 0;

	(void)state;
	subscribe(0xF0, STREAM_MASK_ALL, 7);
	for (int i = 0; i < TICKS; i++) {
		/* the next request once the last was answered */
		if (sent == answered && sent < 4096) {
			host_send((uint8_t)sent, CMD_OP_getState, NULL, 0);
			/* the line's position when this tick's poll reads it */
			read_at[sent++] = P.out_len;
		}
		tick();
		assert_int_equal(P.in_at, P.in_len);
		/* answers seen so far */
		answered = 0;
		parse_out();
		for (size_t k = 1; k < NRX; k++)
			answered += RX[k].op == (0x80 | CMD_OP_getState);
	}
	/* the line drains what is on its way, no tick more */
	P.per_tick = 0;
	server_poll(&U.srv, (uint32_t)U.now_us);
	parse_out();
	unsigned nreq = 0, nstream = 0, worst = 0;
	for (size_t k = 1; k < NRX; k++) {
		if (RX[k].op == WIRE_OP_STREAM) {
			assert_int_equal(RX[k].seq, (uint8_t)nstream);
			nstream++;
			continue;
		}
		assert_int_equal(RX[k].op, 0x80 | CMD_OP_getState);
		assert_int_equal(RX[k].seq, (uint8_t)nreq);
		assert_int_equal(RX[k].payload[0], WIRE_ST_OK);
		/* stream frames not wholly sent when the request was read, ahead
		 * of its answer */
		unsigned between = 0;
		for (size_t j = 1; j < k; j++)
			between += RX[j].op == WIRE_OP_STREAM && RX[j].at + 52 > read_at[nreq];
		if (between > worst)
			worst = between;
		nreq++;
	}
	assert_int_equal(nreq, sent);
	assert_int_equal(nreq, 584);
	assert_int_equal(worst, 1);
	/* 3,000 ticks from the first frame at tick 1: 429 frames */
	assert_int_equal(nstream, 429);
	assert_int_equal(server_serial_stream(&U.srv)->skipped, 0);
	assert_int_equal(U.srv.serial.fs.st.naks, 0);
}

/* A line that stops taking bytes: due frames find the last one unsent and
 * are skipped, counted, their sequence numbers passed over; requests sent
 * meanwhile are all answered once the line moves again. */
static void test_line_behind_skips(void **state)
{
	(void)state;
	subscribe(0, 1u << STREAM_G_POSE, 10);
	for (int i = 0; i < 20; i++)
		tick(); /* frames 0, 1 */
	P.per_tick = 1; /* the line all but stops: 0.01 byte a tick */
	P.credit = 0;
	for (int i = 0; i < 5; i++)
		host_send((uint8_t)(1 + i), CMD_OP_getPosition, NULL, 0);
	for (int i = 0; i < 100; i++)
		tick();
	P.per_tick = 1152;
	for (int i = 0; i < 200; i++)
		tick();
	parse_out();
	const stream_sub_t *ss = server_serial_stream(&U.srv);
	/* 32 slots in 320 ticks: the ones while the line stood still skipped */
	assert_int_equal(ss->sent + ss->skipped, 32);
	assert_true(ss->skipped >= 8);
	unsigned answers = 0, last_seq = 0, frames = 0;
	bool gap = false;
	for (size_t k = 1; k < NRX; k++) {
		if (RX[k].op == WIRE_OP_STREAM) {
			if (frames && RX[k].seq != (uint8_t)(last_seq + 1))
				gap = true;
			last_seq = RX[k].seq;
			frames++;
		} else {
			assert_int_equal(RX[k].op, 0x80 | CMD_OP_getPosition);
			assert_int_equal(RX[k].seq, 1 + answers);
			answers++;
		}
	}
	assert_int_equal(frames, ss->sent);
	assert_true(gap);
	assert_int_equal(last_seq, 31);
	assert_int_equal(answers, 5);
}

/* ---- subscribe, refuse, unsubscribe ---------------------------------------- */

/* Every group at 6 ms does not fit 115200 baud: NAK rate (8), nothing
 * streams; 7 ms does. A bad mask or period: NAK value; a payload of the
 * wrong size: NAK length. */
static void test_refuse_and_unsubscribe(void **state)
{
	(void)state;
	subscribe(0x10, STREAM_MASK_ALL, 6);
	subscribe(0x11, 0x100, 10); /* no group 8 */
	subscribe(0x12, 0x01, 0);   /* no period */
	host_send(0x13, WIRE_OP_STREAM, "\x01\x00\x0A", 3);
	for (int i = 0; i < 100; i++)
		tick();
	parse_out();
	assert_int_equal(NRX, 4);
	/* A5 01 00 10 FD 08 crc */
	static const uint8_t nak[] = {0xA5, 0x01, 0x00, 0x10, 0xFD, 0x08};
	assert_memory_equal(P.out, nak, sizeof(nak));
	assert_int_equal(RX[1].payload[0], WIRE_ST_VALUE);
	assert_int_equal(RX[2].payload[0], WIRE_ST_VALUE);
	assert_int_equal(RX[3].payload[0], WIRE_ST_LENGTH);
	assert_int_equal(RX[3].seq, 0x13);
	assert_int_equal(server_serial_stream(&U.srv)->mask, 0);
	assert_string_equal(wire_status_name(WIRE_ST_RATE), "rate");

	subscribe(0x14, STREAM_MASK_ALL, 7);
	for (int i = 0; i < 70; i++)
		tick();
	subscribe(0x15, 0, 0);
	for (int i = 0; i < 100; i++)
		tick();
	parse_out();
	check_sub_answer(&RX[4], 0x14, STREAM_MASK_ALL, 7, 52, 7);
	assert_int_equal(count_stream(), 10);
	check_sub_answer(&RX[NRX - 1], 0x15, 0, 0, 0, 0);
	assert_int_equal(server_serial_stream(&U.srv)->mask, 0);

	/* a retransmission is answered from the cache, not run again: the
	 * stream does not restart */
	subscribe(0x16, 1u << STREAM_G_QUEUE, 5);
	for (int i = 0; i < 12; i++)
		tick();
	subscribe(0x16, 1u << STREAM_G_QUEUE, 5);
	for (int i = 0; i < 10; i++)
		tick();
	parse_out();
	unsigned k = 0;
	for (size_t i = 0; i < NRX; i++)
		if (RX[i].op == WIRE_OP_STREAM && RX[i].len == 7)
			assert_int_equal(RX[i].seq, k++);
	assert_int_equal(k, 5);
	assert_int_equal(U.srv.serial.fs.st.duplicates, 1);
}

static void host_line(const char *line)
{
	size_t n = strlen(line);

	memcpy(P.in + P.in_len, line, n);
	P.in_len += n;
}

/* The console's text form: "$stream pose,state 100" on the port (read
 * after tick 1), a line "~stream SEQ TICK name value ..." at the end of
 * tick 2 and every 100 ticks after, between whole replies;
 * "$stream" reads it, "$stream off" ends it; a rate the line cannot carry
 * (as text: 119 bytes a line, 14 ms at the fastest) is refused. */
static void test_text_form(void **state)
{
	static const char want[] =
	    "error 8 $stream: the line carries these every 14 ms at the fastest\n"
	    "error 8 $stream GROUPS PERIOD_MS: groups all, a mask or "
	    "pose,cmd,meas,state,alarm,battery,io,queue\n"
	    "error 8 $stream GROUPS PERIOD_MS: groups all, a mask or "
	    "pose,cmd,meas,state,alarm,battery,io,queue\n"
	    "ok stream mask 0x09 period 100 text\n"
	    "~stream 0 2 x_dmm 0 y_dmm 0 theta_mdeg 0 state 25 alarms 0\n"
	    "ok true 25 \"Unpowered\"\n"
	    "ok stream mask 0x09 period 100 sent 1 skipped 0 text\n"
	    "~stream 1 102 x_dmm 0 y_dmm 0 theta_mdeg 0 state 25 alarms 0\n"
	    "~stream 2 202 x_dmm 0 y_dmm 0 theta_mdeg 0 state 25 alarms 0\n"
	    "ok stream off\n"
	    "ok stream mask 0x00 period 0 sent 0 skipped 0\n";
	stream_sample_t s;

	(void)state;
	assert_int_equal(stream_text_bytes(0x09), 119);
	assert_true(stream_text_bytes(STREAM_MASK_ALL) < STREAM_TEXT_MAX);
	host_line("$stream pose,state 13\n$stream pose,nothing 100\n$stream 0x1FF 100\n");
	host_line("$stream pose,state 100\n");
	tick();
	for (int i = 0; i < 99; i++)
		tick();
	stream_read(&U.vehicle, &s);
	host_line("getState\n$stream\n");
	for (int i = 0; i < 110; i++)
		tick();
	host_line("$stream off\n$stream\n");
	for (int i = 0; i < 300; i++)
		tick();
	P.out[P.out_len] = '\0';
	assert_string_equal((char *)P.out, want);
	assert_int_equal(s.state, 25);
}

/* The stream keeps nothing alive: a moving unit whose host only listens
 * stops at the link watchdog's timeout (warning 153) as if there were no
 * stream; the stream shows it. */
static void test_watchdog_not_fed(void **state)
{
	char r[CONSOLE_REPLY_MAX];
	uint8_t p[8];

	(void)state;
	assert_int_equal(setup_wd(1000), 0);
	assert_true(sim_exec(&U, "setPower true", r, sizeof(r)));
	assert_true(sim_exec(&U, "setServo true", r, sizeof(r)));
	double d = 5000;
	memcpy(p, &d, 8);
	host_send(1, CMD_OP_moveForward, p, 8);
	subscribe(2, (1u << STREAM_G_STATE) | (1u << STREAM_G_ALARM), 100);
	for (int i = 0; i < 2000; i++)
		tick();
	parse_out();
	assert_int_equal(RX[0].op, 0x80 | CMD_OP_moveForward);
	assert_int_equal(count_stream(), 20);
	/* the frame after tick 1,001: warning 153 newest */
	stream_sample_t s;
	uint16_t mask;
	uint32_t t;
	unsigned k = 0;
	for (size_t i = 0; i < NRX; i++) {
		if (RX[i].op != WIRE_OP_STREAM)
			continue;
		memset(&s, 0, sizeof(s));
		assert_int_equal(stream_decode(RX[i].payload, RX[i].len, &mask, &t, &s), 0);
		if (k < 10) {
			assert_int_equal(s.state, 0x11);
			assert_int_equal(s.alarm_code, 0);
		} else {
			assert_int_equal(s.alarm_code, 153);
			assert_int_equal(s.alarm_type, 2);
		}
		k++;
	}
	int16_t na = 0;
	vs_alarm_t al;
	uint16_t got = 0;
	vs_getActiveAlarm(&U.vehicle, 1, &na, &al, &got);
	assert_int_equal(al.code, 153);
}

/* ---- one definition, two encodings, two documents ------------------------- */

/* Each row's CAN place holds its value: no two rows share a byte, every
 * byte of A..E is one row's (or A's counter). */
static void test_can_layout_from_table(void **state)
{
	unsigned owner[STREAM_CAN_FRAMES][8];

	(void)state;
	memset(owner, 0xFF, sizeof(owner));
	owner[0][STREAM_CAN_COUNTER_AT] = 1000;
	for (unsigned i = 0; i < stream_field_count; i++) {
		const stream_field_t *f = &stream_fields[i];

		assert_true(f->can_frame < STREAM_CAN_FRAMES);
		for (size_t b = 0; b < stream_type_size(f->type); b++) {
			assert_true(f->can_offset + b < 8);
			assert_int_equal(owner[f->can_frame][f->can_offset + b], 0xFFFFFFFFu);
			owner[f->can_frame][f->can_offset + b] = i;
		}
	}
	for (unsigned fr = 0; fr < STREAM_CAN_FRAMES; fr++)
		for (unsigned b = 0; b < 8; b++)
			assert_int_not_equal(owner[fr][b], 0xFFFFFFFFu);
	/* a sample through both encodings comes back the same */
	stream_sample_t s, c, w;
	memset(&s, 0, sizeof(s));
	for (unsigned i = 0; i < stream_field_count; i++)
		stream_set(&s, &stream_fields[i], -3 - (int64_t)i * 1000);
	memset(&c, 0, sizeof(c));
	memset(&w, 0, sizeof(w));
	for (unsigned fr = 0; fr < STREAM_CAN_FRAMES; fr++) {
		canlink_frame_t f;
		canlink_status_frame(&s, 5, fr, &f);
		assert_int_equal(canlink_status_decode(&f, 5, &c), (int)fr);
	}
	uint8_t buf[STREAM_PAYLOAD_MAX];
	uint16_t mask;
	uint32_t t;
	size_t n = stream_encode(&s, STREAM_MASK_ALL, 77, buf, sizeof(buf));
	assert_int_equal(n, STREAM_PAYLOAD_MAX);
	assert_int_equal(stream_decode(buf, n, &mask, &t, &w), 0);
	assert_int_equal(t, 77);
	for (unsigned i = 0; i < stream_field_count; i++) {
		assert_true(stream_get(&c, &stream_fields[i]) == stream_get(&s, &stream_fields[i]));
		assert_true(stream_get(&w, &stream_fields[i]) == stream_get(&s, &stream_fields[i]));
	}
	/* a payload whose length does not match its mask, or an unknown group */
	assert_int_equal(stream_decode(buf, n - 1, &mask, &t, &w), -1);
	buf[1] = 1;
	assert_int_equal(stream_decode(buf, n, &mask, &t, &w), -1);
	assert_int_equal(stream_decode(buf, 3, &mask, &t, &w), -1);
	assert_int_equal(stream_encode(&s, STREAM_MASK_ALL, 77, buf, 10), 0);
}

static const char *type_name(unsigned t)
{
	static const char *const n[] = {"i16", "i32", "u8", "u16", "u32"};
	return n[t];
}

static char *read_doc(const char *path)
{
	FILE *f = fopen(path, "r");
	static char buf[2][1 << 18];
	static int which;
	char *b = buf[which++ & 1];
	size_t n;

	assert_non_null(f);
	n = fread(b, 1, sizeof(buf[0]) - 1, f);
	fclose(f);
	b[n] = '\0';
	return b;
}

/* The table's units, which only the docs carry. */
static const char *const units[] = {
#define STREAM_FIELD(name, group, type, frame, off, unit, what) unit,
#include "../proto/stream.def"
#undef STREAM_FIELD
};

/* docs/protocol.md's value table: one row per field, in the table's order:
 * | `name` | group | type | unit | ... ; docs/can.md's status table: a row
 * per field at its frame and bytes. */
static void test_docs_match_table(void **state)
{
	const char *proto = read_doc("docs/protocol.md");
	const char *can = read_doc("docs/can.md");
	const char *at = strstr(proto, "## Telemetry stream");

	(void)state;
	assert_non_null(at);
	for (unsigned i = 0; i < stream_field_count; i++) {
		const stream_field_t *f = &stream_fields[i];
		char row[160];
		const char *unit = units[i][0] ? units[i] : "-";

		snprintf(row, sizeof(row), "| `%s` | %s | %s | %s |", f->name,
			 stream_group_names[f->group], type_name(f->type), unit);
		if (!strstr(at, row))
			fail_msg("docs/protocol.md lacks the row \"%s\"", row);
		size_t k = stream_type_size(f->type);
		if (k == 1)
			snprintf(row, sizeof(row), "| %c | %u | `%s` |", 'A' + f->can_frame,
				 f->can_offset, f->name);
		else
			snprintf(row, sizeof(row), "| %c | %u-%u | `%s` |", 'A' + f->can_frame,
				 f->can_offset, (unsigned)(f->can_offset + k - 1), f->name);
		if (!strstr(can, row))
			fail_msg("docs/can.md lacks the row \"%s\"", row);
	}
	/* the budget table: one row per group and one for all */
	for (unsigned g = 0; g <= STREAM_GROUPS; g++) {
		char row[160];
		uint16_t m = g < STREAM_GROUPS ? (uint16_t)(1u << g) : STREAM_MASK_ALL;
		uint32_t ms = stream_min_period_ms(m, 115200);

		snprintf(row, sizeof(row), "| %s | 0x%02X | %u | %u | %u |",
			 g < STREAM_GROUPS ? stream_group_names[g] : "all", m,
			 (unsigned)stream_frame_bytes(m), (unsigned)ms, (unsigned)(1000 / ms));
		if (!strstr(proto, row))
			fail_msg("docs/protocol.md lacks the budget row \"%s\"", row);
	}
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test(test_budget_table),
	    cmocka_unit_test_setup(test_rate_exact, setup),
	    cmocka_unit_test_setup(test_content_exact, setup),
	    cmocka_unit_test_setup(test_interleave_under_load, setup),
	    cmocka_unit_test_setup(test_line_behind_skips, setup),
	    cmocka_unit_test_setup(test_refuse_and_unsubscribe, setup),
	    cmocka_unit_test_setup(test_text_form, setup),
	    cmocka_unit_test(test_watchdog_not_fed),
	    cmocka_unit_test(test_can_layout_from_table),
	    cmocka_unit_test(test_docs_match_table),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
