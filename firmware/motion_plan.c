/* Motion engine: cruise lines, corner planning and the backward pass over
 * the queued corner speeds (the maths in traj.c; traj.h derives it). */
#include "motion_priv.h"

/* A corner's speed cap from its rotation rate and rotational acceleration
 * (the translation limit, which caution can change, applies on top). */
static q32_t corner_vrot(const motion_t *m, const motion_cmd_t *c)
{
	q32_t vr = fx_mul(m->v_r_pt, c->corner.k_mm_deg);
	/* The step into the corner may carry one tick of the line's
	 * acceleration above the speed planned: the margin is that, or 1 %
	 * (fx_udiv64_small: vr / 100 without a library call), never more than
	 * half (a corner too tight for it is not fitted, motion_plan_corner). */
	q32_t pc = vr >= 0 ? (q32_t)fx_udiv64_small((uint64_t)vr, 100) : vr / 100;
	vr -= fx_min64(fx_max64(pc, m->a_t_pt2), vr / 2);
	return fx_min64(vr, c->corner.vacc_pt);
}

/* The square root and divisions are paid when the command is queued, not
 * in the tick that blends into it. */
FX_OUTLINE void motion_cruise_set_start(motion_cmd_t *c, q32_t sx, q32_t sy)
{
	c->sx_mm = sx;
	c->sy_mm = sy;
	c->start_known = true;
	c->len_mm = motion_unit_dir(c->target.x_mm - sx, c->target.y_mm - sy, &c->ux, &c->uy);
}

/* Length of cruise command i's straight part: from the previous corner's
 * exit (or its start) to its own corner's entry (or its waypoint). */
static q32_t cruise_line_len(motion_t *m, uint8_t i)
{
	motion_cmd_t *c = q_at(m, i);
	q32_t l = c->len_mm;
	if (i > 0) {
		motion_cmd_t *p = q_at(m, (uint8_t)(i - 1));
		if (p->kind == MCMD_CRUISE && p->has_corner)
			l -= p->corner.t_mm;
	}
	if (c->has_corner)
		l -= c->corner.t_mm;
	return l > 0 ? l : 0;
}

/* The backward pass from command i down, given what command i + 1 left:
 * its corner speed and braking distance, and whether its speed stayed. Only
 * commands from index lo up have new geometry (a corner planned at lo
 * changes the lines of lo and lo + 1); below them a command's results
 * depend on the next one's line and corner speed alone, so the walk stops
 * at the first command whose successor kept both: queueing a waypoint costs
 * the corners its speed reaches, not the whole queue.
 *
 * With a budget (motion_set_plan_budget), at most that many commands below
 * the new geometry are walked; the rest stay pending (pass_todo: the queue's
 * first pass_todo commands) and motion_plan_idle goes on with them. Until
 * then the head keeps the plan it had, as if the request had come later:
 * the running piece never sees half a pass. */
static void pass_walk(motion_t *m, int i, uint8_t lo, q32_t next_v, q32_t next_extra,
		      bool next_same)
{
	traj_rate_t at;
	traj_rate_init(&at, m->a_t_pt2);
	uint32_t left = m->plan_budget ? m->plan_budget : UINT32_MAX;
	/* Under a jerk limit a line changes speed on traj_ln's ramps
	 * (traj.h, section 6): each takes at most A / J + 2 ticks more than
	 * braking at A, at no more than the line speed, and the line begins
	 * up to a step into it (the corner's last): the braking counts on that
	 * much less of each line. */
	q32_t slack = 0;
	if (ONLINE_JERK && m->j_t_pt3 > 0)
		slack = vt_eff(m) * (m->a_t_pt2 / m->j_t_pt3 + 4);
	for (; i >= 0; i--) {
		if (i + 1 < (int)lo && next_same)
			return; /* older pending work, if any, stays pending */
		if (!(lo > 0 && i + 1 >= (int)lo) && left-- == 0) {
			m->pass_todo = (uint8_t)(i + 1);
			return;
		}
		motion_cmd_t *c = q_at(m, (uint8_t)i);
		if (c->kind != MCMD_CRUISE || !c->has_corner) {
			next_same = !(c->kind == MCMD_CRUISE && c->vend_pt != 0);
			next_v = next_extra = 0;
			if (c->kind == MCMD_CRUISE)
				c->vend_pt = 0;
			continue;
		}
		c->corner_extra_mm = 0;
		q32_t v = fx_min64(vt_eff(m), c->corner_vrot_pt);
		if ((uint8_t)(i + 1) < m->q_count) {
			q32_t after = q_at(m, (uint8_t)(i + 1))->line_mm;
			/* traj_reach(after, next_v, a): the next corner's braking
			 * distance is its line_extra_mm, already formed */
			q32_t reach = traj_umax_r(fx_max64(after - slack, 0) + next_extra, &at);
			if (reach < v)
				v = reach;
			q32_t b = c->corner_a_pt2 == at.a
				      ? traj_brake_dist_r(next_v, &at)
				      : traj_brake_dist(next_v, c->corner_a_pt2);
			c->corner_extra_mm = after + b + next_v;
		}
		next_same = c->vend_pt == v;
		c->vend_pt = v;
		c->line_extra_mm = traj_brake_dist_r(v, &at) + v;
		next_v = v;
		next_extra = c->line_extra_mm;
	}
	m->pass_todo = 0;
	if (ONLINE_JERK)
		motion_line_cout_check(m);
}

