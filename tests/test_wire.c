/* Wire encoding of the command-table types and the generic binary dispatch:
 * exact bytes, bounds and every malformed input. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "../host_sim/sim.h"
#include "../proto/dispatch.h"
#include "../proto/wire.h"

static void test_scalars_exact_bytes(void **state)
{
	cmd_value_t v[3];
	uint8_t b[32];
	size_t n = 0;
	static const uint8_t want[] = {0x01, 0xFE, 0xFF, 0x78, 0x56, 0x34, 0x12};

	(void)state;
	v[0].b = true;
	v[1].h = -2;
	v[2].u = 0x12345678u;
	assert_int_equal(wire_encode("bhu", 3, v, b, sizeof(b), &n), WIRE_ST_OK);
	assert_int_equal(n, sizeof(want));
	assert_memory_equal(b, want, sizeof(want));

	/* 500.0 = 0x407F400000000000, little-endian. */
	{
		static const uint8_t d500[] = {0, 0, 0, 0, 0, 0x40, 0x7F, 0x40};

		v[0].d = 500.0;
		assert_int_equal(wire_encode("d", 1, v, b, sizeof(b), &n), WIRE_ST_OK);
		assert_int_equal(n, 8);
		assert_memory_equal(b, d500, 8);
	}
}

static void test_round_trip_all_types(void **state)
{
	wire_store_t st;
	vs_alarm_t a[2] = {{201, VS_ALARM_FAULT, "axis 0 drive fault 0x0042"},
			   {120, VS_ALARM_WARNING, ""}};
	cmd_value_t in[3], out[3];
	uint8_t b[256];
	size_t n = 0;

	(void)state;
	in[0].h = -32768;
	in[1].s = "Warning-120";
	in[2].alarms.a = a;
	in[2].alarms.n = 2;
	assert_int_equal(wire_encode("hsa", 3, in, b, sizeof(b), &n), WIRE_ST_OK);
	/* 2 + (1 + 11) + 1 + (5 + 1 + 25) + (5 + 1 + 0) */
	assert_int_equal(n, 52);
	assert_int_equal(wire_decode("hsa", 3, b, n, out, &st), WIRE_ST_OK);
	assert_int_equal(out[0].h, -32768);
	assert_string_equal(out[1].s, "Warning-120");
	assert_int_equal(out[2].alarms.n, 2);
	assert_int_equal(out[2].alarms.a[0].code, 201);
	assert_int_equal(out[2].alarms.a[0].type, VS_ALARM_FAULT);
	assert_string_equal(out[2].alarms.a[0].source, "axis 0 drive fault 0x0042");
	assert_int_equal(out[2].alarms.a[1].code, 120);
	assert_string_equal(out[2].alarms.a[1].source, "");

	in[0].d = -0.1;
	assert_int_equal(wire_encode("d", 1, in, b, sizeof(b), &n), WIRE_ST_OK);
	assert_int_equal(wire_decode("d", 1, b, n, out, &st), WIRE_ST_OK);
	assert_true(out[0].d == -0.1);
}

static void test_encode_bounds(void **state)
{
	char longs[300];
	cmd_value_t v[1];
	vs_alarm_t a[1] = {{1, 1, "x"}};
	uint8_t b[16];
	size_t n = 77;

	(void)state;
	v[0].d = 1.0;
	/* Not one byte of a field that does not fit, and *len untouched. */
	assert_int_equal(wire_encode("d", 1, v, b, 7, &n), WIRE_ST_SPACE);
	assert_int_equal(n, 77);
	memset(longs, 'a', sizeof(longs));
	longs[256] = '\0';
	v[0].s = longs;
	assert_int_equal(wire_encode("s", 1, v, b, sizeof(b), &n), WIRE_ST_VALUE);
	longs[255] = '\0';
	assert_int_equal(wire_encode("s", 1, v, b, sizeof(b), &n), WIRE_ST_SPACE);
	v[0].alarms.a = a;
	v[0].alarms.n = VS_ALARM_LIST_MAX + 1;
	assert_int_equal(wire_encode("a", 1, v, b, sizeof(b), &n), WIRE_ST_VALUE);
	assert_int_equal(wire_encode("x", 1, v, b, sizeof(b), &n), WIRE_ST_VALUE);
}

