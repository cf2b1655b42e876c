/* Motion engine: the pieces of the queued commands other than a cruise
 * waypoint (whose stages are the path tick's own, motion_tick.c): a
 * command runs in stages (face, drive, turn), each setting up one piece (a
 * turn, a line, an arc) from where the reference stands. */
#include "motion_priv.h"

#include <stddef.h>

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

void motion_seg_turn(motion_t *m, q32_t angle)
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
	motion_seg_turn(m, c->angle_deg);
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
		motion_seg_turn(m, a);
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
		motion_seg_turn(m, a);
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
		motion_seg_turn(m, a);
		return STAGE_PIECE;
	}
	default:
		return STAGE_DONE;
	}
}

stage_t motion_stage(motion_t *m, motion_cmd_t *c)
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
	default:
		return STAGE_DONE;
	}
}
