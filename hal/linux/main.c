/* vehicle-fw: the firmware on the vehicle's Linux computer (docs/linux.md).
 *
 * One thread: every period it reads the inputs (the backends), runs
 * vehicle_tick() and polls the command server (proto/server.h: console and
 * binary frames on a serial port, the CAN command link with --can), then
 * sleeps to the next absolute deadline (hal/posix/rt.h).
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

#include "../../firmware/config_keep.h"
#include "../../proto/client/bboxfile.h"
#include "../posix/config_xml.h"
#include "../posix/filestore.h"
#include "backend_cfg.h"
#include "lhal.h"
#include "../posix/rt.h"
#include "../posix/tty.h"
#include "../../proto/alarm_log.h"
#include "../../proto/numparse.h"
#include "../../proto/server.h"
#include "../posix/socketcan.h"

/* SYSCONFDIR of make install, fixed at build time (mk/linux.mk); make's
 * default here for tools that read the file alone. */
#ifndef VEHICLE_SYSCONFDIR
#define VEHICLE_SYSCONFDIR "/etc"
#endif
#define DEFAULT_CONFIG	VEHICLE_SYSCONFDIR "/vehicle/vehicle.xml"
#define DEFAULT_RT_PRIO 80
/* Longest deceleration the shutdown waits for before cutting power. */
#define SHUTDOWN_BOUND_MS 10000u

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
	vs_server_t srv;
	server_serial_t ser; /* the serial link's budget, flow control and answers */
	sockcan_t can;	     /* --can: the CAN command link's socket and state */
	canlink_t canlink;
	int in_fd, out_fd;
	uint32_t write_errors;
	rt_status_t rt;
	rt_stats_t st;
	rt_clock_t clk;
	alarm_log_t alarms;    /* the list at the last look: its changes go to the log */
	cfgkeep_t keep;	       /* the configuration changed at run time */
	filestore_t store;     /* --store: where it is saved */
	const char *bbox_path; /* --bbox-file: the black box written on a fault */
	bool bbox_written;     /* ... this freeze's */
} app_t;

static app_t app;
/* The black box: 2 s at the tick rate (at most 10 kHz, config_fields.def). */
#define BBOX_SECONDS 2u
static bbox_sample_t bbox_ring[BBOX_SECONDS * 10000u];

/* A fault froze the black box: written once to --bbox-file (a few hundred
 * KiB, after the unit stopped); a clear re-arms the write. */
static void look_at_bbox(app_t *a)
{
	if (a->v.bbox.status != BBOX_FROZEN) {
		a->bbox_written = false;
		return;
	}
	if (a->bbox_written || !a->bbox_path)
		return;
	a->bbox_written = true;
	if (bbox_file_write_ring(a->bbox_path, &a->v.bbox, a->v.cfg.tick_hz) < 0)
		rt_log(LOG_ERR, "black box: %s: %s", a->bbox_path, strerror(errno));
	else
		rt_log(LOG_NOTICE, "black box: fault %lu at tick %lu, %u samples in %s",
		       (unsigned long)a->v.bbox.fault, (unsigned long)a->v.bbox.trigger,
		       (unsigned)a->v.bbox.count, a->bbox_path);
}

static void log_alarm(void *ctx, const char *line)
{
	(void)ctx;
	rt_log(LOG_NOTICE, "%s", line);
}

/* Alarm events (proto/alarm_log.h), timed from the loop's start. */
static void look_at_alarms(app_t *a)
{
	struct timespec now;

	clock_gettime(CLOCK_MONOTONIC, &now);
	long long ns = ts_diff_ns(&now, &a->clk.t0);
	alarm_log_poll(&a->alarms, &a->v.alarms, ns > 0 ? (uint64_t)ns / 1000u : 0, log_alarm,
		       NULL);
}

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
		 a->clk.period_us, (unsigned long long)a->st.ticks, (unsigned long long)a->st.late,
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
	/* and of each Modbus bus */
	size_t n = strlen(reply);
	lhal_modbus_counters(&a->hal, reply + n, cap - n);
	return true;
}

