/* Client transport: binary frames over a tty (docs/protocol.md). */
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include "client.h"
#include "client_io.h"
#include "../frame.h"
#include "../../hal/posix/tty.h"

uint64_t vcio_now_ms(void)
{
	struct timespec ts;

	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (uint64_t)ts.tv_sec * 1000u + (uint64_t)ts.tv_nsec / 1000000u;
}

int vcio_write_all(int fd, const uint8_t *p, size_t n, unsigned timeout_ms)
{
	uint64_t end = vcio_now_ms() + timeout_ms;

	while (n) {
		ssize_t k = write(fd, p, n);

		if (k > 0) {
			p += k;
			n -= (size_t)k;
			continue;
		}
		if (k < 0 && errno != EAGAIN && errno != EINTR)
			return VC_E_LINK;
		{
			struct pollfd pf = {fd, POLLOUT, 0};
			uint64_t now = vcio_now_ms();

			if (now >= end)
				return VC_E_TIMEOUT;
			if (poll(&pf, 1, (int)(end - now)) < 0 && errno != EINTR)
				return VC_E_LINK;
		}
	}
	return VC_OK;
}

int vcio_read_some(int fd, uint8_t *buf, size_t cap, uint64_t deadline, size_t *got)
{
	*got = 0;
	for (;;) {
		struct pollfd pf = {fd, POLLIN, 0};
		uint64_t now = vcio_now_ms();
		ssize_t k;
		int r;

		if (now >= deadline)
			return VC_E_TIMEOUT;
		r = poll(&pf, 1, (int)(deadline - now));
		if (r < 0) {
			if (errno == EINTR)
				continue;
			return VC_E_LINK;
		}
		if (r == 0)
			return VC_E_TIMEOUT;
		k = read(fd, buf, cap);
		if (k > 0) {
			*got = (size_t)k;
			return VC_OK;
		}
		if (k == 0 || (errno != EAGAIN && errno != EINTR))
			return VC_E_LINK; /* hang-up or device gone */
		if (pf.revents & (POLLHUP | POLLERR))
			return VC_E_LINK;
	}
}

/* Stream frames kept while the host waits for answers (the oldest goes
 * when full). */
#define STREAM_KEEP 64
typedef struct {
	uint8_t seq, len;
	uint8_t p[STREAM_PAYLOAD_MAX];
} kept_t;

typedef struct {
	int fd;
	bool own;
	bool fresh; /* nothing sent yet on this transport */
	uint8_t seq;
	vc_stats_t *stats;
	frame_rx_t rx;
	uint8_t rxbuf[FRAME_RESP_MAX];
	/* The answer being waited for, filled by on_frame. */
	unsigned want_op;
	uint8_t want_seq;
	bool done, crc_seen;
	int status;
	uint8_t *resp;
	size_t cap, len;
	kept_t kept[STREAM_KEEP];
	unsigned kept_at, kept_n;
} serial_t;

/* A frame the unit sent on its own (op without the answer flag). */
static void keep_stream(serial_t *s, const frame_t *f)
{
	kept_t *k;

	if (f->op != WIRE_OP_STREAM || f->len > STREAM_PAYLOAD_MAX)
		return;
	if (s->kept_n == STREAM_KEEP) {
		s->kept_at = (s->kept_at + 1u) % STREAM_KEEP;
		s->kept_n--;
	}
	k = &s->kept[(s->kept_at + s->kept_n) % STREAM_KEEP];
	k->seq = f->seq;
	k->len = (uint8_t)f->len;
	memcpy(k->p, f->payload, f->len);
	s->kept_n++;
}

static void on_frame(void *ctx, const frame_t *f)
{
	serial_t *s = ctx;

	if (f->status == WIRE_ST_OK && !(f->op & FRAME_RESP_FLAG)) {
		keep_stream(s, f);
		return;
	}
	if (s->done)
		return;
	if (f->status != WIRE_ST_OK) {
		/* A damaged answer: ask again. */
		s->crc_seen = true;
		if (s->stats)
			s->stats->crc_errors++;
		return;
	}
	if (!(f->op & FRAME_RESP_FLAG) || f->seq != s->want_seq || f->len < 1)
		return; /* a request echoed back, or the answer to an older request */
	if ((f->op & 0x7Fu) != s->want_op && (f->op & 0x7Fu) != 0)
		return;
	s->status = f->payload[0];
	s->len = 0;
	if (s->status == WIRE_ST_OK) {
		if (f->len - 1 > s->cap) {
			s->status = -1; /* does not fit: malformed */
		} else {
			memcpy(s->resp, f->payload + 1, f->len - 1);
			s->len = f->len - 1;
		}
	}
	s->done = true;
}

