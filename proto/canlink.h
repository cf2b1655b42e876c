/* The CAN link: VehicleService requests and responses, and the periodic
 * status frames, over classic CAN (11-bit identifiers, up to 8 data bytes).
 * docs/can.md is the reference for everything on the bus.
 *
 * Portable: no sockets and no clock here. The port hands every received
 * frame to canlink_rx() and calls canlink_poll() once per control tick with
 * the same free-running microsecond clock the firmware gets; frames go out
 * through a send callback that may refuse a frame (transmit queue full), in
 * which case the link retries on the next poll and never waits.
 *
 * Identifiers (node id N, 1..127):
 *   0x180+N  status A   unit -> host   state, alarm count, counter, battery, vx
 *   0x280+N  status B   unit -> host   pose x, y
 *   0x380+N  status C   unit -> host   pose theta, vy, rotation speed
 *   0x480+N  status D   unit -> host   measured speeds, queue, newest alarm type
 *   0x680+N  status E   unit -> host   newest alarm code, inputs, outputs
 *   (the status group's layout: stream.def, the serial stream's values)
 *   0x580+N  response   unit -> host   segmented message
 *   0x600+N  request    host -> unit   segmented message
 *
 * Messages (before segmentation):
 *   request  = seq u8, opcode u8, request payload  (proto/wire.h)
 *   response = seq u8, opcode u8, status u8 (wire_status_t), and when the
 *              status is WIRE_ST_OK the response payload (result + outs)
 *
 * Segmentation: ISO 15765-2 (ISO-TP), normal addressing, classic CAN:
 *   single      data[0] = 0x00 | len (1..7), data[1..len] = the message
 *   first       data[0] = 0x10 | len >> 8, data[1] = len & 0xFF (len 8..4095),
 *               data[2..7] = message bytes 0..5; DLC 8
 *   consecutive data[0] = 0x20 | index (1, 2, ... 15, 0, 1, ...),
 *               data[1..7] = the next 7 bytes; DLC 8 except the last frame
 *   flow        data[0] = 0x30 | status (0 go on, 1 wait, 2 overflow),
 *               data[1] = block size (0: no limit), data[2] = STmin; DLC 3
 * Bytes past the message in a single or last consecutive frame are padding.
 * The receiver of a first frame answers with a flow control frame on its own
 * identifier (the unit: 0x580+N, always "go on, block size 0, STmin 0"); the
 * sender of a first frame waits for it, then sends consecutive frames in
 * blocks of the block size, at least STmin apart.
 */
#ifndef CANLINK_H
#define CANLINK_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "../firmware/vehicle.h"
#include "../hal/link.h"
#include "stream.h"
#include "wire.h"

/* Identifier bases; the node id is added. */
#define CANLINK_ID_STATUS_A  0x180u
#define CANLINK_ID_STATUS_B  0x280u
#define CANLINK_ID_STATUS_C  0x380u
#define CANLINK_ID_STATUS_D  0x480u
#define CANLINK_ID_STATUS_E  0x680u
#define CANLINK_ID_RESPONSE  0x580u
#define CANLINK_ID_REQUEST   0x600u
#define CANLINK_NODE_MIN     1
#define CANLINK_NODE_MAX     127
#define CANLINK_NODE_DEFAULT 1

/* PCI byte (data[0]) frame types. */
#define CANLINK_PCI_SINGLE 0x00u
#define CANLINK_PCI_FIRST  0x10u
#define CANLINK_PCI_NEXT   0x20u
#define CANLINK_PCI_FLOW   0x30u

/* Flow control frames: flow status, and how long a sender waits for one
 * (ISO 15765-2 N_Bs) before it gives the message up. */
#define CANLINK_FC_CTS	      0u /* continue to send */
#define CANLINK_FC_WAIT	      1u /* wait for another flow control frame */
#define CANLINK_FC_OVFLW      2u /* too long for the receiver: give up */
#define CANLINK_FC_DLC	      3u
#define CANLINK_FC_TIMEOUT_US 1000000u

