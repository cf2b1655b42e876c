/* Motion engine: planning ahead under jerk limits. The next cruise line's
 * profile is planned between two ticks (motion_plan_idle), so that the tick
 * that begins the line only takes it (motion_tick.c, plan_line); and the
 * decisions a new waypoint or a lowered corner speed forces on the line
 * running (glide, or brake in its last ramp). Nothing here calls the tick. */
#include "motion_priv.h"

#include <stdint.h>

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
			m->face_a = motion_cruise_face(c0, &m->ref);
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
