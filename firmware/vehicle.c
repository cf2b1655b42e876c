/* VehicleService core: unit state, refusal rules, supervision and the
 * control tick. Integer only; the double-facing operations and init live in
 * vs_api.c.
 *
 * State precedence (getState, and the order of the refusal checks):
 *   fault > power off > locked > stuck > servo off > paused > busy > warning > ready
 */
#include <stddef.h>
#include <stdint.h>

#include "vehicle.h"

/* ---- tiny string helpers (no libc) ------------------------------------ */

static size_t put_str(char *b, size_t cap, size_t pos, const char *s)
{
	while (*s != '\0' && pos + 1 < cap)
		b[pos++] = *s++;
	if (pos < cap)
		b[pos] = '\0';
	return pos;
}

/* Decimal, at least min_digits (zero padded). */
static size_t put_dec(char *b, size_t cap, size_t pos, uint32_t val, unsigned min_digits)
{
	char t[10];
	unsigned n = 0;
	do {
		t[n++] = (char)('0' + val % 10u);
		val /= 10u;
	} while (val != 0 && n < sizeof t);
	while (n < min_digits && n < sizeof t)
		t[n++] = '0';
	while (n > 0 && pos + 1 < cap)
		b[pos++] = t[--n];
	if (pos < cap)
		b[pos] = '\0';
	return pos;
}

static size_t put_hex4(char *b, size_t cap, size_t pos, uint16_t val)
{
	static const char hex[] = "0123456789ABCDEF";
	pos = put_str(b, cap, pos, "0x");
	for (int sh = 12; sh >= 0; sh -= 4) {
		if (pos + 1 < cap)
			b[pos++] = hex[((unsigned)val >> (unsigned)sh) & 0xFu];
	}
	if (pos < cap)
		b[pos] = '\0';
	return pos;
}

/* Volts with one decimal from millivolts: 22000 -> "22.0". */
static size_t put_volts(char *b, size_t cap, size_t pos, uint32_t mv)
{
	uint32_t dv = (mv + 50u) / 100u;
	pos = put_dec(b, cap, pos, dv / 10u, 1);
	pos = put_str(b, cap, pos, ".");
	pos = put_dec(b, cap, pos, dv % 10u, 1);
	return put_str(b, cap, pos, " V");
}

/* ---- alarms ----------------------------------------------------------- */

static const char *refusal_reason(uint32_t code)
{
	switch (code) {
	case ALM_W_BAD_ARGUMENT:
		return "invalid argument";
	case ALM_W_OVER_LIMIT:
		return "out of limits";
	case ALM_W_KINEMATICS:
		return "not possible on this base";
	case ALM_W_NOT_READY:
		return "unit not ready";
	case ALM_W_SERVO_OFF:
		return "servo off";
	case ALM_W_MOVING:
		return "unit moving";
	case ALM_W_FAULT_ACTIVE:
		return "fault active";
	case ALM_W_LOCKED:
		return "unit locked";
	case ALM_W_QUEUE_FULL:
		return "queue full";
	case ALM_W_BAD_IOID:
		return "no such io id";
	case ALM_W_BAD_AXIS:
		return "no such axis";
	case ALM_W_POWER_OFF:
		return "power off";
	case ALM_W_PAUSED:
		return "unit paused";
	case ALM_W_STUCK:
		return "unit stuck";
	case ALM_W_JOYSTICK:
		return "joystick in use";
	default:
		return "refused";
	}
}

static bool refuse_text(vehicle_t *v, const char *op, uint32_t code, const char *reason)
{
	char s[VS_ALARM_SOURCE_MAX];
	size_t pos = put_str(s, sizeof s, 0, op);
	pos = put_str(s, sizeof s, pos, " refused: ");
	put_str(s, sizeof s, pos, reason);
	alarm_raise(&v->alarms, code, s);
	return false;
}