/* Message headers. */
#define CANLINK_REQ_HDR	 2 /* seq, opcode */
#define CANLINK_RESP_HDR 3 /* seq, opcode, status */
#define CANLINK_REQ_MAX	 (CANLINK_REQ_HDR + WIRE_REQ_MAX)
#define CANLINK_RESP_MAX (CANLINK_RESP_HDR + WIRE_RESP_MAX)
/* The 12-bit length of a first frame. */
#define CANLINK_MSG_LIMIT 4095u

/* A started message not completed within this time is dropped (and, on the
 * unit, answered with a WIRE_ST_TRUNCATED NAK). */
#define CANLINK_RX_TIMEOUT_US 250000u

#define CANLINK_STATUS_HZ_DEFAULT 10
#define CANLINK_STATUS_HZ_MAX	  1000

/* ---- segmentation, shared by the unit and the host --------------------- */

/* Frames a message of len bytes takes (len 1..CANLINK_MSG_LIMIT). */
size_t canlink_seg_count(size_t len);
/* Frame i (0-based) of the message, identifier id. */
void canlink_seg_frame(const uint8_t *msg, size_t len, size_t i, uint32_t id, canlink_frame_t *f);

/* Reassembly of one message stream (one identifier). */
typedef enum {
	CANLINK_RX_PENDING = 0,	   /* frame taken, message not complete */
	CANLINK_RX_DONE = 1,	   /* a message is complete in buf[0..len) */
	CANLINK_RX_FLOW = 2,	   /* a flow control frame: for the sending side,
				      the message in progress is untouched */
	CANLINK_RX_BAD_DLC = -1,   /* DLC too short for its PCI, or zero */
	CANLINK_RX_BAD_PCI = -2,   /* reserved frame type, length 0 or a first
				      frame for a message that fits a single */
	CANLINK_RX_SEQUENCE = -3,  /* consecutive frame out of order or unexpected */
	CANLINK_RX_OVERSIZE = -4,  /* first frame announces more than cap */
	CANLINK_RX_DISCARDED = -5, /* consecutive frame of a refused message */
} canlink_rx_result_t;

typedef struct {
	uint8_t *buf;
	size_t cap;
	size_t len, want;
	uint8_t next_index;
	bool active;	 /* a first frame was taken, consecutive frames expected */
	bool discarding; /* the message being sent was refused (oversize) */
	uint32_t started_us;
	uint32_t aborted; /* messages cut short by a new single or first frame */
	/* Oversize first frame: its header bytes (seq, opcode on a request). */
	uint8_t refused_head[2];
} canlink_rx_t;

void canlink_rx_init(canlink_rx_t *r, uint8_t *buf, size_t cap);
int canlink_rx_feed(canlink_rx_t *r, const canlink_frame_t *f, uint32_t now_us);
/* True when a started message has waited longer than CANLINK_RX_TIMEOUT_US;
 * it is then dropped (buf still holds its first bytes). */
bool canlink_rx_expired(canlink_rx_t *r, uint32_t now_us);

/* A flow control frame with identifier id. */
void canlink_fc_frame(uint32_t id, uint8_t status, uint8_t block_size, uint8_t stmin,
		      canlink_frame_t *f);
/* The separation time an STmin byte asks for, in microseconds: 0x00..0x7F
 * milliseconds, 0xF1..0xF9 100..900 us, reserved values 127 ms (ISO). */
uint32_t canlink_stmin_us(uint8_t stmin);

/* ---- the unit's side --------------------------------------------------- */

/* Sends one frame; false when the transmit queue cannot take it now. */
typedef bool (*canlink_send_fn)(void *ctx, const canlink_frame_t *f);

typedef struct {
	uint8_t node;	    /* CANLINK_NODE_MIN..MAX */
	uint16_t status_hz; /* status frame rate, 0 = off, up to CANLINK_STATUS_HZ_MAX */
} canlink_config_t;

