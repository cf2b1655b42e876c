/* The vehicle unit on a Cortex-M board: reference configuration, the plant
 * of plant.h behind the HAL (Modbus drives, or the loopback), console and
 * binary frames on the UART, one vehicle_tick per SysTick period, the
 * watchdog fed after each.
 *
 * After each tick the telemetry stream's frame, if one is due (server.h,
 * server_stream_next); between ticks the main loop serves the link and
 * drains the UART. A period that passes while the previous tick or a
 * command still runs is seen by the firmware through now_us (its overrun
 * fault), never silently absorbed.
 */
#include "board.h"
#include "firmware/config_keep.h"
#include "firmware/vehicle.h"
#include "flashstore.h"
#include "plant.h"
#include "wdog.h"
#include "proto/server.h"

#ifdef BOARD_STORE_CUT
#include <string.h>
#endif

static vehicle_t unit;
/* The black box in the M4's share of RAM (1 KiB): 8 samples, one every
 * 250 ticks (4 Hz at 1 kHz, the last 2 s) and the fault's (docs/mcu.md). */
#define BOARD_BBOX_SAMPLES 8u
#define BOARD_BBOX_EVERY   250u
static bbox_sample_t bbox_ring[BOARD_BBOX_SAMPLES];
static vs_server_t srv;	    /* the console and the binary frames on the UART */
static cfgkeep_t keep;	    /* $config: the compiled-in base, the store's overlay */
static stream_sub_t stream; /* the telemetry stream on the UART */
static uint32_t stream_end; /* uart_tx_sent() once the last stream frame has left */

/* What the tick and the requests cost, in processor cycles (systick_cycles):
 * read from outside, through a debugger or QEMU's monitor (tests/mcu,
 * docs/mcu.md). A request costs the link step that completed it: its last
 * byte, on which the line or frame is parsed, run and answered. */
typedef struct {
	uint32_t ticks, tick_last, tick_worst;
	uint64_t tick_sum;
	uint32_t requests, req_last, req_worst;
	uint32_t plans, plan_worst; /* idle planning calls that walked */
	/* the last and worst telemetry stream frame (or line) put into the
	 * UART's ring, and the worst of a tick and the frame due after it
	 * together ($stream counts the frames) */
	uint32_t stream_last, stream_worst, due_worst;
} board_cost_t;
volatile board_cost_t board_cost;

/* The configuration lives on the stack only while vehicle_init copies it:
 * 1.2 KiB of RAM that is not held for good. */
static __attribute__((noinline)) uint32_t unit_init(void)
{
	vs_config_t cfg;
	vs_hal_t hal;
	vs_config_defaults(&cfg);
	cfg.has_joystick = false;
#if VS_KIN_ONLY == 1 /* VS_KIN_OMNI: the preprocessor sees no enum */
	/* The mecanum build (make MCU_KIN=omni): 400 mm between the axles. */
	cfg.kinematics = VS_KIN_OMNI;
	cfg.wheel_base_mm = VS_REAL(400.0);
#endif
	plant_config(&cfg);
	/* The compiled-in configuration is the base; the store's goes over. */
	cfgkeep_load(&keep, &cfg, &flashstore, &cfg);
	hal = plant_hal(&cfg);
	if (vehicle_init(&unit, &cfg, &hal, NULL) != 0)
		for (;;)
			;
	cfgkeep_attach(&keep, &unit);
	vehicle_blackbox(&unit, bbox_ring, BOARD_BBOX_SAMPLES, BOARD_BBOX_EVERY);
	plant_start(&unit);
	/* A request walks a few queued waypoints of the corner speed planning,
	 * the idle calls the rest, and a few trial lines of a line's plan each. */
	vehicle_set_plan_budget(&unit, BOARD_PLAN_BUDGET);
	return cfg.tick_hz;
}

/* The link, one received byte at a time, until a request has run or the
 * next period has begun: however many requests a host sends at once, a tick
 * waits for one of them at most, and for no more than the byte that
 * completes it (the bytes before are taken between ticks). A request is
 * taken only once the last reply has gone to the UART: a host that sends
 * faster than the line carries the answers waits, and no reply is cut short
 * (50 $version lines in one write make 4 KiB of replies, four rings' worth).
 * Unread bytes wait in the UART (a port whose receiver can overrun buffers
 * them by interrupt or DMA, see docs/mcu.md). Returns the requests completed
 * so far; *cost: the cycles of the step that completed the last of them. */
