/* A telemetry sample read from the unit (stream.h): the side of the stream
 * that runs on the unit, apart from the encodings, which a client links
 * without the firmware. */
#include "stream.h"

#include <stddef.h>
#include <string.h>

#include "fmt.h"
#include "wire.h"

/* x * mult rounded half away from zero, saturated to [lo, hi]; NaN reads 0. */
static int64_t real_round(vs_real_t x, int32_t mult, int64_t lo, int64_t hi)
{
#ifdef VS_REAL_Q32
	int64_t r;

	if (x == VS_REAL_NAN)
		return 0;
	if (x > INT64_MAX / mult || x < -(INT64_MAX / mult))
		return x < 0 ? lo : hi;
	r = x * mult;
	r = r >= 0 ? (r + ((int64_t)1 << 31)) >> 32 : -((-r + ((int64_t)1 << 31)) >> 32);
#else
	double y = x * (double)mult;
	int64_t r;

	if (y != y)
		return 0;
	if (y <= (double)lo)
		return lo;
	if (y >= (double)hi)
		return hi;
	r = (int64_t)(y < 0 ? y - 0.5 : y + 0.5);
#endif
	return r < lo ? lo : r > hi ? hi : r;
}

/* Q32 per tick -> units per second, rounded, saturated to int16. */
static int16_t rate_i16(q32_t per_tick, uint32_t tick_hz, int32_t mult)
{
	int64_t v = per_tick * (int64_t)tick_hz * mult;
	int64_t half = (int64_t)1 << 31;
	int64_t r = v >= 0 ? (v + half) >> 32 : -((-v + half) >> 32);

	return (int16_t)(r > INT16_MAX ? INT16_MAX : r < INT16_MIN ? INT16_MIN : r);
}

/* Bit k: the k-th input (or output) of the io table is non-zero. */
static void read_io(vehicle_t *v, stream_sample_t *s)
{
	unsigned kin = 0, kout = 0;

	for (unsigned i = 0; i < v->cfg.num_io && i < VS_MAX_IO; i++) {
		const vs_io_def_t *d = &v->cfg.io[i];
		uint32_t val = 0;

		if (d->dir == VS_IO_IN) {
			if (kin < 16 && v->hal.ops->io_read(v->hal.ctx, d->id, &val) && val)
				s->inputs |= (uint16_t)(1u << kin);
			kin++;
		} else {
			if (kout < 16 && v->out_shadow[i])
				s->outputs |= (uint16_t)(1u << kout);
			kout++;
		}
	}
}

void stream_read(vehicle_t *v, stream_sample_t *s)
{
	vs_position_t pos = {0, 0, 0};
	char msg[VS_STATE_MSG_MAX];
	vs_alarm_t newest;
	int16_t state = 0, nalarms = 0;
	uint16_t got = 0;
	vs_real_t batt = 0;
	vs_diag_t d;
	uint32_t hz = v->cfg.tick_hz;

	memset(s, 0, sizeof(*s));
	memset(&d, 0, sizeof(d));
	vs_getState(v, &state, msg);
	vs_getActiveAlarm(v, 1, &nalarms, &newest, &got);
	vs_getBatteryVoltage(v, &batt);
	vs_getPosition(v, &pos);
	vehicle_diag(v, &d);
	s->state = (uint16_t)state;
	s->alarms = nalarms < 0 ? 0 : nalarms > 255 ? 255 : (uint8_t)nalarms;
	if (got) {
		s->alarm_code = newest.code;
		s->alarm_type = (uint8_t)newest.type;
	}
	s->battery_cV = (uint16_t)real_round(batt, 10, 0, UINT16_MAX);
	s->x_dmm = (int32_t)real_round(pos.x, 10, INT32_MIN, INT32_MAX);
	s->y_dmm = (int32_t)real_round(pos.y, 10, INT32_MIN, INT32_MAX);
	s->theta_mdeg = (int32_t)real_round(pos.theta, 1000, INT32_MIN, INT32_MAX);
	s->vx_mm_s = rate_i16(d.cmd_twist_pt.vx_pt, hz, 1);
	s->vy_mm_s = rate_i16(d.cmd_twist_pt.vy_pt, hz, 1);
	s->w_ddeg_s = rate_i16(d.cmd_twist_pt.w_pt, hz, 10);
	s->mvx_mm_s = rate_i16(d.meas_twist_pt.vx_pt, hz, 1);
	s->mvy_mm_s = rate_i16(d.meas_twist_pt.vy_pt, hz, 1);
	s->mw_ddeg_s = rate_i16(d.meas_twist_pt.w_pt, hz, 10);
	s->queue = d.queue_len;
	read_io(v, s);
}
