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
 * The CAN link is attached from server_can.c, so that a platform without
 * CAN (the Cortex-M board) links none of it.
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

/* Most CAN frames taken per poll, so that a flood cannot hold up the tick;
 * the rest wait in the port (and overflow there) until the next poll. */
#define SERVER_CAN_RX_PER_POLL 256

typedef struct vs_server vs_server_t;

struct vs_server {
	vehicle_t *v;
	console_t con;
	link_t serial;
	bool has_serial;
	canlink_t *can; /* the main's storage: a board without CAN pays no RAM */
	vs_can_port_t can_port;
	uint32_t can_port_errors;			   /* receive errors the port reported */
	uint32_t last_us, us_rem, now_ms;		   /* server_poll's millisecond clock */
	void (*poll_can)(vs_server_t *s, uint32_t now_us); /* set by server_attach_can */
};

/* The console on v, its '$' extras handled first by extra (NULL: none).
 * Replies of lines fed straight to the console go to write (NULL: they are
 * dropped) until a serial link takes the output over. */
void server_init(vs_server_t *s, vehicle_t *v, console_extra_fn extra, void *xctx,
		 console_write_fn write, void *wctx);
/* Console and binary frames on one byte stream (link.h); the console's
 * replies go there from now on. */
void server_attach_serial(vs_server_t *s, const vs_link_t *io);
/* The CAN command link on port, its state in can (server_can.c). Returns
 * 0, or -1 for an invalid node id or status rate (nothing attached). */
int server_attach_can(vs_server_t *s, canlink_t *can, const vs_can_port_t *port,
		      const canlink_config_t *cfg);
/* Serves every attached link once: what the serial port has, up to
 * SERVER_CAN_RX_PER_POLL CAN frames, the timeouts and the status frames
 * that are due. Never blocks. */
void server_poll(vs_server_t *s, uint32_t now_us);
/* The CAN link's counters as one "rx N foreign N ..." line (no newline). */
void server_can_counters(const vs_server_t *s, char *buf, size_t cap);

#endif
