/* Stateful fuzz target: random sequences of the 34 operations, hardware
 * events and time, on the firmware and the ideal simulated plant.
 *
 * After every control tick:
 *   - getState reports a valid code, its message matches it (Alarm-### /
 *     Warning-### name an active alarm of that type), Alarm exactly when a
 *     fault is active, never Avoid;
 *   - the commanded body velocity stays within getVelocityLimit, and while
 *     the servo stays on it changes by at most getAccelerationLimit;
 *   - under jerk limits, the motions that honour them (differential path
 *     moves, jog, joystick and continuous goals, their stops and pauses)
 *     change that acceleration by at most the jerk limit;
 *     a differential base never gets y velocity;
 *   - a fault or power off leaves every drive disabled with a zero setpoint;
 *   - a unit that came to rest stays at rest (zero command, plant pose
 *     within 2 mm / 0.5 deg) until an accepted command may move it again
 *     (move*, resume, setJoystick(true)).
 *
 * Input bytes: a sequence of actions, each an action byte and its argument
 * bytes (missing bytes read as 0). Byte 0 picks the base (bit 0: mecanum),
 * the corner planning budget (bits 1-2; 0: whole passes) and jerk limits
 * (bit 3: 5000 mm/s^3 and 3000 deg/s^3, moves at 2000 and 1000).
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../../host_sim/sim.h"

#define MAX_ACTIONS 96
#define MAX_TICKS   20000 /* per input: 20 s at 1 kHz */

typedef struct {
	const uint8_t *p;
	size_t n, i;
} rd_t;

static uint8_t u8(rd_t *r)
{
	return r->i < r->n ? r->p[r->i++] : 0;
}

static uint32_t u32(rd_t *r)
{
	uint32_t v = 0;
	for (int k = 0; k < 4; k++)
		v = v << 8 | u8(r);
	return v;
}

/* Doubles: mostly values near the edges that matter, sometimes raw bits. */
static double dbl(rd_t *r)
{
	static const double tab[] = {
	    0.0,       -0.0,	1.0,	-1.0,	 0.5,	  10.0,	    -10.0,   45.0,     90.0,
	    -90.0,     100.0,	-100.0, 179.9,	 180.0,	  180.001,  -180.0,  200.0,    360.0,
	    -360.0,    499.9,	500.0,	999.999, 1000.0,  1000.001, -1000.0, 1e-9,     5e-324,
	    36000.0,   36000.1, 1e6,	-1e6,	 1e6 + 1, 1e300,    -1e300,  NAN,      INFINITY,
	    -INFINITY, 3.0,	2000.0, -2000.0, 0.001,	  250.0,    720.0,   100000.0, 100001.0,
	};
	uint8_t k = u8(r);
	if (k < sizeof tab / sizeof tab[0])
		return tab[k];
	if (k < 200)
		return (double)(int8_t)u8(r) * 25.0; /* -3200 .. 3175 in steps */
	double d;
	uint64_t b = (uint64_t)u32(r) << 32 | u32(r);
	memcpy(&d, &b, sizeof d);
	return d;
}

static sim_t S;
static bool armed; /* a command may be moving the unit */
static double rest_x, rest_y, rest_th;
static bool have_rest;
static fx_twist_t prev_cmd, prev_acc;
static unsigned jerk_run;    /* ticks in a row that the jerk bound holds over */
static double prev_world[2]; /* previous commanded translation, world frame */
static bool prev_servo;
/* A frozen encoder was injected: the wheel loop then drives that wheel
 * until 203/204 stop it, so a resting unit may move by up to the
 * following-error limit (docs/faults.md). */
static bool encoder_frozen;

static bool twist_zero(const fx_twist_t *t)
{
	return t->vx_pt == 0 && t->vy_pt == 0 && t->w_pt == 0;
}

