/* vehicle-sim: the firmware on the simulated plant, with the bring-up console
 * on stdin/stdout.
 *
 * --realtime ticks at the configured rate against CLOCK_MONOTONIC absolute
 * deadlines and polls stdin between ticks; '$wait' is refused there (the host
 * waits itself: the link is never held). --fast runs lockstep: simulated
 * time advances only inside '$wait', so a script replays the same way every
 * time. Input is fed to the console one line at a time. Every reply is
 * flushed at once.
 */
#include <errno.h>
#include <fcntl.h>
#include <getopt.h>
#include <limits.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include "../firmware/config_keep.h"
#include "../proto/client/bboxfile.h"
#include "../hal/posix/config_xml.h"
#include "../hal/posix/filestore.h"
#include "../hal/posix/rt.h"
#include "../hal/posix/socketcan.h"
#include "../hal/posix/tty.h"
#include "../proto/server.h"
#include "sim.h"
#include "sim_paths.h"

#define INBUF 4096

static volatile sig_atomic_t stop_requested;

static void on_signal(int sig)
{
	(void)sig;
	stop_requested = 1;
}

typedef struct {
	sim_t sim;
	char in[INBUF];
	size_t in_len;
	bool eof;
	bool write_failed;
	/* The unit's links are the simulator's server (sim.srv).
	 * --can: the CAN link's socket, served every tick; the simulator then
	 * runs until a signal even after stdin ends. */
	sockcan_t can;
	canlink_t canlink;
	bool can_on;
	/* --pty: console and binary frames on a pseudo-terminal (proto/link.h)
	 * instead of stdin/stdout; runs until a signal. */
	bool pty_on;
	int pty_master, pty_slave;
	server_serial_t ser; /* the pty's budget, flow control and answers */
	bool skip_line;	     /* --pty --fast: the rest of an over-long stdin line */
} app_t;

static app_t app;
/* The black box: 2 s at the tick rate (at most 10 kHz), as vehicle-fw. */
static bbox_sample_t bbox_ring[2u * 10000u];
static const char *bbox_path; /* --bbox-file */
static bool bbox_written;

/* After each tick: a fault froze the black box, written once to
 * --bbox-file; a clear re-arms the write. */
static void look_at_bbox(void *ctx, sim_t *s)
{
	(void)ctx;
	if (s->vehicle.bbox.status != BBOX_FROZEN) {
		bbox_written = false;
		return;
	}
	if (bbox_written)
		return;
	bbox_written = true;
	if (bbox_file_write_ring(bbox_path, &s->vehicle.bbox, s->cfg.tick_hz) < 0)
		fprintf(stderr, "vehicle-sim: black box: %s: %s\n", bbox_path, strerror(errno));
	else
		fprintf(stderr, "vehicle-sim: black box: fault %lu at tick %lu, %u samples in %s\n",
			(unsigned long)s->vehicle.bbox.fault,
			(unsigned long)s->vehicle.bbox.trigger, (unsigned)s->vehicle.bbox.count,
			bbox_path);
}
/* The configuration changed at run time, and its file (--store). */
static cfgkeep_t keep;
static filestore_t store;

/* Alarm events go to the log (stderr), in simulated time. */
static alarm_log_t alarm_events;

static void log_alarm(void *ctx, const char *line)
{
	(void)ctx;
	rt_log(LOG_NOTICE, "%s", line);
}

static void write_stdout(void *ctx, const char *s, size_t n)
{
	app_t *a = ctx;
	if (fwrite(s, 1, n, stdout) != n || fflush(stdout) != 0)
		a->write_failed = true;
}

/* Feeds complete lines from the input buffer. At EOF a last line without an ending is completed. A
 * buffer full of one over-long line goes to the console whole; it discards it. */
