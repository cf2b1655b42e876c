/* Little-endian encoding of command-table arguments and the generic binary
 * dispatcher (see wire.h for the layouts). */
#include "wire.h"

#include <string.h>

#include "numparse.h"

static const char *const status_names[WIRE_ST_COUNT] = {
    "ok", "crc", "oversize", "length", "opcode", "value", "truncated", "space", "rate",
};

const char *wire_status_name(int st)
{
	if (st < 0 || st >= WIRE_ST_COUNT)
		return "unknown";
	return status_names[st];
}

#if defined(__ARM_FEATURE_UNALIGNED) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
/* A little-endian core that loads and stores at any address (a Cortex-M4):
 * the wire's order is its own, one halfword or word access rather than a
 * byte at a time at each of the many places these are inlined. */
void wire_put_u16(uint8_t *p, uint16_t v)
{
	memcpy(p, &v, sizeof v);
}

void wire_put_u32(uint8_t *p, uint32_t v)
{
	memcpy(p, &v, sizeof v);
}

uint16_t wire_get_u16(const uint8_t *p)
{
	uint16_t v;

	memcpy(&v, p, sizeof v);
	return v;
}

uint32_t wire_get_u32(const uint8_t *p)
{
	uint32_t v;

	memcpy(&v, p, sizeof v);
	return v;
}
#else
void wire_put_u16(uint8_t *p, uint16_t v)
{
	p[0] = (uint8_t)(v & 0xFFu);
	p[1] = (uint8_t)(v >> 8);
}

void wire_put_u32(uint8_t *p, uint32_t v)
{
	for (int i = 0; i < 4; i++)
		p[i] = (uint8_t)((v >> (8 * i)) & 0xFFu);
}

uint16_t wire_get_u16(const uint8_t *p)
{
	return (uint16_t)(p[0] | (unsigned)p[1] << 8);
}

uint32_t wire_get_u32(const uint8_t *p)
{
	return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}
#endif

/* The n low bytes of v, little-endian. */
static void put_u64(uint8_t *p, uint64_t v, unsigned n)
{
	for (unsigned i = 0; i < n; i++, v >>= 8)
		p[i] = (uint8_t)(v & 0xFFu);
}

/* n bytes, little-endian. */
static uint64_t get_u64(const uint8_t *p, unsigned n)
{
	uint64_t v = 0;

	while (n--)
		v = v << 8 | p[n];
	return v;
}

/* Output cursor: every put checks room first, so a short buffer never gets
 * a partial field. */
typedef struct {
	uint8_t *buf;
	size_t cap, len;
} wout_t;

static bool room(const wout_t *o, size_t n)
{
	return o->cap - o->len >= n;
}

static int put_str(wout_t *o, const char *s, size_t max)
{
	size_t n = s ? strlen(s) : 0;

	if (n > max)
		return WIRE_ST_VALUE;
	if (!room(o, 1 + n))
		return WIRE_ST_SPACE;
	o->buf[o->len++] = (uint8_t)n;
	if (n)
		memcpy(o->buf + o->len, s, n);
	o->len += n;
	return WIRE_ST_OK;
}

/* The bytes of a scalar type on the wire; 0 for a string or a sequence. */
static unsigned scalar_size(char type)
{
	switch (type) {
	case CMD_T_BOOL:
		return 1;
	case CMD_T_SHORT:
		return 2;
	case CMD_T_ULONG:
		return 4;
	case CMD_T_DOUBLE:
		return 8;
	default:
		return 0;
	}
}

