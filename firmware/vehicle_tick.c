/* VehicleService core: the control tick and the supervision it runs
 * (loop lateness, link watchdog, drives and encoders, inputs, joystick,
 * position). One file: the supervision inlines into vehicle_tick, and a
 * call between files costs every tick. */
#include <stddef.h>
#include <stdint.h>

#include "vehicle_priv.h"

/* Reports are out of line (cold): their text buffers and calls stay off
 * the every-tick path. */
#define COLD __attribute__((cold, noinline))

static COLD void loop_stalled(vehicle_t *v, uint32_t late_us)
{
	char s[VS_ALARM_SOURCE_MAX];
	size_t pos = vehicle_put_str(s, sizeof s, 0, "control loop stalled ");
	pos = vehicle_put_dec(s, sizeof s, pos, late_us / 1000u, 1);
	vehicle_put_str(s, sizeof s, pos, " ms");
	vehicle_raise_fault(v, ALM_F_LOOP_STALL, s);
}

/* Wake-up lateness is the platform's doing (a busy host, a blocking call):
 * the reference advances by ticks, so a late tick only holds it while the
 * drives keep their last setpoint, and the wheel runs ahead by speed times
 * lateness, which the position loop takes back. Late ticks are counted;
 * only a stall longer than loop_late_ms stops the unit (docs/linux.md). */
static void check_lateness(vehicle_t *v, uint32_t now_us)
{
	if (v->have_now) {
		/* Wrap-safe difference; an early tick is not late. */
		int32_t late = (int32_t)(now_us - v->last_now_us) - (int32_t)v->period_us;
		if (late > 0 && (uint32_t)late * 2u > v->period_us) {
			v->late_ticks++;
			if ((uint32_t)late > v->max_late_us)
				v->max_late_us = (uint32_t)late;
			if ((uint32_t)late > v->loop_late_us)
				loop_stalled(v, (uint32_t)late);
		}
	}
	v->last_now_us = now_us;
	v->have_now = true;
}

void vehicle_set_plan_budget(vehicle_t *v, uint8_t n)
{
	motion_set_plan_budget(&v->motion, n);
}

bool vehicle_plan_idle(vehicle_t *v)
{
	return motion_plan_idle(&v->motion);
}

void vehicle_tick_busy(vehicle_t *v, uint32_t busy_us)
{
	if (busy_us > v->period_us) {
		v->overruns++;
		vehicle_raise_fault(v, ALM_F_OVERRUN, "control tick overrun");
	}
}

void vehicle_link_heard(vehicle_t *v, vs_link_id_t link)
{
	v->link_last = (uint8_t)link;
	v->link_silent_ticks = 0;
}

uint32_t vehicle_link_timeout(const vehicle_t *v)
{
	return v->cfg.link_timeout_ms;
}

/* Out of line: init, $config and $watchdog call it, each its own copy
 * inlined (0.1 KiB of a board's flash). */
COLD void vehicle_set_link_timeout(vehicle_t *v, uint32_t ms)
{
	v->cfg.link_timeout_ms = ms;
	/* ms * tick_hz / 1000, rounded up: at least one tick when on. */
	v->link_timeout_ticks = (uint32_t)(((uint64_t)ms * v->cfg.tick_hz + 999u) / 1000u);
	v->link_silent_ticks = 0;
}

static COLD void link_lost(vehicle_t *v)
{
	static const char *const names[] = {"console", "frames", "CAN"};
	char s[VS_ALARM_SOURCE_MAX];
	size_t pos = vehicle_put_str(s, sizeof s, 0, "link lost: ");
	pos = vehicle_put_str(s, sizeof s, pos, names[v->link_last < 3 ? v->link_last : 0]);
	pos = vehicle_put_str(s, sizeof s, pos, " silent ");
	pos = vehicle_put_dec(s, sizeof s, pos, v->cfg.link_timeout_ms, 1);
	vehicle_put_str(s, sizeof s, pos, " ms");
	motion_stop(&v->motion);
	alarm_raise(&v->alarms, ALM_W_LINK_LOST, s);
}

