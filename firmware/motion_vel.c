/* Motion engine: the velocity modes' ticks (jog, joystick, continuous goal
 * without jerk limits; under them the goal's law is motion_seek.c). Their
 * commands are motion.c's. */
#include "motion_priv.h"

#include <stddef.h>

/* Move x toward target by at most step. */
FX_HELPER q32_t slew(q32_t x, q32_t target, q32_t step)
{
	if (target > x + step)
		return x + step;
	if (target < x - step)
		return x - step;
	return target;
}

/* Move the translation (x, y) toward its target by at most step as a
 * vector: component-wise steps would let a diagonal accelerate at sqrt(2)
 * times the limit on an omni base. */
static void slew2(q32_t *x, q32_t *y, q32_t tx, q32_t ty, q32_t step)
{
	q32_t dx = tx - *x, dy = ty - *y;
	if (dy == 0 || dx == 0) {
		*x = slew(*x, tx, step);
		*y = slew(*y, ty, step);
		return;
	}
	q32_t len = fx_hypot(dx, dy);
	if (len <= step) {
		*x = tx;
		*y = ty;
		return;
	}
	/* Unit direction (Q30) times the step: exact to a raw unit. */
	*x += fx_mul_q30(step, (int32_t)(fx_div(dx, len) >> 2));
	*y += fx_mul_q30(step, (int32_t)(fx_div(dy, len) >> 2));
}

/* The accelerations the velocity modes slew at: the set ones, or the
 * limits while braking (pause, stop). */
static void slew_rates(const motion_t *m, bool braking, q32_t *at, q32_t *ar)
{
	*at = m->a_t_pt2;
	*ar = m->a_r_pt2;
	if (braking) {
		*at = m->amax_t_pt2;
		*ar = m->amax_r_pt2;
	}
}

/* Jerk-limited slew of the velocity modes (traj.h, section 5), per axis:
 * the jerks (set ones, or the limits braking) for translation and rotation,
 * 0 for an axis without one (the acceleration-limited slew). */
static void jerk_slew(motion_t *m, const fx_twist_t *tgt, q32_t at, q32_t ar, bool braking)
{
	q32_t jt = braking ? m->jmax_t_pt3 : m->j_t_pt3;
	q32_t jr = braking ? m->jmax_r_pt3 : m->j_r_pt3;
	if (jt > 0 && KIN_OMNI(m->p.kin)) {
		at = motion_share(at);
		jt = motion_share(jt);
		traj_jslew(&m->vel.vy_pt, &m->vacc.vy_pt, tgt->vy_pt, at, jt);
	}
	if (jt > 0)
		traj_jslew(&m->vel.vx_pt, &m->vacc.vx_pt, tgt->vx_pt, at, jt);
	else
		slew2(&m->vel.vx_pt, &m->vel.vy_pt, tgt->vx_pt, tgt->vy_pt, at);
	if (jr > 0)
		traj_jslew(&m->vel.w_pt, &m->vacc.w_pt, tgt->w_pt, ar, jr);
	else
		m->vel.w_pt = slew(m->vel.w_pt, tgt->w_pt, ar);
}

/* Jog and joystick: slew toward the target velocity. */
/* The tick at rest after a motion that ended under jerk limits
 * (motion_tick): true when this tick is it. */
static bool rest_first(motion_t *m, fx_twist_t *out)
{
	if (!m->rest_tick)
		return false;
	m->rest_tick = false;
	*out = (fx_twist_t){0};
	return true;
}

