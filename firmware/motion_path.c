/* Motion engine: the tick. motion_tick dispatches on the mode; the path
 * mode executes the queued commands piece by piece (a turn, a line, an arc,
 * a cruise corner) on the profiles of traj.c. */
#include "motion_priv.h"

#include <stddef.h>

#define DEG_TO_RAD_Q32 ((q32_t)74961321) /* pi / 180 */
/* Heading change below which a corner step turns its entry direction to
 * first order (0.002 deg: 3.5e-5 rad, squared half below 2^-30). */
#define CORNER_SMALL_DEG ((q32_t)8589935)

static void seg_line(motion_t *m, const fx_pose_t *from, q32_t tx, q32_t ty, q32_t th_end)
{
	seg_t *g = &m->seg;
	*g = (seg_t){0};
	g->kind = SEG_LINE;
	g->p0 = *from;
	g->len = motion_unit_dir(tx - from->x_mm, ty - from->y_mm, &g->ux, &g->uy);
	g->p_end.x_mm = tx;
	g->p_end.y_mm = ty;
	/* Travel sign relative to the heading (moveForward may go backward). */
	int32_t hs, hc;
	fx_sincos_bam(fx_deg_to_bam(from->th_deg), &hs, &hc);
	int64_t dot = (int64_t)g->ux * hc + (int64_t)g->uy * hs;
	g->dir = dot < 0 ? -1 : 1;
	g->dth = fx_wrap_deg(th_end - from->th_deg);
	g->p_end.th_deg = fx_wrap_deg(from->th_deg + g->dth);
	if (g->dth != 0)
		g->omni_k = fx_div(g->len, fx_abs64(g->dth));
}

static void seg_turn(motion_t *m, q32_t angle)
{
	seg_t *g = &m->seg;
	*g = (seg_t){0};
	g->kind = SEG_TURN;
	g->p0 = m->ref;
	g->dir = angle < 0 ? -1 : 1;
	g->len = fx_abs64(angle);
	g->p_end = m->ref;
	g->p_end.th_deg = fx_wrap_deg(m->ref.th_deg + angle);
}

/* Where cruise command c's straight part ends (its corner's entry, or its
 * waypoint), and its length from (x, y) along its direction: no square
 * root or division in the tick that blends into it. */
static inline void cruise_line_end(const motion_cmd_t *c, fx_pose_t *e)
{
	q32_t t = c->has_corner ? c->corner.t_mm : 0;
	e->x_mm = c->target.x_mm - fx_mul_q30(t, c->ux);
	e->y_mm = c->target.y_mm - fx_mul_q30(t, c->uy);
}

static inline q32_t line_len_from(const motion_cmd_t *c, const fx_pose_t *e, q32_t x, q32_t y)
{
	q32_t len = fx_mul_q30(e->x_mm - x, c->ux) + fx_mul_q30(e->y_mm - y, c->uy);
	return len > 0 ? len : 0;
}

/* The straight part of cruise command c, from the reference (its start, or
 * the previous corner's exit) along the direction planned when it was
 * queued. The heading is already along the line (turn or corner before). */
static void cruise_line(motion_t *m, const motion_cmd_t *c)
{
	const fx_pose_t *r = &m->ref;
	/* Only the fields a line or the corner after it reads are set: clearing
	 * the whole piece costs more than the rest of its setup. */
	seg_t *g = &m->seg;
	g->kind = SEG_LINE;
	g->dir = 1;
	g->s = 0;
	g->p0 = *r;
	g->ux = c->ux;
	g->uy = c->uy;
	g->dth = 0;
	g->cx = g->cy = 0;
	cruise_line_end(c, &g->p_end);
	g->p_end.th_deg = r->th_deg;
	g->len = line_len_from(c, &g->p_end, r->x_mm, r->y_mm);
}

/* The corner of cruise command c, from the reference: the piece still holds
 * c's line (cruise_line), so only the corner's own fields are set. */
static void corner_piece(motion_t *m, const motion_cmd_t *c)
{
	seg_t *g = &m->seg;
	g->kind = SEG_CORNER;
	g->s = 0;
	g->p0 = m->ref;
	g->h = 0;
	g->corner = c->corner;
	g->len = 2 * c->corner.lh_mm;
	g->p_end.x_mm = c->exit_x_mm;
	g->p_end.y_mm = c->exit_y_mm;
	g->p_end.th_deg = fx_wrap_deg(m->ref.th_deg + c->corner.phi_deg);
}

/* What one stage of a command did: set up a piece, found nothing to do
 * (its next stage runs), or found the command finished. */
typedef enum { STAGE_DONE, STAGE_PIECE, STAGE_SKIP } stage_t;

static stage_t forward_stage(motion_t *m, motion_cmd_t *c)
{
	const fx_pose_t *r = &m->ref;
	if (c->stage++ > 0)
		return STAGE_DONE;
	seg_line(m, r, c->target.x_mm, c->target.y_mm, r->th_deg);
	if (m->seg.len < TINY_MM)
		return STAGE_SKIP;
	return STAGE_PIECE;
}

static stage_t turn_stage(motion_t *m, motion_cmd_t *c)
{
	if (c->stage++ > 0)
		return STAGE_DONE;
	if (fx_abs64(c->angle_deg) < 1)
		return STAGE_SKIP;
	seg_turn(m, c->angle_deg);
	return STAGE_PIECE;
}

static stage_t arc_stage(motion_t *m, motion_cmd_t *c)
{
	const fx_pose_t *r = &m->ref;
	if (c->stage++ > 0)
		return STAGE_DONE;
	seg_t *g = &m->seg;
	*g = (seg_t){0};
	g->kind = SEG_ARC;
	g->p0 = *r;
	g->cx = c->cx_mm;
	g->cy = c->cy_mm;
	g->dir = c->angle_deg < 0 ? -1 : 1;
	g->len = fx_abs64(c->angle_deg);
	g->p_end = c->target;
	q32_t radius = fx_hypot(r->x_mm - c->cx_mm, r->y_mm - c->cy_mm);
	g->arc_k = fx_mul(radius, DEG_TO_RAD_Q32);
	/* Rigid rotation about the centre c (body frame): the body
	 * moves at w x (-c) = w (c.y, -c.x). */
	g->arc_kx = fx_mul(c->sy_mm, DEG_TO_RAD_Q32);
	g->arc_ky = -fx_mul(c->sx_mm, DEG_TO_RAD_Q32);
	if (g->len < 1)
		return STAGE_SKIP;
	return STAGE_PIECE;
}