static void feed_lines(app_t *a)
{
	while (a->in_len > 0 && !stop_requested) {
		size_t n = 0;
		while (n < a->in_len && a->in[n] != '\n' && a->in[n] != '\r')
			n++;
		if (n < a->in_len) {
			n++; /* include the line ending */
		} else if (a->in_len < sizeof(a->in) && !a->eof) {
			return; /* wait for the rest of the line */
		}
		bool ended = a->in[n - 1] == '\n' || a->in[n - 1] == '\r';
		console_feed(&a->sim.srv.con, (const uint8_t *)a->in, n);
		sim_alarm_look(&a->sim);
		memmove(a->in, a->in + n, a->in_len - n);
		a->in_len -= n;
		if (a->eof && a->in_len == 0 && !ended)
			console_feed(&a->sim.srv.con, (const uint8_t *)"\n", 1);
	}
}

/* Reads what stdin has (blocking or not). Returns false on a fatal error. */
static bool read_input(app_t *a)
{
	if (a->eof || a->in_len == sizeof(a->in))
		return true;
	ssize_t r = read(STDIN_FILENO, a->in + a->in_len, sizeof(a->in) - a->in_len);
	if (r > 0)
		a->in_len += (size_t)r;
	else if (r == 0)
		a->eof = true;
	else if (errno != EINTR && errno != EAGAIN)
		return false;
	return true;
}

static size_t pty_read(void *ctx, uint8_t *buf, size_t max)
{
	app_t *a = ctx;
	ssize_t r = read(a->pty_master, buf, max);

	return r > 0 ? (size_t)r : 0;
}

static size_t pty_write(void *ctx, const uint8_t *buf, size_t len)
{
	app_t *a = ctx;
	ssize_t r = write(a->pty_master, buf, len);

	return r > 0 ? (size_t)r : 0;
}

/* Creates the pseudo-terminal, raw 8N1 at baud (nominal on a pty). The
 * simulator keeps the slave side open too, so that hosts may come and go
 * without the master seeing a hang-up. */
static int pty_open(app_t *a, unsigned baud, char *path, size_t cap)
{
	const char *name;

	a->pty_master = posix_openpt(O_RDWR | O_NOCTTY);
	if (a->pty_master < 0 || grantpt(a->pty_master) != 0 || unlockpt(a->pty_master) != 0)
		return -1;
	name = ptsname(a->pty_master);
	if (!name)
		return -1;
	snprintf(path, cap, "%s", name);
	a->pty_slave = open(path, O_RDWR | O_NOCTTY);
	if (a->pty_slave < 0 || tty_set_raw(a->pty_slave, baud) != 0)
		return -1;
	{
		struct termios t;

		/* The master side sees the bytes as they are, too. */
		if (tcgetattr(a->pty_master, &t) == 0) {
			cfmakeraw(&t);
			tcsetattr(a->pty_master, TCSANOW, &t);
		}
	}
	if (fcntl(a->pty_master, F_SETFL, fcntl(a->pty_master, F_GETFL) | O_NONBLOCK) != 0)
		return -1;
	return 0;
}

static int run_fast(app_t *a)
{
	while (!stop_requested && !a->write_failed) {
		if (!read_input(a))
			return 1;
		feed_lines(a);
		if (a->eof && a->in_len == 0)
			break;
	}
	return 0;
}

/* --pty --fast: the port is served at once without advancing time; stdin
 * carries the lines that do ('$wait MS', '$sim ...', any operation), each
 * answered on stdout. A harness that waits for each stdin reply before its
 * next request through the port gets the same run every time. */
