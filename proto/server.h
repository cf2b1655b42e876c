/* The unit's command server: one owner for every way a host reaches the
 * unit. It holds the console (spec §7), the serial link that carries the
 * console and the binary frames on one byte stream (link.h), and the CAN
 * command link (canlink.h), each optional but the console.
 *
 * A main builds the unit, starts the server, attaches the links its
 * platform has and then runs one loop: read inputs, vehicle_tick,
 * server_poll, sleep to the next tick. The server never blocks and never
 * calls back into the main.
 *
 * The CAN link is attached from server_can.c, and the serial link that
 * server_poll serves from server_serial.c, so that a platform without CAN
 * and with its own serial loop (the Cortex-M board) links none of them.
 * Both serial servings carry the telemetry stream of stream_srv.c.
 */
#ifndef PROTO_SERVER_H
#define PROTO_SERVER_H

#include <stdbool.h>
#include <stdint.h>

#include "../firmware/vehicle.h"
#include "../hal/link.h"
#include "canlink.h"
#include "console.h"
#include "link.h"
#include "stream.h"

/* Most CAN frames taken per poll, so that a flood cannot hold up the tick;
 * the rest wait in the port (and overflow there) until the next poll. */
#define SERVER_CAN_RX_PER_POLL 256

/* The serial link served by server_poll (server_serve_serial, hosts). Each
 * poll takes requests while it has answered fewer than
 * SERVER_SERIAL_REQ_PER_POLL of them with fewer than
 * SERVER_SERIAL_TX_PER_POLL bytes, and has read fewer than
 * SERVER_SERIAL_RX_PER_POLL bytes: a flood costs a period a bounded amount
 * whatever the port's speed (the heaviest answer, getActiveAlarm's 1,116
 * bytes, costs the most: formatting and checksum). Flow control: a byte is
 * taken only while at most SERVER_SERIAL_BACKLOG bytes of answers wait for
 * the port, so a host that does not read stalls its own requests in the
 * port's buffer; nothing is executed that cannot be answered. */
#define SERVER_SERIAL_REQ_PER_POLL 8
#define SERVER_SERIAL_TX_PER_POLL  4096
#define SERVER_SERIAL_RX_PER_POLL  8192
#define SERVER_SERIAL_BACKLOG	   4096
/* The most answers one received byte can cause: it can complete a damaged
 * frame, whose bytes the receiver then reads again as lines and frames, and
 * every answer belongs to a distinct byte it holds (a line's ending, a
 * frame's sync byte): FRAME_REQ_MAX answers of at most FRAME_RESP_MAX bytes
 * (a console reply is shorter). */
#define SERVER_SERIAL_STEP_MAX ((size_t)FRAME_REQ_MAX * FRAME_RESP_MAX)
/* The answers' queue: the backlog and one step's worst on top, so an answer
 * always goes in whole (79,236 bytes of it only for damaged frames full of
 * lines). */
#define SERVER_SERIAL_TXQ (SERVER_SERIAL_BACKLOG + SERVER_SERIAL_STEP_MAX)
#define SERVER_SERIAL_IN  256 /* bytes read from the port at a time */

typedef struct vs_server vs_server_t;

typedef struct {
	uint32_t polls;	       /* polls served */
	uint32_t budget_stops; /* polls that left requests for the next one */
	uint32_t room_stops;   /* polls that stopped taking bytes: answers waited */
	uint32_t max_answers;  /* most answers one poll queued */
	uint32_t max_bytes;    /* most answer bytes one poll queued */
	uint32_t max_queued;   /* most bytes the queue held */
} server_serial_stats_t;

/* The serial service's state: the main's storage (a board that feeds its
 * link itself pays no RAM for it). */
typedef struct {
	vs_link_t io; /* the platform's port */
	uint8_t in[SERVER_SERIAL_IN];
	size_t in_at, in_len; /* read from the port, not yet taken */
	uint8_t q[SERVER_SERIAL_TXQ];
	size_t q_at, q_len;	     /* answers the port has not taken yet */
	uint32_t answers, ans_bytes; /* queued in this poll */
	bool more;		     /* the last poll left takeable bytes: poll again */
	bool blocked;		     /* ... or left them for want of the port */
	server_serial_stats_t st;
	/* The telemetry stream (stream.h): at most one of its frames waits in
	 * the queue at a time, so an answer waits behind one at most. */
	stream_sub_t sub;
	uint32_t q_put_total, q_sent_total; /* bytes into the queue, out to the port */
	uint32_t stream_end;		    /* q_put_total after the last stream frame */
} server_serial_t;

