/* Motion engine: the queue and the commands that queue a move. Relative
 * commands resolve against the reference pose at the call. */
#include "motion_priv.h"

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

bool motion_forward(motion_t *m, q32_t dist_mm)
{
	motion_cmd_t c = {0};
	c.kind = MCMD_FORWARD;
	q32_t dx, dy;
	motion_body_to_world(m->ref.th_deg, dist_mm, 0, &dx, &dy);
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
	fx_pose_t t = motion_rel_to_abs(&m->ref, rel);
	return motion_linear_abs(m, &t);
}

bool motion_circular_rel(motion_t *m, q32_t cx_mm, q32_t cy_mm, q32_t angle_deg)
{
	motion_cmd_t c = {0};
	q32_t dx, dy;
	if (!KIN_OMNI(m->p.kin) && cx_mm != 0)
		return false;
	motion_body_to_world(m->ref.th_deg, cx_mm, cy_mm, &dx, &dy);
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
	fx_rot_q30(rx, ry, co, si, &rx, &ry);
	c.target.x_mm = c.cx_mm + rx;
	c.target.y_mm = c.cy_mm + ry;
	c.target.th_deg = fx_wrap_deg(m->ref.th_deg + angle_deg);
	return push(m, &c);
}

bool motion_cruise_abs(motion_t *m, q32_t x_mm, q32_t y_mm)
{
	motion_cmd_t c = {0};
	c.kind = MCMD_CRUISE;
	c.target.x_mm = x_mm;
	c.target.y_mm = y_mm;
	q32_t sx, sy;
	if (tail_end(m, &sx, &sy))
		motion_cruise_set_start(&c, sx, sy);
	if (!push(m, &c))
		return false;
	uint8_t last = (uint8_t)(m->q_count - 1);
	if (last == 0 || !motion_plan_corner(m, (uint8_t)(last - 1)))
		motion_backward_pass_from(m, last);
	return true;
}
