/* Frame codec and resynchronising receiver (host and unit); the unit's
 * frame server is frame_srv.c. */
#include "frame.h"

#include <string.h>

/* Header and CRC around the len payload bytes already at out + FRAME_HDR:
 * one copy for requests, answers and stream frames. */
static size_t frame_wrap(uint8_t *out, uint8_t seq, uint8_t op, size_t len)
{
	out[0] = FRAME_SYNC;
	wire_put_u16(out + 1, (uint16_t)len);
	out[3] = seq;
	out[4] = op;
	wire_put_u16(out + FRAME_HDR + len, cmd_crc16(0xFFFF, out + 1, FRAME_HDR - 1 + len));
	return FRAME_OVERHEAD + len;
}

/* A frame of len payload bytes fits cap and its length field. */
static bool frame_fits(size_t cap, size_t len)
{
	return len <= 0xFFFFu && cap >= FRAME_OVERHEAD && cap - FRAME_OVERHEAD >= len;
}

size_t frame_encode(uint8_t *out, size_t cap, uint8_t seq, uint8_t op, const uint8_t *payload,
		    size_t len)
{
	if (!frame_fits(cap, len))
		return 0;
	if (len)
		memcpy(out + FRAME_HDR, payload, len);
	return frame_wrap(out, seq, op, len);
}

size_t frame_encode_response(uint8_t *out, size_t cap, uint8_t seq, uint8_t opcode, uint8_t status,
			     const uint8_t *payload, size_t len)
{
	if (len > 0xFFFEu || !frame_fits(cap, len + 1))
		return 0;
	out[FRAME_HDR] = status;
	if (len)
		memcpy(out + FRAME_HDR + 1, payload, len);
	return frame_wrap(out, seq, (uint8_t)(opcode | FRAME_RESP_FLAG), len + 1);
}

void frame_rx_init(frame_rx_t *rx, uint8_t *buf, size_t max_payload, frame_fn on_frame,
		   frame_other_fn on_other, void *ctx)
{
	memset(rx, 0, sizeof(*rx));
	rx->buf = buf;
	rx->max_payload = max_payload;
	rx->cap = FRAME_OVERHEAD + max_payload;
	rx->on_frame = on_frame;
	rx->on_other = on_other;
	rx->ctx = ctx;
	rx->octx = ctx;
}

void frame_rx_set_other(frame_rx_t *rx, frame_other_fn on_other, void *ctx)
{
	rx->on_other = on_other;
	rx->octx = ctx;
}

static void report_bad(frame_rx_t *rx, const uint8_t *c, size_t avail, int status)
{
	frame_t f;

	memset(&f, 0, sizeof(f));
	f.status = status;
	/* The seq byte is echoed as soon as it was received, the op only
	 * reported (it is never trusted in a NAK). */
	if (avail >= 4)
		f.seq = c[3];
	if (avail >= FRAME_HDR) {
		f.header = true;
		f.op = c[4];
	}
	rx->on_frame(rx->ctx, &f);
}

/* A sync byte inside a console line of text belongs to that line. */
static bool held(const frame_rx_t *rx)
{
	return rx->hold && rx->hold(rx->hold_ctx);
}

static void other(frame_rx_t *rx, const uint8_t *data, size_t n)
{
	rx->st.other_bytes += (uint32_t)n;
	if (rx->on_other)
		rx->on_other(rx->octx, data, n);
}

/* Works through buf from the front: bytes before a sync go out as other
 * bytes, complete candidates are checked and reported. A failed candidate
 * gives up only its sync byte, so the bytes after it are scanned again.
 * flush: the link went quiet; an unfinished candidate is dropped too. */
static void scan(frame_rx_t *rx, bool flush)
{
	size_t start = 0;

	while (start < rx->n) {
		const uint8_t *c = rx->buf + start;
		size_t avail = rx->n - start, len, need;

		if (c[0] != FRAME_SYNC || held(rx)) {
			const uint8_t *s = c[0] == FRAME_SYNC ? NULL : memchr(c, FRAME_SYNC, avail);
			size_t k = c[0] == FRAME_SYNC ? 1 : s ? (size_t)(s - c) : avail;

			other(rx, c, k);
			start += k;
			continue;
		}
		if (avail >= 3) {
			len = wire_get_u16(c + 1);
			/* Refused at once, but only once its seq is in to echo. */
			if (len > rx->max_payload && avail >= 4) {
				rx->st.oversize++;
				report_bad(rx, c, avail, WIRE_ST_OVERSIZE);
				start++;
				continue;
			}
			need = FRAME_OVERHEAD + len;
			if (len <= rx->max_payload && avail >= need) {
				uint16_t crc = cmd_crc16(0xFFFF, c + 1, FRAME_HDR - 1 + len);

				if (crc != wire_get_u16(c + FRAME_HDR + len)) {
					rx->st.crc_errors++;
					report_bad(rx, c, avail, WIRE_ST_CRC);
					start++;
					continue;
				}
				{
					frame_t f = {WIRE_ST_OK, true,		c[3], c[4],
						     crc,	 c + FRAME_HDR, len};

					rx->st.frames++;
					rx->on_frame(rx->ctx, &f);
				}
				start += need;
				continue;
			}
		}
		/* An unfinished candidate. */
		if (!flush)
			break;
		rx->st.truncated++;
		start++;
	}
	if (start) {
		memmove(rx->buf, rx->buf + start, rx->n - start);
		rx->n -= start;
	}
}

void frame_rx_set_hold(frame_rx_t *rx, frame_hold_fn hold, void *ctx)
{
	rx->hold = hold;
	rx->hold_ctx = ctx;
}

void frame_rx_feed(frame_rx_t *rx, const uint8_t *data, size_t n, uint32_t now_ms)
{
	size_t i = 0;

	if (n)
		rx->last_ms = now_ms;
	while (i < n) {
		if (rx->n == 0 && data[i] != FRAME_SYNC) {
			/* Outside a frame: hand on the whole run up to the next sync. */
			const uint8_t *s = memchr(data + i, FRAME_SYNC, n - i);
			size_t k = s ? (size_t)(s - (data + i)) : n - i;

			other(rx, data + i, k);
			i += k;
			continue;
		}
		if (rx->n == 0 && held(rx)) {
			other(rx, data + i, 1);
			i++;
			continue;
		}
		/* Never full here: every candidate is complete or rejected by
		 * the time it reaches cap bytes. */
		rx->buf[rx->n++] = data[i++];
		if (rx->n >= 3)
			scan(rx, false);
	}
}

void frame_rx_poll(frame_rx_t *rx, uint32_t now_ms)
{
	if (rx->n == 0 || (uint32_t)(now_ms - rx->last_ms) < FRAME_RX_TIMEOUT_MS)
		return;
	/* The head candidate is answered; what follows is rescanned, and any
	 * further unfinished candidate in it is dropped with a count. */
	rx->st.truncated++;
	report_bad(rx, rx->buf, rx->n, WIRE_ST_TRUNCATED);
	memmove(rx->buf, rx->buf + 1, rx->n - 1);
	rx->n--;
	scan(rx, true);
}
