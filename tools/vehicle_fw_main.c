/* vehicle-fw: the firmware on the vehicle's Linux computer (docs/linux.md).
 *
 * One thread: every period it reads the clock, advances the backends,
 * runs vehicle_tick() and serves the command link (console and binary
 * frames, proto/link.h) on a serial port, then sleeps to the next absolute
 * deadline with clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME).
 *
 * SIGTERM/SIGINT: the link is no longer served, the unit is stopped with
 * its normal deceleration (bounded), then servo off and power off; exit 0.
 */
#include <errno.h>
#include <fcntl.h>
#include <getopt.h>
#include <signal.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "../hal/config_xml.h"
#include "../hal/linux/backend_cfg.h"
#include "../hal/linux/lhal.h"
#include "../hal/linux/rt.h"
#include "../proto/client.h"
#include "../proto/link.h"
#include "../proto/numparse.h"

#define DEFAULT_CONFIG	"/etc/vehicle/vehicle.xml"
#define DEFAULT_RT_PRIO 80
/* Longest deceleration the shutdown waits for before cutting power. */
#define SHUTDOWN_BOUND_MS 10000u
/* Far behind (host stalled): restart the schedule instead of bursting. */
#define SKIP_AFTER_NS 100000000LL

static volatile sig_atomic_t stop_requested;

static void on_signal(int sig)
{
	(void)sig;
	stop_requested = 1;
}

typedef struct {
	vehicle_t v;
	lhal_t hal;
	vs_hal_t vh;
	console_t con;
	link_t link;
	int in_fd, out_fd;
	uint32_t write_errors;
	rt_status_t rt;
	rt_stats_t st;
	struct timespec t0;
	uint32_t period_us;
} app_t;

static app_t app;

static size_t port_read(void *ctx, uint8_t *buf, size_t max)
{
	app_t *a = ctx;
	ssize_t r = read(a->in_fd, buf, max);
	return r > 0 ? (size_t)r : 0;
}

static size_t port_write(void *ctx, const uint8_t *buf, size_t len)
{
	app_t *a = ctx;
	ssize_t r = write(a->out_fd, buf, len);
	if (r < 0 && errno != EAGAIN && errno != EINTR)
		a->write_errors++;
	return r > 0 ? (size_t)r : 0;
}

static void no_write(void *ctx, const char *s, size_t n)
{
	(void)ctx, (void)s, (void)n; /* replaced by link_init */
}

/* "$rt": the loop's own timing, beside the firmware's "$diag". */
static bool rt_extra(void *ctx, int argc, char **argv, char *reply, size_t cap)
{
	app_t *a = ctx;
	if (argc < 1 || !np_streq_nocase(argv[0], "$rt"))
		return false;
	if (argc != 1) {
		snprintf(reply, cap, "error %d $rt takes 0 arguments, got %d", CONSOLE_E_ARITY,
			 argc - 1);
		return true;
	}
	snprintf(reply, cap,
		 "ok period_us %u ticks %llu late %llu max_late_us %u busy_max_us %u skipped %llu "
		 "sched %s "
		 "prio %d mlock %s gpio_errors %u joystick %s battery_errors %u",
		 a->period_us, (unsigned long long)a->st.ticks, (unsigned long long)a->st.late,
		 a->st.max_late_us, a->st.busy_max_us, (unsigned long long)a->st.skipped,
		 a->rt.fifo ? "fifo" : "other", a->rt.priority, a->rt.locked ? "yes" : "no",
		 a->hal.gpio.errors,
		 !a->hal.bk.joystick.used ? "none"
		 : a->hal.joy.present	  ? "present"
					  : "absent",
		 a->hal.battery_errors);
	/* then one group of counters per CANopen bus */
	for (unsigned b = 0; b < BK_CANOPEN_BUSES; b++) {
		size_t n = strlen(reply);
		if (a->hal.can[b].used && n + 2 < cap) {
			reply[n++] = ' ';
			co_bus_counters(&a->hal.can[b], reply + n, cap - n);
		}
	}
	return true;
}

static uint32_t now_us(const app_t *a)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return (uint32_t)((unsigned long long)ts_diff_ns(&t, &a->t0) / 1000ull);
}

