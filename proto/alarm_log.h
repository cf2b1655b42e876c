/* Alarm events for a host program's log (vehicle-sim, vehicle-fw): the unit
 * only keeps a list that a client polls, so a main compares that list with
 * the one it saw last, after every tick and every poll of the links, and
 * logs one line per change (docs/alarms.md, "Alarm events"):
 *
 *   alarm raised 120 warning "moveTurn refused: unit not ready" at 12.345 s
 *   alarm cleared 120 warning "moveTurn refused: unit not ready" at 13.000 s
 *   alarm dropped 110 warning "..." at 14.002 s     (pushed out of a full list)
 *
 * raised: a code not in the list before, or raised again (its text changed,
 * or it moved to the front past others). cleared: gone from a list that is
 * not full (clearAlarm). dropped: gone from a full list, pushed out by newer
 * ones. Within one look, cleared lines come first, then raised, then
 * dropped, each kind oldest first. A code raised again as the newest with the same
 * text, or raised and cleared between two looks, is no change. Host only:
 * nothing of this is in the unit's image.
 */
#ifndef ALARM_LOG_H
#define ALARM_LOG_H

#include <stddef.h>
#include <stdint.h>

#include "../firmware/alarm.h"

/* The longest line: every byte of a source escaped as \xHH. */
#define ALARM_LOG_LINE_MAX (64 + 4 * VS_ALARM_SOURCE_MAX)

typedef void (*alarm_log_fn)(void *ctx, const char *line);

typedef struct {
	alarm_list_t seen; /* the list at the last look */
} alarm_log_t;

/* Starts from an empty list: alarms already active are logged as raised at
 * the first look. */
void alarm_log_init(alarm_log_t *l);
/* Compares now with the list seen last and calls fn once per event with its
 * line (no line ending), t_us being the time to print. Returns the number of
 * events. */
unsigned alarm_log_poll(alarm_log_t *l, const alarm_list_t *now, uint64_t t_us, alarm_log_fn fn,
			void *ctx);
/* One line: what ("raised", "cleared", "dropped"), the alarm, the time. */
void alarm_log_format(char *buf, size_t cap, const char *what, const vs_alarm_t *a, uint64_t t_us);

#endif
