/* Client transport over CAN (see client_can.h, docs/can.md). */
#include "client_can.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "../../hal/posix/socketcan.h"

typedef struct {
	vc_client_t *c;
	vc_can_bus_t bus;
	uint8_t node;
	uint8_t seq;
	canlink_rx_t rx;
	uint8_t rx_buf[CANLINK_RESP_MAX];
	/* status group being collected, and the last complete one */
	canlink_status_t st_work, st_last;
	unsigned st_have; /* bit i: frame i of the group seen */
	bool st_fresh;
	vc_can_stats_t stats;
} can_ctx_t;

static uint32_t elapsed_ms(can_ctx_t *k, uint32_t t0)
{
	return k->bus.now_ms(k->bus.ctx) - t0;
}

/* Status frames are collected whenever they arrive; a group starts at A. */
static bool take_status(can_ctx_t *k, const canlink_frame_t *f)
{
	int which = canlink_status_decode(f, k->node, &k->st_work);

	if (which < 0)
		return false;
	if (which == 0)
		k->st_have = 1u;
	else if (k->st_have & 1u)
		k->st_have |= 1u << which;
	if (k->st_have == (1u << STREAM_CAN_FRAMES) - 1u) {
		k->st_last = k->st_work;
		k->st_fresh = true;
		k->st_have = 0;
	}
	return true;
}

/* The next frame before timeout_ms after t0, counted: VC_OK, VC_E_TIMEOUT or
 * VC_E_LINK. */
static int next_frame(can_ctx_t *k, uint32_t t0, unsigned timeout_ms, canlink_frame_t *f)
{
	for (;;) {
		uint32_t e = elapsed_ms(k, t0);
		if (e >= timeout_ms)
			return VC_E_TIMEOUT;
		int r = k->bus.recv(k->bus.ctx, f, timeout_ms - e);
		if (r < 0)
			return VC_E_LINK;
		if (r > 0) {
			k->stats.frames_rx++;
			k->c->stats.bytes_rx += f->dlc;
			return VC_OK;
		}
	}
}

static int send_frame(can_ctx_t *k, const canlink_frame_t *f)
{
	if (k->bus.send(k->bus.ctx, f) != VC_OK)
		return VC_E_LINK;
	k->stats.frames_tx++;
	k->c->stats.bytes_tx += f->dlc;
	return VC_OK;
}

/* The next frame on the unit's response id; status frames met on the way
 * are taken as status, others are not ours. */
static int next_response(can_ctx_t *k, uint32_t t0, unsigned timeout_ms, canlink_frame_t *f)
{
	for (;;) {
		int r = next_frame(k, t0, timeout_ms, f);
		if (r != VC_OK || (!take_status(k, f) && f->id == CANLINK_ID_RESPONSE + k->node))
			return r;
	}
}

/* Waits for the unit's flow control frame after a first frame or a block:
 * VC_OK with the block size in *bs (0: the rest at once), VC_E_NAK when the
 * unit cannot take the message (its NAK follows), VC_E_TIMEOUT, VC_E_LINK. */
static int await_fc(can_ctx_t *k, uint32_t t0, unsigned timeout_ms, uint8_t *bs)
{
	for (;;) {
		canlink_frame_t f;
		int r = next_response(k, t0, timeout_ms, &f);
		if (r != VC_OK)
			return r;
		if ((f.data[0] & 0xF0u) != CANLINK_PCI_FLOW || f.dlc < CANLINK_FC_DLC) {
			/* A late answer to an earlier request. */
			k->stats.stale++;
			continue;
		}
		switch (f.data[0] & 0x0Fu) {
		case CANLINK_FC_CTS:
			/* The unit always grants STmin 0, which is all this
			 * sender does. */
			*bs = f.data[1];
			return VC_OK;
		case CANLINK_FC_WAIT:
			t0 = k->bus.now_ms(k->bus.ctx);
			break;
		default:
			return VC_E_NAK;
		}
	}
}

/* Sends a request message under ISO 15765-2 flow control. */
static int send_message(can_ctx_t *k, const uint8_t *msg, size_t len, unsigned timeout_ms)
{
	size_t n = canlink_seg_count(len);
	uint8_t bs = 0, sent = 0;

	for (size_t i = 0; i < n; i++) {
		canlink_frame_t f;
		int r;

		canlink_seg_frame(msg, len, i, CANLINK_ID_REQUEST + k->node, &f);
		if ((r = send_frame(k, &f)) != VC_OK)
			return r;
		if (n == 1 || i + 1 == n || (i > 0 && (!bs || ++sent < bs)))
			continue;
		sent = 0;
		r = await_fc(k, k->bus.now_ms(k->bus.ctx), timeout_ms, &bs);
		if (r == VC_E_NAK)
			return VC_OK; /* the unit answers with its NAK */
		if (r != VC_OK)
			return r;
	}
	return VC_OK;
}

