/* Motion engine: the continuous goal (moveContinuousRel) under jerk limits.
 *
 * Each axis approaches its point on its own law, one tick at a time:
 * toward the speed cap at the set acceleration and jerk (traj_jslew,
 * traj.h section 5) for as long as a stop from the state that step leaves
 * still fits in what remains (stop_room, an upper bound); once it would
 * not, the acceleration goes to zero at the jerk and a line to rest over
 * exactly what remains is planned (traj_ln, section 6: the tail), which
 * lands on the point to the raw unit. A retarget drops the tails and the
 * law goes on from the speed and acceleration the unit has: nothing steps.
 * An axis moving away from its point comes to rest at the jerk first.
 *
 * Differential base: the translation axis runs along the heading toward
 * the goal's projection on it (forward or backing, goal_reverse), while
 * the rotation turns toward the goal's bearing on the jerk-limited slew;
 * once there, the goal heading is the rotation axis's point. Mecanum
 * base: the axes are the bearing of the goal and its normal as seen at
 * the retarget; from rest the normal axis has nothing to do and the path
 * is the straight line, after a retarget with motion across the new line
 * that motion comes back to the line. Each axis gets 1 / sqrt(2) of the
 * acceleration and jerk, as in jog, so that the vector never exceeds
 * them. */
#include "motion_priv.h"

#include <stddef.h>

/* Within this of the goal when the translation has come to rest, the
 * reference takes the goal exactly. A mecanum base reaches it but for the
 * Q30 trigonometry that turns its axes' steps into the body twist and the
 * pose (far less). A differential base reaches the goal's projection on
 * its heading, and the turn toward the bearing, which swings as the goal
 * comes near, leaves some microns across (below 10 in the tests; the
 * default wheel's encoder count is 29): within 10 the reference takes
 * the goal; beyond, the unit faces it exactly and goes the rest straight. */
#define LAND_MM	     ((q32_t)429497)   /* 1e-4 mm */
#define LAND_DIFF_MM ((q32_t)42949673) /* 0.01 mm */
/* Closer than this, a differential base stops turning toward the bearing
 * while its translation runs. */
#define NEAR_MM ((q32_t)1 << 32)

/* A mecanum base's axes (Q30 cosine c and sine s of the bearing in the
 * body frame): a body vector (x, y) onto them, and back. */
static inline void to_axes(q32_t x, q32_t y, int32_t c, int32_t s, q32_t *u, q32_t *n)
{
	/* (x, y) turned back by the bearing: the swapped pair turned forward. */
	fx_rot_q30(y, x, c, s, n, u);
}

static inline void from_axes(const motion_t *m, fx_twist_t *vel)
{
	int32_t c = m->sk_c, s = m->sk_s;
	fx_rot_q30(m->sk_v[0], m->sk_v[1], c, s, &vel->vx_pt, &vel->vy_pt);
}

/* A jerk of 0 (unlimited on that axis): one that lets the acceleration
 * swing from -a to a in a tick, the acceleration-limited law. */
FX_HELPER q32_t jerk_or(q32_t j, q32_t a)
{
	return j > 0 ? j : 2 * a + 8;
}

/* An axis's limits: speed cap, the set acceleration and jerk, and the
 * hold its tail may need (stop_room). */
typedef struct {
	q32_t vc, a, j;
	int64_t dip;
} seek_lim_t;

/* x + y for x, y >= 0, saturating (with traj_mul_sat: a few compares where
 * the overflow builtins' 64-bit products cost a 32-bit core 0.5 KiB). */
static FX_OUTLINE int64_t add_sat(int64_t x, int64_t y)
{
	return x > INT64_MAX - y ? INT64_MAX : x + y;
}

/* An upper bound on the distance a stop from speed v >= 0 and change
 * acc >= 0 takes at the limits in l, with the room its tail needs: the
 * acceleration to zero at j (g ticks, the speed rising to at most vg),
 * then a ramp to rest, which takes at most vg / a + a / j + 2 whole ticks
 * (the bound of the ramp that reaches a; by the mean of 2 sqrt(vg / j) and
 * it, also of the one that does not) at a mean speed of at most vg / 2;
 * and a hold at vg long enough for the dip that takes up what the line's
 * speed cannot (traj.h section 6: a rest-to-rest S-curve of less than a
 * tick's distance, l->dip ticks at most), with a few ticks' rounding.
 * Saturates. */
