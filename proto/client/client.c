/* Client library core: generic call over any transport, and the per
 * operation functions with the IDL signatures. */
#include "client.h"

#include <string.h>
#include <time.h>

/* Every row of the table has its vc_<name> function: a row added to
 * commands.def without one fails to compile here. */
typedef void (*vc_any_fn)(void);
static const vc_any_fn vc_fns[] __attribute__((unused)) = {
#define VS_CMD(name, op, it, in, ot, on, idl, help) (vc_any_fn) vc_##name,
#include "../commands.def"
#undef VS_CMD
};

const char *vc_strerror(int err)
{
	switch (err) {
	case VC_OK:
		return "ok";
	case VC_E_TIMEOUT:
		return "timeout";
	case VC_E_NAK:
		return "nak";
	case VC_E_CRC:
		return "crc";
	case VC_E_LINK:
		return "link failure";
	case VC_E_PROTO:
		return "malformed answer";
	case VC_E_ARG:
		return "bad argument";
	case VC_E_REMOTE:
		return "console error";
	case VC_E_UNSUPPORTED:
		return "unsupported";
	case VC_E_STOPPED:
		return "stopped short";
	case VC_E_NOT_DONE:
		return "not done in time";
	default:
		return "unknown error";
	}
}

void vc_init(vc_client_t *c, const vc_transport_t *t)
{
	memset(c, 0, sizeof(*c));
	if (t)
		c->t = *t;
	c->timeout_ms = VC_DEFAULT_TIMEOUT_MS;
	c->retries = VC_DEFAULT_RETRIES;
}

void vc_close(vc_client_t *c)
{
	if (c->t.close)
		c->t.close(c->t.ctx);
	memset(&c->t, 0, sizeof(c->t));
}

static int exchange(vc_client_t *c, unsigned opcode, const uint8_t *req, size_t len, size_t *n)
{
	if (!c->t.exchange)
		return VC_E_LINK;
	c->nak = 0;
	c->remote_msg[0] = '\0';
	return c->t.exchange(c->t.ctx, opcode, req, len, c->resp, sizeof(c->resp), n, &c->nak,
			     c->timeout_ms, c->retries);
}

int vc_call(vc_client_t *c, const cmd_def_t *d, const cmd_value_t in[], bool *ret,
	    cmd_value_t out[])
{
	uint8_t req[WIRE_REQ_MAX];
	size_t len = 0, n = 0;
	bool r = false;
	int e;

	if (!d)
		return VC_E_ARG;
	if (wire_encode_request(d, in, req, sizeof(req), &len) != WIRE_ST_OK)
		return VC_E_ARG;
	e = exchange(c, d->opcode, req, len, &n);
	if (e != VC_OK)
		return e;
	if (wire_decode_response(d, c->resp, n, &r, out, &c->store) != WIRE_ST_OK)
		return VC_E_PROTO;
	if (ret)
		*ret = r;
	return VC_OK;
}

int vc_info(vc_client_t *c, unsigned *proto_version, uint16_t *table_crc, unsigned *ops)
{
	size_t n = 0;
	int e = exchange(c, WIRE_OP_INFO, NULL, 0, &n);

	if (e != VC_OK)
		return e;
	if (n != WIRE_INFO_LEN)
		return VC_E_PROTO;
	if (proto_version)
		*proto_version = c->resp[0];
	if (table_crc)
		*table_crc = wire_get_u16(c->resp + 1);
	if (ops)
		*ops = c->resp[3];
	return VC_OK;
}

int vc_console_line(vc_client_t *c, const char *line, char *reply, size_t cap)
{
	size_t len = strlen(line), n = 0;
	if (len == 0 || len > 64 || strpbrk(line, "\r\n") || cap == 0)
		return VC_E_ARG;
	int e = exchange(c, WIRE_OP_CONSOLE, (const uint8_t *)line, len, &n);
	if (e != VC_OK)
		return e;
	if (n >= cap)
		n = cap - 1;
	memcpy(reply, c->resp, n);
	reply[n] = '\0';
	return VC_OK;
}

