/* The CAN link (see canlink.h and docs/can.md). */
#include "canlink.h"

#include <string.h>

/* ---- segmentation ------------------------------------------------------ */

size_t canlink_seg_count(size_t len)
{
	if (len <= 7)
		return 1;
	/* first frame carries 6 bytes, each consecutive frame 7 */
	return 1 + (len - 6 + 7 - 1) / 7;
}

void canlink_seg_frame(const uint8_t *msg, size_t len, size_t i, uint32_t id, canlink_frame_t *f)
{
	memset(f, 0, sizeof(*f));
	f->id = id;
	if (len <= 7) {
		f->data[0] = (uint8_t)(CANLINK_PCI_SINGLE | len);
		memcpy(&f->data[1], msg, len);
		f->dlc = (uint8_t)(len + 1);
		return;
	}
	if (i == 0) {
		f->data[0] = (uint8_t)(CANLINK_PCI_FIRST | ((len >> 8) & 0x0Fu));
		f->data[1] = (uint8_t)(len & 0xFFu);
		memcpy(&f->data[2], msg, 6);
		f->dlc = 8;
		return;
	}
	size_t off = 6 + (i - 1) * 7;
	size_t n = len - off < 7 ? len - off : 7;
	f->data[0] = (uint8_t)(CANLINK_PCI_NEXT | (i & 0x0Fu));
	memcpy(&f->data[1], msg + off, n);
	f->dlc = (uint8_t)(n + 1);
}

void canlink_rx_init(canlink_rx_t *r, uint8_t *buf, size_t cap)
{
	memset(r, 0, sizeof(*r));
	r->buf = buf;
	r->cap = cap;
}

int canlink_rx_feed(canlink_rx_t *r, const canlink_frame_t *f, uint32_t now_us)
{
	if (f->dlc < 1 || f->dlc > 8)
		return CANLINK_RX_BAD_DLC;
	uint8_t pci = f->data[0] & 0xF0u;
	size_t avail = (size_t)f->dlc - 1;

	if (pci == CANLINK_PCI_SINGLE || pci == CANLINK_PCI_FIRST) {
		/* A new message: whatever was in progress is given up. */
		if (r->active)
			r->aborted++;
		r->active = false;
		r->discarding = false;
	}
	switch (pci) {
	case CANLINK_PCI_SINGLE: {
		size_t n = f->data[0] & 0x0Fu;
		if (n == 0 || n > 7)
			return CANLINK_RX_BAD_PCI;
		if (n > avail)
			return CANLINK_RX_BAD_DLC;
		if (n > r->cap) {
			memcpy(r->refused_head, &f->data[1], n >= 2 ? 2 : 1);
			if (n < 2)
				r->refused_head[1] = 0;
			return CANLINK_RX_OVERSIZE;
		}
		memcpy(r->buf, &f->data[1], n);
		r->len = n;
		return CANLINK_RX_DONE;
	}
	case CANLINK_PCI_FIRST: {
		size_t n = ((size_t)(f->data[0] & 0x0Fu) << 8) | f->data[1];
		if (f->dlc != 8)
			return CANLINK_RX_BAD_DLC;
		if (n <= 7)
			return CANLINK_RX_BAD_PCI;
		if (n > r->cap) {
			r->refused_head[0] = f->data[2];
			r->refused_head[1] = f->data[3];
			r->discarding = true;
			return CANLINK_RX_OVERSIZE;
		}
		memcpy(r->buf, &f->data[2], 6);
		r->len = 6;
		r->want = n;
		r->next_index = 1;
		r->active = true;
		r->started_us = now_us;
		return CANLINK_RX_PENDING;
	}
	case CANLINK_PCI_NEXT: {
		if (r->discarding)
			return CANLINK_RX_DISCARDED;
		if (!r->active || (f->data[0] & 0x0Fu) != r->next_index) {
			/* Lost or stray frame: drop the message, wait for a new start. */
			r->active = false;
			return CANLINK_RX_SEQUENCE;
		}
		size_t rest = r->want - r->len;
		size_t n = rest < 7 ? rest : 7;
		/* Every consecutive frame but the last is full. */
		if (avail < n || (rest > 7 && f->dlc != 8)) {
			r->active = false;
			return CANLINK_RX_BAD_DLC;
		}
		memcpy(r->buf + r->len, &f->data[1], n);
		r->len += n;
		r->next_index = (uint8_t)((r->next_index + 1) & 0x0Fu);
		if (r->len < r->want)
			return CANLINK_RX_PENDING;
		r->active = false;
		return CANLINK_RX_DONE;
	}
	case CANLINK_PCI_FLOW:
		return f->dlc < CANLINK_FC_DLC ? CANLINK_RX_BAD_DLC : CANLINK_RX_FLOW;
	default:
		return CANLINK_RX_BAD_PCI;
	}
}

bool canlink_rx_expired(canlink_rx_t *r, uint32_t now_us)
{
	if (!r->active || (uint32_t)(now_us - r->started_us) <= CANLINK_RX_TIMEOUT_US)
		return false;
	r->active = false;
	return true;
}

void canlink_fc_frame(uint32_t id, uint8_t status, uint8_t block_size, uint8_t stmin,
		      canlink_frame_t *f)
{
	memset(f, 0, sizeof(*f));
	f->id = id;
	f->dlc = CANLINK_FC_DLC;
	f->data[0] = (uint8_t)(CANLINK_PCI_FLOW | (status & 0x0Fu));
	f->data[1] = block_size;
	f->data[2] = stmin;
}