/* This thread's CPU time: what our own work costs, without the time the
 * host gave to other tasks (a preempted tick is late, not over budget). */
static uint64_t cpu_ns(void)
{
	struct timespec t;
	clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
	return (uint64_t)t.tv_sec * 1000000000ull + (uint64_t)t.tv_nsec;
}

static void tick(app_t *a, bool serve)
{
	uint64_t c0 = cpu_ns();
	uint32_t us = rt_clock_now_us(&a->clk);
	lhal_pre_tick(&a->hal, us);
	vehicle_tick(&a->v, us);
	look_at_alarms(a);
	if (serve) {
		server_poll(&a->srv, us);
		look_at_alarms(a);
	}
	look_at_bbox(a);
	a->st.ticks++;
	uint64_t busy = (cpu_ns() - c0) / 1000u;
	uint32_t busy_us = busy > UINT32_MAX ? UINT32_MAX : (uint32_t)busy;
	if (busy_us > a->st.busy_max_us)
		a->st.busy_max_us = busy_us;
	vehicle_tick_busy(&a->v, busy_us);
	/* Between two ticks, as the board's idle loop: the next cruise line's
	 * jerk-limited profile, so that its first tick need not plan it. */
	while (vehicle_plan_idle(&a->v))
		;
}

static bool unit_moving(app_t *a)
{
	return motion_has_work(&a->v.motion) || motion_is_moving(&a->v.motion);
}

static void shutdown_unit(app_t *a)
{
	uint32_t ticks = 0, bound = SHUTDOWN_BOUND_MS * 1000u / a->clk.period_us;
	bool was_moving = unit_moving(a);

	vs_stop(&a->v);
	while (unit_moving(a) && ticks++ < bound) {
		tick(a, false);
		rt_clock_wait(&a->clk, &a->st);
	}
	if (unit_moving(a))
		rt_log(LOG_ERR, "shutdown: unit still moving after %u ms; cutting power",
		       SHUTDOWN_BOUND_MS);
	else if (was_moving)
		rt_log(LOG_INFO, "shutdown: stopped after %u ms", ticks * a->clk.period_us / 1000u);
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
	      "  --port DEV      serve the serial command link on this port\n"
	      "                  (default: stdin/stdout)\n"
	      "  --baud N        line speed of --port (default 115200)\n"
	      "  --can IFACE     also serve the CAN command link on SocketCAN interface\n"
	      "                  IFACE (docs/can.md)\n"
	      "  --node N        CAN node id, 1..127 (default 1)\n"
	      "  --status-hz N   CAN status frame rate, 0 (off)..1000 (default 10)\n"
	      "  --store FILE    keep the configuration changed at run time in FILE ($config\n"
	      "                  save; read at start over the vehicle file; default: none)\n"
	      "  --bbox-file FILE  write the black box to FILE when a fault freezes it\n"
	      "                  (docs/linux.md; default: none)\n"
	      "  --log stderr|syslog  where messages go (default stderr)\n"
	      "  --rt-priority N SCHED_FIFO priority 1..99, 0 for none (default 80)\n"
	      "  --help          this text\n",
	      f);
}

typedef struct {
	const char *config_path, *io_path, *port, *can_iface, *store_path, *bbox_path;
	unsigned long baud, prio, can_node, can_hz;
	bool use_syslog;
	char io_buf[1024];
} opts_t;

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

/* One option with a number: its value, or a message and exit status 2. */
static int number_opt(const char *name, const char *arg, unsigned long lo, unsigned long hi,
		      unsigned long *out)
{
	if (parse_ulong(arg, hi, out) < 0 || *out < lo) {
		fprintf(stderr, "vehicle-fw: --%s: %lu..%lu\n", name, lo, hi);
		return 2;
	}
	return 0;
}

