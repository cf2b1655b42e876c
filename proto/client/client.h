/* Host client library: every VehicleService operation as one C function, over
 * any link (framed binary serial, console text, CAN).
 *
 * Calling convention. Each vc_<op> returns a client status (VC_OK or a
 * negative VC_E_*) and hands the operation's own boolean back through *ret
 * (may be NULL). The remaining parameters follow the IDL exactly as
 * firmware/vehicle.h maps it: in arguments by value, out arguments by
 * pointer, structs as vs_* types. Strings come back as pointers into the
 * client, valid until its next call. Out parameters are written only when
 * the call returns VC_OK.
 *
 * VC_OK means the unit executed the request and answered; *ret false then
 * means the unit refused it (and raised a warning alarm), exactly as on the
 * unit itself. Any VC_E_* means the call's fate is unknown to the library
 * only for VC_E_TIMEOUT / VC_E_LINK; after VC_E_NAK the unit did not run it.
 *
 * Transports. A transport moves one request {opcode, payload} and returns
 * one response {payload} or a failure; payloads are the encodings of
 * proto/wire.h whatever the link, so the library core is link-agnostic. Each
 * transport does its own framing, sequence numbers and retries: a retry of
 * the same request reuses its sequence number, so the unit answers a repeat
 * from its cache instead of executing it twice.
 */
#ifndef CLIENT_H
#define CLIENT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "../../hal/link.h"
#include "../cmdtab.h"
#include "../bbox_wire.h"
#include "../stream.h"
#include "../wire.h"

/* Client status codes. */
enum {
	VC_OK = 0,
	VC_E_TIMEOUT = -1,     /* no answer within the timeout, after all retries */
	VC_E_NAK = -2,	       /* the unit refused the frame; reason in vc_client_t.nak */
	VC_E_CRC = -3,	       /* answers kept failing their check, after all retries */
	VC_E_LINK = -4,	       /* the port or socket failed (closed, read/write error) */
	VC_E_PROTO = -5,       /* an answer that does not fit the request (bad layout) */
	VC_E_ARG = -6,	       /* an argument that cannot be sent (string too long, ...) */
	VC_E_REMOTE = -7,      /* console link: the unit answered "error <code> ..." */
	VC_E_UNSUPPORTED = -8, /* the transport cannot do this (e.g. not built in) */
	VC_E_STOPPED = -9,     /* vc_wait_done: the unit stopped short (a fault, ...) */
	VC_E_NOT_DONE = -10,   /* vc_wait_done: still busy or paused at its timeout */
};

/* Text for a client status ("timeout", "nak", ...). */
const char *vc_strerror(int err);

#define VC_DEFAULT_TIMEOUT_MS 500
#define VC_DEFAULT_RETRIES    2
#define VC_DEFAULT_BAUD	      VS_LINK_DEFAULT_BAUD

typedef struct {
	/* Sends one request and waits for its response, retrying on timeout
	 * or a damaged answer (same sequence number) up to retries times.
	 * Returns VC_OK with the response payload (result byte + outs) in
	 * resp and *resp_len; VC_E_NAK with the reason (wire_status_t) in *nak;
	 * VC_E_REMOTE with the console error code in *nak; or another VC_E_*. */
	int (*exchange)(void *ctx, unsigned opcode, const uint8_t *req, size_t req_len,
			uint8_t *resp, size_t cap, size_t *resp_len, int *nak, unsigned timeout_ms,
			unsigned retries);
	/* Releases the transport (closes the fd it owns). May be NULL. */
	void (*close)(void *ctx);
	/* The next stream frame the unit sent (kept while waiting for
	 * answers, or read now): its payload into p (cap bytes), *len and
	 * *seq; VC_E_TIMEOUT when none came within timeout_ms. NULL: the link
	 * has no stream (console, CAN). */
	int (*stream_next)(void *ctx, uint8_t *p, size_t cap, size_t *len, uint8_t *seq,
			   unsigned timeout_ms);
	void *ctx;
	const char *name; /* "serial", "console", "can" */
} vc_transport_t;

/* Per-transport counters, for tools and tests. */
typedef struct {
	uint32_t requests, retries, timeouts, naks, crc_errors, bytes_tx, bytes_rx;
} vc_stats_t;

