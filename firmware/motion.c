/* Motion engine: command queue, path execution and velocity modes.
 * Profile and corner maths are in traj.c; see traj.h for the derivation. */
#include "motion.h"

#include <stddef.h>

#include "kin.h"

#define TINY_MM	       ((q32_t)4295)	 /* 1e-6 mm: below this a line has no length */
#define TINY_DEG       ((q32_t)4295)	 /* 1e-6 deg */
#define DEG_TO_RAD_Q32 ((q32_t)74961321) /* pi / 180 */
/* Heading change below which a corner step turns its entry direction to
 * first order (0.002 deg: 3.5e-5 rad, squared half below 2^-30). */
#define CORNER_SMALL_DEG ((q32_t)8589935)

static motion_cmd_t *q_at(motion_t *m, uint8_t i)
{
	return &m->q[(uint8_t)(m->q_head + i) % MOTION_QUEUE_LEN];
}

/* The active piece's limits and stopping-distance term are cached: every
 * change to the settings or the queue drops them, and the next tick
 * recomputes them once. */
static void limits_changed(motion_t *m)
{
	m->lim_ok = false;
}

static void per_tick(motion_t *m)
{
	int64_t hz = m->p.tick_hz;
	/* Per-tick values round down so a set limit is never exceeded. */
	m->vmax_t_pt = m->p.vel_limit_t / hz;
	m->vmax_r_pt = m->p.vel_limit_r / hz;
	m->amax_t_pt2 = m->p.acc_limit_t / hz / hz;
	m->amax_r_pt2 = m->p.acc_limit_r / hz / hz;
}

void motion_init(motion_t *m, const motion_params_t *p)
{
	*m = (motion_t){0};
	m->p = *p;
	per_tick(m);
	m->v_t_pt = m->vmax_t_pt;
	m->v_r_pt = m->vmax_r_pt;
	m->a_t_pt2 = fx_max64(m->amax_t_pt2, 1);
	m->a_r_pt2 = fx_max64(m->amax_r_pt2, 1);
	m->jog_timeout_ticks = p->tick_hz / 2;
}

static void backward_pass(motion_t *m);

void motion_set_velocity(motion_t *m, q32_t vt, q32_t vr)
{
	m->v_t_pt = vt / m->p.tick_hz;
	m->v_r_pt = vr / m->p.tick_hz;
	backward_pass(m);
}

void motion_set_accel(motion_t *m, q32_t at, q32_t ar)
{
	int64_t hz = m->p.tick_hz;
	m->a_t_pt2 = at / hz / hz;
	m->a_r_pt2 = ar / hz / hz;
	if (m->a_t_pt2 < 1)
		m->a_t_pt2 = 1;
	if (m->a_r_pt2 < 1)
		m->a_r_pt2 = 1;
	/* Queued corners keep their shapes; their caps follow the new
	 * rotational rate, and the corner speeds the new braking rate. */
	for (uint8_t i = 0; i < m->q_count; i++) {
		motion_cmd_t *c = q_at(m, i);
		if (c->kind == MCMD_CRUISE && c->has_corner && c->corner.lh_mm != 0)
			traj_corner_rates(&c->corner, m->a_r_pt2);
	}
	backward_pass(m);
}

void motion_set_jog_timeout_ms(motion_t *m, uint32_t ms)
{
	m->jog_timeout_ticks = (uint32_t)(((uint64_t)ms * m->p.tick_hz + 999) / 1000);
}

void motion_set_caution(motion_t *m, q32_t vt_cap)
{
	m->cap_t_pt = vt_cap / m->p.tick_hz;
	limits_changed(m);
}

/* Rigid transform taking the reference pose onto a redefined pose: every
 * point the engine holds is mapped through it, so the active piece and the
 * queued targets keep their physical places and no velocity step appears. */
typedef struct {
	q32_t ox, oy, nx, ny, dth;
	int32_t c, s;
} frame_map_t;

static void map_point(const frame_map_t *f, q32_t *x, q32_t *y)
{
	q32_t rx = *x - f->ox, ry = *y - f->oy;
	*x = f->nx + fx_mul_q30(rx, f->c) - fx_mul_q30(ry, f->s);
	*y = f->ny + fx_mul_q30(rx, f->s) + fx_mul_q30(ry, f->c);
}

static void map_pose(const frame_map_t *f, fx_pose_t *p)
{
	map_point(f, &p->x_mm, &p->y_mm);
	p->th_deg = fx_wrap_deg(p->th_deg + f->dth);
}

static void map_dir(const frame_map_t *f, int32_t *ux, int32_t *uy)
{
	int64_t x = *ux, y = *uy;
	*ux = (int32_t)(fx_mul_q30(x, f->c) - fx_mul_q30(y, f->s));
	*uy = (int32_t)(fx_mul_q30(x, f->s) + fx_mul_q30(y, f->c));
}

