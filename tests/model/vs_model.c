/* The model of VehicleService: see vs_model.h. Each rule cites the spec
 * section (VehicleService.md) or the choice in docs/states.md it encodes. */
#include "vs_model.h"

#include <math.h>
#include <string.h>

/* Alarm codes (docs/alarms.md). */
enum {
	W_BAD_ARGUMENT = 110,
	W_OVER_LIMIT = 111,
	W_KINEMATICS = 112,
	W_NOT_READY = 120,
	W_SERVO_OFF = 121,
	W_MOVING = 122,
	W_FAULT_ACTIVE = 123,
	W_LOCKED = 124,
	W_QUEUE_FULL = 125,
	W_BAD_IOID = 126,
	W_BAD_AXIS = 127,
	W_POWER_OFF = 128,
	W_PAUSED = 129,
	W_STUCK = 130,
	W_JOYSTICK = 131,
	W_POSE_LOST = 132,
	W_CONTACT = 150,
	W_OBSTACLE = 151,
	W_JOYSTICK_LOST = 152,
	W_LINK_LOST = 153,
	W_DRIVE_RESTARTED = 155,
	F_DRIVE = 201,
	F_POWER_ON = 205,
	F_POWER_LOST = 206,
	F_ESTOP = 208,
	F_NOT_ENABLED = 211,
	F_DISABLED = 212,
};

#define POS_MAX	  1e6
#define ANGLE_MAX 36000.0

void vm_init(vm_t *m, const vm_config_t *c)
{
	memset(m, 0, sizeof(*m));
	m->c = *c;
	m->jog_timeout_ms = c->jog_timeout_ms;
	m->stick_present = true;
}

/* ---- alarms (spec 5 #3: newest first; a code raised again moves to the
 * front; the list keeps the newest VM_ALARMS_MAX) ---- */

static void raise(vm_t *m, uint32_t code)
{
	unsigned i = 0;
	while (i < m->nalarm && m->alarm[i] != code)
		i++;
	if (i == m->nalarm && m->nalarm < VM_ALARMS_MAX)
		m->nalarm++;
	if (i == VM_ALARMS_MAX)
		i = VM_ALARMS_MAX - 1;
	memmove(&m->alarm[1], &m->alarm[0], i * sizeof(m->alarm[0]));
	m->alarm[0] = code;
}

static bool is_fault(uint32_t code)
{
	return code >= 200;
}

bool vm_fault(const vm_t *m)
{
	for (unsigned i = 0; i < m->nalarm; i++)
		if (is_fault(m->alarm[i]))
			return true;
	return false;
}

static bool active(const vm_t *m, uint32_t code)
{
	for (unsigned i = 0; i < m->nalarm; i++)
		if (m->alarm[i] == code)
			return true;
	return false;
}

/* ---- motion ---- */

static bool host_work(const vm_t *m)
{
	return m->nq > 0 || m->cont != VM_WORK_NONE || m->jog;
}

/* Spec 5, "Servo-on": servo on and no fault or lock (stuck too, 6.10). */
static bool can_run(const vm_t *m)
{
	return m->powered && m->servo && !m->servo_wait && !vm_fault(m) && !m->locked && !m->stuck;
}

bool vm_servo_status(const vm_t *m, unsigned axis)
{
	uint32_t b = 1u << axis;
	return m->servo && !(m->held & b) && !(m->rebooted & b);
}

static bool stick_drives(const vm_t *m)
{
	return m->joystick && m->stick_armed && m->stick_deflected && can_run(m) && !m->paused;
}

bool vm_may_move(const vm_t *m)
{
	return m->brake_left_ms > 0 || stick_drives(m) ||
	       (host_work(m) && can_run(m) && !m->paused);
}

static void drop_host_work(vm_t *m)
{
	m->nq = 0;
	m->path = m->cont = VM_WORK_NONE;
	m->jog = false;
	m->ran_ms = 0;
}