uint32_t canlink_stmin_us(uint8_t stmin)
{
	if (stmin <= 0x7Fu)
		return stmin * 1000u;
	if (stmin >= 0xF1u && stmin <= 0xF9u)
		return (stmin - 0xF0u) * 100u;
	return 127000u;
}

/* ---- status ------------------------------------------------------------ */

/* x * scale rounded half away from zero, saturated; NaN reads 0. */
static int64_t round_sat(double x, double scale, int64_t lo, int64_t hi)
{
	double y = x * scale;

	if (y != y)
		return 0;
	if (y <= (double)lo)
		return lo;
	if (y >= (double)hi)
		return hi;
	return (int64_t)(y < 0 ? y - 0.5 : y + 0.5);
}

/* Q32 per tick -> units per second, rounded, saturated to int16. */
static int16_t rate_i16(q32_t per_tick, uint32_t tick_hz, int32_t mult)
{
	int64_t v = per_tick * (int64_t)tick_hz * mult;
	int64_t half = (int64_t)1 << 31;
	int64_t r = v >= 0 ? (v + half) >> 32 : -((-v + half) >> 32);

	if (r > INT16_MAX)
		r = INT16_MAX;
	if (r < INT16_MIN)
		r = INT16_MIN;
	return (int16_t)r;
}

void canlink_status_read(vehicle_t *v, canlink_status_t *st)
{
	vs_position_t pos = {0, 0, 0};
	char msg[VS_STATE_MSG_MAX];
	vs_alarm_t one[1];
	int16_t state = 0, nalarms = 0;
	uint16_t got = 0;
	double batt = 0;
	vs_diag_t d;

	memset(st, 0, sizeof(*st));
	vs_getState(v, &state, msg);
	vs_getActiveAlarm(v, 0, &nalarms, one, &got);
	vs_getBatteryVoltage(v, &batt);
	vs_getPosition(v, &pos);
	memset(&d, 0, sizeof(d));
	vehicle_diag(v, &d);

	st->state = (uint16_t)state;
	st->alarms = nalarms < 0 ? 0 : nalarms > 255 ? 255 : (uint8_t)nalarms;
	st->battery_cV = (uint16_t)round_sat(batt, 10.0, 0, UINT16_MAX);
	st->x_dmm = (int32_t)round_sat(pos.x, 10.0, INT32_MIN, INT32_MAX);
	st->y_dmm = (int32_t)round_sat(pos.y, 10.0, INT32_MIN, INT32_MAX);
	st->theta_mdeg = (int32_t)round_sat(pos.theta, 1000.0, INT32_MIN, INT32_MAX);
	/* Speed: the commanded body velocity of the last tick. */
	st->vx_mm_s = rate_i16(d.cmd_twist_pt.vx_pt, v->cfg.tick_hz, 1);
	st->vy_mm_s = rate_i16(d.cmd_twist_pt.vy_pt, v->cfg.tick_hz, 1);
	st->w_ddeg_s = rate_i16(d.cmd_twist_pt.w_pt, v->cfg.tick_hz, 10);
}

void canlink_status_frame(const canlink_status_t *st, uint8_t node, unsigned which,
			  canlink_frame_t *f)
{
	memset(f, 0, sizeof(*f));
	f->dlc = 8;
	switch (which) {
	case 0:
		f->id = CANLINK_ID_STATUS_A + node;
		wire_put_u16(&f->data[0], st->state);
		f->data[2] = st->alarms;
		f->data[3] = st->counter;
		wire_put_u16(&f->data[4], st->battery_cV);
		wire_put_u16(&f->data[6], (uint16_t)st->vx_mm_s);
		break;
	case 1:
		f->id = CANLINK_ID_STATUS_B + node;
		wire_put_u32(&f->data[0], (uint32_t)st->x_dmm);
		wire_put_u32(&f->data[4], (uint32_t)st->y_dmm);
		break;
	default:
		f->id = CANLINK_ID_STATUS_C + node;
		wire_put_u32(&f->data[0], (uint32_t)st->theta_mdeg);
		wire_put_u16(&f->data[4], (uint16_t)st->vy_mm_s);
		wire_put_u16(&f->data[6], (uint16_t)st->w_ddeg_s);
		break;
	}
}

int canlink_status_decode(const canlink_frame_t *f, uint8_t node, canlink_status_t *st)
{
	if (f->dlc != 8)
		return -1;
	if (f->id == CANLINK_ID_STATUS_A + node) {
		st->state = wire_get_u16(&f->data[0]);
		st->alarms = f->data[2];
		st->counter = f->data[3];
		st->battery_cV = wire_get_u16(&f->data[4]);
		st->vx_mm_s = (int16_t)wire_get_u16(&f->data[6]);
		return 0;
	}
	if (f->id == CANLINK_ID_STATUS_B + node) {
		st->x_dmm = (int32_t)wire_get_u32(&f->data[0]);
		st->y_dmm = (int32_t)wire_get_u32(&f->data[4]);
		return 1;
	}
	if (f->id == CANLINK_ID_STATUS_C + node) {
		st->theta_mdeg = (int32_t)wire_get_u32(&f->data[0]);
		st->vy_mm_s = (int16_t)wire_get_u16(&f->data[4]);
		st->w_ddeg_s = (int16_t)wire_get_u16(&f->data[6]);
		return 2;
	}
	return -1;
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
	for (unsigned i = 0; i < 3; i++) {
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
