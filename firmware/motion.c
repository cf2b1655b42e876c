/* Motion engine: initialisation, settings, setPosition, the velocity
 * modes' commands, pause, stop, halt and the queries. motion_priv.h lists the engine's other files.
 */
#include "motion_priv.h"

static void per_tick(motion_t *m)
{
	int64_t hz = m->p.tick_hz, hz2 = hz * hz, hz3 = hz2 * hz;
	/* Per-tick values round down so a set limit is never exceeded. One
	 * division by hz^n is n by hz (truncations compose for positive
	 * divisors; hz^3 <= 10^12): a 64-bit division is a call on a board. */
	m->vmax_t_pt = m->p.vel_limit_t / hz;
	m->vmax_r_pt = m->p.vel_limit_r / hz;
	m->amax_t_pt2 = m->p.acc_limit_t / hz2;
	m->amax_r_pt2 = m->p.acc_limit_r / hz2;
	m->jmax_t_pt3 = m->p.jerk_limit_t / hz3;
	m->jmax_r_pt3 = m->p.jerk_limit_r / hz3;
	m->jerk_any = (m->jmax_t_pt3 | m->jmax_r_pt3) != 0;
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

FX_OUTLINE void motion_set_velocity(motion_t *m, q32_t vt, q32_t vr)
{
	m->v_t_pt = vt / m->p.tick_hz;
	m->v_r_pt = vr / m->p.tick_hz;
	motion_backward_pass(m);
}

void motion_set_accel(motion_t *m, q32_t at, q32_t ar)
{
	int64_t hz2 = (int64_t)m->p.tick_hz * m->p.tick_hz; /* as per_tick */
	m->a_t_pt2 = at / hz2;
	m->a_r_pt2 = ar / hz2;
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
	motion_backward_pass(m);
}

void motion_set_jerk(motion_t *m, q32_t jt, q32_t jr)
{
	int64_t hz = m->p.tick_hz, hz3 = hz * hz * hz; /* as per_tick */
	m->j_t_pt3 = jt / hz3;
	m->j_r_pt3 = jr / hz3;
	m->jerk_any = (m->j_t_pt3 | m->j_r_pt3 | m->jmax_t_pt3 | m->jmax_r_pt3) != 0;
	limits_changed(m);
	/* A continuous goal under way takes up the jerk-limited law from its
	 * speed and acceleration (motion_seek.c). */
	if (ONLINE_JERK && m->mode == MODE_CONTINUOUS)
		motion_seek_retarget(m);
}

FX_OUTLINE void motion_set_jog_timeout_ms(motion_t *m, uint32_t ms)
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
	fx_rot_q30(rx, ry, f->c, f->s, &rx, &ry);
	*x = f->nx + rx;
	*y = f->ny + ry;
}

static void map_pose(const frame_map_t *f, fx_pose_t *p)
{
	map_point(f, &p->x_mm, &p->y_mm);
	p->th_deg = fx_wrap_deg(p->th_deg + f->dth);
}

static void map_dir(const frame_map_t *f, int32_t *ux, int32_t *uy)
{
	int64_t x, y;
	fx_rot_q30(*ux, *uy, f->c, f->s, &x, &y);
	*ux = (int32_t)x;
	*uy = (int32_t)y;
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

/* ---- the velocity modes' commands --------------------------------- */

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
	fx_pose_t t = motion_rel_to_abs(&m->ref, rel);
	m->goal = t;
	m->goal_position_done = false;
	/* From rest the first tick picks the direction; a retarget keeps the
	 * one the unit is driving in. */
	if (m->mode != MODE_CONTINUOUS)
		m->goal_reverse = false;
	m->mode = MODE_CONTINUOUS;
	if (ONLINE_JERK && seek_jerk(m))
		motion_seek_retarget(m);
	return true;
}