/* stop() and every stop at the limit (contact, obstacle, link loss, the
 * joystick handed over or let go): brake, discard the queue, nothing
 * resumes; the stick must come back to neutral before it drives. */
static void stop_motion(vm_t *m)
{
	/* Work held by a pause is dropped in the next tick: Busy until then. */
	if (vm_may_move(m) || host_work(m)) {
		m->brake_left_ms = m->c.brake_ms;
		m->stop_pending = true;
	}
	drop_host_work(m);
	m->paused = false;
	m->stick_armed = false;
}

/* A fault halts at once (spec 6.9): the servo goes off, nothing to brake
 * with, all work and the pause are gone. */
static void fault(vm_t *m, uint32_t code)
{
	raise(m, code);
	drop_host_work(m);
	m->paused = false;
	m->servo = false;
	m->servo_wait = false;
	m->brake_left_ms = 0;
	m->stick_armed = false;
}

static void halt(vm_t *m)
{
	drop_host_work(m);
	m->paused = false;
	m->servo = false;
	m->servo_wait = false;
	m->brake_left_ms = 0;
	m->stick_armed = false;
}

/* ---- operations ---- */

static bool finite_within(double x, double lim)
{
	return isfinite(x) && fabs(x) <= lim;
}

static unsigned refuse(vm_t *m, uint32_t code)
{
	m->refuse[m->nrefuse++] = code;
	return 1u; /* false */
}

/* 0 < x <= lim: 110 when not a number, 111 otherwise (setVelocity,
 * setAcceleration: spec 5 #24, #32). */
static uint32_t setting(double x, double lim)
{
	if (!isfinite(x))
		return W_BAD_ARGUMENT;
	return x > 0 && x <= lim ? 0 : W_OVER_LIMIT;
}

static uint32_t settings(double t, double r, double lt, double lr)
{
	uint32_t a = setting(t, lt), b = setting(r, lr);
	if (a == W_BAD_ARGUMENT || b == W_BAD_ARGUMENT)
		return W_BAD_ARGUMENT;
	return a ? a : b;
}

typedef enum { G_READY, G_SERVO, G_JOG } gate_t;

/* The state checks of a move*, in the precedence of docs/states.md:
 * fault, power, lock, obstacle, servo, joystick, then the gate's own. */
static uint32_t gate(const vm_t *m, gate_t g)
{
	if (vm_fault(m))
		return W_FAULT_ACTIVE;
	if (!m->powered)
		return W_SERVO_OFF;
	if (m->locked)
		return W_LOCKED;
	if (m->stuck)
		return W_STUCK;
	if (!m->servo)
		return W_SERVO_OFF;
	if (m->joystick)
		return W_JOYSTICK;
	/* A drive restarted: where the unit is must be said first. */
	if (m->pose_lost)
		return W_POSE_LOST;
	/* Ready-only: idle with servo on (spec 5, 6.9): not paused, no work,
	 * at rest in position. */
	if (g == G_READY && (m->paused || host_work(m) || m->brake_left_ms > 0 ||
			     m->settle_left_ms > 0 || m->servo_wait))
		return W_NOT_READY;
	if (g == G_JOG && m->paused)
		return W_PAUSED;
	return 0;
}

static bool pose_ok(const double *a)
{
	return finite_within(a[0], POS_MAX) && finite_within(a[1], POS_MAX) &&
	       finite_within(a[2], ANGLE_MAX);
}

static bool op_is(const vm_call_t *c, const char *name)
{
	return strcmp(c->op, name) == 0;
}