/* Link watchdog: motion commanded from a host stops when the host falls
 * silent, whatever the joystick flag (a route that runs while the joystick
 * takes over is still the host's). The joystick's own motion and a paused
 * unit need no host; the stop discards the queue and nothing resumes by
 * itself. */
static void supervise_link(vehicle_t *v)
{
	if (v->link_silent_ticks < UINT32_MAX)
		v->link_silent_ticks++;
	if (v->link_timeout_ticks == 0 || v->link_silent_ticks < v->link_timeout_ticks)
		return;
	if (motion_is_paused(&v->motion) || !motion_host_work(&v->motion))
		return;
	v->link_silent_ticks = 0;
	link_lost(v);
}

static void encoder_stuck(vehicle_t *v, uint8_t i)
{
	char s[VS_ALARM_SOURCE_MAX];
	v->encoder_still_ticks[i] = 0;
	vehicle_axis_text(s, sizeof s, "encoder ", i, " stuck");
	vehicle_raise_fault(v, ALM_F_ENCODER_STUCK, s);
}

/* Encoder supervision, in the same pass as the drive sample: a wheel
 * commanded above the stuck threshold whose count did not change. */
static inline void supervise_encoder(vehicle_t *v, uint8_t i, bool moved)
{
	/* A count that moved first: a moving wheel's tick asks nothing more
	 * (8 instructions a wheel, tools/bench/tickcost.sh). */
	if (moved) {
		v->encoder_still_ticks[i] = 0;
		return;
	}
	uint32_t cps = (uint32_t)v->wheel_cps_q8[i];
	bool commanded = v->servo && cps + v->encoder_stuck_off >= v->encoder_stuck_span;
	if (!commanded)
		v->encoder_still_ticks[i] = 0;
	else if (++v->encoder_still_ticks[i] >= v->encoder_stuck_ticks)
		encoder_stuck(v, i);
}

/* No sample for drive_timeout_ms: 202, saying "busy" when the drive only
 * answered that; 213 when it answered that it has no such register or
 * function (the register map is wrong: waiting does not help). */
static COLD void drive_silent_report(vehicle_t *v, uint8_t i, uint8_t why)
{
	char s[VS_ALARM_SOURCE_MAX];
	v->drive_timeout_reported[i] = true;
	if (why == HAL_SILENT_MAP) {
		vehicle_axis_text(s, sizeof s, "drive ", i, " rejects its register map");
		vehicle_raise_fault(v, ALM_F_DRIVE_MAP, s);
		return;
	}
	vehicle_axis_text(s, sizeof s, "drive ", i,
			  why == HAL_SILENT_BUSY ? " not answering: busy" : " not answering");
	vehicle_raise_fault(v, ALM_F_DRIVE_TIMEOUT, s);
}

static COLD void drive_fault_report(vehicle_t *v, uint8_t i, uint16_t fc)
{
	char s[VS_ALARM_SOURCE_MAX];
	size_t pos = vehicle_axis_text(s, sizeof s, "drive ", i, " fault ");
	vehicle_put_hex4(s, sizeof s, pos, fc);
	vehicle_raise_fault(v, ALM_F_DRIVE, s);
}

/* The drive's own state, in the drive's words (CiA 402 names). */
static const char *phase_name(uint8_t ph)
{
#ifdef VS_NO_DRIVE_STATES
	/* A board whose drives report no state carries no names. */
	(void)ph;
	return "";
#else
	static const char *const names[HAL_DRIVE_STATE_COUNT] = {"",
								 "Not ready to switch on",
								 "Switch on disabled",
								 "Ready to switch on",
								 "Switched on",
								 "Operation enabled",
								 "Quick stop active",
								 "Fault reaction active",
								 "Fault",
								 "not operational"};
	return ph < HAL_DRIVE_STATE_COUNT ? names[ph] : "";
#endif
}

/* "drive <axis> <what>: <state>" (no state when the backend does not know
 * it). */
