/* VehicleService core: unit state, refusal rules and the operations without
 * doubles. Integer only; the double-facing operations and init live in
 * vs_api.c, the control tick and its supervision in vehicle_tick.c, the
 * alarm texts and raising a fault in vehicle_fault.c.
 *
 * State precedence (getState, and the order of the refusal checks):
 *   fault > power off > locked > stuck > servo off > paused > busy > warning > ready
 */
#include <stddef.h>
#include <stdint.h>

#include "vehicle_priv.h"

/* ---- alarms ----------------------------------------------------------- */

/* The refusals' texts by code from ALM_W_BAD_ARGUMENT on, one after
 * another (empty: the code is no refusal): a walk over one string where a
 * comparison and a literal per code took 0.1 KiB more flash. */
static const char refusal_texts[] = "invalid argument\0"	  /* 110 */
				    "out of limits\0"		  /* 111 */
				    "not possible on this base\0" /* 112 */
				    "\0\0\0\0\0\0\0"		  /* 113..119 */
				    "unit not ready\0"		  /* 120 */
				    "servo off\0"		  /* 121 */
				    "unit moving\0"		  /* 122 */
				    "fault active\0"		  /* 123 */
				    "unit locked\0"		  /* 124 */
				    "queue full\0"		  /* 125 */
				    "no such io id\0"		  /* 126 */
				    "no such axis\0"		  /* 127 */
				    "power off\0"		  /* 128 */
				    "unit paused\0"		  /* 129 */
				    "unit stuck\0"		  /* 130 */
				    "joystick in use\0"		  /* 131 */
#if !defined(VS_NO_DRIVE_STATES)
				    "position lost\0" /* 132 */
#endif
    ;

static const char *refusal_reason(uint32_t code)
{
	const char *s = refusal_texts;
	uint32_t n = code - ALM_W_BAD_ARGUMENT;
	/* Beyond the last text the walk stops at the string's own end. */
	if (code < ALM_W_BAD_ARGUMENT)
		return "refused";
	while (n > 0 && s < refusal_texts + sizeof refusal_texts - 1)
		if (*s++ == '\0')
			n--;
	return *s ? s : "refused";
}

static bool refuse_text(vehicle_t *v, const char *op, uint32_t code, const char *reason)
{
	char s[VS_ALARM_SOURCE_MAX];
	size_t pos = vehicle_put_str(s, sizeof s, 0, op);
	pos = vehicle_put_str(s, sizeof s, pos, " refused: ");
	vehicle_put_str(s, sizeof s, pos, reason);
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
	if (VS_DRIVE_STATES && v->pose_lost)
		return vehicle_refuse(v, op, ALM_W_POSE_LOST);
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
		if (mode == MODE_PATH || motion_queue_len(&v->motion) > 0 || v->motion.stopping)
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

FX_HELPER const vs_io_def_t *find_io(const vehicle_t *v, uint32_t ioid, unsigned *index)
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
	size_t pos = vehicle_put_str(b, VS_STATE_MSG_MAX, 0, word);
	if (a) {
		pos = vehicle_put_str(b, VS_STATE_MSG_MAX, pos, "-");
		vehicle_put_dec(b, VS_STATE_MSG_MAX, pos, a->code, 3);
	}
}

bool vs_getState(vehicle_t *v, int16_t *state, char msg[VS_STATE_MSG_MAX])
{
	const char *word;
	const vs_alarm_t *why;

	*state = vehicle_state_of(v, &word, &why);
	state_msg(v->state_msg, word, why);
	vehicle_put_str(msg, VS_STATE_MSG_MAX, 0, v->state_msg);
	return true;
}

void vehicle_blackbox(vehicle_t *v, bbox_sample_t *buf, uint16_t cap, uint16_t every)
{
	bbox_init(&v->bbox, buf, cap, every);
}

bool vs_pause(vehicle_t *v)
{
	motion_pause(&v->motion);
	vehicle_disarm_stick(v);
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
	vehicle_disarm_stick(v);
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
	vehicle_disarm_stick(v);
	return true;
}

bool vs_setPower(vehicle_t *v, bool OnOff)
{
	const vs_hal_ops_t *o = v->hal.ops;
	if (!OnOff) {
		motion_halt(&v->motion);
		vehicle_servo_off(v);
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
		vehicle_raise_fault(v, ALM_F_POWER_ON, "main relay did not close");
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
		vehicle_servo_off(v);
		return true;
	}
	if (v->servo)
		return true;
	if (fault_active(v))
		return vehicle_refuse(v, "setServo", ALM_W_FAULT_ACTIVE);
	for (uint8_t i = 0; i < v->naxes; i++) {
		v->hal.ops->drive_enable(v->hal.ctx, i, true);
		v->encoder_still_ticks[i] = 0;
	}
	/* The drives' own word on it (a drive that enables at once, as the
	 * simulated one does, completes servo on here). */
	if (VS_DRIVE_STATES) {
		vehicle_sample_drives(v);
		if (alarm_any_fault(&v->alarms))
			return false;
	}
	/* Wheel references start at the measured counts: no jump, and in
	 * position (nothing to settle). */
	kin_sync(&v->kin, v->meas_counts);
	v->inpos_ticks = v->window_ticks;
	v->settle_ticks = 0;
	v->servo = true;
	if (VS_DRIVE_STATES) {
		v->servo_wait = false;
		v->servo_wait_ticks = 0;
		for (uint8_t i = 0; i < v->naxes; i++)
			v->servo_wait |= !v->drive[i].enabled;
	}
	return true;
}

void vehicle_diag(const vehicle_t *v, vs_diag_t *d)
{
	d->ref_pose = *motion_ref_pose(&v->motion);
	d->odom_pose = v->odom;
	d->cmd_twist_pt = v->cmd;
	d->meas_twist_pt = v->meas;
	for (unsigned i = 0; i < VS_MAX_AXES; i++)
		d->wheel_cps_q8[i] = v->wheel_cps_q8[i];
	d->ticks = v->ticks;
	d->overruns = v->overruns;
	d->late_ticks = v->late_ticks;
	d->max_late_us = v->max_late_us;
	d->queue_len = motion_queue_len(&v->motion);
	d->mode = motion_mode(&v->motion);
}