static int run_pty_fast(app_t *a)
{
	vs_server_t *srv = &a->sim.srv;

	while (!stop_requested && !a->write_failed) {
		/* The port's input unless the unit waits for it to take answers,
		 * its output while answers wait, and at once while the unit can
		 * take more (its budget per poll was spent). */
		short ev = (short)((server_serial_blocked(srv) ? 0 : POLLIN) |
				   (server_serial_queued(srv) ? POLLOUT : 0));
		struct pollfd p[2] = {{.fd = a->pty_master, .events = ev},
				      {.fd = STDIN_FILENO, .events = POLLIN}};
		bool more = server_serial_more(srv);

		if (poll(p, 2, more ? 0 : -1) < 0) {
			if (errno == EINTR)
				continue;
			return 1;
		}
		if (more || (p[0].revents & (POLLIN | POLLOUT))) {
			server_poll(srv, (uint32_t)a->sim.now_us);
			sim_alarm_look(&a->sim);
		}
		if (!(p[1].revents & (POLLIN | POLLHUP | POLLERR)))
			continue;
		if (!read_input(a))
			return 1;
		for (;;) {
			char *nl = memchr(a->in, '\n', a->in_len);
			char reply[CONSOLE_REPLY_MAX];
			bool skip = a->skip_line;
			size_t n;

			if (nl) {
				n = (size_t)(nl - a->in) + 1;
				*nl = '\0';
				a->skip_line = false;
			} else if (a->in_len == sizeof(a->in) || (a->eof && a->in_len)) {
				/* Over-long (the console refuses it, or ignores a
				 * comment; the rest of the line goes with it) or
				 * unterminated at EOF. */
				n = a->in_len;
				a->in[n < sizeof(a->in) ? n : n - 1] = '\0';
				a->skip_line = n == sizeof(a->in);
			} else {
				break;
			}
			if (!skip && sim_exec(&a->sim, a->in, reply, sizeof(reply))) {
				size_t len = strlen(reply);

				reply[len] = '\n';
				write_stdout(a, reply, len + 1);
			}
			memmove(a->in, a->in + n, a->in_len - n);
			a->in_len -= n;
		}
		if (a->eof)
			break;
	}
	return 0;
}

/* The plant and the unit tick on simulated time, one period per wall
 * period; far behind (a debugger, an overloaded host) the wall schedule
 * skips ahead while simulated time stays regular. */
static int run_realtime(app_t *a)
{
	rt_clock_t clk;
	rt_clock_start(&clk, 1000000u / a->sim.cfg.tick_hz);

	while (!stop_requested && !a->write_failed) {
		if (!a->pty_on) {
			struct pollfd pfd = {.fd = STDIN_FILENO, .events = POLLIN};
			if (!a->eof && poll(&pfd, 1, 0) > 0 && !read_input(a))
				return 1;
			feed_lines(a);
			if (a->eof && a->in_len == 0 && !a->can_on)
				break;
		}
		sim_tick(&a->sim);
		server_poll(&a->sim.srv, (uint32_t)a->sim.now_us);
		sim_alarm_look(&a->sim);
		rt_clock_wait(&clk, NULL);
	}
	return 0;
}

/* --can: the CAN command link on a SocketCAN interface. Returns 0 or -1
 * with a message in err. */
static int open_can(app_t *a, const char *iface, unsigned long node, unsigned long hz, char *err,
		    size_t cap)
{
	a->can.fd = -1;
	if (node < CANLINK_NODE_MIN || node > CANLINK_NODE_MAX) {
		snprintf(err, cap, "--node: %d..%d", CANLINK_NODE_MIN, CANLINK_NODE_MAX);
		return -1;
	}
	if (hz > CANLINK_STATUS_HZ_MAX) {
		snprintf(err, cap, "--status-hz: 0..%d", CANLINK_STATUS_HZ_MAX);
		return -1;
	}
	/* Only the request identifier reaches the unit; the kernel filters. */
	uint32_t id = CANLINK_ID_REQUEST + (uint32_t)node;
	if (sockcan_open(&a->can, iface, &id, 1) < 0) {
		snprintf(err, cap, "CAN interface %s: %s", iface, strerror(errno));
		return -1;
	}
	canlink_config_t cc = {.node = (uint8_t)node, .status_hz = (uint16_t)hz};
	vs_can_port_t port = sockcan_port(&a->can);
	if (server_attach_can(&a->sim.srv, &a->canlink, &port, &cc) < 0) {
		snprintf(err, cap, "CAN link configuration rejected");
		return -1;
	}
	a->can_on = true;
	return 0;
}

/* One line of counters at exit, for the operator and the guest tests. */
static void close_can(app_t *a)
{
	char c[512];
	size_t n;

	server_can_counters(&a->sim.srv, c, sizeof(c));
	n = strlen(c);
	c[n++] = ' ';
	sockcan_counters(&a->can, c + n, sizeof(c) - n);
	rt_log(LOG_INFO, "CAN counters: %s", c);
	sockcan_close(&a->can);
}

/* Where vehicle.xml and io.xml come from without --config and --io. */
static char search_dirs[SIM_PATHS_N][SIM_PATHS_MAX];
static size_t search_n;