static COLD void drive_state_fault(vehicle_t *v, uint32_t code, uint8_t i, const char *what)
{
	char s[VS_ALARM_SOURCE_MAX];
#ifdef VS_NO_DRIVE_STATES
	vehicle_axis_text(s, sizeof s, "drive ", i, what);
	vehicle_raise_fault(v, code, s);
	return;
#endif
	size_t pos = vehicle_axis_text(s, sizeof s, "drive ", i, what);
	const char *ph = phase_name(v->drive[i].phase);
	if (*ph) {
		pos = vehicle_put_str(s, sizeof s, pos, ": ");
		vehicle_put_str(s, sizeof s, pos, ph);
	}
	vehicle_raise_fault(v, code, s);
}

/* A drive restarted: its count starts over. The odometry does not take the
 * jump, the wheel loop starts from the new counts, the motion stops, and
 * motion is refused until setPosition says where the unit is. */
static COLD void drive_restarted(vehicle_t *v, uint8_t i)
{
	char s[VS_ALARM_SOURCE_MAX];
	vehicle_axis_text(s, sizeof s, "drive ", i, " position lost: setPosition required");
	motion_stop(&v->motion);
	v->pose_lost = true;
	alarm_raise(&v->alarms, ALM_W_DRIVE_RESTARTED, s);
}

/* Servo on is complete when every drive reports enabled: until then the
 * setpoints are zero and the motion waits; past servo_on_timeout_ms it is a
 * fault naming the first drive not enabled and its state. Once on, a drive
 * that leaves Operation enabled by itself (an STO, a drive's own stop) is a
 * fault too: the other wheels must not drive on alone. */
static void supervise_enable(vehicle_t *v)
{
	uint8_t off = VS_MAX_AXES;
	for (uint8_t i = 0; i < v->naxes && off == VS_MAX_AXES; i++)
		if (!v->drive[i].enabled)
			off = i;
	if (v->servo_wait) {
		if (off == VS_MAX_AXES) {
			v->servo_wait = false;
			/* The wheel references start at the counts of this moment. */
			kin_sync(&v->kin, v->meas_counts);
			v->inpos_ticks = v->window_ticks;
		} else if (++v->servo_wait_ticks > v->servo_on_timeout_ticks) {
			drive_state_fault(v, ALM_F_DRIVE_NOT_ENABLED, off, " not enabled");
		}
	} else if (off != VS_MAX_AXES && v->drive[off].fault_code == 0) {
		drive_state_fault(v, ALM_F_DRIVE_DISABLED, off, " left Operation enabled");
	}
}

/* A drive restarted, reports a fault or no longer does. */
static void drive_news(vehicle_t *v, uint8_t i, const hal_drive_state_t *st)
{
	if (VS_DRIVE_STATES && st->position_lost) {
		v->kin.last_meas[i] = st->position_counts;
		drive_restarted(v, i);
	}
	uint16_t fc = v->powered ? st->fault_code : 0;
	if (fc != 0 && fc != v->drive_fault_reported[i])
		drive_fault_report(v, i, fc);
	v->drive_fault_reported[i] = fc;
}

/* The report's eight bytes as one word, and the bits of the rare news in
 * it (a fault code, a lost position): one mask folded at compile time
 * whatever the bit-fields' layout, one test a drive (6 instructions a tick
 * of a differential base). */
static inline uint64_t drive_bits(const hal_drive_state_t *st)
{
	uint64_t b;
	__builtin_memcpy(&b, st, sizeof b);
	return b;
}
static const hal_drive_state_t drive_rare = {.fault_code = UINT16_MAX,
					     .position_lost = VS_DRIVE_STATES};

/* Reads drive i; true when it reports enabled. Each drive's condition is
 * reported once per occurrence (and again after clearAlarm while it
 * persists), so two faulted drives do not take turns at the front of the
 * list every tick. */