static unsigned expect_move(vm_t *m, const vm_call_t *c)
{
	const double *a = c->a;
	uint32_t g;
	if (op_is(c, "moveForward") || op_is(c, "moveTurn")) {
		if (!finite_within(a[0], op_is(c, "moveTurn") ? ANGLE_MAX : POS_MAX))
			return refuse(m, W_BAD_ARGUMENT);
		if ((g = gate(m, G_READY)) != 0)
			return refuse(m, g);
		return 2u;
	}
	if (op_is(c, "moveLinearRel")) {
		/* A differential base faces the point and drives to it. */
		if (!pose_ok(a))
			return refuse(m, W_BAD_ARGUMENT);
		if ((g = gate(m, G_READY)) != 0)
			return refuse(m, g);
		return 2u;
	}
	if (op_is(c, "moveCircularRel")) {
		if (!finite_within(a[0], POS_MAX) || !finite_within(a[1], POS_MAX) ||
		    !finite_within(a[2], ANGLE_MAX))
			return refuse(m, W_BAD_ARGUMENT);
		if (!m->c.omni && a[0] != 0) /* spec 5 #14 */
			return refuse(m, W_KINEMATICS);
		if ((g = gate(m, G_READY)) != 0)
			return refuse(m, g);
		return 2u;
	}
	if (op_is(c, "moveLinearAbs") || op_is(c, "moveCruiseAbs")) {
		bool lin = op_is(c, "moveLinearAbs");
		if (lin ? !pose_ok(a)
			: (!finite_within(a[0], POS_MAX) || !finite_within(a[1], POS_MAX)))
			return refuse(m, W_BAD_ARGUMENT);
		if ((g = gate(m, G_SERVO)) != 0)
			return refuse(m, g);
		if (m->nq >= m->c.queue_cap)
			return refuse(m, W_QUEUE_FULL);
		/* A stop still braking through the queue holds its places until
		 * rest (docs/states.md). */
		if (m->brake_left_ms > 0 && m->nq + 1 < m->c.queue_cap) {
			m->refuse[m->nrefuse++] = W_QUEUE_FULL;
			return 3u;
		}
		return 2u;
	}
	if (op_is(c, "moveContinuousRel")) {
		if (!pose_ok(a))
			return refuse(m, W_BAD_ARGUMENT);
		if ((g = gate(m, G_SERVO)) != 0)
			return refuse(m, g);
		/* A goal takes over a jog or a goal, not path motion (6.6 and
		 * docs/states.md). */
		if (m->nq > 0)
			return refuse(m, W_MOVING);
		/* A stop while the servo comes on completes once it is on. */
		if ((m->brake_left_ms > 0 && !host_work(m)) || m->servo_wait) {
			m->refuse[m->nrefuse++] = W_MOVING;
			return 3u;
		}
		return 2u;
	}
	if (op_is(c, "moveJog")) {
		if (!isfinite(a[0]) || !isfinite(a[1]) || !isfinite(a[2]))
			return refuse(m, W_BAD_ARGUMENT);
		/* Spec 6.6: each component within its limit. */
		if (fabs(a[0]) > m->c.vel_limit_t || fabs(a[1]) > m->c.vel_limit_t ||
		    fabs(a[2]) > m->c.vel_limit_r)
			return refuse(m, W_OVER_LIMIT);
		if (!m->c.omni && a[1] != 0)
			return refuse(m, W_KINEMATICS);
		if ((g = gate(m, G_JOG)) != 0)
			return refuse(m, g);
		if (m->nq > 0)
			return refuse(m, W_MOVING);
		/* A stop while the servo comes on completes once it is on. */
		if ((m->brake_left_ms > 0 && !host_work(m)) || m->servo_wait) {
			m->refuse[m->nrefuse++] = W_MOVING;
			return 3u;
		}
		return 2u;
	}
	return 0;
}

static bool has_id(const uint32_t *ids, unsigned n, uint32_t id)
{
	for (unsigned i = 0; i < n; i++)
		if (ids[i] == id)
			return true;
	return false;
}