/* A line to a pose, omni base: translation and rotation together, unless
 * the move is mostly rotation (under 1 mm per degree): then the heading
 * would ride on a tiny path ratio, so turn first and then translate. */
static stage_t line_stage_omni(motion_t *m, motion_cmd_t *c)
{
	const fx_pose_t *r = &m->ref;
	q32_t dx = c->target.x_mm - r->x_mm, dy = c->target.y_mm - r->y_mm;
	q32_t dist = fx_hypot(dx, dy);
	q32_t a = fx_wrap_deg(c->target.th_deg - r->th_deg);
	bool split = fx_abs64(a) > FX_ONE / 1000 && dist < fx_abs64(a);
	switch (c->stage++) {
	case 0:
		if (dist >= TINY_MM && !split) {
			c->stage = 2;
			seg_line(m, r, c->target.x_mm, c->target.y_mm, c->target.th_deg);
			return STAGE_PIECE;
		}
		if (fx_abs64(a) < 1)
			return STAGE_SKIP;
		seg_turn(m, a);
		return STAGE_PIECE;
	case 1:
		if (dist < TINY_MM)
			return STAGE_SKIP;
		seg_line(m, r, c->target.x_mm, c->target.y_mm, r->th_deg);
		return STAGE_PIECE;
	default:
		return STAGE_DONE;
	}
}

/* A line to a pose, differential base: face the target, drive to it, turn
 * to the final heading. */
static stage_t line_stage_diff(motion_t *m, motion_cmd_t *c)
{
	const fx_pose_t *r = &m->ref;
	q32_t dx = c->target.x_mm - r->x_mm, dy = c->target.y_mm - r->y_mm;
	q32_t dist = fx_hypot(dx, dy);
	switch (c->stage++) {
	case 0: {
		if (dist < TINY_MM)
			return STAGE_SKIP;
		q32_t a = fx_wrap_deg(fx_atan2_deg(dy, dx) - r->th_deg);
		if (fx_abs64(a) < 1)
			return STAGE_SKIP;
		seg_turn(m, a);
		return STAGE_PIECE;
	}
	case 1:
		if (dist < TINY_MM)
			return STAGE_SKIP;
		seg_line(m, r, c->target.x_mm, c->target.y_mm, r->th_deg);
		return STAGE_PIECE;
	case 2: {
		q32_t a = fx_wrap_deg(c->target.th_deg - r->th_deg);
		if (!c->has_heading || fx_abs64(a) < 1)
			return STAGE_SKIP;
		seg_turn(m, a);
		return STAGE_PIECE;
	}
	default:
		return STAGE_DONE;
	}
}

/* The turn that faces cruise command c's waypoint from pose r (0: none,
 * or no distance to it). */
static q32_t cruise_face(const motion_cmd_t *c, const fx_pose_t *r)
{
	q32_t dx = c->target.x_mm - r->x_mm, dy = c->target.y_mm - r->y_mm;
	if (fx_hypot(dx, dy) < TINY_MM)
		return 0;
	return fx_wrap_deg(fx_atan2_deg(dy, dx) - r->th_deg);
}

/* A cruise waypoint: its line's start becomes known (and the corner into
 * it is planned) when it runs first; it turns to face along its line
 * unless it arrives out of a corner, then runs its line. */
static stage_t cruise_stage(motion_t *m, motion_cmd_t *c)
{
	const fx_pose_t *r = &m->ref;
	switch (c->stage++) {
	case 0: {
		if (!c->start_known) {
			motion_cruise_set_start(c, r->x_mm, r->y_mm);
			if (m->q_count < 2 || !motion_plan_corner(m, 0))
				motion_backward_pass(m);
		}
		if (m->v > 0)
			return STAGE_SKIP; /* arriving out of a corner, already aligned */
		q32_t a;
		if (ONLINE_JERK && m->face_ok && m->face_ref.x_mm == r->x_mm &&
		    m->face_ref.y_mm == r->y_mm && m->face_ref.th_deg == r->th_deg &&
		    m->face_to.x_mm == c->target.x_mm && m->face_to.y_mm == c->target.y_mm)
			a = m->face_a; /* worked out ahead, from here */
		else
			a = cruise_face(c, r);
		m->face_ok = false;
		if (fx_abs64(a) < 1)
			return STAGE_SKIP;
		seg_turn(m, a);
		return STAGE_PIECE;
	}
	case 1:
		if (c->len_mm < TINY_MM)
			return STAGE_SKIP;
		cruise_line(m, c);
		return STAGE_PIECE;
	default:
		/* Its corner, if any, began as its line ended
		 * (path_tick): nothing is left. */
		return STAGE_DONE;
	}
}

static stage_t command_stage(motion_t *m, motion_cmd_t *c)
{
	switch (c->kind) {
	case MCMD_FORWARD:
		return forward_stage(m, c);
	case MCMD_TURN:
		return turn_stage(m, c);
	case MCMD_ARC:
		return arc_stage(m, c);
	case MCMD_LINE:
		if (KIN_OMNI(m->p.kin))
			return line_stage_omni(m, c);
		return line_stage_diff(m, c);
	case MCMD_CRUISE:
		return cruise_stage(m, c);
	default:
		return STAGE_DONE;
	}
}

/* Sets up the next piece of the head command; false when it is finished. */
static bool next_piece(motion_t *m)
{
	motion_cmd_t *c = q_at(m, 0);
	stage_t st;
	do
		st = command_stage(m, c);
	while (st == STAGE_SKIP);
	return st == STAGE_PIECE;
}