bool vehicle_refuse(vehicle_t *v, const char *op, uint32_t code)
{
	return refuse_text(v, op, code, refusal_reason(code));
}

static bool fault_active(const vehicle_t *v)
{
	return alarm_any_fault(&v->alarms);
}

static void servo_off(vehicle_t *v)
{
	for (uint8_t i = 0; i < v->naxes; i++) {
		v->hal.ops->drive_enable(v->hal.ctx, i, false);
		v->drive[i].enabled = false;
		v->wheel_cps_q8[i] = 0;
	}
	v->servo = false;
}

/* Every fault: drop the motion at once and switch the servo off (spec 6.9). */
static void raise_fault(vehicle_t *v, uint32_t code, const char *text)
{
	alarm_raise(&v->alarms, code, text);
	motion_halt(&v->motion);
	servo_off(v);
}

/* A condition that persists (e-stop held, battery critical): raised once
 * while its code is active, and again after clearAlarm if still present. */
static void raise_fault_level(vehicle_t *v, uint32_t code, const char *text)
{
	for (unsigned i = 0; i < v->alarms.n; i++) {
		if (v->alarms.a[i].code == code)
			return;
	}
	raise_fault(v, code, text);
}

static void axis_text(char *s, size_t cap, const char *what, uint8_t axis, const char *tail)
{
	size_t pos = put_str(s, cap, 0, what);
	pos = put_dec(s, cap, pos, axis, 1);
	put_str(s, cap, pos, tail);
}

/* ---- refusal rules for move* ------------------------------------------ */

bool vehicle_move_gate(vehicle_t *v, const char *op, vehicle_gate_t gate)
{
	if (fault_active(v))
		return vehicle_refuse(v, op, ALM_W_FAULT_ACTIVE);
	if (!v->powered)
		return vehicle_refuse(v, op, ALM_W_SERVO_OFF);
	if (v->locked)
		return vehicle_refuse(v, op, ALM_W_LOCKED);
	if (v->stuck)
		return vehicle_refuse(v, op, ALM_W_STUCK);
	if (!v->servo)
		return vehicle_refuse(v, op, ALM_W_SERVO_OFF);
	if (v->joystick_on)
		return vehicle_refuse(v, op, ALM_W_JOYSTICK);
	if (gate == VEHICLE_GATE_READY && (motion_is_paused(&v->motion) ||
					   motion_has_work(&v->motion) || !vehicle_in_position(v)))
		return vehicle_refuse(v, op, ALM_W_NOT_READY);
	/* A velocity command cannot be deferred until resume. */
	if (gate == VEHICLE_GATE_JOG && motion_is_paused(&v->motion))
		return vehicle_refuse(v, op, ALM_W_PAUSED);
	return true;
}

bool vehicle_motion_refused(vehicle_t *v, const char *op, bool velocity_mode)
{
	uint8_t mode = motion_mode(&v->motion);
	if (velocity_mode) {
		if (mode == MODE_PATH || motion_queue_len(&v->motion) > 0)
			return vehicle_refuse(v, op, ALM_W_MOVING);
		return vehicle_refuse(v, op, ALM_W_KINEMATICS);
	}
	if (motion_queue_len(&v->motion) >= MOTION_QUEUE_LEN)
		return vehicle_refuse(v, op, ALM_W_QUEUE_FULL);
	if (mode == MODE_JOG || mode == MODE_CONTINUOUS || mode == MODE_JOYSTICK)
		return vehicle_refuse(v, op, ALM_W_MOVING);
	return vehicle_refuse(v, op, ALM_W_KINEMATICS);
}

/* ---- operations without doubles --------------------------------------- */

bool vs_clearAlarm(vehicle_t *v)
{
	alarm_clear(&v->alarms);
	for (uint8_t i = 0; i < v->naxes; i++) {
		v->hal.ops->drive_reset_fault(v->hal.ctx, i);
		v->drive_fault_reported[i] = 0;
		v->drive_timeout_reported[i] = false;
	}
	return true;
}

