/* The telemetry value set and its two encodings (stream.h, stream.def). */
#include "stream.h"

#include <stddef.h>
#include <string.h>

#include "fmt.h"
#include "wire.h"

/* The units and descriptions are docs (tests/test_stream.c reads them). */
#define STREAM_FIELD(name, group, type, frame, off, unit, what)                                    \
	{#name,                                                                                    \
	 STREAM_G_##group,                                                                         \
	 STREAM_T_##type,                                                                          \
	 frame,                                                                                    \
	 off,                                                                                      \
	 (uint16_t)offsetof(stream_sample_t, name)},
const stream_field_t stream_fields[] = {
#include "stream.def"
};
#undef STREAM_FIELD
const unsigned stream_field_count = sizeof(stream_fields) / sizeof(stream_fields[0]);

const char *const stream_group_names[STREAM_GROUPS] = {"pose",	"cmd",	   "meas", "state",
						       "alarm", "battery", "io",   "queue"};

size_t stream_type_size(unsigned type)
{
	static const uint8_t size[] = {2, 4, 1, 2, 4};

	return type < sizeof(size) ? size[type] : 0;
}

size_t stream_payload_len(uint16_t mask)
{
	size_t n = STREAM_HDR;

	for (unsigned i = 0; i < stream_field_count; i++)
		if (mask & (1u << stream_fields[i].group))
			n += stream_type_size(stream_fields[i].type);
	return n;
}

size_t stream_frame_bytes(uint16_t mask)
{
	return 7u + stream_payload_len(mask);
}

size_t stream_text_bytes(uint16_t mask)
{
	/* "~stream SEQ TICK", then " name value" per field, then LF */
	size_t n = sizeof("~stream 255 4294967295") - 1u + 1u;

	for (unsigned i = 0; i < stream_field_count; i++)
		if (mask & (1u << stream_fields[i].group))
			n += 1u + strlen(stream_fields[i].name) + 1u + 11u;
	return n;
}

/* The rule: bytes / period <= baud / 10 * share, in integers. */
bool stream_fits_bytes(size_t bytes, uint32_t period_ms, uint32_t baud)
{
	uint64_t need = (uint64_t)bytes * 10000u * STREAM_SHARE_DEN;
	uint64_t have = (uint64_t)period_ms * baud * STREAM_SHARE_NUM;

	return need <= have;
}

uint32_t stream_min_period_bytes(size_t bytes, uint32_t baud)
{
	uint64_t need = (uint64_t)bytes * 10000u * STREAM_SHARE_DEN;
	uint64_t per = (uint64_t)baud * STREAM_SHARE_NUM;

	if (!per)
		return 0;
	return (uint32_t)((need + per - 1u) / per);
}

bool stream_fits(uint16_t mask, uint32_t period_ms, uint32_t baud)
{
	return stream_fits_bytes(stream_frame_bytes(mask), period_ms, baud);
}

uint32_t stream_min_period_ms(uint16_t mask, uint32_t baud)
{
	return mask ? stream_min_period_bytes(stream_frame_bytes(mask), baud) : 0;
}

/* ---- reading the unit ---------------------------------------------------- */

/* ---- fields ---------------------------------------------------------------- */

int64_t stream_get(const stream_sample_t *s, const stream_field_t *f)
{
	const uint8_t *p = (const uint8_t *)s + f->at;

	switch (f->type) {
	case STREAM_T_I16: {
		int16_t x;
		memcpy(&x, p, sizeof(x));
		return x;
	}
	case STREAM_T_I32: {
		int32_t x;
		memcpy(&x, p, sizeof(x));
		return x;
	}
	case STREAM_T_U8:
		return *p;
	case STREAM_T_U16: {
		uint16_t x;
		memcpy(&x, p, sizeof(x));
		return x;
	}
	default: {
		uint32_t x;
		memcpy(&x, p, sizeof(x));
		return x;
	}
	}
}