int vc_stream_subscribe(vc_client_t *c, uint16_t mask, unsigned period_ms, vc_stream_info_t *info)
{
	uint8_t req[STREAM_REQ_LEN];
	size_t n = 0;
	int e;

	if (!c->t.stream_next)
		return VC_E_UNSUPPORTED;
	if (period_ms > UINT16_MAX)
		return VC_E_ARG;
	wire_put_u16(req, mask);
	wire_put_u16(req + 2, (uint16_t)period_ms);
	e = exchange(c, WIRE_OP_STREAM, req, sizeof(req), &n);
	if (e != VC_OK)
		return e;
	if (n != STREAM_RESP_LEN)
		return VC_E_PROTO;
	c->stream_seen = false;
	if (info) {
		info->mask = wire_get_u16(c->resp);
		info->period_ms = wire_get_u16(c->resp + 2);
		info->frame_bytes = wire_get_u16(c->resp + 4);
		info->min_period_ms = wire_get_u16(c->resp + 6);
		info->tick_hz = wire_get_u16(c->resp + 8);
	}
	return VC_OK;
}

int vc_stream_unsubscribe(vc_client_t *c)
{
	return vc_stream_subscribe(c, 0, 0, NULL);
}

static int bbox_request(vc_client_t *c, uint8_t action, uint16_t index, bbox_page_t *pg,
			bbox_sample_t *s)
{
	uint8_t req[BBOX_REQ_LEN] = {action, (uint8_t)(index & 0xFFu), (uint8_t)(index >> 8)};
	size_t n = 0;
	int e;

	if (!c->t.name || strcmp(c->t.name, "serial") != 0)
		return VC_E_UNSUPPORTED;
	e = exchange(c, WIRE_OP_BBOX, req, sizeof(req), &n);
	if (e != VC_OK)
		return e;
	if (!bbox_wire_decode(c->resp, n, pg, s) || pg->index != index)
		return VC_E_PROTO;
	return VC_OK;
}

int vc_bbox_page(vc_client_t *c, uint16_t index, bbox_page_t *pg, bbox_sample_t *s)
{
	return bbox_request(c, BBOX_READ, index, pg, s);
}

int vc_bbox_clear(vc_client_t *c, bbox_page_t *pg)
{
	bbox_sample_t none[BBOX_PAGE]; /* a clear's answer has none */

	return bbox_request(c, BBOX_CLEAR, 0, pg, none);
}

int vc_bbox_read(vc_client_t *c, bbox_sample_t *s, size_t cap, size_t *n, bbox_page_t *pg)
{
	bbox_sample_t page[BBOX_PAGE];
	size_t got = 0;
	int e;

	do {
		if (got > UINT16_MAX)
			return VC_E_PROTO;
		e = vc_bbox_page(c, (uint16_t)got, pg, page);
		if (e != VC_OK)
			return e;
		if (got + pg->n > cap)
			return VC_E_ARG;
		memcpy(s + got, page, pg->n * sizeof(*page));
		got += pg->n;
	} while (pg->n > 0 && got < pg->count);
	*n = got;
	return VC_OK;
}

int vc_stream_next(vc_client_t *c, vc_sample_t *s, unsigned timeout_ms)
{
	uint8_t p[STREAM_PAYLOAD_MAX];
	size_t len = 0;
	uint8_t seq = 0;
	int e;

	if (!c->t.stream_next)
		return VC_E_UNSUPPORTED;
	e = c->t.stream_next(c->t.ctx, p, sizeof(p), &len, &seq, timeout_ms);
	if (e != VC_OK)
		return e;
	memset(s, 0, sizeof(*s));
	if (stream_decode(p, len, &s->mask, &s->tick, &s->v) != 0)
		return VC_E_PROTO;
	s->seq = seq;
	s->lost = c->stream_seen ? (uint8_t)(seq - c->stream_seq - 1u) : 0u;
	c->stream_seen = true;
	c->stream_seq = seq;
	return VC_OK;
}