static inline __attribute__((always_inline)) bool sample_drive(vehicle_t *v, uint8_t i)
{
	hal_drive_state_t st = {0};
	v->hal.ops->drive_read(v->hal.ctx, i, &st);
	if (!st.fresh) {
		if (v->powered && v->drive_silent_ticks[i] < UINT32_MAX)
			v->drive_silent_ticks[i]++;
		if (v->powered && v->drive_silent_ticks[i] > v->drive_timeout_ticks &&
		    !v->drive_timeout_reported[i])
			drive_silent_report(v, i, st.silent_why);
		supervise_encoder(v, i, false);
		return v->drive[i].enabled; /* as last reported */
	}
	v->drive_silent_ticks[i] = 0;
	v->drive_timeout_reported[i] = false;
	v->drive[i] = st;
	supervise_encoder(v, i, st.position_counts != v->meas_counts[i]);
	v->meas_counts[i] = st.position_counts;
	/* One test for the rare: a restart, a fault, one that ended. */
	if ((drive_bits(&st) & drive_bits(&drive_rare)) | v->drive_fault_reported[i])
		drive_news(v, i, &st);
	return st.enabled;
}

/* One drive's reading out of line: servo on's, called per drive (0.1 KiB
 * less flash than a second copy of the tick's), and where code size counts
 * the tick's as well (below). */
#ifdef __OPTIMIZE_SIZE__
#define SAMPLE_ONCE __attribute__((noinline))
#else
#define SAMPLE_ONCE COLD
#endif
static SAMPLE_ONCE bool sample_drive_once(vehicle_t *v, uint8_t i)
{
	return sample_drive(v, i);
}

/* Reads every drive; true when every one reports enabled. Inline in the
 * tick (a call and the loop's frame cost the cruise tick 20 instructions,
 * tools/bench/tickcost.sh), and a differential base's two drives without
 * the loop (10 more; a board built for one base has one form, naxes
 * being 2 or 4 by the kinematics). Where code size counts (a board) each
 * drive is one call to the one copy: the drives' supervision inlined per
 * drive took 0.45 KiB of flash more. */
static inline __attribute__((always_inline)) bool sample_drives(vehicle_t *v)
{
#ifdef __OPTIMIZE_SIZE__
	bool all_on = true;
	for (uint8_t i = 0; i < v->naxes; i++)
		all_on &= sample_drive_once(v, i);
	return all_on;
#else
	if (!vs_config_omni(&v->cfg)) {
		bool on0 = sample_drive(v, 0); /* both read, whatever drive 0 says */
		return sample_drive(v, 1) && on0;
	}
	bool all_on = true;
	for (uint8_t i = 0; i < 4; i++)
		all_on &= sample_drive(v, i);
	return all_on;
#endif
}

__attribute__((noinline)) void vehicle_sample_drives(vehicle_t *v)
{
	for (uint8_t i = 0; i < v->naxes; i++)
		(void)sample_drive_once(v, i);
}

/* "battery below N.N V" as a fault (critical) or a warning (low). */
static COLD void battery_report(vehicle_t *v, uint32_t code, uint32_t mv)
{
	char s[VS_ALARM_SOURCE_MAX];
	size_t pos = vehicle_put_str(s, sizeof s, 0, "battery below ");
	vehicle_put_volts(s, sizeof s, pos, mv);
	if (code == ALM_F_BATTERY_CRITICAL)
		vehicle_raise_fault_level(v, code, s);
	else
		alarm_raise(&v->alarms, code, s);
}

