/* The unit's CAN link server (canlink.h, docs/can.md): requests reassembled,
 * run through wire_dispatch and answered, and the status frames sent. */
#include "canlink.h"

#include <string.h>

#include "dispatch.h"

/* ---- status ------------------------------------------------------------ */

void canlink_status_read(vehicle_t *v, canlink_status_t *st)
{
	stream_read(v, st);
}

/* ---- the unit's side --------------------------------------------------- */

int canlink_init(canlink_t *c, vehicle_t *v, const canlink_config_t *cfg, canlink_send_fn send,
		 void *ctx)
{
	if (cfg->node < CANLINK_NODE_MIN || cfg->node > CANLINK_NODE_MAX ||
	    cfg->status_hz > CANLINK_STATUS_HZ_MAX)
		return -1;
	memset(c, 0, sizeof(*c));
	c->v = v;
	c->cfg = *cfg;
	c->send = send;
	c->send_ctx = ctx;
	canlink_rx_init(&c->rx, c->rx_buf, sizeof(c->rx_buf));
	c->status_period_us = cfg->status_hz ? 1000000u / cfg->status_hz : 0;
	(void)cmd_table_crc(); /* now, so that protocol info costs no tick */
	return 0;
}

static void wait_fc(canlink_t *c, uint32_t now_us)
{
	c->tx_wait_fc = true;
	c->tx_fc_us = now_us;
	c->tx_block = 0;
}

/* Sends what is left of the response as far as flow control allows: after
 * the first frame the host's flow control frame, then blocks of its block
 * size, consecutive frames at least its STmin apart (so at most one per
 * poll when STmin is not 0). Stops at the first refusal. */
static void tx_flush(canlink_t *c, uint32_t now_us)
{
	while (c->tx_next < c->tx_count && !c->tx_wait_fc) {
		canlink_frame_t f;

		if (c->tx_cf_sent && c->tx_stmin_us &&
		    (uint32_t)(now_us - c->tx_last_us) < c->tx_stmin_us)
			return;
		canlink_seg_frame(c->tx_msg, c->tx_len, c->tx_next,
				  CANLINK_ID_RESPONSE + c->cfg.node, &f);
		if (!c->send(c->send_ctx, &f)) {
			c->stats.tx_busy++;
			return;
		}
		c->stats.tx_frames++;
		c->tx_next++;
		if (c->tx_count == 1)
			continue;
		if (c->tx_next == 1) {
			wait_fc(c, now_us);
			continue;
		}
		c->tx_cf_sent = true;
		c->tx_last_us = now_us;
		if (c->tx_bs && ++c->tx_block == c->tx_bs && c->tx_next < c->tx_count)
			wait_fc(c, now_us);
	}
}

/* Queues a response message (tx_buf or nak_buf). */
static void tx_start(canlink_t *c, const uint8_t *msg, size_t len, uint32_t now_us)
{
	c->tx_msg = msg;
	c->tx_len = len;
	c->tx_next = 0;
	c->tx_count = canlink_seg_count(len);
	c->tx_wait_fc = c->tx_cf_sent = false;
	tx_flush(c, now_us);
}

static void abandon_tx(canlink_t *c)
{
	if (c->tx_next < c->tx_count)
		c->stats.tx_abandoned++;
	c->tx_next = c->tx_count = 0;
	c->tx_wait_fc = false;
}

/* The host's flow control frame for the response being sent. */
static void take_fc(canlink_t *c, const canlink_frame_t *f, uint32_t now_us)
{
	c->stats.rx_flow++;
	/* ISO 15765-2: a flow control frame nobody waits for is ignored. */
	if (!c->tx_wait_fc)
		return;
	switch (f->data[0] & 0x0Fu) {
	case CANLINK_FC_CTS:
		c->tx_wait_fc = false;
		c->tx_bs = f->data[1];
		c->tx_stmin_us = canlink_stmin_us(f->data[2]);
		tx_flush(c, now_us);
		break;
	case CANLINK_FC_WAIT:
		c->tx_fc_us = now_us;
		break;
	default:
		/* Overflow, or a status ISO does not define: the host cannot
		 * take this response. */
		c->stats.tx_overflow++;
		c->tx_next = c->tx_count = 0;
		c->tx_wait_fc = false;
		break;
	}
}

static void fc_flush(canlink_t *c)
{
	canlink_frame_t f;

	if (!c->fc_pending)
		return;
	canlink_fc_frame(CANLINK_ID_RESPONSE + c->cfg.node, c->fc_status, 0, 0, &f);
	if (!c->send(c->send_ctx, &f)) {
		c->stats.tx_busy++;
		return;
	}
	c->fc_pending = false;
	c->stats.fc_sent++;
	c->stats.tx_frames++;
}

/* Answers a request's first frame: go on (block size 0, STmin 0: the unit
 * takes back-to-back frames), or overflow for one longer than it accepts. */
static void send_fc(canlink_t *c, uint8_t status)
{
	c->fc_pending = true;
	c->fc_status = status;
	fc_flush(c);
}

static void send_nak(canlink_t *c, uint8_t seq, uint8_t opcode, int status, uint32_t now_us)
{
	abandon_tx(c);
	c->nak_buf[0] = seq;
	c->nak_buf[1] = opcode;
	c->nak_buf[2] = (uint8_t)status;
	c->stats.naks++;
	/* A NAK answers nothing that ran, so it has its own buffer and the
	 * retransmission cache in tx_buf stays valid. */
	tx_start(c, c->nak_buf, CANLINK_RESP_HDR, now_us);
}

