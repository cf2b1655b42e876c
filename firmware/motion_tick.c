/* Motion engine: the tick. motion_tick dispatches on the mode; the path
 * mode executes the queued commands piece by piece (a turn, a line, an arc,
 * a cruise corner) on the profiles of traj.c. Each command runs in stages,
 * each setting up one piece: a cruise waypoint's turn and line here, with
 * the corner set up as its line ends (the crossing is a cruise's dearest
 * tick); the other commands' stages in motion_piece.c. */
#include "motion_priv.h"

#include <stddef.h>

/* Heading change below which a corner step turns its entry direction to
 * first order (0.002 deg: 3.5e-5 rad, squared half below 2^-30). */
#define CORNER_SMALL_DEG ((q32_t)8589935)

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
		/* Nothing to turn: the line in this call, not in another pass
		 * of next_piece's loop (10 instructions on a line's first tick). */
		c->stage = 2;
		if (m->v > 0)
			goto line; /* arriving out of a corner, already aligned */
		q32_t a;
		if (ONLINE_JERK && m->face_ok && m->face_ref.x_mm == r->x_mm &&
		    m->face_ref.y_mm == r->y_mm && m->face_ref.th_deg == r->th_deg &&
		    m->face_to.x_mm == c->target.x_mm && m->face_to.y_mm == c->target.y_mm)
			a = m->face_a; /* worked out ahead, from here */
		else
			a = motion_cruise_face(c, r);
		m->face_ok = false;
		if (fx_abs64(a) < 1)
			goto line;
		c->stage = 1;
		motion_seg_turn(m, a);
		return STAGE_PIECE;
	}
	case 1:
	line:
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
	if (c->kind == MCMD_CRUISE)
		return cruise_stage(m, c);
	return motion_stage(m, c);
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

/* The corner of cruise command c, from the reference: the piece still holds
 * c's line (cruise_line), so only the corner's own fields are set. */
static void corner_piece(motion_t *m, const motion_cmd_t *c)
{
	seg_t *g = &m->seg;
	g->kind = SEG_CORNER;
	g->s = 0;
	g->p0 = m->ref;
	g->h = 0;
	g->corner = &c->corner;
	g->len = 2 * c->corner.lh_mm;
	g->p_end.x_mm = c->exit_x_mm;
	g->p_end.y_mm = c->exit_y_mm;
	g->p_end.th_deg = fx_wrap_deg(m->ref.th_deg + c->corner.phi_deg);
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
		fx_rot_q30(rx, ry, co, si, &rx, &ry);
		out->x_mm = g->cx + rx;
		out->y_mm = g->cy + ry;
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
		q32_t lh = g->corner->lh_mm;
		q32_t h1 = traj_corner_heading(g->corner, s);
		q32_t hm;
		if (s_old == 0 && s <= lh) {
			/* The step in from the line: h(s / 2) = h1 / 4 exactly. */
			hm = h1 / 4;
		} else if (s <= lh || s_old >= lh) {
			int64_t du = traj_corner_u(g->corner, ds); /* ds / Lh, Q30 */
			int32_t du2 = (int32_t)((du * du) >> 30);
			q32_t corr = fx_mul_q30(g->corner->phi_deg, du2) / 8;
			hm = (g->h + h1) / 2 + (s <= lh ? -corr : corr);
		} else {
			hm = traj_corner_heading(g->corner, s_old + ds / 2);
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
	/* (dx, dy) turned back by the heading: the swapped pair turned forward. */
	fx_rot_q30(dy, dx, c, s, &t->vy_pt, &t->vx_pt);
	if (!KIN_OMNI(m->p.kin))
		t->vy_pt = 0;
	t->w_pt = dth;
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
				 * up to 2a (fuzz_ops's corpus, regress-opposite-
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
		/* The servo off (measured given): nothing is driven, the
		 * joystick waits at rest, and the reference follows the
		 * wheels as when idle (else servo on would start from where
		 * the unit was before a push: fault 204, found by fuzz_model). */
		if (measured)
			m->ref = *measured;
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