static void check_state(void)
{
	vehicle_t *v = &S.vehicle;
	int16_t st = 0;
	char msg[VS_STATE_MSG_MAX];
	char want[VS_STATE_MSG_MAX + 8];

	vs_getState(v, &st, msg);
	if (memchr(msg, 0, sizeof msg) == NULL)
		abort();
	const vs_alarm_t *f = alarm_newest(&v->alarms, VS_ALARM_FAULT);
	const vs_alarm_t *w = alarm_newest(&v->alarms, VS_ALARM_WARNING);
	if ((st == VS_STATE_ALARM) != (f != NULL))
		abort();
	switch (st) {
	case VS_STATE_READY:
		snprintf(want, sizeof want, "Ready");
		break;
	case VS_STATE_BUSY:
		snprintf(want, sizeof want, "Busy");
		break;
	case VS_STATE_WARNING:
		if (!w)
			abort();
		snprintf(want, sizeof want, "Warning-%03u", (unsigned)w->code);
		break;
	case VS_STATE_ALARM:
		snprintf(want, sizeof want, "Alarm-%03u", (unsigned)f->code);
		break;
	case VS_STATE_STUCK:
		snprintf(want, sizeof want, "Stuck");
		break;
	case VS_STATE_PAUSED:
		snprintf(want, sizeof want, "Paused");
		break;
	case VS_STATE_LOCKED:
		snprintf(want, sizeof want, "Locked");
		break;
	case VS_STATE_POWERED:
		snprintf(want, sizeof want, "Powered");
		break;
	case VS_STATE_UNPOWERED:
		snprintf(want, sizeof want, "Unpowered");
		break;
	default:
		abort(); /* Avoid or an invalid code */
	}
	if (strcmp(msg, want) != 0)
		abort();
	for (unsigned i = 0; i < v->alarms.n; i++) {
		uint32_t c = v->alarms.a[i].code;
		if (!((c >= 110 && c <= 155) || (c >= 201 && c <= 212)) ||
		    v->alarms.a[i].type != (uint8_t)alarm_type_of(c) ||
		    !memchr(v->alarms.a[i].source, 0, VS_ALARM_SOURCE_MAX))
			abort();
	}
}

/* Whether the tick just run is one of a motion that honours the jerk
 * limits (or rest): moves on the jerk-limited profile (lim_j) on a
 * differential base, and the velocity modes with a jerk set (their stops
 * reach the acceleration limit at the jerk limit). */
static bool jerk_applies(const vehicle_t *v, const fx_twist_t *t)
{
	const motion_t *m = &v->motion;
	if (!v->servo || alarm_any_fault(&v->alarms) || m->jmax_t_pt3 == 0)
		return false;
	switch (motion_mode(m)) {
	case MODE_IDLE:
		return twist_zero(t);
	case MODE_PATH:
		return S.cfg.kinematics == VS_KIN_DIFF && (m->lim_j > 0 || twist_zero(t));
	case MODE_JOG:
	case MODE_JOYSTICK:
	case MODE_CONTINUOUS:
		return m->j_t_pt3 > 0 && m->j_r_pt3 > 0;
	default:
		return false;
	}
}

/* The mode the tick began in (an action between two ticks may have
 * switched it): a tick counts only when that mode honours the jerk too. */
static uint8_t mode_pre;
static bool jerk_set_pre; /* both jerks set when the tick began ($jerk between) */
static int corner_recent;

static void check_jerk(const vehicle_t *v, const fx_twist_t *t)
{
	const motion_t *m = &v->motion;
	fx_twist_t acc = {t->vx_pt - prev_cmd.vx_pt, t->vy_pt - prev_cmd.vy_pt,
			  t->w_pt - prev_cmd.w_pt};
	bool vel_mode =
	    mode_pre == MODE_JOG || mode_pre == MODE_JOYSTICK || mode_pre == MODE_CONTINUOUS;
	bool pre_ok = mode_pre == MODE_IDLE || (vel_mode && jerk_set_pre) ||
		      (mode_pre == MODE_PATH && S.cfg.kinematics == VS_KIN_DIFF);
	bool applies = jerk_applies(v, t) && prev_servo && pre_ok;
	/* The set jerk while moving, the limit while braking: the larger
	 * bounds both. 16 raw units of slack, as for the acceleration. */
	double jt = (double)fx_max64(m->j_t_pt3, m->jmax_t_pt3) + 16;
	double jr = (double)fx_max64(m->j_r_pt3, m->jmax_r_pt3) + 16;
	/* A cruise corner's rotation is its clothoid's (the issue leaves it
	 * so): its rate's slope steps where the corner begins, turns and
	 * ends. On the differential base a line turns only where a corner
	 * shorter than a step is crossed within the tick, so the ticks of a
	 * line or a corner and the two after them are exempt on the rotation
	 * axis alone (turns and arcs are not). */
	corner_recent =
	    motion_mode(m) == MODE_PATH && (m->seg.kind == SEG_CORNER || m->seg.kind == SEG_LINE)
		? 3
	    : corner_recent ? corner_recent - 1
			    : 0;
	if (corner_recent)
		jr = INFINITY;
	if (applies && jerk_run >= 2 &&
	    (fabs((double)(acc.vx_pt - prev_acc.vx_pt)) > jt ||
	     fabs((double)(acc.vy_pt - prev_acc.vy_pt)) > jt ||
	     fabs((double)(acc.w_pt - prev_acc.w_pt)) > jr))
		abort(); /* jerk limit */
	jerk_run = applies ? jerk_run + 1 : 0;
	prev_acc = acc;
}

