/* The VehicleService operations at the boundary, and vehicle_init.
 *
 * With config.c, the one firmware file that computes with vs_real_t
 * (real.h): doubles on a host, Q32 on a board built with VS_REAL_Q32. Each
 * argument is checked once (NaN, infinity, range) and converted to Q32; the
 * tick never sees a double. libc is not available, so NaN is "x != x" and
 * infinity fails the range bounds.
 *
 * Check order of a move*: the arguments first (110 invalid, 111 over a
 * limit, 112 not possible on this base), so the same command always gets
 * the same answer for its form; then the unit state (vehicle_move_gate);
 * then what the motion engine says (queue full, ...).
 */
#include <stddef.h>
#include <stdint.h>

#include "vehicle_priv.h"

#define POS_MAX_MM    VS_REAL(1e6)
#define ANGLE_MAX_DEG VS_REAL(36000.0)
#define PI_D	      3.14159265358979323846

/* Finite and |x| <= lim. */
FX_HELPER bool within(vs_real_t x, vs_real_t lim)
{
	return !vs_real_nan(x) && x >= -lim && x <= lim;
}

#ifdef VS_REAL_Q32
#define to_q32(x)   (x)
#define from_q32(x) (x)
/* round(x * scale) for 0 <= x * scale < 2^31 */
FX_HELPER int64_t scaled(vs_real_t x, uint32_t scale)
{
	return (x * scale + (INT64_C(1) << 31)) >> 32;
}
#else
#define TWO_POW_32 4294967296.0

/* Rounded to nearest; callers have bounded |x| well inside the range. */
static q32_t to_q32(double x)
{
	double r = x * TWO_POW_32;
	return (q32_t)(r >= 0.0 ? r + 0.5 : r - 0.5);
}

static double from_q32(q32_t x)
{
	return (double)x / TWO_POW_32;
}

static int64_t scaled(double x, uint32_t scale)
{
	return (int64_t)(x * scale + 0.5);
}
#endif

static bool pose_ok(const vs_position_t *p)
{
	return within(p->x, POS_MAX_MM) && within(p->y, POS_MAX_MM) &&
	       within(p->theta, ANGLE_MAX_DEG);
}

static fx_pose_t pose_q32(const vs_position_t *p)
{
	fx_pose_t q = {to_q32(p->x), to_q32(p->y), to_q32(p->theta)};
	return q;
}

/* ---- init ------------------------------------------------------------- */

static bool hal_complete(const vs_hal_t *hal, const vs_config_t *c)
{
	const vs_hal_ops_t *o = hal ? hal->ops : NULL;
	if (!o || !o->drive_set_velocity || !o->drive_enable || !o->drive_read ||
	    !o->drive_reset_fault || !o->power_set || !o->power_feedback || !o->io_read ||
	    !o->io_write || !o->battery_mv)
		return false;
	if (vs_config_contact(c) && !o->contact)
		return false;
	if (vs_config_obstacle(c) && (!o->obstacle || !o->obstacle_caution))
		return false;
	if (vs_config_estop(c) && !o->estop)
		return false;
	if (c->has_joystick && !o->joystick)
		return false;
	return true;
}

FX_HELPER uint32_t ms_to_ticks(uint32_t ms, uint32_t tick_hz)
{
	uint32_t t = (uint32_t)(((uint64_t)ms * tick_hz + 999u) / 1000u);
	return t ? t : 1u;
}

/* What the ANY fields give the unit, from its configuration (init, a
 * change at run time, $jerk: one copy each): the jerk in force and the
 * battery thresholds in millivolts. */
static void jerk_in_force(vehicle_t *v)
{
	motion_set_jerk(&v->motion, to_q32(v->cfg.jerk_default_t_mm_s3),
			to_q32(v->cfg.jerk_default_r_deg_s3));
}

static void battery_limits(vehicle_t *v)
{
	v->battery_low_mv = (uint32_t)scaled(v->cfg.battery_low_v, 1000u);
	v->battery_critical_mv = (uint32_t)scaled(v->cfg.battery_critical_v, 1000u);
}

/* The motion engine at the configured limits and defaults (cfg: the
 * unit's); returns its kinematics. */
