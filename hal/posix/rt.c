/* Log sink, real-time setup and loop timing of the host programs; see rt.h. */
#include "rt.h"

#include <errno.h>
#include <sched.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <sys/mman.h>

static bool log_syslog;
static const char *log_ident = "vehicle-fw"; /* until rt_log_open */

void rt_log_open(const char *ident, bool use_syslog)
{
	log_ident = ident;
	log_syslog = use_syslog;
	if (use_syslog)
		openlog(ident, LOG_PID, LOG_DAEMON);
}

void rt_log(int prio, const char *fmt, ...)
{
	va_list ap;
	va_start(ap, fmt);
	if (log_syslog) {
		vsyslog(prio, fmt, ap);
	} else {
		fprintf(stderr, "%s: ", log_ident);
		if (prio <= LOG_WARNING)
			fputs(prio <= LOG_ERR ? "error: " : "warning: ", stderr);
		vfprintf(stderr, fmt, ap);
		fputc('\n', stderr);
	}
	va_end(ap);
}

void rt_setup(int prio, rt_status_t *st)
{
	memset(st, 0, sizeof(*st));
	if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0)
		st->locked = true;
	else
		rt_log(LOG_WARNING,
		       "mlockall: %s; memory not locked, page faults may delay ticks "
		       "(needs CAP_IPC_LOCK or LimitMEMLOCK=infinity)",
		       strerror(errno));
	if (prio <= 0)
		return;
	struct sched_param sp = {.sched_priority = prio};
	if (sched_setscheduler(0, SCHED_FIFO, &sp) == 0) {
		st->fifo = true;
		st->priority = prio;
	} else {
		rt_log(LOG_WARNING,
		       "SCHED_FIFO priority %d: %s; running as a normal process, ticks may be late "
		       "(needs CAP_SYS_NICE or an rtprio limit)",
		       prio, strerror(errno));
	}
}

void ts_add_ns(struct timespec *t, long long ns)
{
	long long v = (long long)t->tv_nsec + ns;
	t->tv_sec += (time_t)(v / 1000000000LL);
	t->tv_nsec = (long)(v % 1000000000LL);
	if (t->tv_nsec < 0) {
		t->tv_nsec += 1000000000L;
		t->tv_sec--;
	}
}

long long ts_diff_ns(const struct timespec *a, const struct timespec *b)
{
	return (long long)(a->tv_sec - b->tv_sec) * 1000000000LL + (a->tv_nsec - b->tv_nsec);
}

void rt_clock_start(rt_clock_t *c, uint32_t period_us)
{
	c->period_us = period_us;
	clock_gettime(CLOCK_MONOTONIC, &c->t0);
	c->next = c->t0;
}

uint32_t rt_clock_now_us(const rt_clock_t *c)
{
	struct timespec t;

	clock_gettime(CLOCK_MONOTONIC, &t);
	return (uint32_t)((unsigned long long)ts_diff_ns(&t, &c->t0) / 1000ull);
}

void rt_clock_wait(rt_clock_t *c, rt_stats_t *st)
{
	struct timespec now;

	ts_add_ns(&c->next, (long long)c->period_us * 1000LL);
	while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &c->next, NULL) == EINTR)
		;
	clock_gettime(CLOCK_MONOTONIC, &now);
	long long late = ts_diff_ns(&now, &c->next);
	if (st && late > (long long)c->period_us * 500LL)
		st->late++;
	if (st && late > 0 && (unsigned long long)late / 1000ull > st->max_late_us)
		st->max_late_us = (uint32_t)((unsigned long long)late / 1000ull);
	if (late > RT_SKIP_AFTER_NS) {
		if (st)
			st->skipped +=
			    (unsigned long long)late / ((unsigned long long)c->period_us * 1000ull);
		c->next = now;
	}
}