void stream_set(stream_sample_t *s, const stream_field_t *f, int64_t val)
{
	uint8_t *p = (uint8_t *)s + f->at;

	switch (f->type) {
	case STREAM_T_I16: {
		int16_t x = (int16_t)val;
		memcpy(p, &x, sizeof(x));
		break;
	}
	case STREAM_T_I32: {
		int32_t x = (int32_t)val;
		memcpy(p, &x, sizeof(x));
		break;
	}
	case STREAM_T_U8:
		*p = (uint8_t)val;
		break;
	case STREAM_T_U16: {
		uint16_t x = (uint16_t)val;
		memcpy(p, &x, sizeof(x));
		break;
	}
	default: {
		uint32_t x = (uint32_t)val;
		memcpy(p, &x, sizeof(x));
		break;
	}
	}
}

/* Little-endian, the field's width (4 bytes at most). */
static void put_le(uint8_t *p, int64_t val, size_t n)
{
	uint32_t u = (uint32_t)val;

	for (size_t i = 0; i < n; i++, u >>= 8)
		p[i] = (uint8_t)u;
}

static int64_t get_le(const uint8_t *p, unsigned type)
{
	size_t n = stream_type_size(type);
	uint64_t u = 0;

	for (size_t i = 0; i < n; i++)
		u |= (uint64_t)p[i] << (8u * i);
	if (type == STREAM_T_I16)
		return (int16_t)(uint16_t)u;
	if (type == STREAM_T_I32)
		return (int32_t)(uint32_t)u;
	return (int64_t)u;
}

/* ---- serial ---------------------------------------------------------------- */

/* The rows of mask's groups in the serial order, by group, then as listed:
 * from r = {0, 0}, the next row, NULL after the last. */
typedef struct {
	unsigned g, i;
} rows_t;

static const stream_field_t *next_row(rows_t *r, uint16_t mask)
{
	for (; r->g < STREAM_GROUPS; r->g++, r->i = 0) {
		if (!(mask & (1u << r->g)))
			continue;
		while (r->i < stream_field_count) {
			const stream_field_t *f = &stream_fields[r->i++];

			if (f->group == r->g)
				return f;
		}
	}
	return NULL;
}

size_t stream_encode(const stream_sample_t *s, uint16_t mask, uint32_t tick, uint8_t *out,
		     size_t cap)
{
	size_t n = STREAM_HDR;
	rows_t r = {0, 0};
	const stream_field_t *f;

	if (cap < stream_payload_len(mask))
		return 0;
	wire_put_u16(out, mask);
	wire_put_u32(out + 2, tick);
	while ((f = next_row(&r, mask)) != NULL) {
		size_t w = stream_type_size(f->type);

		put_le(out + n, stream_get(s, f), w);
		n += w;
	}
	return n;
}

int stream_decode(const uint8_t *p, size_t len, uint16_t *mask, uint32_t *tick, stream_sample_t *s)
{
	size_t n = STREAM_HDR;
	rows_t r = {0, 0};
	const stream_field_t *f;
	uint16_t m;

	if (len < STREAM_HDR)
		return -1;
	m = wire_get_u16(p);
	if ((m & ~STREAM_MASK_ALL) || len != stream_payload_len(m))
		return -1;
	*mask = m;
	*tick = wire_get_u32(p + 2);
	while ((f = next_row(&r, m)) != NULL) {
		stream_set(s, f, get_le(p + n, f->type));
		n += stream_type_size(f->type);
	}
	return 0;
}

/* " name v" at out + n, v in decimal (every field fits 32 bits), as far as
 * cap holds it with a NUL after; the length the line would have. A line's
 * fields without the general formatter: a few times cheaper on a board. */
static size_t put_field(char *out, size_t n, size_t cap, const char *name, int64_t v)
{
	char b[13];
	size_t k = sizeof(b);
	uint32_t u = (uint32_t)(v < 0 ? -v : v);

	do {
		b[--k] = (char)('0' + u % 10u);
		u /= 10u;
	} while (u);
	if (v < 0)
		b[--k] = '-';
	b[--k] = ' ';
	if (n + 1 < cap)
		out[n] = ' ';
	for (n++; *name; name++, n++)
		if (n + 1 < cap)
			out[n] = *name;
	for (; k < sizeof(b); k++, n++)
		if (n + 1 < cap)
			out[n] = b[k];
	return n;
}

