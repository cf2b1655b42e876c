/* Console lines and binary frames parsed (and executed) per second.
 *
 * Both paths get the same realistic mix of requests, fed as one byte stream
 * to the unit's receive side (console_feed, frame_srv_feed) on a powered,
 * servo-on unit with no ticks running: the first moveForward queues, later
 * ones are refused (unit busy), as are the jogs; clearAlarm keeps the alarm
 * list from filling. Replies are produced and discarded. Wall-clock time,
 * best of 5 runs of at least 0.2 s each.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "proto/cmdtab.h"
#include "proto/console.h"
#include "proto/frame.h"
#include "proto/wire.h"
#include "rig.h"

static rig_t rig;

static const char *const mix[] = {
    "getPosition",	  "getState",	       "moveForward 100",  "getActiveAlarm 5",
    "setVelocity 400 60", "getBatteryVoltage", "moveJog 100 0 10", "getVelocityLimit",
    "getInput 1",	  "clearAlarm",
};
#define MIX_N (sizeof mix / sizeof mix[0])

static size_t out_bytes;

static void sink(void *ctx, const char *s, size_t n)
{
	(void)ctx;
	(void)s;
	out_bytes += n;
}

static void frame_sink(void *ctx, const uint8_t *d, size_t n)
{
	(void)ctx;
	(void)d;
	out_bytes += n;
}

static double now_s(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return (double)t.tv_sec + (double)t.tv_nsec * 1e-9;
}

/* Best rate over 5 runs: run(reps) processes reps * MIX_N requests. */
static double rate(void (*run)(unsigned))
{
	double best = 0;
	for (int k = 0; k < 5; k++) {
		unsigned reps = 0;
		double t0 = now_s(), t;
		do {
			run(100);
			reps += 100;
			t = now_s() - t0;
		} while (t < 0.2);
		size_t mix_n = MIX_N;
		double r = (double)reps * (double)mix_n / t;
		if (r > best)
			best = r;
	}
	return best;
}

static console_t con;
static uint8_t line_stream[4096];
static size_t line_len;

static void run_console(unsigned reps)
{
	for (unsigned i = 0; i < reps; i++)
		console_feed(&con, line_stream, line_len);
}

static frame_srv_t srv;
static uint8_t frame_stream[MIX_N][FRAME_REQ_MAX];
static size_t frame_len[MIX_N];

static void run_frames(unsigned reps)
{
	for (unsigned i = 0; i < reps; i++) {
		for (size_t k = 0; k < MIX_N; k++) {
			/* A fresh sequence number, or the server answers from its
			 * duplicate cache without running the operation. */
			uint8_t *f = frame_stream[k];
			f[3] = (uint8_t)(f[3] + MIX_N);
			uint16_t crc = cmd_crc16(0xFFFF, f + 1, frame_len[k] - 3);
			f[frame_len[k] - 2] = (uint8_t)crc;
			f[frame_len[k] - 1] = (uint8_t)(crc >> 8);
			frame_srv_feed(&srv, f, frame_len[k], 0);
		}
	}
}

/* The mix as frames: the console's own table gives opcodes and types. */
static void build_frames(void)
{
	for (size_t k = 0; k < MIX_N; k++) {
		char buf[64], *argv[8] = {NULL};
		int argc = 0;
		snprintf(buf, sizeof buf, "%s", mix[k]);
		for (char *p = strtok(buf, " "); p && argc < 8; p = strtok(NULL, " "))
			argv[argc++] = p;
		const cmd_def_t *d = argc ? cmd_by_name(argv[0]) : NULL;
		cmd_value_t in[CMD_MAX_FIELDS];
		memset(in, 0, sizeof in);
		if (argc == 0 || !d || (int)d->n_in != argc - 1) {
			fprintf(stderr, "parserate: bad mix entry %s\n", mix[k]);
			exit(2);
		}
		for (unsigned i = 0; i < d->n_in; i++) {
			switch (d->in_types[i]) {
			case CMD_T_DOUBLE:
				in[i].d = strtod(argv[i + 1], NULL);
				break;
			case CMD_T_SHORT:
				in[i].h = (int16_t)strtol(argv[i + 1], NULL, 10);
				break;
			case CMD_T_ULONG:
				in[i].u = (uint32_t)strtoul(argv[i + 1], NULL, 10);
				break;
			case CMD_T_BOOL:
				in[i].b = strtol(argv[i + 1], NULL, 10) != 0;
				break;
			default:
				break;
			}
		}
		uint8_t payload[WIRE_REQ_MAX];
		size_t plen = 0;
		if (wire_encode_request(d, in, payload, sizeof payload, &plen) != WIRE_ST_OK) {
			fprintf(stderr, "parserate: cannot encode %s\n", mix[k]);
			exit(2);
		}
		frame_len[k] = frame_encode(frame_stream[k], FRAME_REQ_MAX, (uint8_t)k, d->opcode,
					    payload, plen);
		if (frame_len[k] == 0) {
			fprintf(stderr, "parserate: cannot frame %s\n", mix[k]);
			exit(2);
		}
	}
}

int main(void)
{
	rig_init(&rig);
	for (size_t k = 0; k < MIX_N; k++)
		line_len += (size_t)snprintf((char *)line_stream + line_len,
					     sizeof line_stream - line_len, "%s\r\n", mix[k]);
	console_init(&con, &rig.v, sink, NULL);
	unsigned lines0 = con.lines;
	run_console(1);
	if (con.lines - lines0 != MIX_N) {
		fprintf(stderr, "parserate: console took %u of %zu lines\n", con.lines - lines0,
			MIX_N);
		return 2;
	}
	double lr = rate(run_console);

	build_frames();
	frame_srv_init(&srv, &rig.v, frame_sink, NULL, NULL, NULL);
	run_frames(1);
	if (srv.st.executed != MIX_N) {
		fprintf(stderr, "parserate: %u of %zu frames executed\n", srv.st.executed, MIX_N);
		return 2;
	}
	double fr = rate(run_frames);

	printf("mix of %zu requests:", MIX_N);
	for (size_t k = 0; k < MIX_N; k++)
		printf("%s %s", k ? "," : "", mix[k]);
	printf("\n");
	printf("console lines parsed and executed: %.0f lines/s (%.2f us per line)\n", lr,
	       1e6 / lr);
	printf("binary frames parsed and executed: %.0f frames/s (%.2f us per frame)\n", fr,
	       1e6 / fr);
	return 0;
}
