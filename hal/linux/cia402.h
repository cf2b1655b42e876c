/* Wheel drives over CANopen (CiA 301 / CiA 402) on SocketCAN, profile
 * velocity mode.
 *
 * Start-up (lhal_open, before the control loop; blocking is allowed here):
 * per drive NMT "reset communication" (0x000: 82 node), then the boot-up
 * message 0x700+node (00) within boot_timeout_ms, then the configuration
 * by expedited SDO (0x600+node requests, 0x580+node replies, one at a time,
 * sdo_timeout_ms each; co_config_list() is the exact sequence: device type
 * check, controlword shutdown, velocity 0, modes of operation 3, RPDO1 and
 * TPDO1 disabled / mapped / enabled (TPDO1 carries the modes of operation
 * display 0x6061 beside statusword and position), heartbeat producer time, optionally
 * the consumer of the master's heartbeat and the profile acceleration),
 * then NMT start (0x000: 01 node), the drives' heartbeat saying operational
 * (within heartbeat_timeout_ms) and one SYNC answered by every TPDO1
 * (within sdo_timeout_ms), so that the first tick has every position. An
 * abort, a timeout or a missing boot-up fails the start with one line
 * naming the bus, node, index:subindex and the abort code with its meaning.
 *
 * Each control tick (co_bus_pre_tick, from lhal_pre_tick, never blocking):
 *   1. drain the received frames (at most CO_RX_PER_TICK): TPDO1
 *      0x180+node (statusword, position actual), heartbeat 0x700+node, EMCY
 *      0x080+node, SDO replies 0x580+node;
 *   2. heartbeat consumer and, for a drive that restarted, its
 *      configuration again (one SDO exchange per tick, non-blocking);
 *   3. send: the master's heartbeat when due (master_node set), RPDO1
 *      0x200+node per started drive (controlword, target velocity), one
 *      SYNC 0x080. RPDO1 carries the commands of the previous tick; the
 *      drives apply it at this SYNC and answer with TPDO1, read on the next
 *      tick. The target velocity is 0 unless the drive reports enabled (a
 *      drive that just reached Operation enabled starts from 0, not from a
 *      setpoint streamed while it was off). Enable operation (0x0F) is sent
 *      only while 0x6061 says profile velocity; otherwise the drive is held
 *      switched on (0x07) and the reason logged once.
 * A send the kernel cannot queue (ENOBUFS, EAGAIN) is counted and dropped;
 * the next tick sends fresh values. ENETDOWN (the interface is down) is
 * counted, logged once, and logged again when sends succeed again. Log
 * lines of the tick go through a ring to a thread of normal priority
 * (started by co_bus_open), never written from the tick.
 *
 * The drive reads fresh only while its TPDO1 arrives every tick (one since
 * the previous read), its heartbeat arrived within heartbeat_timeout_ms and
 * says operational (0x05): any other heartbeat state counts as a lost
 * drive too. The firmware's drive_timeout_ms then raises fault 202.
 * A drive that sends a boot-up message after the start (it restarted), or
 * goes from operational to pre-operational, is configured again in the
 * tick and started. One that came back without a boot-up message (e.g. its
 * own heartbeat consumer timed out) keeps counting: its 0x6064 continues,
 * and so does the count with the offset it had. One that restarted counts
 * on from the last reported value and reports position_lost on its first
 * fresh read: what the wheel travelled meanwhile is unknown.
 *
 * Reported state (co_drive_read): phase from the statusword (co_hal_phase),
 * HAL_DRIVE_NOT_OPERATIONAL while the drive is being configured again or
 * its heartbeat says stopped, pre-operational or boot-up; enabled only in
 * Operation enabled with 0x6061 = 3 and not that. Polarity reverse: the
 * velocity sent and the position read are negated here.
 *
 * Fault: the statusword says fault (or fault reaction active); the code is
 * the error code of the last EMCY with a non-zero code, CO_GENERIC_FAULT
 * (0x1000, "generic error") when none came. The code is forgotten on an
 * EMCY 0x0000 (error reset) or when the drive leaves the fault state.
 * drive_reset_fault: controlword bit 7 rises (0x0080) once the drive is in
 * fault (a drive in fault reaction is waited for) and is held while it
 * stays there, at most fault_reset_ms from the request; then it is low
 * again, so that the next request is a new rising edge. The fault code
 * reads 0 from the request until the drive leaves the fault state or the
 * bound passes.
 *
 * Units: the drive's velocity unit is counts/s (0x60FF, int32) and its
 * position unit counts (0x6064, int32): configure the drive's factor group
 * accordingly. The firmware's counts/s Q8 setpoint is rounded to the
 * nearest count/s.
 *
 * Protocol functions (co_* without a bus) are pure and tested on the host;
 * the bus functions do I/O through co_io_t (SocketCAN by default).
 */