unsigned vm_expect(vm_t *m, const vm_call_t *c)
{
	m->nrefuse = 0;
	if (strncmp(c->op, "move", 4) == 0)
		return expect_move(m, c);
	if (op_is(c, "getInput"))
		return has_id(m->c.in_ids, m->c.n_in, c->u) ? 2u : refuse(m, W_BAD_IOID);
	if (op_is(c, "setOutput"))
		return c->u != 0 && has_id(m->c.out_ids, m->c.n_out, c->u) ? 2u
									   : refuse(m, W_BAD_IOID);
	if (op_is(c, "getServoStatus"))
		return c->u < m->c.naxes ? 2u : refuse(m, W_BAD_AXIS);
	if (op_is(c, "setVelocity")) {
		uint32_t e = settings(c->a[0], c->a[1], m->c.vel_limit_t, m->c.vel_limit_r);
		return e ? refuse(m, e) : 2u;
	}
	if (op_is(c, "setAcceleration")) {
		uint32_t e = settings(c->a[0], c->a[1], m->c.acc_limit_t, m->c.acc_limit_r);
		if (e)
			return refuse(m, e);
		/* false while moving (Busy, Avoid), servo on's wait for the drives
		 * (Busy) included: a paused unit at rest takes it. */
		if ((host_work(m) && can_run(m) && !m->paused) || m->servo_wait)
			return refuse(m, W_MOVING);
		if (vm_may_move(m)) {
			m->refuse[m->nrefuse++] = W_MOVING;
			return 3u;
		}
		return 2u;
	}
	if (op_is(c, "setJogTimeout"))
		return c->s > 0 ? 2u : refuse(m, W_OVER_LIMIT);
	if (op_is(c, "setPosition"))
		return pose_ok(c->a) ? 2u : refuse(m, W_BAD_ARGUMENT);
	if (op_is(c, "setPower")) {
		/* Table 8's neighbour: true = done, false = powering on failed
		 * (a fault, not a refusal). */
		if (c->b && !m->powered && m->relay_fail)
			return 1u;
		return 2u;
	}
	if (op_is(c, "setServo")) {
		/* Table 8. */
		if (!m->powered)
			return refuse(m, W_POWER_OFF);
		if (c->b && !m->servo && vm_fault(m))
			return refuse(m, W_FAULT_ACTIVE);
		/* Servo on asks the drives first: a fault one reports now is
		 * raised, and servo on fails with it (no refusal warning). */
		if (c->b && !m->servo && (m->drive_latched & ~m->drive_reported))
			return 1u;
		return 2u;
	}
	/* Every other operation is "always true". */
	return 2u;
}