bool vs_getActiveAlarm(vehicle_t *v, int16_t numOfAlarm, int16_t *numOfActiveAlarm,
		       vs_alarm_t *activeAlarms, uint16_t *len)
{
	uint16_t n = 0;
	if (numOfAlarm > 0 && activeAlarms) {
		uint16_t want = (uint16_t)numOfAlarm;
		while (n < want && n < v->alarms.n) {
			activeAlarms[n] = v->alarms.a[n];
			n++;
		}
	}
	if (numOfActiveAlarm)
		*numOfActiveAlarm = (int16_t)v->alarms.n;
	if (len)
		*len = n;
	return true;
}

bool vs_getIFVersion(vehicle_t *v, const char **version)
{
	(void)v;
	*version = VS_IF_VERSION;
	return true;
}

bool vs_getVersion(vehicle_t *v, const char **ver)
{
	*ver = v->cfg.firmware_version ? v->cfg.firmware_version : VS_FW_VERSION;
	return true;
}

static const vs_io_def_t *find_io(const vehicle_t *v, uint32_t ioid, unsigned *index)
{
	if (ioid == 0)
		return NULL;
	for (unsigned i = 0; i < v->cfg.num_io; i++) {
		if (v->cfg.io[i].id == ioid) {
			*index = i;
			return &v->cfg.io[i];
		}
	}
	return NULL;
}

static uint32_t width_mask(uint8_t width)
{
	return width >= 32 ? UINT32_MAX : ((uint32_t)1 << width) - 1u;
}

bool vs_getInput(vehicle_t *v, uint32_t ioid, uint32_t *input)
{
	unsigned idx = 0;
	const vs_io_def_t *d = find_io(v, ioid, &idx);
	uint32_t val = 0;
	if (!d || d->dir != VS_IO_IN || !v->hal.ops->io_read(v->hal.ctx, ioid, &val))
		return vehicle_refuse(v, "getInput", ALM_W_BAD_IOID);
	*input = val & width_mask(d->width);
	return true;
}

bool vs_setOutput(vehicle_t *v, uint32_t ioid, uint32_t output, uint32_t mask)
{
	if (ioid == 0)
		return refuse_text(v, "setOutput", ALM_W_BAD_IOID, "io id 0 reserved");
	unsigned idx = 0;
	const vs_io_def_t *d = find_io(v, ioid, &idx);
	if (!d || d->dir != VS_IO_OUT)
		return vehicle_refuse(v, "setOutput", ALM_W_BAD_IOID);
	uint32_t val = ((v->out_shadow[idx] & ~mask) | (output & mask)) & width_mask(d->width);
	/* The shadow only takes values that reached the backend. */
	if (!v->hal.ops->io_write(v->hal.ctx, ioid, val))
		return vehicle_refuse(v, "setOutput", ALM_W_BAD_IOID);
	v->out_shadow[idx] = val;
	return true;
}

bool vs_getServoStatus(vehicle_t *v, uint32_t axisid, bool *status)
{
	if (axisid >= v->naxes)
		return vehicle_refuse(v, "getServoStatus", ALM_W_BAD_AXIS);
	*status = v->drive[axisid].enabled;
	return true;
}

static void state_msg(char *b, const char *word, const vs_alarm_t *a)
{
	size_t pos = put_str(b, VS_STATE_MSG_MAX, 0, word);
	if (a) {
		pos = put_str(b, VS_STATE_MSG_MAX, pos, "-");
		put_dec(b, VS_STATE_MSG_MAX, pos, a->code, 3);
	}
}