/* What a piece allows of a translational limit t (mm per tick, or per
 * tick squared) and a rotational limit r (deg alike), for the set limits
 * and the hard ones: speeds and accelerations take the same form. A turn
 * has r; an arc the lower of r and t over its mm per degree; a line whose
 * heading turns with the path (omni) the lower of t and r times its mm per
 * degree, kept 1/4096 below as omni_k is rounded; any other line t. A
 * corner's acceleration is the lower of t and half of r times its mm per
 * degree, the other half is the curvature change (traj.h,
 * traj_corner_rates); its speed cap is planned (corner_vrot). */
static inline q32_t piece_limit(const seg_t *g, q32_t t, q32_t r)
{
	switch (g->kind) {
	case SEG_TURN:
		return r;
	case SEG_ARC:
		return fx_min64(r, fx_div(t, g->arc_k));
	case SEG_LINE:
		if (g->dth != 0) {
			q32_t rk = fx_mul(r, g->omni_k);
			return fx_min64(t, rk - (rk >> 12));
		}
		return t;
	case SEG_CORNER:
		return fx_min64(t, fx_mul(r, g->corner.k_mm_deg) / 2);
	default:
		return t;
	}
}

/* Stands in for an unlimited (0) jerk in piece_limit, which takes the
 * lower of two; a piece limit above JERK_REAL (the largest configurable
 * jerk at the slowest tick is about 2^35 raw) is none. */
#define JERK_NONE ((q32_t)1 << 60)
#define JERK_REAL ((q32_t)1 << 40)

/* The active piece's jerk limit for translation and rotation jerks t, r
 * (0 = unlimited); 0 when neither limits it. */
static q32_t piece_jerk(const seg_t *g, q32_t t, q32_t r)
{
	if (t == 0 && r == 0)
		return 0;
	q32_t j = piece_limit(g, t ? t : JERK_NONE, r ? r : JERK_NONE);
	return j >= JERK_REAL ? 0 : j;
}

/* Speed cap and acceleration of the active piece; a corner's are those the
 * backward pass planned with (corner_a_pt2: piece_limit at the set rates). */
static void piece_limits(const motion_t *m, q32_t *vmax, q32_t *a)
{
	const seg_t *g = &m->seg;
	switch (g->kind) {
	case SEG_TURN:
	case SEG_ARC:
	case SEG_LINE:
		*vmax = piece_limit(g, vt_eff(m), m->v_r_pt);
		*a = piece_limit(g, m->a_t_pt2, m->a_r_pt2);
		break;
	case SEG_CORNER: {
		const motion_cmd_t *c = q_at((motion_t *)m, 0);
		*vmax = fx_min64(vt_eff(m), c->corner_vrot_pt);
		*a = c->corner_a_pt2;
		break;
	}
	default:
		*vmax = 0;
		*a = m->a_t_pt2;
	}
	if (*a < 1)
		*a = 1;
}

/* Distance beyond the active piece's end that the profile may count on
 * to stop within: a blended corner's virtual stop (traj.h). */
static q32_t piece_horizon_extra(motion_t *m)
{
	const seg_t *g = &m->seg;
	if (m->q_count == 0)
		return 0;
	motion_cmd_t *c = q_at(m, 0);
	if (c->kind != MCMD_CRUISE || !c->has_corner)
		return 0;
	/* Both planned by the backward pass, with the rates piece_limits gives
	 * these pieces. */
	if (g->kind == SEG_LINE)
		return c->line_extra_mm;
	if (g->kind == SEG_CORNER)
		return c->corner_extra_mm;
	return 0;
}

/* Moves the reference pose, in place, from the progress g->s to s along
 * the active piece (the caller then sets g->s). */
static void piece_advance(motion_t *m, q32_t s)
{
	seg_t *g = &m->seg;
	q32_t s_old = g->s;
	fx_pose_t *out = &m->ref;
	switch (g->kind) {
	case SEG_LINE:
		out->x_mm = g->p0.x_mm + fx_mul_q30(s, g->ux);
		out->y_mm = g->p0.y_mm + fx_mul_q30(s, g->uy);
		if (g->dth != 0) {
			/* The fraction of the line covered, Q30: exactly 1 at its
			 * end, so the heading arrives on dth without a final step. */
			int32_t frac = (int32_t)(fx_div(s, g->len) >> 2);
			out->th_deg = fx_wrap_deg(g->p0.th_deg + fx_mul_q30(g->dth, frac));
		}
		break;
	case SEG_TURN:
		out->th_deg = fx_wrap_deg(g->p0.th_deg + g->dir * s);
		break;
	case SEG_ARC: {
		uint32_t b = fx_deg_to_bam(g->dir * s);
		int32_t co, si;
		fx_sincos_bam(b, &si, &co);
		q32_t rx = g->p0.x_mm - g->cx, ry = g->p0.y_mm - g->cy;
		out->x_mm = g->cx + fx_mul_q30(rx, co) - fx_mul_q30(ry, si);
		out->y_mm = g->cy + fx_mul_q30(rx, si) + fx_mul_q30(ry, co);
		out->th_deg = fx_wrap_deg(g->p0.th_deg + g->dir * s);
		break;
	}
	case SEG_CORNER: {
		/* Heading is exact along the clothoids; position integrates the
		 * step at the midpoint heading. Within one clothoid the heading is
		 * quadratic in s (h'' = +-phi / Lh^2), so the midpoint's is the
		 * mean of the ends minus h'' ds^2 / 8: one evaluation a step. The
		 * step starts at the progress g->s, whose heading is g->h. */
		q32_t ds = s - s_old;
		q32_t lh = g->corner.lh_mm;
		q32_t h1 = traj_corner_heading(&g->corner, s);
		q32_t hm;
		if (s_old == 0 && s <= lh) {
			/* The step in from the line: h(s / 2) = h1 / 4 exactly. */
			hm = h1 / 4;
		} else if (s <= lh || s_old >= lh) {
			int64_t du = traj_corner_u(&g->corner, ds); /* ds / Lh, Q30 */
			int32_t du2 = (int32_t)((du * du) >> 30);
			q32_t corr = fx_mul_q30(g->corner.phi_deg, du2) / 8;
			hm = (g->h + h1) / 2 + (s <= lh ? -corr : corr);
		} else {
			hm = traj_corner_heading(&g->corner, s_old + ds / 2);
		}
		g->h = h1;
		int32_t sn, cs;
		if (hm < CORNER_SMALL_DEG && hm > -CORNER_SMALL_DEG) {
			/* Entering (the step that blends in from the line): the
			 * entry direction turned by hm to first order; the error,
			 * hm^2 / 2 in radians, is below the Q30 resolution. */
			int64_t r30 = fx_mul_fit(hm, DEG_TO_RAD_Q32) >> 2;
			cs = g->ux - (int32_t)((g->uy * r30) >> 30);
			sn = g->uy + (int32_t)((g->ux * r30) >> 30);
		} else {
			fx_sincos_bam(fx_deg_to_bam(g->p0.th_deg + hm), &sn, &cs);
		}
		out->x_mm += fx_mul_q30(ds, cs);
		out->y_mm += fx_mul_q30(ds, sn);
		out->th_deg = fx_wrap_deg(g->p0.th_deg + h1);
		break;
	}
	default:
		break;
	}
}

