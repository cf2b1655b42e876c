/* Alarm list: newest first, bounded, one entry per code. */
#include <stddef.h>

#include "alarm.h"

void alarm_clear(alarm_list_t *l)
{
	l->n = 0;
}

vs_alarm_type_t alarm_type_of(uint32_t code)
{
	if (code >= 100 && code <= 199)
		return VS_ALARM_WARNING;
	if (code >= 200 && code <= 299)
		return VS_ALARM_FAULT;
	return VS_ALARM_UNKNOWN;
}

void alarm_raise(alarm_list_t *l, uint32_t code, const char *source)
{
	/* Slot to vacate: the code's own entry if active, else the oldest
	 * (or one past the end when there is room). */
	unsigned last = l->n;
	for (unsigned i = 0; i < l->n; i++) {
		if (l->a[i].code == code) {
			last = i;
			break;
		}
	}
	if (last == l->n) {
		if (l->n < VS_ALARM_LIST_MAX)
			l->n++;
		else
			last = VS_ALARM_LIST_MAX - 1;
	}
	/* Whole entries: a copy field by field and byte by byte took more
	 * flash than the call of the copy. */
	for (unsigned i = last; i > 0; i--)
		l->a[i] = l->a[i - 1];

	vs_alarm_t *a = &l->a[0];
	a->code = code;
	a->type = (uint8_t)alarm_type_of(code);
	unsigned k = 0;
	if (source) {
		while (k < VS_ALARM_SOURCE_MAX - 1 && source[k] != '\0') {
			a->source[k] = source[k];
			k++;
		}
	}
	a->source[k] = '\0';
}

bool alarm_any_fault(const alarm_list_t *l)
{
	return alarm_newest(l, VS_ALARM_FAULT) != NULL;
}

const vs_alarm_t *alarm_newest(const alarm_list_t *l, vs_alarm_type_t type)
{
	for (unsigned i = 0; i < l->n; i++) {
		if (l->a[i].type == (uint8_t)type)
			return &l->a[i];
	}
	return NULL;
}