static void test_decode_malformed(void **state)
{
	wire_store_t st;
	cmd_value_t v[3];
	uint8_t b[80];

	(void)state;
	memset(b, 0, sizeof(b));
	/* short, trailing */
	assert_int_equal(wire_decode("d", 1, b, 7, v, &st), WIRE_ST_LENGTH);
	assert_int_equal(wire_decode("d", 1, b, 9, v, &st), WIRE_ST_LENGTH);
	assert_int_equal(wire_decode("", 0, b, 1, v, &st), WIRE_ST_LENGTH);
	assert_int_equal(wire_decode("", 0, b, 0, v, &st), WIRE_ST_OK);
	/* boolean 2 */
	b[0] = 2;
	assert_int_equal(wire_decode("b", 1, b, 1, v, &st), WIRE_ST_VALUE);
	/* string longer than its bytes */
	b[0] = 5;
	memcpy(b + 1, "abc", 3);
	assert_int_equal(wire_decode("s", 1, b, 4, v, &st), WIRE_ST_LENGTH);
	/* string with a NUL inside */
	b[0] = 3;
	b[1] = 'a';
	b[2] = 0;
	b[3] = 'b';
	assert_int_equal(wire_decode("s", 1, b, 4, v, &st), WIRE_ST_VALUE);
	/* 17 alarms */
	b[0] = VS_ALARM_LIST_MAX + 1;
	assert_int_equal(wire_decode("a", 1, b, 1, v, &st), WIRE_ST_VALUE);
	/* alarm source of 64 bytes */
	memset(b, 0x41, sizeof(b));
	b[0] = 1;
	b[5] = 2;
	b[6] = 64;
	assert_int_equal(wire_decode("a", 1, b, 7 + 64, v, &st), WIRE_ST_VALUE);
	b[6] = 63;
	assert_int_equal(wire_decode("a", 1, b, 7 + 63, v, &st), WIRE_ST_OK);
	assert_int_equal(v[0].alarms.n, 1);
	assert_int_equal(strlen(v[0].alarms.a[0].source), 63);
	/* response: result byte must be 0/1 */
	b[0] = 7;
	{
		bool r;

		assert_int_equal(wire_decode_response(cmd_by_opcode(CMD_OP_stop), b, 1, &r, v, &st),
				 WIRE_ST_VALUE);
		assert_int_equal(wire_decode_response(cmd_by_opcode(CMD_OP_stop), b, 0, &r, v, &st),
				 WIRE_ST_LENGTH);
	}
}

static sim_t S;

static void boot(void)
{
	vs_config_t cfg;
	plant_params_t pp;

	vs_config_defaults(&cfg);
	/* Time passes in lockstep waits with no request; the link watchdog
	 * has its own tests. */
	cfg.link_timeout_ms = 0;
	plant_params_default(&pp);
	assert_int_equal(sim_init(&S, &cfg, &pp), 0);
}