static void usage(FILE *f)
{
	fputs("usage: vehicle-sim [options]\n"
	      "  --config FILE   vehicle description (default: vehicle.xml from the first of\n"
	      "                  the folders below that has one)\n"
	      "  --io FILE       io.xml (default: io.xml, found the same way)\n"
	      "  --realtime      tick at the configured rate in wall time ($wait refused)\n"
	      "  --fast          lockstep: time advances only in '$wait MS'; exit at EOF\n"
	      "                  (default: --realtime on a terminal, else --fast)\n"
	      "  --trace FILE    CSV trace, one row per tick (columns: docs/trace.md)\n"
	      "  --trace-every N one trace row every N ticks\n"
	      "  --bbox-file FILE  write the black box (2 s of ticks) to FILE when a fault\n"
	      "                  freezes it (docs/linux.md)\n"
	      "  --ideal         ideal plant: no motor lag, no acceleration/current limit, and\n"
	      "                  the finest power-of-two encoder resolution up to 2^20 counts\n"
	      "                  that the configured speed limits admit (replaces a coarser\n"
	      "                  configured one; the start-up line on stderr says which)\n"
	      "  --can IFACE     serve the CAN link on SocketCAN interface IFACE (docs/can.md);\n"
	      "                  implies --realtime, keeps running after stdin ends\n"
	      "  --node N        CAN node id, 1..127 (default 1)\n"
	      "  --status-hz N   CAN status frame rate, 0 (off)..1000 (default 10)\n"
	      "  --pty           serve the serial link (console and frames, docs/protocol.md) on\n"
	      "                  a new pseudo-terminal instead of stdin/stdout; prints its path\n"
	      "                  as the first line on stdout; --realtime (default) runs until\n"
	      "                  a signal; with --fast the port is served without advancing\n"
	      "                  time, stdin lines ('$wait MS', '$sim ...') are answered on\n"
	      "                  stdout, and the run ends at EOF on stdin\n"
	      "  --baud N        line speed set on the pty (default 115200; nominal on a pty)\n"
	      "  --store FILE    keep the configuration changed at run time in FILE ($config\n"
	      "                  save; read at start over the vehicle file; default: none)\n"
	      "  --help          this text\n"
	      "Console on stdin/stdout (spec section 7); simulator extras: $wait MS, $sim ...\n"
	      "(see host_sim/sim.h).\n"
	      "Configuration folders, in order:\n",
	      f);
	for (size_t i = 0; i < search_n; i++)
		fprintf(f, "  %s\n", search_dirs[i]);
}

/* The program's own path, so that its configuration is found from any
 * working folder; NULL when the system cannot say. */
static const char *exe_path(char buf[PATH_MAX])
{
	return realpath("/proc/self/exe", buf);
}