bool vs_getState(vehicle_t *v, int16_t *state, char msg[VS_STATE_MSG_MAX])
{
	const vs_alarm_t *fault = alarm_newest(&v->alarms, VS_ALARM_FAULT);
	const vs_alarm_t *warn = alarm_newest(&v->alarms, VS_ALARM_WARNING);
	/* Braking for a lock, an obstacle or a pause, or settling, the unit is
	 * Busy: the state that follows is reported once the wheels are in
	 * place. */
	bool settled = vehicle_in_position(v);
	int16_t code;
	if (fault) {
		code = VS_STATE_ALARM;
		state_msg(v->state_msg, "Alarm", fault);
	} else if (!v->powered) {
		code = VS_STATE_UNPOWERED;
		state_msg(v->state_msg, "Unpowered", NULL);
	} else if (settled && v->locked) {
		code = VS_STATE_LOCKED;
		state_msg(v->state_msg, "Locked", NULL);
	} else if (settled && v->stuck) {
		code = VS_STATE_STUCK;
		state_msg(v->state_msg, "Stuck", NULL);
	} else if (!v->servo) {
		code = VS_STATE_POWERED;
		state_msg(v->state_msg, "Powered", NULL);
	} else if (settled && motion_is_paused(&v->motion)) {
		code = VS_STATE_PAUSED;
		state_msg(v->state_msg, "Paused", NULL);
	} else if (!settled || motion_has_work(&v->motion)) {
		code = VS_STATE_BUSY;
		state_msg(v->state_msg, "Busy", NULL);
	} else if (warn) {
		code = VS_STATE_WARNING;
		state_msg(v->state_msg, "Warning", warn);
	} else {
		code = VS_STATE_READY;
		state_msg(v->state_msg, "Ready", NULL);
	}
	*state = code;
	put_str(msg, VS_STATE_MSG_MAX, 0, v->state_msg);
	return true;
}

bool vs_pause(vehicle_t *v)
{
	motion_pause(&v->motion);
	return true;
}

bool vs_resume(vehicle_t *v)
{
	motion_resume(&v->motion);
	return true;
}

bool vs_stop(vehicle_t *v)
{
	motion_stop(&v->motion);
	return true;
}

bool vs_unlock(vehicle_t *v)
{
	v->locked = false;
	return true;
}

bool vs_setDigitalSensorLock(vehicle_t *v, bool OnOff)
{
	v->sensor_lock = OnOff;
	return true;
}

bool vs_setJogTimeout(vehicle_t *v, int16_t timeout)
{
	if (timeout <= 0)
		return vehicle_refuse(v, "setJogTimeout", ALM_W_OVER_LIMIT);
	motion_set_jog_timeout_ms(&v->motion, (uint32_t)timeout);
	v->jog_timeout_ms = timeout;
	return true;
}

bool vs_setJoystick(vehicle_t *v, bool OnOff)
{
	if (OnOff != v->joystick_on)
		motion_joystick_enable(&v->motion, OnOff);
	v->joystick_on = OnOff;
	return true;
}

bool vs_setPower(vehicle_t *v, bool OnOff)
{
	const vs_hal_ops_t *o = v->hal.ops;
	if (!OnOff) {
		motion_halt(&v->motion);
		servo_off(v);
		o->power_set(v->hal.ctx, false);
		v->powered = false;
		return true;
	}
	if (v->powered)
		return true;
	bool ok = o->power_set(v->hal.ctx, true);
	/* power_set may wait for the relay to settle (hal.h, at most 50 ms);
	 * where commands run between ticks on the loop's thread that wait
	 * delays the next tick. Nothing moves while unpowered, so the overrun
	 * check restarts from the next tick instead of calling it late. */
	v->have_now = false;
	if (!ok || !o->power_feedback(v->hal.ctx)) {
		/* Leave the relay commanded open rather than half-known. */
		o->power_set(v->hal.ctx, false);
		raise_fault(v, ALM_F_POWER_ON, "main relay did not close");
		return false;
	}
	v->powered = true;
	for (uint8_t i = 0; i < v->naxes; i++)
		v->drive_silent_ticks[i] = 0;
	return true;
}