/* This thread's CPU time: what our own work costs, without the time the
 * host gave to other tasks (a preempted tick is late, not over budget). */
static uint64_t cpu_ns(void)
{
	struct timespec t;
	clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
	return (uint64_t)t.tv_sec * 1000000000ull + (uint64_t)t.tv_nsec;
}

static void tick(app_t *a, bool serve_link)
{
	uint64_t c0 = cpu_ns();
	uint32_t us = now_us(a);
	lhal_pre_tick(&a->hal, us);
	vehicle_tick(&a->v, us);
	if (serve_link)
		link_poll(&a->link, us / 1000u);
	a->st.ticks++;
	uint64_t busy = (cpu_ns() - c0) / 1000u;
	uint32_t busy_us = busy > UINT32_MAX ? UINT32_MAX : (uint32_t)busy;
	if (busy_us > a->st.busy_max_us)
		a->st.busy_max_us = busy_us;
	vehicle_tick_busy(&a->v, busy_us);
}

/* Sleeps to the next deadline, counting late wake-ups. */
static void wait_next(app_t *a, struct timespec *next)
{
	struct timespec now;
	ts_add_ns(next, (long long)a->period_us * 1000LL);
	while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, next, NULL) == EINTR)
		;
	clock_gettime(CLOCK_MONOTONIC, &now);
	long long late = ts_diff_ns(&now, next);
	if (late > (long long)a->period_us * 500LL)
		a->st.late++;
	if (late > 0 && (unsigned long long)late / 1000ull > a->st.max_late_us)
		a->st.max_late_us = (uint32_t)((unsigned long long)late / 1000ull);
	if (late > SKIP_AFTER_NS) {
		a->st.skipped +=
		    (unsigned long long)late / ((unsigned long long)a->period_us * 1000ull);
		*next = now;
	}
}

static bool unit_moving(app_t *a)
{
	return motion_has_work(&a->v.motion) || motion_is_moving(&a->v.motion);
}

static void shutdown_unit(app_t *a, struct timespec *next)
{
	uint32_t ticks = 0, bound = SHUTDOWN_BOUND_MS * 1000u / a->period_us;
	bool was_moving = unit_moving(a);

	vs_stop(&a->v);
	while (unit_moving(a) && ticks++ < bound) {
		tick(a, false);
		wait_next(a, next);
	}
	if (unit_moving(a))
		rt_log(LOG_ERR, "shutdown: unit still moving after %u ms; cutting power",
		       SHUTDOWN_BOUND_MS);
	else if (was_moving)
		rt_log(LOG_INFO, "shutdown: stopped after %u ms", ticks * a->period_us / 1000u);
	if (a->v.powered)
		vs_setServo(&a->v, false);
	vs_setPower(&a->v, false);
	tick(a, false);
	bool servo = false;
	for (uint8_t i = 0; i < a->v.naxes; i++)
		servo = servo || a->hal.loop[i].enabled;
	rt_log(LOG_INFO, "final state: %s, relay %s, servo %s, %s",
	       a->v.powered ? "powered" : "unpowered", a->hal.relay_cmd ? "closed" : "open",
	       servo ? "on" : "off", unit_moving(a) ? "moving" : "stopped");
}

static void usage(FILE *f)
{
	fputs("usage: vehicle-fw [options]\n"
	      "  --config FILE   vehicle description with its <backends> section\n"
	      "                  (default " DEFAULT_CONFIG ")\n"
	      "  --io FILE       io.xml (default: io.xml beside the configuration)\n"
	      "  --port DEV      serve the command link on this serial port\n"
	      "                  (default: stdin/stdout)\n"
	      "  --baud N        line speed of --port (default 115200)\n"
	      "  --log stderr|syslog  where messages go (default stderr)\n"
	      "  --rt-priority N SCHED_FIFO priority 1..99, 0 for none (default 80)\n"
	      "  --help          this text\n",
	      f);
}

static int parse_ulong(const char *s, unsigned long max, unsigned long *out)
{
	char *end;
	errno = 0;
	unsigned long n = strtoul(s, &end, 10);
	if (*s < '0' || *s > '9' || *end != '\0' || errno || n > max)
		return -1;
	*out = n;
	return 0;
}