static int put_value(wout_t *o, char type, const cmd_value_t *v)
{
	unsigned sz = scalar_size(type);

	if (sz) {
		/* Every scalar little-endian in its sz bytes: one store loop
		 * (a board's flash). */
		uint64_t bits;

		if (!room(o, sz))
			return WIRE_ST_SPACE;
		if (type == CMD_T_BOOL)
			bits = v->b ? 1 : 0;
		else if (type == CMD_T_SHORT)
			bits = (uint16_t)v->h;
		else if (type == CMD_T_ULONG)
			bits = v->u;
		else
#ifdef VS_REAL_Q32
			bits = np_q32_to_ieee(v->d);
#else
			memcpy(&bits, &v->d, sizeof(bits));
#endif
		put_u64(o->buf + o->len, bits, sz);
		o->len += sz;
		return WIRE_ST_OK;
	}
	switch (type) {
	case CMD_T_STRING:
		return put_str(o, v->s, WIRE_STR_MAX);
	case CMD_T_ALARMS: {
		uint16_t n = v->alarms.n;

		if (n > VS_ALARM_LIST_MAX || (n && !v->alarms.a))
			return WIRE_ST_VALUE;
		if (!room(o, 1))
			return WIRE_ST_SPACE;
		o->buf[o->len++] = (uint8_t)n;
		for (uint16_t i = 0; i < n; i++) {
			const vs_alarm_t *a = &v->alarms.a[i];
			char src[VS_ALARM_SOURCE_MAX];
			int st;

			if (!room(o, 5))
				return WIRE_ST_SPACE;
			wire_put_u32(o->buf + o->len, a->code);
			o->buf[o->len + 4] = a->type;
			o->len += 5;
			/* The unit's buffer may lack a terminator; never read past it. */
			memcpy(src, a->source, sizeof(src));
			src[sizeof(src) - 1] = '\0';
			st = put_str(o, src, VS_ALARM_SOURCE_MAX - 1);
			if (st != WIRE_ST_OK)
				return st;
		}
		return WIRE_ST_OK;
	}
	default:
		return WIRE_ST_VALUE;
	}
}

int wire_encode(const char *types, unsigned n, const cmd_value_t v[], uint8_t *buf, size_t cap,
		size_t *len)
{
	wout_t o = {buf, cap, 0};

	for (unsigned i = 0; i < n; i++) {
		int st = put_value(&o, types[i], &v[i]);

		if (st != WIRE_ST_OK)
			return st;
	}
	*len = o.len;
	return WIRE_ST_OK;
}

typedef struct {
	const uint8_t *buf;
	size_t len, pos;
} win_t;

static bool avail(const win_t *in, size_t n)
{
	return in->len - in->pos >= n;
}

/* Copies a length-prefixed string into dst (room for max + 1). Inline: a
 * unit decodes requests only, without strings (wire_dispatch), and its
 * copies then go with the paths that call them; out of line, the body
 * stayed in a board's image uncalled. */
static inline __attribute__((always_inline)) int get_str(win_t *in, char *dst, size_t max)
{
	size_t n;

	if (!avail(in, 1))
		return WIRE_ST_LENGTH;
	n = in->buf[in->pos];
	if (n > max)
		return WIRE_ST_VALUE;
	if (!avail(in, 1 + n))
		return WIRE_ST_LENGTH;
	if (memchr(in->buf + in->pos + 1, 0, n))
		return WIRE_ST_VALUE;
	memcpy(dst, in->buf + in->pos + 1, n);
	dst[n] = '\0';
	in->pos += 1 + n;
	return WIRE_ST_OK;
}