void motion_velocity_tick(motion_t *m, fx_twist_t *out)
{
	if (rest_first(m, out))
		return;
	bool braking = m->stopping || m->paused;
	fx_twist_t tgt = m->vtarget;
	q32_t at, ar;
	slew_rates(m, braking, &at, &ar);
	if (m->mode == MODE_JOG && ++m->jog_age_ticks > m->jog_timeout_ticks)
		tgt = (fx_twist_t){0};
	if (braking)
		tgt = (fx_twist_t){0};
	/* Caution cap and set velocity bound the target: the translation as a
	 * vector (a mecanum diagonal is not faster than the cap). */
	q32_t vt = vt_eff(m);
	if (KIN_OMNI(m->p.kin) && tgt.vy_pt != 0) {
		q32_t len = fx_hypot(tgt.vx_pt, tgt.vy_pt);
		if (len > vt) {
			/* Rounded toward zero: never over the cap. */
			q32_t k = fx_div(vt, len);
			tgt.vx_pt = fx_mul(tgt.vx_pt, k);
			tgt.vy_pt = fx_mul(tgt.vy_pt, k);
		}
	} else {
		tgt.vx_pt = fx_clamp64(tgt.vx_pt, -vt, vt);
	}
	tgt.w_pt = fx_clamp64(tgt.w_pt, -m->v_r_pt, m->v_r_pt);
	if (m->j_t_pt3 | m->j_r_pt3) {
		jerk_slew(m, &tgt, at, ar, braking);
	} else {
		slew2(&m->vel.vx_pt, &m->vel.vy_pt, tgt.vx_pt, tgt.vy_pt, at);
		m->vel.w_pt = slew(m->vel.w_pt, tgt.w_pt, ar);
	}
	*out = m->vel;
	if (twist_zero(&m->vel) && twist_zero(&tgt)) {
		/* At rest: the acceleration the slew ended on is gone. */
		m->vacc = (fx_twist_t){0};
		bool jog_done = m->mode == MODE_JOG && (m->jog_age_ticks > m->jog_timeout_ticks ||
							braking || twist_zero(&m->vtarget));
		bool joystick_done = m->mode == MODE_JOYSTICK && m->stopping;
		if (jog_done || joystick_done) {
			m->mode = MODE_IDLE;
			m->stopping = false;
		}
	}
}

/* pi / 180 in Q32. */
#define VS_RAD_PER_DEG_Q32 ((q32_t)74961321)

/* Toward the goal on a differential base, heading error e, forward or
 * backing (motion_goal_facing). */
static void goal_want_diff(motion_t *m, q32_t e, q32_t dist, fx_twist_t *want)
{
	motion_goal_facing(m, &e);
	q32_t ae = fx_abs64(e);
	/* Turn toward the goal; translate along the projected distance. */
	q32_t wr = fx_min64(traj_umax(ae, m->a_r_pt2), m->v_r_pt);
	want->w_pt = e < 0 ? -wr : wr;
	uint32_t b = fx_deg_to_bam(e);
	q32_t proj = fx_mul_q30(dist, fx_cos_bam(b));
	if (proj > 0 && ae < fx_from_int(45)) {
		want->vx_pt = fx_min64(traj_umax(proj, m->a_t_pt2), vt_eff(m));
		/* No faster than the turn can bring the goal round: the circle
		 * through it tangent to the heading has radius d / (2 sin e),
		 * and at v / w above it the unit orbits the goal. */
		int32_t s = fx_sin_bam(b);
		if (s != 0) {
			q32_t w_rad = fx_mul(wr, VS_RAD_PER_DEG_Q32);
			q32_t cap = fx_div(fx_mul(dist, w_rad), 8 * (q32_t)(s < 0 ? -s : s));
			want->vx_pt = fx_min64(want->vx_pt, cap);
		}
	}
	if (m->goal_reverse)
		want->vx_pt = -want->vx_pt;
	if (dist < m->v_t_pt && ae < fx_from_int(1))
		want->w_pt = 0;
}

/* The velocity wanted toward the goal: its position (dx, dy away, at
 * dist) until reached, then its heading. */
