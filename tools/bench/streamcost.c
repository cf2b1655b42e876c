/* The telemetry stream's cost, counted in instructions by callgrind: the
 * serial server's poll after each tick of the blended cruise
 * (scenario.h), without a subscription and with one, so that the
 * difference is the stream's own work (the due check every tick; the
 * sample, its encoding, the frame's check and the queue on frame ticks).
 *
 * Run under
 *   valgrind --tool=callgrind --collect-atstart=no --toggle-collect=bench_poll \
 *     ./streamcost MODE
 * MODE: none, pose_state_10 (pose and state every 10 ms), all_7 (every
 * group every 7 ms, the fastest at 115200 baud), all_1 (every group every
 * tick, on a port of 1 Mbaud). One dump per poll, labelled "poll".
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <valgrind/callgrind.h>

#include "proto/server.h"
#include "scenario.h"

static rig_t rig;
static vs_server_t srv;
static server_serial_t ser;

__attribute__((noinline)) void bench_poll(vs_server_t *s, uint32_t now_us);

/* The measured function: one poll of the link, nothing read. */
__attribute__((noinline)) void bench_poll(vs_server_t *s, uint32_t now_us)
{
	server_poll(s, now_us);
}

static size_t no_read(void *ctx, uint8_t *b, size_t n)
{
	(void)ctx, (void)b, (void)n;
	return 0;
}

static size_t sink(void *ctx, const uint8_t *b, size_t n)
{
	(void)ctx, (void)b;
	return n;
}

static void tick_poll(rig_t *r, const char *label)
{
	(void)label;
	rig_tick_firmware(r);
	bench_poll(&srv, r->now_us);
	CALLGRIND_DUMP_STATS_AT("poll");
}

static bool retarget(rig_t *r, vs_position_t p, const char *label)
{
	(void)label;
	return vs_moveContinuousRel(&r->v, p);
}

static bool plan(rig_t *r, const char *label)
{
	(void)label;
	return vehicle_plan_idle(&r->v);
}

int main(int argc, char **argv)
{
	static const bench_hooks_t hooks = {tick_poll, retarget, plan};
	static const struct {
		const char *name;
		uint16_t mask, period;
		uint32_t baud;
	} modes[] = {{"none", 0, 0, STREAM_BAUD},
		     {"pose_state_10", 0x09, 10, STREAM_BAUD},
		     {"all_7", STREAM_MASK_ALL, 7, STREAM_BAUD},
		     {"all_1", STREAM_MASK_ALL, 1, 1000000}};
	const vs_link_t io = {no_read, sink, NULL};
	unsigned m;

	for (m = 0; m < sizeof(modes) / sizeof(modes[0]); m++)
		if (argc > 1 && strcmp(argv[1], modes[m].name) == 0)
			break;
	if (m == sizeof(modes) / sizeof(modes[0])) {
		fprintf(stderr, "usage: streamcost none|pose_state_10|all_7|all_1\n");
		return 2;
	}
	rig_init(&rig);
	server_init(&srv, &rig.v, NULL, NULL, NULL, NULL);
	server_serve_serial(&srv, &ser, &io);
	server_serial_set_baud(&srv, modes[m].baud);
	if (modes[m].mask && stream_start(&ser.sub, rig.v.cfg.tick_hz, rig.v.ticks, modes[m].mask,
					  modes[m].period, false) != WIRE_ST_OK) {
		fprintf(stderr, "streamcost: %s refused\n", modes[m].name);
		return 1;
	}
	long n = bench_scenario(&rig, "cruise", &hooks);
	printf("%s: %ld polls, %lu stream frames, %lu skipped\n", modes[m].name, n,
	       (unsigned long)ser.sub.sent, (unsigned long)ser.sub.skipped);
	return 0;
}