/* One operation by opcode; out[] is filled only on success. */
static int run(vc_client_t *c, unsigned op, bool *ret, const cmd_value_t *in, cmd_value_t *out)
{
	cmd_value_t tmp[CMD_MAX_FIELDS];
	cmd_value_t none[1];

	memset(tmp, 0, sizeof(tmp));
	memset(none, 0, sizeof(none));
	return vc_call(c, cmd_by_opcode(op), in ? in : none, ret, out ? out : tmp);
}

static int run_void(vc_client_t *c, unsigned op, bool *ret)
{
	return run(c, op, ret, NULL, NULL);
}

static int run_d(vc_client_t *c, unsigned op, bool *ret, double a, double b, double t)
{
	cmd_value_t in[3];

	in[0].d = a;
	in[1].d = b;
	in[2].d = t;
	return run(c, op, ret, in, NULL);
}

static int run_b(vc_client_t *c, unsigned op, bool *ret, bool b)
{
	cmd_value_t in[1];

	in[0].b = b;
	return run(c, op, ret, in, NULL);
}

static int get_dd(vc_client_t *c, unsigned op, bool *ret, double *a, double *b)
{
	cmd_value_t out[2];
	int e = run(c, op, ret, NULL, out);

	if (e == VC_OK) {
		if (a)
			*a = out[0].d;
		if (b)
			*b = out[1].d;
	}
	return e;
}

static int get_s(vc_client_t *c, unsigned op, bool *ret, const char **s)
{
	cmd_value_t out[1];
	int e = run(c, op, ret, NULL, out);

	if (e == VC_OK && s)
		*s = out[0].s;
	return e;
}

int vc_clearAlarm(vc_client_t *c, bool *ret)
{
	return run_void(c, CMD_OP_clearAlarm, ret);
}

int vc_getAccelerationLimit(vc_client_t *c, bool *ret, double *accLimitT, double *accLimitR)
{
	return get_dd(c, CMD_OP_getAccelerationLimit, ret, accLimitT, accLimitR);
}

int vc_getActiveAlarm(vc_client_t *c, bool *ret, int16_t numOfAlarm, int16_t *numOfActiveAlarm,
		      vs_alarm_t *activeAlarms, uint16_t *len)
{
	cmd_value_t in[1], out[2];
	uint16_t room = numOfAlarm > 0 ? (uint16_t)numOfAlarm : 0;
	int e;

	in[0].h = numOfAlarm;
	e = run(c, CMD_OP_getActiveAlarm, ret, in, out);
	if (e != VC_OK)
		return e;
	/* The unit never sends more than asked; a unit that did is broken. */
	if (out[1].alarms.n > room)
		return VC_E_PROTO;
	if (numOfActiveAlarm)
		*numOfActiveAlarm = out[0].h;
	if (activeAlarms && out[1].alarms.n)
		memcpy(activeAlarms, out[1].alarms.a, out[1].alarms.n * sizeof(vs_alarm_t));
	if (len)
		*len = out[1].alarms.n;
	return VC_OK;
}

int vc_getBatteryVoltage(vc_client_t *c, bool *ret, double *voltage)
{
	cmd_value_t out[1];
	int e = run(c, CMD_OP_getBatteryVoltage, ret, NULL, out);

	if (e == VC_OK && voltage)
		*voltage = out[0].d;
	return e;
}

int vc_getDefaultAcceleration(vc_client_t *c, bool *ret, vs_velocity_t *defaultAccel)
{
	vs_velocity_t v = {0, 0};
	int e = get_dd(c, CMD_OP_getDefaultAcceleration, ret, &v.translation, &v.rotation);

	if (e == VC_OK && defaultAccel)
		*defaultAccel = v;
	return e;
}

