/* Motion engine internals shared by its files; motion.h is the interface,
 * and motion_t (motion.h) the one home of the engine's state.
 *
 * The files in layers, each calling only those below it (`make lint`
 * fails on any cycle between the objects, tools/lint/objdeps.sh):
 *
 *   commands   motion.c        init, settings, setPosition, the velocity
 *                              modes' commands, pause/stop/halt, queries
 *              motion_queue.c  the commands that queue a move
 *   executor   motion_tick.c   motion_tick (the mode dispatch), the path
 *                              mode's tick: the active piece's profile,
 *                              crossing from piece to piece, a cruise
 *                              waypoint's pieces
 *              motion_piece.c  the other commands' pieces
 *              motion_vel.c    the velocity modes' ticks
 *              motion_seek.c   the continuous goal under jerk limits
 *   planner    motion_plan.c   cruise lines, corner planning, the backward
 *                              pass over the corner speeds
 *              motion_ahead.c  line profiles planned ahead, the glide
 *                              decisions a new waypoint forces
 *   geometry   motion_geom.c   what the commands, pieces and plans share
 * and below them all traj*.c (the profiles' maths) and the helpers here,
 * inline wherever they are used. The planner never calls the executor; the
 * executor takes what the planner made (a plan made ahead, the corner
 * speeds).
 *
 * The path tick keeps what a cruise crosses every few ticks in its own
 * file (the jerk-limited speed, a cruise waypoint's line and corner): a
 * call between files costs the blended cruise's dearest tick (a corner's
 * last, which sets up the next line) 14 to 44 instructions and its mean 17
 * under jerk limits (host, tools/bench/tickcost.sh, measured), which its
 * budget of 1,000 does not have. The other commands' pieces are set up
 * from rest, once a piece. The Cortex-M images link with -flto.
 */
#ifndef MOTION_PRIV_H
#define MOTION_PRIV_H

#include "motion.h"

/* The jerk-limited profiles that start or end at speed (cruise lines
 * between their corner speeds, the glide to a new speed limit, planning
 * ahead, the continuous goal's law in motion_seek.c): a build may leave them
 * out (-DMOTION_NO_ONLINE_JERK, the Cortex-M images for now: docs/jerk.md);
 * it then runs cruise lines on the acceleration-limited profile, brakes to
 * rest for a lower limit and runs the continuous goal's
 * acceleration-limited law. */
#ifdef MOTION_NO_ONLINE_JERK
#define ONLINE_JERK 0
#else
#define ONLINE_JERK 1
#endif

#define TINY_MM	 ((q32_t)4295) /* 1e-6 mm: below this a line has no length */
#define TINY_DEG ((q32_t)4295) /* 1e-6 deg */

FX_HELPER motion_cmd_t *q_at(motion_t *m, uint8_t i)
{
	return &m->q[(uint8_t)(m->q_head + i) % MOTION_QUEUE_LEN];
}

/* The active piece's limits and stopping-distance term are cached: every
 * change to the settings or the queue drops them, and the next tick
 * recomputes them once. */
static inline void limits_changed(motion_t *m)
{
	m->lim_ok = false;
}

/* Effective translation speed limit (set value, caution cap). */
static inline q32_t vt_eff(const motion_t *m)
{
	q32_t v = m->v_t_pt;
	if (m->cap_t_pt > 0 && m->cap_t_pt < v)
		v = m->cap_t_pt;
	return v;
}

/* Inline: out of line, the blended cruise's dearest tick cost 12 more
 * instructions (tools/bench/tickcost.sh, measured). */
static inline __attribute__((always_inline)) void pop(motion_t *m)
{
	if (m->q_count == 0)
		return;
	m->q_head = (uint8_t)((m->q_head + 1) % MOTION_QUEUE_LEN);
	m->q_count--;
	if (m->stop_drop)
		m->stop_drop--;
	if (m->pass_todo)
		m->pass_todo--;
	limits_changed(m);
}

/* x / sqrt(2) rounded down, for x >= 0 of any size (split in two so that
 * no product passes 2^62): a mecanum base's translation axes each get this
 * share of the limits under a jerk limit, so that the vector never exceeds
 * them. 2^30 / sqrt(2) rounded down is 759250124. */
FX_HELPER q32_t motion_share(q32_t x)
{
	const int64_t k = 759250124, lo = x & ((1 << 30) - 1);
	return (x >> 30) * k + ((lo * k) >> 30);
}

/* Toward a continuous goal on a differential base at bearing error *e:
 * forward or backing, whichever faces it (a goal that falls behind is
 * reached by backing along the line, not by circling it; the 20 degree
 * band about the side keeps the choice from chattering); *e becomes the
 * error of the direction chosen. True when the direction changed. */
static inline bool motion_goal_facing(motion_t *m, q32_t *e)
{
	bool rev = m->goal_reverse;
	q32_t ae = fx_abs64(*e);
	if (!rev && ae > fx_from_int(100))
		m->goal_reverse = true;
	else if (rev && ae < fx_from_int(80))
		m->goal_reverse = false;
	if (m->goal_reverse)
		*e = fx_wrap_deg(*e + fx_from_int(180));
	return rev != m->goal_reverse;
}

/* The jerk-limited line running, and the one planned ahead (motion.h):
 * taking the plan made ahead swaps them, with no copy in the tick. */
