/* The serial link as server_poll serves it on a host: a budget per poll and
 * flow control (see server.h).
 *
 * The console and the frame server write every answer whole into a queue
 * (the link's port writes here), which drains into the platform's port as
 * fast as the port takes it. Received bytes are taken in steps, each only
 * while at most SERVER_SERIAL_BACKLOG bytes of answers wait: the queue then
 * has room for the most a step can cause, so no answer is ever cut or
 * dropped, and a host that does not read finds its requests waiting in the
 * port's buffer, not executed.
 */
#include "server.h"

#include <string.h>

_Static_assert(CONSOLE_REPLY_MAX <= FRAME_RESP_MAX, "a console reply fits a step's room");

static server_serial_t *ss_of(const vs_server_t *s)
{
	return s->poll_serial ? s->serial.port.io.ctx : NULL;
}

static void q_copy(server_serial_t *ss, const uint8_t *b, size_t n)
{
	size_t at = (ss->q_at + ss->q_len) % SERVER_SERIAL_TXQ;
	size_t first = SERVER_SERIAL_TXQ - at < n ? SERVER_SERIAL_TXQ - at : n;

	memcpy(ss->q + at, b, first);
	memcpy(ss->q, b + first, n - first);
	ss->q_len += n;
	ss->q_put_total += (uint32_t)n;
	if (ss->q_len > ss->st.max_queued)
		ss->st.max_queued = (uint32_t)ss->q_len;
}

/* The port's write: the answer goes into the queue whole. Steps are taken
 * only while the queue has room for their worst, so nothing is refused
 * here (the port would count it as txdrop). */
static size_t q_put(void *ctx, const uint8_t *b, size_t n)
{
	server_serial_t *ss = ctx;

	if (n > SERVER_SERIAL_TXQ - ss->q_len)
		return 0;
	q_copy(ss, b, n);
	ss->answers++;
	ss->ans_bytes += (uint32_t)n;
	return n;
}

/* As much of the queue as the port takes now. */
static void q_flush(server_serial_t *ss)
{
	while (ss->q_len && ss->io.write) {
		size_t first = SERVER_SERIAL_TXQ - ss->q_at;
		size_t k = ss->io.write(ss->io.ctx, ss->q + ss->q_at,
					first < ss->q_len ? first : ss->q_len);

		if (!k)
			break;
		ss->q_at = (ss->q_at + k) % SERVER_SERIAL_TXQ;
		ss->q_len -= k;
		ss->q_sent_total += (uint32_t)k;
	}
}

/* The next step's bytes. With a frame in progress, one byte: it may
 * complete the frame (SERVER_SERIAL_STEP_MAX). Else the bytes up to the
 * first line ending (CR LF as one) or sync byte: only that byte can cause
 * an answer (a line's reply; a sync byte only starts a frame). */
static size_t step_len(const link_t *l, const uint8_t *p, size_t n)
{
	if (frame_rx_busy(&l->fs.rx))
		return 1;
	for (size_t i = 0; i < n; i++) {
		if (p[i] == '\r' && i + 1 < n && p[i + 1] == '\n')
			return i + 2;
		if (p[i] == '\r' || p[i] == '\n' || p[i] == FRAME_SYNC)
			return i + 1;
	}
	return n;
}

static bool room(server_serial_t *ss)
{
	if (ss->q_len > SERVER_SERIAL_BACKLOG)
		q_flush(ss);
	return ss->q_len <= SERVER_SERIAL_BACKLOG;
}

/* A stream frame when one is due, ahead of this poll's answers, unless the
 * last one has not left yet (the line is behind: the slot is skipped, its
 * sequence number too, and counted), so that no answer ever waits behind
 * more than one stream frame. */
