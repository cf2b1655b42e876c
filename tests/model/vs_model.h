/* An executable model of VehicleService (../shared/spec/VehicleService.md),
 * written from the specification and docs/states.md (the choices the spec
 * leaves to us), not from the firmware: the unit's states, every
 * operation's acceptance, reply and refusal code in each, and the inputs
 * that change them (joystick, contact, obstacle, e-stop, relay, drive
 * faults, link silence, pause, stop, power).
 *
 * The model does not simulate motion. What it cannot know (when a move
 * ends, when braking comes to rest) it leaves open, and the differential
 * harness (tests/model/vs_diff.c) resolves it by observation: after every
 * control tick the unit's getState is checked against the set of states
 * the model allows and then taken as the truth for those open questions
 * (vm_observe). Everything else is predicted exactly: replies, refusal
 * codes, the alarm list (codes, newest first), which states are possible,
 * and when the unit may move at all (vm_may_move).
 */
#ifndef VS_MODEL_H
#define VS_MODEL_H

#include <stdbool.h>
#include <stdint.h>

#define VM_ALARMS_MAX 16
#define VM_IO_MAX     16

/* State codes (spec section 4), as bits of a set: 1u << (code - 0x10). */
#define VM_BIT(code) (1u << ((code)-0x10))

typedef struct {
	bool omni;
	unsigned naxes;
	double vel_limit_t, vel_limit_r, acc_limit_t, acc_limit_r;
	uint32_t link_timeout_ms; /* 0: no link watchdog */
	uint32_t servo_on_timeout_ms;
	uint32_t jog_timeout_ms; /* at start-up */
	uint32_t tick_us;
	/* The longest a stop may take to come to rest and settle (from the
	 * velocity limit at the acceleration limit, plus the settle time). */
	uint32_t brake_ms;
	/* Settling after a stop (settle time, window, margin): with the set
	 * accelerations it makes brake_ms again after setAcceleration, since
	 * a jog's or the stick's own stop brakes at the set acceleration. */
	uint32_t settle_ms;
	unsigned queue_cap;
	double deadband; /* joystick, fraction of full scale */
	uint32_t in_ids[VM_IO_MAX], out_ids[VM_IO_MAX];
	unsigned n_in, n_out;
	bool has_contact, has_obstacle, has_estop, has_joystick;
} vm_config_t;

typedef enum {
	VM_WORK_NONE = 0,
	VM_WORK_SURE,  /* host motion that cannot have ended yet */
	VM_WORK_MAYBE, /* host motion that may have ended (observation tells) */
} vm_work_t;

typedef struct {
	vm_config_t c;
	/* Unit state. */
	bool powered, servo, locked, stuck, paused, joystick, sensor_lock;
	/* Host-commanded motion: path commands queued (running included), a jog
	 * (until jog_left_ms runs out: then it brakes), a continuous goal. */
	unsigned nq;
	vm_work_t path, cont;
	bool jog, jog_zero;
	uint32_t jog_left_ms, jog_timeout_ms;
	uint32_t ran_ms; /* host motion has been running this long */
	/* A stop of any kind: the unit may still be braking and settling for
	 * this long. */
	uint32_t brake_left_ms;
	/* Joystick: the stick's reading (past the deadband: deflected), and
	 * whether it may drive (armed: it was seen at neutral since the last
	 * stop, fault, pause or hand-over). */
	bool stick_present, stick_deflected, stick_armed;
	/* Inputs held, and those the next tick takes (the unit samples its
	 * inputs once per tick, in the order of docs/states.md). */
	bool contact, obstacle, estop, relay_fail;
	bool in_contact, in_obstacle, in_drop;
	uint32_t drive_latched, drive_reported; /* per axis: a fault, until clearAlarm resets it */
	uint32_t settle_left_ms;
	unsigned in_axis;
	/* Drives: power stages held off (an STO), drives that rebooted (they
	 * forgot the enable until the next setServo(true)); servo on waiting
	 * for them (wait_ms so far); a position lost to a reboot. */
	uint32_t held, rebooted, in_reboot;
	bool servo_wait, pose_lost;
	/* A stop with work to drop, before the tick that drops it. */
	bool stop_pending;
	uint32_t wait_ms; /* a push: the hold may be busy this long */
	uint32_t silent_ms;
	bool wd_open;
	/* Alarms, newest first. */
	uint32_t alarm[VM_ALARMS_MAX];
	unsigned nalarm;
	/* The refusal codes the last call may have raised (0: none). */
	uint32_t refuse[4];
	unsigned nrefuse;
} vm_t;

void vm_init(vm_t *m, const vm_config_t *c);

/* One operation: its name and its arguments as the console takes them.
 * vm_expect returns the replies the spec allows (bit 0: false, bit 1:
 * true) and leaves in m->refuse the warning codes a false reply may raise;
 * vm_apply then takes the reply the unit gave (one of those) and changes
 * the model. */
typedef struct {
	const char *op;
	double a[3];
	unsigned n;
	bool b;	    /* boolean argument */
	uint32_t u; /* integer arguments: ioid, axis */
	int32_t s;  /* short argument */
} vm_call_t;

unsigned vm_expect(vm_t *m, const vm_call_t *call);
void vm_apply(vm_t *m, const vm_call_t *call, bool reply);
/* The warning a refusal raised (one of m->refuse), or an alarm the plant's
 * physics may raise at any time (154, not in position). */
void vm_refused(vm_t *m, uint32_t code);
/* A fault the plant's physics raised (204: pushes piled up past the
 * following-error bound before the hold took them back). */
void vm_plant_fault(vm_t *m, uint32_t code);
/* The link watchdog's time came while the host motion may already have
 * ended (vm_t.wd_open): the unit's alarm list says whether it fired. */
void vm_watchdog(vm_t *m, bool fired);

/* Inputs (each takes effect at the next control tick, as the unit samples
 * them once per tick). */
typedef enum {
	VM_IN_CONTACT,	/* on / off */
	VM_IN_OBSTACLE, /* on / off */
	VM_IN_ESTOP,	/* on / off */
	VM_IN_RELAY_DROP,
	VM_IN_RELAY_FAIL,   /* on: setPower(true) fails until off (repaired) */
	VM_IN_DRIVE_FAULT,  /* on axis vm_t.in_axis */
	VM_IN_STICK,	    /* on: deflected past the deadband; off: neutral */
	VM_IN_STICK_LOST,   /* on: the joystick device is gone; off: it is back */
	VM_IN_PUSH,	    /* the base was pushed: the hold brings it back */
	VM_IN_DRIVE_HOLD,   /* on/off: vm_t.in_axis's power stage held off */
	VM_IN_DRIVE_REBOOT, /* vm_t.in_axis restarts */
} vm_input_t;
void vm_input(vm_t *m, vm_input_t in, bool on);

/* One control tick of time, with no request on the link. */
void vm_tick(vm_t *m);
/* A request arrived (any valid one, before its own effect). */
void vm_heard(vm_t *m);

/* getState: the set of codes the model allows now (VM_BIT), and the ###
 * that goes with Alarm and Warning. */
uint32_t vm_states(const vm_t *m, uint32_t *fault_num, uint32_t *warn_num);
/* The unit's state after a tick, one of vm_states: what it settles. */
void vm_observe(vm_t *m, int code);
/* The unit may be moving now (commanded motion, or braking from it). */
bool vm_may_move(const vm_t *m);
bool vm_fault(const vm_t *m);
/* getServoStatus(axis): the drive's own report. */
bool vm_servo_status(const vm_t *m, unsigned axis);

#endif