#ifndef HAL_LINUX_CIA402_H
#define HAL_LINUX_CIA402_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "../hal.h"
#include "../posix/socketcan.h"
#include "backend_cfg.h"

/* ---- protocol ----------------------------------------------------------- */

/* Identifiers: function code, plus the node id where there is one. */
#define CO_ID_NMT	0x000u
#define CO_ID_SYNC	0x080u
#define CO_ID_EMCY	0x080u
#define CO_ID_TPDO1	0x180u
#define CO_ID_RPDO1	0x200u
#define CO_ID_SDO_REPLY 0x580u
#define CO_ID_SDO_REQ	0x600u
#define CO_ID_HEARTBEAT 0x700u

/* NMT command specifiers. */
#define CO_NMT_START	  0x01u
#define CO_NMT_STOP	  0x02u
#define CO_NMT_PREOP	  0x80u
#define CO_NMT_RESET_NODE 0x81u
#define CO_NMT_RESET_COMM 0x82u

/* Heartbeat states. */
#define CO_HB_BOOTUP	  0x00u
#define CO_HB_STOPPED	  0x04u
#define CO_HB_OPERATIONAL 0x05u
#define CO_HB_PREOP	  0x7Fu
#define CO_HB_NONE	  0xFFu /* none received since the supervision started */

/* Controlword commands. */
#define CO_CW_DISABLE_VOLTAGE 0x0000u
#define CO_CW_SHUTDOWN	      0x0006u
#define CO_CW_SWITCH_ON	      0x0007u
#define CO_CW_ENABLE_OP	      0x000Fu
#define CO_CW_FAULT_RESET     0x0080u

/* Fault code when the statusword says fault and no EMCY gave a code
 * (CiA 301 emergency code "generic error"). */
#define CO_GENERIC_FAULT 0x1000u
/* Device type 0x1000, bits 0..15: the device profile. */
#define CO_PROFILE_402		 0x0192u
#define CO_MODE_PROFILE_VELOCITY 3u
/* The default bound of the fault reset hold (<canopen fault_reset_ms>). */
#define CO_FAULT_RESET_MS 200u

/* Drive state from the statusword (CiA 402). */
typedef enum {
	CO_ST_UNKNOWN = 0, /* no statusword yet, or a bit pattern of no state */
	CO_ST_NOT_READY,
	CO_ST_SWITCH_ON_DISABLED,
	CO_ST_READY, /* ready to switch on */
	CO_ST_SWITCHED_ON,
	CO_ST_OP_ENABLED,
	CO_ST_QUICK_STOP,
	CO_ST_FAULT_REACTION,
	CO_ST_FAULT,
} co_state_t;

co_state_t co_state_of(uint16_t statusword);
const char *co_state_name(co_state_t s);
bool co_state_is_fault(co_state_t s); /* fault or fault reaction active */
/* The HAL's name of the same state (hal_drive_phase_t). */
uint8_t co_hal_phase(co_state_t s);

/* The controlword that moves a drive in state s one step toward operation
 * enabled (enable) or ready to switch on, power stage off (!enable):
 * switch on disabled -> shutdown 0x06, ready -> switch on 0x07 (or 0x06),
 * switched on / operation enabled -> enable operation 0x0F (or shutdown
 * 0x06), quick stop active -> disable voltage 0x00, fault -> 0x00, or the
 * fault reset 0x80 when reset is set. Unknown and not ready: 0x06. */
