/* The CAN link (proto/canlink.c) and the client's CAN transport
 * (proto/client_can.c) in one process: the unit is the simulator with its
 * canlink, the host is the client library, and the "bus" between them is a
 * frame queue. Simulated time advances only while the host waits for frames.
 *
 * Covers: every operation through the CAN mapping against a twin simulator
 * driven through the console (same replies, exact), the segmentation and its
 * edge cases, the documented frame layouts byte for byte, retransmissions,
 * NAKs, status frames, the jog watchdog, and bad input of every kind (nothing
 * crashes, nothing moves, queued motion is kept, the link resynchronises,
 * each drop is counted).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "../host_sim/sim.h"
#include "../proto/canlink.h"
#include "../proto/client/client.h"
#include "../proto/client/client_can.h"
#include "../proto/console.h"

#define QN 8192

typedef struct {
	sim_t sim;
	canlink_t link;
	canlink_frame_t q[QN]; /* unit -> host */
	uint64_t qt[QN];       /* when each was sent, simulated us */
	size_t head, tail;
	bool refuse;   /* the unit's transmit queue is full */
	bool lose;     /* answers are lost, flow control frames go through */
	uint32_t sent; /* frames the unit sent */
} unit_t;

static unit_t U; /* the unit on CAN */
static sim_t T;	 /* its twin, on the console */
static vc_client_t C;
static char rep[CONSOLE_REPLY_MAX];

static bool unit_send(void *ctx, const canlink_frame_t *f)
{
	unit_t *u = ctx;

	if (u->refuse)
		return false;
	if (u->lose && (f->data[0] & 0xF0u) != CANLINK_PCI_FLOW)
		return true;
	assert_true(u->tail - u->head < QN);
	u->qt[u->tail % QN] = u->sim.now_us;
	u->q[u->tail++ % QN] = *f;
	u->sent++;
	return true;
}

static void unit_tick(void *ctx, sim_t *s)
{
	unit_t *u = ctx;
	canlink_poll(&u->link, (uint32_t)s->now_us);
}

static uint32_t now_us(void)
{
	return (uint32_t)U.sim.now_us;
}

/* The host's bus: sending delivers at once; waiting runs the unit. */
static int bus_send(void *ctx, const canlink_frame_t *f)
{
	(void)ctx;
	canlink_rx(&U.link, f, now_us());
	return VC_OK;
}

static uint32_t bus_now_ms(void *ctx)
{
	(void)ctx;
	return (uint32_t)(U.sim.now_us / 1000u);
}

static int bus_recv(void *ctx, canlink_frame_t *f, unsigned timeout_ms)
{
	uint32_t t0 = bus_now_ms(ctx);

	while (U.head == U.tail) {
		if (bus_now_ms(ctx) - t0 >= timeout_ms)
			return 0;
		sim_tick(&U.sim);
	}
	*f = U.q[U.head++ % QN];
	return 1;
}

static void boot_sim(sim_t *s, double wheel_diameter_mm)
{
	vs_config_t cfg;
	plant_params_t pp;

	vs_config_defaults(&cfg);
	/* Time passes in lockstep waits with no request; the link watchdog
	 * has its own tests. */
	cfg.link_timeout_ms = 0;
	if (wheel_diameter_mm > 0)
		cfg.wheel_diameter_mm = wheel_diameter_mm;
	plant_params_default(&pp);
	assert_int_equal(sim_init(s, &cfg, &pp), 0);
}

/* Unit and twin booted alike; the CAN link at node, status_hz. */
static void boot_all(unsigned node, unsigned status_hz)
{
	/* 1/32 mm per encoder count: straight targets land on whole counts
	 * (as in test_conformance.c). */
	double wheel = 16384.0 / (32.0 * 3.14159265358979323846);

	memset(&U, 0, sizeof(U));
	boot_sim(&U.sim, wheel);
	boot_sim(&T, wheel);
	canlink_config_t cfg = {.node = (uint8_t)node, .status_hz = (uint16_t)status_hz};
	assert_int_equal(canlink_init(&U.link, sim_vehicle(&U.sim), &cfg, unit_send, &U), 0);
	sim_set_tick_cb(&U.sim, unit_tick, &U);
	vc_can_bus_t bus = {.send = bus_send, .recv = bus_recv, .now_ms = bus_now_ms};
	assert_int_equal(vc_attach_can(&C, &bus, node, 1), VC_OK);
}

static int setup(void **state)
{
	(void)state;
	boot_all(1, 0);
	return 0;
}

static int teardown(void **state)
{
	(void)state;
	vc_close(&C);
	return 0;
}

static const char *twin(const char *line)
{
	if (!sim_exec(&T, line, rep, sizeof(rep)))
		return "(none)";
	return rep;
}

/* ---- formatting a CAN answer the way the console writes it -------------- */