static q32_t stop_room(q32_t v, q32_t acc, const seek_lim_t *l)
{
	int64_t g = fx_div_nn(acc + l->j - 1, l->j);
	int64_t vg = add_sat(v, traj_mul_sat(acc, g + 1) / 2);
	int64_t t = fx_div_nn(vg, l->a) + fx_div_nn(l->a, l->j) + 4;
	return add_sat(traj_mul_sat(vg, g + l->dip + 8), traj_mul_sat(vg, t) / 2);
}

/* The tail to rest over dd from speed u: on the line between speeds, its
 * top speed searched up to the cap only within 1/64 above u (the law
 * brought the unit as near the cap as a stop allowed, and the search's
 * cost grows with its range); from rest on the S-curve, in the line's
 * ramp buffer. */
static bool tail_plan(motion_t *m, int i, q32_t dd, q32_t u, const seek_lim_t *l)
{
	traj_ln_t *ln = &m->lnb[i];
	m->sk_rest[i] = u == 0;
	if (u == 0)
		return traj_sc_plan(&ln->ramp, dd, l->vc, l->a, l->j);
	q32_t cap = fx_min64(l->vc, u + u / 64 + 2);
	return traj_ln_plan(ln, dd, u, 0, fx_max64(cap, 2), l->a, l->j);
}

/* Whether the tail's next step is its last (at rest). */
static bool tail_done(const motion_t *m, int i)
{
	const traj_ln_t *ln = &m->lnb[i];
	return m->sk_rest[i] ? ln->ramp.k >= ln->ramp.ticks : ln->k >= ln->n;
}

/* The tail's next step, and whether it was its last (at rest). */
static q32_t tail_next(motion_t *m, int i, bool *last)
{
	traj_ln_t *ln = &m->lnb[i];
	*last = tail_done(m, i);
	return m->sk_rest[i] ? traj_sc_next(&ln->ramp) : traj_ln_next(ln);
}

/* One tick of axis i (tail in lnb[i]) toward a point d away (signed):
 * *v its speed, *acc its last change; limits l. plan: this tick may plan
 * a tail (one a tick, to bound its cost). Returns whether it planned. */
static bool seek_axis(motion_t *m, int i, q32_t *v, q32_t *acc, q32_t d, const seek_lim_t *l,
		      bool plan)
{
	q32_t v0 = *v, a = l->a, j = l->j;
	/* The tail runs to its end (its last tick, at rest, included) unless
	 * the cap changed under it: then the law goes on from here. */
	if (m->sk_on[i] && (m->sk_cap[i] == l->vc || tail_done(m, i))) {
		bool last;
		*v = m->sk_sg[i] * tail_next(m, i, &last);
		*acc = *v - v0;
		m->sk_on[i] = !last;
		return false;
	}
	m->sk_on[i] = false;
	q32_t sg = d > 0 || (d == 0 && v0 >= 0) ? 1 : -1;
	q32_t dd = sg * d, u = sg * v0, au = sg * *acc;
	bool planned = false;
	if (u < 0) {
		traj_jslew(&u, &au, 0, a, j); /* away from the point: to rest */
	} else {
		q32_t u1 = u, a1 = au;
		traj_jslew(&u1, &a1, l->vc, a, j);
		/* A slew that cannot turn a hard braking round before rest
		 * leaves a negative speed: the acceleration to zero instead
		 * (stop_room takes speeds from rest up). */
		if (u1 >= 0 && dd - u1 >= stop_room(u1, fx_max64(a1, 0), l)) {
			u = u1;
			au = a1;
		} else if (au != 0) {
			/* The acceleration to zero at the jerk, then the tail. */
			au = au > 0 ? fx_max64(au - j, 0) : fx_min64(au + j, 0);
			u += au;
		} else if (dd == 0 && u == 0) {
			/* on the point */
		} else if (plan && tail_plan(m, i, dd, u, l)) {
			m->sk_on[i] = true;
			m->sk_sg[i] = (int8_t)sg;
			m->sk_cap[i] = l->vc;
			planned = true;
			bool last;
			q32_t n = tail_next(m, i, &last);
			au = n - u;
			u = n;
		} else if (plan) {
			/* Too near to stop on it (a retarget inside the stopping
			 * distance): to rest at the jerk, and back. */
			traj_jslew(&u, &au, 0, a, j);
		}
	}
	*v = sg * u;
	*acc = sg * au;
	return planned;
}

/* The translation's limits at cap vc (a mecanum axis's share of them),
 * and the rotation's. */
static seek_lim_t lim_t(const motion_t *m, q32_t vc, bool share)
{
	q32_t a = m->a_t_pt2, j = jerk_or(m->j_t_pt3, a);
	if (share) { /* at least a raw unit: the laws divide by them */
		a = fx_max64(motion_share(a), 1);
		j = fx_max64(motion_share(j), 1);
	}
	return (seek_lim_t){vc, a, j, m->sk_dip[0]};
}