/* Lower each corner's speed so the unit can brake to the next corner's speed
 * on the line between, and to a stop at the last waypoint; and keep, per
 * corner, what the tick needs when its line or the corner begins. Commands
 * from index lo up have new geometry (0: the limits changed, all of them). */
void motion_backward_pass_from(motion_t *m, uint8_t lo)
{
	limits_changed(m);
	if (vt_eff(m) != m->pass_vt)
		lo = 0; /* every corner speed follows a new line speed */
	m->pass_vt = vt_eff(m);
	for (uint8_t i = lo; i < m->q_count; i++) {
		motion_cmd_t *c = q_at(m, i);
		if (c->kind != MCMD_CRUISE)
			continue;
		if (c->start_known)
			c->line_mm = cruise_line_len(m, i);
		if (!c->has_corner)
			continue;
		/* A corner's own caps, here and never left pending: the running
		 * piece reads them (a lower rotation limit holds at once). Below
		 * lo they stand (same corner, same limits). */
		c->corner_vrot_pt = corner_vrot(m, c);
		/* A collinear pass (no corner piece) brakes at the line's rate. */
		c->corner_a_pt2 = fx_max64(
		    c->corner.lh_mm > 0 ? fx_min64(m->a_t_pt2, c->corner.acc_pt2) : m->a_t_pt2, 1);
	}
	pass_walk(m, (int)m->q_count - 1, lo, 0, 0, false);
}

bool motion_plan_idle(motion_t *m)
{
	if (m->pass_todo == 0)
		return motion_plan_next_line(m);
	limits_changed(m);
	uint8_t i = m->pass_todo;
	q32_t next_v = 0, next_extra = 0;
	if (i < m->q_count) {
		const motion_cmd_t *n = q_at(m, i);
		if (n->kind == MCMD_CRUISE && n->has_corner) {
			next_v = n->vend_pt;
			next_extra = n->line_extra_mm;
		}
	}
	pass_walk(m, i - 1, 0, next_v, next_extra, false);
	return true;
}

void motion_set_plan_budget(motion_t *m, uint8_t n)
{
	m->plan_budget = n;
}

void motion_backward_pass(motion_t *m)
{
	motion_backward_pass_from(m, 0);
}

/* Distance from the reference to the point where the active line ends, if
 * the head command is a cruise line being executed. The running piece may
 * belong to no queued command (a stop's braking, with new commands queued
 * behind it): only the head's own line (stage 2, next_piece) counts. */
static bool head_line_remaining(motion_t *m, q32_t *rem)
{
	if (m->mode != MODE_PATH || m->seg.kind != SEG_LINE || m->q_count == 0)
		return false;
	const motion_cmd_t *h = q_at(m, 0);
	if (h->kind != MCMD_CRUISE || h->stage != 2)
		return false;
	*rem = m->seg.len - m->seg.s;
	return true;
}

/* Collinear: the waypoint is passed straight through at full speed. */
static bool pass_straight(motion_t *m, motion_cmd_t *c, uint8_t i)
{
	c->corner = (traj_corner_t){0};
	c->corner.k_mm_deg = INT64_MAX / 4;
	c->corner.vacc_pt = INT64_MAX / 4;
	c->has_corner = true;
	motion_backward_pass_from(m, i);
	return true;
}

/* Whether the line running can slow to speed c within d. Under a jerk
 * limit the glide and the ramps take up to 2 A / J + 6 ticks more, at up
 * to the speed the glide reaches; accelerating, the glide takes the
 * acceleration to zero at the jerk first, the speed rising by up to acc
 * (acc / J + 1) / 2 before the line can slow. */
