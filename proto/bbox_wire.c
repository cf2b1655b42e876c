/* The black box on the links, the unit's side (bbox_wire.h). */
#include "bbox_wire.h"

#include <stddef.h>
#include <string.h>

#include "console.h"
#include "fmt.h"
#include "numparse.h"
#include "wire.h"

_Static_assert(BBOX_RESP_MAX <= WIRE_RESP_MAX, "a page fits an answer");

/* A sample's memory is its layout on the wire, little-endian without gaps,
 * on every unit this firmware runs on (x86-64, arm64, Cortex-M): one copy
 * (0.2 KiB less flash on a board than field by field). */
_Static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "a little-endian unit");
#define BBOX_AT(m, at) _Static_assert(offsetof(bbox_sample_t, m) == (at), #m " at its wire offset");
BBOX_AT(ref, 0)
BBOX_AT(odo, 24)
BBOX_AT(cmd, 48)
BBOX_AT(sp_q8, 72)
BBOX_AT(enc, 88)
BBOX_AT(tick, 104)
BBOX_AT(newest_alarm, 108)
BBOX_AT(state, 112)
BBOX_AT(queue_len, 114)
BBOX_AT(alarms, 115)
#undef BBOX_AT
_Static_assert(sizeof(fx_pose_t) == 24 && sizeof(fx_twist_t) == 24, "three Q32 each");
_Static_assert(BBOX_SAMPLE_LEN == 116, "the sample's wire length");

static void put_sample(uint8_t *p, const bbox_sample_t *s)
{
	memcpy(p, s, BBOX_SAMPLE_LEN);
}

/* The samples this unit puts in an answer (a client takes up to BBOX_PAGE,
 * reading on from the count it got): a board answers fewer, as a page of
 * eight took it 36,500 cycles, more than the 25,000 of a 1 ms tick. */
#ifndef BBOX_UNIT_PAGE
#define BBOX_UNIT_PAGE BBOX_PAGE
#endif
_Static_assert(BBOX_UNIT_PAGE >= 1 && BBOX_UNIT_PAGE <= BBOX_PAGE, "a page within the client's");

_Static_assert(VS_MAX_AXES == 4, "the sample's layout has four axes");

static size_t put_page(const vehicle_t *v, uint16_t index, uint8_t *resp)
{
	const blackbox_t *b = &v->bbox;
	uint16_t n = (uint16_t)(b->count - index);

	if (n > BBOX_UNIT_PAGE)
		n = BBOX_UNIT_PAGE;
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

/* ---- $bbox ---- */

static const char *const status_names[] = {"off", "armed", "frozen"};

void bbox_console(vehicle_t *v, int argc, char **argv, char *reply, size_t cap)
{
	blackbox_t *b = &v->bbox;

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
#ifdef VS_NO_BBOX_TEXT
	} else if (argc >= 2 &&
		   (np_streq_nocase(argv[1], "header") || np_streq_nocase(argv[1], "dump"))) {
		fmt_print(reply, cap, "error %d $bbox %s is not in this build: read it in frames",
			  CONSOLE_E_EXTRA, argv[1]);
#else
	} else if (argc == 2 && np_streq_nocase(argv[1], "header")) {
		fmt_print(reply, cap, "ok %s", bbox_csv_header);
	} else if (argc == 3 && np_streq_nocase(argv[1], "dump")) {
		int64_t i;

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
#endif
	} else {
		fmt_print(reply, cap, "error %d $bbox takes nothing, clear, header or dump INDEX",
			  CONSOLE_E_EXTRA);
	}
}
