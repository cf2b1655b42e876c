/* The telemetry stream on a serial link, for every server of one (see
 * server.h): the subscription frame (WIRE_OP_STREAM), the console's
 * "$stream" and the choice of the frame or line due. The host's queued
 * service (server_serial.c) and the board's main (hal/cortexm/board_main.c)
 * each put what server_stream_next gives into their own output.
 */
#include "server.h"

#include "fmt.h"
#include "numparse.h"

/* A subscription request (frame_stream_fn): at the tick count now. */
static size_t stream_req(void *ctx, const uint8_t *p, size_t len, uint8_t *resp, int *st)
{
	vs_server_t *s = ctx;

	return stream_subscribe(s->stream, s->v->cfg.tick_hz, s->v->ticks, p, len, resp, st);
}

size_t server_stream_next(vs_server_t *s, bool busy, size_t room, uint8_t *out, size_t cap)
{
	stream_sub_t *ss = s->stream;
	uint8_t payload[STREAM_PAYLOAD_MAX];
	stream_sample_t smp;
	uint8_t seq;
	size_t n;

	if (!ss || !stream_due(ss, s->v->ticks))
		return 0;
	seq = ss->seq++;
	n = ss->text ? stream_text_bytes(ss->mask) : stream_frame_bytes(ss->mask);
	if (busy || room < n || cap <= n) { /* cap: a text line's NUL too */
		ss->skipped++;
		return 0;
	}
	stream_read(s->v, &smp);
	if (ss->text) {
		n = stream_text(&smp, ss->mask, seq, s->v->ticks, (char *)out, cap);
	} else {
		n = stream_encode(&smp, ss->mask, s->v->ticks, payload, sizeof(payload));
		n = frame_encode(out, cap, seq, WIRE_OP_STREAM, payload, n);
	}
	ss->sent++;
	return n;
}

/* "$stream": the subscription and its counters; "$stream off"; "$stream
 * GROUPS PERIOD_MS": the text form on this port (GROUPS "all", a mask, or
 * names joined by commas: pose,state). */
static bool parse_groups(const char *a, uint16_t *mask)
{
	int64_t v;

	if (np_streq_nocase(a, "all")) {
		*mask = STREAM_MASK_ALL;
		return true;
	}
	if (np_parse_int(a, 1, STREAM_MASK_ALL, &v) == NP_OK) {
		*mask = (uint16_t)v;
		return true;
	}
	*mask = 0;
	while (*a) {
		char name[16];
		size_t n = 0;
		unsigned g;

		while (*a && *a != ',' && n + 1 < sizeof(name))
			name[n++] = *a++;
		name[n] = '\0';
		for (g = 0; g < STREAM_GROUPS && !np_streq_nocase(name, stream_group_names[g]); g++)
			;
		if (g == STREAM_GROUPS || (*a && *a != ','))
			return false;
		*mask = (uint16_t)(*mask | (1u << g));
		if (*a == ',')
			a++;
	}
	return *mask != 0;
}

/* "$stream GROUPS PERIOD_MS": true when in force (the reply is the
 * status's), else the error in reply. */
static bool stream_text_sub(vs_server_t *s, char **argv, char *reply, size_t cap)
{
	uint16_t mask;
	int64_t period;
	int st;

	if (!parse_groups(argv[1], &mask) ||
	    np_parse_int(argv[2], 1, UINT16_MAX, &period) != NP_OK) {
		fmt_print(reply, cap,
			  "error %d $stream GROUPS PERIOD_MS: groups all, a mask or "
			  "pose,cmd,meas,state,alarm,battery,io,queue",
			  CONSOLE_E_EXTRA);
		return false;
	}
	st = stream_start(s->stream, s->v->cfg.tick_hz, s->v->ticks, mask, (uint16_t)period, true);
	if (st == WIRE_ST_RATE)
		fmt_print(reply, cap,
			  "error %d $stream: the line carries these every %lu ms at the fastest",
			  CONSOLE_E_EXTRA,
			  (unsigned long)stream_min_period_bytes(stream_text_bytes(mask),
								 s->stream->baud));
	else if (st != WIRE_ST_OK)
		fmt_print(reply, cap, "error %d $stream: a period of whole ticks", CONSOLE_E_EXTRA);
	return st == WIRE_ST_OK;
}

static bool stream_extra(void *ctx, int argc, char **argv, char *reply, size_t cap)
{
	vs_server_t *s = ctx;
	const stream_sub_t *ss = s->stream;
	size_t n;

	if (argc < 1 || !np_streq_nocase(argv[0], "$stream"))
		return s->stream_extra ? s->stream_extra(s->stream_xctx, argc, argv, reply, cap)
				       : false;
	if (argc == 2 && np_streq_nocase(argv[1], "off")) {
		stream_start(s->stream, s->v->cfg.tick_hz, s->v->ticks, 0, 0, false);
		fmt_print(reply, cap, "ok stream off");
		return true;
	}
	if (argc != 1 && argc != 3) {
		fmt_print(reply, cap, "error %d $stream takes 0, 1 (off) or 2 arguments, got %d",
			  CONSOLE_E_ARITY, argc - 1);
		return true;
	}
	if (argc == 3 && !stream_text_sub(s, argv, reply, cap))
		return true;
	/* the status; after a text subscription without its counters (the
	 * reply's few dozen bytes fit any console reply) */
	n = fmt_print(reply, cap, "ok stream mask 0x%02X period %u", (unsigned)ss->mask,
		      (unsigned)ss->period_ms);
	if (argc == 1)
		n += fmt_print(reply + n, cap - n, " sent %lu skipped %lu", (unsigned long)ss->sent,
			       (unsigned long)ss->skipped);
	if (ss->text)
		fmt_print(reply + n, cap - n, " text");
	return true;
}

void server_stream_init(vs_server_t *s, stream_sub_t *sub, uint32_t baud)
{
	stream_sub_init(sub, baud);
	s->stream = sub;
	frame_srv_set_stream(&s->serial.fs, stream_req, s);
	s->stream_extra = s->con.extra;
	s->stream_xctx = s->con.xctx;
	console_set_extra(&s->con, stream_extra, s);
}