int vc_getDefaultVelocity(vc_client_t *c, bool *ret, vs_velocity_t *defaultVel)
{
	vs_velocity_t v = {0, 0};
	int e = get_dd(c, CMD_OP_getDefaultVelocity, ret, &v.translation, &v.rotation);

	if (e == VC_OK && defaultVel)
		*defaultVel = v;
	return e;
}

int vc_getIFVersion(vc_client_t *c, bool *ret, const char **version)
{
	return get_s(c, CMD_OP_getIFVersion, ret, version);
}

int vc_getInput(vc_client_t *c, bool *ret, uint32_t ioid, uint32_t *input)
{
	cmd_value_t in[1], out[1];
	int e;

	in[0].u = ioid;
	e = run(c, CMD_OP_getInput, ret, in, out);
	if (e == VC_OK && input)
		*input = out[0].u;
	return e;
}

int vc_getPosition(vc_client_t *c, bool *ret, vs_position_t *pos)
{
	cmd_value_t out[3];
	int e = run(c, CMD_OP_getPosition, ret, NULL, out);

	if (e == VC_OK && pos) {
		pos->x = out[0].d;
		pos->y = out[1].d;
		pos->theta = out[2].d;
	}
	return e;
}

int vc_getServoStatus(vc_client_t *c, bool *ret, uint32_t axisid, bool *status)
{
	cmd_value_t in[1], out[1];
	int e;

	in[0].u = axisid;
	e = run(c, CMD_OP_getServoStatus, ret, in, out);
	if (e == VC_OK && status)
		*status = out[0].b;
	return e;
}

int vc_getState(vc_client_t *c, bool *ret, int16_t *state, char msg[VS_STATE_MSG_MAX])
{
	cmd_value_t out[2];
	int e = run(c, CMD_OP_getState, ret, NULL, out);

	if (e != VC_OK)
		return e;
	size_t len = strlen(out[1].s);
	if (len >= VS_STATE_MSG_MAX)
		return VC_E_PROTO;
	if (state)
		*state = out[0].h;
	if (msg)
		memcpy(msg, out[1].s, len + 1);
	return VC_OK;
}

int vc_getVelocityLimit(vc_client_t *c, bool *ret, double *velLimitT, double *velLimitR)
{
	return get_dd(c, CMD_OP_getVelocityLimit, ret, velLimitT, velLimitR);
}

int vc_getVersion(vc_client_t *c, bool *ret, const char **ver)
{
	return get_s(c, CMD_OP_getVersion, ret, ver);
}

int vc_moveCircularRel(vc_client_t *c, bool *ret, vs_point_t centerPoint, double theta)
{
	return run_d(c, CMD_OP_moveCircularRel, ret, centerPoint.x, centerPoint.y, theta);
}

int vc_moveContinuousRel(vc_client_t *c, bool *ret, vs_position_t pos)
{
	return run_d(c, CMD_OP_moveContinuousRel, ret, pos.x, pos.y, pos.theta);
}

int vc_moveCruiseAbs(vc_client_t *c, bool *ret, vs_point_t cruisePoint)
{
	return run_d(c, CMD_OP_moveCruiseAbs, ret, cruisePoint.x, cruisePoint.y, 0);
}

int vc_moveForward(vc_client_t *c, bool *ret, double x_)
{
	return run_d(c, CMD_OP_moveForward, ret, x_, 0, 0);
}

int vc_moveJog(vc_client_t *c, bool *ret, double xVel, double yVel, double thetaVel)
{
	return run_d(c, CMD_OP_moveJog, ret, xVel, yVel, thetaVel);
}

int vc_moveLinearAbs(vc_client_t *c, bool *ret, vs_position_t pos)
{
	return run_d(c, CMD_OP_moveLinearAbs, ret, pos.x, pos.y, pos.theta);
}

int vc_moveLinearRel(vc_client_t *c, bool *ret, vs_position_t pos)
{
	return run_d(c, CMD_OP_moveLinearRel, ret, pos.x, pos.y, pos.theta);
}

int vc_moveTurn(vc_client_t *c, bool *ret, double theta_)
{
	return run_d(c, CMD_OP_moveTurn, ret, theta_, 0, 0);
}

