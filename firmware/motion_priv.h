/* Motion engine internals shared by its files; motion.h is the interface.
 *
 * The files, callers above callees; nothing calls back up:
 *   motion.c        init, settings, setPosition, pause/stop/halt, queries
 *   motion_queue.c  the commands that queue a move
 *   motion_path.c   motion_tick (the mode dispatch), the path mode's tick
 *                   and its pieces
 *   motion_vel.c    jog, joystick and continuous modes: commands and ticks
 *   motion_seek.c   the continuous goal under jerk limits
 *   motion_plan.c   cruise lines, corner planning and the backward pass
 *   motion_geom.c   geometry the commands and the pieces share
 * and below them all the helpers here, inline wherever they are used.
 *
 * motion_tick shares a file with the path tick and its pieces: a call
 * between files costs the blended cruise's dearest tick 9 to 17
 * instructions (host, tools/bench/tickcost.sh, measured), which its budget
 * of 1,000 does not have. The velocity modes' ticks are such calls: 18 to
 * 23 instructions a jog or retarget tick, far inside their budgets. The
 * Cortex-M images link with -flto.
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

/* motion_path.c: whether the line running to rest on its jerk-limited
 * plan can still glide into a corner queued now (not in its last ramp),
 * and the glide's start. */
bool motion_line_may_blend(const motion_t *m);
void motion_line_glide(motion_t *m);
/* After the backward pass: a jerk-limited line running into its corner
 * whose speed the pass lowered plans again. */
void motion_line_cout_check(motion_t *m);

/* motion_seek.c: the continuous goal's tick under jerk limits, and its
 * retarget (a new goal). */
void motion_seek_tick(motion_t *m, fx_twist_t *out);
void motion_seek_retarget(motion_t *m);

/* motion_geom.c */
/* Rotate a body-frame vector into the world frame at heading th. */
void motion_body_to_world(q32_t th, q32_t bx, q32_t by, q32_t *wx, q32_t *wy);
/* The pose rel (in the body frame of from) in the world frame. */
fx_pose_t motion_rel_to_abs(const fx_pose_t *from, const fx_pose_t *rel);
/* Length of (dx, dy) and its unit direction in Q30 (0, 0 for no length). */
q32_t motion_unit_dir(q32_t dx, q32_t dy, int32_t *ux, int32_t *uy);

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

/* motion_path.c: the next cruise line's jerk-limited profile, planned
 * ahead (true when it planned). */
bool motion_plan_next_line(motion_t *m);

/* motion_vel.c: the ticks of the velocity modes. */
void motion_velocity_tick(motion_t *m, fx_twist_t *out); /* jog, joystick */
void motion_continuous_tick(motion_t *m, fx_twist_t *out);

#endif