/* Table 8 of the source. "Alarm" there is a fault: warnings never block. */
bool vs_setServo(vehicle_t *v, bool OnOff)
{
	if (!v->powered)
		return vehicle_refuse(v, "setServo", ALM_W_POWER_OFF);
	if (!OnOff) {
		if (v->servo)
			motion_halt(&v->motion);
		servo_off(v);
		return true;
	}
	if (v->servo)
		return true;
	if (fault_active(v))
		return vehicle_refuse(v, "setServo", ALM_W_FAULT_ACTIVE);
	/* Wheel references start at the measured counts: no jump. */
	kin_sync(&v->kin, v->meas_counts);
	for (uint8_t i = 0; i < v->naxes; i++) {
		v->hal.ops->drive_enable(v->hal.ctx, i, true);
		v->drive[i].enabled = true;
		v->encoder_still_ticks[i] = 0;
	}
	v->servo = true;
	return true;
}

void vehicle_diag(const vehicle_t *v, vs_diag_t *d)
{
	d->ref_pose = *motion_ref_pose(&v->motion);
	d->odom_pose = v->odom;
	d->cmd_twist_pt = v->cmd;
	for (unsigned i = 0; i < VS_MAX_AXES; i++)
		d->wheel_cps_q8[i] = v->wheel_cps_q8[i];
	d->ticks = v->ticks;
	d->overruns = v->overruns;
	d->late_ticks = v->late_ticks;
	d->max_late_us = v->max_late_us;
	d->queue_len = motion_queue_len(&v->motion);
	d->mode = motion_mode(&v->motion);
}

/* ---- the control tick ------------------------------------------------- */

/* Reports are out of line (cold): their text buffers and calls stay off
 * the every-tick path. */
#define COLD __attribute__((cold, noinline))

static COLD void loop_stalled(vehicle_t *v, uint32_t late_us)
{
	char s[VS_ALARM_SOURCE_MAX];
	size_t pos = put_str(s, sizeof s, 0, "control loop stalled ");
	pos = put_dec(s, sizeof s, pos, late_us / 1000u, 1);
	put_str(s, sizeof s, pos, " ms");
	raise_fault(v, ALM_F_LOOP_STALL, s);
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
		raise_fault(v, ALM_F_OVERRUN, "control tick overrun");
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

void vehicle_set_link_timeout(vehicle_t *v, uint32_t ms)
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
	size_t pos = put_str(s, sizeof s, 0, "link lost: ");
	pos = put_str(s, sizeof s, pos, names[v->link_last < 3 ? v->link_last : 0]);
	pos = put_str(s, sizeof s, pos, " silent ");
	pos = put_dec(s, sizeof s, pos, v->cfg.link_timeout_ms, 1);
	put_str(s, sizeof s, pos, " ms");
	motion_stop(&v->motion);
	alarm_raise(&v->alarms, ALM_W_LINK_LOST, s);
}

/* Link watchdog: motion commanded from a host stops when the host falls
 * silent. The joystick drives locally and a paused unit holds still, so
 * neither needs the host; the stop discards the queue and nothing resumes
 * by itself. */
static void supervise_link(vehicle_t *v)
{
	if (v->link_silent_ticks < UINT32_MAX)
		v->link_silent_ticks++;
	if (v->link_timeout_ticks == 0 || v->link_silent_ticks < v->link_timeout_ticks)
		return;
	if (v->joystick_on || motion_is_paused(&v->motion) || !motion_has_work(&v->motion))
		return;
	v->link_silent_ticks = 0;
	link_lost(v);
}

static void encoder_stuck(vehicle_t *v, uint8_t i)
{
	char s[VS_ALARM_SOURCE_MAX];
	v->encoder_still_ticks[i] = 0;
	axis_text(s, sizeof s, "encoder ", i, " stuck");
	raise_fault(v, ALM_F_ENCODER_STUCK, s);
}

/* Encoder supervision, in the same pass as the drive sample: a wheel
 * commanded above the stuck threshold whose count did not change. */