void vm_apply(vm_t *m, const vm_call_t *c, bool reply)
{
	const double *a = c->a;
	if (!reply) {
		if (op_is(c, "setPower"))
			fault(m, F_POWER_ON);
		if (op_is(c, "setServo") && m->nrefuse == 0)
			for (unsigned i = 0; i < m->c.naxes; i++) {
				uint32_t b = 1u << i;
				if ((m->drive_latched & b) && !(m->drive_reported & b)) {
					fault(m, F_DRIVE);
					m->drive_reported |= b;
				}
			}
		return; /* the refusal's warning: the harness raises what it saw */
	}
	if (op_is(c, "moveForward") || op_is(c, "moveTurn") || op_is(c, "moveLinearRel") ||
	    op_is(c, "moveCircularRel") || op_is(c, "moveLinearAbs") || op_is(c, "moveCruiseAbs")) {
		m->nq++;
		m->path = VM_WORK_SURE;
		m->ran_ms = 0;
		(void)a;
	} else if (op_is(c, "moveContinuousRel")) {
		m->jog = false;
		/* A goal where the unit stands (a whole turn included) may be
		 * done in the tick it is taken, paused or not. */
		bool here =
		    fabs(a[0]) < 1e-6 && fabs(a[1]) < 1e-6 && fabs(remainder(a[2], 360.0)) < 1e-6;
		m->cont = here ? VM_WORK_MAYBE : VM_WORK_SURE;
		m->ran_ms = 0;
	} else if (op_is(c, "moveJog")) {
		m->cont = VM_WORK_NONE;
		m->jog = true;
		m->jog_zero = a[0] == 0 && a[1] == 0 && a[2] == 0;
		m->jog_left_ms = m->jog_timeout_ms;
	} else if (op_is(c, "setAcceleration")) {
		double s = fmax(m->c.vel_limit_t / a[0], m->c.vel_limit_r / a[1]);
		m->c.brake_ms = (uint32_t)fmin(2000.0 * s, 1e9) + m->c.settle_ms;
	} else if (op_is(c, "clearAlarm")) {
		/* Clears every alarm and resets the drives' faults. */
		m->nalarm = 0;
		m->drive_latched = m->drive_reported = 0;
	} else if (op_is(c, "pause")) {
		/* Spec 5 #22: moving, brake then Paused; idle, Paused at once.
		 * The stick must come back to neutral after it. */
		if (vm_may_move(m))
			m->brake_left_ms = m->c.brake_ms;
		m->paused = true;
		m->stick_armed = false;
		/* A jog cannot wait for resume (as it is refused while paused,
		 * 129): the pause ends it. */
		m->jog = false;
	} else if (op_is(c, "resume")) {
		m->paused = false;
	} else if (op_is(c, "stop")) {
		stop_motion(m); /* spec 5 #33 */
	} else if (op_is(c, "setPosition")) {
		m->pose_lost = false;
	} else if (op_is(c, "unlock")) {
		m->locked = false;
	} else if (op_is(c, "setDigitalSensorLock")) {
		m->sensor_lock = c->b;
	} else if (op_is(c, "setJogTimeout")) {
		uint32_t age = m->jog_timeout_ms - m->jog_left_ms;
		m->jog_timeout_ms = (uint32_t)c->s;
		m->jog_left_ms = m->jog_timeout_ms > age ? m->jog_timeout_ms - age : 0;
	} else if (op_is(c, "setJoystick")) {
		/* Spec 5 #27 and docs/states.md: taking the joystick ends host
		 * motion like stop(); letting it go brakes to Ready; either way
		 * the stick must be seen at neutral before it drives. */
		if (c->b && !m->joystick)
			stop_motion(m);
		else if (!c->b && m->joystick) {
			if (vm_may_move(m))
				m->brake_left_ms = m->c.brake_ms;
			m->stick_armed = false;
		}
		m->joystick = c->b;
	} else if (op_is(c, "setPower")) {
		if (!c->b) {
			halt(m);
			m->powered = false;
		} else {
			m->powered = true;
		}
	} else if (op_is(c, "setServo")) {
		if (!c->b && m->servo)
			halt(m);
		else if (c->b && !m->servo) {
			/* Servo on completes when every drive reports enabled;
			 * the simulated drives do at once unless held. */
			m->servo = true;
			m->rebooted = 0;
			m->servo_wait = m->held != 0;
			m->wait_ms = 0;
		}
	}
}

void vm_refused(vm_t *m, uint32_t code)
{
	raise(m, code);
}

void vm_plant_fault(vm_t *m, uint32_t code)
{
	fault(m, code);
}

/* ---- inputs and time ---- */

void vm_input(vm_t *m, vm_input_t in, bool on)
{
	switch (in) {
	case VM_IN_CONTACT:
		m->in_contact = on;
		break;
	case VM_IN_OBSTACLE:
		m->in_obstacle = on;
		break;
	case VM_IN_ESTOP:
		m->estop = on && m->c.has_estop;
		break;
	case VM_IN_RELAY_DROP:
		m->in_drop = true;
		break;
	case VM_IN_RELAY_FAIL:
		m->relay_fail = on;
		break;
	case VM_IN_DRIVE_FAULT:
		m->drive_latched |= 1u << m->in_axis;
		break;
	case VM_IN_STICK:
		/* Let go while driving: the joystick's motion brakes. */
		if (!on && stick_drives(m))
			m->brake_left_ms = m->c.brake_ms;
		m->stick_deflected = on;
		break;
	case VM_IN_STICK_LOST:
		m->stick_present = !on;
		break;
	case VM_IN_PUSH:
		m->settle_left_ms = m->c.brake_ms;
		break;
	case VM_IN_DRIVE_HOLD:
		if (on)
			m->held |= 1u << m->in_axis;
		else
			m->held &= ~(1u << m->in_axis);
		break;
	case VM_IN_DRIVE_REBOOT:
		m->in_reboot |= 1u << m->in_axis;
		break;
	}
}