static void put(char *buf, size_t cap, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void put(char *buf, size_t cap, const char *fmt, ...)
{
	size_t n = strlen(buf);
	va_list ap;

	va_start(ap, fmt);
	vsnprintf(buf + n, cap - n, fmt, ap);
	va_end(ap);
}

static void put_double(char *buf, size_t cap, double d)
{
	char tmp[64];

	snprintf(tmp, sizeof(tmp), "%.3f", d);
	put(buf, cap, " %s", strcmp(tmp, "-0.000") == 0 ? "0.000" : tmp);
}

static void format_answer(const cmd_def_t *d, bool ret, const cmd_value_t out[], char *buf,
			  size_t cap)
{
	static const char *const tname[] = {"unknown", "fault", "warning"};

	snprintf(buf, cap, "ok %s", ret ? "true" : "false");
	for (unsigned i = 0; i < d->n_out; i++) {
		switch (d->out_types[i]) {
		case CMD_T_BOOL:
			put(buf, cap, " %s", out[i].b ? "true" : "false");
			break;
		case CMD_T_SHORT:
			put(buf, cap, " %d", out[i].h);
			break;
		case CMD_T_ULONG:
			put(buf, cap, " %lu", (unsigned long)out[i].u);
			break;
		case CMD_T_DOUBLE:
			put_double(buf, cap, out[i].d);
			break;
		case CMD_T_STRING:
			put(buf, cap, " \"%s\"", out[i].s);
			break;
		case CMD_T_ALARMS:
			put(buf, cap, " %u", out[i].alarms.n);
			for (unsigned k = 0; k < out[i].alarms.n; k++) {
				const vs_alarm_t *a = &out[i].alarms.a[k];
				put(buf, cap, " %lu %s \"%s\"", (unsigned long)a->code,
				    a->type < 3 ? tname[a->type] : "?", a->source);
			}
			break;
		}
	}
}

/* Runs one console-syntax line over CAN through the client library and
 * returns the answer in console form. */
static const char *can_line(const char *line)
{
	static char out_buf[CONSOLE_REPLY_MAX];
	char copy[CONSOLE_LINE_MAX + 1], *tok[8], *save = NULL;
	int n = 0;

	snprintf(copy, sizeof(copy), "%s", line);
	for (char *t = strtok_r(copy, " ", &save); t && n < 8; t = strtok_r(NULL, " ", &save))
		tok[n++] = t;
	const cmd_def_t *d = cmd_by_name(tok[0]);
	assert_non_null(d);
	assert_int_equal(n - 1, d->n_in);
	cmd_value_t in[CMD_MAX_FIELDS], out[CMD_MAX_FIELDS];
	memset(in, 0, sizeof(in));
	for (unsigned i = 0; i < d->n_in; i++) {
		const char *a = tok[i + 1];
		switch (d->in_types[i]) {
		case CMD_T_BOOL:
			in[i].b = strcmp(a, "true") == 0;
			break;
		case CMD_T_SHORT:
			in[i].h = (int16_t)strtol(a, NULL, 10);
			break;
		case CMD_T_ULONG:
			in[i].u = (uint32_t)strtoul(a, NULL, 10);
			break;
		default:
			in[i].d = strtod(a, NULL);
			break;
		}
	}
	bool ret = false;
	int r = vc_call(&C, d, in, &ret, out);
	if (r != VC_OK) {
		snprintf(out_buf, sizeof(out_buf), "client error %d (%s)", r, vc_strerror(r));
		return out_buf;
	}
	format_answer(d, ret, out, out_buf, sizeof(out_buf));
	return out_buf;
}

/* Both units run the line; their answers must be the expected one. */
static void both(const char *line, const char *want)
{
	char tw[CONSOLE_REPLY_MAX];

	snprintf(tw, sizeof(tw), "%s", twin(line));
	assert_string_equal(tw, want);
	assert_string_equal(can_line(line), want);
}

static void wait_both(uint32_t ms)
{
	sim_run_ms(&U.sim, ms);
	sim_run_ms(&T, ms);
}

/* ---- every operation, CAN against the console --------------------------- */

static void test_every_op_matches_console(void **state)
{
	bool seen[CMD_COUNT + 1];
	static const struct {
		const char *line, *want;
		uint32_t wait_ms;
	} script[] = {
	    {"getState", "ok true 25 \"Unpowered\"", 0},
	    {"getIFVersion", "ok true \"RTC VehicleService interface: ver.2.0.0\"", 0},
	    {"getVersion", "ok true \"Ver.1.0.0\"", 0},
	    {"getVelocityLimit", "ok true 1000.000 180.000", 0},
	    {"getAccelerationLimit", "ok true 1000.000 360.000", 0},
	    {"getDefaultVelocity", "ok true 500.000 90.000", 0},
	    {"getDefaultAcceleration", "ok true 500.000 180.000", 0},
	    {"getBatteryVoltage", "ok true 252.000", 0},
	    {"getServoStatus 0", "ok true false", 0},
	    {"getServoStatus 7", "ok false false", 0},
	    {"moveForward 100", "ok false", 0},
	    {"getActiveAlarm 1", "ok true 2 1 121 warning \"moveForward refused: servo off\"", 0},
	    {"getActiveAlarm 2",
	     "ok true 2 2 121 warning \"moveForward refused: servo off\" "
	     "127 warning \"getServoStatus refused: no such axis\"",
	     0},
	    {"getActiveAlarm 0", "ok true 2 0", 0},
	    {"clearAlarm", "ok true", 0},
	    {"setServo true", "ok false", 0},
	    {"setPower true", "ok true", 0},
	    {"setServo true", "ok true", 0},
	    {"getServoStatus 1", "ok true true", 0},
	    {"getState", "ok true 18 \"Warning-128\"", 0},
	    {"clearAlarm", "ok true", 0},
	    {"getState", "ok true 16 \"Ready\"", 0},
	    {"setVelocity 0 90", "ok false", 0},
	    {"setVelocity 400 90", "ok true", 0},
	    {"setAcceleration 400 180", "ok true", 0},
	    {"setJogTimeout 0", "ok false", 0},
	    {"setJogTimeout 300", "ok true", 0},
	    {"clearAlarm", "ok true", 0},
	    {"moveForward 1000", "ok true", 0},
	    {"getState", "ok true 17 \"Busy\"", 5000},
	    {"getPosition", "ok true 1000.000 0.000 0.000", 0},
	    {"setPosition 0 0 0", "ok true", 0},
	    {"moveLinearRel 200 0 0", "ok true", 3000},
	    {"getPosition", "ok true 200.000 0.000 0.000", 0},
	    {"moveTurn 90", "ok true", 3000},
	    {"moveLinearAbs 300 0 0", "ok true", 0},
	    {"pause", "ok true", 0},
	    {"resume", "ok true", 5000},
	    {"moveCircularRel 0 100 90", "ok true", 4000},
	    {"moveCircularRel 10 100 90", "ok false", 0},
	    {"moveContinuousRel 100 0 0", "ok true", 3000},
	    {"moveCruiseAbs 500 0", "ok true", 0},
	    {"stop", "ok true", 2000},
	    {"moveJog 0 10 0", "ok false", 0},
	    {"moveJog 100 0 0", "ok true", 2000},
	    {"getState", "ok true 18 \"Warning-112\"", 0},
	    {"clearAlarm", "ok true", 0},
	    {"setDigitalSensorLock true", "ok true", 0},
	    {"setDigitalSensorLock false", "ok true", 0},
	    {"unlock", "ok true", 0},
	    {"setJoystick false", "ok true", 0},
	    {"setOutput 0 1 1", "ok false", 0},
	    {"setOutput 999 1 1", "ok false", 0},
	    {"getInput 999", "ok false 0", 0},
	    {"setServo false", "ok true", 0},
	    {"setPower false", "ok true", 0},
	    {"getState", "ok true 25 \"Unpowered\"", 0},
	};

	(void)state;
	memset(seen, 0, sizeof(seen));
	for (size_t i = 0; i < sizeof(script) / sizeof(script[0]); i++) {
		char name[40];
		sscanf(script[i].line, "%39s", name);
		const cmd_def_t *d = cmd_by_name(name);
		assert_non_null(d);
		seen[d->opcode] = true;
		both(script[i].line, script[i].want);
		if (script[i].wait_ms)
			wait_both(script[i].wait_ms);
		/* The two units stay identical between steps. */
		char tw[CONSOLE_REPLY_MAX];
		snprintf(tw, sizeof(tw), "%s", twin("getPosition"));
		assert_string_equal(can_line("getPosition"), tw);
	}
	for (unsigned op = 1; op <= CMD_COUNT; op++) {
		if (!seen[op])
			fail_msg("operation %s not covered", cmd_by_opcode(op)->name);
	}
	assert_int_equal(U.link.stats.naks, 0);
	assert_int_equal(U.link.stats.replays, 0);
}

static void test_info(void **state)
{
	unsigned ver = 0, ops = 0;
	uint16_t crc = 0;

	(void)state;
	assert_int_equal(vc_info(&C, &ver, &crc, &ops), VC_OK);
	assert_int_equal(ver, CMD_PROTO_VERSION);
	assert_int_equal(crc, cmd_table_crc());
	assert_int_equal(ops, CMD_COUNT);
}

/* The typed functions too, for one of each shape. */
static void test_typed_functions(void **state)
{
	bool ret = false, st = true;
	vs_position_t p = {1, 1, 1};
	int16_t code = 0, nact = -1;
	char msg[VS_STATE_MSG_MAX];
	vs_alarm_t al[4];
	uint16_t len = 9;
	const char *s = NULL;

	(void)state;
	assert_int_equal(vc_getState(&C, &ret, &code, msg), VC_OK);
	assert_true(ret);
	assert_int_equal(code, 0x19);
	assert_string_equal(msg, "Unpowered");
	assert_int_equal(vc_getServoStatus(&C, &ret, 0, &st), VC_OK);
	assert_true(ret);
	assert_false(st);
	assert_int_equal(vc_moveTurn(&C, &ret, 10), VC_OK);
	assert_false(ret);
	assert_int_equal(vc_getActiveAlarm(&C, &ret, 4, &nact, al, &len), VC_OK);
	assert_int_equal(nact, 1);
	assert_int_equal(len, 1);
	assert_int_equal(al[0].code, 121);
	assert_int_equal(al[0].type, VS_ALARM_WARNING);
	assert_string_equal(al[0].source, "moveTurn refused: servo off");
	assert_int_equal(vc_getIFVersion(&C, &ret, &s), VC_OK);
	assert_string_equal(s, VS_IF_VERSION);
	assert_int_equal(vc_setPower(&C, &ret, true), VC_OK);
	assert_int_equal(vc_setServo(&C, &ret, true), VC_OK);
	assert_int_equal(vc_moveForward(&C, &ret, 250), VC_OK);
	assert_true(ret);
	sim_run_ms(&U.sim, 3000);
	assert_int_equal(vc_getPosition(&C, &ret, &p), VC_OK);
	assert_true(p.x == 250.0 && p.y == 0.0 && p.theta == 0.0);
}

/* ---- segmentation ------------------------------------------------------- */

static void test_segmentation_counts_and_bytes(void **state)
{
	uint8_t msg[20];
	canlink_frame_t f;

	(void)state;
	assert_int_equal(canlink_seg_count(1), 1);
	assert_int_equal(canlink_seg_count(7), 1);
	assert_int_equal(canlink_seg_count(8), 2);
	assert_int_equal(canlink_seg_count(13), 2);
	assert_int_equal(canlink_seg_count(14), 3);
	assert_int_equal(canlink_seg_count(20), 3);
	assert_int_equal(canlink_seg_count(111), 16); /* 6 + 15*7 = 111 */
	assert_int_equal(canlink_seg_count(112), 17);
	assert_int_equal(CANLINK_RESP_MAX, 1111);
	assert_int_equal(canlink_seg_count(1111), 159); /* 6 + 158*7 = 1112 */

	for (unsigned i = 0; i < sizeof(msg); i++)
		msg[i] = (uint8_t)(0xA0 + i);
	canlink_seg_frame(msg, 20, 0, 0x585, &f);
	static const uint8_t ff[8] = {0x10, 20, 0xA0, 0xA1, 0xA2, 0xA3, 0xA4, 0xA5};
	assert_int_equal(f.id, 0x585);
	assert_int_equal(f.dlc, 8);
	assert_memory_equal(f.data, ff, 8);
	canlink_seg_frame(msg, 20, 1, 0x585, &f);
	static const uint8_t cf1[8] = {0x21, 0xA6, 0xA7, 0xA8, 0xA9, 0xAA, 0xAB, 0xAC};
	assert_int_equal(f.dlc, 8);
	assert_memory_equal(f.data, cf1, 8);
	canlink_seg_frame(msg, 20, 2, 0x585, &f);
	static const uint8_t cf2[8] = {0x22, 0xAD, 0xAE, 0xAF, 0xB0, 0xB1, 0xB2, 0xB3};
	assert_int_equal(f.dlc, 8);
	assert_memory_equal(f.data, cf2, 8);
	canlink_seg_frame(msg, 3, 0, 0x601, &f);
	static const uint8_t sf[4] = {0x03, 0xA0, 0xA1, 0xA2};
	assert_int_equal(f.dlc, 4);
	assert_memory_equal(f.data, sf, 4);
	/* a 12-bit length */
	static uint8_t big[CANLINK_MSG_LIMIT];
	canlink_seg_frame(big, 0x4D2, 0, 0x585, &f);
	assert_int_equal(f.data[0], 0x14);
	assert_int_equal(f.data[1], 0xD2);
}

/* Every length from 1 to the largest response, reassembled exactly,
 * including the wrap of the 4-bit index after 15. */
static void test_segmentation_roundtrip(void **state)
{
	static uint8_t msg[CANLINK_RESP_MAX], got[CANLINK_RESP_MAX];
	canlink_rx_t rx;

	(void)state;
	for (size_t i = 0; i < sizeof(msg); i++)
		msg[i] = (uint8_t)(i * 37u + 11u);
	canlink_rx_init(&rx, got, sizeof(got));
	for (size_t len = 1; len <= sizeof(msg); len++) {
		size_t n = canlink_seg_count(len);
		memset(got, 0, sizeof(got));
		for (size_t i = 0; i < n; i++) {
			canlink_frame_t f;
			canlink_seg_frame(msg, len, i, 0x585, &f);
			if (i > 0)
				assert_int_equal(f.data[0], 0x20 | (i & 15));
			int r = canlink_rx_feed(&rx, &f, 0);
			assert_int_equal(r, i + 1 == n ? CANLINK_RX_DONE : CANLINK_RX_PENDING);
		}
		assert_int_equal(rx.len, len);
		assert_memory_equal(got, msg, len);
	}
	assert_int_equal(rx.aborted, 0);
}

static canlink_frame_t frame(uint32_t id, uint8_t dlc, const char *hex)
{
	canlink_frame_t f;

	memset(&f, 0, sizeof(f));
	f.id = id;
	f.dlc = dlc;
	size_t len = strlen(hex);
	for (unsigned i = 0; i < 8 && 2 * i + 1 < len; i++) {
		unsigned b;
		/* within hex: 2 * i + 1 < len */
		// cppcheck-suppress pointerOutOfBounds
		sscanf(hex + 2 * i, "%2x", &b);
		f.data[i] = (uint8_t)b;
	}
	return f;
}

static void test_reassembly_errors(void **state)
{
	uint8_t buf[26];
	canlink_rx_t rx;
	canlink_frame_t f;

	(void)state;
	canlink_rx_init(&rx, buf, sizeof(buf));
	f = frame(0x601, 0, "");
	assert_int_equal(canlink_rx_feed(&rx, &f, 0), CANLINK_RX_BAD_DLC);
	f = frame(0x601, 9, "0201020304050607");
	assert_int_equal(canlink_rx_feed(&rx, &f, 0), CANLINK_RX_BAD_DLC);
	f = frame(0x601, 3, "00");
	assert_int_equal(canlink_rx_feed(&rx, &f, 0), CANLINK_RX_BAD_PCI); /* length 0 */
	f = frame(0x601, 3, "080102");
	assert_int_equal(canlink_rx_feed(&rx, &f, 0), CANLINK_RX_BAD_PCI); /* single of 8 */
	f = frame(0x601, 3, "050102");
	assert_int_equal(canlink_rx_feed(&rx, &f, 0),
			 CANLINK_RX_BAD_DLC); /* 5 announced, 2 there */
	for (unsigned t = 4; t <= 15; t++) {
		f = frame(0x601, 8, "0001020304050607");
		f.data[0] = (uint8_t)(t << 4);
		assert_int_equal(canlink_rx_feed(&rx, &f, 0), CANLINK_RX_BAD_PCI);
	}
	/* flow control: for the sender, taken whatever its status; DLC 3 at least */
	f = frame(0x601, 3, "300000");
	assert_int_equal(canlink_rx_feed(&rx, &f, 0), CANLINK_RX_FLOW);
	f = frame(0x601, 8, "3F00000000000000");
	assert_int_equal(canlink_rx_feed(&rx, &f, 0), CANLINK_RX_FLOW);
	f = frame(0x601, 2, "3000");
	assert_int_equal(canlink_rx_feed(&rx, &f, 0), CANLINK_RX_BAD_DLC);
	f = frame(0x601, 7, "100A010203040506");
	assert_int_equal(canlink_rx_feed(&rx, &f, 0), CANLINK_RX_BAD_DLC); /* first not 8 */
	f = frame(0x601, 8, "1007010203040506");
	assert_int_equal(canlink_rx_feed(&rx, &f, 0), CANLINK_RX_BAD_PCI); /* fits a single */
	f = frame(0x601, 8, "2101020304050607");
	assert_int_equal(canlink_rx_feed(&rx, &f, 0), CANLINK_RX_SEQUENCE); /* no first */
	/* out of order */
	f = frame(0x601, 8, "1014010203040506");
	assert_int_equal(canlink_rx_feed(&rx, &f, 0), CANLINK_RX_PENDING);
	f = frame(0x601, 8, "2201020304050607");
	assert_int_equal(canlink_rx_feed(&rx, &f, 0), CANLINK_RX_SEQUENCE);
	f = frame(0x601, 8, "2101020304050607"); /* too late: the message is gone */
	assert_int_equal(canlink_rx_feed(&rx, &f, 0), CANLINK_RX_SEQUENCE);
	/* a short consecutive frame that is not the last */
	f = frame(0x601, 8, "1014010203040506");
	assert_int_equal(canlink_rx_feed(&rx, &f, 0), CANLINK_RX_PENDING);
	f = frame(0x601, 5, "21010203");
	assert_int_equal(canlink_rx_feed(&rx, &f, 0), CANLINK_RX_BAD_DLC);
	/* oversize: refused at the first frame, the rest discarded */
	f = frame(0x601, 8, "101B070901020304");
	assert_int_equal(canlink_rx_feed(&rx, &f, 0), CANLINK_RX_OVERSIZE);
	assert_int_equal(rx.refused_head[0], 7);
	assert_int_equal(rx.refused_head[1], 9);
	for (unsigned i = 1; i <= 3; i++) {
		f = frame(0x601, 8, "2001020304050607");
		f.data[0] = (uint8_t)(0x20 | i);
		assert_int_equal(canlink_rx_feed(&rx, &f, 0), CANLINK_RX_DISCARDED);
	}
	/* a flow control frame between consecutive frames leaves the message */
	f = frame(0x601, 8, "100A010203040506");
	assert_int_equal(canlink_rx_feed(&rx, &f, 0), CANLINK_RX_PENDING);
	f = frame(0x601, 3, "300008");
	assert_int_equal(canlink_rx_feed(&rx, &f, 0), CANLINK_RX_FLOW);
	f = frame(0x601, 5, "2107080910");
	assert_int_equal(canlink_rx_feed(&rx, &f, 0), CANLINK_RX_DONE);
	assert_int_equal(rx.len, 10);
	assert_int_equal(buf[9], 0x10);
	/* a new single frame resynchronises at once, and aborts a started one */
	f = frame(0x601, 8, "1014010203040506");
	assert_int_equal(canlink_rx_feed(&rx, &f, 1000), CANLINK_RX_PENDING);
	f = frame(0x601, 3, "020509");
	assert_int_equal(canlink_rx_feed(&rx, &f, 0), CANLINK_RX_DONE);
	assert_int_equal(rx.len, 2);
	assert_int_equal(buf[0], 5);
	assert_int_equal(buf[1], 9);
	assert_int_equal(rx.aborted, 1);
	/* padding after a single frame's message is ignored */
	f = frame(0x601, 8, "020609AAAAAAAAAA");
	assert_int_equal(canlink_rx_feed(&rx, &f, 0), CANLINK_RX_DONE);
	assert_int_equal(rx.len, 2);
	/* a stalled message expires after CANLINK_RX_TIMEOUT_US, not before */
	f = frame(0x601, 8, "1014010203040506");
	assert_int_equal(canlink_rx_feed(&rx, &f, 1000), CANLINK_RX_PENDING);
	assert_false(canlink_rx_expired(&rx, 1000 + CANLINK_RX_TIMEOUT_US));
	assert_true(canlink_rx_expired(&rx, 1001 + CANLINK_RX_TIMEOUT_US));
	assert_false(canlink_rx_expired(&rx, 2001 + CANLINK_RX_TIMEOUT_US));
}

/* ---- the documented frames, byte for byte ------------------------------- */

static size_t pending(void)
{
	return U.tail - U.head;
}

static canlink_frame_t pop(void)
{
	assert_true(pending() > 0);
	return U.q[U.head++ % QN];
}

static void send_raw(uint32_t id, uint8_t dlc, const char *hex)
{
	canlink_frame_t f = frame(id, dlc, hex);
	canlink_rx(&U.link, &f, now_us());
}

static void expect_frame(uint32_t id, uint8_t dlc, const char *hex)
{
	canlink_frame_t want = frame(id, dlc, hex), got = pop();
	assert_int_equal(got.id, want.id);
	assert_int_equal(got.dlc, want.dlc);
	assert_memory_equal(got.data, want.data, want.dlc);
}

static void test_wire_layout(void **state)
{
	(void)state;
	/* getState, seq 0x05: single frame 02 05 0B */
	send_raw(0x601, 3, "02050B");
	/* response: seq, opcode, status 0, result 1, state 0x0019,
	 * "Unpowered" (u8 9 + 9 bytes) = 3 + 1 + 2 + 10 = 16 bytes */
	expect_frame(0x581, 8, "1010050B00011900");
	/* the rest after the host's flow control: go on, block size 0 */
	assert_int_equal(pending(), 0);
	send_raw(0x601, 3, "300000");
	expect_frame(0x581, 8, "2109556E706F7765"); /* 9, "Unpowe" */
	expect_frame(0x581, 4, "22726564");	    /* "red" */
	assert_int_equal(pending(), 0);

	/* moveForward -20.5 mm, seq 6: 2 + 8 = 10 bytes, a first frame and
	 * one consecutive frame; refused (Unpowered): result 0. The first
	 * frame is answered with flow control: go on, block size 0, STmin 0. */
	send_raw(0x601, 8, "100A061100000000");
	expect_frame(0x581, 3, "300000");
	assert_int_equal(pending(), 0);
	send_raw(0x601, 5, "21008034C0");
	expect_frame(0x581, 5, "0406110000");
	/* unknown opcode 0x50: NAK reason 4 */
	send_raw(0x601, 3, "020750");
	expect_frame(0x581, 4, "03075004");
	/* getPosition with a stray argument byte: NAK reason 3 (length) */
	send_raw(0x601, 4, "03080900");
	expect_frame(0x581, 4, "03080903");
	/* setPower with boolean 2: NAK reason 5 (value) */
	send_raw(0x601, 4, "03091E02");
	expect_frame(0x581, 4, "03091E05");
	/* a request longer than any operation's: flow control "overflow",
	 * then NAK 2 */
	send_raw(0x601, 8, "10400A1100000000");
	expect_frame(0x581, 3, "320000");
	expect_frame(0x581, 4, "030A1102");
	assert_int_equal(U.link.stats.naks, 4);
	assert_int_equal(U.link.stats.requests, 2);
	assert_int_equal(U.link.stats.fc_sent, 2);
	assert_int_equal(U.link.stats.rx_flow, 1);
	assert_int_equal(U.link.stats.rx_bad_pci, 0);
}

/* A long response under the host's flow control (ISO 15765-2): block size
 * and STmin honoured, "wait" restarts the wait, "overflow" and silence give
 * the response up; a flow control frame nobody waits for is ignored. */
static void test_response_flow_control(void **state)
{
	static const char ver[] = "RTC VehicleService interface: ver.2.0.0";
	uint8_t buf[CANLINK_RESP_MAX];
	canlink_rx_t rx;
	canlink_frame_t f;
	size_t first;

	(void)state;
	canlink_rx_init(&rx, buf, sizeof(buf));
	/* getIFVersion: 3 + 1 + 1 + 39 = 44 bytes, first frame and 6 more */
	send_raw(0x601, 3, "022007");
	f = pop();
	assert_int_equal(canlink_rx_feed(&rx, &f, 0), CANLINK_RX_PENDING);
	assert_int_equal(f.data[1], 44);
	sim_run_ms(&U.sim, 900);
	assert_int_equal(pending(), 0);
	/* block size 2, STmin 5 ms: one at once, the next 5 ms later */
	first = U.tail;
	send_raw(0x601, 3, "300205");
	assert_int_equal(pending(), 1);
	sim_run_ms(&U.sim, 20);
	assert_int_equal(pending(), 2);
	assert_true(U.qt[(first + 1) % QN] - U.qt[first % QN] >= 5000);
	assert_true(U.qt[(first + 1) % QN] - U.qt[first % QN] <= 6000);
	/* "wait" restarts the 1 s wait: 1.8 s in all, still there */
	send_raw(0x601, 3, "310000");
	sim_run_ms(&U.sim, 900);
	send_raw(0x601, 3, "310000");
	sim_run_ms(&U.sim, 900);
	assert_int_equal(pending(), 2);
	assert_int_equal(U.link.stats.tx_fc_timeouts, 0);
	/* the rest, STmin 500 us (0xF5): one frame per 1 ms tick */
	first = U.tail;
	send_raw(0x601, 3, "3000F5");
	sim_run_ms(&U.sim, 10);
	assert_int_equal(pending(), 6);
	for (unsigned i = 1; i < 4; i++)
		assert_int_equal(U.qt[(first + i) % QN] - U.qt[(first + i - 1) % QN], 1000);
	for (unsigned i = 0; i < 6; i++) {
		f = pop();
		assert_int_equal(canlink_rx_feed(&rx, &f, 0),
				 i == 5 ? CANLINK_RX_DONE : CANLINK_RX_PENDING);
	}
	assert_int_equal(rx.len, 44);
	assert_memory_equal(buf + 5, ver, 39);
	assert_int_equal(U.link.stats.tx_abandoned + U.link.stats.tx_overflow, 0);

	/* no flow control within 1 s: the response is given up */
	send_raw(0x601, 3, "022107");
	expect_frame(0x581, 8, "102C210700012752");
	sim_run_ms(&U.sim, 1002);
	assert_int_equal(U.link.stats.tx_fc_timeouts, 1);
	send_raw(0x601, 3, "300000"); /* late: ignored */
	assert_int_equal(pending(), 0);
	/* overflow: given up at once */
	send_raw(0x601, 3, "022207");
	expect_frame(0x581, 8, "102C220700012752");
	send_raw(0x601, 3, "320000");
	sim_run_ms(&U.sim, 10);
	assert_int_equal(pending(), 0);
	assert_int_equal(U.link.stats.tx_overflow, 1);
	/* a retransmission is answered from the cache, under flow control too */
	send_raw(0x601, 3, "022207");
	expect_frame(0x581, 8, "102C220700012752");
	send_raw(0x601, 3, "300000");
	assert_int_equal(pending(), 6);
	assert_int_equal(U.link.stats.replays, 1);
	assert_int_equal(U.link.stats.requests, 3);
	assert_int_equal(U.link.stats.rx_flow, 7);
	assert_int_equal(U.link.stats.rx_bad_pci, 0);
}

static void test_node_id(void **state)
{
	(void)state;
	vc_close(&C);
	canlink_config_t bad = {.node = 0, .status_hz = 10};
	canlink_t l;
	assert_int_equal(canlink_init(&l, sim_vehicle(&U.sim), &bad, unit_send, &U), -1);
	bad.node = 128;
	assert_int_equal(canlink_init(&l, sim_vehicle(&U.sim), &bad, unit_send, &U), -1);
	bad.node = 1;
	bad.status_hz = 1001;
	assert_int_equal(canlink_init(&l, sim_vehicle(&U.sim), &bad, unit_send, &U), -1);

	boot_all(42, 0);
	/* node 1's request is not for us */
	send_raw(0x601, 3, "02050B");
	assert_int_equal(pending(), 0);
	assert_int_equal(U.link.stats.rx_foreign, 1);
	send_raw(0x600 + 42, 3, "02050B");
	canlink_frame_t f = pop();
	assert_int_equal(f.id, 0x580 + 42);
	assert_string_equal(can_line("getState"), "ok true 25 \"Unpowered\"");
}

/* ---- retransmission ------------------------------------------------------ */

static void test_retransmission_runs_once(void **state)
{
	vs_diag_t d;

	(void)state;
	assert_string_equal(can_line("setPower true"), "ok true");
	assert_string_equal(can_line("setServo true"), "ok true");
	assert_string_equal(can_line("pause"), "ok true");
	/* moveLinearAbs 300 0 0, seq 0x40, sent twice: queued once */
	static const char *ff = "101A4013"
				"00000000";
	/* x = 300.0 = 0x4072C00000000000, y = theta = 0 */
	static const char *cf[3] = {"2100C07240000000", "2200000000000000", "23000000000000"};
	for (int rep_i = 0; rep_i < 2; rep_i++) {
		send_raw(0x601, 8, ff);
		expect_frame(0x581, 3, "300000");
		send_raw(0x601, 8, cf[0]);
		send_raw(0x601, 8, cf[1]);
		send_raw(0x601, 7, cf[2]);
		expect_frame(0x581, 5, "0440130001");
	}
	vehicle_diag(sim_vehicle(&U.sim), &d);
	assert_int_equal(d.queue_len, 1);
	assert_int_equal(U.link.stats.replays, 1);
	/* the same bytes under a new sequence number run again */
	send_raw(0x601, 8, "101A411300000000");
	expect_frame(0x581, 3, "300000");
	send_raw(0x601, 8, cf[0]);
	send_raw(0x601, 8, cf[1]);
	send_raw(0x601, 7, cf[2]);
	expect_frame(0x581, 5, "0441130001");
	vehicle_diag(sim_vehicle(&U.sim), &d);
	assert_int_equal(d.queue_len, 2);
	/* through the client: the answer to the first attempt is lost, the
	 * retry (same sequence number) is answered from the cache */
	U.lose = true;
	C.timeout_ms = 50;
	C.retries = 0;
	bool ret = true;
	vs_position_t p = {600, 0, 0};
	assert_int_equal(vc_moveLinearAbs(&C, &ret, p), VC_E_TIMEOUT);
	U.lose = false;
	U.head = U.tail; /* whatever was half sent */
	vehicle_diag(sim_vehicle(&U.sim), &d);
	assert_int_equal(d.queue_len, 3);
	/* the client's next call is a new request: a new sequence number */
	assert_string_equal(can_line("resume"), "ok true");
	sim_run_ms(&U.sim, 8000);
	assert_string_equal(can_line("getPosition"), "ok true 600.000 0.000 0.000");
}

/* The client retries with the same sequence number after a timeout. */
static bool drop_first;
static int lossy_send(void *ctx, const canlink_frame_t *f)
{
	if (drop_first) {
		drop_first = false;
		return VC_OK; /* lost on the bus */
	}
	return bus_send(ctx, f);
}

static void test_client_retry(void **state)
{
	(void)state;
	vc_close(&C);
	vc_can_bus_t bus = {.send = lossy_send, .recv = bus_recv, .now_ms = bus_now_ms};
	assert_int_equal(vc_attach_can(&C, &bus, 1, 1), VC_OK);
	C.timeout_ms = 100;
	C.retries = 2;
	drop_first = true;
	uint32_t t0 = bus_now_ms(NULL);
	assert_string_equal(can_line("setPower true"), "ok true");
	assert_int_equal(bus_now_ms(NULL) - t0, 100);
	assert_int_equal(C.stats.retries, 1);
	assert_int_equal(C.stats.timeouts, 1);
	assert_int_equal(U.link.stats.requests, 1);
	assert_int_equal(U.link.stats.replays, 0);
	C.retries = 0;
	assert_string_equal(can_line("getState"), "ok true 24 \"Powered\"");
	/* a unit that never answers: timeout after all retries */
	C.retries = 2;
	U.refuse = true;
	bool ret;
	t0 = bus_now_ms(NULL);
	assert_int_equal(vc_clearAlarm(&C, &ret), VC_E_TIMEOUT);
	assert_int_equal(bus_now_ms(NULL) - t0, 300);
	/* ran once; the two retries were answered from the cache */
	assert_int_equal(U.link.stats.requests, 3); /* setPower, getState, clearAlarm */
	assert_int_equal(U.link.stats.replays, 2);
	U.refuse = false;
	/* NAK is reported as such, with its reason */
	cmd_value_t in[1], out[1];
	cmd_def_t fake = *cmd_by_opcode(CMD_OP_clearAlarm);
	fake.opcode = 0x60;
	assert_int_equal(vc_call(&C, &fake, in, &ret, out), VC_E_NAK);
	assert_int_equal(C.nak, WIRE_ST_OPCODE);
}

/* ---- status frames ------------------------------------------------------- */

static void test_status_frames(void **state)
{
	canlink_status_t st;

	(void)state;
	vc_close(&C);
	boot_all(3, 10);
	sim_run_ms(&U.sim, 1000);
	/* polls at 1..1000 ms; groups at 1, 101, ... 901 ms */
	assert_int_equal(pending(), 50);
	for (unsigned g = 0; g < 10; g++) {
		canlink_frame_t a = pop(), b = pop(), c = pop(), d = pop(), e = pop();
		assert_int_equal(a.id, 0x183);
		assert_int_equal(b.id, 0x283);
		assert_int_equal(c.id, 0x383);
		assert_int_equal(d.id, 0x483);
		assert_int_equal(e.id, 0x683);
		assert_int_equal(a.dlc, 8);
		/* state 0x0019, no alarm, counter g, about 25.2 V (the pack
		 * model sags a little), 0 mm/s */
		uint8_t want_a[4] = {0x19, 0x00, 0x00, (uint8_t)g};
		assert_memory_equal(a.data, want_a, 4);
		assert_in_range(a.data[4] | a.data[5] << 8, 2500, 2520);
		assert_int_equal(a.data[6] | a.data[7], 0);
		static const uint8_t zero[8] = {0};
		assert_memory_equal(b.data, zero, 8);
		assert_memory_equal(c.data, zero, 8);
		/* at rest, nothing queued, no alarm, io.xml's outputs off */
		assert_memory_equal(d.data, zero, 8);
		assert_memory_equal(e.data, zero, 8);
	}
	assert_int_equal(U.link.stats.status_sent, 10);

	/* moving: pose and speed follow the unit */
	assert_string_equal(can_line("setPower true"), "ok true");
	assert_string_equal(can_line("setServo true"), "ok true");
	assert_string_equal(can_line("setJogTimeout 10000"), "ok true");
	assert_string_equal(can_line("setPosition 1234.56 -20 -90.5"), "ok true");
	assert_string_equal(can_line("moveJog 250 0 -30"), "ok true");
	sim_run_ms(&U.sim, 800);
	U.head = U.tail;
	assert_int_equal(vc_can_status(&C, &st, 200), VC_OK);
	assert_int_equal(st.state, 0x11);
	assert_int_equal(st.vx_mm_s, 250);
	assert_int_equal(st.w_ddeg_s, -300);
	assert_int_equal(st.vy_mm_s, 0);
	assert_in_range(st.battery_cV, 2400, 2520);

	/* pose at the moment of that group, from the unit's own odometry */
	canlink_status_t now;
	canlink_status_read(sim_vehicle(&U.sim), &now);
	vs_position_t p;
	vs_getPosition(sim_vehicle(&U.sim), &p);
	assert_int_equal(now.x_dmm, (int32_t)(p.x * 10 + (p.x < 0 ? -0.5 : 0.5)));
	assert_int_equal(now.y_dmm, (int32_t)(p.y * 10 + (p.y < 0 ? -0.5 : 0.5)));
	assert_int_equal(now.theta_mdeg, (int32_t)(p.theta * 1000 + (p.theta < 0 ? -0.5 : 0.5)));
	double batt;
	vs_getBatteryVoltage(sim_vehicle(&U.sim), &batt);
	assert_int_equal(now.battery_cV, (uint16_t)(batt * 10 + 0.5));
	/* heading about -90..-114 deg: mostly -y travel, 0.8 s at <= 250 mm/s */
	assert_true(st.y_dmm < -200 - 500 && st.y_dmm > -200 - 2500);

	/* an alarm shows in the count */
	assert_string_equal(can_line("moveJog 0 10 0"), "ok false");
	assert_int_equal(vc_can_status(&C, &st, 200), VC_OK);
	assert_int_equal(st.alarms, 1);

	/* a full transmit queue loses status groups (counted) and never
	 * blocks; the response waits and goes out when the queue drains */
	uint32_t dropped = U.link.stats.status_dropped;
	U.refuse = true;
	send_raw(0x603, 3, "02770B");
	sim_run_ms(&U.sim, 500);
	assert_int_equal(U.link.stats.status_dropped - dropped, 5);
	assert_true(U.link.stats.tx_busy >= 5);
	U.head = U.tail;
	U.refuse = false;
	sim_tick(&U.sim);
	canlink_frame_t r = pop();
	assert_int_equal(r.id, 0x583);
	assert_int_equal(r.data[0], 0x10);
	assert_int_equal(r.data[2], 0x77);

	/* status off */
	vc_close(&C);
	boot_all(3, 0);
	sim_run_ms(&U.sim, 1000);
	assert_int_equal(pending(), 0);
}

/* The status layout, byte for byte, and its decoding. */
static void test_status_layout(void **state)
{
	canlink_status_t st = {.state = 0x13,
			       .alarms = 2,
			       .counter = 0xFE,
			       .battery_cV = 2375,
			       .vx_mm_s = -250,
			       .vy_mm_s = 3,
			       .w_ddeg_s = -451,
			       .x_dmm = 123456,
			       .y_dmm = -2,
			       .theta_mdeg = -179999,
			       .mvx_mm_s = -249,
			       .mvy_mm_s = 2,
			       .mw_ddeg_s = -450,
			       .queue = 7,
			       .alarm_type = 1,
			       .alarm_code = 204,
			       .inputs = 0x8001,
			       .outputs = 0x0102};
	canlink_status_t back;
	canlink_frame_t f;

	(void)state;
	memset(&back, 0, sizeof(back));
	canlink_status_frame(&st, 9, 0, &f);
	/* 0x0013, 2 alarms, counter 0xFE, 2375 = 0x0947, -250 = 0xFF06 */
	assert_int_equal(f.id, 0x189);
	assert_int_equal(f.dlc, 8);
	assert_memory_equal(f.data, "\x13\x00\x02\xFE\x47\x09\x06\xFF", 8);
	assert_int_equal(canlink_status_decode(&f, 9, &back), 0);
	canlink_status_frame(&st, 9, 1, &f);
	/* 123456 = 0x0001E240, -2 = 0xFFFFFFFE */
	assert_int_equal(f.id, 0x289);
	assert_memory_equal(f.data, "\x40\xE2\x01\x00\xFE\xFF\xFF\xFF", 8);
	assert_int_equal(canlink_status_decode(&f, 9, &back), 1);
	canlink_status_frame(&st, 9, 2, &f);
	/* -179999 = 0xFFFD40E1, 3, -451 = 0xFE3D */
	assert_int_equal(f.id, 0x389);
	assert_memory_equal(f.data, "\xE1\x40\xFD\xFF\x03\x00\x3D\xFE", 8);
	assert_int_equal(canlink_status_decode(&f, 9, &back), 2);
	canlink_status_frame(&st, 9, 3, &f);
	/* -249 = 0xFF07, 2, -450 = 0xFE3E, queue 7, a fault */
	assert_int_equal(f.id, 0x489);
	assert_memory_equal(f.data, "\x07\xFF\x02\x00\x3E\xFE\x07\x01", 8);
	assert_int_equal(canlink_status_decode(&f, 9, &back), 3);
	canlink_status_frame(&st, 9, 4, &f);
	/* 204 = 0xCC, inputs 0x8001, outputs 0x0102 */
	assert_int_equal(f.id, 0x689);
	assert_memory_equal(f.data, "\xCC\x00\x00\x00\x01\x80\x02\x01", 8);
	assert_int_equal(canlink_status_decode(&f, 9, &back), 4);
	assert_memory_equal(&back, &st, sizeof(st));
	/* another node's status, or a short frame, is not ours */
	assert_int_equal(canlink_status_decode(&f, 8, &back), -1);
	f.dlc = 7;
	assert_int_equal(canlink_status_decode(&f, 9, &back), -1);
}

/* ---- jog watchdog -------------------------------------------------------- */

static void test_jog_watchdog_on_silence(void **state)
{
	canlink_status_t st;

	(void)state;
	vc_close(&C);
	boot_all(1, 50);
	assert_string_equal(can_line("setPower true"), "ok true");
	assert_string_equal(can_line("setServo true"), "ok true");
	assert_string_equal(can_line("setJogTimeout 200"), "ok true");
	/* a host that keeps jogging keeps the unit moving */
	for (int i = 0; i < 10; i++) {
		assert_string_equal(can_line("moveJog 200 0 0"), "ok true");
		sim_run_ms(&U.sim, 100);
	}
	U.head = U.tail;
	assert_int_equal(vc_can_status(&C, &st, 100), VC_OK);
	assert_int_equal(st.vx_mm_s, 200);
	/* silence: 100..120 ms since the last jog; deceleration starts at
	 * 200 ms (500 mm/s^2: 400 ms to stop) */
	sim_run_ms(&U.sim, 60);
	U.head = U.tail;
	assert_int_equal(vc_can_status(&C, &st, 100), VC_OK);
	assert_int_equal(st.vx_mm_s, 200);
	sim_run_ms(&U.sim, 600);
	U.head = U.tail;
	assert_int_equal(vc_can_status(&C, &st, 100), VC_OK);
	assert_int_equal(st.vx_mm_s, 0);
	assert_int_equal(st.state, 0x10);
	assert_string_equal(can_line("getState"), "ok true 16 \"Ready\"");
}

/* ---- bad input ----------------------------------------------------------- */

/* Queued motion on a paused unit: bad input must neither move it nor lose
 * the queue. */
static void paused_with_queue(void)
{
	assert_string_equal(can_line("setPower true"), "ok true");
	assert_string_equal(can_line("setServo true"), "ok true");
	assert_string_equal(can_line("pause"), "ok true");
	assert_string_equal(can_line("moveLinearAbs 300 0 0"), "ok true");
	assert_string_equal(can_line("moveLinearAbs 600 0 0"), "ok true");
	assert_string_equal(can_line("moveLinearAbs 900 0 0"), "ok true");
}

static void still_paused_then_completes(void)
{
	vs_diag_t d;
	vehicle_diag(sim_vehicle(&U.sim), &d);
	assert_int_equal(d.queue_len, 3);
	assert_string_equal(can_line("getState"), "ok true 21 \"Paused\"");
	assert_string_equal(can_line("getPosition"), "ok true 0.000 0.000 0.000");
	assert_true(sim_exec(&U.sim, "$sim pose", rep, sizeof(rep)));
	assert_string_equal(rep, "ok pose 0.000 0.000 0.000");
	assert_string_equal(can_line("resume"), "ok true");
	sim_run_ms(&U.sim, 10000);
	assert_string_equal(can_line("getPosition"), "ok true 900.000 0.000 0.000");
	assert_string_equal(can_line("getState"), "ok true 16 \"Ready\"");
}

static uint32_t rng = 12345;
static uint32_t rnd(void)
{
	rng = rng * 1103515245u + 12345u;
	return rng >> 8;
}

/* Every kind of malformed frame, in known numbers, interleaved, at a rate
 * no bus can carry (all within one tick); each is counted exactly. */
static void test_bad_frames_counted(void **state)
{
	(void)state;
	paused_with_queue();
	U.head = U.tail;
	canlink_stats_t s0 = U.link.stats;
	unsigned n_dlc = 0, n_pci = 0, n_seq = 0, n_disc = 0, n_over = 0, n_nak = 0, n_foreign = 0;
	unsigned n_timeout = 0, n_abort = 0, n_short = 0, n_flow = 0, n_cts = 0, n_ovfl = 0;
	unsigned got_nak = 0, got_cts = 0, got_ovfl = 0;

	for (unsigned i = 0; i < 20000; i++) {
		canlink_frame_t f;
		/* Every frame the unit sent: a NAK (a single frame with a
		 * non-zero reason) or a flow control frame for a first frame. */
		while (pending()) {
			f = pop();
			assert_int_equal(f.id, 0x581);
			if (f.dlc == CANLINK_FC_DLC) {
				assert_true(f.data[0] == 0x30 || f.data[0] == 0x32);
				assert_int_equal(f.data[1], 0);
				assert_int_equal(f.data[2], 0);
				got_cts += f.data[0] == 0x30;
				got_ovfl += f.data[0] == 0x32;
				continue;
			}
			assert_int_equal(f.dlc, 4);
			assert_int_equal(f.data[0], 3);
			assert_true(f.data[3] == WIRE_ST_OVERSIZE || f.data[3] == WIRE_ST_OPCODE ||
				    f.data[3] == WIRE_ST_LENGTH || f.data[3] == WIRE_ST_TRUNCATED);
			got_nak++;
		}
		memset(&f, 0, sizeof(f));
		f.id = 0x601;
		f.dlc = 8;
		for (unsigned k = 0; k < 8; k++)
			f.data[k] = (uint8_t)rnd();
		switch (i % 11) {
		case 0: /* empty */
			f.dlc = 0;
			n_dlc++;
			break;
		case 1: /* reserved frame types; flow control frames nobody waits
			 * for are taken silently */
			if (rnd() % 2) {
				f.data[0] = (uint8_t)(0x30 | (f.data[0] & 15));
				f.dlc = (uint8_t)(3 + rnd() % 6);
				n_flow++;
				break;
			}
			f.data[0] = (uint8_t)((4 + rnd() % 12) << 4 | (f.data[0] & 15));
			n_pci++;
			break;
		case 2: /* consecutive frame without a first */
			f.data[0] = (uint8_t)(0x20 | (f.data[0] & 15));
			n_seq++;
			break;
		case 3: /* single frame announcing more than it carries */
			f.data[0] = (uint8_t)(2 + rnd() % 6);
			f.dlc = (uint8_t)(1 + rnd() % f.data[0]);
			n_dlc++;
			break;
		case 4: /* first frame shorter than 8 */
			f.data[0] = 0x10;
			f.data[1] = 20;
			f.dlc = (uint8_t)(2 + rnd() % 6);
			n_dlc++;
			break;
		case 5: { /* oversize message: first frame and 3 of its followers */
			unsigned len = 27 + rnd() % (CANLINK_MSG_LIMIT - 27);
			f.data[0] = (uint8_t)(0x10 | len >> 8);
			f.data[1] = (uint8_t)len;
			canlink_rx(&U.link, &f, now_us());
			for (unsigned k = 1; k <= 3; k++) {
				f.data[0] = (uint8_t)(0x20 | k);
				canlink_rx(&U.link, &f, now_us());
			}
			n_over++;
			n_nak++;
			n_ovfl++;
			n_disc += 3;
			continue;
		}
		case 6: /* unknown opcodes: 35..126 and 128..255 */
			f.data[0] = 0x02;
			f.data[2] = (uint8_t)(35 + rnd() % 221);
			if (f.data[2] == WIRE_OP_INFO)
				f.data[2] = 0xFF;
			f.dlc = 3;
			n_nak++;
			break;
		case 7: /* a motion command with the wrong payload size */
			f.data[0] = 0x06;
			f.data[2] = CMD_OP_moveForward;
			f.dlc = 7;
			n_nak++;
			break;
		case 8: /* other identifiers */
			f.id = rnd() % 0x800;
			if (f.id == 0x601)
				f.id = 0x602;
			n_foreign++;
			break;
		case 9: /* truncated: a first frame, then a new start aborts it */
			f.data[0] = 0x10;
			f.data[1] = 20;
			canlink_rx(&U.link, &f, now_us());
			f.data[0] = 0x01; /* a single frame of 1 byte: no opcode */
			f.dlc = 2;
			n_abort++;
			n_short++;
			n_cts++;
			break;
		default: /* a first frame left hanging until it times out */
			f.data[0] = 0x10;
			f.data[1] = 20;
			canlink_rx(&U.link, &f, now_us());
			sim_run_ms(&U.sim, CANLINK_RX_TIMEOUT_US / 1000 + 2);
			n_timeout++;
			n_nak++;
			n_cts++;
			continue;
		}
		canlink_rx(&U.link, &f, now_us());
	}
	canlink_stats_t s = U.link.stats;
	assert_int_equal(s.rx_bad_dlc - s0.rx_bad_dlc, n_dlc);
	assert_int_equal(s.rx_bad_pci - s0.rx_bad_pci, n_pci);
	assert_int_equal(s.rx_sequence - s0.rx_sequence, n_seq);
	assert_int_equal(s.rx_discarded - s0.rx_discarded, n_disc);
	assert_int_equal(s.rx_oversize - s0.rx_oversize, n_over);
	assert_int_equal(s.rx_foreign - s0.rx_foreign, n_foreign);
	assert_int_equal(s.rx_timeouts - s0.rx_timeouts, n_timeout);
	assert_int_equal(s.rx_aborted - s0.rx_aborted, n_abort);
	assert_int_equal(s.rx_short - s0.rx_short, n_short);
	assert_int_equal(s.naks - s0.naks, n_nak);
	assert_int_equal(s.rx_flow - s0.rx_flow, n_flow);
	assert_int_equal(s.fc_sent - s0.fc_sent, n_cts + n_ovfl);
	assert_int_equal(s.requests, s0.requests);
	/* every NAK and flow control frame went out */
	while (pending()) {
		canlink_frame_t f = pop();
		if (f.dlc == CANLINK_FC_DLC) {
			got_cts += f.data[0] == 0x30;
			got_ovfl += f.data[0] == 0x32;
		} else {
			got_nak++;
		}
	}
	assert_int_equal(got_nak, n_nak);
	assert_int_equal(got_cts, n_cts);
	assert_int_equal(got_ovfl, n_ovfl);
	still_paused_then_completes();
}

/* Uniformly random frames on the request identifier: whatever they decode
 * to, the link survives, counts every frame, and answers a real request
 * right after. The unit is unpowered and stays so unless a random frame
 * happened to be a well-formed setPower, which the counters would show. */
static void test_random_frames(void **state)
{
	(void)state;
	U.head = U.tail;
	for (unsigned i = 0; i < 200000; i++) {
		canlink_frame_t f;
		f.id = 0x601;
		f.dlc = (uint8_t)(rnd() % 9);
		for (unsigned k = 0; k < 8; k++)
			f.data[k] = (uint8_t)rnd();
		canlink_rx(&U.link, &f, now_us());
		if (i % 1000 == 0)
			sim_tick(&U.sim);
		U.head = U.tail;
	}
	canlink_stats_t s = U.link.stats;
	assert_int_equal(s.rx_frames, 200000);
	assert_true(s.rx_bad_dlc + s.rx_bad_pci + s.rx_sequence > 100000);
	/* resynchronised: the next request is answered normally */
	bool ret = false;
	vs_position_t p = {1, 1, 1};
	assert_int_equal(vc_getPosition(&C, &ret, &p), VC_OK);
	assert_true(ret);
}

/* A flood of garbage while the unit moves: the motion runs exactly as
 * without it. */
static void test_flood_while_moving(void **state)
{
	(void)state;
	assert_string_equal(can_line("setPower true"), "ok true");
	assert_string_equal(can_line("setServo true"), "ok true");
	assert_string_equal(can_line("moveLinearAbs 300 0 0"), "ok true");
	assert_string_equal(can_line("moveLinearAbs 600 0 0"), "ok true");
	/* 8000 frames per simulated second (beyond 1 Mbit/s) for 5 s */
	for (unsigned t = 0; t < 5000; t++) {
		for (unsigned k = 0; k < 8; k++) {
			canlink_frame_t f = frame(0x601, 8, "2300000000000000");
			f.data[1] = (uint8_t)rnd();
			canlink_rx(&U.link, &f, now_us());
		}
		sim_tick(&U.sim);
	}
	assert_int_equal(U.link.stats.rx_sequence, 40000);
	U.head = U.tail;
	assert_string_equal(can_line("getPosition"), "ok true 600.000 0.000 0.000");
	assert_string_equal(can_line("getState"), "ok true 16 \"Ready\"");
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test(test_segmentation_counts_and_bytes),
	    cmocka_unit_test(test_segmentation_roundtrip),
	    cmocka_unit_test(test_reassembly_errors),
	    cmocka_unit_test_setup_teardown(test_every_op_matches_console, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_info, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_typed_functions, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_wire_layout, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_response_flow_control, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_node_id, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_retransmission_runs_once, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_client_retry, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_status_frames, setup, teardown),
	    cmocka_unit_test(test_status_layout),
	    cmocka_unit_test_setup_teardown(test_jog_watchdog_on_silence, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_bad_frames_counted, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_random_frames, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_flood_while_moving, setup, teardown),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