void motion_set_pose(motion_t *m, const fx_pose_t *p)
{
	frame_map_t f = {.ox = m->ref.x_mm, .oy = m->ref.y_mm, .nx = p->x_mm, .ny = p->y_mm};
	f.dth = fx_wrap_deg(p->th_deg - m->ref.th_deg);
	uint32_t b = fx_deg_to_bam(f.dth);
	f.c = fx_cos_bam(b);
	f.s = fx_sin_bam(b);
	for (uint8_t i = 0; i < m->q_count; i++) {
		motion_cmd_t *c = q_at(m, i);
		map_pose(&f, &c->target);
		map_point(&f, &c->cx_mm, &c->cy_mm);
		if (c->kind == MCMD_CRUISE) {
			map_point(&f, &c->sx_mm, &c->sy_mm);
			map_point(&f, &c->exit_x_mm, &c->exit_y_mm);
			map_dir(&f, &c->ux, &c->uy);
		}
	}
	if (m->seg.kind != SEG_NONE) {
		map_pose(&f, &m->seg.p0);
		map_pose(&f, &m->seg.p_end);
		map_point(&f, &m->seg.cx, &m->seg.cy);
		map_dir(&f, &m->seg.ux, &m->seg.uy);
	}
	map_pose(&f, &m->goal);
	if (m->mode == MODE_IDLE) {
		m->ref = *p;
		m->ref.th_deg = fx_wrap_deg(p->th_deg);
	} else {
		/* Moving: the reference goes through the same rounding as the
		 * piece it is on, so the next step has no nanometre jump. */
		map_pose(&f, &m->ref);
	}
}

/* Effective translation speed limit (set value, caution cap). */
static q32_t vt_eff(const motion_t *m)
{
	q32_t v = m->v_t_pt;
	if (m->cap_t_pt > 0 && m->cap_t_pt < v)
		v = m->cap_t_pt;
	return v;
}

/* ---- queue ---------------------------------------------------------- */

static bool queue_full(const motion_t *m)
{
	return m->q_count >= MOTION_QUEUE_LEN;
}

/* Position where the last queued command ends, if known. */
static bool tail_end(motion_t *m, q32_t *x, q32_t *y)
{
	if (m->q_count > m->stop_drop) {
		motion_cmd_t *c = q_at(m, (uint8_t)(m->q_count - 1));
		*x = c->target.x_mm;
		*y = c->target.y_mm;
		return true;
	}
	if (m->stop_drop)
		return false; /* where the stop ends: known when it runs */
	if (m->mode == MODE_IDLE || m->mode == MODE_PATH) {
		*x = m->ref.x_mm;
		*y = m->ref.y_mm;
		return true;
	}
	return false;
}