static void handle_request(canlink_t *c, const uint8_t *req, size_t len, uint32_t now_us)
{
	if (len < CANLINK_REQ_HDR) {
		/* No sequence number and opcode to answer to. */
		c->stats.rx_short++;
		return;
	}
	if (c->have_last && len == c->last_req_len && memcmp(req, c->last_req, len) == 0) {
		/* Retransmission: same sequence number, same request. The cached
		 * response in tx_buf is sent again; the operation does not run. */
		c->stats.replays++;
		vehicle_link_heard(c->v, VS_LINK_CAN);
		abandon_tx(c);
		tx_start(c, c->tx_buf, c->tx_len_last, now_us);
		return;
	}
	abandon_tx(c);
	/* tx_buf is about to hold the new response: the old one is gone. */
	c->have_last = false;
	int status = WIRE_ST_OK;
	size_t n = wire_dispatch(c->v, req[1], req + CANLINK_REQ_HDR, len - CANLINK_REQ_HDR,
				 c->tx_buf + CANLINK_RESP_HDR, sizeof(c->tx_buf) - CANLINK_RESP_HDR,
				 &status);
	if (status != WIRE_ST_OK) {
		send_nak(c, req[0], req[1], status, now_us);
		return;
	}
	c->stats.requests++;
	vehicle_link_heard(c->v, VS_LINK_CAN);
	c->tx_buf[0] = req[0];
	c->tx_buf[1] = req[1];
	c->tx_buf[2] = WIRE_ST_OK;
	memcpy(c->last_req, req, len);
	c->last_req_len = len;
	c->have_last = true;
	c->tx_len_last = CANLINK_RESP_HDR + n;
	tx_start(c, c->tx_buf, c->tx_len_last, now_us);
}

void canlink_rx(canlink_t *c, const canlink_frame_t *f, uint32_t now_us)
{
	if (f->id != CANLINK_ID_REQUEST + c->cfg.node) {
		c->stats.rx_foreign++;
		return;
	}
	c->stats.rx_frames++;
	uint32_t aborted = c->rx.aborted;
	int r = canlink_rx_feed(&c->rx, f, now_us);
	c->stats.rx_aborted += c->rx.aborted - aborted;

	switch (r) {
	case CANLINK_RX_DONE:
		handle_request(c, c->rx.buf, c->rx.len, now_us);
		break;
	case CANLINK_RX_PENDING:
		/* Only a first frame leaves a message pending. */
		if ((f->data[0] & 0xF0u) == CANLINK_PCI_FIRST)
			send_fc(c, CANLINK_FC_CTS);
		break;
	case CANLINK_RX_FLOW:
		take_fc(c, f, now_us);
		break;
	case CANLINK_RX_BAD_DLC:
		c->stats.rx_bad_dlc++;
		break;
	case CANLINK_RX_BAD_PCI:
		c->stats.rx_bad_pci++;
		break;
	case CANLINK_RX_SEQUENCE:
		c->stats.rx_sequence++;
		break;
	case CANLINK_RX_OVERSIZE:
		/* Never executed: the sender learns why at once. */
		c->stats.rx_oversize++;
		/* A first frame: the ISO sender stops at the overflow status. */
		if ((f->data[0] & 0xF0u) == CANLINK_PCI_FIRST)
			send_fc(c, CANLINK_FC_OVFLW);
		send_nak(c, c->rx.refused_head[0], c->rx.refused_head[1], WIRE_ST_OVERSIZE, now_us);
		break;
	default:
		c->stats.rx_discarded++;
		break;
	}
}

static void status_send(canlink_t *c)
{
	canlink_status_t st;
	bool all = true;

	canlink_status_read(c->v, &st);
	st.counter = c->status_counter++;
	for (unsigned i = 0; i < STREAM_CAN_FRAMES; i++) {
		canlink_frame_t f;

		canlink_status_frame(&st, c->cfg.node, i, &f);
		if (c->send(c->send_ctx, &f))
			c->stats.tx_frames++;
		else
			all = false;
	}
	/* Status is periodic: a lost group is replaced by the next one. */
	if (all)
		c->stats.status_sent++;
	else
		c->stats.status_dropped++;
}

void canlink_poll(canlink_t *c, uint32_t now_us)
{
	if (canlink_rx_expired(&c->rx, now_us)) {
		c->stats.rx_timeouts++;
		send_nak(c, c->rx.buf[0], c->rx.buf[1], WIRE_ST_TRUNCATED, now_us);
	}
	if (c->tx_wait_fc && (uint32_t)(now_us - c->tx_fc_us) > CANLINK_FC_TIMEOUT_US) {
		/* ISO 15765-2 N_Bs: the host does not want the rest. */
		c->stats.tx_fc_timeouts++;
		c->tx_next = c->tx_count = 0;
		c->tx_wait_fc = false;
	}
	fc_flush(c);
	tx_flush(c, now_us);
	if (!c->status_period_us)
		return;
	if (!c->status_started) {
		c->status_started = true;
		c->status_next_us = now_us;
	}
	if ((int32_t)(now_us - c->status_next_us) >= 0) {
		status_send(c);
		c->status_next_us += c->status_period_us;
		/* Far behind (stalled host): restart the schedule, no burst. */
		if ((int32_t)(now_us - c->status_next_us) >= 0)
			c->status_next_us = now_us + c->status_period_us;
	}
}