static int exchange_once(serial_t *s, unsigned opcode, const uint8_t *req, size_t req_len,
			 uint8_t *resp, size_t cap, size_t *resp_len, int *nak, unsigned timeout_ms,
			 unsigned retries)
{
	uint8_t frame[FRAME_REQ_MAX];
	size_t flen;
	int last = VC_E_TIMEOUT;

	if (opcode == 0 || opcode > 0x7F || req_len > FRAME_REQ_PAYLOAD_MAX)
		return VC_E_ARG;
	s->seq++;
	flen = frame_encode(frame, sizeof(frame), s->seq, (uint8_t)opcode, req, req_len);
	if (!flen)
		return VC_E_ARG;
	s->want_op = opcode;
	s->want_seq = s->seq;
	s->resp = resp;
	s->cap = cap;
	if (s->stats)
		s->stats->requests++;

	for (unsigned attempt = 0; attempt <= retries; attempt++) {
		uint64_t deadline;
		int e;

		if (attempt && s->stats)
			s->stats->retries++;
		s->done = false;
		s->crc_seen = false;
		/* forget a half-received answer of the last attempt (not a stream
		 * frame half read before the first: its sample would be lost) */
		if (attempt)
			s->rx.n = 0;
		e = vcio_write_all(s->fd, frame, flen, timeout_ms);
		if (e == VC_E_LINK)
			return e;
		if (s->stats)
			s->stats->bytes_tx += (uint32_t)flen;
		deadline = vcio_now_ms() + timeout_ms;
		while (!s->done && !s->crc_seen) {
			uint8_t buf[512];
			size_t got = 0;

			e = vcio_read_some(s->fd, buf, sizeof(buf), deadline, &got);
			if (e == VC_E_LINK)
				return e;
			if (e == VC_E_TIMEOUT)
				break;
			if (s->stats)
				s->stats->bytes_rx += (uint32_t)got;
			frame_rx_feed(&s->rx, buf, got, (uint32_t)vcio_now_ms());
		}
		if (s->done) {
			if (s->status == WIRE_ST_OK) {
				*resp_len = s->len;
				return VC_OK;
			}
			if (s->status < 0)
				return VC_E_PROTO;
			/* Our request arrived damaged: send it again. */
			if (s->status == WIRE_ST_CRC || s->status == WIRE_ST_TRUNCATED) {
				last = VC_E_CRC;
				continue;
			}
			if (s->stats)
				s->stats->naks++;
			*nak = s->status;
			return VC_E_NAK;
		}
		if (s->crc_seen) {
			last = VC_E_CRC;
		} else {
			last = VC_E_TIMEOUT;
			if (s->stats)
				s->stats->timeouts++;
		}
	}
	return last;
}

static int serial_exchange(void *ctx, unsigned opcode, const uint8_t *req, size_t req_len,
			   uint8_t *resp, size_t cap, size_t *resp_len, int *nak,
			   unsigned timeout_ms, unsigned retries)
{
	serial_t *s = ctx;

	if (s->fresh) {
		/* The unit caches its last answer by sequence number and request.
		 * A new host process could by chance start at that number with
		 * the same request, and get the old answer instead of a fresh
		 * run; one protocol-info exchange first makes that impossible.
		 * Its outcome does not matter. */
		uint8_t info[WIRE_RESP_MAX];
		size_t n = 0;
		int k = 0;

		s->fresh = false;
		(void)exchange_once(s, WIRE_OP_INFO, NULL, 0, info, sizeof(info), &n, &k,
				    timeout_ms, 0);
	}
	return exchange_once(s, opcode, req, req_len, resp, cap, resp_len, nak, timeout_ms,
			     retries);
}

static int serial_stream_next(void *ctx, uint8_t *p, size_t cap, size_t *len, uint8_t *seq,
			      unsigned timeout_ms)
{
	serial_t *s = ctx;
	uint64_t deadline = vcio_now_ms() + timeout_ms;

	s->done = true; /* no answer is awaited: answers read now are dropped */
	while (!s->kept_n) {
		uint8_t buf[512];
		size_t got = 0;
		int e = vcio_read_some(s->fd, buf, sizeof(buf), deadline, &got);

		if (e != VC_OK)
			return e;
		if (s->stats)
			s->stats->bytes_rx += (uint32_t)got;
		frame_rx_feed(&s->rx, buf, got, (uint32_t)vcio_now_ms());
	}
	{
		kept_t *k = &s->kept[s->kept_at];

		s->kept_at = (s->kept_at + 1u) % STREAM_KEEP;
		s->kept_n--;
		if (k->len > cap)
			return VC_E_PROTO;
		memcpy(p, k->p, k->len);
		*len = k->len;
		*seq = k->seq;
	}
	return VC_OK;
}

static void serial_close(void *ctx)
{
	serial_t *s = ctx;

	if (s->own)
		close(s->fd);
	free(s);
}

int vc_attach_serial_fd(vc_client_t *c, int fd, bool own)
{
	serial_t *s = calloc(1, sizeof(*s));
	vc_transport_t t = {0};

	if (!s) {
		errno = ENOMEM;
		return VC_E_LINK;
	}
	s->fd = fd;
	s->own = own;
	s->fresh = true;
	s->seq =
	    (uint8_t)(vcio_now_ms() & 0xFFu); /* a restarted host does not repeat the last seq */
	frame_rx_init(&s->rx, s->rxbuf, FRAME_RESP_PAYLOAD_MAX, on_frame, NULL, s);
	t.exchange = serial_exchange;
	t.close = serial_close;
	t.stream_next = serial_stream_next;
	t.ctx = s;
	t.name = "serial";
	vc_init(c, &t);
	s->stats = &c->stats;
	return VC_OK;
}

int vc_open_serial(vc_client_t *c, const char *dev, unsigned baud)
{
	int fd = tty_open(dev, baud);

	if (fd < 0)
		return VC_E_LINK;
	return vc_attach_serial_fd(c, fd, true);
}
