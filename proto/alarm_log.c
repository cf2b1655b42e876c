/* Alarm events from two looks at the unit's alarm list; see alarm_log.h. */
#include "alarm_log.h"

#include <string.h>

#include "fmt.h"

void alarm_log_init(alarm_log_t *l)
{
	memset(l, 0, sizeof(*l));
}

static bool same_alarm(const vs_alarm_t *a, const vs_alarm_t *b)
{
	return a->code == b->code && a->type == b->type && strcmp(a->source, b->source) == 0;
}

static bool has_code(const vs_alarm_t *a, unsigned n, uint32_t code)
{
	for (unsigned i = 0; i < n; i++)
		if (a[i].code == code)
			return true;
	return false;
}

/* Whether now[p..] is what the old list becomes once now[0..p) are raised
 * on it: the old entries whose codes those did not take, in order, cut to
 * the list's length (alarm_raise moves or inserts at the front). */
static bool rest_is_old(const alarm_list_t *old, const alarm_list_t *now, unsigned p)
{
	unsigned k = p;

	for (unsigned i = 0; i < old->n && k < now->n; i++) {
		if (has_code(now->a, p, old->a[i].code))
			continue;
		if (!same_alarm(&old->a[i], &now->a[k]))
			return false;
		k++;
	}
	return k == now->n;
}

static const char *type_name(uint8_t t)
{
	return t == VS_ALARM_FAULT ? "fault" : t == VS_ALARM_WARNING ? "warning" : "unknown";
}

void alarm_log_format(char *buf, size_t cap, const char *what, const vs_alarm_t *a, uint64_t t_us)
{
	/* The source quoted as the console writes strings (docs/console.md). */
	char src[4 * VS_ALARM_SOURCE_MAX + 1];
	size_t k = 0;

	for (const unsigned char *s = (const unsigned char *)a->source;
	     *s && s < (const unsigned char *)a->source + VS_ALARM_SOURCE_MAX; s++) {
		if (*s == '"' || *s == '\\') {
			src[k++] = '\\';
			src[k++] = (char)*s;
		} else if (*s < 0x20 || *s > 0x7E) {
			static const char hex[] = "0123456789abcdef";

			src[k++] = '\\';
			src[k++] = 'x';
			src[k++] = hex[*s >> 4];
			src[k++] = hex[*s & 15u];
		} else {
			src[k++] = (char)*s;
		}
	}
	src[k] = '\0';
	fmt_print(buf, cap, "alarm %s %lu %s \"%s\" at %llu.%03llu s", what, (unsigned long)a->code,
		  type_name(a->type), src, (unsigned long long)(t_us / 1000000u),
		  (unsigned long long)(t_us / 1000u % 1000u));
}

unsigned alarm_log_poll(alarm_log_t *l, const alarm_list_t *now, uint64_t t_us, alarm_log_fn fn,
			void *ctx)
{
	const alarm_list_t *old = &l->seen;
	char line[ALARM_LOG_LINE_MAX];
	unsigned p = 0, events = 0;
	bool full = now->n >= VS_ALARM_LIST_MAX;

	if (now->n == old->n && memcmp(now->a, old->a, now->n * sizeof(now->a[0])) == 0)
		return 0;
	/* The fewest raises that explain the new list (p = now->n always does). */
	while (p < now->n && !rest_is_old(old, now, p))
		p++;
	/* each kind oldest first */
	for (unsigned i = old->n; !full && i-- > 0;) {
		if (!has_code(now->a, now->n, old->a[i].code)) {
			alarm_log_format(line, sizeof(line), "cleared", &old->a[i], t_us);
			fn(ctx, line);
			events++;
		}
	}
	for (unsigned i = p; i-- > 0;) {
		alarm_log_format(line, sizeof(line), "raised", &now->a[i], t_us);
		fn(ctx, line);
		events++;
	}
	for (unsigned i = old->n; full && i-- > 0;) {
		if (!has_code(now->a, now->n, old->a[i].code)) {
			alarm_log_format(line, sizeof(line), "dropped", &old->a[i], t_us);
			fn(ctx, line);
			events++;
		}
	}
	l->seen = *now;
	return events;
}
