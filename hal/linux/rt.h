/* vehicle-fw's process environment: log sink, real-time scheduling and the
 * periodic loop's timing statistics. */
#ifndef HAL_LINUX_RT_H
#define HAL_LINUX_RT_H

#include <stdbool.h>
#include <stdint.h>
#include <syslog.h>
#include <time.h>

/* Logs to stderr ("vehicle-fw: ..." lines) or syslog (LOG_DAEMON). */
void rt_log_open(bool use_syslog);
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

void ts_add_ns(struct timespec *t, long long ns);
long long ts_diff_ns(const struct timespec *a, const struct timespec *b); /* a - b */

#endif