static seek_lim_t lim_r(const motion_t *m)
{
	return (seek_lim_t){m->v_r_pt, m->a_r_pt2, jerk_or(m->j_r_pt3, m->a_r_pt2), m->sk_dip[1]};
}

/* Braking (pause, stop): each axis to rest at the limits, reached at the
 * jerk limits; the tails are dropped. */
static void seek_brake(motion_t *m, fx_twist_t *vel, fx_twist_t *acc)
{
	q32_t at = m->amax_t_pt2, jt = jerk_or(m->jmax_t_pt3, at);
	q32_t ar = m->amax_r_pt2, jr = jerk_or(m->jmax_r_pt3, ar);
	m->sk_on[0] = m->sk_on[1] = false;
	if (KIN_OMNI(m->p.kin)) {
		at = fx_max64(motion_share(at), 1);
		jt = fx_max64(motion_share(jt), 1);
		for (int i = 0; i < 2; i++)
			traj_jslew(&m->sk_v[i], &m->sk_a[i], 0, at, jt);
	} else {
		traj_jslew(&vel->vx_pt, &acc->vx_pt, 0, at, jt);
	}
	traj_jslew(&vel->w_pt, &acc->w_pt, 0, ar, jr);
}

/* Differential base, toward the goal's position dist away, bearing error e
 * (the direction chosen as the acceleration-limited law chooses it). */
static void seek_diff(motion_t *m, q32_t e, q32_t dist, fx_twist_t *vel, fx_twist_t *acc)
{
	if (motion_goal_facing(m, &e))
		m->sk_on[0] = false; /* the tail ran the other way */
	q32_t ae = fx_abs64(e), dir = m->goal_reverse ? -1 : 1;
	/* Along the heading to the goal's projection on it; off by more than
	 * 45 degrees, no translation: to rest while the turn comes round. */
	q32_t proj = fx_mul_q30(dist, fx_cos_bam(fx_deg_to_bam(e)));
	q32_t u = dir * vel->vx_pt, au = dir * acc->vx_pt;
	seek_lim_t lt = lim_t(m, vt_eff(m), false), lr = lim_r(m);
	/* Near the goal the bearing swings: the turn stops while the
	 * translation runs its course; at rest there, still off the goal (the
	 * turn had not come round), the unit first faces it exactly, then
	 * goes the rest straight. */
	bool near = dist < NEAR_MM, moving = u != 0 || au != 0 || m->sk_on[0];
	bool facing = (vel->w_pt == 0 && acc->w_pt == 0 && !m->sk_on[1] && ae < TINY_DEG) ||
		      dist < LAND_DIFF_MM;
	bool go = near ? moving || facing : ae < fx_from_int(45) || m->sk_on[0];
	bool planned = false;
	if (go)
		planned = seek_axis(m, 0, &u, &au, proj, &lt, true);
	else
		traj_jslew(&u, &au, 0, lt.a, lt.j);
	vel->vx_pt = dir * u;
	acc->vx_pt = dir * au;
	if (near && (go || u != 0 || au != 0)) {
		m->sk_on[1] = false;
		traj_jslew(&vel->w_pt, &acc->w_pt, 0, lr.a, lr.j);
	} else {
		seek_axis(m, 1, &vel->w_pt, &acc->w_pt, e, &lr, !planned);
	}
}

/* Mecanum base: the goal dx, dy away in the body frame, on the axes of the
 * bearing seen at the last retarget (the caller forms the body twist). */
static void seek_omni(motion_t *m, q32_t dx, q32_t dy, fx_twist_t *vel, fx_twist_t *acc)
{
	q32_t du, dn, vc = vt_eff(m);
	to_axes(dx, dy, m->sk_c, m->sk_s, &du, &dn);
	/* Across the line as well (the retarget left motion across it, or
	 * the pose moved off it): each axis within 1 / sqrt(2) of the speed
	 * too. Less than the landing's tolerance off it is not motion. */
	bool across = m->sk_v[1] | m->sk_a[1] | m->sk_on[1] || dn >= LAND_MM || dn <= -LAND_MM;
	if (across)
		vc = motion_share(vc);
	seek_lim_t l = lim_t(m, vc, true);
	bool planned = seek_axis(m, 0, &m->sk_v[0], &m->sk_a[0], du, &l, true);
	if (across)
		seek_axis(m, 1, &m->sk_v[1], &m->sk_a[1], dn, &l, !planned);
	seek_lim_t lr = lim_r(m);
	traj_jslew(&vel->w_pt, &acc->w_pt, 0, lr.a, lr.j);
}