static inline void supervise_encoder(vehicle_t *v, uint8_t i, bool moved)
{
	int32_t cps = v->wheel_cps_q8[i];
	bool commanded =
	    v->servo && (cps >= v->encoder_stuck_cps_q8 || cps <= -v->encoder_stuck_cps_q8);
	if (!commanded || moved)
		v->encoder_still_ticks[i] = 0;
	else if (++v->encoder_still_ticks[i] >= v->encoder_stuck_ticks)
		encoder_stuck(v, i);
}

static COLD void drive_silent_report(vehicle_t *v, uint8_t i)
{
	char s[VS_ALARM_SOURCE_MAX];
	v->drive_timeout_reported[i] = true;
	axis_text(s, sizeof s, "drive ", i, " not answering");
	raise_fault(v, ALM_F_DRIVE_TIMEOUT, s);
}

static COLD void drive_fault_report(vehicle_t *v, uint8_t i, uint16_t fc)
{
	char s[VS_ALARM_SOURCE_MAX];
	size_t pos = put_str(s, sizeof s, 0, "drive ");
	pos = put_dec(s, sizeof s, pos, i, 1);
	pos = put_str(s, sizeof s, pos, " fault ");
	put_hex4(s, sizeof s, pos, fc);
	raise_fault(v, ALM_F_DRIVE, s);
}

static void sample_drives(vehicle_t *v)
{
	/* Each drive's condition is reported once per occurrence (and again
	 * after clearAlarm while it persists), so two faulted drives do not
	 * take turns at the front of the list every tick. */
	for (uint8_t i = 0; i < v->naxes; i++) {
		hal_drive_state_t st = {0};
		v->hal.ops->drive_read(v->hal.ctx, i, &st);
		if (!st.fresh) {
			if (v->powered && v->drive_silent_ticks[i] < UINT32_MAX)
				v->drive_silent_ticks[i]++;
			if (v->powered && v->drive_silent_ticks[i] > v->drive_timeout_ticks &&
			    !v->drive_timeout_reported[i])
				drive_silent_report(v, i);
			supervise_encoder(v, i, false);
			continue;
		}
		v->drive_silent_ticks[i] = 0;
		v->drive_timeout_reported[i] = false;
		v->drive[i] = st;
		supervise_encoder(v, i, st.position_counts != v->meas_counts[i]);
		v->meas_counts[i] = st.position_counts;
		uint16_t fc = v->powered ? st.fault_code : 0;
		if (fc != 0 && fc != v->drive_fault_reported[i])
			drive_fault_report(v, i, fc);
		v->drive_fault_reported[i] = fc;
	}
}

/* "battery below N.N V" as a fault (critical) or a warning (low). */
static COLD void battery_report(vehicle_t *v, uint32_t code, uint32_t mv)
{
	char s[VS_ALARM_SOURCE_MAX];
	size_t pos = put_str(s, sizeof s, 0, "battery below ");
	put_volts(s, sizeof s, pos, mv);
	if (code == ALM_F_BATTERY_CRITICAL)
		raise_fault_level(v, code, s);
	else
		alarm_raise(&v->alarms, code, s);
}

