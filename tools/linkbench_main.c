/* linkbench: getPosition round trip over a pseudo-terminal through the
 * client library and the unit's serial link, next to the time the same
 * bytes take on a real 115200 8N1 line (10 bits per byte); the frame
 * decoder's throughput; and a request flood from a host with no speed
 * limit (a pty, like a USB serial port, has none): what a poll of the link
 * costs the unit's tick under it, within the link's budget per poll
 * (proto/server.h). A benchmark, not a test: it prints, never fails. A pty
 * does not pace bytes at the line rate, so the measured round trip is the
 * software cost; on a real line add the wire time. */
#include <fcntl.h>
#include <poll.h>
#include <stdlib.h>
#include <pthread.h>
#include <pty.h>
#include <stdio.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "../host_sim/sim.h"
#include "../hal/posix/tty.h"
#include "../proto/client/client.h"
#include "../proto/server.h"

static sim_t S;
static server_serial_t SER;
static int M = -1;
static volatile int run_unit = 1;

static double now_s(void)
{
	struct timespec ts;

	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static size_t m_read(void *ctx, uint8_t *b, size_t n)
{
	ssize_t r = read(*(int *)ctx, b, n);
	return r > 0 ? (size_t)r : 0;
}

static size_t m_write(void *ctx, const uint8_t *b, size_t n)
{
	ssize_t r = write(*(int *)ctx, b, n);
	return r > 0 ? (size_t)r : 0;
}

static double cpu_s(void)
{
	struct timespec ts;

	clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
	return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

/* What the unit's polls cost while measuring: this thread's CPU time in
 * server_poll, as vehicle-fw counts its tick's work. */
static volatile int measure;
static double poll_cpu_sum, poll_cpu_max, poll_cpu[8192];
static unsigned long polls;

static int cmp_double(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;

	return (x > y) - (x < y);
}

/* The unit polls its link every 1 ms tick in real time, as the firmware. */
static void *unit(void *arg)
{
	(void)arg;
	while (run_unit) {
		double c0 = cpu_s(), c;

		server_poll(&S.srv, (uint32_t)(uint64_t)(now_s() * 1e6));
		c = cpu_s() - c0;
		if (measure) {
			poll_cpu_sum += c;
			if (c > poll_cpu_max)
				poll_cpu_max = c;
			if (polls < sizeof(poll_cpu) / sizeof(poll_cpu[0]))
				poll_cpu[polls] = c;
			polls++;
		}
		sim_tick(&S);
		usleep(1000);
	}
	return NULL;
}

/* The host of the flood: writes the requests over and over as fast as the
 * port takes them and reads every answer as it comes. */
static const uint8_t *flood_req;
static size_t flood_len;
static volatile int flood_run;
static unsigned long flood_rx;

static void *flood_host(void *arg)
{
	int fd = *(int *)arg;
	size_t at = 0;
	uint8_t b[65536];

	while (flood_run) {
		struct pollfd p = {fd, POLLIN | POLLOUT, 0};
		ssize_t k;

		if (poll(&p, 1, 10) <= 0)
			continue;
		if ((p.revents & POLLIN) && (k = read(fd, b, sizeof(b))) > 0)
			flood_rx += (unsigned long)k;
		if ((p.revents & POLLOUT) && (k = write(fd, flood_req + at, flood_len - at)) > 0)
			at = (at + (size_t)k) % flood_len;
	}
	return NULL;
}

/* The polls' CPU time measured so far: mean, p99, max in us. */
static void poll_figures(double *mean, double *p99, double *max)
{
	const size_t cap = sizeof(poll_cpu) / sizeof(poll_cpu[0]);
	size_t n = polls < cap ? (size_t)polls : cap;

	*mean = *p99 = *max = 0.0;
	if (!n)
		return;
	qsort(poll_cpu, n, sizeof(poll_cpu[0]), cmp_double);
	*mean = poll_cpu_sum / (double)polls * 1e6;
	*p99 = poll_cpu[n * 99 / 100] * 1e6;
	*max = poll_cpu_max * 1e6;
}

static void measure_for(double secs)
{
	poll_cpu_sum = poll_cpu_max = 0;
	polls = 0;
	measure = 1;
	usleep((useconds_t)(secs * 1e6));
	measure = 0;
}

/* One flood of 2 s: 2,560 copies of the request (seq 0..255 over), its
 * answers of ans bytes. */
static void flood(int fd, const char *what, uint8_t op, const void *pay, size_t plen, size_t ans)
{
	static uint8_t req[2560 * (FRAME_OVERHEAD + 2)];
	pthread_t th;
	uint32_t ex0 = S.srv.serial.fs.st.executed, drop0 = S.srv.serial.port.dropped;
	double secs = 2.0, per, mean, p99, max;
	unsigned long answers;

	flood_len = 0;
	for (unsigned i = 0; i < 2560; i++)
		flood_len += frame_encode(req + flood_len, sizeof(req) - flood_len, (uint8_t)i, op,
					  pay, plen);
	flood_req = req;
	flood_rx = 0;
	memset(&SER.st, 0, sizeof(SER.st));
	flood_run = 1;
	/* A host that writes only what the port takes now: the unit takes no
	 * more than it can answer, and a blocked write would never read. */
	fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK);
	pthread_create(&th, NULL, flood_host, &fd);
	measure_for(secs);
	flood_run = 0;
	pthread_join(th, NULL);
	answers = S.srv.serial.fs.st.executed - ex0;
	per = answers ? poll_cpu_sum / (double)answers : 0;
	printf("  %s (%zu-byte answers):\n", what, ans);
	printf(
	    "    %8.0f answers/s, %lu polls; per poll at most %u answers, %u bytes; txdrop %lu\n",
	    (double)answers / secs, polls, SER.st.max_answers, SER.st.max_bytes,
	    (unsigned long)(S.srv.serial.port.dropped - drop0));
	poll_figures(&mean, &p99, &max);
	printf(
	    "    server_poll CPU: mean %.1f us, p99 %.1f us, max %.1f us (%.1f us an answer, its "
	    "write to the pty included)\n",
	    mean, p99, max, per * 1e6);
	{
		/* what one poll took before the budget: 8 KiB of requests */
		size_t whole = SERVER_SERIAL_RX_PER_POLL / (FRAME_OVERHEAD + plen);

		printf("    unbounded, one poll's 8 KiB would be %zu requests: %.0f us\n", whole,
		       (double)whole * per * 1e6);
	}
	/* the last answers out before the next flood */
	usleep(200000);
	{
		uint8_t b[65536];
		struct pollfd p = {fd, POLLIN, 0};

		while (poll(&p, 1, 100) > 0 && read(fd, b, sizeof(b)) > 0)
			;
	}
	fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) & ~O_NONBLOCK);
}

