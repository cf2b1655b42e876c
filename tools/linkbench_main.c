/* linkbench: getPosition round trip over a pseudo-terminal through the
 * client library and the unit's serial link, next to the time the same
 * bytes take on a real 115200 8N1 line (10 bits per byte), and the frame
 * decoder's throughput. A benchmark, not a test: it prints, never fails.
 * A pty does not pace bytes at the line rate, so the measured round trip
 * is the software cost; on a real line add the wire time. */
#include <fcntl.h>
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

/* The unit polls its link every 1 ms tick in real time, as the firmware. */
static void *unit(void *arg)
{
	(void)arg;
	while (run_unit) {
		server_poll(&S.srv, (uint32_t)(uint64_t)(now_s() * 1e6));
		sim_tick(&S);
		usleep(1000);
	}
	return NULL;
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
	server_attach_serial(&S.srv, &io);
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
