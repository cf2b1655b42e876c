/* Log sink and real-time setup of vehicle-fw; see rt.h. */
#include "rt.h"

#include <errno.h>
#include <sched.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <sys/mman.h>

static bool log_syslog;

void rt_log_open(bool use_syslog)
{
	log_syslog = use_syslog;
	if (use_syslog)
		openlog("vehicle-fw", LOG_PID, LOG_DAEMON);
}

void rt_log(int prio, const char *fmt, ...)
{
	va_list ap;
	va_start(ap, fmt);
	if (log_syslog) {
		vsyslog(prio, fmt, ap);
	} else {
		fputs("vehicle-fw: ", stderr);
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