static void stream_emit(vs_server_t *s, server_serial_t *ss)
{
	uint8_t out[STREAM_TEXT_MAX];
	/* The last frame is unsent while its end lies within the queued bytes
	 * (stream_end - sent in 1..q_len): a test that holds across the
	 * counters' wrap, however long ago the last frame went. */
	size_t n = server_stream_next(s, ss->stream_end - ss->q_sent_total - 1u < ss->q_len,
				      SERVER_SERIAL_TXQ - ss->q_len, out, sizeof(out));

	if (n) {
		q_copy(ss, out, n);
		ss->stream_end = ss->q_put_total;
	}
}

static void poll_serial(vs_server_t *s, uint32_t now_ms)
{
	server_serial_t *ss = ss_of(s);
	link_t *l = &s->serial;
	size_t rx = 0;
	bool drained = false;

	ss->answers = ss->ans_bytes = 0;
	ss->more = ss->blocked = false;
	ss->st.polls++;
	q_flush(ss);
	stream_emit(s, ss);
	q_flush(ss);
	for (;;) {
		size_t k;

		if (!room(ss)) {
			/* The port takes no more: the rest waits where it is. */
			ss->blocked = true;
			ss->st.room_stops++;
			break;
		}
		if (ss->answers >= SERVER_SERIAL_REQ_PER_POLL ||
		    ss->ans_bytes >= SERVER_SERIAL_TX_PER_POLL) {
			ss->more = true;
			ss->st.budget_stops++;
			break;
		}
		if (ss->in_at == ss->in_len) {
			if (!ss->io.read) {
				drained = true;
				break;
			}
			if (rx >= SERVER_SERIAL_RX_PER_POLL) {
				ss->more = true;
				break;
			}
			ss->in_at = 0;
			ss->in_len = ss->io.read(ss->io.ctx, ss->in, sizeof(ss->in));
			rx += ss->in_len;
			if (!ss->in_len) {
				drained = true;
				break;
			}
		}
		k = step_len(l, ss->in + ss->in_at, ss->in_len - ss->in_at);
		link_feed(l, ss->in + ss->in_at, k, now_ms);
		ss->in_at += k;
	}
	/* The frame inter-byte timeout only once everything received has been
	 * taken: bytes that wait here or in the port are not silence. Its NAK
	 * and the bytes read again after it are a step's worth at most. */
	if (drained && room(ss))
		frame_srv_poll(&l->fs, now_ms);
	if (ss->answers > ss->st.max_answers)
		ss->st.max_answers = ss->answers;
	if (ss->ans_bytes > ss->st.max_bytes)
		ss->st.max_bytes = ss->ans_bytes;
	q_flush(ss);
	if (ss->blocked && ss->q_len <= SERVER_SERIAL_BACKLOG) {
		/* The port took the backlog after all: more can be taken now. */
		ss->blocked = false;
		ss->more = true;
	}
}

void server_serve_serial(vs_server_t *s, server_serial_t *ss, const vs_link_t *io)
{
	const vs_link_t q = {NULL, q_put, ss};

	memset(ss, 0, sizeof(*ss));
	ss->io = *io;
	link_init(&s->serial, &s->con, &q);
	server_stream_init(s, &ss->sub, STREAM_BAUD);
	s->poll_serial = poll_serial;
}

void server_serial_set_baud(vs_server_t *s, uint32_t baud)
{
	if (s->stream)
		s->stream->baud = baud ? baud : STREAM_BAUD;
}

const stream_sub_t *server_serial_stream(const vs_server_t *s)
{
	const server_serial_t *ss = ss_of(s);

	return ss ? &ss->sub : NULL;
}

size_t server_serial_queued(const vs_server_t *s)
{
	const server_serial_t *ss = ss_of(s);

	return ss ? ss->q_len : 0;
}

bool server_serial_blocked(const vs_server_t *s)
{
	const server_serial_t *ss = ss_of(s);

	return ss && ss->blocked;
}

bool server_serial_more(const vs_server_t *s)
{
	const server_serial_t *ss = ss_of(s);

	return ss && ss->more;
}