/* Body twist that carries the reference from a to b (midpoint heading). */
static void twist_between(const motion_t *m, const fx_pose_t *a, const fx_pose_t *b, fx_twist_t *t)
{
	q32_t dth = fx_wrap_deg(b->th_deg - a->th_deg);
	q32_t dx = b->x_mm - a->x_mm, dy = b->y_mm - a->y_mm;
	uint32_t mid = fx_deg_to_bam(a->th_deg + dth / 2);
	int32_t c, s;
	fx_sincos_bam(mid, &s, &c);
	t->vx_pt = fx_mul_q30(dx, c) + fx_mul_q30(dy, s);
	t->vy_pt = KIN_OMNI(m->p.kin) ? fx_mul_q30(dy, c) - fx_mul_q30(dx, s) : 0;
	t->w_pt = dth;
}

/* True when the piece just finished flows into the next without stopping. */
static bool blends_onward(motion_t *m, uint8_t finished_kind)
{
	if (m->q_count == 0)
		return false;
	motion_cmd_t *c = q_at(m, 0);
	if (c->kind != MCMD_CRUISE || !c->has_corner)
		return false;
	return finished_kind == SEG_LINE || finished_kind == SEG_CORNER;
}

/* The profile that runs is dropped (braking, a new plan). */
static void plan_drop(motion_t *m)
{
	m->sc_on = m->ln_on = m->glide = m->hold_on = false;
}

/* A stop came to rest: the commands it braked through are discarded. */
static void stop_done(motion_t *m)
{
	m->stopping = false;
	m->acc = 0;
	plan_drop(m);
	while (m->stop_drop)
		pop(m);
	m->seg.kind = SEG_NONE;
	m->mode = m->q_count ? MODE_PATH : MODE_IDLE;
}

/* The speed the active piece ends at under jerk limits: a cruise line's
 * corner speed (within the line's own cap, as traj_ln_plan takes it), or
 * rest. */
static q32_t piece_cout(motion_t *m)
{
	if (m->seg.kind != SEG_LINE || !blends_onward(m, SEG_LINE))
		return 0;
	return fx_min64(q_at(m, 0)->vend_pt, m->lim_vmax - 1);
}

/* The line of rem from the present speed to cout at the piece's limits:
 * the plan made ahead for it (motion_plan_idle), or one made now. */
static bool plan_line(motion_t *m, q32_t rem, q32_t cout)
{
	const q32_t *k = m->ln_key;
	m->plan_cap = m->lim_vmax;
	/* One test for the six: this is a cruise line's first tick. */
	bool same = m->ln_next == LN_NEXT_PLAN &&
		    ((k[0] ^ rem) | (k[1] ^ m->v) | (k[2] ^ cout) | (k[3] ^ m->lim_vmax) |
		     (k[4] ^ m->lim_a) | (k[5] ^ m->lim_j)) == 0;
	m->ln_next = LN_NEXT_NONE;
	if (same)
		m->ln_i ^= 1;
	else if (!traj_ln_plan(ln_run(m), rem, m->v, cout, m->lim_vmax, m->lim_a, m->lim_j) &&
		 (cout == 0 ||
		  !traj_ln_plan(ln_run(m), rem, m->v, 0, m->lim_vmax, m->lim_a, m->lim_j)))
		return false; /* the caller brakes, and plans again at rest */
	m->ln_on = true;
	return true;
}

/* A new speed limit while the profile runs (setVelocity, the caution
 * input). Lowered below what lies ahead, the unit glides down to it: the
 * acceleration to zero at the jerk, then the line from that speed (traj.h,
 * section 6); in the last ramp to rest, whose speeds only fall, or in a
 * corner held at its speed, it brakes at the limits if it is above the new
 * one (and plans again at rest); in the last ramp into a corner the ramp
 * runs on to the corner's speed and the corner brakes. Raised, the line from the speed held
 * (zero acceleration: nothing steps) is planned at once; accelerating or
 * slowing, the profile runs on until it holds. */
/* Whether the running plan is in its last ramp (the S-curve's, or the
 * line's into its end speed), where its speed only falls. */
static bool last_ramp(const motion_t *m)
{
	const traj_ln_t *ln = &m->lnb[m->ln_i];
	return m->sc_on ? m->sc.k >= m->sc.nv : ln->k > ln->l1 + ln->hold;
}