static bool line_can_slow(const motion_t *m, q32_t d, q32_t c)
{
	q32_t top = m->v;
	if (ONLINE_JERK && m->lim_j > 0) {
		q32_t aj = m->a_t_pt2 / m->lim_j;
		d -= (m->v + m->a_t_pt2 * (aj + 1) / 2) * (2 * aj + 6);
		if (m->acc > 0)
			top += m->acc * (m->acc / m->lim_j + 1) / 2;
	}
	return traj_reach(d, c, m->a_t_pt2) >= top;
}

/* Plan the corner at queued cruise command i (blending into i + 1); true
 * when one was planned (and the corner speeds with it). */
bool motion_plan_corner(motion_t *m, uint8_t i)
{
	motion_cmd_t *c = q_at(m, i), *n = q_at(m, (uint8_t)(i + 1));
	if (i < m->stop_drop)
		return false; /* discarded by a stop: no corner into what follows */
	if (c->kind != MCMD_CRUISE || n->kind != MCMD_CRUISE || !c->start_known || c->has_corner)
		return false;
	/* The head command's stage 2 is its line running (next_piece), then
	 * its corner: a corner can still be fitted in what is left of the line. */
	if (i == 0 && (c->stage > 2 || (c->stage == 2 && m->seg.kind != SEG_LINE)))
		return false; /* already past its line */
	q32_t lin = c->len_mm, lout = n->len_mm;
	if (lin < TINY_MM || lout < TINY_MM)
		return false;
	/* The deflection from the two lines' unit vectors (the next line
	 * starts on this waypoint): one arctangent, not two headings. */
	int64_t cross = (int64_t)c->ux * n->uy - (int64_t)c->uy * n->ux;
	int64_t dot = (int64_t)c->ux * n->ux + (int64_t)c->uy * n->uy;
	q32_t phi = fx_atan2_deg(cross, dot);
	if (fx_abs64(phi) < TINY_DEG)
		return pass_straight(m, c, i);
	q32_t t = m->p.cruise_blend_mm;
	q32_t avail_in = lin;
	if (i > 0) {
		motion_cmd_t *p = q_at(m, (uint8_t)(i - 1));
		if (p->kind == MCMD_CRUISE && p->has_corner)
			avail_in -= p->corner.t_mm;
	}
	t = fx_min64(t, avail_in);
	t = fx_min64(t, lout / 2);
	q32_t rem = 0;
	bool executing = (i == 0) && head_line_remaining(m, &rem);
	/* A line running to rest under a jerk limit glides into the corner
	 * (motion_ahead.c, motion_line_glide) unless it is in its last ramp,
	 * which stops on the waypoint. */
	if (executing && m->lim_j > 0 && (!ONLINE_JERK || !motion_line_may_blend(m)))
		return false;
	if (executing)
		t = fx_min64(t, rem - m->v - m->v_t_pt);
	traj_corner_t corner;
	if (t <= TINY_MM || !traj_corner_plan(&corner, phi, t, m->a_r_pt2))
		return false;
	/* Too tight to enter at speed: its rotation's speed cap within two
	 * ticks of the line's braking (the step in may carry one). The unit
	 * stops on the waypoint and turns there. */
	if (fx_mul(m->v_r_pt, corner.k_mm_deg) <= 2 * m->a_t_pt2)
		return false;
	c->corner = corner;
	c->has_corner = true;
	/* Exit: the integration arrives there within nanometres (clothoid
	 * heading exact, midpoint steps); the piece ends on it, so the next
	 * line is the one planned. */
	c->exit_x_mm = c->target.x_mm + fx_mul_q30(corner.t_mm, n->ux);
	c->exit_y_mm = c->target.y_mm + fx_mul_q30(corner.t_mm, n->uy);
	motion_backward_pass_from(m, i);
	if (executing) {
		/* Can the unit still slow to the corner speed before it begins? */
		if (!line_can_slow(m, rem - corner.t_mm, c->vend_pt)) {
			c->has_corner = false;
			motion_backward_pass_from(m, i);
			return true;
		}
		/* The line now ends at the corner entry; under a jerk limit it
		 * glides into it from the next tick. */
		if (ONLINE_JERK && m->lim_j > 0)
			motion_line_glide(m);
		m->seg.len -= corner.t_mm;
		m->seg.p_end.x_mm = c->target.x_mm - fx_mul_q30(corner.t_mm, c->ux);
		m->seg.p_end.y_mm = c->target.y_mm - fx_mul_q30(corner.t_mm, c->uy);
	}
	return true;
}