uint16_t co_controlword(co_state_t s, bool enable, bool reset);

/* Counts/s Q8 -> counts/s, rounded to nearest (half away from zero). */
int32_t co_velocity_of_q8(int32_t counts_per_s_q8);

/* Frames. */
void co_nmt_frame(canlink_frame_t *f, uint8_t cs, uint8_t node);
void co_sync_frame(canlink_frame_t *f);
void co_heartbeat_frame(canlink_frame_t *f, uint8_t node, uint8_t state);
void co_rpdo1_frame(canlink_frame_t *f, uint8_t node, uint16_t controlword, int32_t velocity);
/* TPDO1 payload: statusword, position actual, modes of operation display
 * (7 bytes). false: too short. */
bool co_tpdo1_decode(const canlink_frame_t *f, uint16_t *statusword, int32_t *position,
		     int8_t *mode);

typedef struct {
	uint16_t code;	/* emergency error code; 0: error reset / no error */
	uint8_t reg;	/* error register (0x1001) */
	uint8_t mfr[5]; /* manufacturer-specific bytes */
} co_emcy_t;
/* false: fewer than 3 bytes (missing manufacturer bytes read 0). */
bool co_emcy_decode(const canlink_frame_t *f, co_emcy_t *e);

/* One expedited SDO transfer. */
typedef struct {
	uint16_t index;
	uint8_t sub;
	uint8_t size;	/* download: 1, 2 or 4 bytes */
	bool upload;	/* read instead of write */
	uint32_t value; /* download: the value; upload: expected value & mask */
	uint32_t mask;	/* upload: bits that must equal value (0: any) */
} co_sdo_req_t;

enum {
	CO_SDO_OK = 0,	 /* *value: the uploaded value (0 for a download) */
	CO_SDO_ABORT,	 /* *value: the abort code */
	CO_SDO_NOT_OURS, /* another node, or another object's reply */
	CO_SDO_BAD,	 /* a reply this client does not speak (segmented, wrong command) */
};
void co_sdo_request_frame(canlink_frame_t *f, uint8_t node, const co_sdo_req_t *r);
int co_sdo_reply_decode(const canlink_frame_t *f, uint8_t node, const co_sdo_req_t *r,
			uint32_t *value);
/* Meaning of an SDO abort code (CiA 301), "unknown abort code" otherwise. */
const char *co_sdo_abort_text(uint32_t code);

/* Configuration sequence of one drive. */
typedef struct {
	uint16_t heartbeat_ms;	/* 0x1017 */
	uint8_t master_node;	/* 0: none; else 0x1016:01 consumes its heartbeat */
	uint16_t consumer_ms;	/* the drive's timeout for the master's heartbeat */
	uint32_t profile_accel; /* 0: not written; else 0x6083 and 0x6084 */
} co_cfg_t;
#define CO_CFG_MAX 24
unsigned co_config_list(const co_cfg_t *c, uint8_t node, co_sdo_req_t out[CO_CFG_MAX]);

/* Heartbeat consumer, on the caller's microsecond clock (wrap-safe). */
typedef struct {
	uint8_t state; /* last state received, CO_HB_NONE: none yet */
	uint32_t last_us;
} co_hb_t;
/* Supervision starts now: the timeout runs from here, no state yet. */
void co_hb_arm(co_hb_t *h, uint32_t now_us);
void co_hb_rx(co_hb_t *h, uint8_t state, uint32_t now_us);
/* Operational and heard from within timeout_us. */
bool co_hb_alive(const co_hb_t *h, uint32_t now_us, uint32_t timeout_us);

/* ---- the bus ------------------------------------------------------------ */

/* At most this many received frames handled per tick. */
#define CO_RX_PER_TICK 64
/* A configuration that failed in the tick is tried again after this. */
#define CO_RETRY_US 1000000u