static void plan_new_limit(motion_t *m)
{
	if (m->hold_on) {
		if (m->hold_v > m->lim_vmax)
			plan_drop(m);
		return;
	}
	const traj_ln_t *ln = ln_run(m);
	q32_t top = m->sc_on ? m->sc.vm : fx_max64(ln->w, m->v);
	if (last_ramp(m)) {
		/* Into a corner the ramp runs on to the corner's speed, which
		 * the corner's rotation needs (a glide here would give up the
		 * braking); the corner brakes to the new limit if it is above
		 * it (plan_at_speed). */
		if (m->v >= m->lim_vmax && (m->sc_on || ln->cout == 0))
			plan_drop(m);
	} else if (m->lim_vmax <= top || (m->lim_vmax > m->plan_cap && m->acc == 0)) {
		plan_drop(m);
		m->glide = true;
	}
}

/* A waypoint queued while a line runs to rest on its plan made the line a
 * blend (motion_plan_corner): it glides into the new corner (the
 * acceleration to zero at the jerk, then the line from that speed to the
 * corner's, as for a new speed limit), unless it is already in its last
 * ramp to rest, which runs on and stops on the waypoint (no corner is
 * fitted then). */
bool motion_line_may_blend(const motion_t *m)
{
	return (m->sc_on || m->ln_on) && !last_ramp(m);
}

void motion_line_glide(motion_t *m)
{
	plan_drop(m);
	m->glide = true;
}

/* A waypoint queued later can lower the speed of the corner the running
 * line brakes into (the line after it is short, the corner after that
 * sharp). The line's plan still ends at the old speed: it glides and plans
 * again from its speed; in its last ramp, which cannot turn round, it
 * brakes at the limits (and plans again at rest). */
void motion_line_cout_check(motion_t *m)
{
	const traj_ln_t *ln = ln_run(m);
	if (m->mode != MODE_PATH || m->seg.kind != SEG_LINE || !m->ln_on || m->lim_j == 0 ||
	    ln->cout <= piece_cout(m))
		return;
	if (last_ramp(m))
		plan_drop(m);
	else
		motion_line_glide(m);
}

/* A piece begun at speed (a cruise line or corner, under jerk limits): a
 * corner holds the speed it is entered at (its rotation is the clothoid's),
 * a line runs from it to its corner's speed (traj.h, section 6). */
static void plan_at_speed(motion_t *m, q32_t rem)
{
	if (m->seg.kind == SEG_CORNER) {
		m->hold_on =
		    m->hold_v > 0 && m->hold_v <= m->lim_vmax && fx_abs64(m->acc) <= m->lim_j;
		m->plan_cap = m->lim_vmax;
		return;
	}
	plan_line(m, rem, piece_cout(m));
}

/* A glide's tick (sc_speed): the acceleration to zero at the jerk, then
 * the line from that speed to the piece's end speed. True with the speed
 * in *u, false when no line fits and the piece must brake. */
static bool glide_step(motion_t *m, q32_t rem, q32_t *u)
{
	if (m->acc != 0) {
		/* Below the profile's speeds, so braking still fits. */
		q32_t a =
		    m->acc > 0 ? fx_max64(m->acc - m->lim_j, 0) : fx_min64(m->acc + m->lim_j, 0);
		m->acc = a;
		/* Short of a stop, the step may cross into the corner. */
		*u = blends_onward(m, m->seg.kind) ? m->v + a : fx_min64(m->v + a, rem);
		return true;
	}
	m->glide = false;
	q32_t cout = piece_cout(m);
	if (plan_line(m, rem, cout)) {
		*u = traj_ln_next(ln_run(m));
		m->acc = *u - m->v;
		return true;
	}
	if (!blends_onward(m, m->seg.kind) || m->v > cout)
		return false;
	/* No room for the line into the corner, already at or below the
	 * corner's speed: the speed holds into the corner (braking at the
	 * line's limits would overrun the corner's share of the rotation's
	 * acceleration). */
	m->hold_on = true;
	m->hold_v = m->v;
	m->plan_cap = m->lim_vmax;
	*u = m->v;
	return true;
}

/* A piece under a jerk limit. From rest to rest it runs on the planned
 * S-curve (traj.h, section 4) over what is left of it; a cruise line runs
 * from its speed to its corner's (section 6), and a corner holds its
 * speed; after a new speed limit the line from the speed then. Braking
 * (pause, stop), or resumed while still braking, it changes speed toward
 * rest at the limits (section 5) and plans the rest of the piece once at
 * rest. Out of line: the acceleration-limited pieces do not pay for it. */
static q32_t sc_speed(motion_t *m, bool braking)
{
	/* A corner held at its speed, limit unchanged: first, as its ticks
	 * are a cruise's dearest. */
	if (ONLINE_JERK && m->hold_on && !braking && m->lim_vmax == m->plan_cap) {
		m->acc = m->hold_v - m->v; /* a brake from here starts from it */
		return m->hold_v;
	}
	q32_t rem = m->seg.len - m->seg.s;
	if (braking) {
		plan_drop(m);
		m->fresh = false;
	} else if (m->fresh) {
		m->fresh = false;
		if (ONLINE_JERK && m->v > 0)
			plan_at_speed(m, rem);
	} else if (!ONLINE_JERK) {
		if (m->sc_on && m->lim_vmax <= m->sc.vm)
			plan_drop(m); /* a lower limit: brake, and plan again at rest */
	} else if ((m->sc_on || m->ln_on || m->hold_on) && m->v > 0 && m->lim_vmax != m->plan_cap) {
		plan_new_limit(m);
	}
	if (ONLINE_JERK && m->hold_on) {
		/* The crossing into the next line is path_tick's. */
		m->acc = m->hold_v - m->v;
		return m->hold_v;
	}
	if (ONLINE_JERK && m->glide) {
		q32_t u;
		if (glide_step(m, rem, &u))
			return u;
		/* No room for the line to rest: brake, and plan again at rest. */
	}
	if (braking || (!m->sc_on && !m->ln_on && m->v > 0)) {
		q32_t v = m->v, amax = piece_limit(&m->seg, m->amax_t_pt2, m->amax_r_pt2);
		q32_t jb = piece_jerk(&m->seg, m->jmax_t_pt3, m->jmax_r_pt3);
		if (jb > 0) {
			traj_jslew(&v, &m->acc, 0, amax, jb);
		} else { /* no jerk limit to brake at: as without */
			v = fx_max64(v - amax, 0);
			m->acc = v - m->v;
		}
		/* The fastest way to rest is never slower than the plan, which
		 * stops by the end: this only guards the raw unit. A piece that
		 * blends into the next brakes on across it. */
		return blends_onward(m, m->seg.kind) ? v : fx_min64(v, rem);
	}
	if (!m->sc_on && !m->ln_on && m->acc != 0) {
		/* The brake landed last tick (its last change of speed up to
		 * the braking jerk): a tick at rest before the plan starts. */
		m->acc = 0;
		return 0;
	}
	if (!m->sc_on && !m->ln_on) {
		/* From rest: to rest on the S-curve, into a corner on the line. */
		q32_t cout = piece_cout(m);
		m->plan_cap = m->lim_vmax;
		if (!ONLINE_JERK || cout == 0 || !plan_line(m, rem, cout)) {
			if (!traj_sc_plan(&m->sc, rem, m->lim_vmax, m->lim_a, m->lim_j)) {
				m->lim_j = 0; /* no room for the rounding margins: as without */
				return traj_step(m->v, rem, m->lim_vmax, m->lim_a);
			}
			m->sc_on = true;
		}
	}
	q32_t u = ONLINE_JERK && m->ln_on ? traj_ln_next(ln_run(m)) : traj_sc_next(&m->sc);
	m->acc = u - m->v;
	return u;
}