static void supervise_inputs(vehicle_t *v)
{
	const vs_hal_ops_t *o = v->hal.ops;
	void *c = v->hal.ctx;

	if (vs_config_estop(&v->cfg) && o->estop(c))
		vehicle_raise_fault_level(v, ALM_F_ESTOP, "emergency stop");

	if (v->powered && !o->power_feedback(c)) {
		v->powered = false;
		vehicle_raise_fault(v, ALM_F_POWER_LOST, "main power lost");
		/* Command the relay open as well: Unpowered means the circuit is
		 * off, and a contact that recloses by itself must not bring the
		 * drive supply back until setPower(true). */
		o->power_set(c, false);
	}

	v->battery_mv = o->battery_mv(c);
	if (v->battery_mv < v->battery_critical_mv)
		battery_report(v, ALM_F_BATTERY_CRITICAL, v->battery_critical_mv);
	/* Warn once per crossing; 0.1 V of hysteresis keeps noise from
	 * repeating it. */
	if (v->battery_low_armed && v->battery_mv < v->battery_low_mv) {
		v->battery_low_armed = false;
		battery_report(v, ALM_W_BATTERY_LOW, v->battery_low_mv);
	} else if (v->battery_mv >= v->battery_low_mv + 100u) {
		v->battery_low_armed = true;
	}

	/* Contact locks on its rising edge, so that after unlock the unit can
	 * back away while the bumper is still pressed. */
	if (vs_config_contact(&v->cfg)) {
		bool contact = o->contact(c);
		if (contact && !v->contact_prev && v->sensor_lock) {
			motion_stop(&v->motion);
			v->locked = true;
			alarm_raise(&v->alarms, ALM_W_CONTACT, "contact detected");
		}
		v->contact_prev = contact;
	}

	if (vs_config_obstacle(&v->cfg)) {
		bool obstacle = o->obstacle(c);
		if (obstacle && !v->obstacle_prev) {
			motion_stop(&v->motion);
			v->stuck = true;
			alarm_raise(&v->alarms, ALM_W_OBSTACLE, "obstacle detected");
		} else if (!obstacle) {
			v->stuck = false;
		}
		v->obstacle_prev = obstacle;

		bool caution = o->obstacle_caution(c);
		if (caution != v->caution_prev)
			motion_set_caution(&v->motion, caution ? v->caution_vel_t : 0);
		v->caution_prev = caution;
	}
}

static int16_t deadband(int16_t a, int32_t db)
{
	int32_t x = a;
	if (x > 32767)
		x = 32767;
	if (x < -32767)
		x = -32767;
	if (x <= db && x >= -db)
		return 0;
	/* Rescale so the output still spans the full range past the band. */
	int32_t mag = (x < 0 ? -x : x) - db;
	int32_t out = (int32_t)(((int64_t)mag * 32767) / (32767 - db));
	return (int16_t)(x < 0 ? -out : out);
}

static void feed_joystick(vehicle_t *v)
{
	if (!v->joystick_on)
		return;
	hal_joystick_t js = {{0, 0, 0}, false};
	if (vs_config_joystick(&v->cfg))
		v->hal.ops->joystick(v->hal.ctx, &js);
	if (!js.present) {
		/* Off for good: a joystick coming back must not move the unit. */
		motion_joystick_enable(&v->motion, false);
		motion_stop(&v->motion);
		v->joystick_on = false;
		alarm_raise(&v->alarms, ALM_W_JOYSTICK_LOST, "joystick lost");
		return;
	}
	int16_t x = 0, y = 0, r = 0;
	/* The stick drives only from neutral: after a stop, a pause, a fault,
	 * the servo off or the hand-over, a stick still held over does not
	 * drive the unit off again (it must come back first). */
	bool can = v->servo && !v->locked && !v->stuck && !motion_is_paused(&v->motion) &&
		   motion_mode(&v->motion) == MODE_JOYSTICK;
	if (can) {
		x = deadband(js.axis[0], v->joystick_deadband_q15);
		y = vs_config_omni(&v->cfg) ? deadband(js.axis[1], v->joystick_deadband_q15) : 0;
		r = deadband(js.axis[2], v->joystick_deadband_q15);
		if ((x | y | r) == 0)
			v->stick_armed = true;
	} else {
		v->stick_armed = false;
	}
	if (!v->stick_armed)
		x = y = r = 0;
	motion_joystick_input(&v->motion, x, y, r, true);
}

/* "<what> <n> counts": the worst wheel's distance from its reference. */
static COLD void counts_msg(char *s, const char *what, int64_t err_q32)
{
	int64_t n = err_q32 >> 32;
	size_t pos = vehicle_put_str(s, VS_ALARM_SOURCE_MAX, 0, what);
	pos = vehicle_put_dec(s, VS_ALARM_SOURCE_MAX, pos,
			      (uint32_t)(n > UINT32_MAX ? UINT32_MAX : n), 1);
	vehicle_put_str(s, VS_ALARM_SOURCE_MAX, pos, " counts");
}