/* Returns -1 to go on, else the exit status. */
static int parse_args(int argc, char **argv, opts_t *o)
{
	enum {
		O_CONFIG = 1,
		O_IO,
		O_PORT,
		O_BAUD,
		O_LOG,
		O_PRIO,
		O_HELP,
		O_CAN,
		O_NODE,
		O_HZ,
		O_STORE,
		O_BBOX
	};
	static const struct option opts[] = {
	    {"config", required_argument, NULL, O_CONFIG},
	    {"io", required_argument, NULL, O_IO},
	    {"port", required_argument, NULL, O_PORT},
	    {"baud", required_argument, NULL, O_BAUD},
	    {"log", required_argument, NULL, O_LOG},
	    {"rt-priority", required_argument, NULL, O_PRIO},
	    {"help", no_argument, NULL, O_HELP},
	    {"can", required_argument, NULL, O_CAN},
	    {"node", required_argument, NULL, O_NODE},
	    {"status-hz", required_argument, NULL, O_HZ},
	    {"store", required_argument, NULL, O_STORE},
	    {"bbox-file", required_argument, NULL, O_BBOX},
	    {NULL, 0, NULL, 0},
	};
	int c, rc = 0;
	while (rc == 0 && (c = getopt_long(argc, argv, "", opts, NULL)) != -1) {
		switch (c) {
		case O_CONFIG:
			o->config_path = optarg;
			break;
		case O_IO:
			o->io_path = optarg;
			break;
		case O_PORT:
			o->port = optarg;
			break;
		case O_CAN:
			o->can_iface = optarg;
			break;
		case O_STORE:
			o->store_path = optarg;
			break;
		case O_BBOX:
			o->bbox_path = optarg;
			break;
		case O_BAUD:
			rc = number_opt("baud", optarg, 1, 4000000, &o->baud);
			break;
		case O_PRIO:
			rc = number_opt("rt-priority", optarg, 0, 99, &o->prio);
			break;
		case O_NODE:
			rc = number_opt("node", optarg, CANLINK_NODE_MIN, CANLINK_NODE_MAX,
					&o->can_node);
			break;
		case O_HZ:
			rc = number_opt("status-hz", optarg, 0, CANLINK_STATUS_HZ_MAX, &o->can_hz);
			break;
		case O_LOG:
			o->use_syslog = !strcmp(optarg, "syslog");
			if (!o->use_syslog && strcmp(optarg, "stderr") != 0) {
				fprintf(stderr, "vehicle-fw: --log: stderr or syslog\n");
				rc = 2;
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
	if (rc)
		return rc;
	if (optind < argc) {
		fprintf(stderr, "vehicle-fw: unexpected argument '%s'\n", argv[optind]);
		return 2;
	}
	if (!o->config_path) /* getopt gives every option an argument; the analyser cannot know */
		o->config_path = DEFAULT_CONFIG;
	if (!o->io_path) {
		const char *slash = strrchr(o->config_path, '/');
		int dir = slash ? (int)(slash - o->config_path + 1) : 0;
		snprintf(o->io_buf, sizeof(o->io_buf), "%.*sio.xml", dir, o->config_path);
		o->io_path = o->io_buf;
	}
	return -1;
}

/* Warnings about a configuration that loads but will not do what it says. */
static void check_config(const app_t *a, const vs_config_t *cfg, const backend_cfg_t *bk)
{
	static const struct {
		unsigned fn;
		size_t off;
	} needs[] = {
	    {BK_LINE_CONTACT, offsetof(vs_config_t, has_contact_sensor)},
	    {BK_LINE_OBSTACLE, offsetof(vs_config_t, has_obstacle_input)},
	    {BK_LINE_ESTOP, offsetof(vs_config_t, has_estop)},
	};
	for (size_t i = 0; i < sizeof(needs) / sizeof(needs[0]); i++)
		if (*(const bool *)((const char *)cfg + needs[i].off) &&
		    !lgpio_has_fn(&a->hal.gpio, needs[i].fn))
			rt_log(LOG_WARNING,
			       "%s is configured in <devices> but has no <line>: reads "
			       "inactive",
			       backend_line_name(needs[i].fn));

	if (bk->joystick.used)
		rt_log(a->hal.joy.present ? LOG_INFO : LOG_WARNING, "joystick %s: %s",
		       bk->joystick.device,
		       a->hal.joy.present ? "open" : "not present (looked for once a second)");
	for (unsigned n = 0; n < BK_MODBUS_BUSES; n++)
		if (bk->bus[n].used &&
		    bk->bus[n].timeout_ms * (bk->bus[n].retries + 1) >= cfg->drive_timeout_ms)
			rt_log(
			    LOG_WARNING,
			    "modbus bus %u: timeout_ms x (retries + 1) = %u ms reaches the drive "
			    "timeout (%u ms): one lost reply can trip it",
			    n, bk->bus[n].timeout_ms * (bk->bus[n].retries + 1),
			    (unsigned)cfg->drive_timeout_ms);
}

/* The configuration, the backends and the unit. Returns 0 or -1 (logged). */
static int open_unit(app_t *a, const opts_t *o, backend_cfg_t *bk)
{
	vs_config_t cfg;
	hal_io_map_t io_map;
	char err[512];

	if (backend_cfg_load_all(o->config_path, o->io_path, &cfg, &io_map, bk, err, sizeof(err)) <
	    0) {
		rt_log(LOG_ERR, "%s", err);
		return -1;
	}
	if (o->store_path && filestore_open(&a->store, o->store_path, err, sizeof(err)) < 0) {
		rt_log(LOG_ERR, "--store: %s", err);
		return -1;
	}
	/* The vehicle file is the base; the store's overlay goes over it. */
	cfgkeep_load(&a->keep, &cfg, o->store_path ? &a->store.hs : NULL, &cfg);
	if (o->store_path) {
		console_config_store(&a->keep, err, sizeof(err));
		rt_log(a->keep.boot.result > CFGKEEP_BOOT_LOADED ? LOG_WARNING : LOG_INFO,
		       "configuration %s (%s)", err, o->store_path);
	}
	if (lhal_open(&a->hal, bk, &io_map, vs_config_axes(&cfg), err, sizeof(err)) < 0) {
		rt_log(LOG_ERR, "%s", err);
		return -1;
	}
	check_config(a, &cfg, bk);
	a->vh.ops = &lhal_ops;
	a->vh.ctx = &a->hal;
	const char *bad = NULL;
	if (vehicle_init(&a->v, &cfg, &a->vh, &bad) < 0) {
		rt_log(LOG_ERR, "%s: configuration rejected: %s", o->config_path, bad ? bad : "?");
		lhal_close(&a->hal);
		return -1;
	}
	cfgkeep_attach(&a->keep, &a->v);
	vehicle_blackbox(&a->v, bbox_ring, (uint16_t)(BBOX_SECONDS * cfg.tick_hz), 1);
	a->bbox_path = o->bbox_path;
	rt_clock_start(&a->clk, 1000000u / cfg.tick_hz);
	return 0;
}

/* The command server: the serial link on --port or stdin/stdout, and the
 * CAN link on --can. Returns 0 or -1 (logged). */
static int open_links(app_t *a, const opts_t *o)
{
	if (o->port) {
		a->in_fd = tty_open(o->port, (unsigned)o->baud);
		if (a->in_fd < 0) {
			rt_log(LOG_ERR, "%s: %s", o->port, strerror(errno));
			return -1;
		}
		a->out_fd = a->in_fd;
	} else {
		a->in_fd = STDIN_FILENO;
		a->out_fd = STDOUT_FILENO;
		fcntl(STDIN_FILENO, F_SETFL, fcntl(STDIN_FILENO, F_GETFL) | O_NONBLOCK);
	}
	server_init(&a->srv, &a->v, rt_extra, a, NULL, NULL);
	console_set_keep(&a->srv.con, &a->keep);
	vs_link_t lio = {port_read, port_write, a};
	server_serve_serial(&a->srv, &a->ser, &lio);
	if (o->port) /* the stream's budget is the line's */
		server_serial_set_baud(&a->srv, (uint32_t)o->baud);

	a->can.fd = -1;
	if (!o->can_iface)
		return 0;
	/* Only the request identifier reaches the unit; the kernel filters. */
	uint32_t id = CANLINK_ID_REQUEST + (uint32_t)o->can_node;
	canlink_config_t cc = {.node = (uint8_t)o->can_node, .status_hz = (uint16_t)o->can_hz};
	if (sockcan_open(&a->can, o->can_iface, &id, 1) < 0) {
		rt_log(LOG_ERR, "CAN interface %s: %s", o->can_iface, strerror(errno));
		return -1;
	}
	vs_can_port_t port = sockcan_port(&a->can);
	if (server_attach_can(&a->srv, &a->canlink, &port, &cc) <
	    0) { /* the options were checked */
		rt_log(LOG_ERR, "CAN link configuration rejected");
		return -1;
	}
	return 0;
}

static void log_exit(app_t *a, const backend_cfg_t *bk)
{
	vs_diag_t d;
	char c[400];

	vehicle_diag(&a->v, &d);
	rt_log(LOG_INFO,
	       "exit: %llu ticks, %llu late wake-ups (max %u us), %llu periods skipped, "
	       "busiest period %u us, %u firmware overruns",
	       (unsigned long long)a->st.ticks, (unsigned long long)a->st.late, a->st.max_late_us,
	       (unsigned long long)a->st.skipped, a->st.busy_max_us, d.overruns);
	if (bk->battery_source != BK_BATTERY_FIXED)
		rt_log(LOG_INFO, "exit: %u failed battery reads", a->hal.battery_errors);
	for (unsigned b = 0; b < BK_CANOPEN_BUSES; b++)
		if (a->hal.can[b].used) {
			co_bus_counters(&a->hal.can[b], c, sizeof(c));
			rt_log(LOG_INFO, "exit: %s", c);
		}
	char m[1024];
	if (lhal_modbus_counters(&a->hal, m, sizeof(m)) > 0)
		rt_log(LOG_INFO, "exit:%s", m);
	if (a->srv.can) {
		size_t n;
		server_can_counters(&a->srv, c, sizeof(c));
		n = strlen(c);
		c[n++] = ' ';
		sockcan_counters(&a->can, c + n, sizeof(c) - n);
		rt_log(LOG_INFO, "CAN counters: %s", c);
	}
}

int main(int argc, char **argv)
{
	opts_t o = {.config_path = DEFAULT_CONFIG,
		    .baud = VS_LINK_DEFAULT_BAUD,
		    .prio = DEFAULT_RT_PRIO,
		    .can_node = CANLINK_NODE_DEFAULT,
		    .can_hz = CANLINK_STATUS_HZ_DEFAULT};
	int rc = parse_args(argc, argv, &o);
	if (rc >= 0)
		return rc;
	rt_log_open("vehicle-fw", o.use_syslog);

	app_t *a = &app;
	alarm_log_init(&a->alarms);
	backend_cfg_t bk;
	if (open_unit(a, &o, &bk) < 0)
		return 1;
	if (open_links(a, &o) < 0) {
		lhal_close(&a->hal);
		return 1;
	}

	struct sigaction sa;
	memset(&sa, 0, sizeof(sa));
	sa.sa_handler = on_signal;
	sigemptyset(&sa.sa_mask);
	sigaction(SIGINT, &sa, NULL);
	sigaction(SIGTERM, &sa, NULL);
	signal(SIGPIPE, SIG_IGN);

	rt_setup((int)o.prio, &a->rt);
	rt_log(LOG_INFO, "%s, %u axes, %u Hz, link on %s (%lu 8N1), %s%s", o.config_path,
	       a->v.naxes, a->v.cfg.tick_hz, o.port ? o.port : "stdin/stdout", o.baud,
	       a->rt.fifo ? "SCHED_FIFO" : "SCHED_OTHER", a->rt.locked ? ", memory locked" : "");
	if (o.can_iface)
		rt_log(LOG_INFO, "CAN link on %s, node %lu, status %lu Hz", o.can_iface, o.can_node,
		       o.can_hz);

	rt_clock_start(&a->clk, a->clk.period_us);
	while (!stop_requested) {
		tick(a, true);
		rt_clock_wait(&a->clk, &a->st);
	}
	rt_log(LOG_INFO, "signal: stopping the unit");
	shutdown_unit(a);
	log_exit(a, &bk);
	lhal_close(&a->hal);
	if (o.port)
		close(a->in_fd);
	if (a->can.fd >= 0)
		sockcan_close(&a->can);
	return 0;
}
