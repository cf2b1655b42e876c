/* Lateness of a 1 kHz control loop on Linux.
 *
 *   looplat [SECONDS]     (default 60)
 *
 * The loop sleeps with clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME) to
 * each period's start, then runs vehicle_tick on the loopback plant while
 * the unit drives the 10-waypoint cruise route over and over. Lateness is
 * wake-up time minus the period's start. An overrun is a tick that ended
 * after the next period had begun; periods missed entirely are counted as
 * overruns too and skipped. The firmware is handed the scheduled time, so
 * its own overrun fault does not stop the unit mid-measurement.
 * SCHED_FIFO (priority 80) and mlockall are used when permitted; the
 * report says which.
 */
#include <errno.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <time.h>

#include "rig.h"

#define PERIOD_NS 1000000LL

static rig_t rig;

static long long ts_ns(const struct timespec *t)
{
	return t->tv_sec * 1000000000LL + t->tv_nsec;
}

static int cmp_ll(const void *a, const void *b)
{
	long long x = *(const long long *)a, y = *(const long long *)b;
	return x < y ? -1 : x > y;
}

static void queue_route(void)
{
	for (int i = 0; i < ROUTE_N; i++)
		vs_moveCruiseAbs(&rig.v, (vs_point_t){route_mm[i][0], route_mm[i][1]});
}

int main(int argc, char **argv)
{
	char *end = NULL;
	double secs = argc > 1 ? strtod(argv[1], &end) : 60.0;
	if (!(secs >= 1.0 && secs <= 3600.0) || (end && *end != '\0')) {
		fprintf(stderr, "usage: looplat [SECONDS 1..3600]\n");
		return 2;
	}
	long long n = (long long)(secs * 1e9 / PERIOD_NS);
	long long *late = malloc((size_t)n * sizeof *late);
	if (!late) {
		fprintf(stderr, "looplat: out of memory\n");
		return 2;
	}

	struct sched_param sp = {.sched_priority = 80};
	bool fifo = sched_setscheduler(0, SCHED_FIFO, &sp) == 0;
	bool locked = mlockall(MCL_CURRENT | MCL_FUTURE) == 0;

	rig_init(&rig);
	queue_route();

	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	long long start = ts_ns(&t) + 10 * PERIOD_NS, next = start;
	long long overruns = 0, missed = 0, got = 0, exec_max = 0;
	uint32_t sched_us = 1000000u;
	while (got < n) {
		struct timespec dl = {(time_t)(next / 1000000000LL), (long)(next % 1000000000LL)};
		while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &dl, NULL) == EINTR)
			;
		clock_gettime(CLOCK_MONOTONIC, &t);
		long long woke = ts_ns(&t);
		late[got++] = woke - next;

		sched_us += 1000u;
		vehicle_tick(&rig.v, sched_us);
		if (!motion_has_work(&rig.v.motion))
			queue_route();

		clock_gettime(CLOCK_MONOTONIC, &t);
		long long done = ts_ns(&t);
		if (done - woke > exec_max)
			exec_max = done - woke;
		next += PERIOD_NS;
		if (done > next) {
			overruns++;
			/* Skip the periods that are already over. */
			while (done > next + PERIOD_NS) {
				next += PERIOD_NS;
				missed++;
			}
		}
	}
	qsort(late, (size_t)got, sizeof *late, cmp_ll);
#define PCT(p) (late[(size_t)((double)(got - 1) * (p))] / 1000.0)
	printf("1 kHz loop, %.0f s, %lld ticks; SCHED_FIFO %s, mlockall %s\n", secs, got,
	       fifo ? "yes (prio 80)" : "no (not permitted: SCHED_OTHER)", locked ? "yes" : "no");
	printf("  lateness us: p50 %.1f  p99 %.1f  p99.9 %.1f  max %.1f\n", PCT(0.5), PCT(0.99),
	       PCT(0.999), late[got - 1] / 1000.0);
	printf("  overruns (tick ended after the next period began): %lld, periods skipped: %lld\n",
	       overruns + missed, missed);
	printf("  longest tick, wall clock: %.1f us\n", exec_max / 1000.0);
	free(late);
	return 0;
}