struct vs_server {
	vehicle_t *v;
	console_t con;
	link_t serial;
	/* set by server_serve_serial; its state is serial.port.io.ctx */
	void (*poll_serial)(vs_server_t *s, uint32_t now_ms);
	canlink_t *can; /* the main's storage: a board without CAN pays no RAM */
	vs_can_port_t can_port;
	uint32_t can_port_errors;			   /* receive errors the port reported */
	uint32_t last_us, us_rem, now_ms;		   /* server_poll's millisecond clock */
	void (*poll_can)(vs_server_t *s, uint32_t now_us); /* set by server_attach_can */
	console_extra_fn main_extra;			   /* the main's extras, after $bbox */
	void *main_xctx;
	/* The telemetry stream on the serial link (server_stream_init): the
	 * main's storage; NULL: none, the subscription is NAKed. */
	stream_sub_t *stream;
	console_extra_fn stream_extra; /* the console's extras after "$stream" */
	void *stream_xctx;
};

/* The console on v, its '$' extras handled first by extra (NULL: none)
 * after $bbox (the black box, bbox_wire.h).
 * Replies of lines fed straight to the console go to write (NULL: they are
 * dropped) until a serial link takes the output over. */
void server_init(vs_server_t *s, vehicle_t *v, console_extra_fn extra, void *xctx,
		 console_write_fn write, void *wctx);
/* Console and binary frames on one byte stream (link.h); the console's
 * replies go there from now on. The owner reads the port and feeds the
 * link itself (link_feed: the board, a byte at a time); server_poll does
 * not serve it. */
void server_attach_serial(vs_server_t *s, const vs_link_t *io);
/* The same, served by server_poll with the per-poll budget and flow control
 * above (server_serial.c): answers go out whole through ss's queue, in
 * order, none dropped; bytes wait in the port while the queue holds more
 * than the backlog. */
void server_serve_serial(vs_server_t *s, server_serial_t *ss, const vs_link_t *io);
/* The telemetry stream (stream.h) on the serial link, attached by either
 * call above, its subscription in sub, for a line of baud (0: STREAM_BAUD):
 * the subscription frames (WIRE_OP_STREAM) and "$stream" on the console
 * (stream_srv.c). server_serve_serial attaches it itself. */
void server_stream_init(vs_server_t *s, stream_sub_t *sub, uint32_t baud);
/* The main's side, once after each tick: when a frame (or, for "$stream",
 * a text line) is due, it goes into out (cap bytes) and its length is
 * returned, unless the last one has not left yet (busy) or the output's
 * room (its free bytes) cannot hold it: then the slot is skipped and
 * counted, its sequence number passed over, and 0 returned (0 too when
 * none is due). No answer then waits behind more than one of them. */
size_t server_stream_next(vs_server_t *s, bool busy, size_t room, uint8_t *out, size_t cap);
/* After a poll, for a main that sleeps in poll(2) between polls: bytes that
 * wait for the port to take them (wait for POLLOUT), whether the service
 * leaves received bytes until the port takes answers (do not wait for
 * POLLIN), and whether it can take more now (poll again at once). */
size_t server_serial_queued(const vs_server_t *s);
/* The serial line's speed, for the stream's budget (default STREAM_BAUD). */
void server_serial_set_baud(vs_server_t *s, uint32_t baud);
/* The stream's subscription (NULL when the serial link is not served). */
const stream_sub_t *server_serial_stream(const vs_server_t *s);
bool server_serial_blocked(const vs_server_t *s);
bool server_serial_more(const vs_server_t *s);
/* The CAN command link on port, its state in can (server_can.c). Returns
 * 0, or -1 for an invalid node id or status rate (nothing attached). */
int server_attach_can(vs_server_t *s, canlink_t *can, const vs_can_port_t *port,
		      const canlink_config_t *cfg);
/* Serves every attached link once: the serial link within its budget (if
 * served by server_serve_serial), up to SERVER_CAN_RX_PER_POLL CAN frames,
 * the timeouts and the status frames that are due. Never blocks. */
void server_poll(vs_server_t *s, uint32_t now_us);
/* The CAN link's counters as one "rx N foreign N ..." line (no newline). */
void server_can_counters(const vs_server_t *s, char *buf, size_t cap);

#endif