int main(int argc, char **argv)
{
	const char *config_path = DEFAULT_CONFIG, *io_path = NULL, *port = NULL;
	unsigned long baud = VC_DEFAULT_BAUD, prio = DEFAULT_RT_PRIO;
	bool use_syslog = false;
	char io_buf[1024], err[512];

	enum { O_CONFIG = 1, O_IO, O_PORT, O_BAUD, O_LOG, O_PRIO, O_HELP };
	static const struct option opts[] = {
	    {"config", required_argument, NULL, O_CONFIG},
	    {"io", required_argument, NULL, O_IO},
	    {"port", required_argument, NULL, O_PORT},
	    {"baud", required_argument, NULL, O_BAUD},
	    {"log", required_argument, NULL, O_LOG},
	    {"rt-priority", required_argument, NULL, O_PRIO},
	    {"help", no_argument, NULL, O_HELP},
	    {NULL, 0, NULL, 0},
	};
	int o;
	while ((o = getopt_long(argc, argv, "", opts, NULL)) != -1) {
		switch (o) {
		case O_CONFIG:
			config_path = optarg;
			break;
		case O_IO:
			io_path = optarg;
			break;
		case O_PORT:
			port = optarg;
			break;
		case O_BAUD:
			if (parse_ulong(optarg, 4000000, &baud) < 0 || baud == 0) {
				fprintf(stderr,
					"vehicle-fw: --baud: a line speed such as 115200\n");
				return 2;
			}
			break;
		case O_LOG:
			if (!strcmp(optarg, "syslog")) {
				use_syslog = true;
			} else if (strcmp(optarg, "stderr") != 0) {
				fprintf(stderr, "vehicle-fw: --log: stderr or syslog\n");
				return 2;
			}
			break;
		case O_PRIO:
			if (parse_ulong(optarg, 99, &prio) < 0) {
				fprintf(stderr, "vehicle-fw: --rt-priority: 0..99\n");
				return 2;
			}
			break;
		case O_HELP:
			usage(stdout);
			return 0;
		default:
			usage(stderr);
			return 2;
		}
	}
	if (optind < argc) {
		fprintf(stderr, "vehicle-fw: unexpected argument '%s'\n", argv[optind]);
		return 2;
	}
	rt_log_open(use_syslog);
	if (!config_path) /* getopt gives every -c an argument; the analyser cannot know */
		config_path = DEFAULT_CONFIG;
	if (!io_path) {
		const char *slash = strrchr(config_path, '/');
		int dir = slash ? (int)(slash - config_path + 1) : 0;
		snprintf(io_buf, sizeof(io_buf), "%.*sio.xml", dir, config_path);
		io_path = io_buf;
	}

	app_t *a = &app;
	vs_config_t cfg;
	hal_io_map_t io_map;
	backend_cfg_t bk;
	if (config_load(config_path, io_path, &cfg, &io_map, err, sizeof(err)) < 0 ||
	    backend_cfg_load(config_path, &bk, err, sizeof(err)) < 0) {
		rt_log(LOG_ERR, "%s", err);
		return 1;
	}
	uint8_t naxes = vs_config_axes(&cfg);
	if (lhal_open(&a->hal, &bk, &io_map, naxes, err, sizeof(err)) < 0) {
		rt_log(LOG_ERR, "%s", err);
		return 1;
	}
	static const struct {
		unsigned fn;
		size_t off;
	} needs[] = {
	    {BK_LINE_CONTACT, offsetof(vs_config_t, has_contact_sensor)},
	    {BK_LINE_OBSTACLE, offsetof(vs_config_t, has_obstacle_input)},
	    {BK_LINE_ESTOP, offsetof(vs_config_t, has_estop)},
	};
	for (size_t i = 0; i < sizeof(needs) / sizeof(needs[0]); i++)
		if (*(const bool *)((const char *)&cfg + needs[i].off) &&
		    !lgpio_has_fn(&a->hal.gpio, needs[i].fn))
			rt_log(LOG_WARNING,
			       "%s is configured in <devices> but has no <line>: reads "
			       "inactive",
			       backend_line_name(needs[i].fn));

	if (bk.joystick.used)
		rt_log(a->hal.joy.present ? LOG_INFO : LOG_WARNING, "joystick %s: %s",
		       bk.joystick.device,
		       a->hal.joy.present ? "open" : "not present (looked for once a second)");
	for (unsigned n = 0; n < BK_MODBUS_BUSES; n++)
		if (bk.bus[n].used &&
		    bk.bus[n].timeout_ms * (bk.bus[n].retries + 1) >= cfg.drive_timeout_ms)
			rt_log(
			    LOG_WARNING,
			    "modbus bus %u: timeout_ms x (retries + 1) = %u ms reaches the drive "
			    "timeout (%u ms): one lost reply can trip it",
			    n, bk.bus[n].timeout_ms * (bk.bus[n].retries + 1),
			    (unsigned)cfg.drive_timeout_ms);

	a->vh.ops = &lhal_ops;
	a->vh.ctx = &a->hal;
	const char *bad = NULL;
	if (vehicle_init(&a->v, &cfg, &a->vh, &bad) < 0) {
		rt_log(LOG_ERR, "%s: configuration rejected: %s", config_path, bad ? bad : "?");
		lhal_close(&a->hal);
		return 1;
	}
	a->period_us = 1000000u / cfg.tick_hz;

	if (port) {
		a->in_fd = vc_tty_open(port, (unsigned)baud);
		if (a->in_fd < 0) {
			rt_log(LOG_ERR, "%s: %s", port, strerror(errno));
			lhal_close(&a->hal);
			return 1;
		}
		a->out_fd = a->in_fd;
	} else {
		a->in_fd = STDIN_FILENO;
		a->out_fd = STDOUT_FILENO;
		fcntl(STDIN_FILENO, F_SETFL, fcntl(STDIN_FILENO, F_GETFL) | O_NONBLOCK);
	}
	console_init(&a->con, &a->v, no_write, NULL);
	console_set_extra(&a->con, rt_extra, a);
	vs_link_t lio = {port_read, port_write, a};
	link_init(&a->link, &a->con, &lio);

	struct sigaction sa;
	memset(&sa, 0, sizeof(sa));
	sa.sa_handler = on_signal;
	sigemptyset(&sa.sa_mask);
	sigaction(SIGINT, &sa, NULL);
	sigaction(SIGTERM, &sa, NULL);
	signal(SIGPIPE, SIG_IGN);

	rt_setup((int)prio, &a->rt);
	rt_log(LOG_INFO, "%s, %u axes, %u Hz, link on %s (%lu 8N1), %s%s", config_path, naxes,
	       cfg.tick_hz, port ? port : "stdin/stdout", baud,
	       a->rt.fifo ? "SCHED_FIFO" : "SCHED_OTHER", a->rt.locked ? ", memory locked" : "");

	struct timespec next;
	clock_gettime(CLOCK_MONOTONIC, &a->t0);
	next = a->t0;
	while (!stop_requested) {
		tick(a, true);
		wait_next(a, &next);
	}
	rt_log(LOG_INFO, "signal: stopping the unit");
	shutdown_unit(a, &next);
	vs_diag_t d;
	vehicle_diag(&a->v, &d);
	rt_log(LOG_INFO,
	       "exit: %llu ticks, %llu late wake-ups (max %u us), %llu periods skipped, "
	       "busiest period %u us, %u firmware overruns",
	       (unsigned long long)a->st.ticks, (unsigned long long)a->st.late, a->st.max_late_us,
	       (unsigned long long)a->st.skipped, a->st.busy_max_us, d.overruns);
	if (bk.battery_source != BK_BATTERY_FIXED)
		rt_log(LOG_INFO, "exit: %u failed battery reads", a->hal.battery_errors);
	for (unsigned b = 0; b < BK_CANOPEN_BUSES; b++)
		if (a->hal.can[b].used) {
			char c[200];
			co_bus_counters(&a->hal.can[b], c, sizeof(c));
			rt_log(LOG_INFO, "exit: %s", c);
		}
	lhal_close(&a->hal);
	if (port)
		close(a->in_fd);
	return 0;
}
