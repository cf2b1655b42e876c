/* Fuzz target: the binary frame decoder and the unit's frame server
 * (proto/frame.c, wire.c) on a unit on the simulated plant.
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
#include "../../proto/frame.h"

static sim_t S;
static frame_srv_t srv;
static frame_rx_t back; /* parses what the unit sent */
static uint8_t back_buf[FRAME_RESP_MAX];
static uint32_t back_frames;

static void on_back_frame(void *ctx, const frame_t *f)
{
	(void)ctx;
	if (f->status != WIRE_ST_OK || !(f->op & FRAME_RESP_FLAG) || f->len < 1 ||
	    f->len > FRAME_RESP_PAYLOAD_MAX)
		abort();
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
	frame_srv_init(&srv, &S.vehicle, on_write, NULL, on_other, NULL);
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
	}
	frame_srv_poll(&srv, now + 1000);
	if (frame_rx_busy(&srv.rx) || back_frames < srv.st.executed)
		abort();
	return 0;
}