static COLD void following_fault(vehicle_t *v, int64_t ferr)
{
	char s[VS_ALARM_SOURCE_MAX];
	counts_msg(s, "following error ", ferr);
	vehicle_raise_fault(v, ALM_F_FOLLOWING, s);
}

static COLD void settle_report(vehicle_t *v, int64_t ferr)
{
	char s[VS_ALARM_SOURCE_MAX];
	counts_msg(s, "not in position: ", ferr);
	alarm_raise(&v->alarms, ALM_W_NOT_IN_POSITION, s);
}

/* Pose-level hold at rest: the part of the pose error (the reference the
 * motion ended on minus the odometry, in the unit's frame) that the wheel
 * loop will not remove by itself, i.e. beyond what its wheels still have to
 * travel, goes into the wheel references (kin.h). Wheels that reach their
 * counts by another path than they left them (a push that turned and slid
 * the base, the last corner of a route) leave such a remainder, since the
 * pose depends on the path. A differential base cannot move sideways: its
 * remainder across the heading stays (it shows in getPosition). Runs on the
 * ticks at rest in which a wheel moved, so it costs a moving tick nothing. */
static void hold_pose(vehicle_t *v)
{
	const fx_pose_t *r = motion_ref_pose(&v->motion);
	q32_t ex = r->x_mm - v->odom.x_mm, ey = r->y_mm - v->odom.y_mm;
	int32_t s, c;
	fx_twist_t d, e;
	fx_sincos_bam(fx_deg_to_bam(v->odom.th_deg), &s, &c);
	kin_pending(&v->kin, &d);
	e.vx_pt = fx_mul_q30(ex, c) + fx_mul_q30(ey, s) - d.vx_pt;
	e.vy_pt = vs_config_omni(&v->cfg) ? fx_mul_q30(ey, c) - fx_mul_q30(ex, s) - d.vy_pt : 0;
	e.w_pt = fx_wrap_deg(r->th_deg - v->odom.th_deg) - d.w_pt;
	kin_offset(&v->kin, &e);
}

/* In position (CiA 402's position window and window time): the reference
 * at rest and every wheel within the window of it for the window time.
 * Once there, the motion is done until the next one: a wheel the hold
 * brings back into the window afterwards (a push, a creep) does not make
 * the unit Busy again, so a host that saw Ready is not refused.
 * Until then the motion is not done: the unit stays Busy, and Paused,
 * Locked and Stuck wait for it too. A unit that does not get there within
 * settle_timeout_ms raises warning 154 once and is taken as done (it holds
 * where it is). */
static void supervise_position(vehicle_t *v, int64_t ferr, const fx_twist_t *moved)
{
	/* The reference moved this tick (the command is its step; zero with
	 * the servo off). */
	if ((v->cmd.vx_pt | v->cmd.vy_pt | v->cmd.w_pt) != 0) {
		v->inpos_ticks = 0;
		v->settle_ticks = 0;
		return;
	}
	if (!v->servo) {
		/* Nothing to hold; servo on starts from the measured counts, in
		 * position. */
		v->inpos_ticks = v->window_ticks;
		v->settle_ticks = 0;
		return;
	}
	/* At rest, a wheel moved: the pose may have left its hold. */
	if ((moved->vx_pt | moved->vy_pt | moved->w_pt) != 0)
		hold_pose(v);
	if (ferr <= v->window_q32) {
		/* Taken as done at the settle timeout (154): it stays done
		 * when the wheels come into the window after all. */
		if (v->settle_ticks > v->settle_timeout_ticks)
			v->inpos_ticks = v->window_ticks;
		v->settle_ticks = 0;
		if (v->inpos_ticks < v->window_ticks)
			v->inpos_ticks++;
	} else if (v->inpos_ticks < v->window_ticks) {
		v->inpos_ticks = 0;
		if (v->settle_ticks <= v->settle_timeout_ticks &&
		    ++v->settle_ticks > v->settle_timeout_ticks)
			settle_report(v, ferr);
	}
}