static motion_kin_t init_motion(vehicle_t *v, const vs_config_t *cfg)
{
	motion_params_t mp = {
	    .tick_hz = cfg->tick_hz,
	    .kin = vs_config_omni(cfg) ? MOTION_KIN_OMNI : MOTION_KIN_DIFF,
	    .vel_limit_t = to_q32(cfg->vel_limit_t_mm_s),
	    .vel_limit_r = to_q32(cfg->vel_limit_r_deg_s),
	    .acc_limit_t = to_q32(cfg->acc_limit_t_mm_s2),
	    .acc_limit_r = to_q32(cfg->acc_limit_r_deg_s2),
	    .jerk_limit_t = to_q32(cfg->jerk_limit_t_mm_s3),
	    .jerk_limit_r = to_q32(cfg->jerk_limit_r_deg_s3),
	    .cruise_blend_mm = to_q32(cfg->cruise_blend_mm),
	};
	motion_init(&v->motion, &mp);
	jerk_in_force(v);
	return mp.kin;
}

/* The wheel loop and odometry; returns the encoder counts per mm, which
 * the supervision limits are counted in. */
static vs_real_t init_kin(vehicle_t *v, const vs_config_t *cfg, motion_kin_t kin)
{
	vs_real_t twice_half =
	    vs_config_omni(cfg) ? cfg->wheel_base_mm + cfg->track_width_mm : cfg->track_width_mm;
#ifdef VS_REAL_Q32
	q32_t counts_per_mm = fx_div(vs_real_int(cfg->encoder_counts_per_rev),
				     fx_mul(VS_REAL(PI_D), cfg->wheel_diameter_mm));
	q32_t mm_per_deg = fx_mul(twice_half, VS_REAL(PI_D / 360.0));
	q32_t deg_per_mm = fx_div(VS_REAL_ONE, mm_per_deg);
#else
	double counts_per_mm_d =
	    (double)cfg->encoder_counts_per_rev / (PI_D * cfg->wheel_diameter_mm);
	double mm_per_deg_d = twice_half / 2.0 * PI_D / 180.0;
	q32_t counts_per_mm = to_q32(counts_per_mm_d);
	q32_t mm_per_deg = to_q32(mm_per_deg_d);
	q32_t deg_per_mm = to_q32(1.0 / mm_per_deg_d);
#endif
	kin_params_t kp = {
	    .kin = (uint8_t)kin,
	    .n = v->naxes,
	    .tick_hz = cfg->tick_hz,
	    .counts_per_mm = counts_per_mm,
	    .mm_per_deg = mm_per_deg,
	    .deg_per_mm = deg_per_mm,
	    .kp_q16 = scaled(cfg->wheel_kp_per_s, 65536u),
	};
	/* The feed-forward's lead for a drive lag, in ticks (kin.h): the lag
	 * plus the tick by which the wheel loop runs ahead of its reference. */
	for (unsigned i = 0; i < VS_MAX_AXES; i++)
		kp.lag_q16[i] =
		    cfg->drive_lag_ms[i] > 0
			? scaled(cfg->drive_lag_ms[i] * cfg->tick_hz / 1000 + VS_REAL_ONE, 65536u)
			: 0;
	kin_init(&v->kin, &kp);
#ifdef VS_REAL_Q32
	return counts_per_mm;
#else
	return counts_per_mm_d; /* unrounded: the supervision limits round once */
#endif
}

/* Supervision limits in ticks, counts and millivolts. */
static void init_supervision(vehicle_t *v, const vs_config_t *cfg, vs_real_t counts_per_mm)
{
	v->period_us = 1000000u / cfg->tick_hz;
	v->drive_timeout_ticks = ms_to_ticks(cfg->drive_timeout_ms, cfg->tick_hz);
	v->servo_on_timeout_ticks = ms_to_ticks(cfg->servo_on_timeout_ms, cfg->tick_hz);
	v->loop_late_us = cfg->loop_late_ms * 1000u;
	vehicle_set_link_timeout(v, cfg->link_timeout_ms);
	v->encoder_stuck_ticks = ms_to_ticks(cfg->encoder_stuck_ms, cfg->tick_hz);
	/* A speed that must move the encoder by 20 counts within the window:
	 * well clear of quantisation, so a slow creep never trips it. */
	uint32_t stuck_cps_q8 = 20u * 256u * 1000u / cfg->encoder_stuck_ms; /* 85..512,000 */
	/* |cps| >= T as one unsigned compare: cps + (T - 1) >= 2T - 1. */
	v->encoder_stuck_off = stuck_cps_q8 - 1u;
	v->encoder_stuck_span = 2u * stuck_cps_q8 - 1u;
#ifdef VS_REAL_Q32
	q32_t following = fx_mul(cfg->following_error_mm, counts_per_mm);
	q32_t window = fx_mul(cfg->position_window_mm, counts_per_mm);
	v->following_err_max_q32 = (following + (INT64_C(1) << 31)) >> 32 << 32;
#else
	double window = cfg->position_window_mm * counts_per_mm;
	v->following_err_max_q32 = (int64_t)(cfg->following_error_mm * counts_per_mm + 0.5) << 32;
#endif
	/* The window is at least one count: a wheel at rest may sit a count
	 * off its reference in quantisation. */
	v->window_q32 = to_q32(window < VS_REAL_ONE ? VS_REAL_ONE : window);
	v->window_ticks = ms_to_ticks(cfg->position_window_ms, cfg->tick_hz);
	v->settle_timeout_ticks = ms_to_ticks(cfg->settle_timeout_ms, cfg->tick_hz);
	v->inpos_ticks = v->window_ticks; /* servo off: nothing to settle */
	battery_limits(v);
	v->battery_low_armed = true;
	v->caution_vel_t = to_q32(cfg->caution_vel_t_mm_s);
	v->joystick_deadband_q15 = (int32_t)scaled(cfg->joystick_deadband, 32767u);
}

