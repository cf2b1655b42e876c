/* The CAN link (see canlink.h and docs/can.md): segmentation, reassembly,
 * flow control and the status frames, for host and unit alike; the unit's
 * server is canlink_srv.c. */
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

static const uint16_t status_ids[STREAM_CAN_FRAMES] = {CANLINK_ID_STATUS_A, CANLINK_ID_STATUS_B,
						       CANLINK_ID_STATUS_C, CANLINK_ID_STATUS_D,
						       CANLINK_ID_STATUS_E};

void canlink_status_frame(const canlink_status_t *st, uint8_t node, unsigned which,
			  canlink_frame_t *f)
{
	memset(f, 0, sizeof(*f));
	f->dlc = 8;
	if (which >= STREAM_CAN_FRAMES)
		which = STREAM_CAN_FRAMES - 1u;
	f->id = status_ids[which] + node;
	stream_can_put(st, which, f->data);
}

int canlink_status_decode(const canlink_frame_t *f, uint8_t node, canlink_status_t *st)
{
	if (f->dlc != 8)
		return -1;
	for (unsigned i = 0; i < STREAM_CAN_FRAMES; i++) {
		if (f->id == status_ids[i] + (uint32_t)node) {
			stream_can_get(f->data, i, st);
			return (int)i;
		}
	}
	return -1;
}
