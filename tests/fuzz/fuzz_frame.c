/* Fuzz target: the binary frame decoder and the unit's frame server
 * (proto/frame.c, wire.c) on a unit on the simulated plant, with the
 * telemetry stream's subscription (proto/stream.c) as the serial server has
 * it: every stream frame due after a tick is encoded and read back; and the
 * black box's readout (proto/bbox_wire.h) on a small ring recording every
 * other tick: every answer decodes to its header and samples.
 *
 * Input: chunks, each a control byte (bits 0-5: chunk length, bits 6-7:
 * time since the previous chunk: 0, 1, 60 or 150 ms, so the inter-byte
 * timeout fires) and its bytes. Checked: everything the unit writes back is
 * a sequence of well-formed response frames (sync, length, check, response
 * flag) and nothing else; no more operations run than good frames arrived;
 * the receive buffer never claims more than it holds.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "../../host_sim/sim.h"
#include "../../proto/bbox_wire.h"
#include "../../proto/frame.h"
#include "../../proto/stream.h"

static sim_t S;
static frame_srv_t srv;
static frame_rx_t back; /* parses what the unit sent */
static uint8_t back_buf[FRAME_RESP_MAX];
static uint32_t back_frames;
static stream_sub_t sub;
static bbox_sample_t ring[12];

static size_t on_stream(void *ctx, const uint8_t *p, size_t len, uint8_t *resp, int *st)
{
	(void)ctx;
	size_t n = stream_subscribe(&sub, S.vehicle.cfg.tick_hz, S.vehicle.ticks, p, len, resp, st);
	if ((*st == WIRE_ST_OK) != (n == STREAM_RESP_LEN))
		abort();
	return n;
}

/* A due stream frame, as the serial server sends it: it decodes to its
 * mask and tick, and the rate in force fits the line. */
static void stream_tick(void)
{
	uint8_t p[STREAM_PAYLOAD_MAX];
	stream_sample_t smp, back_smp;
	uint16_t mask;
	uint32_t tick;
	size_t n;

	if (!stream_due(&sub, S.vehicle.ticks))
		return;
	if (!stream_fits(sub.mask, sub.period_ms, sub.baud))
		abort();
	stream_read(&S.vehicle, &smp);
	n = stream_encode(&smp, sub.mask, S.vehicle.ticks, p, sizeof(p));
	memset(&back_smp, 0, sizeof(back_smp));
	if (n != stream_payload_len(sub.mask) ||
	    stream_decode(p, n, &mask, &tick, &back_smp) != 0 || mask != sub.mask ||
	    tick != S.vehicle.ticks)
		abort();
}

static void on_back_frame(void *ctx, const frame_t *f)
{
	(void)ctx;
	if (f->status != WIRE_ST_OK || !(f->op & FRAME_RESP_FLAG) || f->len < 1 ||
	    f->len > FRAME_RESP_PAYLOAD_MAX)
		abort();
	if (f->op == (FRAME_RESP_FLAG | WIRE_OP_BBOX) && f->len > 1) {
		bbox_page_t pg;
		bbox_sample_t smp[BBOX_PAGE];

		if (!bbox_wire_decode(f->payload + 1, f->len - 1, &pg, smp) || pg.count > pg.cap ||
		    pg.index + pg.n > pg.count)
			abort();
	}
	back_frames++;
}

static void on_back_other(void *ctx, const uint8_t *d, size_t n)
{
	(void)ctx, (void)d;
	if (n)
		abort(); /* the unit wrote bytes that are not a frame */
}

static void on_write(void *ctx, const uint8_t *d, size_t n)
{
	(void)ctx;
	if (n < FRAME_OVERHEAD + 1 || n > FRAME_RESP_MAX || d[0] != FRAME_SYNC)
		abort();
	frame_rx_feed(&back, d, n, 0);
	if (frame_rx_busy(&back))
		abort(); /* one write is whole frames */
}

static void on_other(void *ctx, const uint8_t *d, size_t n)
{
	(void)ctx, (void)d, (void)n;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	static const uint32_t gap_ms[4] = {0, 1, 60, 150};
	vs_config_t cfg;
	uint32_t now = 1000;

	vs_config_defaults(&cfg);
	if (sim_init(&S, &cfg, NULL) != 0)
		abort();
	vehicle_blackbox(&S.vehicle, ring, 12, 2);
	frame_srv_init(&srv, &S.vehicle, on_write, NULL, on_other, NULL);
	stream_sub_init(&sub, STREAM_BAUD);
	frame_srv_set_stream(&srv, on_stream, NULL);
	frame_rx_init(&back, back_buf, FRAME_RESP_PAYLOAD_MAX, on_back_frame, on_back_other, NULL);
	back_frames = 0;

	size_t i = 0;
	while (i < size) {
		uint8_t ctl = data[i++];
		size_t n = ctl & 0x3f;
		if (n > size - i)
			n = size - i;
		now += gap_ms[ctl >> 6];
		frame_srv_poll(&srv, now);
		frame_srv_feed(&srv, data + i, n, now);
		i += n;
		if (srv.rx.n > srv.rx.cap || srv.st.executed > srv.rx.st.frames)
			abort();
		/* a little time for the unit between chunks */
		sim_tick(&S);
		stream_tick();
	}
	frame_srv_poll(&srv, now + 1000);
	if (frame_rx_busy(&srv.rx) || back_frames < srv.st.executed)
		abort();
	return 0;
}