/* Everything derived from cfg, as init and a change at run time both do:
 * the motion engine with the settings in force (v->vel_set, v->acc_set,
 * v->jog_timeout_ms), the wheel loop and the supervision limits. */
static void derive(vehicle_t *v, const vs_config_t *cfg)
{
	v->cfg = *cfg;
	init_supervision(v, cfg, init_kin(v, cfg, init_motion(v, cfg)));
	motion_set_velocity(&v->motion, to_q32(v->vel_set.translation),
			    to_q32(v->vel_set.rotation));
	motion_set_accel(&v->motion, to_q32(v->acc_set.translation), to_q32(v->acc_set.rotation));
	motion_set_jog_timeout_ms(&v->motion, (uint16_t)v->jog_timeout_ms);
}

int vehicle_init(vehicle_t *v, const vs_config_t *cfg, const vs_hal_t *hal, const char **bad_field)
{
	int rc = vs_config_check(cfg, bad_field);
	if (rc != 0)
		return rc;
	if (!hal_complete(hal, cfg)) {
		if (bad_field)
			*bad_field = "hal";
		return -4;
	}

	*v = (vehicle_t){0};
	v->hal = *hal;
	v->naxes = vs_config_axes(cfg);
	v->vel_set = (vs_velocity_t){cfg->vel_default_t_mm_s, cfg->vel_default_r_deg_s};
	v->acc_set = (vs_velocity_t){cfg->acc_default_t_mm_s2, cfg->acc_default_r_deg_s2};
	v->jog_timeout_ms = (int16_t)cfg->jog_timeout_default_ms;
	derive(v, cfg);

	/* Start Unpowered in fact, not only in name. */
	for (uint8_t i = 0; i < v->naxes; i++)
		hal->ops->drive_enable(hal->ctx, i, false);
	hal->ops->power_set(hal->ctx, false);
	v->battery_mv = hal->ops->battery_mv(hal->ctx);
	return 0;
}

/* ---- queries ---------------------------------------------------------- */

bool vs_getAccelerationLimit(vehicle_t *v, vs_real_t *accLimitT, vs_real_t *accLimitR)
{
	*accLimitT = v->cfg.acc_limit_t_mm_s2;
	*accLimitR = v->cfg.acc_limit_r_deg_s2;
	return true;
}

bool vs_getVelocityLimit(vehicle_t *v, vs_real_t *velLimitT, vs_real_t *velLimitR)
{
	*velLimitT = v->cfg.vel_limit_t_mm_s;
	*velLimitR = v->cfg.vel_limit_r_deg_s;
	return true;
}

bool vs_getDefaultAcceleration(vehicle_t *v, vs_velocity_t *defaultAccel)
{
	defaultAccel->translation = v->cfg.acc_default_t_mm_s2;
	defaultAccel->rotation = v->cfg.acc_default_r_deg_s2;
	return true;
}

bool vs_getDefaultVelocity(vehicle_t *v, vs_velocity_t *defaultVel)
{
	defaultVel->translation = v->cfg.vel_default_t_mm_s;
	defaultVel->rotation = v->cfg.vel_default_r_deg_s;
	return true;
}