static void goal_want(motion_t *m, q32_t dx, q32_t dy, q32_t dist, fx_twist_t *want)
{
	if (!m->goal_position_done) {
		q32_t bearing = fx_atan2_deg(dy, dx);
		q32_t e = fx_wrap_deg(bearing - m->ref.th_deg);
		if (KIN_OMNI(m->p.kin)) {
			q32_t sp = fx_min64(traj_umax(dist, m->a_t_pt2), vt_eff(m));
			uint32_t b = fx_deg_to_bam(e);
			want->vx_pt = fx_mul_q30(sp, fx_cos_bam(b));
			want->vy_pt = fx_mul_q30(sp, fx_sin_bam(b));
		} else {
			goal_want_diff(m, e, dist, want);
		}
	} else {
		q32_t e = fx_wrap_deg(m->goal.th_deg - m->ref.th_deg);
		q32_t wr = fx_min64(traj_umax(fx_abs64(e), m->a_r_pt2), m->v_r_pt);
		want->w_pt = e < 0 ? -wr : wr;
	}
}

/* After the step: land on the goal heading exactly (the last turning
 * step), or on the goal position once within reach of it. */
static void goal_arrive(motion_t *m, q32_t at, q32_t ar)
{
	if (m->goal_position_done) {
		q32_t e = fx_wrap_deg(m->goal.th_deg - m->ref.th_deg);
		if (fx_abs64(e) <= fx_abs64(m->vel.w_pt) && fx_abs64(m->vel.w_pt) <= ar) {
			/* Final step: land on the goal heading exactly. */
			m->ref.th_deg = m->goal.th_deg;
			m->vel = (fx_twist_t){0};
			m->mode = MODE_IDLE;
		}
	} else if (fx_hypot(m->goal.x_mm - m->ref.x_mm, m->goal.y_mm - m->ref.y_mm) < TINY_MM &&
		   fx_abs64(m->vel.vx_pt) <= at) {
		m->ref.x_mm = m->goal.x_mm;
		m->ref.y_mm = m->goal.y_mm;
		m->vel.vx_pt = 0;
		m->vel.vy_pt = 0;
		m->goal_position_done = true;
	}
}

/* Continuous mode: drive toward the goal with slewed velocities. */
void motion_continuous_tick(motion_t *m, fx_twist_t *out)
{
	if (rest_first(m, out))
		return;
	if (ONLINE_JERK && seek_jerk(m)) {
		motion_seek_tick(m, out);
		return;
	}
	bool braking = m->stopping || m->paused;
	fx_twist_t want = {0};
	q32_t dx = m->goal.x_mm - m->ref.x_mm, dy = m->goal.y_mm - m->ref.y_mm;
	q32_t dist = fx_hypot(dx, dy);
	if (!m->goal_position_done && dist < TINY_MM && fx_abs64(m->vel.vx_pt) == 0 &&
	    m->vel.vy_pt == 0)
		m->goal_position_done = true;
	goal_want(m, dx, dy, dist, &want);
	q32_t at, ar;
	slew_rates(m, braking, &at, &ar);
	if (braking)
		want = (fx_twist_t){0};
	fx_twist_t v0 = m->vel;
	slew2(&m->vel.vx_pt, &m->vel.vy_pt, want.vx_pt, want.vy_pt, at);
	m->vel.w_pt = slew(m->vel.w_pt, want.w_pt, ar);
	/* Never step past the goal: the last step covers the exact remainder
	 * (backing up, the same with the signs turned). */
	q32_t dir = m->goal_reverse ? -1 : 1;
	if (!m->goal_position_done && dir * m->vel.vx_pt > dist && !KIN_OMNI(m->p.kin))
		m->vel.vx_pt = dir * fx_max64(dist, dir * v0.vx_pt - at);
	/* The change of velocity, which a jog that takes over slews on
	 * from. */
	m->vacc.vx_pt = m->vel.vx_pt - v0.vx_pt;
	m->vacc.vy_pt = m->vel.vy_pt - v0.vy_pt;
	m->vacc.w_pt = m->vel.w_pt - v0.w_pt;
	*out = m->vel;
	odom_integrate(&m->ref, out, NULL);
	goal_arrive(m, at, ar);
	if (braking && twist_zero(&m->vel)) {
		if (m->stopping) {
			m->stopping = false;
			m->mode = MODE_IDLE;
		}
	}
}