/* The inputs as one tick samples them, in the unit's order (docs/states.md):
 * drives, e-stop, main power, contact, obstacle. */
static void sample_inputs(vm_t *m)
{
	/* Each drive's fault once per occurrence, in axis order; a drive
	 * without power reports none. */
	if (!m->powered)
		m->drive_reported = 0;
	for (unsigned i = 0; i < m->c.naxes; i++) {
		uint32_t b = 1u << i;
		/* A restart: its count starts over (155), it forgot the enable
		 * and any fault; the motion stops. */
		if (m->in_reboot & b) {
			m->in_reboot &= ~b;
			m->rebooted |= b;
			m->drive_latched &= ~b;
			m->drive_reported &= ~b;
			stop_motion(m);
			m->pose_lost = true;
			raise(m, W_DRIVE_RESTARTED);
		}
		if (m->powered && (m->drive_latched & b) && !(m->drive_reported & b)) {
			fault(m, F_DRIVE);
			m->drive_reported |= b;
		}
	}
	/* Conditions that persist are raised again while present. */
	if (m->estop && !active(m, F_ESTOP))
		fault(m, F_ESTOP);
	if (m->in_drop && m->powered) {
		fault(m, F_POWER_LOST);
		m->powered = false;
	}
	m->in_drop = false;
	/* The lock takes the contact's rising edge (docs/faults.md). */
	bool c = m->in_contact && m->c.has_contact;
	if (c && !m->contact && m->sensor_lock) {
		stop_motion(m);
		m->locked = true;
		raise(m, W_CONTACT);
	}
	m->contact = c;
	/* Spec 6.10. */
	bool o = m->in_obstacle && m->c.has_obstacle;
	if (o && !m->obstacle) {
		stop_motion(m);
		m->stuck = true;
		raise(m, W_OBSTACLE);
	} else if (!o) {
		m->stuck = false;
	}
	m->obstacle = o;
	/* Servo on: waits for every drive; once on, a drive out of Operation
	 * enabled is a fault (no wheel drives alone). */
	if (m->servo && m->powered) {
		uint32_t off = m->held | m->rebooted;
		unsigned ax = 0;
		while (ax < m->c.naxes && !(off & (1u << ax)))
			ax++;
		if (m->servo_wait) {
			if (ax == m->c.naxes)
				m->servo_wait = false;
			else if (++m->wait_ms > m->c.servo_on_timeout_ms)
				fault(m, F_NOT_ENABLED);
		} else if (ax < m->c.naxes) {
			fault(m, F_DISABLED);
		}
	}
}

void vm_heard(vm_t *m)
{
	m->silent_ms = 0;
}