static void check_tick(void)
{
	vehicle_t *v = &S.vehicle;
	const vs_config_t *c = &S.cfg;
	const fx_twist_t *t = &v->cmd;
	double hz = c->tick_hz, q = 4294967296.0;
	/* One Q32 LSB of slack for the conversions. */
	double vt = c->vel_limit_t_mm_s / hz * q + 2, vr = c->vel_limit_r_deg_s / hz * q + 2;
	double at = c->acc_limit_t_mm_s2 / hz / hz * q + 2;
	double ar = c->acc_limit_r_deg_s2 / hz / hz * q + 2;

	check_state();
	if (fabs((double)t->vx_pt) > vt || fabs((double)t->vy_pt) > vt ||
	    fabs((double)t->w_pt) > vr)
		abort(); /* velocity limit */
	if (c->kinematics == VS_KIN_DIFF && t->vy_pt != 0)
		abort();
	/* The commanded translation changes by at most the limit in the frame
	 * it is commanded in: the world for path moves (a mecanum base that
	 * turns while it translates changes its body-frame components by
	 * v * w at constant world velocity), the vehicle for jog, joystick and
	 * continuous moves (a turning jog is an arc: its centripetal v * w is
	 * not a change of the command). Either frame's bound is accepted. The
	 * twist comes from Q30 trigonometry, so 16 raw units (4e-9 mm/tick^2,
	 * no physical meaning) of slack. */
	/* The twist is taken at the tick's midpoint heading. */
	double th = ((double)v->motion.ref.th_deg - (double)t->w_pt / 2) / q * M_PI / 180.0;
	double wx = (double)t->vx_pt * cos(th) - (double)t->vy_pt * sin(th);
	double wy = (double)t->vx_pt * sin(th) + (double)t->vy_pt * cos(th);
	bool omni = c->kinematics == VS_KIN_OMNI;
	/* Mecanum: the body twist is derived through Q30 trigonometry from
	 * world poses (and re-expressed through setPosition), which shows as up
	 * to a few 1e-4 of the limit on single ticks; the spec's bound is 1 %.
	 * The differential reference base is held exactly (below). */
	double at_omni = at * 1.01;
	bool trans_over = omni ? hypot(wx - prev_world[0], wy - prev_world[1]) > at_omni &&
				     hypot((double)(t->vx_pt - prev_cmd.vx_pt),
					   (double)(t->vy_pt - prev_cmd.vy_pt)) > at_omni
			       : fabs((double)(t->vx_pt - prev_cmd.vx_pt)) > at;
	/* Rotation: exact to 16 raw units on the differential base; a mecanum
	 * line that turns as it goes interpolates its heading in Q32 fractions
	 * of the line, steps of up to 2e-4 of the limit: the spec's 1 %. */
	double ar_lim = omni ? ar * 1.01 : ar + 16;
	if (prev_servo && v->servo &&
	    (trans_over || fabs((double)(t->w_pt - prev_cmd.w_pt)) > ar_lim)) {
		fprintf(stderr,
			"fuzz_ops: tick %u, mode %d: acceleration over the limit (translation %s, "
			"rotation change %.0f raw against %.0f)\n",
			v->ticks, v->motion.mode, trans_over ? "over" : "within",
			fabs((double)(t->w_pt - prev_cmd.w_pt)), ar_lim);
		abort(); /* acceleration limit */
	}
	check_jerk(v, t);
	prev_world[0] = wx;
	prev_world[1] = wy;
	if (alarm_any_fault(&v->alarms) || !v->powered) {
		if (v->servo)
			abort();
		for (uint8_t i = 0; i < S.plant.n; i++)
			if (S.plant.w[i].enable_cmd || S.plant.w[i].setpoint_q8 != 0)
				abort();
	}
	if (!v->powered && S.plant.relay_cmd)
		abort();

	/* At rest with nothing pending: disarm and remember where. */
	if (armed && !motion_has_work(&v->motion) && motion_mode(&v->motion) == MODE_IDLE &&
	    twist_zero(t) && !v->joystick_on) {
		armed = false;
		have_rest = false;
	}
	if (!armed) {
		if (!twist_zero(t))
			abort(); /* moving without a command */
		double x, y, pth;
		plant_pose(&S.plant, &x, &y, &pth);
		if (!have_rest) {
			rest_x = x, rest_y = y, rest_th = pth;
			have_rest = true;
		}
		double dth = fabs(pth - rest_th);
		if (dth > 180.0)
			dth = 360.0 - dth;
		double lim_mm = encoder_frozen ? c->following_error_mm * 1.5 + 2.0 : 2.0;
		double lim_deg = encoder_frozen ? 45.0 : 0.5;
		if (hypot(x - rest_x, y - rest_y) > lim_mm || dth > lim_deg)
			abort(); /* drifted without a command */
	}
	prev_cmd = *t;
	prev_servo = v->servo;
}