typedef struct {
	vc_transport_t t;
	unsigned timeout_ms;  /* per attempt */
	unsigned retries;     /* further attempts after the first */
	int nak;	      /* last NAK reason or console error code */
	vc_stats_t stats;     /* kept by the transports */
	char remote_msg[160]; /* console link: text of the last "error" reply */
	wire_store_t store;   /* strings and alarms of the last answer */
	bool stream_seen;     /* a stream frame was read since the subscription */
	uint8_t stream_seq;   /* ... and its sequence number */
	uint8_t resp[WIRE_RESP_MAX];
} vc_client_t;

/* Sets up c around a transport (defaults for timeout and retries). */
void vc_init(vc_client_t *c, const vc_transport_t *t);
void vc_close(vc_client_t *c);

/* Transports. Each returns VC_OK or VC_E_LINK (errno tells why).
 * Serial: binary frames (proto/frame.h) on a tty, raw 8N1 at baud.
 * Console: the text console (docs/console.md) on a tty, same API.
 * The *_fd forms take an open descriptor (a pty in tests); own: close it
 * with the client. baud 0 leaves the line speed alone. */
int vc_open_serial(vc_client_t *c, const char *dev, unsigned baud);
int vc_attach_serial_fd(vc_client_t *c, int fd, bool own);
int vc_open_console(vc_client_t *c, const char *dev, unsigned baud);
int vc_attach_console_fd(vc_client_t *c, int fd, bool own);
/* CAN (proto/client/client_can.c): SocketCAN interface, unit node id. */
int vc_open_can(vc_client_t *c, const char *iface, unsigned node);

/* Generic call: any table row, in[]/out[] as cmd_invoke's. out strings and
 * alarm sequences point into c->store. */
int vc_call(vc_client_t *c, const cmd_def_t *d, const cmd_value_t in[], bool *ret,
	    cmd_value_t out[]);

/* Protocol version, table checksum and operation count of the unit
 * (WIRE_OP_INFO; over the console, "$version"). */
int vc_info(vc_client_t *c, unsigned *proto_version, uint16_t *table_crc, unsigned *ops);
/* One console line run by the unit (docs/console.md: the bring-up extras,
 * $config ...), its reply line into reply (cap bytes, "" when the line gets
 * none): over frames as WIRE_OP_CONSOLE (at most 64 bytes), over the
 * console as the line itself; CAN has no such request (VC_E_NAK). VC_OK
 * whatever the reply says ("ok ..." or "error ..."); VC_E_ARG for a line
 * over 64 bytes or with a line ending. */
int vc_console_line(vc_client_t *c, const char *line, char *reply, size_t cap);

/* The telemetry stream (docs/protocol.md, "Telemetry stream"; serial
 * frames only: VC_E_UNSUPPORTED on the console and CAN). Subscribe to the
 * groups of mask (bit STREAM_G_*) every period_ms; info (may be NULL) gets
 * what the unit put in force. A set the line cannot carry: VC_E_NAK with
 * c->nak WIRE_ST_RATE (info is not written). */
typedef struct {
	uint16_t mask, period_ms, frame_bytes, min_period_ms, tick_hz;
} vc_stream_info_t;
int vc_stream_subscribe(vc_client_t *c, uint16_t mask, unsigned period_ms, vc_stream_info_t *info);
int vc_stream_unsubscribe(vc_client_t *c);
/* One sample of the stream: its sequence number, groups, the unit's tick,
 * how many frames were lost before it (a gap in the sequence numbers), and
 * the values (those of groups not in mask read 0). */
typedef struct {
	uint8_t seq;
	uint16_t mask;
	uint32_t tick;
	uint32_t lost;
	stream_sample_t v;
} vc_sample_t;
/* The next sample, waiting up to timeout_ms (VC_E_TIMEOUT); VC_E_PROTO for
 * a frame that does not decode. */
int vc_stream_next(vc_client_t *c, vc_sample_t *s, unsigned timeout_ms);

/* The black box (docs/protocol.md "Black box"; serial frames only:
 * VC_E_UNSUPPORTED on the console and CAN). vc_bbox_page: the answer for
 * the samples from index (its header in pg, its samples in s, room for
 * BBOX_PAGE); an index past the count is VC_E_NAK (WIRE_ST_VALUE).
 * vc_bbox_read: every sample, page by page, into s (room for cap), *n of
 * them; a ring still recording moves between pages (read it frozen).
 * vc_bbox_clear: empties and re-arms it. */
int vc_bbox_page(vc_client_t *c, uint16_t index, bbox_page_t *pg, bbox_sample_t *s);
int vc_bbox_read(vc_client_t *c, bbox_sample_t *s, size_t cap, size_t *n, bbox_page_t *pg);
int vc_bbox_clear(vc_client_t *c, bbox_page_t *pg);