static uint32_t serve_link(uint32_t done, uint32_t now_ms, uint32_t seen, uint32_t *cost)
{
	uint8_t b;
	uint32_t r = seen;

	while (r == seen && systick_count() == done && uart_tx_pending() == 0 &&
	       uart_link.read(NULL, &b, 1) == 1) {
		uint32_t t0 = systick_cycles();
		link_feed(&srv.serial, &b, 1, now_ms);
		r = srv.con.lines + srv.serial.fs.rx.st.frames;
		*cost = systick_cycles() - t0;
	}
	frame_srv_poll(&srv.serial.fs, now_ms); /* the frame inter-byte timeout */
	return r;
}

/* The telemetry stream's frame (or $stream's line) due after this tick,
 * into the UART's ring if the last one has left and the ring has room for
 * it; else the slot is skipped and counted (server_stream_next). A request
 * is taken only into an empty ring (serve_link), so an answer waits behind
 * one stream frame at most. Not inlined: its buffer is on the stack only
 * while it runs. */
static __attribute__((noinline)) void serve_stream(uint32_t tick_cost)
{
	uint8_t out[STREAM_TEXT_MAX];
	uint32_t t0 = systick_cycles(), c;
	/* unsent while its end lies within the ring's bytes (server_serial.c) */
	size_t n = server_stream_next(&srv, stream_end - uart_tx_sent() - 1u < uart_tx_pending(),
				      uart_tx_room(), out, sizeof(out));

	if (!n)
		return;
	uart_link.write(NULL, out, n);
	stream_end = uart_tx_sent() + (uint32_t)uart_tx_pending();
	c = systick_cycles() - t0;
	board_cost.stream_last = c;
	if (c > board_cost.stream_worst)
		board_cost.stream_worst = c;
	if (tick_cost + c > board_cost.due_worst)
		board_cost.due_worst = tick_cost + c;
}

#ifdef BOARD_STORE_CUT
/* The reset-in-the-save test image's $storecut K (flashstore.h). */
static bool store_cut(void *ctx, int argc, char **argv, char *reply, size_t cap)
{
	uint32_t k = 0;
	(void)ctx;
	if (argc != 2 || strcmp(argv[0], "$storecut") != 0)
		return false;
	for (const char *p = argv[1]; *p >= '0' && *p <= '9'; p++)
		k = k * 10u + (uint32_t)(*p - '0');
	flashstore_arm_cut(k);
	strncpy(reply, "ok cut", cap);
	return true;
}
#define BOARD_EXTRA store_cut
#else
#define BOARD_EXTRA plant_extra
#endif

int main(void)
{
	uint32_t tick_hz = unit_init();
	uart_init();
	server_init(&srv, &unit, BOARD_EXTRA, NULL, NULL, NULL);
	console_set_keep(&srv.con, &keep);
	server_attach_serial(&srv, &uart_link);
	server_stream_init(&srv, &stream, BOARD_UART_LINE_BAUD);
	systick_init(tick_hz);
#ifndef BOARD_STORE_CUT /* its cut stops the board as a power cut would */
	wdog_start();
#endif

	uint32_t done = systick_count();
	uint32_t period_us = 1000000u / tick_hz;
	uint32_t seen = 0; /* requests completed so far: console lines and frames */
	for (;;) {
		uint32_t now = systick_count(), t0 = systick_cycles(), c = 0, r;
		if (now != done) {
			/* Late by several periods: the clock jumps, and the firmware
			 * sees it. */
			done = now;
			vehicle_tick(&unit, done * period_us);
			c = systick_cycles() - t0;
			board_cost.ticks++;
			board_cost.tick_last = c;
			board_cost.tick_sum += c;
			if (c > board_cost.tick_worst)
				board_cost.tick_worst = c;
			/* The tick's own cost over a period is fault 209. */
			vehicle_tick_busy(&unit, c / (BOARD_CPU_HZ / 1000000u));
			plant_tick();
			serve_stream(c);
			continue;
		}
		r = serve_link(done, done * period_us / 1000u, seen, &c);
		if (r != seen) {
			seen = r;
			board_cost.requests++;
			board_cost.req_last = c;
			if (c > board_cost.req_worst)
				board_cost.req_worst = c;
		} else if (systick_count() == done) {
			/* Nothing to serve: the queue's planning goes on. */
			t0 = systick_cycles();
			if (vehicle_plan_idle(&unit)) {
				c = systick_cycles() - t0;
				board_cost.plans++;
				if (c > board_cost.plan_worst)
					board_cost.plan_worst = c;
			}
		}
		plant_poll();
		uart_poll_tx();
	}
}
