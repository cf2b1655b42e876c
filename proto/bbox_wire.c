/* The black box on the links (bbox_wire.h). */
#include "bbox_wire.h"

#include <string.h>

#include "console.h"
#include "fmt.h"
#include "numparse.h"
#include "wire.h"

_Static_assert(BBOX_RESP_MAX <= WIRE_RESP_MAX, "a page fits an answer");

static void put_i64(uint8_t *p, int64_t v)
{
	wire_put_u32(p, (uint32_t)((uint64_t)v & 0xFFFFFFFFu));
	wire_put_u32(p + 4, (uint32_t)((uint64_t)v >> 32));
}

static int64_t get_i64(const uint8_t *p)
{
	return (int64_t)((uint64_t)wire_get_u32(p) | (uint64_t)wire_get_u32(p + 4) << 32);
}

static void put_sample(uint8_t *p, const bbox_sample_t *s)
{
	const q32_t q[9] = {s->ref.x_mm,   s->ref.y_mm,	 s->ref.th_deg, s->odo.x_mm, s->odo.y_mm,
			    s->odo.th_deg, s->cmd.vx_pt, s->cmd.vy_pt,	s->cmd.w_pt};

	for (unsigned i = 0; i < 9; i++)
		put_i64(p + 8 * i, q[i]);
	for (unsigned i = 0; i < VS_MAX_AXES; i++) {
		wire_put_u32(p + 72 + 4 * i, (uint32_t)s->sp_q8[i]);
		wire_put_u32(p + 88 + 4 * i, (uint32_t)s->enc[i]);
	}
	wire_put_u32(p + 104, s->tick);
	wire_put_u32(p + 108, s->newest_alarm);
	wire_put_u16(p + 112, (uint16_t)s->state);
	p[114] = s->queue_len;
	p[115] = s->alarms;
}

static void get_sample(const uint8_t *p, bbox_sample_t *s)
{
	q32_t *q[9] = {&s->ref.x_mm,   &s->ref.y_mm,  &s->ref.th_deg, &s->odo.x_mm, &s->odo.y_mm,
		       &s->odo.th_deg, &s->cmd.vx_pt, &s->cmd.vy_pt,  &s->cmd.w_pt};

	for (unsigned i = 0; i < 9; i++)
		*q[i] = get_i64(p + 8 * i);
	for (unsigned i = 0; i < VS_MAX_AXES; i++) {
		s->sp_q8[i] = (int32_t)wire_get_u32(p + 72 + 4 * i);
		s->enc[i] = (int32_t)wire_get_u32(p + 88 + 4 * i);
	}
	s->tick = wire_get_u32(p + 104);
	s->newest_alarm = wire_get_u32(p + 108);
	s->state = (int16_t)wire_get_u16(p + 112);
	s->queue_len = p[114];
	s->alarms = p[115];
}

_Static_assert(VS_MAX_AXES == 4, "the sample's layout has four axes");

static size_t put_page(const vehicle_t *v, uint16_t index, uint8_t *resp)
{
	const blackbox_t *b = &v->bbox;
	uint16_t n = (uint16_t)(b->count - index);

	if (n > BBOX_PAGE)
		n = BBOX_PAGE;
	resp[0] = b->status;
	resp[1] = (uint8_t)n;
	wire_put_u16(resp + 2, b->count);
	wire_put_u16(resp + 4, index);
	wire_put_u16(resp + 6, b->cap);
	wire_put_u16(resp + 8, b->every ? b->every : 1u);
	wire_put_u16(resp + 10, (uint16_t)v->cfg.tick_hz);
	wire_put_u32(resp + 12, b->status == BBOX_FROZEN ? b->trigger : 0u);
	wire_put_u32(resp + 16, b->status == BBOX_FROZEN ? b->fault : 0u);
	for (uint16_t i = 0; i < n; i++)
		put_sample(resp + BBOX_HDR_LEN + (size_t)i * BBOX_SAMPLE_LEN,
			   bbox_get(b, (uint16_t)(index + i)));
	return BBOX_HDR_LEN + (size_t)n * BBOX_SAMPLE_LEN;
}

size_t bbox_wire_serve(vehicle_t *v, const uint8_t *p, size_t len, uint8_t *resp, int *st)
{
	if (len != BBOX_REQ_LEN) {
		*st = WIRE_ST_LENGTH;
		return 0;
	}
	uint16_t index = wire_get_u16(p + 1);
	if ((p[0] == BBOX_READ && index > v->bbox.count) || (p[0] == BBOX_CLEAR && index != 0) ||
	    p[0] > BBOX_CLEAR) {
		*st = WIRE_ST_VALUE;
		return 0;
	}
	if (p[0] == BBOX_CLEAR)
		bbox_clear(&v->bbox);
	*st = WIRE_ST_OK;
	return put_page(v, index, resp);
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

/* ---- $bbox ---- */

static const char *const status_names[] = {"off", "armed", "frozen"};

void bbox_console(vehicle_t *v, int argc, char **argv, char *reply, size_t cap)
{
	blackbox_t *b = &v->bbox;
	int64_t i;

	if (argc == 1) {
		fmt_print(reply, cap,
			  "ok bbox %s samples %u of %u every %u tick_hz %lu trigger %lu fault %lu",
			  status_names[b->status], (unsigned)b->count, (unsigned)b->cap,
			  (unsigned)(b->every ? b->every : 1u), (unsigned long)v->cfg.tick_hz,
			  (unsigned long)(b->status == BBOX_FROZEN ? b->trigger : 0u),
			  (unsigned long)(b->status == BBOX_FROZEN ? b->fault : 0u));
	} else if (argc == 2 && np_streq_nocase(argv[1], "clear")) {
		bbox_clear(b);
		fmt_print(reply, cap, "ok bbox %s", status_names[b->status]);
	} else if (argc == 2 && np_streq_nocase(argv[1], "header")) {
		fmt_print(reply, cap, "ok %s", bbox_csv_header);
	} else if (argc == 3 && np_streq_nocase(argv[1], "dump")) {
		if (b->count == 0 || np_parse_int(argv[2], 0, b->count - 1, &i) != NP_OK) {
			fmt_print(reply, cap, "error %d $bbox dump: %u samples held",
				  CONSOLE_E_EXTRA, (unsigned)b->count);
			return;
		}
		const bbox_sample_t *s = bbox_get(b, (uint16_t)i);
		size_t n = fmt_print(reply, cap, "ok ");
		bbox_csv_row(s, v->cfg.tick_hz,
			     b->status == BBOX_FROZEN && s->tick == b->trigger ? b->fault : 0u,
			     reply + n, cap - n);
	} else {
		fmt_print(reply, cap, "error %d $bbox takes nothing, clear, header or dump INDEX",
			  CONSOLE_E_EXTRA);
	}
}
