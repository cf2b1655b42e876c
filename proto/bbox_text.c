/* The black box on the links, what a client needs as well (bbox_wire.h):
 * the answer's decoding and the text form. No firmware symbol: vehiclectl
 * links it. */
#include "bbox_wire.h"

#include "fmt.h"
#include "wire.h"

static int64_t get_i64(const uint8_t *p)
{
	return (int64_t)((uint64_t)wire_get_u32(p) | (uint64_t)wire_get_u32(p + 4) << 32);
}

static void get_sample(const uint8_t *p, bbox_sample_t *s)
{
	q32_t *q[9] = {&s->ref.x_mm,   &s->ref.y_mm,  &s->ref.th_deg, &s->odo.x_mm, &s->odo.y_mm,
		       &s->odo.th_deg, &s->cmd.vx_pt, &s->cmd.vy_pt,  &s->cmd.w_pt};

	for (size_t i = 0; i < 9; i++)
		*q[i] = get_i64(p + 8 * i);
	for (size_t i = 0; i < VS_MAX_AXES; i++) {
		s->sp_q8[i] = (int32_t)wire_get_u32(p + 72 + 4 * i);
		s->enc[i] = (int32_t)wire_get_u32(p + 88 + 4 * i);
	}
	s->tick = wire_get_u32(p + 104);
	s->newest_alarm = wire_get_u32(p + 108);
	s->state = (int16_t)wire_get_u16(p + 112);
	s->queue_len = p[114];
	s->alarms = p[115];
}

bool bbox_wire_decode(const uint8_t *p, size_t len, bbox_page_t *pg, bbox_sample_t *out)
{
	if (len < BBOX_HDR_LEN || p[1] > BBOX_PAGE ||
	    len != BBOX_HDR_LEN + (size_t)p[1] * BBOX_SAMPLE_LEN)
		return false;
	pg->status = p[0];
	pg->n = p[1];
	pg->count = wire_get_u16(p + 2);
	pg->index = wire_get_u16(p + 4);
	pg->cap = wire_get_u16(p + 6);
	pg->every = wire_get_u16(p + 8);
	pg->tick_hz = wire_get_u16(p + 10);
	pg->trigger = wire_get_u32(p + 12);
	pg->fault = wire_get_u32(p + 16);
	for (unsigned i = 0; i < pg->n; i++)
		get_sample(p + BBOX_HDR_LEN + (size_t)i * BBOX_SAMPLE_LEN, &out[i]);
	return true;
}

#ifndef VS_NO_BBOX_TEXT
/* ---- the text form ---- */

const char bbox_csv_header[] =
    "time_s,cmd_x_mm,cmd_y_mm,cmd_th_deg,odo_x_mm,odo_y_mm,odo_th_deg,"
    "cmd_vx_mm_s,cmd_vy_mm_s,cmd_w_deg_s,sp0_cps,sp1_cps,sp2_cps,sp3_cps,"
    "state,queue_len,alarms,newest_alarm,enc0,enc1,enc2,enc3,tick,fault";

/* ",<mag / 2^shift>" with dec decimals, rounded to nearest, ties to even:
 * what C's printf writes for the same value as a double ("%.4f"), sign of
 * a negative value rounded to zero included, without floating point. */
static size_t put_fixed(char *b, size_t cap, bool neg, uint64_t mag, unsigned shift, unsigned dec)
{
	static const uint32_t p10[] = {1u, 10u, 100u, 1000u, 10000u};
	uint64_t mask = ((uint64_t)1 << shift) - 1u;
	uint64_t ip = mag >> shift;
	uint64_t r = (mag & mask) * p10[dec];
	uint64_t q = r >> shift, rem = r & mask, half = (uint64_t)1 << (shift - 1u);
	const char *sg = neg ? "-" : "";
	unsigned long long ipl, ql;

	if (rem > half || (rem == half && (q & 1u)))
		q++;
	if (q == p10[dec]) {
		ip++;
		q = 0;
	}
	ipl = ip;
	ql = q;
	if (dec == 4)
		return fmt_print(b, cap, ",%s%llu.%04llu", sg, ipl, ql);
	if (dec == 3)
		return fmt_print(b, cap, ",%s%llu.%03llu", sg, ipl, ql);
	return fmt_print(b, cap, ",%s%llu.%02llu", sg, ipl, ql);
}

static uint64_t mag64(int64_t v)
{
	return v < 0 ? 0u - (uint64_t)v : (uint64_t)v;
}

size_t bbox_csv_row(const bbox_sample_t *s, uint32_t tick_hz, uint32_t fault, char *buf, size_t cap)
{
	const q32_t pose[6] = {s->ref.x_mm, s->ref.y_mm, s->ref.th_deg,
			       s->odo.x_mm, s->odo.y_mm, s->odo.th_deg};
	const q32_t tw[3] = {s->cmd.vx_pt, s->cmd.vy_pt, s->cmd.w_pt};
	/* the simulator's clock: whole microseconds at the end of the tick */
	if (cap < BBOX_CSV_MAX) /* then no field below can pass the end */
		return 0;
	uint64_t us = (uint64_t)s->tick * 1000000u / (tick_hz ? tick_hz : 1u);
	size_t n = fmt_print(buf, cap, "%llu.%06llu", (unsigned long long)(us / 1000000u),
			     (unsigned long long)(us % 1000000u));

	for (unsigned i = 0; i < 6; i++)
		n += put_fixed(buf + n, cap - n, pose[i] < 0, mag64(pose[i]), 32, 4);
	for (unsigned i = 0; i < 3; i++)
		n += put_fixed(buf + n, cap - n, tw[i] < 0, mag64(tw[i]) * tick_hz, 32, 3);
	for (unsigned i = 0; i < VS_MAX_AXES; i++)
		n += put_fixed(buf + n, cap - n, s->sp_q8[i] < 0, mag64(s->sp_q8[i]), 8, 2);
	n += fmt_print(buf + n, cap - n, ",%d,%u,%u,%lu", s->state, (unsigned)s->queue_len,
		       (unsigned)s->alarms, (unsigned long)s->newest_alarm);
	for (unsigned i = 0; i < VS_MAX_AXES; i++)
		n += fmt_print(buf + n, cap - n, ",%ld", (long)s->enc[i]);
	n += fmt_print(buf + n, cap - n, ",%lu,%lu", (unsigned long)s->tick, (unsigned long)fault);
	return n;
}
#endif