/* Corner planning spread over idle calls, as on the Cortex-M board: one
 * call between two ticks, so a pass can outlive several (0: off). */
static uint8_t plan_budget;

static void tick(void)
{
	if (plan_budget)
		vehicle_plan_idle(&S.vehicle);
	mode_pre = motion_mode(&S.vehicle.motion);
	jerk_set_pre = S.vehicle.motion.j_t_pt3 > 0 && S.vehicle.motion.j_r_pt3 > 0;
	sim_tick(&S);
	check_tick();
}

static bool act(rd_t *r, unsigned *ticks)
{
	vehicle_t *v = &S.vehicle;
	plant_t *pl = &S.plant;
	uint8_t a = u8(r);
	bool moved = false;

	switch (a % 48) {
	case 0:
		vs_clearAlarm(v);
		break;
	case 1: {
		int16_t n = (int16_t)(u8(r) % 20) - 2, na;
		vs_alarm_t al[20];
		uint16_t len = 0;
		vs_getActiveAlarm(v, n, &na, al, &len);
		if (len > 20 || (n >= 0 && len > n) || na != v->alarms.n)
			abort();
		break;
	}
	case 2: {
		uint32_t in = 0;
		vs_getInput(v, u8(r) % 12, &in);
		break;
	}
	case 3: {
		bool st;
		vs_getServoStatus(v, u8(r) % 6, &st);
		break;
	}
	case 4: {
		vs_position_t p;
		vs_getPosition(v, &p);
		if (!isfinite(p.x) || !isfinite(p.y) || !(p.theta > -180.0 && p.theta <= 180.0))
			abort();
		break;
	}
	case 5: {
		vs_point_t c = {dbl(r), dbl(r)};
		moved = vs_moveCircularRel(v, c, dbl(r));
		break;
	}
	case 6: {
		vs_position_t p = {dbl(r), dbl(r), dbl(r)};
		moved = vs_moveContinuousRel(v, p);
		break;
	}
	case 7: {
		vs_point_t c = {dbl(r), dbl(r)};
		moved = vs_moveCruiseAbs(v, c);
		break;
	}
	case 8:
		moved = vs_moveForward(v, dbl(r));
		break;
	case 9:
	case 10: {
		double x = dbl(r), y = dbl(r), w = dbl(r);
		moved = vs_moveJog(v, x, y, w);
		break;
	}
	case 11: {
		vs_position_t p = {dbl(r), dbl(r), dbl(r)};
		moved = vs_moveLinearAbs(v, p);
		break;
	}
	case 12: {
		vs_position_t p = {dbl(r), dbl(r), dbl(r)};
		moved = vs_moveLinearRel(v, p);
		break;
	}
	case 13:
		moved = vs_moveTurn(v, dbl(r));
		break;
	case 14:
		vs_pause(v);
		break;
	case 15:
		vs_resume(v);
		moved = true;
		break;
	case 16: {
		vs_velocity_t acc = {dbl(r), dbl(r)};
		vs_setAcceleration(v, acc);
		break;
	}
	case 17:
		vs_setDigitalSensorLock(v, u8(r) & 1);
		break;
	case 18:
		vs_setJogTimeout(v, (int16_t)(u8(r) << 8 | u8(r)));
		break;
	case 19: {
		bool on = u8(r) & 1;
		vs_setJoystick(v, on);
		moved = on;
		break;
	}
	case 20:
		vs_setOutput(v, u8(r) % 12, u32(r), u32(r));
		break;
	case 21: {
		vs_position_t p = {dbl(r), dbl(r), dbl(r)};
		vs_setPosition(v, p);
		break;
	}
	case 22:
		vs_setPower(v, u8(r) & 1);
		break;
	case 23:
		vs_setServo(v, u8(r) & 1);
		break;
	case 24: {
		vs_velocity_t vel = {dbl(r), dbl(r)};
		vs_setVelocity(v, vel);
		break;
	}
	case 25:
		vs_stop(v);
		break;
	case 26:
		vs_unlock(v);
		break;
	/* hardware events */
	case 27:
		pl->contact_inject = u8(r) & 1;
		break;
	case 28:
		pl->obstacle = u8(r) & 1;
		break;
	case 29:
		pl->caution = u8(r) & 1;
		break;
	case 30:
		pl->estop = u8(r) & 1;
		break;
	case 31:
		plant_set_relay_mode(pl, (plant_relay_mode_t)(u8(r) % 3));
		break;
	case 32: {
		uint8_t ax = u8(r) % pl->n;
		switch (u8(r) % 4) {
		case 0:
			plant_drive_fault(pl, ax, (uint16_t)(u8(r) | 1));
			break;
		case 1:
			plant_drive_ok(pl, ax);
			break;
		case 2:
			plant_drive_stuck(pl, ax, true);
			encoder_frozen = true;
			break;
		default:
			plant_drive_silent(pl, ax, true);
			break;
		}
		break;
	}
	case 33:
		plant_set_battery_ocv(pl, 18.0 + (double)(u8(r) % 80) * 0.1);
		break;
	case 34: {
		bool present = u8(r) % 8 != 0;
		double x = (double)(int8_t)u8(r) / 127.0, y = (double)(int8_t)u8(r) / 127.0;
		double w = (double)(int8_t)u8(r) / 127.0;
		plant_set_joystick(pl, x, y, w, present);
		break;
	}
	case 35:
		plant_set_input(pl, u8(r) % 6, u32(r));
		break;
	case 36: /* $jerk */
		vehicle_set_jerk(v, dbl(r), dbl(r));
		break;
	/* time: most actions are ticks */
	default: {
		unsigned n = 1u + (unsigned)u8(r) * ((a & 1) ? 8u : 1u);
		for (unsigned k = 0; k < n && *ticks < MAX_TICKS; k++, (*ticks)++)
			tick();
		break;
	}
	}
	if (moved)
		armed = true;
	return *ticks < MAX_TICKS;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	vs_config_t cfg;
	plant_params_t pp;
	rd_t r = {data, size, 0};
	unsigned ticks = 0;

	vs_config_defaults(&cfg);
	uint8_t setup = u8(&r);
	if (setup & 1) {
		cfg.kinematics = VS_KIN_OMNI;
		cfg.wheel_base_mm = 400.0;
	}
	plan_budget = (setup >> 1) & 3;
	if (setup & 8) {
		cfg.jerk_limit_t_mm_s3 = 5000.0;
		cfg.jerk_limit_r_deg_s3 = 3000.0;
		cfg.jerk_default_t_mm_s3 = 2000.0;
		cfg.jerk_default_r_deg_s3 = 1000.0;
	}
	plant_params_ideal(&pp);
	plant_config_lag(&pp, &cfg);
	if (sim_init(&S, &cfg, &pp) != 0)
		abort();
	vehicle_set_plan_budget(&S.vehicle, plan_budget);
	armed = false;
	have_rest = false;
	encoder_frozen = false;
	prev_servo = false;
	prev_cmd = (fx_twist_t){0, 0, 0};
	prev_acc = (fx_twist_t){0, 0, 0};
	jerk_run = 0;
	corner_recent = 0;
	prev_world[0] = prev_world[1] = 0;
	for (unsigned k = 0; k < MAX_ACTIONS && r.i < r.n; k++) {
		bool go = act(&r, &ticks);
		/* A servo that went off between two ticks (even if switched on
		 * again) stopped the motion at once: no acceleration bound
		 * applies across that boundary. */
		if (!S.vehicle.servo)
			prev_servo = false;
		/* setPosition may have turned the world frame: the previous
		 * command, re-expressed in the frame now in force. */
		double th = ((double)S.vehicle.motion.ref.th_deg - (double)prev_cmd.w_pt / 2) /
			    4294967296.0 * M_PI / 180.0;
		prev_world[0] = (double)prev_cmd.vx_pt * cos(th) - (double)prev_cmd.vy_pt * sin(th);
		prev_world[1] = (double)prev_cmd.vx_pt * sin(th) + (double)prev_cmd.vy_pt * cos(th);
		if (!go)
			break;
	}
	/* Let the last command play out a little. */
	for (unsigned k = 0; k < 200; k++)
		tick();
	return 0;
}