bool vs_getBatteryVoltage(vehicle_t *v, vs_real_t *voltage)
{
	/* 0.1 V units: 24300 mV reads 243.0. */
#ifdef VS_REAL_Q32
	uint32_t mv = v->battery_mv;
	*voltage = vs_real_int(mv / 100u) + (vs_real_int(mv % 100u) + 50) / 100;
#else
	*voltage = (double)v->battery_mv / 100.0;
#endif
	return true;
}

bool vs_getPosition(vehicle_t *v, vs_position_t *pos)
{
	q32_t th = fx_wrap_deg(v->odom.th_deg);
	/* The interface range is (-180, 180]. */
	if (th == -FX_DEG_180)
		th = FX_DEG_180;
	pos->x = from_q32(v->odom.x_mm);
	pos->y = from_q32(v->odom.y_mm);
	pos->theta = from_q32(th);
	return true;
}

/* ---- settings --------------------------------------------------------- */

/* 0 < x <= limit, finite; 110 when not a number, 111 otherwise. */
FX_HELPER uint32_t check_setting(vs_real_t x, vs_real_t limit)
{
	if (!vs_real_finite(x))
		return ALM_W_BAD_ARGUMENT;
	if (!(x > 0 && x <= limit))
		return ALM_W_OVER_LIMIT;
	return 0;
}

/* The real member at offset off of c. */
static vs_real_t real_of(const vs_config_t *c, size_t off)
{
	return *(const vs_real_t *)(const void *)((const char *)c + off);
}

/* A pair's r member follows its t member (check_pair, keep_setting). */
#define PAIR(t, r) (offsetof(vs_config_t, r) == offsetof(vs_config_t, t) + sizeof(vs_real_t))
_Static_assert(PAIR(vel_default_t_mm_s, vel_default_r_deg_s) &&
		   PAIR(vel_limit_t_mm_s, vel_limit_r_deg_s) &&
		   PAIR(acc_default_t_mm_s2, acc_default_r_deg_s2) &&
		   PAIR(acc_limit_t_mm_s2, acc_limit_r_deg_s2),
	       "the pairs a setting is judged by");
#undef PAIR

/* A setting (t, r) against the limit pair at offset lim of c: 0, or the
 * refusal's code (110 when either is not a number, else 111). */
static uint32_t check_pair(const vs_velocity_t *set, const vs_config_t *c, size_t lim)
{
	uint32_t e = check_setting(set->translation, real_of(c, lim));
	uint32_t er = check_setting(set->rotation, real_of(c, lim + sizeof(vs_real_t)));
	return e == 0 || er == ALM_W_BAD_ARGUMENT ? er : e;
}

bool vs_setVelocity(vehicle_t *v, vs_velocity_t vel)
{
	uint32_t e = check_pair(&vel, &v->cfg, offsetof(vs_config_t, vel_limit_t_mm_s));
	if (e != 0)
		return vehicle_refuse(v, "setVelocity", e);
	motion_set_velocity(&v->motion, to_q32(vel.translation), to_q32(vel.rotation));
	v->vel_set = vel;
	return true;
}

bool vs_setAcceleration(vehicle_t *v, vs_velocity_t accel)
{
	uint32_t e = check_pair(&accel, &v->cfg, offsetof(vs_config_t, acc_limit_t_mm_s2));
	if (e != 0)
		return vehicle_refuse(v, "setAcceleration", e);
	/* Moving = Busy (or Avoid), waiting for the drives to enable included;
	 * a unit paused at rest may take it. */
	if (motion_is_moving(&v->motion) ||
	    (motion_has_work(&v->motion) && !motion_is_paused(&v->motion)) ||
	    vehicle_servo_waiting(v))
		return vehicle_refuse(v, "setAcceleration", ALM_W_MOVING);
	motion_set_accel(&v->motion, to_q32(accel.translation), to_q32(accel.rotation));
	v->acc_set = accel;
	return true;
}

bool vs_setPosition(vehicle_t *v, vs_position_t pos)
{
	if (!pose_ok(&pos))
		return vehicle_refuse(v, "setPosition", ALM_W_BAD_ARGUMENT);
	fx_pose_t p = pose_q32(&pos);
	p.th_deg = fx_wrap_deg(p.th_deg);
	v->odom = p;
#ifndef VS_NO_DRIVE_STATES
	v->pose_lost = false; /* the host says where the unit is */
#endif
	/* At rest the new pose is where the unit is now: the wheel loop drops
	 * what it still had to correct, so that the reference, the odometry
	 * and the wheels agree (a move sent next starts from p exactly). */
	if (!motion_has_work(&v->motion))
		kin_sync(&v->kin, v->meas_counts);
	motion_set_pose(&v->motion, &p);
	return true;
}

