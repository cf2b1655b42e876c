/* The unit's frame server: frames in, operations run through wire_dispatch,
 * answers out (frame.h). */
#include "frame.h"

#include <string.h>

#include "bbox_wire.h"
#include "dispatch.h"

static void srv_nak(frame_srv_t *s, uint8_t seq, uint8_t op, int status)
{
	uint8_t out[FRAME_OVERHEAD + 1];
	size_t n = frame_encode_response(out, sizeof(out), seq, op, (uint8_t)status, NULL, 0);

	s->st.naks++;
	if (s->write && n)
		s->write(s->wctx, out, n);
}

/* A console line in a frame: NAK value unless it is one line of 1..64
 * bytes without NUL; the reply's bytes are the answer. */
static size_t run_line(frame_srv_t *s, const frame_t *f, uint8_t *resp, size_t cap, int *st)
{
	char line[FRAME_REQ_PAYLOAD_MAX + 1];
	if (!s->line) {
		*st = WIRE_ST_OPCODE;
		return 0;
	}
	if (f->len == 0 || f->len > FRAME_REQ_PAYLOAD_MAX) {
		*st = WIRE_ST_VALUE;
		return 0;
	}
	for (size_t i = 0; i < f->len; i++) {
		uint8_t b = f->payload[i];
		if (b == 0 || b == '\r' || b == '\n') {
			*st = WIRE_ST_VALUE;
			return 0;
		}
		line[i] = (char)b;
	}
	line[f->len] = '\0';
	if (!s->line(s->lctx, line, (char *)resp, cap))
		return 0;
	return strnlen((const char *)resp, cap);
}

static void srv_frame(void *ctx, const frame_t *f)
{
	frame_srv_t *s = ctx;
	uint8_t resp[WIRE_RESP_MAX];
	size_t n;
	int st = WIRE_ST_OK;

	if (f->status != WIRE_ST_OK) {
		/* The opcode of a damaged frame cannot be trusted: answer with 0.
		 * The seq is the one received, 0 when the frame ended before it. */
		srv_nak(s, f->seq, 0, f->status);
		return;
	}
	if (f->op & FRAME_RESP_FLAG) {
		/* A response travelling the wrong way (echo, loopback): not a
		 * request, and answering it could ping-pong. */
		s->st.naks++;
		return;
	}
	if (s->have_last && f->seq == s->last_seq && f->op == s->last_op && f->crc == s->last_crc) {
		s->st.duplicates++;
		vehicle_link_heard(s->v, VS_LINK_FRAMES);
		if (s->write)
			s->write(s->wctx, s->last_resp, s->last_len);
		return;
	}
	if (f->op == WIRE_OP_CONSOLE)
		n = run_line(s, f, resp, sizeof(resp), &st);
	else if (f->op == WIRE_OP_STREAM && s->stream)
		n = s->stream(s->sctx, f->payload, f->len, resp, &st);
	else if (f->op == WIRE_OP_BBOX)
		n = bbox_wire_serve(s->v, f->payload, f->len, resp, &st);
	else
		n = wire_dispatch(s->v, f->op, f->payload, f->len, resp, sizeof(resp), &st);
	if (st != WIRE_ST_OK) {
		srv_nak(s, f->seq, f->op, st);
		return;
	}
	s->st.executed++;
	vehicle_link_heard(s->v, VS_LINK_FRAMES);
	s->last_len = frame_encode_response(s->last_resp, sizeof(s->last_resp), f->seq, f->op,
					    WIRE_ST_OK, resp, n);
	s->have_last = s->last_len > 0;
	s->last_seq = f->seq;
	s->last_op = f->op;
	s->last_crc = f->crc;
	if (s->write && s->last_len)
		s->write(s->wctx, s->last_resp, s->last_len);
}

void frame_srv_init(frame_srv_t *s, vehicle_t *v, frame_write_fn write, void *wctx,
		    frame_other_fn on_other, void *octx)
{
	memset(s, 0, sizeof(*s));
	s->v = v;
	s->write = write;
	s->wctx = wctx;
	frame_rx_init(&s->rx, s->rxbuf, FRAME_REQ_PAYLOAD_MAX, srv_frame, NULL, s);
	frame_rx_set_other(&s->rx, on_other, octx);
}