static int get_value(win_t *in, char type, cmd_value_t *v, unsigned field, wire_store_t *st)
{
	unsigned sz = scalar_size(type);

	if (sz) {
		uint64_t bits;

		if (!avail(in, sz))
			return WIRE_ST_LENGTH;
		bits = get_u64(in->buf + in->pos, sz);
		if (type == CMD_T_BOOL) {
			if (bits > 1)
				return WIRE_ST_VALUE;
			v->b = bits == 1;
		} else if (type == CMD_T_SHORT) {
			v->h = (int16_t)(uint16_t)bits;
		} else if (type == CMD_T_ULONG) {
			v->u = (uint32_t)bits;
		} else {
#ifdef VS_REAL_Q32
			v->d = np_q32_from_ieee(bits);
#else
			memcpy(&v->d, &bits, sizeof(bits));
#endif
		}
		in->pos += sz;
		return WIRE_ST_OK;
	}
	switch (type) {
	case CMD_T_STRING: {
		int r;

		if (!st)
			return WIRE_ST_VALUE;
		r = get_str(in, st->str[field], WIRE_STR_MAX);

		v->s = st->str[field];
		return r;
	}
	case CMD_T_ALARMS: {
		uint8_t n;

		if (!st)
			return WIRE_ST_VALUE;
		if (!avail(in, 1))
			return WIRE_ST_LENGTH;
		n = in->buf[in->pos++];
		if (n > VS_ALARM_LIST_MAX)
			return WIRE_ST_VALUE;
		v->alarms.a = st->alarms;
		v->alarms.n = 0;
		for (uint8_t i = 0; i < n; i++) {
			vs_alarm_t *a = &st->alarms[i];
			int r;

			if (!avail(in, 5))
				return WIRE_ST_LENGTH;
			memset(a, 0, sizeof(*a));
			a->code = wire_get_u32(in->buf + in->pos);
			a->type = in->buf[in->pos + 4];
			in->pos += 5;
			r = get_str(in, a->source, VS_ALARM_SOURCE_MAX - 1);
			if (r != WIRE_ST_OK)
				return r;
			v->alarms.n = (uint16_t)(i + 1);
		}
		return WIRE_ST_OK;
	}
	default:
		return WIRE_ST_VALUE;
	}
}

int wire_decode(const char *types, unsigned n, const uint8_t *buf, size_t len, cmd_value_t v[],
		wire_store_t *st)
{
	win_t in = {buf, len, 0};

	if (n > CMD_MAX_FIELDS)
		return WIRE_ST_VALUE;
	for (unsigned i = 0; i < n; i++) {
		int r;

		memset(&v[i], 0, sizeof(v[i]));
		r = get_value(&in, types[i], &v[i], i, st);
		if (r != WIRE_ST_OK)
			return r;
	}
	return in.pos == len ? WIRE_ST_OK : WIRE_ST_LENGTH;
}

int wire_encode_request(const cmd_def_t *d, const cmd_value_t in[], uint8_t *buf, size_t cap,
			size_t *len)
{
	return wire_encode(d->in_types, d->n_in, in, buf, cap, len);
}

int wire_decode_request(const cmd_def_t *d, const uint8_t *buf, size_t len, cmd_value_t in[],
			wire_store_t *st)
{
	return wire_decode(d->in_types, d->n_in, buf, len, in, st);
}

int wire_encode_response(const cmd_def_t *d, bool result, const cmd_value_t out[], uint8_t *buf,
			 size_t cap, size_t *len)
{
	size_t n = 0;
	int st;

	if (cap < 1)
		return WIRE_ST_SPACE;
	buf[0] = result ? 1 : 0;
	st = wire_encode(d->out_types, d->n_out, out, buf + 1, cap - 1, &n);
	if (st == WIRE_ST_OK)
		*len = n + 1;
	return st;
}

int wire_decode_response(const cmd_def_t *d, const uint8_t *buf, size_t len, bool *result,
			 cmd_value_t out[], wire_store_t *st)
{
	if (len < 1)
		return WIRE_ST_LENGTH;
	if (buf[0] > 1)
		return WIRE_ST_VALUE;
	*result = buf[0] == 1;
	return wire_decode(d->out_types, d->n_out, buf + 1, len - 1, out, st);
}

size_t wire_info(uint8_t *buf)
{
	buf[0] = CMD_PROTO_VERSION;
	wire_put_u16(buf + 1, cmd_table_crc());
	buf[3] = CMD_COUNT;
	wire_put_u16(buf + 4, WIRE_REQ_MAX);
	wire_put_u16(buf + 6, WIRE_RESP_MAX);
	return WIRE_INFO_LEN;
}