static void test_dispatch(void **state)
{
	uint8_t req[32], resp[WIRE_RESP_MAX];
	cmd_value_t in[3];
	size_t n, len;
	int st = -1;
	vs_diag_t d;

	(void)state;
	boot();
	/* getState: true, 25 Unpowered */
	n = wire_dispatch(&S.vehicle, CMD_OP_getState, NULL, 0, resp, sizeof(resp), &st);
	assert_int_equal(st, WIRE_ST_OK);
	{
		static const uint8_t want[] = {1,   25,	 0,   9,   'U', 'n', 'p',
					       'o', 'w', 'e', 'r', 'e', 'd'};

		assert_int_equal(n, sizeof(want));
		assert_memory_equal(resp, want, sizeof(want));
	}
	/* setPower true, setServo true, moveForward 500 runs */
	req[0] = 1;
	n = wire_dispatch(&S.vehicle, CMD_OP_setPower, req, 1, resp, sizeof(resp), &st);
	assert_int_equal(st, WIRE_ST_OK);
	assert_int_equal(n, 1);
	assert_int_equal(resp[0], 1);
	n = wire_dispatch(&S.vehicle, CMD_OP_setServo, req, 1, resp, sizeof(resp), &st);
	assert_int_equal(st, WIRE_ST_OK);
	assert_int_equal(n, 1);
	assert_int_equal(resp[0], 1);
	/* malformed requests: nothing runs */
	in[0].d = 500;
	assert_int_equal(
	    wire_encode_request(cmd_by_opcode(CMD_OP_moveForward), in, req, sizeof(req), &len),
	    WIRE_ST_OK);
	assert_int_equal(len, 8);
	n = wire_dispatch(&S.vehicle, CMD_OP_moveForward, req, 7, resp, sizeof(resp), &st);
	assert_int_equal(st, WIRE_ST_LENGTH);
	assert_int_equal(n, 0);
	n = wire_dispatch(&S.vehicle, CMD_OP_moveForward, req, 9, resp, sizeof(resp), &st);
	assert_int_equal(st, WIRE_ST_LENGTH);
	assert_int_equal(n, 0);
	n = wire_dispatch(&S.vehicle, 0, req, 8, resp, sizeof(resp), &st);
	assert_int_equal(st, WIRE_ST_OPCODE);
	assert_int_equal(n, 0);
	n = wire_dispatch(&S.vehicle, 35, req, 8, resp, sizeof(resp), &st);
	assert_int_equal(st, WIRE_ST_OPCODE);
	assert_int_equal(n, 0);
	req[8] = 2;
	n = wire_dispatch(&S.vehicle, CMD_OP_setPower, req + 8, 1, resp, sizeof(resp), &st);
	assert_int_equal(st, WIRE_ST_VALUE);
	assert_int_equal(n, 0);
	vehicle_diag(&S.vehicle, &d);
	assert_int_equal(d.queue_len, 0);
	assert_int_equal(d.mode, 0);
	/* the well-formed one moves */
	n = wire_dispatch(&S.vehicle, CMD_OP_moveForward, req, 8, resp, sizeof(resp), &st);
	assert_int_equal(st, WIRE_ST_OK);
	assert_int_equal(n, 1);
	assert_int_equal(resp[0], 1);
	vehicle_diag(&S.vehicle, &d);
	assert_int_not_equal(d.mode, 0);
	/* protocol info */
	n = wire_dispatch(&S.vehicle, WIRE_OP_INFO, NULL, 0, resp, sizeof(resp), &st);
	assert_int_equal(st, WIRE_ST_OK);
	assert_int_equal(n, WIRE_INFO_LEN);
	assert_int_equal(resp[0], CMD_PROTO_VERSION);
	assert_int_equal(wire_get_u16(resp + 1), cmd_table_crc());
	assert_int_equal(resp[3], 34);
	assert_int_equal(wire_get_u16(resp + 4), 24);
	assert_int_equal(wire_get_u16(resp + 6), WIRE_RESP_MAX);
	n = wire_dispatch(&S.vehicle, WIRE_OP_INFO, req, 1, resp, sizeof(resp), &st);
	assert_int_equal(st, WIRE_ST_LENGTH);
}

/* WIRE_REQ_MAX and WIRE_RESP_MAX really bound every row. */
static void test_limits_cover_table(void **state)
{
	(void)state;
	for (unsigned i = 0; i < CMD_COUNT; i++) {
		const cmd_def_t *d = &cmd_table[i];
		size_t in = 0, out = 1;

		for (unsigned k = 0; k < d->n_in; k++)
			in += d->in_types[k] == 'd'   ? 8
			      : d->in_types[k] == 'u' ? 4
			      : d->in_types[k] == 'h' ? 2
			      : d->in_types[k] == 'b' ? 1
						      : 10000;
		for (unsigned k = 0; k < d->n_out; k++)
			out += d->out_types[k] == 'd'	? 8
			       : d->out_types[k] == 'u' ? 4
			       : d->out_types[k] == 'h' ? 2
			       : d->out_types[k] == 'b' ? 1
			       : d->out_types[k] == 's'
				   ? 1 + WIRE_STR_MAX
				   : 1 + VS_ALARM_LIST_MAX * WIRE_ALARM_MAX_BYTES;
		assert_true(in <= WIRE_REQ_MAX);
		/* getState's string is at most VS_STATE_MSG_MAX - 1 bytes in practice;
		 * the bound that matters is the alarm list. */
		if (strchr(d->out_types, 'a'))
			assert_int_equal(out, WIRE_RESP_MAX);
		else
			assert_true(out <= WIRE_RESP_MAX);
	}
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test(test_scalars_exact_bytes),
	    cmocka_unit_test(test_round_trip_all_types),
	    cmocka_unit_test(test_encode_bounds),
	    cmocka_unit_test(test_decode_malformed),
	    cmocka_unit_test(test_dispatch),
	    cmocka_unit_test(test_limits_cover_table),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