/* The operations, in spec order. */
int vc_clearAlarm(vc_client_t *c, bool *ret);
int vc_getAccelerationLimit(vc_client_t *c, bool *ret, double *accLimitT, double *accLimitR);
/* activeAlarms has room for max(numOfAlarm, 0) entries; *len gets how many
 * were written. */
int vc_getActiveAlarm(vc_client_t *c, bool *ret, int16_t numOfAlarm, int16_t *numOfActiveAlarm,
		      vs_alarm_t *activeAlarms, uint16_t *len);
int vc_getBatteryVoltage(vc_client_t *c, bool *ret, double *voltage);
int vc_getDefaultAcceleration(vc_client_t *c, bool *ret, vs_velocity_t *defaultAccel);
int vc_getDefaultVelocity(vc_client_t *c, bool *ret, vs_velocity_t *defaultVel);
int vc_getIFVersion(vc_client_t *c, bool *ret, const char **version);
int vc_getInput(vc_client_t *c, bool *ret, uint32_t ioid, uint32_t *input);
int vc_getPosition(vc_client_t *c, bool *ret, vs_position_t *pos);
int vc_getServoStatus(vc_client_t *c, bool *ret, uint32_t axisid, bool *status);
int vc_getState(vc_client_t *c, bool *ret, int16_t *state, char msg[VS_STATE_MSG_MAX]);
int vc_getVelocityLimit(vc_client_t *c, bool *ret, double *velLimitT, double *velLimitR);
int vc_getVersion(vc_client_t *c, bool *ret, const char **ver);
int vc_moveCircularRel(vc_client_t *c, bool *ret, vs_point_t centerPoint, double theta);
int vc_moveContinuousRel(vc_client_t *c, bool *ret, vs_position_t pos);
int vc_moveCruiseAbs(vc_client_t *c, bool *ret, vs_point_t cruisePoint);
int vc_moveForward(vc_client_t *c, bool *ret, double x_);
int vc_moveJog(vc_client_t *c, bool *ret, double xVel, double yVel, double thetaVel);
int vc_moveLinearAbs(vc_client_t *c, bool *ret, vs_position_t pos);
int vc_moveLinearRel(vc_client_t *c, bool *ret, vs_position_t pos);
int vc_moveTurn(vc_client_t *c, bool *ret, double theta_);
int vc_pause(vc_client_t *c, bool *ret);
int vc_resume(vc_client_t *c, bool *ret);
int vc_setAcceleration(vc_client_t *c, bool *ret, vs_velocity_t accel);
int vc_setDigitalSensorLock(vc_client_t *c, bool *ret, bool OnOff);
int vc_setJogTimeout(vc_client_t *c, bool *ret, int16_t timeout);
int vc_setJoystick(vc_client_t *c, bool *ret, bool OnOff);
int vc_setOutput(vc_client_t *c, bool *ret, uint32_t ioid, uint32_t output, uint32_t mask);
int vc_setPosition(vc_client_t *c, bool *ret, vs_position_t pos);
int vc_setPower(vc_client_t *c, bool *ret, bool OnOff);
int vc_setServo(vc_client_t *c, bool *ret, bool OnOff);
int vc_setVelocity(vc_client_t *c, bool *ret, vs_velocity_t vel);
int vc_stop(vc_client_t *c, bool *ret);
int vc_unlock(vc_client_t *c, bool *ret);

/* Waiting for motion to be done (spec 6.9, docs/console.md "Waiting for a
 * motion"). A warning from any refused request stays until clearAlarm, so an
 * idle unit answers Warning-### as well as Ready: both are done.
 *   done (VC_OK)            16 Ready, 18 Warning-###
 *   stopped (VC_E_STOPPED)  19 Alarm-### (a fault), 20 Stuck, 23 Locked,
 *                           24 Powered, 25 Unpowered: the motion cannot end
 *                           where it was going without the host
 *   not yet                 17 Busy, 21 Paused, 22 Avoid, any other code
 * vc_wait_done polls getState every VC_WAIT_POLL_MS (which also feeds the
 * link watchdog) until done or stopped, or VC_E_NOT_DONE once timeout_ms
 * has passed; a link failure returns its VC_E_*. state and msg (either may
 * be NULL) get the last state read. */
#define VC_WAIT_POLL_MS 20
bool vc_state_done(int16_t state);
bool vc_state_stopped(int16_t state);
int vc_wait_done(vc_client_t *c, unsigned timeout_ms, int16_t *state, char msg[VS_STATE_MSG_MAX]);

#endif
