/* The host programs' process environment (vehicle-fw, vehicle-sim): log
 * sink, real-time scheduling, and the periodic loop's clock and timing
 * statistics. */
#ifndef HAL_POSIX_RT_H
#define HAL_POSIX_RT_H

#include <stdbool.h>
#include <stdint.h>
#include <syslog.h>
#include <time.h>

/* Logs to stderr ("IDENT: ..." lines) or syslog (LOG_DAEMON). */
void rt_log_open(const char *ident, bool use_syslog);
void rt_log(int prio, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

typedef struct {
	bool locked; /* mlockall succeeded */
	bool fifo;   /* SCHED_FIFO granted */
	int priority;
} rt_status_t;

/* mlockall and SCHED_FIFO at prio, each when permitted; a warning naming
 * the missing privilege otherwise. prio 0: stay SCHED_OTHER. */
void rt_setup(int prio, rt_status_t *st);

/* Loop timing: a wake-up later than half a period counts as late; busy is
 * the loop's own CPU time in one period. */
typedef struct {
	uint64_t ticks;
	uint64_t late;
	uint32_t max_late_us;
	uint32_t busy_max_us;
	uint64_t skipped; /* periods dropped after falling far behind */
} rt_stats_t;

/* The loop's schedule: absolute CLOCK_MONOTONIC deadlines one period
 * apart, so that a late wake-up does not shift the ticks after it. */
typedef struct {
	struct timespec t0, next;
	uint32_t period_us;
} rt_clock_t;

/* Far behind (stopped in a debugger, host stalled): the schedule restarts
 * from now instead of bursting through the missed periods. */
#define RT_SKIP_AFTER_NS 100000000LL

void rt_clock_start(rt_clock_t *c, uint32_t period_us);
/* Microseconds since rt_clock_start (wraps after 71 minutes, as the
 * firmware's clock does). */
uint32_t rt_clock_now_us(const rt_clock_t *c);
/* Sleeps to the next deadline and counts the wake-up in st (NULL: not
 * counted): late when more than half a period after it, skipped periods
 * when more than RT_SKIP_AFTER_NS. */
void rt_clock_wait(rt_clock_t *c, rt_stats_t *st);

void ts_add_ns(struct timespec *t, long long ns);
long long ts_diff_ns(const struct timespec *a, const struct timespec *b); /* a - b */

#endif