static bool push(motion_t *m, const motion_cmd_t *c)
{
	if (queue_full(m))
		return false;
	*q_at(m, m->q_count) = *c;
	m->q_count++;
	limits_changed(m);
	if (m->mode == MODE_IDLE)
		m->mode = MODE_PATH;
	return true;
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

/* Rotate a body-frame vector into the world frame at heading th. */
static void body_to_world(q32_t th, q32_t bx, q32_t by, q32_t *wx, q32_t *wy)
{
	uint32_t b = fx_deg_to_bam(th);
	int32_t c, s;
	fx_sincos_bam(b, &s, &c);
	*wx = fx_mul_q30(bx, c) - fx_mul_q30(by, s);
	*wy = fx_mul_q30(bx, s) + fx_mul_q30(by, c);
}

bool motion_forward(motion_t *m, q32_t dist_mm)
{
	motion_cmd_t c = {0};
	c.kind = MCMD_FORWARD;
	q32_t dx, dy;
	body_to_world(m->ref.th_deg, dist_mm, 0, &dx, &dy);
	c.target = m->ref;
	c.target.x_mm += dx;
	c.target.y_mm += dy;
	c.angle_deg = dist_mm; /* signed distance */
	return push(m, &c);
}

bool motion_turn(motion_t *m, q32_t angle_deg)
{
	motion_cmd_t c = {0};
	c.kind = MCMD_TURN;
	c.target = m->ref;
	c.target.th_deg = fx_wrap_deg(m->ref.th_deg + angle_deg);
	c.angle_deg = angle_deg;
	return push(m, &c);
}

bool motion_linear_abs(motion_t *m, const fx_pose_t *abs_pose)
{
	motion_cmd_t c = {0};
	c.kind = MCMD_LINE;
	c.has_heading = true;
	c.target = *abs_pose;
	c.target.th_deg = fx_wrap_deg(abs_pose->th_deg);
	return push(m, &c);
}

bool motion_linear_rel(motion_t *m, const fx_pose_t *rel)
{
	fx_pose_t t = m->ref;
	q32_t dx, dy;
	body_to_world(m->ref.th_deg, rel->x_mm, rel->y_mm, &dx, &dy);
	t.x_mm += dx;
	t.y_mm += dy;
	t.th_deg = fx_wrap_deg(m->ref.th_deg + rel->th_deg);
	return motion_linear_abs(m, &t);
}

bool motion_circular_rel(motion_t *m, q32_t cx_mm, q32_t cy_mm, q32_t angle_deg)
{
	motion_cmd_t c = {0};
	q32_t dx, dy;
	if (m->p.kin == MOTION_KIN_DIFF && cx_mm != 0)
		return false;
	body_to_world(m->ref.th_deg, cx_mm, cy_mm, &dx, &dy);
	c.kind = MCMD_ARC;
	c.cx_mm = m->ref.x_mm + dx;
	c.cy_mm = m->ref.y_mm + dy;
	c.sx_mm = cx_mm;
	c.sy_mm = cy_mm;
	c.angle_deg = angle_deg;
	/* End pose: the start rotated about the centre. */
	uint32_t b = fx_deg_to_bam(angle_deg);
	int32_t co, si;
	fx_sincos_bam(b, &si, &co);
	q32_t rx = -dx, ry = -dy;
	c.target.x_mm = c.cx_mm + fx_mul_q30(rx, co) - fx_mul_q30(ry, si);
	c.target.y_mm = c.cy_mm + fx_mul_q30(rx, si) + fx_mul_q30(ry, co);
	c.target.th_deg = fx_wrap_deg(m->ref.th_deg + angle_deg);
	return push(m, &c);
}

/* ---- cruise planning ------------------------------------------------- */

/* A corner's speed cap from its rotation rate and rotational acceleration
 * (the translation limit, which caution can change, applies on top). */
static q32_t corner_vrot(const motion_t *m, const motion_cmd_t *c)
{
	q32_t vr = fx_mul(m->v_r_pt, c->corner.k_mm_deg);
	/* 1 % margin: the step into the corner may carry one tick of a
	 * (fx_udiv64_small: vr / 100 without a library call) */
	vr -= vr >= 0 ? (q32_t)fx_udiv64_small((uint64_t)vr, 100) : vr / 100;
	return fx_min64(vr, c->corner.vacc_pt);
}

/* Length of (dx, dy) and its unit direction in Q30 (0, 0 for no length).
 * Out of line: it runs when a command is queued or a piece starts, and
 * inlined it cost the steady cruise tick 5 instructions (measured). */
static __attribute__((noinline)) q32_t unit_dir(q32_t dx, q32_t dy, int32_t *ux, int32_t *uy)
{
	q32_t len = fx_hypot(dx, dy);
	*ux = *uy = 0;
	if (len > 0) {
		*ux = (int32_t)(fx_div(dx, len) >> 2);
		*uy = (int32_t)(fx_div(dy, len) >> 2);
	}
	return len;
}

/* A cruise command's line geometry, once its start is known: the square
 * root and divisions are paid when it is queued, not in the tick that
 * blends into it. */
static void cruise_set_start(motion_cmd_t *c, q32_t sx, q32_t sy)
{
	c->sx_mm = sx;
	c->sy_mm = sy;
	c->start_known = true;
	c->len_mm = unit_dir(c->target.x_mm - sx, c->target.y_mm - sy, &c->ux, &c->uy);
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
			q32_t reach = traj_umax_r(after + next_extra, &at);
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
}

/* Lower each corner's speed so the unit can brake to the next corner's speed
 * on the line between, and to a stop at the last waypoint; and keep, per
 * corner, what the tick needs when its line or the corner begins. Commands
 * from index lo up have new geometry (0: the limits changed, all of them). */
static void backward_pass_from(motion_t *m, uint8_t lo)
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
		return false;
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

static void backward_pass(motion_t *m)
{
	backward_pass_from(m, 0);
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

/* Plan the corner at queued cruise command i (blending into i + 1); true
 * when one was planned (and the corner speeds with it). */
static bool plan_corner(motion_t *m, uint8_t i)
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
	if (fx_abs64(phi) < TINY_DEG) {
		/* Collinear: pass straight through at full speed. */
		c->corner = (traj_corner_t){0};
		c->corner.k_mm_deg = INT64_MAX / 4;
		c->corner.vacc_pt = INT64_MAX / 4;
		c->has_corner = true;
		backward_pass_from(m, i);
		return true;
	}
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
	if (executing)
		t = fx_min64(t, rem - m->v - m->v_t_pt);
	traj_corner_t corner;
	if (t <= TINY_MM || !traj_corner_plan(&corner, phi, t, m->a_r_pt2))
		return false;
	c->corner = corner;
	c->has_corner = true;
	/* Exit: the integration arrives there within nanometres (clothoid
	 * heading exact, midpoint steps); the piece ends on it, so the next
	 * line is the one planned. */
	c->exit_x_mm = c->target.x_mm + fx_mul_q30(corner.t_mm, n->ux);
	c->exit_y_mm = c->target.y_mm + fx_mul_q30(corner.t_mm, n->uy);
	backward_pass_from(m, i);
	if (executing) {
		/* Can the unit still slow to the corner speed before it begins? */
		q32_t d = rem - corner.t_mm;
		if (traj_reach(d, c->vend_pt, m->a_t_pt2) < m->v) {
			c->has_corner = false;
			backward_pass_from(m, i);
			return true;
		}
		/* The line now ends at the corner entry. */
		m->seg.len -= corner.t_mm;
		m->seg.p_end.x_mm = c->target.x_mm - fx_mul_q30(corner.t_mm, c->ux);
		m->seg.p_end.y_mm = c->target.y_mm - fx_mul_q30(corner.t_mm, c->uy);
	}
	return true;
}

bool motion_cruise_abs(motion_t *m, q32_t x_mm, q32_t y_mm)
{
	motion_cmd_t c = {0};
	c.kind = MCMD_CRUISE;
	c.target.x_mm = x_mm;
	c.target.y_mm = y_mm;
	q32_t sx, sy;
	if (tail_end(m, &sx, &sy))
		cruise_set_start(&c, sx, sy);
	if (!push(m, &c))
		return false;
	uint8_t last = (uint8_t)(m->q_count - 1);
	if (last == 0 || !plan_corner(m, (uint8_t)(last - 1)))
		backward_pass_from(m, last);
	return true;
}

/* ---- velocity modes --------------------------------------------------- */

static bool velocity_mode_allowed(const motion_t *m)
{
	return m->mode == MODE_IDLE || m->mode == MODE_JOG || m->mode == MODE_CONTINUOUS;
}

bool motion_jog(motion_t *m, q32_t vx, q32_t vy, q32_t w)
{
	if (!velocity_mode_allowed(m) || m->q_count > 0 || m->stopping || m->paused)
		return false;
	int64_t hz = m->p.tick_hz;
	m->vtarget.vx_pt = vx / hz;
	m->vtarget.vy_pt = vy / hz;
	m->vtarget.w_pt = w / hz;
	m->jog_age_ticks = 0;
	m->mode = MODE_JOG;
	return true;
}

bool motion_continuous_rel(motion_t *m, const fx_pose_t *rel)
{
	if (!velocity_mode_allowed(m) || m->q_count > 0 || m->stopping)
		return false;
	fx_pose_t t = m->ref;
	q32_t dx, dy;
	body_to_world(m->ref.th_deg, rel->x_mm, rel->y_mm, &dx, &dy);
	t.x_mm += dx;
	t.y_mm += dy;
	t.th_deg = fx_wrap_deg(m->ref.th_deg + rel->th_deg);
	m->goal = t;
	m->goal_position_done = false;
	/* From rest the first tick picks the direction; a retarget keeps the
	 * one the unit is driving in. */
	if (m->mode != MODE_CONTINUOUS)
		m->goal_reverse = false;
	m->mode = MODE_CONTINUOUS;
	return true;
}

void motion_joystick_enable(motion_t *m, bool on)
{
	m->joystick = on;
	if (on) {
		if (m->mode == MODE_IDLE || m->mode == MODE_JOG || m->mode == MODE_CONTINUOUS)
			m->mode = MODE_JOYSTICK;
		m->vtarget = (fx_twist_t){0};
	} else if (m->mode == MODE_JOYSTICK) {
		/* Decelerate at the acceleration limit, then idle. */
		m->vtarget = (fx_twist_t){0};
		m->stopping = true;
	}
}

void motion_joystick_input(motion_t *m, int16_t x, int16_t y, int16_t r, bool present)
{
	if (m->mode != MODE_JOYSTICK || m->stopping)
		return;
	if (!present) {
		m->vtarget = (fx_twist_t){0};
		return;
	}
	m->vtarget.vx_pt = vt_eff(m) / 32767 * x;
	m->vtarget.vy_pt = m->p.kin == MOTION_KIN_OMNI ? vt_eff(m) / 32767 * y : 0;
	m->vtarget.w_pt = m->v_r_pt / 32767 * r;
}

/* ---- pause / stop ---------------------------------------------------- */

void motion_pause(motion_t *m)
{
	m->paused = true;
	if (m->mode == MODE_JOG || m->mode == MODE_JOYSTICK)
		m->vtarget = (fx_twist_t){0};
}

void motion_resume(motion_t *m)
{
	m->paused = false;
}

void motion_stop(motion_t *m)
{
	/* Path motion brakes along the path it is on, which may run on into
	 * the queued commands (a cruise line ends at speed in its corner):
	 * they are discarded once the unit is at rest, and commands queued
	 * meanwhile run after that. */
	m->stop_drop = m->q_count;
	limits_changed(m);
	m->stopping = true;
	m->vtarget = (fx_twist_t){0};
}

void motion_halt(motion_t *m)
{
	m->q_count = 0;
	m->stop_drop = 0;
	m->pass_todo = 0;
	limits_changed(m);
	m->seg.kind = SEG_NONE;
	m->v = 0;
	m->vel = (fx_twist_t){0};
	m->vtarget = (fx_twist_t){0};
	m->stopping = false;
	m->paused = false;
	m->rest_tick = false;
	m->mode = m->joystick ? MODE_JOYSTICK : MODE_IDLE;
}

/* ---- path execution -------------------------------------------------- */

static void seg_line(motion_t *m, const fx_pose_t *from, q32_t tx, q32_t ty, q32_t th_end)
{
	seg_t *g = &m->seg;
	*g = (seg_t){0};
	g->kind = SEG_LINE;
	g->p0 = *from;
	g->len = unit_dir(tx - from->x_mm, ty - from->y_mm, &g->ux, &g->uy);
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

/* The straight part of cruise command c, from the reference (its start, or
 * the previous corner's exit) along the direction planned when it was
 * queued, to its corner's entry or its waypoint. The length is measured
 * along that direction: no square root or division in the tick that blends
 * into it. The heading is already along the line (turn or corner before). */
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
	q32_t t = c->has_corner ? c->corner.t_mm : 0;
	g->p_end.x_mm = c->target.x_mm - fx_mul_q30(t, c->ux);
	g->p_end.y_mm = c->target.y_mm - fx_mul_q30(t, c->uy);
	g->p_end.th_deg = r->th_deg;
	q32_t len =
	    fx_mul_q30(g->p_end.x_mm - r->x_mm, c->ux) + fx_mul_q30(g->p_end.y_mm - r->y_mm, c->uy);
	g->len = len > 0 ? len : 0;
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

/* Sets up the next piece of the head command; false when it is finished. */
static bool next_piece(motion_t *m)
{
	motion_cmd_t *c = q_at(m, 0);
	fx_pose_t *r = &m->ref;
	for (;;) {
		switch (c->kind) {
		case MCMD_FORWARD:
			if (c->stage++ > 0)
				return false;
			seg_line(m, r, c->target.x_mm, c->target.y_mm, r->th_deg);
			if (m->seg.len < TINY_MM)
				continue;
			return true;
		case MCMD_TURN:
			if (c->stage++ > 0)
				return false;
			if (fx_abs64(c->angle_deg) < 1)
				continue;
			seg_turn(m, c->angle_deg);
			return true;
		case MCMD_ARC: {
			if (c->stage++ > 0)
				return false;
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
				continue;
			return true;
		}
		case MCMD_LINE: {
			q32_t dx = c->target.x_mm - r->x_mm, dy = c->target.y_mm - r->y_mm;
			q32_t dist = fx_hypot(dx, dy);
			if (m->p.kin == MOTION_KIN_OMNI) {
				/* Translation and rotation together, unless the move is
				 * mostly rotation (under 1 mm per degree): then the
				 * heading would ride on a tiny path ratio, so turn
				 * first and then translate. */
				q32_t a = fx_wrap_deg(c->target.th_deg - r->th_deg);
				bool split = fx_abs64(a) > FX_ONE / 1000 && dist < fx_abs64(a);
				switch (c->stage++) {
				case 0:
					if (dist >= TINY_MM && !split) {
						c->stage = 2;
						seg_line(m, r, c->target.x_mm, c->target.y_mm,
							 c->target.th_deg);
						return true;
					}
					if (fx_abs64(a) < 1)
						continue;
					seg_turn(m, a);
					return true;
				case 1:
					if (dist < TINY_MM)
						continue;
					seg_line(m, r, c->target.x_mm, c->target.y_mm, r->th_deg);
					return true;
				default:
					return false;
				}
			}
			switch (c->stage++) {
			case 0: {
				if (dist < TINY_MM)
					continue;
				q32_t a = fx_wrap_deg(fx_atan2_deg(dy, dx) - r->th_deg);
				if (fx_abs64(a) < 1)
					continue;
				seg_turn(m, a);
				return true;
			}
			case 1:
				if (dist < TINY_MM)
					continue;
				seg_line(m, r, c->target.x_mm, c->target.y_mm, r->th_deg);
				return true;
			case 2: {
				q32_t a = fx_wrap_deg(c->target.th_deg - r->th_deg);
				if (!c->has_heading || fx_abs64(a) < 1)
					continue;
				seg_turn(m, a);
				return true;
			}
			default:
				return false;
			}
		}
		case MCMD_CRUISE:
			switch (c->stage++) {
			case 0: {
				if (!c->start_known) {
					cruise_set_start(c, r->x_mm, r->y_mm);
					if (m->q_count < 2 || !plan_corner(m, 0))
						backward_pass(m);
				}
				if (m->v > 0)
					continue; /* arriving out of a corner, already aligned */
				q32_t dx = c->target.x_mm - r->x_mm, dy = c->target.y_mm - r->y_mm;
				if (fx_hypot(dx, dy) < TINY_MM)
					continue;
				q32_t a = fx_wrap_deg(fx_atan2_deg(dy, dx) - r->th_deg);
				if (fx_abs64(a) < 1)
					continue;
				seg_turn(m, a);
				return true;
			}
			case 1:
				if (c->len_mm < TINY_MM)
					continue;
				cruise_line(m, c);
				return true;
			default:
				/* Its corner, if any, began as its line ended
				 * (path_tick): nothing is left. */
				return false;
			}
		default:
			return false;
		}
	}
}

/* Speed cap and acceleration of the active piece. */
static void piece_limits(const motion_t *m, q32_t *vmax, q32_t *a)
{
	const seg_t *g = &m->seg;
	switch (g->kind) {
	case SEG_TURN:
		*vmax = m->v_r_pt;
		*a = m->a_r_pt2;
		break;
	case SEG_ARC: {
		q32_t vt = fx_div(vt_eff(m), g->arc_k), at = fx_div(m->a_t_pt2, g->arc_k);
		*vmax = fx_min64(m->v_r_pt, vt);
		*a = fx_min64(m->a_r_pt2, at);
		break;
	}
	case SEG_LINE:
		*vmax = vt_eff(m);
		*a = m->a_t_pt2;
		if (g->dth != 0) {
			/* omni_k is rounded: keep 1/4096 below the rotation limits. */
			q32_t vr = fx_mul(m->v_r_pt, g->omni_k), ar = fx_mul(m->a_r_pt2, g->omni_k);
			*vmax = fx_min64(*vmax, vr - (vr >> 12));
			*a = fx_min64(*a, ar - (ar >> 12));
		}
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
	t->vy_pt = m->p.kin == MOTION_KIN_OMNI ? fx_mul_q30(dy, c) - fx_mul_q30(dx, s) : 0;
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

static void path_tick(motion_t *m, fx_twist_t *out)
{
	bool braking = m->paused || m->stopping;
	if (braking && m->v == 0) {
		if (m->stopping) {
			m->stopping = false;
			while (m->stop_drop)
				pop(m);
			m->seg.kind = SEG_NONE;
			m->mode = m->q_count ? MODE_PATH : MODE_IDLE;
		}
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
			m->seg.s = 0;
			limits_changed(m);
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
			if (!m->lim_ok) {
				piece_limits(m, &m->lim_vmax, &m->lim_a);
				m->lim_extra = piece_horizon_extra(m);
				m->lim_cruise = -1;
				m->lim_n = -1;
				m->lim_ok = true;
			}
			q32_t d = m->seg.len - m->seg.s + m->lim_extra;
			q32_t u;
			if (m->v == m->lim_vmax) {
				/* At the cap with room to stop from it, traj_step keeps
				 * the speed: skip it (its braking distance divides). */
				if (m->lim_cruise < 0)
					m->lim_cruise =
					    m->lim_vmax + traj_brake_dist(m->lim_vmax, m->lim_a);
				u = d >= m->lim_cruise
					? m->v
					: traj_step_near(m->v, d, m->lim_vmax, m->lim_a, &m->lim_n);
			} else {
				u = traj_step_near(m->v, d, m->lim_vmax, m->lim_a, &m->lim_n);
			}
			if (braking) {
				/* Stop at the acceleration limit, along the path. */
				q32_t amax = m->amax_t_pt2;
				if (m->seg.kind == SEG_TURN)
					amax = m->amax_r_pt2;
				else if (m->seg.kind == SEG_ARC)
					amax = fx_min64(m->amax_r_pt2,
							fx_div(m->amax_t_pt2, m->seg.arc_k));
				else if (m->seg.kind == SEG_LINE && m->seg.dth != 0)
				/* Heading turns with the path: both limits bind. */
				{
					q32_t ar = fx_mul(m->amax_r_pt2, m->seg.omni_k);
					amax = fx_min64(amax, ar - (ar >> 12));
				} else if (m->seg.kind == SEG_CORNER)
					/* Half the rotational limit for braking, the other
					 * half is the curvature change (traj.h). */
					amax = fx_min64(
					    amax,
					    fx_mul(m->amax_r_pt2, m->seg.corner.k_mm_deg) / 2);
				u = fx_min64(u, fx_max64(m->v - amax, 0));
			}
			budget = u;
			m->v = u;
		}
		q32_t rem = m->seg.len - m->seg.s;
		along = along &&
			(m->seg.kind == SEG_CORNER || (m->seg.kind == SEG_LINE && m->seg.dth == 0));
		if (dir == 0)
			dir = m->seg.dir;
		if (budget < rem) {
			piece_advance(m, m->seg.s + budget);
			m->seg.s += budget;
			moved += budget;
			if (m->seg.kind == SEG_TURN && m->seg.s != budget) {
				*out = (fx_twist_t){.w_pt = m->seg.dir * budget};
				return;
			}
			if (m->seg.kind == SEG_ARC) {
				/* Exact rates; the pose itself is analytic. */
				q32_t w = m->seg.dir * budget;
				out->vx_pt = fx_mul(w, m->seg.arc_kx);
				out->vy_pt = fx_mul(w, m->seg.arc_ky);
				out->w_pt = w;
				return;
			}
			break;
		}
		/* Piece complete: land exactly on its end (a corner's integration
		 * arrives within nanometres of its planned exit). */
		m->ref = m->seg.p_end;
		budget -= rem;
		moved += rem;
		uint8_t kind = m->seg.kind;
		m->seg.kind = SEG_NONE;
		if (!blends_onward(m, kind)) {
			/* A stop: the last step covered the exact remainder (< a). */
			m->v = 0;
			m->rest_tick = true;
			break;
		}
		if (kind == SEG_LINE && q_at(m, 0)->corner.lh_mm != 0) {
			/* Into the corner here, not through next_piece: this is
			 * the dearest tick of a cruise (a collinear pass has no
			 * corner piece). */
			corner_piece(m, q_at(m, 0));
			limits_changed(m);
		}
		if (budget == 0)
			break;
	}
	if (along && m->p.kin == MOTION_KIN_DIFF) {
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

/* Move x toward target by at most step. */
static q32_t slew(q32_t x, q32_t target, q32_t step)
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

static bool twist_zero(const fx_twist_t *t)
{
	return t->vx_pt == 0 && t->vy_pt == 0 && t->w_pt == 0;
}

/* Jog and joystick: slew toward the target velocity. */
static void velocity_tick(motion_t *m, fx_twist_t *out)
{
	bool braking = m->stopping || m->paused;
	fx_twist_t tgt = m->vtarget;
	q32_t at = m->a_t_pt2, ar = m->a_r_pt2;
	if (m->mode == MODE_JOG && ++m->jog_age_ticks > m->jog_timeout_ticks)
		tgt = (fx_twist_t){0};
	if (braking) {
		tgt = (fx_twist_t){0};
		at = m->amax_t_pt2;
		ar = m->amax_r_pt2;
	}
	/* Caution cap and set velocity bound the target. */
	q32_t vt = vt_eff(m);
	tgt.vx_pt = fx_clamp64(tgt.vx_pt, -vt, vt);
	tgt.vy_pt = fx_clamp64(tgt.vy_pt, -vt, vt);
	tgt.w_pt = fx_clamp64(tgt.w_pt, -m->v_r_pt, m->v_r_pt);
	slew2(&m->vel.vx_pt, &m->vel.vy_pt, tgt.vx_pt, tgt.vy_pt, at);
	m->vel.w_pt = slew(m->vel.w_pt, tgt.w_pt, ar);
	*out = m->vel;
	if (twist_zero(&m->vel) && twist_zero(&tgt)) {
		bool jog_done = m->mode == MODE_JOG && (m->jog_age_ticks > m->jog_timeout_ticks ||
							braking || twist_zero(&m->vtarget));
		bool joystick_done = m->mode == MODE_JOYSTICK && m->stopping;
		if (jog_done || joystick_done) {
			m->mode = MODE_IDLE;
			m->stopping = false;
		}
	}
}

/* Continuous mode: drive toward the goal with slewed velocities. */
static void continuous_tick(motion_t *m, fx_twist_t *out)
{
	bool braking = m->stopping || m->paused;
	fx_twist_t want = {0};
	q32_t dx = m->goal.x_mm - m->ref.x_mm, dy = m->goal.y_mm - m->ref.y_mm;
	q32_t dist = fx_hypot(dx, dy);
	if (!m->goal_position_done && dist < TINY_MM && fx_abs64(m->vel.vx_pt) == 0 &&
	    m->vel.vy_pt == 0)
		m->goal_position_done = true;
	if (!m->goal_position_done) {
		q32_t bearing = fx_atan2_deg(dy, dx);
		q32_t e = fx_wrap_deg(bearing - m->ref.th_deg);
		if (m->p.kin == MOTION_KIN_OMNI) {
			q32_t sp = fx_min64(traj_umax(dist, m->a_t_pt2), vt_eff(m));
			uint32_t b = fx_deg_to_bam(e);
			want.vx_pt = fx_mul_q30(sp, fx_cos_bam(b));
			want.vy_pt = fx_mul_q30(sp, fx_sin_bam(b));
		} else {
			/* Drive forward or backward, whichever faces the goal: a
			 * goal that falls behind (a retarget inside the stopping
			 * distance, an overshoot) is reached by backing along the
			 * line, not by turning round at speed and circling it. The
			 * 20 degree band about the side keeps the choice from
			 * chattering. */
			q32_t ae = fx_abs64(e);
			if (!m->goal_reverse && ae > fx_from_int(100))
				m->goal_reverse = true;
			else if (m->goal_reverse && ae < fx_from_int(80))
				m->goal_reverse = false;
			if (m->goal_reverse) {
				e = fx_wrap_deg(e + fx_from_int(180));
				ae = fx_abs64(e);
			}
			/* Turn toward the goal; translate along the projected distance. */
			q32_t wr = fx_min64(traj_umax(ae, m->a_r_pt2), m->v_r_pt);
			want.w_pt = e < 0 ? -wr : wr;
			uint32_t b = fx_deg_to_bam(e);
			q32_t proj = fx_mul_q30(dist, fx_cos_bam(b));
			if (proj > 0 && ae < fx_from_int(45))
				want.vx_pt = fx_min64(traj_umax(proj, m->a_t_pt2), vt_eff(m));
			if (m->goal_reverse)
				want.vx_pt = -want.vx_pt;
			if (dist < m->v_t_pt && ae < fx_from_int(1))
				want.w_pt = 0;
		}
	} else {
		q32_t e = fx_wrap_deg(m->goal.th_deg - m->ref.th_deg);
		q32_t wr = fx_min64(traj_umax(fx_abs64(e), m->a_r_pt2), m->v_r_pt);
		want.w_pt = e < 0 ? -wr : wr;
	}
	q32_t at = m->a_t_pt2, ar = m->a_r_pt2;
	if (braking) {
		want = (fx_twist_t){0};
		at = m->amax_t_pt2;
		ar = m->amax_r_pt2;
	}
	q32_t prev_vx = m->vel.vx_pt;
	slew2(&m->vel.vx_pt, &m->vel.vy_pt, want.vx_pt, want.vy_pt, at);
	m->vel.w_pt = slew(m->vel.w_pt, want.w_pt, ar);
	/* Never step past the goal: the last step covers the exact remainder
	 * (backing up, the same with the signs turned). */
	q32_t dir = m->goal_reverse ? -1 : 1;
	if (!m->goal_position_done && dir * m->vel.vx_pt > dist && m->p.kin == MOTION_KIN_DIFF)
		m->vel.vx_pt = dir * fx_max64(dist, dir * prev_vx - at);
	*out = m->vel;
	odom_integrate(&m->ref, out, NULL);
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
	if (braking && twist_zero(&m->vel)) {
		if (m->stopping) {
			m->stopping = false;
			m->mode = MODE_IDLE;
		}
	}
}

void motion_tick(motion_t *m, const fx_pose_t *measured, fx_twist_t *out)
{
	*out = (fx_twist_t){0};
	switch (m->mode) {
	case MODE_PATH:
		path_tick(m, out);
		m->vel = *out;
		break;
	case MODE_JOG:
	case MODE_JOYSTICK:
		velocity_tick(m, out);
		odom_integrate(&m->ref, out, NULL);
		break;
	case MODE_CONTINUOUS:
		continuous_tick(m, out);
		break;
	default:
		m->stopping = false;
		m->vel = (fx_twist_t){0};
		/* Idle: follow the measured pose so relative moves start from it. */
		if (measured)
			m->ref = *measured;
		break;
	}
	/* A velocity mode that ended hands over to queued path commands. */
	if (m->mode == MODE_IDLE && m->q_count > 0)
		m->mode = MODE_PATH;
	if (m->mode == MODE_IDLE && m->joystick)
		m->mode = MODE_JOYSTICK;
}

bool motion_is_moving(const motion_t *m)
{
	return !twist_zero(&m->vel) || m->v != 0;
}

bool motion_has_work(const motion_t *m)
{
	/* An enabled joystick at rest is not work: the unit is waiting. */
	return (m->mode != MODE_IDLE && m->mode != MODE_JOYSTICK) || motion_is_moving(m);
}

bool motion_is_paused(const motion_t *m)
{
	return m->paused;
}
uint8_t motion_queue_len(const motion_t *m)
{
	/* Not the commands a stop is braking through: they are gone. */
	return (uint8_t)(m->q_count - m->stop_drop);
}
uint8_t motion_mode(const motion_t *m)
{
	return m->mode;
}