/* The position hold is motion too. At rest every wheel's setpoint stays
 * within the speed in force (set velocity, caution cap). A wheel pushed
 * more than a millimetre off its reference is brought back as a move, not
 * as a step to the loop gain times the error: within what it can brake
 * from inside the error, its magnitude rising by at most the set
 * acceleration a tick. Settling after a move is otherwise left as it is. */
static void bound_hold(vehicle_t *v, const int32_t prev[])
{
	int64_t hz = v->cfg.tick_hz;
	q32_t cpm = v->kin.p.counts_per_mm;
	int64_t far = cpm; /* 1 mm in counts, Q32 */
	/* Plain comparisons: the fx helpers are out of line on a board, a
	 * copy per file. */
	/* The speed in force bounds every wheel at rest (a set velocity below
	 * what the loop settles at included). */
	int64_t cap = (fx_mul(motion_speed_cap(&v->motion), cpm) * hz) >> 24;
	for (uint8_t i = 0; i < v->naxes; i++) {
		int64_t err = v->kin.ref_counts_q32[i];
		if (err < 0)
			err = -err;
		int64_t b = cap;
		if (err > far) {
			q32_t a_pt2 = fx_mul(motion_accel_set(&v->motion), cpm); /* counts/tick^2 */
			int64_t step = ((a_pt2 * hz) >> 24) + 1;
			int64_t u = (traj_umax(err, a_pt2) * hz) >> 24;
			int64_t p = prev[i] < 0 ? -(int64_t)prev[i] : prev[i];
			if (u < b)
				b = u;
			if (p + step < b)
				b = p + step;
		}
		int32_t o = v->wheel_cps_q8[i];
		v->wheel_cps_q8[i] = (int32_t)(o > b ? b : o < -b ? -b : o);
	}
}

bool vehicle_in_position(const vehicle_t *v)
{
	if (vehicle_servo_waiting(v))
		return false;
	return !v->servo || v->inpos_ticks >= v->window_ticks ||
	       v->settle_ticks > v->settle_timeout_ticks;
}

/* The state's code and the alarm it names (NULL: none). */
static int16_t state_code(const vehicle_t *v, const vs_alarm_t **why)
{
	const vs_alarm_t *fault = alarm_newest(&v->alarms, VS_ALARM_FAULT);
	/* Braking for a lock, an obstacle or a pause, or settling, the unit is
	 * Busy: the state that follows is reported once the wheels are in
	 * place. */
	bool settled = vehicle_servo_waiting(v) || vehicle_in_position(v);
	*why = fault;
	if (fault)
		return VS_STATE_ALARM;
	if (!v->powered)
		return VS_STATE_UNPOWERED;
	if (settled && v->locked)
		return VS_STATE_LOCKED;
	if (settled && v->stuck)
		return VS_STATE_STUCK;
	if (!v->servo)
		return VS_STATE_POWERED;
	if (settled && motion_is_paused(&v->motion))
		return VS_STATE_PAUSED;
	if (!settled || vehicle_servo_waiting(v) || motion_has_work(&v->motion))
		return VS_STATE_BUSY;
	*why = alarm_newest(&v->alarms, VS_ALARM_WARNING);
	return *why ? VS_STATE_WARNING : VS_STATE_READY;
}

/* The state's code, its word and the alarm it names (NULL: none). The
 * words from one table by code (VS_STATE_READY up): a store of a literal
 * per state cost more flash. */
int16_t vehicle_state_of(const vehicle_t *v, const char **word, const vs_alarm_t **why)
{
	static const char *const words[] = {"Ready",  "Busy",  "Warning", "Alarm",   "Stuck",
					    "Paused", "Avoid", "Locked",  "Powered", "Unpowered"};
	_Static_assert(sizeof words / sizeof words[0] == VS_STATE_UNPOWERED - VS_STATE_READY + 1,
		       "a word for each state");
	int16_t code = state_code(v, why);
	*word = words[code - VS_STATE_READY];
	return code;
}