/* ---- motion ----------------------------------------------------------- */

bool vs_moveForward(vehicle_t *v, vs_real_t x_)
{
	/* The literal, not an array: one copy with the command table's. */
	const char *const op = "moveForward";
	if (!within(x_, POS_MAX_MM))
		return vehicle_refuse(v, op, ALM_W_BAD_ARGUMENT);
	if (!vehicle_move_gate(v, op, VEHICLE_GATE_READY))
		return false;
	if (!motion_forward(&v->motion, to_q32(x_)))
		return vehicle_motion_refused(v, op, false);
	return true;
}

bool vs_moveTurn(vehicle_t *v, vs_real_t theta_)
{
	const char *const op = "moveTurn";
	if (!within(theta_, ANGLE_MAX_DEG))
		return vehicle_refuse(v, op, ALM_W_BAD_ARGUMENT);
	if (!vehicle_move_gate(v, op, VEHICLE_GATE_READY))
		return false;
	if (!motion_turn(&v->motion, to_q32(theta_)))
		return vehicle_motion_refused(v, op, false);
	return true;
}

bool vs_moveLinearRel(vehicle_t *v, vs_position_t pos)
{
	const char *const op = "moveLinearRel";
	if (!pose_ok(&pos))
		return vehicle_refuse(v, op, ALM_W_BAD_ARGUMENT);
	if (!vehicle_move_gate(v, op, VEHICLE_GATE_READY))
		return false;
	fx_pose_t rel = pose_q32(&pos);
	if (!motion_linear_rel(&v->motion, &rel))
		return vehicle_motion_refused(v, op, false);
	return true;
}

bool vs_moveCircularRel(vehicle_t *v, vs_point_t centerPoint, vs_real_t theta)
{
	const char *const op = "moveCircularRel";
	if (!within(centerPoint.x, POS_MAX_MM) || !within(centerPoint.y, POS_MAX_MM) ||
	    !within(theta, ANGLE_MAX_DEG))
		return vehicle_refuse(v, op, ALM_W_BAD_ARGUMENT);
	/* A differential base can only turn about a point on its axle line. */
	if (!vs_config_omni(&v->cfg) && centerPoint.x != 0)
		return vehicle_refuse(v, op, ALM_W_KINEMATICS);
	if (!vehicle_move_gate(v, op, VEHICLE_GATE_READY))
		return false;
	if (!motion_circular_rel(&v->motion, to_q32(centerPoint.x), to_q32(centerPoint.y),
				 to_q32(theta)))
		return vehicle_motion_refused(v, op, false);
	return true;
}

bool vs_moveLinearAbs(vehicle_t *v, vs_position_t pos)
{
	const char *const op = "moveLinearAbs";
	if (!pose_ok(&pos))
		return vehicle_refuse(v, op, ALM_W_BAD_ARGUMENT);
	if (!vehicle_move_gate(v, op, VEHICLE_GATE_SERVO))
		return false;
	fx_pose_t p = pose_q32(&pos);
	if (!motion_linear_abs(&v->motion, &p))
		return vehicle_motion_refused(v, op, false);
	return true;
}

bool vs_moveCruiseAbs(vehicle_t *v, vs_point_t cruisePoint)
{
	const char *const op = "moveCruiseAbs";
	if (!within(cruisePoint.x, POS_MAX_MM) || !within(cruisePoint.y, POS_MAX_MM))
		return vehicle_refuse(v, op, ALM_W_BAD_ARGUMENT);
	if (!vehicle_move_gate(v, op, VEHICLE_GATE_SERVO))
		return false;
	if (!motion_cruise_abs(&v->motion, to_q32(cruisePoint.x), to_q32(cruisePoint.y)))
		return vehicle_motion_refused(v, op, false);
	return true;
}

bool vs_moveContinuousRel(vehicle_t *v, vs_position_t pos)
{
	const char *const op = "moveContinuousRel";
	if (!pose_ok(&pos))
		return vehicle_refuse(v, op, ALM_W_BAD_ARGUMENT);
	if (!vehicle_move_gate(v, op, VEHICLE_GATE_SERVO))
		return false;
	fx_pose_t rel = pose_q32(&pos);
	if (!motion_continuous_rel(&v->motion, &rel))
		return vehicle_motion_refused(v, op, true);
	return true;
}