void vm_tick(vm_t *m)
{
	uint32_t ms = m->c.tick_us / 1000u ? m->c.tick_us / 1000u : 1u;
	m->stop_pending = false;
	sample_inputs(m);
	/* The link watchdog covers every host-commanded motion, whatever the
	 * joystick flag; a paused unit holds still (faults.md). */
	m->silent_ms += ms;
	m->wd_open = false;
	if (m->c.link_timeout_ms && m->silent_ms >= m->c.link_timeout_ms && host_work(m) &&
	    !m->paused && can_run(m)) {
		/* A jog within a tick or two of its timeout may already be
		 * braking by itself. */
		bool sure = m->path == VM_WORK_SURE || m->cont == VM_WORK_SURE ||
			    (m->jog && !m->jog_zero && m->jog_left_ms > 2);
		if (sure)
			vm_watchdog(m, true);
		else
			m->wd_open = true;
	}
	if (m->joystick) {
		if (!m->stick_present || !m->c.has_joystick) {
			stop_motion(m);
			m->joystick = false;
			raise(m, W_JOYSTICK_LOST);
		} else if (!m->stick_deflected) {
			m->stick_armed = true;
		}
	}
	if (m->jog) {
		m->jog_left_ms = m->jog_left_ms > ms ? m->jog_left_ms - ms : 0;
		if (m->jog_left_ms == 0 || m->jog_zero) {
			/* The jog's own stop (spec 5 #18). */
			m->jog = false;
			if (can_run(m))
				m->brake_left_ms = m->c.brake_ms;
		}
	}
	m->brake_left_ms = m->brake_left_ms > ms ? m->brake_left_ms - ms : 0;
	m->settle_left_ms = m->settle_left_ms > ms ? m->settle_left_ms - ms : 0;
	if (host_work(m) && can_run(m) && !m->paused) {
		m->ran_ms += ms;
		if (m->path == VM_WORK_SURE)
			m->path = VM_WORK_MAYBE;
		if (m->cont == VM_WORK_SURE)
			m->cont = VM_WORK_MAYBE;
	}
}

void vm_watchdog(vm_t *m, bool fired)
{
	m->wd_open = false;
	if (fired) {
		stop_motion(m);
		raise(m, W_LINK_LOST);
		m->silent_ms = 0;
	} else {
		/* The motion had ended: what is left is settling. */
		drop_host_work(m);
		m->brake_left_ms = m->c.brake_ms;
	}
}

/* ---- getState ---- */

static uint32_t newest(const vm_t *m, bool want_fault)
{
	for (unsigned i = 0; i < m->nalarm; i++)
		if (is_fault(m->alarm[i]) == want_fault)
			return m->alarm[i];
	return 0;
}

uint32_t vm_states(const vm_t *m, uint32_t *fault_num, uint32_t *warn_num)
{
	*fault_num = newest(m, true);
	*warn_num = newest(m, false);
	uint32_t braking = m->brake_left_ms > 0 || m->settle_left_ms > 0 ? VM_BIT(0x11) : 0;
	if (*fault_num)
		return VM_BIT(0x13);
	if (!m->powered)
		return VM_BIT(0x19);
	if (m->locked)
		return VM_BIT(0x17) | braking;
	if (m->stuck)
		return VM_BIT(0x14) | braking;
	if (!m->servo)
		return VM_BIT(0x18);
	if (m->paused)
		return VM_BIT(0x15) | braking;
	uint32_t idle = *warn_num ? VM_BIT(0x12) : VM_BIT(0x10);
	bool sure = m->path == VM_WORK_SURE || m->cont == VM_WORK_SURE ||
		    (m->jog && !m->jog_zero) || m->servo_wait;
	if (sure)
		return VM_BIT(0x11);
	bool maybe = m->nq > 0 || m->cont != VM_WORK_NONE || m->jog || braking || stick_drives(m);
	return maybe ? (idle | VM_BIT(0x11)) : idle;
}

void vm_observe(vm_t *m, int code)
{
	switch (code) {
	case 0x10:
	case 0x12:
		/* Idle: the host motion ended and the unit is at rest. */
		drop_host_work(m);
		m->brake_left_ms = 0;
		m->settle_left_ms = 0;
		break;
	case 0x15:
	case 0x14:
	case 0x17:
		/* At rest; a stop not yet taken by a tick still brakes after. */
		if (!m->stop_pending)
			m->brake_left_ms = 0;
		m->settle_left_ms = 0;
		break;
	default:
		break;
	}
}