/* The tick's sample for the black box (vehicle_tick, when one is due). */
/* Out of line: make bench counts it apart (tools/bench/tickcost.sh). */
__attribute__((noinline)) void vehicle_bbox_record(vehicle_t *v)
{
	bbox_sample_t *s = bbox_slot(&v->bbox);
	const char *word;
	const vs_alarm_t *why;

	s->ref = *motion_ref_pose(&v->motion);
	s->odo = v->odom;
	s->cmd = v->cmd;
	for (unsigned i = 0; i < VS_MAX_AXES; i++) {
		s->sp_q8[i] = v->wheel_cps_q8[i];
		s->enc[i] = v->meas_counts[i];
	}
	s->tick = v->ticks;
	s->newest_alarm = v->alarms.n ? v->alarms.a[0].code : 0u;
	s->state = vehicle_state_of(v, &word, &why);
	s->queue_len = motion_queue_len(&v->motion);
	s->alarms = (uint8_t)v->alarms.n;
	bbox_commit(&v->bbox);
}

void vehicle_tick(vehicle_t *v, uint32_t now_us)
{
	check_lateness(v, now_us);
	bool all_on = sample_drives(v);
	supervise_inputs(v);
	/* After the inputs: a relay that opened is a power fault, not a drive
	 * that left Operation enabled. */
	if (VS_DRIVE_STATES && v->servo && (!all_on || v->servo_wait))
		supervise_enable(v);
	supervise_link(v);
	feed_joystick(v);

	fx_twist_t cmd;
	/* At rest the reference stays where the motion ended and the wheel
	 * loop holds the unit there: one owner of where the unit is. Only with
	 * the servo off (wheels free) does it follow the odometry. */
	/* While the servo comes on the motion waits (nothing to drive yet). */
	bool drive = v->servo && !vehicle_servo_waiting(v);
	if (drive) {
		motion_tick(&v->motion, NULL, &cmd);
	} else {
		/* Nothing may move with the servo off; the odometry still
		 * follows wheels pushed by hand. */
		if (!v->servo)
			motion_tick(&v->motion, &v->odom, &cmd);
		cmd = (fx_twist_t){0, 0, 0};
	}
	v->cmd = cmd;

	fx_twist_t delta;
	int64_t ferr;
	/* At rest the hold is bounded from the setpoints of the tick before. */
	bool hold = v->servo && (cmd.vx_pt | cmd.vy_pt | cmd.w_pt) == 0;
	int32_t prev[VS_MAX_AXES];
	if (hold)
		for (uint8_t i = 0; i < v->naxes; i++)
			prev[i] = v->wheel_cps_q8[i];
	kin_step(&v->kin, &cmd, v->meas_counts, v->wheel_cps_q8, &delta, &ferr);
	if (hold)
		bound_hold(v, prev);
	odom_integrate(&v->odom, &delta, &v->odom_trig);
	v->meas = delta;

	if (v->servo && ferr > v->following_err_max_q32)
		following_fault(v, ferr);
	supervise_position(v, ferr, &delta);

	if (!drive)
		for (uint8_t i = 0; i < v->naxes; i++)
			v->wheel_cps_q8[i] = 0;
	/* A differential base's two setpoints without the loop (6
	 * instructions a tick). */
	const vs_hal_ops_t *o = v->hal.ops;
	void *c = v->hal.ctx;
	if (!vs_config_omni(&v->cfg)) {
		int32_t w1 = v->wheel_cps_q8[1];
		o->drive_set_velocity(c, 0, v->wheel_cps_q8[0]);
		o->drive_set_velocity(c, 1, w1);
	} else {
		for (uint8_t i = 0; i < 4; i++)
			o->drive_set_velocity(c, i, v->wheel_cps_q8[i]);
	}
	v->ticks++;
	/* Recorded here, out of the motion tick: its cost is bbox's line in
	 * make bench. */
	if (bbox_due(&v->bbox))
		vehicle_bbox_record(v);
}