static void supervise_inputs(vehicle_t *v)
{
	const vs_hal_ops_t *o = v->hal.ops;
	void *c = v->hal.ctx;

	if (v->cfg.has_estop && o->estop(c))
		raise_fault_level(v, ALM_F_ESTOP, "emergency stop");

	if (v->powered && !o->power_feedback(c)) {
		v->powered = false;
		raise_fault(v, ALM_F_POWER_LOST, "main power lost");
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
	if (v->cfg.has_contact_sensor) {
		bool contact = o->contact(c);
		if (contact && !v->contact_prev && v->sensor_lock) {
			motion_stop(&v->motion);
			v->locked = true;
			alarm_raise(&v->alarms, ALM_W_CONTACT, "contact detected");
		}
		v->contact_prev = contact;
	}

	if (v->cfg.has_obstacle_input) {
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
	if (v->cfg.has_joystick)
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
	if (v->servo && !v->locked && !v->stuck) {
		x = deadband(js.axis[0], v->joystick_deadband_q15);
		y = v->cfg.kinematics == VS_KIN_OMNI
			? deadband(js.axis[1], v->joystick_deadband_q15)
			: 0;
		r = deadband(js.axis[2], v->joystick_deadband_q15);
	}
	motion_joystick_input(&v->motion, x, y, r, true);
}

/* "<what> <n> counts": the worst wheel's distance from its reference. */
static COLD void counts_msg(char *s, const char *what, int64_t err_q32)
{
	int64_t n = err_q32 >> 32;
	size_t pos = put_str(s, VS_ALARM_SOURCE_MAX, 0, what);
	pos = put_dec(s, VS_ALARM_SOURCE_MAX, pos, (uint32_t)(n > UINT32_MAX ? UINT32_MAX : n), 1);
	put_str(s, VS_ALARM_SOURCE_MAX, pos, " counts");
}

static COLD void following_fault(vehicle_t *v, int64_t ferr)
{
	char s[VS_ALARM_SOURCE_MAX];
	counts_msg(s, "following error ", ferr);
	raise_fault(v, ALM_F_FOLLOWING, s);
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
	e.vy_pt =
	    v->cfg.kinematics == VS_KIN_OMNI ? fx_mul_q30(ey, c) - fx_mul_q30(ex, s) - d.vy_pt : 0;
	e.w_pt = fx_wrap_deg(r->th_deg - v->odom.th_deg) - d.w_pt;
	kin_offset(&v->kin, &e);
}

/* In position (CiA 402's position window and window time): the reference
 * at rest and every wheel within the window of it for the window time.
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
		v->settle_ticks = 0;
		if (v->inpos_ticks < v->window_ticks)
			v->inpos_ticks++;
	} else {
		v->inpos_ticks = 0;
		if (v->settle_ticks <= v->settle_timeout_ticks &&
		    ++v->settle_ticks > v->settle_timeout_ticks)
			settle_report(v, ferr);
	}
}

bool vehicle_in_position(const vehicle_t *v)
{
	return !v->servo || v->inpos_ticks >= v->window_ticks ||
	       v->settle_ticks > v->settle_timeout_ticks;
}

void vehicle_tick(vehicle_t *v, uint32_t now_us)
{
	check_lateness(v, now_us);
	sample_drives(v);
	supervise_inputs(v);
	supervise_link(v);
	feed_joystick(v);

	fx_twist_t cmd;
	/* At rest the reference stays where the motion ended and the wheel
	 * loop holds the unit there: one owner of where the unit is. Only with
	 * the servo off (wheels free) does it follow the odometry. */
	motion_tick(&v->motion, v->servo ? NULL : &v->odom, &cmd);
	if (!v->servo) {
		/* Nothing may move with the servo off; the odometry still
		 * follows wheels pushed by hand. */
		cmd = (fx_twist_t){0, 0, 0};
	}
	v->cmd = cmd;

	fx_twist_t delta;
	int64_t ferr;
	kin_step(&v->kin, &cmd, v->meas_counts, v->wheel_cps_q8, &delta, &ferr);
	odom_integrate(&v->odom, &delta, &v->odom_trig);

	if (v->servo && ferr > v->following_err_max_q32)
		following_fault(v, ferr);
	supervise_position(v, ferr, &delta);

	if (!v->servo)
		for (uint8_t i = 0; i < v->naxes; i++)
			v->wheel_cps_q8[i] = 0;
	for (uint8_t i = 0; i < v->naxes; i++)
		v->hal.ops->drive_set_velocity(v->hal.ctx, i, v->wheel_cps_q8[i]);
	v->ticks++;
}