/* Counters, for diagnostics and the bad-input tests. */
typedef struct {
	uint32_t rx_frames;  /* frames with the request identifier */
	uint32_t rx_foreign; /* other identifiers, ignored */
	uint32_t rx_bad_dlc;
	uint32_t rx_bad_pci;
	uint32_t rx_sequence;
	uint32_t rx_discarded;
	uint32_t rx_aborted;
	uint32_t rx_timeouts;
	uint32_t rx_oversize;
	uint32_t rx_short; /* complete message shorter than seq + opcode */
	uint32_t rx_flow;  /* flow control frames from the host */
	uint32_t fc_sent;  /* flow control frames the unit sent */
	uint32_t requests; /* operations executed */
	uint32_t replays;  /* retransmissions answered from the cache */
	uint32_t naks;	   /* responses with a non-zero status */
	uint32_t tx_frames;
	uint32_t tx_busy;	 /* send refused, retried on the next poll */
	uint32_t tx_abandoned;	 /* response not finished when the next request came */
	uint32_t tx_fc_timeouts; /* response given up: no flow control in time */
	uint32_t tx_overflow;	 /* response given up: the host said overflow */
	uint32_t status_sent;	 /* status groups sent */
	uint32_t status_dropped; /* status groups (partly) not sent: queue full */
} canlink_stats_t;

typedef struct {
	vehicle_t *v;
	canlink_config_t cfg;
	canlink_send_fn send;
	void *send_ctx;
	canlink_rx_t rx;
	uint8_t rx_buf[CANLINK_REQ_MAX];
	/* The message being sent, frame by frame: tx_buf (the last response,
	 * tx_len_last bytes) or nak_buf. */
	uint8_t tx_buf[CANLINK_RESP_MAX];
	uint8_t nak_buf[CANLINK_RESP_HDR];
	const uint8_t *tx_msg;
	size_t tx_len, tx_next, tx_count, tx_len_last;
	/* Flow control of the response: waiting for the host's frame since
	 * tx_fc_us; its block size, frames sent in the block, STmin. */
	bool tx_wait_fc, tx_cf_sent;
	uint8_t tx_bs, tx_block;
	uint32_t tx_fc_us, tx_stmin_us, tx_last_us;
	/* The flow control answer to a request's first frame, not yet sent. */
	bool fc_pending;
	uint8_t fc_status;
	/* The last executed request and its response, for retransmissions. */
	uint8_t last_req[CANLINK_REQ_MAX];
	size_t last_req_len;
	bool have_last;
	/* Status schedule. */
	uint32_t status_period_us, status_next_us;
	bool status_started;
	uint8_t status_counter;
	canlink_stats_t stats;
} canlink_t;

/* Returns 0, or -1 for an invalid node id or status rate (nothing set). */
int canlink_init(canlink_t *c, vehicle_t *v, const canlink_config_t *cfg, canlink_send_fn send,
		 void *ctx);
/* One received frame (any identifier; others are ignored). */
void canlink_rx(canlink_t *c, const canlink_frame_t *f, uint32_t now_us);
/* Once per tick: finishes a pending response, drops a stalled message,
 * sends the status frames when due. */
void canlink_poll(canlink_t *c, uint32_t now_us);

/* The status frames' content, decoded (also used by the host): the
 * telemetry sample of stream.def, whose rows place each value in a frame. */
typedef stream_sample_t canlink_status_t;

/* Fills st from the unit (what the next status group will carry). */
void canlink_status_read(vehicle_t *v, canlink_status_t *st);
/* Frames 0..4 (A..E) of a status group for node. */
void canlink_status_frame(const canlink_status_t *st, uint8_t node, unsigned which,
			  canlink_frame_t *f);
/* Decodes a status frame of node into st (only the fields that frame
 * carries). Returns 0..4 for A..E, or -1 when f is none of them. */
int canlink_status_decode(const canlink_frame_t *f, uint8_t node, canlink_status_t *st);

#endif
