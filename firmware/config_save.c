/* The configuration's saved form (config_save.h). */
#include "config_save.h"

#include "cfgstore.h"

uint8_t vs_config_type_size(uint8_t type)
{
	switch (type) {
	case VS_CFG_DOUBLE:
		return (uint8_t)sizeof(vs_real_t);
	case VS_CFG_U32:
		return 4;
	case VS_CFG_U16:
		return 2;
	case VS_CFG_BOOL:
		return (uint8_t)sizeof(bool);
	default:
		return (uint8_t)sizeof(vs_kinematics_t);
	}
}

static size_t name_len(const char *s)
{
	size_t n = 0;
	while (s[n])
		n++;
	return n;
}

/* Worked out once (cfgkeep_load asks at start): a bitwise CRC over the
 * table's names costs a board 2.5 ms, more than a period, in every
 * $config store and $diag that shows it. */
uint32_t vs_config_schema(void)
{
	static uint32_t schema;
	static bool known;
	if (known)
		return schema;
	uint32_t crc = 0;
	for (unsigned i = 0; i < VS_CONFIG_NFIELDS; i++) {
		const vs_config_field_t *f = &vs_config_fields[i];
		uint8_t tn[2] = {f->type, f->n};
		crc = cfgstore_crc32(crc, f->name, (uint32_t)name_len(f->name));
		crc = cfgstore_crc32(crc, tn, 2);
	}
	schema = crc;
	known = true;
	return crc;
}

static bool same_bytes(const uint8_t *a, const uint8_t *b, size_t n)
{
	for (size_t i = 0; i < n; i++)
		if (a[i] != b[i])
			return false;
	return true;
}

size_t vs_config_encode(const void *cur, const void *base, uint8_t *buf, size_t cap)
{
	if (cap < 4)
		return 0;
	size_t pos = 4;
	uint16_t count = 0;
	for (unsigned i = 0; i < VS_CONFIG_NFIELDS; i++) {
		const vs_config_field_t *f = &vs_config_fields[i];
		uint8_t sz = vs_config_type_size(f->type);
		size_t nl = name_len(f->name);
		for (uint8_t k = 0; k < f->n; k++) {
			const uint8_t *a = (const uint8_t *)cur + f->off + (size_t)k * sz;
			const uint8_t *b = (const uint8_t *)base + f->off + (size_t)k * sz;
			if (same_bytes(a, b, sz))
				continue;
			if (nl > 255 || pos + 1 + nl + 3 + sz > cap)
				return 0;
			buf[pos++] = (uint8_t)nl;
			for (size_t j = 0; j < nl; j++)
				buf[pos++] = (uint8_t)f->name[j];
			buf[pos++] = k;
			buf[pos++] = f->type;
			buf[pos++] = sz;
			for (uint8_t j = 0; j < sz; j++)
				buf[pos++] = a[j];
			count++;
		}
	}
	buf[0] = VS_CFGSAVE_VERSION;
	buf[1] = VS_CFGSAVE_FORMAT;
	buf[2] = (uint8_t)count;
	buf[3] = (uint8_t)(count >> 8);
	return pos;
}

static const vs_config_field_t *find(const uint8_t *name, size_t nl)
{
	for (unsigned i = 0; i < VS_CONFIG_NFIELDS; i++) {
		const char *s = vs_config_fields[i].name;
		if (name_len(s) == nl && same_bytes((const uint8_t *)s, name, nl))
			return &vs_config_fields[i];
	}
	return NULL;
}

/* One pass: check (apply false) or apply. */
static vs_config_decode_status_t walk(vs_config_t *out, const uint8_t *buf, size_t len,
				      vs_config_decode_t *info, bool apply)
{
	uint16_t count = (uint16_t)(buf[2] | buf[3] << 8);
	size_t pos = 4;
	info->applied = info->dropped = 0;
	for (uint16_t e = 0; e < count; e++) {
		if (pos >= len)
			return VS_CFGSAVE_MALFORMED;
		size_t nl = buf[pos++];
		if (len - pos < nl + 3)
			return VS_CFGSAVE_MALFORMED;
		const uint8_t *name = buf + pos;
		pos += nl;
		uint8_t k = buf[pos], type = buf[pos + 1], sz = buf[pos + 2];
		pos += 3;
		if (len - pos < sz)
			return VS_CFGSAVE_MALFORMED;
		const vs_config_field_t *f = find(name, nl);
		/* A boolean is one byte, 0 or 1: no other value is read into
		 * a bool. */
		bool bad_bool = type == VS_CFG_BOOL && sz == 1 && buf[pos] > 1;
		if (!f || f->type != type || k >= f->n || sz != vs_config_type_size(type) ||
		    bad_bool) {
			info->dropped++;
		} else {
			if (apply) {
				uint8_t *d = (uint8_t *)out + f->off + (size_t)k * sz;
				for (uint8_t j = 0; j < sz; j++)
					d[j] = buf[pos + j];
			}
			info->applied++;
		}
		pos += sz;
	}
	return pos == len ? VS_CFGSAVE_OK : VS_CFGSAVE_MALFORMED;
}

vs_config_decode_status_t vs_config_decode(vs_config_t *out, const uint8_t *buf, size_t len,
					   vs_config_decode_t *info)
{
	vs_config_decode_t dummy;
	if (!info)
		info = &dummy;
	info->applied = info->dropped = 0;
	if (len < 4)
		return VS_CFGSAVE_MALFORMED;
	if (buf[0] != VS_CFGSAVE_VERSION || buf[1] != VS_CFGSAVE_FORMAT)
		return VS_CFGSAVE_FOREIGN;
	vs_config_decode_status_t st = walk(out, buf, len, info, false);
	if (st != VS_CFGSAVE_OK)
		return st;
	return walk(out, buf, len, info, true);
}