int vc_pause(vc_client_t *c, bool *ret)
{
	return run_void(c, CMD_OP_pause, ret);
}

int vc_resume(vc_client_t *c, bool *ret)
{
	return run_void(c, CMD_OP_resume, ret);
}

int vc_setAcceleration(vc_client_t *c, bool *ret, vs_velocity_t accel)
{
	return run_d(c, CMD_OP_setAcceleration, ret, accel.translation, accel.rotation, 0);
}

int vc_setDigitalSensorLock(vc_client_t *c, bool *ret, bool OnOff)
{
	return run_b(c, CMD_OP_setDigitalSensorLock, ret, OnOff);
}

int vc_setJogTimeout(vc_client_t *c, bool *ret, int16_t timeout)
{
	cmd_value_t in[1];

	in[0].h = timeout;
	return run(c, CMD_OP_setJogTimeout, ret, in, NULL);
}

int vc_setJoystick(vc_client_t *c, bool *ret, bool OnOff)
{
	return run_b(c, CMD_OP_setJoystick, ret, OnOff);
}

int vc_setOutput(vc_client_t *c, bool *ret, uint32_t ioid, uint32_t output, uint32_t mask)
{
	cmd_value_t in[3];

	in[0].u = ioid;
	in[1].u = output;
	in[2].u = mask;
	return run(c, CMD_OP_setOutput, ret, in, NULL);
}

int vc_setPosition(vc_client_t *c, bool *ret, vs_position_t pos)
{
	return run_d(c, CMD_OP_setPosition, ret, pos.x, pos.y, pos.theta);
}

int vc_setPower(vc_client_t *c, bool *ret, bool OnOff)
{
	return run_b(c, CMD_OP_setPower, ret, OnOff);
}

int vc_setServo(vc_client_t *c, bool *ret, bool OnOff)
{
	return run_b(c, CMD_OP_setServo, ret, OnOff);
}

int vc_setVelocity(vc_client_t *c, bool *ret, vs_velocity_t vel)
{
	return run_d(c, CMD_OP_setVelocity, ret, vel.translation, vel.rotation, 0);
}

int vc_stop(vc_client_t *c, bool *ret)
{
	return run_void(c, CMD_OP_stop, ret);
}

int vc_unlock(vc_client_t *c, bool *ret)
{
	return run_void(c, CMD_OP_unlock, ret);
}

bool vc_state_done(int16_t state)
{
	return state == VS_STATE_READY || state == VS_STATE_WARNING;
}

bool vc_state_stopped(int16_t state)
{
	return state == VS_STATE_ALARM || state == VS_STATE_STUCK || state == VS_STATE_LOCKED ||
	       state == VS_STATE_POWERED || state == VS_STATE_UNPOWERED;
}

/* Monotonic milliseconds. Not client_serial.c's vcio_now_ms: the transports
 * call into this file, never the other way (make lint: objdeps). */
static uint64_t mono_ms(void)
{
	struct timespec ts;

	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (uint64_t)ts.tv_sec * 1000u + (uint64_t)ts.tv_nsec / 1000000u;
}

int vc_wait_done(vc_client_t *c, unsigned timeout_ms, int16_t *state, char msg[VS_STATE_MSG_MAX])
{
	uint64_t end = mono_ms() + timeout_ms;
	char m[VS_STATE_MSG_MAX];
	int16_t st = 0;

	for (;;) {
		int e = vc_getState(c, NULL, &st, m);

		if (e != VC_OK)
			return e;
		if (state)
			*state = st;
		if (msg)
			memcpy(msg, m, sizeof(m));
		if (vc_state_done(st))
			return VC_OK;
		if (vc_state_stopped(st))
			return VC_E_STOPPED;
		if (mono_ms() >= end)
			return VC_E_NOT_DONE;
		struct timespec ts = {0, VC_WAIT_POLL_MS * 1000000L};
		nanosleep(&ts, NULL);
	}
}