bool vs_moveJog(vehicle_t *v, vs_real_t xVel, vs_real_t yVel, vs_real_t thetaVel)
{
	const char *const op = "moveJog";
	if (!vs_real_finite(xVel) || !vs_real_finite(yVel) || !vs_real_finite(thetaVel))
		return vehicle_refuse(v, op, ALM_W_BAD_ARGUMENT);
	/* Spec 6.6: magnitudes within the limits; signs reverse; zero stops. */
	if (!within(xVel, v->cfg.vel_limit_t_mm_s) || !within(yVel, v->cfg.vel_limit_t_mm_s) ||
	    !within(thetaVel, v->cfg.vel_limit_r_deg_s))
		return vehicle_refuse(v, op, ALM_W_OVER_LIMIT);
	if (!vs_config_omni(&v->cfg) && yVel != 0)
		return vehicle_refuse(v, op, ALM_W_KINEMATICS);
	if (!vehicle_move_gate(v, op, VEHICLE_GATE_JOG))
		return false;
	if (!motion_jog(&v->motion, to_q32(xVel), to_q32(yVel), to_q32(thetaVel)))
		return vehicle_motion_refused(v, op, true);
	return true;
}

void vehicle_jerk(const vehicle_t *v, vs_real_t *jt, vs_real_t *jr)
{
	*jt = v->cfg.jerk_default_t_mm_s3;
	*jr = v->cfg.jerk_default_r_deg_s3;
}

bool vehicle_set_jerk(vehicle_t *v, vs_real_t jt, vs_real_t jr)
{
	if (!vs_jerk_fits(&v->cfg, jt, v->cfg.jerk_limit_t_mm_s3) ||
	    !vs_jerk_fits(&v->cfg, jr, v->cfg.jerk_limit_r_deg_s3))
		return false;
	/* The running configuration holds it, as $config shows. */
	v->cfg.jerk_default_t_mm_s3 = jt;
	v->cfg.jerk_default_r_deg_s3 = jr;
	jerk_in_force(v);
	return true;
}

/* ---- the configuration changed at run time ---------------------------- */

bool vehicle_config_idle(const vehicle_t *v)
{
	return !v->servo && !motion_has_work(&v->motion);
}

/* A setting in force *set (t, r) stays while it is within its new limits
 * and its default did not change; else it becomes the new default. def,
 * lim: the offsets of the default's and the limit's t members (one copy of
 * the rule for the speed and the acceleration). */
static void keep_setting(vs_velocity_t *set, const vs_config_t *old, const vs_config_t *cfg,
			 size_t def, size_t lim)
{
	size_t r = sizeof(vs_real_t);
	vs_real_t def_t = real_of(cfg, def), def_r = real_of(cfg, def + r);
	if (real_of(old, def) != def_t || real_of(old, def + r) != def_r ||
	    check_pair(set, cfg, lim) != 0)
		*set = (vs_velocity_t){def_t, def_r};
}

void vehicle_reconfigure(vehicle_t *v, const vs_config_t *cfg)
{
	keep_setting(&v->vel_set, &v->cfg, cfg, offsetof(vs_config_t, vel_default_t_mm_s),
		     offsetof(vs_config_t, vel_limit_t_mm_s));
	keep_setting(&v->acc_set, &v->cfg, cfg, offsetof(vs_config_t, acc_default_t_mm_s2),
		     offsetof(vs_config_t, acc_limit_t_mm_s2));
	if (cfg->jog_timeout_default_ms != v->cfg.jog_timeout_default_ms)
		v->jog_timeout_ms = (int16_t)cfg->jog_timeout_default_ms;

	/* As vehicle_init derives them; the unit's state (power, alarms, the
	 * pose, the encoders' last counts) stays. */
	derive(v, cfg);
	kin_sync(&v->kin, v->meas_counts);
	motion_set_pose(&v->motion, &v->odom);
}

void vehicle_config_live(vehicle_t *v, const vs_config_t *cfg)
{
	uint32_t link = v->cfg.link_timeout_ms;
	v->cfg = *cfg;
	if (cfg->link_timeout_ms != link)
		vehicle_set_link_timeout(v, cfg->link_timeout_ms);
	jerk_in_force(v);
	battery_limits(v);
}
