/* The differential harness (vs_diff.h). Requests go through the console
 * exactly as a host's lines would (sim_exec: parser, link watchdog); the
 * state is observed after every tick through the interface functions
 * (vs_getState, vs_getActiveAlarm), which are not link traffic; inputs go
 * straight into the plant, as the hardware would show them. */
#include "vs_diff.h"

#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../../host_sim/sim.h"
#include "../../proto/cmdtab.h"
#include "../../proto/console.h"
#include "vs_model.h"

#define MAX_ACTIONS 120
#define MAX_TICKS   30000

static sim_t S;
static vm_t M;
static unsigned long n_actions;
/* FNV-1a over every tick's command, drive setpoints, odometry, reference
 * and mode: two builds that agree on it behaved the same, tick for tick. */
static uint64_t tick_hash;

static void hash_bytes(const void *p, size_t n)
{
	const uint8_t *b = p;
	for (size_t i = 0; i < n; i++)
		tick_hash = (tick_hash ^ b[i]) * 0x100000001b3ull;
}

typedef struct {
	const uint8_t *p;
	size_t n, i;
} rd_t;

static uint8_t u8(rd_t *r)
{
	return r->i < r->n ? r->p[r->i++] : 0;
}

/* Harness state for the invariants. */
static struct {
	char *why;
	size_t cap;
	unsigned step;
	char act[CONSOLE_LINE_MAX + 8];
	double vt_set, vr_set, vt_grace, vr_grace; /* set velocity, and the old one */
	uint32_t grace_ms;
	bool caution;
	fx_twist_t prev;
	double prev_wx, prev_wy; /* world frame, mm/s */
	bool pushed;		 /* pushed since the servo came on */
	fx_twist_t prev_acc;	 /* the last tick's change of the command */
	bool acc_valid;
	uint8_t mode_pre;
	bool prev_servo;
	double counts_per_mm;
	unsigned ticks;
} H;