/* A cruise line's profile planned ahead (motion_plan_idle) for the length,
 * speeds and limits in ln_key; true when it planned. */
static bool plan_ahead_at(motion_t *m, q32_t len, q32_t cin, q32_t cout, q32_t v, q32_t a, q32_t j)
{
	const q32_t key[6] = {len, cin, cout, v, a, j};
	traj_ln_t *ln = ln_ahead(m);
	if (len <= 0 || j == 0)
		return false;
	/* A key tried, planned or not, is not tried again; one being planned
	 * goes on. */
	bool same = m->ln_next != LN_NEXT_NONE;
	for (int i = 0; i < 6; i++) {
		same = same && key[i] == m->ln_key[i];
		m->ln_key[i] = key[i];
	}
	if (same && m->ln_next != LN_NEXT_PART)
		return false;
	if (!same)
		ln->n = 0;
	/* A budget bounds the trial lines a call takes (the board's main loop
	 * runs the tick between calls). */
	int r = traj_ln_plan_part(ln, len, cin, cout, v, a, j,
				  m->plan_budget ? m->plan_budget : INT64_MAX);
	m->ln_next = r > 0 ? LN_NEXT_PLAN : r < 0 ? LN_NEXT_PART : LN_NEXT_KEY;
	return true;
}

/* The profile of a cruise line that has yet to begin, at the line's
 * limits. */
static bool plan_ahead(motion_t *m, q32_t len, q32_t cin, q32_t cout)
{
	return plan_ahead_at(m, len, cin, cout, vt_eff(m), m->a_t_pt2, m->j_t_pt3);
}

/* A line that glides (a waypoint queued, a new speed limit): the line from
 * the speed its glide ends at, for the tick after its acceleration reaches
 * zero (glide_step), planned ahead. From the change a0 = |acc| the glide
 * takes n = ceil(a0 / J) ticks, the k-th changing the speed by a_k =
 * a0 - k J (0 from the n-th); its speeds are v + sg A_k, A_k = k a0 -
 * J k (k + 1) / 2 for k < n and A_n = A_(n-1), and the sum of A_1 ..
 * A_(n-1) is a0 m (m + 1) / 2 - J m (m + 1) (m + 2) / 6 with m = n - 1. */
static bool plan_glide(motion_t *m)
{
	q32_t a0 = fx_abs64(m->acc), j = m->lim_j, sg = m->acc < 0 ? -1 : 1;
	int64_t n = (a0 + j - 1) / j, mm = n > 0 ? n - 1 : 0;
	/* Beyond reason (a change of 2^36 raw a tick, a glide of 4096 ticks):
	 * planned in the tick, as before. Within, the sums stay below 2^60
	 * (J m < a0). */
	if (n > 4096 || a0 > ((int64_t)1 << 36))
		return false;
	int64_t an = mm * a0 - j * (mm * (mm + 1) / 2);
	int64_t sum = n ? a0 * (mm * (mm + 1) / 2) - j * (mm * (mm + 1) * (mm + 2) / 6) + an : 0;
	q32_t v = m->v + sg * an, moved = n * m->v + sg * sum;
	return plan_ahead_at(m, m->seg.len - m->seg.s - moved, v, piece_cout(m), m->lim_vmax,
			     m->lim_a, m->lim_j);
}

/* The next cruise line's profile, planned ahead under jerk limits. The
 * head's line, before it begins, starts from rest where the unit stands
 * (a turn to face it moves no position) toward its corner's speed (one
 * that ends at rest runs the S-curve, planned in its first tick). Or the
 * line after the head's, while the head's line or corner runs: it begins
 * at the corner's exit after the corner's last step carried it o = n c -
 * R in, R what is left of the corner from the tick (2 Lh before it: a
 * line lands on its end on a tick) and the corner holding speed c, or
 * where a collinear pass's line ends, at that line's last speed. */
