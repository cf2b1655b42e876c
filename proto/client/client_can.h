/* The client library's CAN transport (docs/can.md), over any frame bus:
 * SocketCAN (vc_open_can in client.h) or, for in-process tests, a bus the
 * caller provides. Status frames seen while waiting are kept, so a tool can
 * read the unit's heartbeat without a request.
 */
#ifndef CLIENT_CAN_H
#define CLIENT_CAN_H

#include <stdbool.h>

#include "../canlink.h"
#include "client.h"

typedef struct {
	/* VC_OK, or VC_E_LINK (the bus failed). A full transmit queue is
	 * waited out by the bus itself, within reason. */
	int (*send)(void *ctx, const canlink_frame_t *f);
	/* 1 with a frame, 0 when timeout_ms passed without one, VC_E_LINK. */
	int (*recv)(void *ctx, canlink_frame_t *f, unsigned timeout_ms);
	/* A millisecond clock for the timeouts (wall time, or simulated time
	 * in tests). */
	uint32_t (*now_ms)(void *ctx);
	void (*close)(void *ctx);
	void *ctx;
} vc_can_bus_t;

/* Attaches the CAN transport over bus to the unit with node id node
 * (1..127). Returns VC_OK or VC_E_ARG. The first sequence number is random
 * unless seq0 >= 0 (tests). */
int vc_attach_can(vc_client_t *c, const vc_can_bus_t *bus, unsigned node, int seq0);

/* Waits up to timeout_ms for the next complete status group (frames A, B
 * and C with the same counter window) and returns it. VC_OK, VC_E_TIMEOUT
 * or VC_E_LINK; VC_E_UNSUPPORTED when c is not a CAN client. */
int vc_can_status(vc_client_t *c, canlink_status_t *st, unsigned timeout_ms);

/* Counters of the CAN transport (frames that did not fit a response). */
typedef struct {
	uint32_t frames_tx, frames_rx, stale, bad;
} vc_can_stats_t;
int vc_can_stats(vc_client_t *c, vc_can_stats_t *st);

#endif