/* Frame I/O: send 1 sent, 0 queue full, -1 error (errno); recv 1 frame,
 * 0 none, -1 error (errno); wait (start-up and close only) 1 readable,
 * 0 timeout, -1 error. */
typedef struct {
	int (*send)(void *ctx, const canlink_frame_t *f);
	int (*recv)(void *ctx, canlink_frame_t *f);
	int (*wait)(void *ctx, int timeout_ms);
	void *ctx;
} co_io_t;

typedef enum { CO_PHASE_IDLE = 0, CO_PHASE_CONFIG, CO_PHASE_RUN } co_phase_t;
typedef enum { CO_HBLOG_UNKNOWN = 0, CO_HBLOG_ALIVE, CO_HBLOG_LOST } co_hblog_t;

typedef struct {
	uint8_t node, axis;
	co_phase_t phase;
	/* commands of the firmware */
	bool want_enable;
	bool reverse; /* polarity reverse: setpoint and position negated */
	int32_t target_q8;
	bool reset_req; /* pending or held until reset_until_us */
	uint32_t reset_until_us;
	/* feedback */
	bool have_status;
	uint16_t status;
	co_state_t state;
	int8_t mode;	  /* modes of operation display 0x6061 */
	bool mode_logged; /* "not profile velocity" logged for this occurrence */
	int32_t raw_pos, pos, pos_offset;
	bool rebase;	   /* restarted: the next position continues from pos */
	bool lost_pending; /* restarted: position_lost on the next fresh read */
	bool tpdo_new;
	uint16_t emcy_code;
	co_hb_t hb;
	uint32_t armed_us;
	bool alive, seen_operational, booted;
	co_hblog_t hblog;
	/* configuration: cfg[0..ncfg), then NMT start */
	co_sdo_req_t cfg[CO_CFG_MAX];
	unsigned ncfg, step;
	bool sdo_pending, sdo_got;
	uint32_t sdo_sent_us, retry_at_us;
	bool fail_logged;
	canlink_frame_t sdo_rx;
	uint32_t emcy_count, restarts;
} co_drive_t;

typedef struct {
	bool used;
	unsigned index;
	bk_canopen_bus_t cfg;
	sockcan_t sock;
	co_io_t io;
	co_drive_t d[VS_MAX_AXES];
	unsigned nd;
	bool started, have_now, down;
	bool logs; /* co_bus_open started the log thread (log lines from the tick) */
	uint32_t now_us, hb_due_us;
	/* counters */
	uint32_t tx, tx_full, tx_down, tx_errors;
	uint32_t rx, rx_errors, rx_bad, emcy;
} co_bus_t;

void co_bus_init(co_bus_t *b, unsigned index, const bk_canopen_bus_t *cfg);
/* Before co_bus_start; returns the drive's index on the bus. reverse:
 * polarity reverse (setpoint and position negated by the master). */
unsigned co_bus_add(co_bus_t *b, uint8_t axis, uint8_t node, bool reverse);
/* Opens the interface (receive filters for the added drives) and uses it
 * for b->io. -1 with one line in err. */
int co_bus_open(co_bus_t *b, char *err, size_t errlen);
/* The start-up sequence above. -1 with one line in err. */
int co_bus_start(co_bus_t *b, char *err, size_t errlen);
void co_bus_pre_tick(co_bus_t *b, uint32_t now_us);
/* Started drives: shutdown and velocity 0 by SDO, the consumer of the
 * master's heartbeat off, NMT pre-operational (best effort); closes. */
void co_bus_close(co_bus_t *b);
/* "canopen0 can0 tx N tx_full N tx_down N tx_errors N rx N rx_errors N
 * emcy N" (for $rt and the exit log). */
int co_bus_counters(const co_bus_t *b, char *buf, size_t len);

void co_drive_set_velocity(co_bus_t *b, unsigned i, int32_t counts_per_s_q8);
void co_drive_enable(co_bus_t *b, unsigned i, bool on);
void co_drive_reset_fault(co_bus_t *b, unsigned i);
void co_drive_read(co_bus_t *b, unsigned i, hal_drive_state_t *st);

#endif