bool motion_plan_next_line(motion_t *m)
{
	if (!ONLINE_JERK || m->mode != MODE_PATH || m->q_count == 0 || m->stopping || m->paused ||
	    !m->jerk_any)
		return false;
	if (m->glide && m->seg.kind == SEG_LINE && m->lim_ok && m->lim_j > 0)
		return plan_glide(m);
	const motion_cmd_t *c0 = q_at(m, 0);
	if (c0->kind != MCMD_CRUISE || !c0->start_known)
		return false;
	fx_pose_t e;
	q32_t v = vt_eff(m);
	if (c0->stage < 2) {
		if (c0->stage == 0 && !m->face_ok) {
			/* Its first tick's turn to face it, with the line's. */
			m->face_ref = m->ref;
			m->face_to = c0->target;
			m->face_a = cruise_face(c0, &m->ref);
			m->face_ok = true;
			return true;
		}
		if (!c0->has_corner || c0->vend_pt == 0)
			return false;
		cruise_line_end(c0, &e);
		q32_t len = line_len_from(c0, &e, m->ref.x_mm, m->ref.y_mm);
		return plan_ahead(m, len, 0, fx_min64(c0->vend_pt, v - 1));
	}
	const motion_cmd_t *c1 = q_at(m, 1);
	if (m->q_count < 2 || m->lim_j == 0 || !c0->has_corner || c1->kind != MCMD_CRUISE ||
	    !c1->start_known || c0->stage != 2)
		return false;
	q32_t c, lh2 = 2 * c0->corner.lh_mm;
	if (m->seg.kind == SEG_LINE && m->ln_on)
		c = lh2 ? ln_run(m)->cout : ln_run(m)->cout + (ln_run(m)->r > 0);
	else if (m->seg.kind == SEG_CORNER && m->hold_on)
		c = m->hold_v;
	else
		return false;
	if (c <= 0)
		return false;
	cruise_line_end(c1, &e);
	q32_t x = lh2 ? c0->exit_x_mm : c0->target.x_mm;
	q32_t y = lh2 ? c0->exit_y_mm : c0->target.y_mm;
	/* In the corner already, what is left of it from this tick on: it
	 * may have been entered mid-tick (straight from the corner before). */
	q32_t left = m->seg.kind == SEG_CORNER ? lh2 - m->seg.s : lh2;
	q32_t o = lh2 ? ((left + c - 1) / c) * c - left : 0;
	q32_t cout = c1->has_corner ? fx_min64(c1->vend_pt, v - 1) : 0;
	return plan_ahead(m, line_len_from(c1, &e, x, y) - o, c, cout);
}

/* The three parts of path_tick below are inline by force: left to the
 * compiler (which inlines them too), the cruise's dearest tick cost 13
 * more instructions, 1,001 of its 1,000 (tools/bench/tickcost.sh). */

/* The active piece's speed this tick: the profile's step at the piece's
 * limits (computed once per piece); braking, at most the acceleration
 * limit below the present speed. */
static inline __attribute__((always_inline)) q32_t piece_speed(motion_t *m, bool braking)
{
	if (!m->lim_ok) {
		piece_limits(m, &m->lim_vmax, &m->lim_a);
		m->lim_extra = piece_horizon_extra(m);
		m->lim_cruise = -1;
		m->lim_n = -1;
		m->lim_ok = true;
	}
	if (m->lim_j > 0)
		return sc_speed(m, braking);
	q32_t d = m->seg.len - m->seg.s + m->lim_extra;
	q32_t u;
	if (m->v == m->lim_vmax) {
		/* At the cap with room to stop from it, traj_step keeps
		 * the speed: skip it (its braking distance divides). */
		if (m->lim_cruise < 0)
			m->lim_cruise = m->lim_vmax + traj_brake_dist(m->lim_vmax, m->lim_a);
		u = d >= m->lim_cruise ? m->v
				       : traj_step_near(m->v, d, m->lim_vmax, m->lim_a, &m->lim_n);
	} else {
		u = traj_step_near(m->v, d, m->lim_vmax, m->lim_a, &m->lim_n);
	}
	if (braking) {
		/* Stop at the acceleration limit, along the path. */
		q32_t amax = piece_limit(&m->seg, m->amax_t_pt2, m->amax_r_pt2);
		u = fx_min64(u, fx_max64(m->v - amax, 0));
	}
	return u;
}

/* Advances the active piece by step, short of its end; true when that
 * gave the tick's twist (a turn's; an arc's exact rates, its pose being
 * analytic). */
static inline __attribute__((always_inline)) bool piece_move(motion_t *m, q32_t step,
							     fx_twist_t *out)
{
	piece_advance(m, m->seg.s + step);
	m->seg.s += step;
	if (m->seg.kind == SEG_TURN && m->seg.s != step) {
		*out = (fx_twist_t){.w_pt = m->seg.dir * step};
		return true;
	}
	if (m->seg.kind == SEG_ARC) {
		q32_t w = m->seg.dir * step;
		out->vx_pt = fx_mul(w, m->seg.arc_kx);
		out->vy_pt = fx_mul(w, m->seg.arc_ky);
		out->w_pt = w;
		return true;
	}
	return false;
}

/* The active piece is complete: land exactly on its end (a corner's
 * integration arrives within nanometres of its planned exit). True when
 * the path flows on into the next piece; false at a stop, whose last step
 * covered the exact remainder (< a). */
static inline __attribute__((always_inline)) bool piece_finish(motion_t *m)
{
	m->ref = m->seg.p_end;
	uint8_t kind = m->seg.kind;
	m->seg.kind = SEG_NONE;
	if (!blends_onward(m, kind)) {
		m->v = 0;
		m->acc = 0;
		m->rest_tick = true;
		plan_drop(m);
		return false;
	}
	if (kind == SEG_LINE && q_at(m, 0)->corner.lh_mm != 0) {
		/* Into the corner here, not through next_piece: this is
		 * the dearest tick of a cruise (a collinear pass has no
		 * corner piece). */
		corner_piece(m, q_at(m, 0));
		limits_changed(m);
	}
	if (m->lim_j) {
		/* A cruise line under jerk limits ran into its corner (on a
		 * tick, at the line's end speed): the corner holds that speed
		 * from the next tick. A line planned from rest to rest that a
		 * waypoint queued since turned into a blend has landed (at the
		 * speed of its last step, up to a jerk): what follows runs on
		 * the acceleration-limited profile. */
		bool on = ONLINE_JERK && m->ln_on && ln_run(m)->cout > 0;
		/* Into the corner under the jerk limit however the line ended
		 * (braking, gliding; not a plan from rest that became a blend,
		 * which lands at its last step's speed): the
		 * corner holds the speed it is entered at if that steps no
		 * acceleration, or brakes (sc_speed, plan_at_speed). */
		bool corner =
		    ONLINE_JERK && kind == SEG_LINE && m->seg.kind == SEG_CORNER && !m->sc_on;
		m->hold_v = on ? ln_run(m)->cout : m->v;
		if (!on && !corner)
			m->lim_j = 0;
		plan_drop(m);
		m->fresh = on || corner;
	}
	return true;
}

