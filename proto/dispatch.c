/* The unit's side of the command table: every transport's request, decoded
 * into cmd_value_t arrays, runs the operation here. The host's client
 * library links cmdtab.c and wire.c, never this file, and so no firmware. */
#include "dispatch.h"

#include <string.h>

static vs_position_t in_pos(const cmd_value_t in[])
{
	vs_position_t p = {in[0].d, in[1].d, in[2].d};
	return p;
}

static vs_point_t in_point(const cmd_value_t in[])
{
	vs_point_t p = {in[0].d, in[1].d};
	return p;
}

static vs_velocity_t in_vel(const cmd_value_t in[])
{
	vs_velocity_t p = {in[0].d, in[1].d};
	return p;
}

bool cmd_invoke(vehicle_t *v, const cmd_def_t *d, const cmd_value_t in[], cmd_value_t out[],
		cmd_scratch_t *scratch)
{
	vs_position_t pos = {0, 0, 0};
	vs_velocity_t vel = {0, 0};
	bool r = false;
	unsigned op = cmd_opcode(d);

	/* Every out field starts defined, whatever the operation does. */
	for (unsigned i = 0; i < d->n_out; i++) {
		memset(&out[i], 0, sizeof(out[i]));
		if (d->out_types[i] == CMD_T_STRING)
			out[i].s = "";
		if (d->out_types[i] == CMD_T_ALARMS)
			out[i].alarms.a = scratch->alarms;
	}

	switch (op) {
	case CMD_OP_clearAlarm:
		return vs_clearAlarm(v);
	case CMD_OP_getAccelerationLimit:
		return vs_getAccelerationLimit(v, &out[0].d, &out[1].d);
	case CMD_OP_getActiveAlarm: {
		int16_t want = in[0].h;
		uint16_t len = 0;

		if (want < 0)
			want = 0;
		if (want > VS_ALARM_LIST_MAX)
			want = VS_ALARM_LIST_MAX;
		r = vs_getActiveAlarm(v, want, &out[0].h, scratch->alarms, &len);
		/* Never trust len beyond the buffer we offered. */
		out[1].alarms.n = len > (uint16_t)want ? (uint16_t)want : len;
		return r;
	}
	case CMD_OP_getBatteryVoltage:
		return vs_getBatteryVoltage(v, &out[0].d);
	case CMD_OP_getDefaultAcceleration:
		r = vs_getDefaultAcceleration(v, &vel);
		break;
	case CMD_OP_getDefaultVelocity:
		r = vs_getDefaultVelocity(v, &vel);
		break;
	case CMD_OP_getIFVersion:
		r = vs_getIFVersion(v, &out[0].s);
		if (!out[0].s)
			out[0].s = "";
		return r;
	case CMD_OP_getInput:
		return vs_getInput(v, in[0].u, &out[0].u);
	case CMD_OP_getPosition:
		r = vs_getPosition(v, &pos);
		out[0].d = pos.x;
		out[1].d = pos.y;
		out[2].d = pos.theta;
		return r;
	case CMD_OP_getServoStatus:
		return vs_getServoStatus(v, in[0].u, &out[0].b);
	case CMD_OP_getState:
		memset(scratch->msg, 0, sizeof(scratch->msg));
		r = vs_getState(v, &out[0].h, scratch->msg);
		scratch->msg[VS_STATE_MSG_MAX - 1] = '\0';
		out[1].s = scratch->msg;
		return r;
	case CMD_OP_getVelocityLimit:
		return vs_getVelocityLimit(v, &out[0].d, &out[1].d);
	case CMD_OP_getVersion:
		r = vs_getVersion(v, &out[0].s);
		if (!out[0].s)
			out[0].s = "";
		return r;
	case CMD_OP_moveCircularRel:
		return vs_moveCircularRel(v, in_point(in), in[2].d);
	case CMD_OP_moveCruiseAbs:
		return vs_moveCruiseAbs(v, in_point(in));
	case CMD_OP_moveForward:
		return vs_moveForward(v, in[0].d);
	case CMD_OP_moveJog:
		return vs_moveJog(v, in[0].d, in[1].d, in[2].d);
	case CMD_OP_moveTurn:
		return vs_moveTurn(v, in[0].d);
	case CMD_OP_pause:
		return vs_pause(v);
	case CMD_OP_resume:
		return vs_resume(v);
	case CMD_OP_setAcceleration:
		return vs_setAcceleration(v, in_vel(in));
	case CMD_OP_setDigitalSensorLock:
		return vs_setDigitalSensorLock(v, in[0].b);
	case CMD_OP_setJogTimeout:
		return vs_setJogTimeout(v, in[0].h);
	case CMD_OP_setJoystick:
		return vs_setJoystick(v, in[0].b);
	case CMD_OP_setOutput:
		return vs_setOutput(v, in[0].u, in[1].u, in[2].u);
	case CMD_OP_setPower:
		return vs_setPower(v, in[0].b);
	case CMD_OP_setServo:
		return vs_setServo(v, in[0].b);
	case CMD_OP_setVelocity:
		return vs_setVelocity(v, in_vel(in));
	case CMD_OP_stop:
		return vs_stop(v);
	case CMD_OP_unlock:
		return vs_unlock(v);
	case CMD_OP_moveContinuousRel:
	case CMD_OP_moveLinearAbs:
	case CMD_OP_moveLinearRel:
	case CMD_OP_setPosition:
		/* the pose read once for the four that take one */
		pos = in_pos(in);
		if (op == CMD_OP_moveContinuousRel)
			return vs_moveContinuousRel(v, pos);
		if (op == CMD_OP_moveLinearAbs)
			return vs_moveLinearAbs(v, pos);
		if (op == CMD_OP_moveLinearRel)
			return vs_moveLinearRel(v, pos);
		return vs_setPosition(v, pos);
	default:
		return false;
	}
	/* getDefaultAcceleration / getDefaultVelocity */
	out[0].d = vel.translation;
	out[1].d = vel.rotation;
	return r;
}

size_t wire_dispatch(vehicle_t *v, unsigned opcode, const uint8_t *req, size_t len, uint8_t *resp,
		     size_t cap, int *status)
{
	/* No operation takes a string or an alarm sequence in, so requests
	 * decode without a wire_store_t (1.9 kB); one that did would be refused
	 * with WIRE_ST_VALUE, never run. The out scratch is static: too large
	 * for a small firmware stack, and the dispatcher is never re-entered. */
	static cmd_scratch_t scratch;
	cmd_value_t in[CMD_MAX_FIELDS], out[CMD_MAX_FIELDS];
	const cmd_def_t *d;
	size_t n = 0;
	bool r;

	if (opcode == WIRE_OP_INFO) {
		if (len != 0) {
			*status = WIRE_ST_LENGTH;
			return 0;
		}
		if (cap < WIRE_INFO_LEN) {
			*status = WIRE_ST_SPACE;
			return 0;
		}
		*status = WIRE_ST_OK;
		return wire_info(resp);
	}
	d = cmd_by_opcode(opcode);
	if (!d) {
		*status = WIRE_ST_OPCODE;
		return 0;
	}
	*status = wire_decode_request(d, req, len, in, NULL);
	if (*status != WIRE_ST_OK)
		return 0;
	r = cmd_invoke(v, d, in, out, &scratch);
	*status = wire_encode_response(d, r, out, resp, cap, &n);
	return *status == WIRE_ST_OK ? n : 0;
}
