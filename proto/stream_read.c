/* A telemetry sample read from the unit (stream.h): the side of the stream
 * that runs on the unit, apart from the encodings, which a client links
 * without the firmware. */
#include "stream.h"

#include <stddef.h>
#include <string.h>

#include "fmt.h"
#include "wire.h"

/* A Q32 value rounded to the integer, half away from zero. */
static int64_t q32_round(int64_t v)
{
	int64_t half = (int64_t)1 << 31;

	return v >= 0 ? (v + half) >> 32 : -((-v + half) >> 32);
}

/* x * mult rounded half away from zero, saturated to [lo, hi]; NaN reads 0. */
static int64_t real_round(vs_real_t x, int32_t mult, int64_t lo, int64_t hi)
{
#ifdef VS_REAL_Q32
	/* |x| * mult in its whole and fraction parts: no product overflows
	 * (the whole part is below 2^31, mult below 2^10) and no 64-bit
	 * division is needed (a library call on a board); a product beyond
	 * int64 saturates as before. */
	uint64_t u, m;
	int64_t r;

	if (x == VS_REAL_NAN)
		return 0;
	u = x < 0 ? (uint64_t)0 - (uint64_t)x : (uint64_t)x;
	m = (u >> 32) * (uint32_t)mult + (((u & 0xFFFFFFFFu) * (uint32_t)mult + (1u << 31)) >> 32);
	r = x < 0 ? -(int64_t)m : (int64_t)m;
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
	int64_t r = q32_round(per_tick * (int64_t)tick_hz * mult);

	return (int16_t)(r > INT16_MAX ? INT16_MAX : r < INT16_MIN ? INT16_MIN : r);
}

/* A body twist per tick -> mm/s, mm/s, 0.1 deg/s. */
static void twist_put(const fx_twist_t *t, uint32_t tick_hz, int16_t *vx, int16_t *vy, int16_t *w)
{
	*vx = rate_i16(t->vx_pt, tick_hz, 1);
	*vy = rate_i16(t->vy_pt, tick_hz, 1);
	*w = rate_i16(t->w_pt, tick_hz, 10);
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
	int16_t state = 0;
	vs_real_t batt = 0;

	memset(s, 0, sizeof(*s));
	vs_getState(v, &state, msg);
	vs_getBatteryVoltage(v, &batt);
	vs_getPosition(v, &pos);
	s->state = (uint16_t)state;
	/* getActiveAlarm's count and newest (a[0]), read in place */
	s->alarms = v->alarms.n;
	if (v->alarms.n) {
		s->alarm_code = v->alarms.a[0].code;
		s->alarm_type = (uint8_t)v->alarms.a[0].type;
	}
	s->battery_cV = (uint16_t)real_round(batt, 10, 0, UINT16_MAX);
	s->x_dmm = (int32_t)real_round(pos.x, 10, INT32_MIN, INT32_MAX);
	s->y_dmm = (int32_t)real_round(pos.y, 10, INT32_MIN, INT32_MAX);
	s->theta_mdeg = (int32_t)real_round(pos.theta, 1000, INT32_MIN, INT32_MAX);
	/* what vehicle_diag reports as cmd_twist_pt, meas_twist_pt and
	 * queue_len, without copying the rest of it */
	twist_put(&v->cmd, v->cfg.tick_hz, &s->vx_mm_s, &s->vy_mm_s, &s->w_ddeg_s);
	twist_put(&v->meas, v->cfg.tick_hz, &s->mvx_mm_s, &s->mvy_mm_s, &s->mw_ddeg_s);
	s->queue = motion_queue_len(&v->motion);
	read_io(v, s);
}