/* A piece was set up: from its start, with its limits to compute. From
 * rest to rest it runs on the jerk-limited profile, its limit fixed for
 * the piece. */
static inline __attribute__((always_inline)) void piece_begin(motion_t *m)
{
	m->seg.s = 0;
	m->fresh = true;
	m->lim_j = 0;
	/* The profiles are dropped where a piece ends (piece_finish) or the
	 * unit stops (stop_done, motion_halt). A cruise line runs along its
	 * heading: its jerk is the translation's, when it is entered with an
	 * acceleration the jerk can take over (|acc| <= J, one compare);
	 * after an acceleration-limited corner's larger one the line runs as
	 * that corner did (else the jerk could not turn it round before rest,
	 * and the speed went below zero). */
	if (m->jerk_any) {
		if (ONLINE_JERK && m->seg.kind == SEG_LINE && q_at(m, 0)->kind == MCMD_CRUISE) {
			if ((uint64_t)(m->acc + m->j_t_pt3) <= (uint64_t)(2 * m->j_t_pt3))
				m->lim_j = m->j_t_pt3;
		} else if (m->v == 0 && !blends_onward(m, m->seg.kind))
			m->lim_j = piece_jerk(&m->seg, m->j_t_pt3, m->j_r_pt3);
	}
	limits_changed(m);
}

static void path_tick(motion_t *m, fx_twist_t *out)
{
	bool braking = m->paused || m->stopping;
	if (braking && m->v == 0) {
		if (m->stopping)
			stop_done(m);
		*out = (fx_twist_t){0};
		return;
	}
	fx_pose_t start = m->ref;
	q32_t budget = -1;
	/* Path length covered this tick, and whether every piece it crossed is
	 * a straight line or a corner (path length and heading change are then
	 * the whole twist of a differential base). */
	q32_t moved = 0;
	bool along = true;
	int8_t dir = 0;
	for (;;) {
		if (m->seg.kind == SEG_NONE) {
			if (m->q_count == 0) {
				m->mode = MODE_IDLE;
				m->v = 0;
				m->rest_tick = false;
				break;
			}
			if (!next_piece(m)) {
				/* A stage skipped as too short may have set up its
				 * piece: none is left, or the next command would run
				 * it (as the end of its own line). */
				m->seg.kind = SEG_NONE;
				pop(m);
				continue;
			}
			piece_begin(m);
			if (m->rest_tick) {
				/* A stop is a tick at zero before the next piece: the
				 * stopping piece's last step was its remainder (up to
				 * a), and a next piece that starts the other way takes
				 * a as well; both in one tick would change the speed by
				 * up to 2a (tests/fuzz/findings/fuzz_ops-opposite-
				 * turns-after-a-stop: 390 deg/s^2 on a 360 limit). */
				m->rest_tick = false;
				*out = (fx_twist_t){0};
				return;
			}
		}
		if (budget < 0) {
			budget = piece_speed(m, braking);
			m->v = budget;
		}
		q32_t rem = m->seg.len - m->seg.s;
		along = along &&
			(m->seg.kind == SEG_CORNER || (m->seg.kind == SEG_LINE && m->seg.dth == 0));
		if (dir == 0)
			dir = m->seg.dir;
		if (budget < rem) {
			moved += budget;
			if (piece_move(m, budget, out))
				return;
			break;
		}
		budget -= rem;
		moved += rem;
		if (!piece_finish(m) || budget == 0)
			break;
	}
	if (along && !KIN_OMNI(m->p.kin)) {
		/* The path length at the step's heading change; the odometry
		 * integrates it at the midpoint heading, as the corner's own
		 * integration does. Lines here all run the same way: only cruise
		 * lines blend, and they run forward. */
		*out = (fx_twist_t){.vx_pt = dir * moved,
				    .w_pt = fx_wrap_deg(m->ref.th_deg - start.th_deg)};
		return;
	}
	twist_between(m, &start, &m->ref, out);
}

void motion_tick(motion_t *m, const fx_pose_t *measured, fx_twist_t *out)
{
	*out = (fx_twist_t){0};
	uint8_t mode_before = m->mode;
	switch (m->mode) {
	case MODE_PATH:
		path_tick(m, out);
		m->vel = *out;
		break;
	case MODE_JOG:
	case MODE_JOYSTICK:
		motion_velocity_tick(m, out);
		odom_integrate(&m->ref, out, NULL);
		break;
	case MODE_CONTINUOUS:
		motion_continuous_tick(m, out);
		break;
	default:
		m->stopping = false;
		m->rest_tick = false; /* this tick is the one at rest */
		m->vel = (fx_twist_t){0};
		/* At rest: a jog or joystick after a path move starts its slew
		 * from zero acceleration, not from the last one it ran. */
		m->vacc = (fx_twist_t){0};
		/* Idle: follow the measured pose so relative moves start from it. */
		if (measured)
			m->ref = *measured;
		break;
	}
	if (m->mode == MODE_IDLE) {
		/* A motion that ended at rest under jerk limits leaves its last
		 * change of speed (up to the braking jerk) to settle: a tick at
		 * rest before the next (each mode's tick honours rest_tick).
		 * Without jerk limits a stop's last step is a change of speed
		 * like any other (today's profiles, bit for bit). */
		if (mode_before != MODE_IDLE && m->jerk_any)
			m->rest_tick = true;
		/* A velocity mode that ended hands over to queued path
		 * commands. */
		if (m->q_count > 0)
			m->mode = MODE_PATH;
		else if (m->joystick)
			m->mode = MODE_JOYSTICK;
	}
}