/* Waits for the response to (seq, opcode) until timeout_ms after t0.
 * VC_OK with the message in k->rx_buf[0..*len), VC_E_TIMEOUT, VC_E_LINK. */
static int await_response(can_ctx_t *k, uint8_t opcode, uint32_t t0, unsigned timeout_ms,
			  size_t *len)
{
	for (;;) {
		canlink_frame_t f;
		int r = next_response(k, t0, timeout_ms, &f);
		if (r != VC_OK)
			return r;
		int fr = canlink_rx_feed(&k->rx, &f, k->bus.now_ms(k->bus.ctx) * 1000u);
		if (fr < 0) {
			k->stats.bad++;
			continue;
		}
		if (fr == CANLINK_RX_PENDING && (f.data[0] & 0xF0u) == CANLINK_PCI_FIRST) {
			/* ISO 15765-2: the rest comes after our flow control,
			 * all at once (block size 0, STmin 0). */
			canlink_frame_t fc;

			canlink_fc_frame(CANLINK_ID_REQUEST + k->node, CANLINK_FC_CTS, 0, 0, &fc);
			if (send_frame(k, &fc) != VC_OK)
				return VC_E_LINK;
		}
		if (fr != CANLINK_RX_DONE)
			continue;
		if (k->rx.len < CANLINK_RESP_HDR || k->rx_buf[0] != k->seq ||
		    k->rx_buf[1] != opcode) {
			/* An answer to an earlier attempt or request. */
			k->stats.stale++;
			continue;
		}
		*len = k->rx.len;
		return VC_OK;
	}
}

static int can_exchange(void *ctx, unsigned opcode, const uint8_t *req, size_t req_len,
			uint8_t *resp, size_t cap, size_t *resp_len, int *nak, unsigned timeout_ms,
			unsigned retries)
{
	can_ctx_t *k = ctx;
	uint8_t msg[CANLINK_REQ_HDR + WIRE_RESP_MAX];

	if (opcode > 0xFF || req_len > sizeof(msg) - CANLINK_REQ_HDR)
		return VC_E_ARG;
	k->seq++;
	msg[0] = k->seq;
	msg[1] = (uint8_t)opcode;
	if (req_len)
		memcpy(msg + CANLINK_REQ_HDR, req, req_len);
	size_t len = CANLINK_REQ_HDR + req_len;

	k->c->stats.requests++;
	for (unsigned attempt = 0; attempt <= retries; attempt++) {
		if (attempt)
			k->c->stats.retries++;
		/* A retry repeats the same sequence number: the unit answers it
		 * from its cache without running the operation again. */
		int r = send_message(k, msg, len, timeout_ms);
		size_t rlen = 0;
		if (r == VC_OK)
			r = await_response(k, (uint8_t)opcode, k->bus.now_ms(k->bus.ctx),
					   timeout_ms, &rlen);
		if (r == VC_E_TIMEOUT) {
			k->c->stats.timeouts++;
			continue;
		}
		if (r != VC_OK)
			return r;
		uint8_t status = k->rx_buf[2];
		if (status != WIRE_ST_OK) {
			if (rlen != CANLINK_RESP_HDR)
				return VC_E_PROTO;
			k->c->stats.naks++;
			if (nak)
				*nak = status;
			return VC_E_NAK;
		}
		if (rlen - CANLINK_RESP_HDR > cap)
			return VC_E_PROTO;
		memcpy(resp, k->rx_buf + CANLINK_RESP_HDR, rlen - CANLINK_RESP_HDR);
		*resp_len = rlen - CANLINK_RESP_HDR;
		return VC_OK;
	}
	return VC_E_TIMEOUT;
}

static void can_close(void *ctx)
{
	can_ctx_t *k = ctx;

	if (k->bus.close)
		k->bus.close(k->bus.ctx);
	free(k);
}