size_t stream_text(const stream_sample_t *s, uint16_t mask, uint8_t seq, uint32_t tick, char *out,
		   size_t cap)
{
	size_t n = fmt_print(out, cap, "~stream %u %lu", (unsigned)seq, (unsigned long)tick);
	rows_t r = {0, 0};
	const stream_field_t *f;

	while ((f = next_row(&r, mask)) != NULL)
		n = put_field(out, n, cap, f->name, stream_get(s, f));
	if (n + 1u >= cap)
		return 0;
	out[n++] = '\n';
	out[n] = '\0';
	return n;
}

/* ---- CAN ------------------------------------------------------------------- */

void stream_can_put(const stream_sample_t *s, unsigned which, uint8_t data[8])
{
	memset(data, 0, 8);
	if (which == 0)
		data[STREAM_CAN_COUNTER_AT] = s->counter;
	for (unsigned i = 0; i < stream_field_count; i++) {
		const stream_field_t *f = &stream_fields[i];

		if (f->can_frame == which)
			put_le(data + f->can_offset, stream_get(s, f), stream_type_size(f->type));
	}
}

void stream_can_get(const uint8_t data[8], unsigned which, stream_sample_t *s)
{
	if (which == 0)
		s->counter = data[STREAM_CAN_COUNTER_AT];
	for (unsigned i = 0; i < stream_field_count; i++) {
		const stream_field_t *f = &stream_fields[i];

		if (f->can_frame == which)
			stream_set(s, f, get_le(data + f->can_offset, f->type));
	}
}

/* ---- subscription ---------------------------------------------------------- */

void stream_sub_init(stream_sub_t *ss, uint32_t baud)
{
	memset(ss, 0, sizeof(*ss));
	ss->baud = baud ? baud : STREAM_BAUD;
}

int stream_start(stream_sub_t *ss, uint32_t tick_hz, uint32_t now_tick, uint16_t mask,
		 uint16_t period, bool text)
{
	uint32_t ticks = 0;

	if (mask) {
		/* A period of whole ticks, at least one. */
		uint32_t t = (uint32_t)period * tick_hz;

		ticks = t / 1000u;
		if ((mask & ~STREAM_MASK_ALL) || !ticks || t % 1000u)
			return WIRE_ST_VALUE;
		if (!stream_fits_bytes(text ? stream_text_bytes(mask) : stream_frame_bytes(mask),
				       period, ss->baud))
			return WIRE_ST_RATE;
	} else {
		period = 0;
		text = false;
	}
	ss->mask = mask;
	ss->period_ms = period;
	ss->period_ticks = ticks;
	ss->text = text;
	/* The first frame at the end of the next tick. */
	ss->next_tick = now_tick + 1u;
	ss->seq = 0;
	ss->sent = ss->skipped = 0;
	return WIRE_ST_OK;
}

size_t stream_subscribe(stream_sub_t *ss, uint32_t tick_hz, uint32_t now_tick, const uint8_t *p,
			size_t len, uint8_t *resp, int *st)
{
	uint16_t mask, period;

	*st = WIRE_ST_OK;
	if (len != STREAM_REQ_LEN) {
		*st = WIRE_ST_LENGTH;
		return 0;
	}
	mask = wire_get_u16(p);
	period = wire_get_u16(p + 2);
	*st = stream_start(ss, tick_hz, now_tick, mask, period, false);
	if (*st != WIRE_ST_OK)
		return 0;
	period = ss->period_ms;
	wire_put_u16(resp, mask);
	wire_put_u16(resp + 2, period);
	wire_put_u16(resp + 4, (uint16_t)(mask ? stream_frame_bytes(mask) : 0));
	wire_put_u16(resp + 6, (uint16_t)stream_min_period_ms(mask, ss->baud));
	wire_put_u16(resp + 8, (uint16_t)tick_hz);
	return STREAM_RESP_LEN;
}

bool stream_due(stream_sub_t *ss, uint32_t now_tick)
{
	uint32_t late;

	if (!ss->mask || (int32_t)(now_tick - ss->next_tick) < 0)
		return false;
	/* Slots passed without a poll: skipped, their numbers too. */
	late = (now_tick - ss->next_tick) / ss->period_ticks;
	ss->seq = (uint8_t)(ss->seq + late);
	ss->skipped += late;
	ss->next_tick += (late + 1u) * ss->period_ticks;
	return true;
}