void motion_joystick_enable(motion_t *m, bool on)
{
	if (on == m->joystick)
		return;
	m->joystick = on;
	if (on) {
		/* The joystick takes over as stop() would: host motion brakes at
		 * the limit and its queue is dropped; the joystick drives from
		 * rest (motion_tick hands over once idle). */
		if (m->mode == MODE_IDLE) {
			m->mode = MODE_JOYSTICK;
			m->paused = false;
		} else {
			motion_stop(m);
		}
		m->vtarget = (fx_twist_t){0};
	} else if (m->mode == MODE_JOYSTICK) {
		/* Decelerate at the acceleration limit, then idle; at rest idle
		 * now (a command sent next is not refused for a stop). */
		m->vtarget = (fx_twist_t){0};
		if (motion_is_moving(m)) {
			m->stopping = true;
		} else {
			/* A stop still flagged (stop() under the joystick at
			 * rest) has nothing left to brake either. */
			m->mode = MODE_IDLE;
			m->stopping = false;
		}
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
	m->vtarget.vy_pt = KIN_OMNI(m->p.kin) ? vt_eff(m) / 32767 * y : 0;
	m->vtarget.w_pt = m->v_r_pt / 32767 * r;
}

/* ---- pause / stop ---------------------------------------------------- */

/* Still to the last bit: no velocity, no change of it, the seek law idle
 * (a jog or goal sent but not yet run by a tick is such). */
static bool at_rest(const motion_t *m)
{
	return twist_zero(&m->vel) && twist_zero(&m->vacc) &&
	       (!ONLINE_JERK || !(m->sk_on[0] | m->sk_on[1]));
}

void motion_pause(motion_t *m)
{
	m->paused = true;
	if (m->mode == MODE_JOG || m->mode == MODE_JOYSTICK)
		m->vtarget = (fx_twist_t){0};
	/* A jog cannot wait for resume (it is refused while paused): the
	 * pause ends it, at once when it has not moved (docs/states.md). */
	if (m->mode == MODE_JOG && at_rest(m))
		m->mode = MODE_IDLE;
}

void motion_resume(motion_t *m)
{
	m->paused = false;
}

void motion_stop(motion_t *m)
{
	/* Nothing moving and nothing queued: nothing to stop (a jog or goal
	 * sent next is not refused for a stop still "braking"). */
	if (m->mode == MODE_IDLE && m->q_count == 0 && !motion_is_moving(m)) {
		m->paused = false;
		return;
	}
	/* Path motion brakes along the path it is on, which may run on into
	 * the queued commands (a cruise line ends at speed in its corner):
	 * they are discarded once the unit is at rest, and commands queued
	 * meanwhile run after that. */
	m->stop_drop = m->q_count;
	limits_changed(m);
	m->stopping = true;
	if (m->mode != MODE_PATH) {
		/* Nothing queued is under way (a jog or a goal runs ahead of
		 * it): it goes now, or it would run once the stop is done. */
		m->q_count = 0;
		m->stop_drop = 0;
		m->pass_todo = 0;
		m->ln_next = LN_NEXT_NONE;
		m->face_ok = false;
		/* A jog or goal at rest (paused, or not yet ticked) has nothing
		 * to brake: Ready at once, as the model of the spec has it. */
		if (m->mode != MODE_JOYSTICK && at_rest(m)) {
			m->mode = MODE_IDLE;
			m->stopping = false;
		}
	}
	/* Spec 5 #33: stop ends in Ready, a pause included. */
	m->paused = false;
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
	m->acc = 0;
	m->sc_on = m->ln_on = m->glide = m->hold_on = m->fresh = false;
	m->ln_next = LN_NEXT_NONE;
	m->face_ok = false;
	m->vel = (fx_twist_t){0};
	m->vacc = (fx_twist_t){0};
	m->vtarget = (fx_twist_t){0};
	if (ONLINE_JERK) { /* the continuous goal's law (motion_seek.c) */
		m->sk_on[0] = m->sk_on[1] = false;
		m->sk_v[0] = m->sk_v[1] = m->sk_a[0] = m->sk_a[1] = 0;
	}
	m->stopping = false;
	m->paused = false;
	m->rest_tick = false;
	m->mode = m->joystick ? MODE_JOYSTICK : MODE_IDLE;
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

bool motion_host_work(const motion_t *m)
{
	if (m->q_count > m->stop_drop)
		return true;
	if (m->stopping)
		return false;
	switch (m->mode) {
	case MODE_PATH:
	case MODE_CONTINUOUS:
		return true;
	case MODE_JOG:
		return m->jog_age_ticks <= m->jog_timeout_ticks && !twist_zero(&m->vtarget);
	default:
		return false;
	}
}

q32_t motion_speed_cap(const motion_t *m)
{
	return vt_eff(m);
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