static inline traj_ln_t *ln_run(motion_t *m)
{
	return &m->lnb[m->ln_i];
}

static inline traj_ln_t *ln_ahead(motion_t *m)
{
	return &m->lnb[m->ln_i ^ 1];
}

static inline bool twist_zero(const fx_twist_t *t)
{
	return t->vx_pt == 0 && t->vy_pt == 0 && t->w_pt == 0;
}

/* pi / 180 in Q32. */
#define DEG_TO_RAD_Q32 ((q32_t)74961321)

/* The continuous goal honours the jerk settings (motion_seek.c). */
static inline bool seek_jerk(const motion_t *m)
{
	return (m->j_t_pt3 | m->j_r_pt3) != 0;
}

/* True when the piece just finished flows into the next without stopping. */
static inline bool blends_onward(motion_t *m, uint8_t finished_kind)
{
	if (m->q_count == 0)
		return false;
	motion_cmd_t *c = q_at(m, 0);
	if (c->kind != MCMD_CRUISE || !c->has_corner)
		return false;
	return finished_kind == SEG_LINE || finished_kind == SEG_CORNER;
}

/* The profile that runs is dropped (braking, a new plan). */
static inline void plan_drop(motion_t *m)
{
	m->sc_on = m->ln_on = m->glide = m->hold_on = false;
}

/* The speed the active piece ends at under jerk limits: a cruise line's
 * corner speed (within the line's own cap, as traj_ln_plan takes it), or
 * rest. */
static inline q32_t piece_cout(motion_t *m)
{
	if (m->seg.kind != SEG_LINE || !blends_onward(m, SEG_LINE))
		return 0;
	return fx_min64(q_at(m, 0)->vend_pt, m->lim_vmax - 1);
}

/* Whether the running plan is in its last ramp (the S-curve's, or the
 * line's into its end speed), where its speed only falls. */
FX_HELPER bool last_ramp(const motion_t *m)
{
	const traj_ln_t *ln = &m->lnb[m->ln_i];
	return m->sc_on ? m->sc.k >= m->sc.nv : ln->k > ln->l1 + ln->hold;
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
		return fx_min64(t, fx_mul(r, g->corner->k_mm_deg) / 2);
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
FX_HELPER q32_t piece_jerk(const seg_t *g, q32_t t, q32_t r)
{
	if (t == 0 && r == 0)
		return 0;
	q32_t j = piece_limit(g, t ? t : JERK_NONE, r ? r : JERK_NONE);
	return j >= JERK_REAL ? 0 : j;
}

/* motion_piece.c: the next stage of a queued command other than a cruise
 * waypoint (what it did), and the turn piece of angle from the reference
 * (the cruise waypoint's turn to face its line too). */
typedef enum { STAGE_DONE, STAGE_PIECE, STAGE_SKIP } stage_t;
stage_t motion_stage(motion_t *m, motion_cmd_t *c);
void motion_seg_turn(motion_t *m, q32_t angle);

/* motion_vel.c: the ticks of the velocity modes. */
void motion_velocity_tick(motion_t *m, fx_twist_t *out); /* jog, joystick */
void motion_continuous_tick(motion_t *m, fx_twist_t *out);

/* motion_seek.c: the continuous goal's tick under jerk limits, and its
 * retarget (a new goal). */
void motion_seek_tick(motion_t *m, fx_twist_t *out);
void motion_seek_retarget(motion_t *m);

/* motion_plan.c */
/* A cruise command's line geometry, once its start is known. */
void motion_cruise_set_start(motion_cmd_t *c, q32_t sx, q32_t sy);
/* Plan the corner at queued cruise command i (blending into i + 1); true
 * when one was planned (and the corner speeds with it). */
bool motion_plan_corner(motion_t *m, uint8_t i);
/* The corner speeds, for commands from index lo up with new geometry (0:
 * the limits changed, all of them). */
void motion_backward_pass_from(motion_t *m, uint8_t lo);
void motion_backward_pass(motion_t *m);

/* motion_ahead.c: whether the line running to rest on its jerk-limited
 * plan can still glide into a corner queued now (not in its last ramp),
 * and the glide's start. */
bool motion_line_may_blend(const motion_t *m);
void motion_line_glide(motion_t *m);
/* After the backward pass: a jerk-limited line running into its corner
 * whose speed the pass lowered plans again. */
void motion_line_cout_check(motion_t *m);
/* The next cruise line's jerk-limited profile, planned ahead (true when it
 * planned). */
bool motion_plan_next_line(motion_t *m);

/* motion_geom.c */
/* Rotate a body-frame vector into the world frame at heading th. */
void motion_body_to_world(q32_t th, q32_t bx, q32_t by, q32_t *wx, q32_t *wy);
/* The pose rel (in the body frame of from) in the world frame. */
fx_pose_t motion_rel_to_abs(const fx_pose_t *from, const fx_pose_t *rel);
/* Length of (dx, dy) and its unit direction in Q30 (0, 0 for no length). */
q32_t motion_unit_dir(q32_t dx, q32_t dy, int32_t *ux, int32_t *uy);
/* The turn that faces cruise command c's waypoint from pose r (0: none, or
 * no distance to it). */
q32_t motion_cruise_face(const motion_cmd_t *c, const fx_pose_t *r);

#endif