static unsigned nframes;
static void count_frame(void *ctx, const frame_t *f)
{
	(void)ctx;
	(void)f;
	nframes++;
}

int main(void)
{
	vs_config_t cfg;
	plant_params_t pp;
	vs_link_t io = {m_read, m_write, &M};
	vc_client_t *c = calloc(1, sizeof(*c));
	int s;
	pthread_t th;
	const int N = 500;
	double t0, rt;
	vs_position_t pos;
	size_t req = FRAME_OVERHEAD, resp = FRAME_OVERHEAD + 1 + 1 + 3 * 8;

	vs_config_defaults(&cfg);
	plant_params_default(&pp);
	if (!c || sim_init(&S, &cfg, &pp) != 0 || openpty(&M, &s, NULL, NULL, NULL) != 0) {
		free(c);
		return 1;
	}
	tty_set_raw(s, 115200);
	tty_set_raw(M, 0);
	fcntl(M, F_SETFL, fcntl(M, F_GETFL) | O_NONBLOCK);
	server_serve_serial(&S.srv, &SER, &io);
	pthread_create(&th, NULL, unit, NULL);
	vc_attach_serial_fd(c, s, true);
	vc_getPosition(c, NULL, &pos); /* first call also does the info handshake */
	t0 = now_s();
	for (int i = 0; i < N; i++)
		if (vc_getPosition(c, NULL, &pos) != VC_OK) {
			fprintf(stderr, "linkbench: getPosition failed\n");
			vc_close(c);
			free(c);
			return 1;
		}
	rt = (now_s() - t0) / N;

	/* The flood: the client's port is the host's; 16 alarms of 63-byte
	 * sources make getActiveAlarm's largest answer. */
	printf(
	    "request flood over a pty, the host writing and reading as fast as it goes, the unit "
	    "polling every 1 ms\n(budget per poll: %d requests, %d bytes of answers, %d bytes "
	    "read; "
	    "this thread's CPU time in server_poll):\n",
	    SERVER_SERIAL_REQ_PER_POLL, SERVER_SERIAL_TX_PER_POLL, SERVER_SERIAL_RX_PER_POLL);
	{
		const uint8_t count[2] = {16, 0};

		for (unsigned k = 0; k < 16; k++) {
			char src[64];

			memset(src, 'a' + (int)k, 63);
			src[63] = '\0';
			alarm_raise(&S.vehicle.alarms, 100 + k, src);
		}
		double mean, p99, max;

		measure_for(1.0);
		poll_figures(&mean, &p99, &max);
		printf("  no request, for reference (the machine's own noise): mean %.1f us, p99 "
		       "%.1f us, max %.1f us\n",
		       mean, p99, max);
		flood(s, "getActiveAlarm 16, 16 alarms", CMD_OP_getActiveAlarm, count, 2,
		      FRAME_RESP_MAX);
		alarm_clear(&S.vehicle.alarms);
		flood(s, "getState", CMD_OP_getState, NULL, 0, 21);
	}
	run_unit = 0;
	pthread_join(th, NULL);
	printf("getPosition over a pty (unit polls every 1 ms tick), %d calls:\n", N);
	printf("  measured round trip      %8.3f ms\n", rt * 1e3);
	printf("  bytes on the wire        %8zu (request %zu + answer %zu)\n", req + resp, req,
	       resp);
	printf("  wire time at 115200 8N1  %8.3f ms (10 bits per byte)\n",
	       (double)(req + resp) * 10.0 / 115200.0 * 1e3);
	printf("  expected on a real line  %8.3f ms\n",
	       rt * 1e3 + (double)(req + resp) * 10.0 / 115200.0 * 1e3);

	/* Decoder throughput: a buffer of getPosition answers, fed in 64-byte chunks. */
	{
		static uint8_t buf[1 << 20];
		uint8_t pay[32] = {0}, rxbuf[FRAME_RESP_MAX];
		size_t n = 0, k;
		frame_rx_t rx;
		double t;
		unsigned reps = 20;

		while ((
		    k = frame_encode_response(buf + n, sizeof(buf) - n, (uint8_t)n, 9, 0, pay, 25)))
			n += k;
		frame_rx_init(&rx, rxbuf, FRAME_RESP_PAYLOAD_MAX, count_frame, NULL, NULL);
		t = now_s();
		for (unsigned r = 0; r < reps; r++)
			for (size_t i = 0; i < n; i += 64)
				frame_rx_feed(&rx, buf + i, n - i < 64 ? n - i : 64, 0);
		t = now_s() - t;
		printf("frame decoder: %u frames of %zu bytes in %.3f s = %.0f frames/s "
		       "(a 115200 line carries %.0f/s)\n",
		       nframes, resp, t, nframes / t, 11520.0 / (double)resp);
	}
	vc_close(c);
	free(c);
	return 0;
}
