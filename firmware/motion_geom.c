/* Motion engine: geometry shared by the commands and the pieces. */
#include "motion_priv.h"

void motion_body_to_world(q32_t th, q32_t bx, q32_t by, q32_t *wx, q32_t *wy)
{
	uint32_t b = fx_deg_to_bam(th);
	int32_t c, s;
	fx_sincos_bam(b, &s, &c);
	fx_rot_q30(bx, by, c, s, wx, wy);
}

fx_pose_t motion_rel_to_abs(const fx_pose_t *from, const fx_pose_t *rel)
{
	fx_pose_t t = *from;
	q32_t dx, dy;
	motion_body_to_world(from->th_deg, rel->x_mm, rel->y_mm, &dx, &dy);
	t.x_mm += dx;
	t.y_mm += dy;
	t.th_deg = fx_wrap_deg(from->th_deg + rel->th_deg);
	return t;
}

/* Out of line: it runs when a command is queued or a piece starts, and
 * inlined it cost the steady cruise tick 5 instructions (measured). */
__attribute__((noinline)) q32_t motion_unit_dir(q32_t dx, q32_t dy, int32_t *ux, int32_t *uy)
{
	q32_t len = fx_hypot(dx, dy);
	*ux = *uy = 0;
	if (len > 0) {
		*ux = (int32_t)(fx_div(dx, len) >> 2);
		*uy = (int32_t)(fx_div(dy, len) >> 2);
	}
	return len;
}

/* The turn that faces cruise command c's waypoint from pose r (0: none,
 * or no distance to it). */
q32_t motion_cruise_face(const motion_cmd_t *c, const fx_pose_t *r)
{
	q32_t dx = c->target.x_mm - r->x_mm, dy = c->target.y_mm - r->y_mm;
	if (fx_hypot(dx, dy) < TINY_MM)
		return 0;
	return fx_wrap_deg(fx_atan2_deg(dy, dx) - r->th_deg);
}