/* A new goal: the tails are dropped; a mecanum base takes the goal's
 * bearing as its axes and its velocity and acceleration onto them. */
void motion_seek_retarget(motion_t *m)
{
	m->sk_on[0] = m->sk_on[1] = false;
	m->ln_next = LN_NEXT_NONE; /* the line buffers serve the tails now */
	/* The dips' bound (stop_room) for a tick's distance at the limit. */
	bool omni = KIN_OMNI(m->p.kin);
	seek_lim_t lt = lim_t(m, 0, omni), lr = lim_r(m);
	m->sk_dip[0] = traj_sc_ticks_bound(m->vmax_t_pt, lt.a, lt.j);
	m->sk_dip[1] = traj_sc_ticks_bound(m->vmax_r_pt, lr.a, lr.j);
	if (!omni)
		return;
	q32_t wx = m->goal.x_mm - m->ref.x_mm, wy = m->goal.y_mm - m->ref.y_mm, dx, dy;
	motion_body_to_world(-m->ref.th_deg, wx, wy, &dx, &dy);
	int32_t c, s;
	if (motion_unit_dir(dx, dy, &c, &s) == 0) {
		c = 1 << 30;
		s = 0;
	}
	m->sk_c = c;
	m->sk_s = s;
	to_axes(m->vel.vx_pt, m->vel.vy_pt, c, s, &m->sk_v[0], &m->sk_v[1]);
	to_axes(m->vacc.vx_pt, m->vacc.vy_pt, c, s, &m->sk_a[0], &m->sk_a[1]);
}

/* The goal heading once the position is reached: the rotation axis's
 * point (its tail in lnb[1]); true when it is on it. */
static bool seek_heading(motion_t *m, fx_twist_t *vel, fx_twist_t *acc)
{
	q32_t e = fx_wrap_deg(m->goal.th_deg - m->ref.th_deg);
	seek_lim_t lr = lim_r(m);
	seek_axis(m, 1, &vel->w_pt, &acc->w_pt, e, &lr, true);
	return !m->sk_on[1] && vel->w_pt == 0 && acc->w_pt == 0 && fx_abs64(e) < TINY_DEG;
}

void motion_seek_tick(motion_t *m, fx_twist_t *out)
{
	bool braking = m->stopping || m->paused;
	fx_twist_t vel = m->vel, acc = m->vacc;
	q32_t wx = m->goal.x_mm - m->ref.x_mm, wy = m->goal.y_mm - m->ref.y_mm;
	q32_t dist = fx_hypot(wx, wy);
	bool omni = KIN_OMNI(m->p.kin);
	if (braking) {
		seek_brake(m, &vel, &acc);
	} else if (m->goal_position_done) {
		vel.vx_pt = vel.vy_pt = acc.vx_pt = acc.vy_pt = 0;
		m->sk_v[0] = m->sk_v[1] = m->sk_a[0] = m->sk_a[1] = 0;
		if (seek_heading(m, &vel, &acc)) {
			m->ref.th_deg = m->goal.th_deg;
			m->mode = MODE_IDLE;
		}
	} else if (omni) {
		q32_t dx, dy;
		motion_body_to_world(-m->ref.th_deg, wx, wy, &dx, &dy);
		seek_omni(m, dx, dy, &vel, &acc);
	} else {
		q32_t e = fx_wrap_deg(fx_atan2_deg(wy, wx) - m->ref.th_deg);
		seek_diff(m, e, dist, &vel, &acc);
	}
	if (omni) { /* the translation is on the axes */
		from_axes(m, &vel);
		acc.vx_pt = vel.vx_pt - m->vel.vx_pt;
		acc.vy_pt = vel.vy_pt - m->vel.vy_pt;
	}
	m->vel = vel;
	m->vacc = acc;
	*out = vel;
	odom_integrate(&m->ref, out, NULL);
	bool still = vel.vx_pt == 0 && vel.vy_pt == 0 && !m->sk_on[0] && !m->sk_on[1];
	if (!m->goal_position_done && !braking && still && acc.vx_pt == 0 && acc.vy_pt == 0 &&
	    fx_hypot(m->goal.x_mm - m->ref.x_mm, m->goal.y_mm - m->ref.y_mm) <
		(omni ? LAND_MM : LAND_DIFF_MM)) {
		m->ref.x_mm = m->goal.x_mm;
		m->ref.y_mm = m->goal.y_mm;
		m->goal_position_done = true;
	}
	if (braking && twist_zero(&m->vel) && m->stopping) {
		m->stopping = false;
		m->mode = MODE_IDLE;
	}
}
