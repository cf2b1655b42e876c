/* Fuzz target: the CAN frame and segment decoder (proto/canlink.c) and the
 * unit's CAN link on a unit on the simulated plant.
 *
 * Input: records of 11 bytes: control (bits 0-1: time since the previous
 * record 0, 1, 10 or 300 ms; bit 2: a foreign identifier instead of the
 * request one; bit 3: the transmit queue refuses frames until the next
 * record; bit 4: poll), DLC byte (taken modulo 16: DLCs over 8 are seen as
 * 8 data bytes at most by a controller, and checked here to be refused or
 * clamped without reading past the frame), one spare byte and 8 data bytes.
 *
 * Checked: every frame the unit sends uses one of its own identifiers with
 * DLC 0..8; its responses reassemble (host side) into whole messages with
 * the response header; no more operations run than request frames came;
 * the standalone reassembler returns one of its results (flow control
 * frames included) and never reports more bytes than it holds.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "../../host_sim/sim.h"
#include "../../proto/canlink.h"

#define NODE 5

static sim_t S;
static canlink_t link_;
static bool tx_busy;
static canlink_rx_t host_rx;
static uint8_t host_buf[CANLINK_RESP_MAX];

static bool on_send(void *ctx, const canlink_frame_t *f)
{
	(void)ctx;
	if (f->dlc > 8)
		abort();
	switch (f->id) {
	case CANLINK_ID_STATUS_A + NODE:
	case CANLINK_ID_STATUS_B + NODE:
	case CANLINK_ID_STATUS_C + NODE:
	case CANLINK_ID_STATUS_D + NODE:
	case CANLINK_ID_STATUS_E + NODE:
		return !tx_busy;
	case CANLINK_ID_RESPONSE + NODE:
		break;
	default:
		abort(); /* not one of the unit's identifiers */
	}
	if (tx_busy)
		return false;
	int r = canlink_rx_feed(&host_rx, f, 0);
	if (r < 0 && r != CANLINK_RX_SEQUENCE)
		abort(); /* the unit sent a malformed segment */
	if (r == CANLINK_RX_DONE && (host_rx.len < CANLINK_RESP_HDR || host_rx.len > host_rx.cap))
		abort();
	return true;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	static const uint32_t gap_us[4] = {0, 1000, 10000, 300000};
	static canlink_rx_t solo;
	static uint8_t solo_buf[64];
	vs_config_t cfg;
	canlink_config_t lc = {NODE, 100};
	uint32_t now = 5000;

	vs_config_defaults(&cfg);
	if (sim_init(&S, &cfg, NULL) != 0)
		abort();
	tx_busy = false;
	if (canlink_init(&link_, &S.vehicle, &lc, on_send, NULL) != 0)
		abort();
	canlink_rx_init(&host_rx, host_buf, sizeof host_buf);
	canlink_rx_init(&solo, solo_buf, sizeof solo_buf);

	for (size_t i = 0; i + 11 <= size; i += 11) {
		const uint8_t *r = data + i;
		canlink_frame_t f;
		now += gap_us[r[0] & 3];
		tx_busy = (r[0] & 8) != 0;
		f.id = (r[0] & 4) ? (uint32_t)(r[2] << 3 | (r[1] >> 5)) & 0x7ffu
				  : CANLINK_ID_REQUEST + NODE;
		f.dlc = (uint8_t)((r[1] & 0xf) > 8 ? 8 : (r[1] & 0xf));
		memcpy(f.data, r + 3, 8);
		uint32_t before = link_.stats.requests;
		canlink_rx(&link_, &f, now);
		if (link_.stats.requests > before + 1 ||
		    link_.stats.requests + link_.stats.replays > link_.stats.rx_frames)
			abort();
		/* The segment decoder alone, on a small buffer. */
		int sr = canlink_rx_feed(&solo, &f, now);
		if (sr < CANLINK_RX_DISCARDED || sr > CANLINK_RX_FLOW || solo.len > solo.cap)
			abort();
		canlink_rx_expired(&solo, now);
		if (r[0] & 0x10) {
			canlink_poll(&link_, now);
			sim_tick(&S);
		}
	}
	tx_busy = false;
	for (int k = 0; k < 50; k++) {
		now += 1000;
		canlink_poll(&link_, now);
	}
	return 0;
}