int main(int argc, char **argv)
{
	const char *config_path = NULL, *io_path = NULL, *store_path = NULL;
	char exe[PATH_MAX], config_buf[PATH_MAX], io_buf[PATH_MAX];
	const char *trace_path = NULL;
	unsigned long trace_every = 1;
	int realtime = -1;
	bool ideal = false;
	const char *can_iface = NULL;
	unsigned long can_node = CANLINK_NODE_DEFAULT, can_hz = CANLINK_STATUS_HZ_DEFAULT;

	bool pty = false;
	unsigned long baud = VS_LINK_DEFAULT_BAUD;

	enum {
		O_CONFIG = 1,
		O_IO,
		O_RT,
		O_FAST,
		O_TRACE,
		O_EVERY,
		O_IDEAL,
		O_HELP,
		O_CAN,
		O_NODE,
		O_HZ,
		O_PTY,
		O_BAUD,
		O_STORE,
		O_BBOX
	};
	static const struct option opts[] = {
	    {"config", required_argument, NULL, O_CONFIG},
	    {"io", required_argument, NULL, O_IO},
	    {"realtime", no_argument, NULL, O_RT},
	    {"fast", no_argument, NULL, O_FAST},
	    {"trace", required_argument, NULL, O_TRACE},
	    {"trace-every", required_argument, NULL, O_EVERY},
	    {"ideal", no_argument, NULL, O_IDEAL},
	    {"help", no_argument, NULL, O_HELP},
	    {"can", required_argument, NULL, O_CAN},
	    {"node", required_argument, NULL, O_NODE},
	    {"status-hz", required_argument, NULL, O_HZ},
	    {"pty", no_argument, NULL, O_PTY},
	    {"baud", required_argument, NULL, O_BAUD},
	    {"store", required_argument, NULL, O_STORE},
	    {"bbox-file", required_argument, NULL, O_BBOX},
	    {NULL, 0, NULL, 0},
	};
	int o;
	search_n = sim_paths_dirs(exe_path(exe), search_dirs);
	while ((o = getopt_long(argc, argv, "", opts, NULL)) != -1) {
		switch (o) {
		case O_CONFIG:
			config_path = optarg;
			break;
		case O_IO:
			io_path = optarg;
			break;
		case O_RT:
			realtime = 1;
			break;
		case O_FAST:
			realtime = 0;
			break;
		case O_TRACE:
			trace_path = optarg;
			break;
		case O_EVERY: {
			char *end;
			trace_every = strtoul(optarg, &end, 10);
			if (*optarg == '\0' || *end != '\0' || trace_every < 1 ||
			    trace_every > 1000000) {
				fprintf(stderr, "vehicle-sim: --trace-every: 1..1000000\n");
				return 2;
			}
			break;
		}
		case O_IDEAL:
			ideal = true;
			break;
		case O_HELP:
			usage(stdout);
			return 0;
		case O_CAN:
			can_iface = optarg;
			break;
		case O_PTY:
			pty = true;
			break;
		case O_STORE:
			store_path = optarg;
			break;
		case O_BBOX:
			bbox_path = optarg;
			break;
		case O_BAUD: {
			char *end;
			baud = strtoul(optarg, &end, 10);
			if (*optarg == '\0' || *end != '\0' || baud == 0 || baud > 4000000) {
				fprintf(stderr,
					"vehicle-sim: --baud: a line speed such as 115200\n");
				return 2;
			}
			break;
		}
		case O_NODE:
		case O_HZ: {
			char *end;
			unsigned long n = strtoul(optarg, &end, 10);
			if (*optarg == '\0' || *end != '\0' || n > 100000) {
				fprintf(stderr, "vehicle-sim: --%s: not a number\n",
					o == O_NODE ? "node" : "status-hz");
				return 2;
			}
			*(o == O_NODE ? &can_node : &can_hz) = n;
			break;
		}
		default:
			usage(stderr);
			return 2;
		}
	}
	if (optind < argc) {
		fprintf(stderr, "vehicle-sim: unexpected argument '%s'\n", argv[optind]);
		usage(stderr);
		return 2;
	}
	if (realtime < 0)
		realtime = isatty(STDIN_FILENO) || can_iface || pty ? 1 : 0;
	if (can_iface && !realtime) {
		fprintf(stderr, "vehicle-sim: --can needs --realtime\n");
		return 2;
	}

	vs_config_t cfg;
	char err[512];
	if (!config_path) {
		if (sim_paths_find(search_dirs, search_n, "vehicle.xml", config_buf,
				   sizeof(config_buf)) < 0) {
			fprintf(stderr, "vehicle-sim: %s (--config FILE names one)\n", config_buf);
			return 1;
		}
		config_path = config_buf;
	}
	if (!io_path) {
		if (sim_paths_find(search_dirs, search_n, "io.xml", io_buf, sizeof(io_buf)) < 0) {
			fprintf(stderr, "vehicle-sim: %s (--io FILE names one)\n", io_buf);
			return 1;
		}
		io_path = io_buf;
	}
	if (config_load(config_path, io_path, &cfg, NULL, err, sizeof(err)) < 0) {
		fprintf(stderr, "vehicle-sim: %s\n", err);
		return 1;
	}
	plant_params_t pp;
	if (ideal) {
		plant_params_ideal(&pp);
		/* The firmware converts counts with the configured resolution, so
		 * the fine encoder goes into the configuration too. */
		cfg.encoder_counts_per_rev = plant_hires_counts_per_rev(&cfg);
		plant_config_lag(&pp, &cfg);
	} else {
		plant_params_default(&pp);
	}

	app_t *a = &app;
	const char *bad = NULL;
	rt_log_open("vehicle-sim", false);
	if (store_path && filestore_open(&store, store_path, err, sizeof(err)) < 0) {
		fprintf(stderr, "vehicle-sim: --store: %s\n", err);
		return 1;
	}
	/* The vehicle file is the base; the store's overlay goes over it. */
	cfgkeep_load(&keep, &cfg, store_path ? &store.hs : NULL, &cfg);
	if (sim_init_ex(&a->sim, &cfg, &pp, &bad) < 0) {
		fprintf(stderr, "vehicle-sim: configuration rejected: %s\n", bad ? bad : "?");
		return 1;
	}
	cfgkeep_attach(&keep, &a->sim.vehicle);
	vehicle_blackbox(&a->sim.vehicle, bbox_ring, (uint16_t)(2u * cfg.tick_hz), 1);
	if (bbox_path)
		sim_set_tick_cb(&a->sim, look_at_bbox, NULL);
	console_set_keep(&a->sim.srv.con, &keep);
	if (store_path) {
		console_config_store(&keep, err, sizeof(err));
		fprintf(stderr, "vehicle-sim: configuration %s (%s)\n", err, store_path);
	}
	sim_set_output(&a->sim, write_stdout, a);
	alarm_log_init(&alarm_events);
	sim_set_alarm_log(&a->sim, &alarm_events, log_alarm, NULL);
	if (realtime)
		sim_set_realtime(&a->sim, true);

	if (can_iface) {
		if (open_can(a, can_iface, can_node, can_hz, err, sizeof(err)) < 0) {
			fprintf(stderr, "vehicle-sim: %s\n", err);
			return 1;
		}
		fprintf(stderr, "vehicle-sim: CAN link on %s, node %lu, status %lu Hz\n", can_iface,
			can_node, can_hz);
	}

	if (pty) {
		char path[256];
		vs_link_t io = {pty_read, pty_write, a};

		if (pty_open(a, (unsigned)baud, path, sizeof(path)) < 0) {
			fprintf(stderr, "vehicle-sim: --pty: %s\n", strerror(errno));
			return 1;
		}
		server_serve_serial(&a->sim.srv, &a->ser, &io);
		a->pty_on = true;
		printf("%s\n", path);
		fflush(stdout);
		fprintf(stderr, "vehicle-sim: serial link on %s, %lu 8N1\n", path, baud);
	}

	trace_t trace;
	if (trace_path) {
		if (trace_open(&trace, trace_path, (uint32_t)trace_every) < 0) {
			fprintf(stderr, "vehicle-sim: %s: %s\n", trace_path, strerror(errno));
			return 1;
		}
		sim_set_trace(&a->sim, &trace);
	}

	struct sigaction sa;
	memset(&sa, 0, sizeof(sa));
	sa.sa_handler = on_signal; /* no SA_RESTART: a blocking read returns */
	sigemptyset(&sa.sa_mask);
	sigaction(SIGINT, &sa, NULL);
	sigaction(SIGTERM, &sa, NULL);
	signal(SIGPIPE, SIG_IGN);

	char plant_desc[64] = "";
	if (ideal)
		snprintf(plant_desc, sizeof(plant_desc), "ideal plant, %u-count encoders, ",
			 (unsigned)cfg.encoder_counts_per_rev);
	fprintf(stderr, "vehicle-sim: %s base, %u axes, %u Hz, %s%s mode (%s, %s)\n",
		cfg.kinematics == VS_KIN_OMNI ? "mecanum" : "differential", vs_config_axes(&cfg),
		cfg.tick_hz, plant_desc, realtime ? "realtime" : "fast", config_path, io_path);

	int rc = realtime ? run_realtime(a) : pty ? run_pty_fast(a) : run_fast(a);
	if (a->can_on)
		close_can(a);

	if (trace_path && trace_close(&trace) < 0) {
		fprintf(stderr, "vehicle-sim: %s: write failed\n", trace_path);
		rc = 1;
	}
	return rc;
}