static int fail(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
static int fail(const char *fmt, ...)
{
	va_list ap;
	size_t k = (size_t)snprintf(H.why, H.cap, "step %u (%s): ", H.step, H.act);
	if (k < H.cap) {
		va_start(ap, fmt);
		vsnprintf(H.why + k, H.cap - k, fmt, ap);
		va_end(ap);
	}
	return 1;
}

/* ---- observation ---- */

static void alarms_text(char *b, size_t cap, const uint32_t *a, unsigned n)
{
	size_t k = 0;
	b[0] = '\0';
	for (unsigned i = 0; i < n && k < cap; i++)
		k += (size_t)snprintf(b + k, cap - k, "%s%u", i ? "," : "", (unsigned)a[i]);
}

static unsigned unit_alarms(uint32_t *codes)
{
	const vehicle_t *v = &S.vehicle;
	for (unsigned i = 0; i < v->alarms.n; i++)
		codes[i] = v->alarms.a[i].code;
	return v->alarms.n;
}

static bool same_alarms(const vm_t *m, const uint32_t *codes, unsigned n)
{
	return n == m->nalarm && memcmp(codes, m->alarm, n * sizeof(codes[0])) == 0;
}

/* The alarm list and the state against the model; then the state settles
 * the model's open questions. */
static int observe(void)
{
	uint32_t codes[VS_ALARM_LIST_MAX];
	unsigned n = unit_alarms(codes);
	if (M.wd_open) {
		vm_t fired = M;
		vm_watchdog(&fired, true);
		vm_watchdog(&M, same_alarms(&fired, codes, n));
	}
	/* Not in position (154) is the plant's physics: the model takes it;
	 * so is a following error (204) while pushes are being taken back. */
	if (n > 0 && codes[0] == 154 && (M.nalarm == 0 || M.alarm[0] != 154))
		vm_refused(&M, 154);
	if (n > 0 && codes[0] == 204 && H.pushed && (M.nalarm == 0 || M.alarm[0] != 204))
		vm_plant_fault(&M, 204);
	if (!same_alarms(&M, codes, n)) {
		char a[128], b[128];
		alarms_text(a, sizeof a, M.alarm, M.nalarm);
		alarms_text(b, sizeof b, codes, n);
		return fail("alarms: model [%s], unit [%s]", a, b);
	}
	int16_t st;
	char msg[VS_STATE_MSG_MAX];
	vs_getState(&S.vehicle, &st, msg);
	uint32_t fnum, wnum;
	uint32_t allowed = vm_states(&M, &fnum, &wnum);
	if (st < 0x10 || st > 0x19 || !(allowed & VM_BIT(st)))
		return fail("state %s (0x%x); the model allows mask 0x%x", msg, (unsigned)st,
			    (unsigned)allowed);
	char want[24] = "";
	if (st == 0x13)
		snprintf(want, sizeof want, "Alarm-%03u", (unsigned)fnum);
	else if (st == 0x12)
		snprintf(want, sizeof want, "Warning-%03u", (unsigned)wnum);
	if (want[0] && strcmp(want, msg) != 0)
		return fail("state %s, the model says %s", msg, want);
	vm_observe(&M, st);
	return 0;
}

/* ---- invariants ---- */

static double fxd(q32_t x)
{
	return (double)x / 4294967296.0;
}

static double hyp(double a, double b)
{
	return sqrt(a * a + b * b);
}

/* DIFF_TRACE: every step; DIFF_TICKS: every tick's command too. */
static bool trace, ticks_trace;

static int invariants(void)
{
	const vehicle_t *v = &S.vehicle;
	double hz = S.cfg.tick_hz;
	fx_twist_t t = v->cmd;
	double vx = fxd(t.vx_pt) * hz, vy = fxd(t.vy_pt) * hz;
	double w = fxd(t.w_pt) * hz;
	bool rest = t.vx_pt == 0 && t.vy_pt == 0 && t.w_pt == 0;

	/* With the servo off nothing is driven (a fault's own tick still
	 * carries the command; the drives get zero). */
	if (!vm_may_move(&M) && !rest && v->servo)
		return fail("the unit moves (%.3f mm/s, %.3f mm/s, %.3f deg/s) with no motion "
			    "command in force",
			    vx, vy, w);
	/* Speed: a vector bound, in every mode. Slack: a raw unit a tick. */
	double vt_free = fmax(H.vt_set, H.grace_ms ? H.vt_grace : 0);
	double vt = vt_free;
	if (H.caution && vt > S.cfg.caution_vel_t_mm_s)
		vt = S.cfg.caution_vel_t_mm_s;
	double vr = fmax(H.vr_set, H.grace_ms ? H.vr_grace : 0);
	double slack = 1e-6 * hz;
	/* The caution cap, like a new set velocity, is reached by braking. */
	double vt_cap = H.caution && H.grace_ms ? vt_free : vt;
	if (hyp(vx, vy) > vt_cap + slack)
		return fail("translation %.3f mm/s over the bound %.3f mm/s", hyp(vx, vy), vt_cap);
	if (fabs(w) > vr + slack)
		return fail("rotation %.3f deg/s over the bound %.3f deg/s", fabs(w), vr);
	/* Acceleration: the change of the translation vector per tick, in the
	 * world frame; turning adds its centripetal part v w. */
	double th =
	    fxd(motion_ref_pose(&v->motion)->th_deg) * M_PI / 180.0 - fxd(t.w_pt) * M_PI / 360.0;
	double wx = vx * cos(th) - vy * sin(th), wy = vx * sin(th) + vy * cos(th);
	if (v->servo && H.prev_servo && !alarm_any_fault(&v->alarms)) {
		double dv = hyp(wx - H.prev_wx, wy - H.prev_wy) * hz;
		double turn = hyp(vx, vy) * fabs(w) * M_PI / 180.0;
		if (dv > S.cfg.acc_limit_t_mm_s2 + turn + 16e-6 * hz * hz)
			return fail("translation changes at %.1f mm/s^2, over the limit %.1f "
				    "(turning %.1f)",
				    dv, S.cfg.acc_limit_t_mm_s2, turn);
	}
	if (ticks_trace)
		fprintf(stderr,
			"  tick: v %.3f %.3f mm/s  w %.3f deg/s  heading %.3f deg  mode %d\n", vx,
			vy, w, fxd(motion_ref_pose(&v->motion)->th_deg), motion_mode(&v->motion));
	H.prev_wx = wx;
	H.prev_wy = wy;
	/* Jerk: in the velocity modes with jerks set, the change of the
	 * translation's acceleration (a vector, in the body frame the slew
	 * works in) within the larger of the set jerk and the limit. */
	const motion_t *mo = &v->motion;
	uint8_t mode = motion_mode(mo);
	bool vel = mode == MODE_JOG || mode == MODE_JOYSTICK || mode == MODE_CONTINUOUS;
	fx_twist_t acc = {t.vx_pt - H.prev.vx_pt, t.vy_pt - H.prev.vy_pt, t.w_pt - H.prev.w_pt};
	if (vel && H.mode_pre == mode && mo->j_t_pt3 > 0 && mo->j_r_pt3 > 0 && v->servo &&
	    H.prev_servo && H.acc_valid && !alarm_any_fault(&v->alarms)) {
		double j =
		    hyp(fxd(acc.vx_pt - H.prev_acc.vx_pt), fxd(acc.vy_pt - H.prev_acc.vy_pt));
		double lim = fxd(mo->j_t_pt3 > mo->jmax_t_pt3 ? mo->j_t_pt3 : mo->jmax_t_pt3);
		if (j > lim + 16.0 / 4294967296.0)
			return fail("translation jerk %.1f mm/s^3 over the bound %.1f mm/s^3",
				    j * hz * hz * hz, lim * hz * hz * hz);
	}
	H.acc_valid = vel;
	H.mode_pre = mode;
	H.prev_acc = acc;
	/* The position hold at rest: each wheel within the speed bound. */
	if (rest && v->servo) {
		for (unsigned i = 0; i < v->naxes; i++) {
			double mm_s = fabs((double)v->wheel_cps_q8[i] / 256.0) / H.counts_per_mm;
			if (mm_s > vt + 1.0)
				return fail("at rest, wheel %u is set to %.1f mm/s, over %.1f mm/s",
					    i, mm_s, vt);
		}
	}
	H.prev = t;
	H.prev_servo = v->servo;
	return 0;
}

static int tick(void)
{
	/* The servo off drops what a push left (servo on starts afresh). */
	if (!S.vehicle.servo)
		H.pushed = false;
	sim_tick(&S);
	vm_tick(&M);
	H.ticks++;
	const vehicle_t *v = &S.vehicle;
	uint8_t mode = motion_mode(&v->motion);
	hash_bytes(&v->cmd, sizeof v->cmd);
	hash_bytes(v->wheel_cps_q8, sizeof v->wheel_cps_q8);
	hash_bytes(&v->odom, sizeof v->odom);
	hash_bytes(motion_ref_pose(&v->motion), sizeof(fx_pose_t));
	hash_bytes(&mode, 1);
	if (H.grace_ms)
		H.grace_ms--;
	if (observe())
		return 1;
	return invariants();
}

/* ---- actions ---- */

static double arg(rd_t *r, double scale)
{
	static const double tab[] = {0.0,   1.0,    -1.0,  10.0,    -10.0,  45.0,   -90.0,
				     100.0, -100.0, 250.0, 500.0,   -500.0, 1000.0, 1e7,
				     -1e7,  36001., 180.0, 1000.01, 0.5};
	uint8_t k = u8(r);
	if (k < sizeof tab / sizeof tab[0])
		return tab[k];
	return (double)(int8_t)u8(r) * scale;
}

/* The operations a run needs most (power, servo, motion) come often. */
static const char *pick_op(uint8_t k)
{
	static const char *const often[] = {
	    "setPower",	     "setServo",      "moveForward",	   "moveJog",
	    "moveCruiseAbs", "moveLinearAbs", "moveContinuousRel", "stop",
	    "pause",	     "resume",	      "setJoystick",	   "clearAlarm"};
	if (k < 2 * sizeof often / sizeof often[0])
		return often[k / 2];
	/* The 34 operations from the command table itself. */
	return cmd_table[k % CMD_COUNT].name;
}

static int do_op(rd_t *r)
{
	vm_call_t c = {0};
	char line[CONSOLE_LINE_MAX];
	c.op = pick_op(u8(r));
	int k = snprintf(line, sizeof line, "%s", c.op);
	/* Most jogs within the limits, y only where the base has it. */
	bool sane_jog = strcmp(c.op, "moveJog") == 0 && (u8(r) & 3) != 0;
	const cmd_def_t *d = cmd_by_name(c.op);
	unsigned nd = 0;
	for (unsigned i = 0; i < d->n_in; i++) {
		switch (d->in_types[i]) {
		case CMD_T_BOOL:
			/* Power and servo mostly on. */
			c.b = (u8(r) & (strncmp(c.op, "setPower", 8) && strncmp(c.op, "setServo", 8)
					    ? 3
					    : 7)) != 0;
			k += snprintf(line + k, sizeof line - (size_t)k, " %s",
				      c.b ? "true" : "false");
			break;
		case CMD_T_DOUBLE: {
			double x = arg(r, strstr(c.op, "Jog") || strstr(c.op, "set") ? 10.0 : 25.0);
			if (sane_jog)
				x = nd == 1 && !vs_config_omni(&S.cfg) ? 0.0
				    : nd == 2			       ? fmod(x, 90.0)
								       : fmod(x, 800.0);
			if (nd < 3)
				c.a[nd++] = x;
			k += snprintf(line + k, sizeof line - (size_t)k, " %.17g", x);
			break;
		}
		case CMD_T_SHORT:
			c.s = (int16_t)((int8_t)u8(r) * 20);
			k += snprintf(line + k, sizeof line - (size_t)k, " %d", c.s);
			break;
		default: {
			uint32_t u = u8(r) % 6;
			if (i == 0)
				c.u = u;
			k += snprintf(line + k, sizeof line - (size_t)k, " %u", (unsigned)u);
			break;
		}
		}
	}
	c.n = nd;
	snprintf(H.act, sizeof H.act, "%s", line);
	/* A valid request: the watchdog restarts before it runs. */
	vm_heard(&M);
	unsigned allowed = vm_expect(&M, &c);
	char rep[CONSOLE_REPLY_MAX];
	if (!sim_exec(&S, line, rep, sizeof rep))
		return fail("no reply");
	if (trace) {
		int16_t st;
		char msg[VS_STATE_MSG_MAX];
		vs_getState(&S.vehicle, &st, msg);
		printf("  %6u ms  %-40s %-24s %s (model: nq %u brake %u)\n", H.ticks, line, rep,
		       msg, M.nq, (unsigned)M.brake_left_ms);
	}
	bool ok;
	if (strncmp(rep, "ok true", 7) == 0)
		ok = true;
	else if (strncmp(rep, "ok false", 8) == 0)
		ok = false;
	else
		return fail("reply '%s'", rep);
	if (!(allowed & (ok ? 2u : 1u)))
		return fail("reply %s, the model allows %s", ok ? "true" : "false",
			    allowed == 1   ? "false only"
			    : allowed == 2 ? "true only"
					   : "none");
	if (!ok && M.nrefuse > 0) {
		uint32_t code = S.vehicle.alarms.n ? S.vehicle.alarms.a[0].code : 0;
		bool known = false;
		for (unsigned i = 0; i < M.nrefuse; i++)
			known |= M.refuse[i] == code;
		if (!known)
			return fail("refused with warning %u, the model expects %u%s",
				    (unsigned)code, M.nrefuse ? (unsigned)M.refuse[0] : 0u,
				    M.nrefuse > 1 ? " or another" : "");
		vm_refused(&M, code);
	}
	vm_apply(&M, &c, ok);
	if (ok && strcmp(c.op, "getServoStatus") == 0) {
		bool want = vm_servo_status(&M, c.u);
		if ((strcmp(rep + 8, "true") == 0) != want)
			return fail("'%s': the model says servo %s", rep, want ? "on" : "off");
	}
	/* A new pose turns the world frame the velocity is compared in. */
	if (ok && strcmp(c.op, "setPosition") == 0)
		H.prev_servo = false;
	/* A servo off between ticks (setServo, setPower, a fault) stops the
	 * drives at once: the next command starts from rest. */
	if (!S.vehicle.servo) {
		H.prev = H.prev_acc = (fx_twist_t){0, 0, 0};
		H.prev_wx = H.prev_wy = 0;
	}
	/* A new jerk or acceleration takes effect from the next tick. */
	H.acc_valid = false;
	if (ok && strcmp(c.op, "setVelocity") == 0) {
		H.vt_grace = fmax(H.vt_set, H.grace_ms ? H.vt_grace : 0);
		H.vr_grace = fmax(H.vr_set, H.grace_ms ? H.vr_grace : 0);
		H.grace_ms = M.c.brake_ms;
		H.vt_set = c.a[0];
		H.vr_set = c.a[1];
	}
	return observe();
}

static int do_input(rd_t *r)
{
	plant_t *pl = &S.plant;
	uint8_t k = u8(r) % 16, a = u8(r);
	/* The inputs that end all motion (e-stop, relay, drive faults, a held
	 * or rebooted drive) one time in four: the rest drive the stick. */
	if ((k == 4 || k == 6 || k == 8 || k == 14 || k == 15) && (a & 0xC0))
		k = (uint8_t)(9 + (a & 1));
	switch (k) {
	case 0:
	case 1:
		pl->contact_inject = k == 0;
		vm_input(&M, VM_IN_CONTACT, k == 0);
		snprintf(H.act, sizeof H.act, "contact %s", k == 0 ? "on" : "off");
		break;
	case 2:
	case 3:
		pl->obstacle = k == 2;
		vm_input(&M, VM_IN_OBSTACLE, k == 2);
		snprintf(H.act, sizeof H.act, "obstacle %s", k == 2 ? "on" : "off");
		break;
	case 4:
	case 5:
		pl->estop = k == 4;
		vm_input(&M, VM_IN_ESTOP, k == 4);
		snprintf(H.act, sizeof H.act, "estop %s", k == 4 ? "on" : "off");
		break;
	case 6:
		plant_set_relay_mode(pl, PLANT_RELAY_DROP);
		vm_input(&M, VM_IN_RELAY_DROP, true);
		snprintf(H.act, sizeof H.act, "relay drops");
		break;
	case 7:
		/* Broken until repaired. */
		plant_set_relay_mode(pl, M.relay_fail ? PLANT_RELAY_OK : PLANT_RELAY_FAIL);
		vm_input(&M, VM_IN_RELAY_FAIL, !M.relay_fail);
		snprintf(H.act, sizeof H.act, "relay %s", M.relay_fail ? "broken" : "repaired");
		break;
	case 8: {
		uint8_t ax = (uint8_t)(a % pl->n);
		plant_drive_fault(pl, ax, 0x2310);
		M.in_axis = ax;
		vm_input(&M, VM_IN_DRIVE_FAULT, true);
		snprintf(H.act, sizeof H.act, "drive %u fault", ax);
		if (tick())
			return 1;
		plant_drive_ok(pl, ax);
		return 0;
	}
	case 9:
	case 10: {
		/* Full scale on one or two axes, or neutral. */
		double x = 0, y = 0, rr = 0;
		if (k == 9) {
			x = (a & 1) ? 1.0 : (a & 2) ? -0.7 : 0;
			y = (a & 4) ? 1.0 : 0;
			rr = (a & 8) ? -1.0 : 0;
			if (x == 0 && rr == 0 && (y == 0 || !vs_config_omni(&S.cfg)))
				x = 0.5;
		}
		plant_set_joystick(pl, x, y, rr, true);
		vm_input(&M, VM_IN_STICK_LOST, false);
		vm_input(&M, VM_IN_STICK, k == 9);
		snprintf(H.act, sizeof H.act, "stick %.1f %.1f %.1f", x, y, rr);
		break;
	}
	case 11:
		plant_set_joystick(pl, 0, 0, 0, false);
		vm_input(&M, VM_IN_STICK_LOST, true);
		vm_input(&M, VM_IN_STICK, false);
		snprintf(H.act, sizeof H.act, "joystick lost");
		break;
	case 14: {
		uint8_t ax = (uint8_t)(a % pl->n);
		bool on = !(M.held & (1u << ax));
		plant_drive_hold(pl, ax, on);
		M.in_axis = ax;
		vm_input(&M, VM_IN_DRIVE_HOLD, on);
		snprintf(H.act, sizeof H.act, "drive %u %s", ax, on ? "held off" : "released");
		break;
	}
	case 15: {
		uint8_t ax = (uint8_t)(a % pl->n);
		plant_drive_reboot(pl, ax);
		M.in_axis = ax;
		vm_input(&M, VM_IN_DRIVE_REBOOT, true);
		snprintf(H.act, sizeof H.act, "drive %u reboots", ax);
		break;
	}
	case 12:
		H.caution = !H.caution;
		pl->caution = H.caution;
		/* The cap is reached by braking, as a lower set velocity is. */
		if (H.caution) {
			H.vt_grace = fmax(H.vt_set, H.grace_ms ? H.vt_grace : 0);
			H.vr_grace = fmax(H.vr_set, H.grace_ms ? H.vr_grace : 0);
			H.grace_ms = M.c.brake_ms;
		}
		snprintf(H.act, sizeof H.act, "caution %s", H.caution ? "on" : "off");
		break;
	default: {
		/* A push by hand, within the following-error bound. */
		double dx = (double)(int8_t)a / 8.0;
		plant_push(pl, dx, vs_config_omni(&S.cfg) ? -dx / 2 : 0, dx / 16);
		vm_input(&M, VM_IN_PUSH, true);
		H.pushed = true;
		snprintf(H.act, sizeof H.act, "push %.2f mm", dx);
		break;
	}
	}
	/* The unit samples its inputs at the next tick: take it before any
	 * request, as the model has already taken the input. */
	return tick();
}

static int do_wait(rd_t *r)
{
	uint8_t a = u8(r);
	unsigned n = a < 128 ? a : (unsigned)(a - 127) * 40u;
	snprintf(H.act, sizeof H.act, "wait %u ticks", n);
	for (unsigned i = 0; i < n && H.ticks < MAX_TICKS; i++)
		if (tick())
			return 1;
	return 0;
}

static void setup(uint8_t mode)
{
	vs_config_t cfg;
	plant_params_t pp;
	vs_config_defaults(&cfg);
	if (mode & 1) {
		cfg.kinematics = VS_KIN_OMNI;
		cfg.wheel_diameter_mm = 100;
		cfg.track_width_mm = 450;
		cfg.wheel_base_mm = 400;
	}
	if (mode & 4) {
		cfg.jerk_limit_t_mm_s3 = 5000;
		cfg.jerk_limit_r_deg_s3 = 3000;
		cfg.jerk_default_t_mm_s3 = 2000;
		cfg.jerk_default_r_deg_s3 = 1000;
	}
	if (mode & 2) {
		plant_params_ideal(&pp);
		cfg.encoder_counts_per_rev = plant_hires_counts_per_rev(&cfg);
		plant_config_lag(&pp, &cfg);
	} else {
		plant_params_default(&pp);
	}
	/* The battery's sag under load is not what this harness is about. */
	pp.battery_r_ohm = 0;
	if (sim_init(&S, &cfg, &pp) != 0)
		abort();

	vm_config_t c = {
	    .omni = mode & 1,
	    .naxes = vs_config_axes(&cfg),
	    .vel_limit_t = cfg.vel_limit_t_mm_s,
	    .vel_limit_r = cfg.vel_limit_r_deg_s,
	    .acc_limit_t = cfg.acc_limit_t_mm_s2,
	    .acc_limit_r = cfg.acc_limit_r_deg_s2,
	    .link_timeout_ms = cfg.link_timeout_ms,
	    .servo_on_timeout_ms = cfg.servo_on_timeout_ms,
	    .jog_timeout_ms = cfg.jog_timeout_default_ms,
	    .tick_us = 1000000u / cfg.tick_hz,
	    .queue_cap = MOTION_QUEUE_LEN,
	    .deadband = cfg.joystick_deadband,
	    .has_contact = cfg.has_contact_sensor,
	    .has_obstacle = cfg.has_obstacle_input,
	    .has_estop = cfg.has_estop,
	    .has_joystick = cfg.has_joystick,
	};
	/* From the velocity limit at the set acceleration (the velocity modes'
	 * own stops brake at it; under jerk limits the ramps add v/a), then
	 * settling. */
	double brake_s = cfg.vel_limit_t_mm_s / cfg.acc_default_t_mm_s2;
	double rot_s = cfg.vel_limit_r_deg_s / cfg.acc_default_r_deg_s2;
	c.settle_ms = cfg.settle_timeout_ms + cfg.position_window_ms + 200u;
	c.brake_ms = (uint32_t)(1000.0 * 2.0 * fmax(brake_s, rot_s)) + cfg.settle_timeout_ms +
		     cfg.position_window_ms + 200u;
	for (unsigned i = 0; i < cfg.num_io; i++) {
		if (cfg.io[i].dir == VS_IO_IN)
			c.in_ids[c.n_in++] = cfg.io[i].id;
		else
			c.out_ids[c.n_out++] = cfg.io[i].id;
	}
	vm_init(&M, &c);
	H.vt_set = cfg.vel_default_t_mm_s;
	H.vr_set = cfg.vel_default_r_deg_s;
	H.grace_ms = 0;
	H.caution = false;
	H.prev = (fx_twist_t){0, 0, 0};
	H.prev_wx = H.prev_wy = 0;
	H.pushed = false;
	H.prev_acc = (fx_twist_t){0, 0, 0};
	H.acc_valid = false;
	H.mode_pre = 0;
	H.prev_servo = false;
	H.ticks = 0;
	double d = cfg.wheel_diameter_mm;
	H.counts_per_mm = (double)cfg.encoder_counts_per_rev / (3.14159265358979 * d);
}

int diff_run(const uint8_t *data, size_t n, char *why, size_t cap)
{
	rd_t r = {data, n, 0};
	H.why = why;
	H.cap = cap;
	H.step = 0;
	snprintf(H.act, sizeof H.act, "start");
	if (cap)
		why[0] = '\0';
	trace = getenv("DIFF_TRACE") != NULL;
	ticks_trace = getenv("DIFF_TICKS") != NULL;
	setup(u8(&r));
	n_actions = 0;
	tick_hash = 0xcbf29ce484222325ull;
	while (r.i < r.n && H.step < MAX_ACTIONS && H.ticks < MAX_TICKS) {
		uint8_t k = u8(&r);
		H.step++;
		n_actions++;
		int rc;
		if (k < 150)
			rc = do_op(&r);
		else if (k < 200)
			rc = do_wait(&r);
		else
			rc = do_input(&r);
		if (trace && k >= 150) {
			int16_t st;
			char msg[VS_STATE_MSG_MAX];
			vs_getState(&S.vehicle, &st, msg);
			uint32_t al[VS_ALARM_LIST_MAX];
			char at[128];
			alarms_text(at, sizeof at, al, unit_alarms(al));
			printf("  %6u ms  %-65s %s [%s] servo %d\n", H.ticks, H.act, msg, at,
			       S.vehicle.servo);
		}
		if (rc)
			return 1;
	}
	return 0;
}

unsigned long diff_last_actions(void)
{
	return n_actions;
}

uint64_t diff_last_hash(void)
{
	return tick_hash;
}