int vc_attach_can(vc_client_t *c, const vc_can_bus_t *bus, unsigned node, int seq0)
{
	if (node < CANLINK_NODE_MIN || node > CANLINK_NODE_MAX)
		return VC_E_ARG;
	can_ctx_t *k = calloc(1, sizeof(*k));
	if (!k)
		return VC_E_LINK;
	k->c = c;
	k->bus = *bus;
	k->node = (uint8_t)node;
	if (seq0 >= 0) {
		k->seq = (uint8_t)(seq0 - 1);
	} else {
		struct timespec ts;
		clock_gettime(CLOCK_MONOTONIC, &ts);
		/* A restarted host should not repeat its predecessor's last
		 * sequence number, which the unit would take for a retry. */
		k->seq = (uint8_t)((unsigned long)ts.tv_nsec ^ (unsigned long)getpid());
	}
	canlink_rx_init(&k->rx, k->rx_buf, sizeof(k->rx_buf));
	vc_transport_t t = {.exchange = can_exchange, .close = can_close, .ctx = k, .name = "can"};
	vc_init(c, &t);
	return VC_OK;
}

int vc_can_status(vc_client_t *c, canlink_status_t *st, unsigned timeout_ms)
{
	if (c->t.exchange != can_exchange)
		return VC_E_UNSUPPORTED;
	can_ctx_t *k = c->t.ctx;
	uint32_t t0 = k->bus.now_ms(k->bus.ctx);

	k->st_fresh = false;
	for (;;) {
		canlink_frame_t f;
		int r = next_frame(k, t0, timeout_ms, &f);
		if (r != VC_OK)
			return r;
		take_status(k, &f);
		if (k->st_fresh) {
			*st = k->st_last;
			return VC_OK;
		}
	}
}

int vc_can_stats(vc_client_t *c, vc_can_stats_t *st)
{
	if (c->t.exchange != can_exchange)
		return VC_E_UNSUPPORTED;
	*st = ((can_ctx_t *)c->t.ctx)->stats;
	return VC_OK;
}

/* ---- SocketCAN bus ----------------------------------------------------- */

static uint32_t mono_ms(void *ctx)
{
	struct timespec ts;

	(void)ctx;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (uint32_t)((uint64_t)ts.tv_sec * 1000u + (uint64_t)ts.tv_nsec / 1000000u);
}

static int sock_send(void *ctx, const canlink_frame_t *f)
{
	sockcan_t *s = ctx;

	/* A full transmit queue drains in microseconds on a live bus; give it
	 * a bounded number of short waits, then call the link failed. */
	for (int i = 0; i < 200; i++) {
		int r = sockcan_send(s, f);
		if (r > 0)
			return VC_OK;
		if (r < 0)
			return VC_E_LINK;
		struct timespec ts = {0, 1000000};
		nanosleep(&ts, NULL);
	}
	return VC_E_LINK;
}

static int sock_recv(void *ctx, canlink_frame_t *f, unsigned timeout_ms)
{
	sockcan_t *s = ctx;
	int r = sockcan_recv(s, f);

	if (r != 0)
		return r > 0 ? 1 : VC_E_LINK;
	r = sockcan_wait(s, timeout_ms > 60000 ? 60000 : (int)timeout_ms);
	if (r < 0)
		return VC_E_LINK;
	if (r == 0)
		return 0;
	r = sockcan_recv(s, f);
	return r > 0 ? 1 : r == 0 ? 0 : VC_E_LINK;
}

static void sock_close(void *ctx)
{
	sockcan_close(ctx);
	free(ctx);
}

int vc_open_can(vc_client_t *c, const char *iface, unsigned node)
{
	if (node < CANLINK_NODE_MIN || node > CANLINK_NODE_MAX) {
		errno = EINVAL;
		return VC_E_LINK;
	}
	sockcan_t *s = malloc(sizeof(*s));
	if (!s)
		return VC_E_LINK;
	uint32_t ids[6] = {CANLINK_ID_RESPONSE + node, CANLINK_ID_STATUS_A + node,
			   CANLINK_ID_STATUS_B + node, CANLINK_ID_STATUS_C + node,
			   CANLINK_ID_STATUS_D + node, CANLINK_ID_STATUS_E + node};
	if (sockcan_open(s, iface, ids, 6) < 0) {
		int e = errno;
		free(s);
		errno = e;
		return VC_E_LINK;
	}
	vc_can_bus_t bus = {
	    .send = sock_send, .recv = sock_recv, .now_ms = mono_ms, .close = sock_close, .ctx = s};
	int r = vc_attach_can(c, &bus, node, -1);
	if (r != VC_OK)
		sock_close(s);
	return r;
}
