/* Console unit tests: the line parser, the reply formatter, line assembly
 * from a byte stream, the command table and the '$' extras, against the
 * real firmware on the fake HAL. Every expected reply is written out in full.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "../firmware/vehicle.h"
#include "../proto/cmdtab.h"
#include "../proto/console.h"
#include "../proto/numparse.h"
#include "fake_hal.h"

static fake_hal_t fh;
static vehicle_t veh;
static console_t con;
static char out[1 << 16]; /* what console_feed wrote */
static size_t out_len;
static char rep[CONSOLE_REPLY_MAX];

static void collect(void *ctx, const char *s, size_t n)
{
	(void)ctx;
	assert_true(out_len + n < sizeof(out));
	memcpy(out + out_len, s, n);
	out_len += n;
	out[out_len] = '\0';
}

static int setup(void **state)
{
	vs_config_t cfg;
	vs_hal_t hal;
	const char *bad = NULL;

	(void)state;
	fake_hal_config(&cfg);
	fake_hal_init(&fh, cfg.tick_hz);
	hal = fake_hal_bind(&fh);
	memset(&veh, 0, sizeof(veh));
	assert_int_equal(vehicle_init(&veh, &cfg, &hal, &bad), 0);
	console_init(&con, &veh, collect, NULL);
	out_len = 0;
	out[0] = '\0';
	return 0;
}

/* Runs one line; "(none)" when it gets no reply. */
static const char *ex(const char *line)
{
	if (!console_exec(&con, line, rep, sizeof(rep)))
		return "(none)";
	return rep;
}

#define EXPECT(line, reply) assert_string_equal(ex(line), reply)
/* s starts with the literal prefix p */
#define PREFIX(s, p) assert_memory_equal(s, p, sizeof(p) - 1)

static void feed_str(const char *s, size_t n)
{
	console_feed(&con, (const uint8_t *)s, n);
}

#define FEED(lit) feed_str(lit, sizeof(lit) - 1)

static void power_up(void)
{
	EXPECT("setPower true", "ok true");
	EXPECT("setServo true", "ok true");
	EXPECT("getState", "ok true 16 \"Ready\"");
}

/* ---- the command table --------------------------------------------------- */

static const char *const spec_order[34] = {
    "clearAlarm",
    "getAccelerationLimit",
    "getActiveAlarm",
    "getBatteryVoltage",
    "getDefaultAcceleration",
    "getDefaultVelocity",
    "getIFVersion",
    "getInput",
    "getPosition",
    "getServoStatus",
    "getState",
    "getVelocityLimit",
    "getVersion",
    "moveCircularRel",
    "moveContinuousRel",
    "moveCruiseAbs",
    "moveForward",
    "moveJog",
    "moveLinearAbs",
    "moveLinearRel",
    "moveTurn",
    "pause",
    "resume",
    "setAcceleration",
    "setDigitalSensorLock",
    "setJogTimeout",
    "setJoystick",
    "setOutput",
    "setPosition",
    "setPower",
    "setServo",
    "setVelocity",
    "stop",
    "unlock",
};

static void test_table_order_and_opcodes(void **state)
{
	(void)state;
	assert_int_equal(CMD_COUNT, 34);
	for (unsigned i = 0; i < 34; i++) {
		assert_string_equal(cmd_table[i].name, spec_order[i]);
		assert_int_equal(cmd_table[i].opcode, i + 1);
		assert_ptr_equal(cmd_by_opcode(i + 1), &cmd_table[i]);
		assert_ptr_equal(cmd_by_name(spec_order[i]), &cmd_table[i]);
	}
	/* cmd_by_name searches the rows as they stand: in the names' order */
	for (unsigned i = 1; i < 34; i++)
		assert_true(np_cmp_nocase(cmd_table[i - 1].name, cmd_table[i].name) < 0);
	assert_null(cmd_by_opcode(0));
	assert_null(cmd_by_opcode(35));
	assert_ptr_equal(cmd_by_name("MOVEFORWARD"), &cmd_table[16]);
	assert_ptr_equal(cmd_by_name("getstate"), &cmd_table[10]);
	assert_null(cmd_by_name("moveForwar"));
	assert_null(cmd_by_name("moveForwardx"));
	assert_null(cmd_by_name(""));
	assert_int_equal(CMD_OP_moveForward, 17);
	assert_int_equal(CMD_OP_unlock, 34);
}

static void test_table_layouts(void **state)
{
	(void)state;
	for (unsigned i = 0; i < CMD_COUNT; i++) {
		const cmd_def_t *d = &cmd_table[i];
		const char *f;

		assert_int_equal(strlen(d->in_types), d->n_in);
		assert_int_equal(strlen(d->out_types), d->n_out);
		/* one name per type code, no more */
		for (unsigned k = 0; k < d->n_in; k++)
			assert_true(cmd_field_name(d->in_names, k, &f) > 0);
		assert_int_equal(cmd_field_name(d->in_names, d->n_in, &f), 0);
		for (unsigned k = 0; k < d->n_out; k++)
			assert_true(cmd_field_name(d->out_names, k, &f) > 0);
		assert_int_equal(cmd_field_name(d->out_names, d->n_out, &f), 0);
		for (const char *t = d->in_types; *t; t++)
			assert_non_null(strchr("bhud", *t));
		for (const char *t = d->out_types; *t; t++)
			assert_non_null(strchr("bhudsa", *t));
		assert_true(strlen(d->help) > 10);
	}
	/* A few rows in full: the flattening of the IDL structs. */
	const cmd_def_t *d = cmd_by_name("getPosition");
	assert_string_equal(d->in_types, "");
	assert_string_equal(d->out_types, "ddd");
	assert_string_equal(d->out_names, "x y theta");
	d = cmd_by_name("moveCircularRel");
	assert_string_equal(d->in_types, "ddd");
	assert_string_equal(d->in_names, "x y theta");
	d = cmd_by_name("getActiveAlarm");
	assert_string_equal(d->in_types, "h");
	assert_string_equal(d->out_types, "ha");
	d = cmd_by_name("setOutput");
	assert_string_equal(d->in_types, "uuu");
	assert_string_equal(d->in_names, "ioid output mask");
	d = cmd_by_name("getState");
	assert_string_equal(d->out_types, "hs");
	d = cmd_by_name("setVelocity");
	assert_string_equal(d->in_types, "dd");
	assert_string_equal(d->in_names, "translation rotation");
	d = cmd_by_name("getServoStatus");
	assert_string_equal(d->in_types, "u");
	assert_string_equal(d->out_types, "b");
	d = cmd_by_name("setJogTimeout");
	assert_string_equal(d->in_types, "h");
	d = cmd_by_name("moveJog");
	assert_string_equal(d->in_names, "xVel yVel thetaVel");
}

static void test_table_checksum(void **state)
{
	char text[2048];
	size_t n = 0;

	(void)state;
	/* CRC-16/CCITT-FALSE check value. */
	assert_int_equal(cmd_crc16(0xFFFF, "123456789", 9), 0x29B1);
	/* The documented serialisation. */
	for (unsigned i = 0; i < CMD_COUNT; i++)
		n += (size_t)snprintf(text + n, sizeof(text) - n, "%s:%u:%s:%s\n",
				      cmd_table[i].name, cmd_table[i].opcode, cmd_table[i].in_types,
				      cmd_table[i].out_types);
	assert_true(n < sizeof(text));
	assert_memory_equal(text, "clearAlarm:1::\ngetAccelerationLimit:2::dd\n", 42);
	assert_int_equal(cmd_table_crc(), cmd_crc16(0xFFFF, text, n));
	/* Pinned: a change to any name, opcode or type must come with a new
	 * CMD_PROTO_VERSION and a new value here. */
	assert_int_equal(CMD_PROTO_VERSION, 1);
	assert_int_equal(cmd_table_crc(), 0x1F09);
	assert_int_equal(cmd_table_crc(), CMD_TABLE_CRC); /* what a board answers */
}

/* ---- strict number parsing ----------------------------------------------- */

static void test_numparse(void **state)
{
	double d = 0;
	int64_t i = 0;
	bool b;

	(void)state;
	assert_int_equal(np_parse_double("1e3", &d), NP_OK);
	assert_true(d == 1000.0);
	assert_int_equal(np_parse_double("-.5", &d), NP_OK);
	assert_true(d == -0.5);
	assert_int_equal(np_parse_double("+7.", &d), NP_OK);
	assert_true(d == 7.0);
	assert_int_equal(np_parse_double("1E-2", &d), NP_OK);
	assert_true(d == 0.01);
	static const char *const bad[] = {
	    "",		"+",	"-",	 ".",	"e5", "1e", "1e+", "nan",   "NaN",    "inf", "-inf",
	    "Infinity", "0x10", "1.5.2", "1,5", "1 ", " 1", "--1", "1e999", "-1e999", "1_0", "5f"};
	for (unsigned k = 0; k < sizeof(bad) / sizeof(bad[0]); k++)
		assert_int_equal(np_parse_double(bad[k], &d), NP_SYNTAX);

	assert_int_equal(np_parse_int("32767", INT16_MIN, INT16_MAX, &i), NP_OK);
	assert_int_equal(i, 32767);
	assert_int_equal(np_parse_int("32768", INT16_MIN, INT16_MAX, &i), NP_RANGE);
	assert_int_equal(np_parse_int("-32768", INT16_MIN, INT16_MAX, &i), NP_OK);
	assert_int_equal(i, -32768);
	assert_int_equal(np_parse_int("-32769", INT16_MIN, INT16_MAX, &i), NP_RANGE);
	assert_int_equal(np_parse_int("4294967295", 0, UINT32_MAX, &i), NP_OK);
	assert_int_equal(i, 4294967295LL);
	assert_int_equal(np_parse_int("4294967296", 0, UINT32_MAX, &i), NP_RANGE);
	assert_int_equal(np_parse_int("-1", 0, UINT32_MAX, &i), NP_RANGE);
	assert_int_equal(np_parse_int("-0", 0, UINT32_MAX, &i), NP_OK);
	assert_int_equal(i, 0);
	assert_int_equal(np_parse_int("1e3", 0, UINT32_MAX, &i), NP_OK);
	assert_int_equal(i, 1000);
	assert_int_equal(np_parse_int("2.500e1", 0, UINT32_MAX, &i), NP_OK);
	assert_int_equal(i, 25);
	assert_int_equal(np_parse_int("12000e-3", 0, UINT32_MAX, &i), NP_OK);
	assert_int_equal(i, 12);
	assert_int_equal(np_parse_int("0.000", 0, UINT32_MAX, &i), NP_OK);
	assert_int_equal(i, 0);
	/* exact, whatever a double would round to */
	assert_int_equal(np_parse_int("4294967295.0000000000000001", 0, UINT32_MAX, &i), NP_RANGE);
	assert_int_equal(np_parse_int("1.5", 0, UINT32_MAX, &i), NP_RANGE);
	assert_int_equal(np_parse_int("0.5", 0, UINT32_MAX, &i), NP_RANGE);
	assert_int_equal(np_parse_int("1e-1", 0, UINT32_MAX, &i), NP_RANGE);
	assert_int_equal(np_parse_int("1e99999999999", 0, UINT32_MAX, &i), NP_RANGE);
	assert_int_equal(np_parse_int("99999999999999999999999", 0, UINT32_MAX, &i), NP_RANGE);
	assert_int_equal(np_parse_int("1e-99999999999", 0, UINT32_MAX, &i), NP_RANGE);
	assert_int_equal(np_parse_int("0x1", 0, UINT32_MAX, &i), NP_SYNTAX);
	assert_int_equal(np_parse_int("nan", 0, UINT32_MAX, &i), NP_SYNTAX);
	assert_int_equal(np_parse_int("", 0, UINT32_MAX, &i), NP_SYNTAX);

	static const char *const yes[] = {"true", "TRUE", "True", "1", "on", "ON", "oN"};
	static const char *const no[] = {"false", "FALSE", "0", "off", "OFF", "Off"};
	for (unsigned k = 0; k < sizeof(yes) / sizeof(yes[0]); k++) {
		b = false;
		assert_true(np_parse_bool(yes[k], &b));
		assert_true(b);
	}
	for (unsigned k = 0; k < sizeof(no) / sizeof(no[0]); k++) {
		b = true;
		assert_true(np_parse_bool(no[k], &b));
		assert_false(b);
	}
	static const char *const neither[] = {"", "2", "yes", "no", "t", "f", "onn", "of", "01"};
	for (unsigned k = 0; k < sizeof(neither) / sizeof(neither[0]); k++)
		assert_false(np_parse_bool(neither[k], &b));
}

/* ---- errors, each with its exact text --------------------------------------- */

static void test_error_unknown(void **state)
{
	(void)state;
	EXPECT("foo", "error 1 unknown operation foo");
	EXPECT("moveForwar 1", "error 1 unknown operation moveForwar");
	EXPECT("$xyz", "error 1 unknown command $xyz");
	EXPECT("$", "error 1 unknown command $");
}

static void test_error_arity(void **state)
{
	(void)state;
	EXPECT("moveForward 1 2", "error 2 moveForward takes 1 argument, got 2");
	EXPECT("moveForward", "error 2 moveForward takes 1 argument, got 0");
	EXPECT("getState now", "error 2 getState takes 0 arguments, got 1");
	EXPECT("setOutput 3 1", "error 2 setOutput takes 3 arguments, got 2");
	EXPECT("setPosition 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20",
	       "error 2 setPosition takes 3 arguments, got 20");
	/* arity is checked before the arguments' form */
	EXPECT("moveForward x y", "error 2 moveForward takes 1 argument, got 2");
}

static void test_error_number(void **state)
{
	(void)state;
	EXPECT("moveForward abc", "error 3 moveForward x_: bad number abc");
	EXPECT("moveForward NaN", "error 3 moveForward x_: bad number NaN");
	EXPECT("moveForward inf", "error 3 moveForward x_: bad number inf");
	EXPECT("moveForward -INF", "error 3 moveForward x_: bad number -INF");
	EXPECT("moveForward 1e999", "error 3 moveForward x_: bad number 1e999");
	EXPECT("moveForward 0x10", "error 3 moveForward x_: bad number 0x10");
	EXPECT("moveForward 10mm", "error 3 moveForward x_: bad number 10mm");
	EXPECT("setPosition 1 2 three", "error 3 setPosition theta: bad number three");
	EXPECT("setVelocity 100 -", "error 3 setVelocity rotation: bad number -");
	EXPECT("getInput one", "error 3 getInput ioid: bad number one");
	/* the first bad argument is the one reported */
	EXPECT("moveJog a b c", "error 3 moveJog xVel: bad number a");
}

static void test_error_range(void **state)
{
	(void)state;
	EXPECT("setJogTimeout 32767", "ok true");
	EXPECT("setJogTimeout 32768",
	       "error 4 setJogTimeout timeout: 32768 is not an integer in -32768..32767");
	EXPECT("setJogTimeout -32769",
	       "error 4 setJogTimeout timeout: -32769 is not an integer in -32768..32767");
	EXPECT("setJogTimeout 1.5",
	       "error 4 setJogTimeout timeout: 1.5 is not an integer in -32768..32767");
	/* in range, refused by the unit: not a console error */
	EXPECT("setJogTimeout -32768", "ok false");
	EXPECT("getInput -1", "error 4 getInput ioid: -1 is not an integer in 0..4294967295");
	EXPECT("getInput 4294967296",
	       "error 4 getInput ioid: 4294967296 is not an integer in 0..4294967295");
	EXPECT("getInput 4294967295", "ok false 0");
	EXPECT("getActiveAlarm 32768",
	       "error 4 getActiveAlarm numOfAlarm: 32768 is not an integer in -32768..32767");
	EXPECT("setOutput 3 1 4294967296",
	       "error 4 setOutput mask: 4294967296 is not an integer in 0..4294967295");
}

static void test_error_bool(void **state)
{
	(void)state;
	EXPECT("setPower maybe",
	       "error 5 setPower OnOff: bad boolean maybe (true|false|1|0|on|off)");
	EXPECT("setServo 2", "error 5 setServo OnOff: bad boolean 2 (true|false|1|0|on|off)");
	EXPECT("setJoystick yes",
	       "error 5 setJoystick OnOff: bad boolean yes (true|false|1|0|on|off)");
	EXPECT("getState", "ok true 25 \"Unpowered\"");
}

static void test_bool_forms(void **state)
{
	static const char *const on[] = {"true", "TRUE", "1", "on", "On"};
	static const char *const off[] = {"false", "False", "0", "off", "OFF"};
	char line[64];

	(void)state;
	for (unsigned k = 0; k < 5; k++) {
		snprintf(line, sizeof(line), "setPower %s", on[k]);
		EXPECT(line, "ok true");
		EXPECT("getState", "ok true 24 \"Powered\"");
		snprintf(line, sizeof(line), "SETPOWER %s", off[k]);
		EXPECT(line, "ok true");
		EXPECT("getState", "ok true 25 \"Unpowered\"");
	}
}

static void test_number_forms_reach_the_unit(void **state)
{
	(void)state;
	EXPECT("setPosition 1E3 -25e-1 +.5", "ok true");
	EXPECT("getPosition", "ok true 1000.000 -2.500 0.500");
	EXPECT("setPosition 12. -0.0001 0", "ok true");
	/* a value that rounds to zero never prints as -0.000 */
	EXPECT("getPosition", "ok true 12.000 0.000 0.000");
	EXPECT("setPosition 0.0127 1e-3 -90", "ok true");
	EXPECT("getPosition", "ok true 0.013 0.001 -90.000");
	EXPECT("\tgetposition  \t", "ok true 0.013 0.001 -90.000");
}

static void test_errors_change_nothing(void **state)
{
	static const char *const bad[] = {
	    "setPower",
	    "setPower 1 1",
	    "setPower maybe",
	    "setPosition 5 5",
	    "setPosition nan 0 0",
	    "setPosition 1e999 0 0",
	    "setServo 2",
	    "moveForward 100 100",
	    "setOutput 3 255",
	    "setOutput 3 255 256 1",
	    "stopp",
	    "$nothing",
	};

	(void)state;
	power_up();
	for (unsigned k = 0; k < sizeof(bad) / sizeof(bad[0]); k++)
		assert_memory_equal(ex(bad[k]), "error ", 6);
	fake_run(&fh, &veh, 50);
	EXPECT("getState", "ok true 16 \"Ready\"");
	EXPECT("getActiveAlarm 16", "ok true 0 0");
	EXPECT("getPosition", "ok true 0.000 0.000 0.000");
	assert_int_equal(fh.io_write_calls, 0);
	assert_int_equal(con.errors, sizeof(bad) / sizeof(bad[0]));
}

/* ---- lines from a byte stream --------------------------------------------- */

static unsigned count_lines(const char *s)
{
	unsigned n = 0;

	for (; *s; s++)
		n += *s == '\n';
	return n;
}

static void test_line_endings(void **state)
{
	(void)state;
	FEED("getState\r\ngetState\rgetState\n");
	assert_string_equal(out, "ok true 25 \"Unpowered\"\nok true 25 \"Unpowered\"\n"
				 "ok true 25 \"Unpowered\"\n");
	out_len = 0;
	out[0] = '\0';
	/* a CRLF split across two reads is still one line end */
	FEED("getVersion\r");
	FEED("\ngetIFVersion\n");
	assert_string_equal(out, "ok true \"Ver.1.0.0\"\n"
				 "ok true \"RTC VehicleService interface: ver.2.0.0\"\n");
	out_len = 0;
	out[0] = '\0';
	/* LF CR is two line ends around an empty line: no reply for it */
	FEED("getState\n\rgetState\r\r\n\n");
	assert_int_equal(count_lines(out), 2);
	/* a line with no end yet gets no reply */
	out_len = 0;
	out[0] = '\0';
	FEED("getSta");
	assert_int_equal(out_len, 0);
	FEED("te\n");
	assert_string_equal(out, "ok true 25 \"Unpowered\"\n");
}

static void test_comments_and_empty_lines(void **state)
{
	(void)state;
	EXPECT("", "(none)");
	EXPECT("   \t ", "(none)");
	EXPECT("# setPower on", "(none)");
	EXPECT("  \t# indented comment", "(none)");
	EXPECT("#", "(none)");
	/* '#' only starts a comment at the front */
	EXPECT("getState #", "error 2 getState takes 0 arguments, got 1");
	FEED("\n\r\n   \n# x\n\t#y\r");
	assert_int_equal(out_len, 0);
	/* a comment is ignored whatever bytes it holds (UTF-8 in scripts) */
	FEED("# \xe7\xa7\xbb\xe5\x8b\x95 \x01\n");
	assert_int_equal(out_len, 0);
	EXPECT("getState", "ok true 25 \"Unpowered\"");
	/* only "getState #" was an error */
	assert_int_equal(con.errors, 1);
}

static void test_line_length(void **state)
{
	char line[400];

	(void)state;
	/* exactly 255 bytes: fine */
	memset(line, ' ', sizeof(line));
	memcpy(line, "getState", 8);
	line[255] = '\0';
	EXPECT(line, "ok true 25 \"Unpowered\"");
	line[255] = '\n';
	feed_str(line, 256);
	assert_string_equal(out, "ok true 25 \"Unpowered\"\n");
	out_len = 0;
	out[0] = '\0';
	/* 256 bytes: one error, the whole line discarded */
	memset(line, ' ', sizeof(line));
	memcpy(line, "setPower on", 11);
	line[256] = '\n';
	feed_str(line, 257);
	assert_string_equal(out, "error 6 line too long (max 255 bytes)\n");
	EXPECT("getState", "ok true 25 \"Unpowered\"");
	line[256] = '\0';
	EXPECT(line, "error 6 line too long (max 255 bytes)");
	/* a very long line in pieces: still one error, then the next line runs */
	out_len = 0;
	out[0] = '\0';
	memset(line, 'x', sizeof(line));
	for (int k = 0; k < 20; k++)
		feed_str(line, sizeof(line));
	FEED("\r\ngetState\n");
	assert_string_equal(out, "error 6 line too long (max 255 bytes)\n"
				 "ok true 25 \"Unpowered\"\n");
	assert_int_equal(con.len, 0);
}

/* A comment gets no reply however long it is (spec section 7), and is
 * discarded whole: nothing of it reaches the next line. Over-long lines
 * that are not comments still get error 6, once. */
static void test_long_comment(void **state)
{
	char line[1200];

	(void)state;
	/* 300 bytes: "# " and x's, in one piece and a byte at a time */
	memset(line, 'x', sizeof(line));
	memcpy(line, "# ", 2);
	line[300] = '\n';
	feed_str(line, 301);
	assert_int_equal(out_len, 0);
	for (size_t i = 0; i <= 300; i++)
		feed_str(line + i, 1);
	assert_int_equal(out_len, 0);
	/* 1,100 bytes of any kind after leading blanks, CR LF ended, then a
	 * line that runs: its reply is the only one */
	memset(line, ' ', 10);
	line[10] = '#';
	for (size_t i = 11; i < 1100; i++)
		line[i] = (char)(i % 7 == 0 ? 0xA5 : i % 5 == 0 ? 0x01 : 'a' + (int)(i % 26));
	memcpy(line + 1100, "\r\n", 2);
	feed_str(line, 1102);
	FEED("getState\n");
	assert_string_equal(out, "ok true 25 \"Unpowered\"\n");
	out_len = 0;
	out[0] = '\0';
	/* its first non-blank byte past the 255 kept: still a comment */
	memset(line, ' ', 600);
	memcpy(line + 400, "# late", 6);
	line[600] = '\n';
	feed_str(line, 601);
	assert_int_equal(out_len, 0);
	/* ... but an operation there is a line too long, and so are 600 blanks */
	memcpy(line + 400, "getSta", 6);
	feed_str(line, 601);
	memset(line, ' ', 600);
	feed_str(line, 601);
	assert_string_equal(out, "error 6 line too long (max 255 bytes)\n"
				 "error 6 line too long (max 255 bytes)\n");
	assert_int_equal(con.len, 0);
	/* console_exec (the simulator's stdin lines) says the same */
	line[600] = '\0';
	memcpy(line + 400, "#  x", 4);
	EXPECT(line, "(none)");
	memset(line, '#', 600);
	EXPECT(line, "(none)");
	line[0] = 'g';
	EXPECT(line, "error 6 line too long (max 255 bytes)");
	/* four lines answered: getState and three errors; comments count none */
	assert_int_equal(con.lines, 4);
	assert_int_equal(con.errors, 3);
}

static void test_binary_garbage(void **state)
{
	(void)state;
	EXPECT("getState\x01", "error 7 binary data in line");
	EXPECT("get\x7fState", "error 7 binary data in line");
	EXPECT("setPower \xc3\xa9", "error 7 binary data in line");
	EXPECT("\x1b[AgetState", "error 7 binary data in line");
	/* tab is whitespace, not garbage */
	EXPECT("setPower\ton", "ok true");
	EXPECT("setPower off", "ok true");
	/* a NUL byte is garbage too, and does not cut the line short */
	FEED("setPower on\0 garbage\n");
	assert_string_equal(out, "error 7 binary data in line\n");
	EXPECT("getState", "ok true 25 \"Unpowered\"");
}

/* xorshift32: fixed seed, the same stream every run. */
static uint32_t rng = 0x2545F491u;
static uint32_t rnd(void)
{
	rng ^= rng << 13;
	rng ^= rng >> 17;
	rng ^= rng << 5;
	return rng;
}

static void check_replies_well_formed(void)
{
	const char *p = out;

	while (*p) {
		const char *nl = strchr(p, '\n');

		assert_non_null(nl);
		assert_true(strncmp(p, "ok ", 3) == 0 || strncmp(p, "error ", 6) == 0 ||
			    (nl - p == 2 && strncmp(p, "ok", 2) == 0));
		assert_true((size_t)(nl - p) < CONSOLE_REPLY_MAX);
		for (const char *q = p; q < nl; q++)
			assert_true(*q >= 0x20 && *q < 0x7f);
		p = nl + 1;
	}
}

static void test_fuzz_feed(void **state)
{
	static const char *const words[] = {
	    "getState", "moveForward",	  "setPower", "on",  "1e3", "-",  "$help",     "$diag",
	    "#",	"getActiveAlarm", "16",	      "nan", "\"",  "\\", "setOutput", "3",
	    "0",	"moveJog",
	};
	uint8_t buf[96];

	(void)state;
	for (int it = 0; it < 5000; it++) {
		size_t n = rnd() % sizeof(buf);

		for (size_t k = 0; k < n; k++) {
			uint32_t r = rnd() % 16;

			if (r == 0)
				buf[k] = '\n';
			else if (r == 1)
				buf[k] = '\r';
			else if (r < 4)
				buf[k] = ' ';
			else if (r < 7) {
				const char *w = words[rnd() % (sizeof(words) / sizeof(words[0]))];
				size_t wl = strlen(w);

				if (k + wl > n)
					wl = n - k;
				memcpy(buf + k, w, wl);
				k += wl - (wl > 0);
			} else
				buf[k] = (uint8_t)rnd();
		}
		out_len = 0;
		out[0] = '\0';
		console_feed(&con, buf, n);
		check_replies_well_formed();
		assert_true(con.len <= CONSOLE_LINE_MAX + 1);
		if (it % 64 == 0)
			fake_run(&fh, &veh, 5);
	}
	/* still in step afterwards: a fresh line gets its exact reply */
	out_len = 0;
	out[0] = '\0';
	FEED("\ngetIFVersion\n");
	const char *want = "ok true \"RTC VehicleService interface: ver.2.0.0\"\n";
	assert_true(out_len >= strlen(want));
	assert_string_equal(out + out_len - strlen(want), want);
}

/* ---- reply formatting ----------------------------------------------------- */

static void test_reply_formats(void **state)
{
	(void)state;
	EXPECT("getState", "ok true 25 \"Unpowered\"");
	EXPECT("getIFVersion", "ok true \"RTC VehicleService interface: ver.2.0.0\"");
	EXPECT("getVersion", "ok true \"Ver.1.0.0\"");
	EXPECT("getVelocityLimit", "ok true 1000.000 180.000");
	EXPECT("getAccelerationLimit", "ok true 1000.000 360.000");
	EXPECT("getDefaultVelocity", "ok true 500.000 90.000");
	EXPECT("getDefaultAcceleration", "ok true 500.000 180.000");
	EXPECT("getBatteryVoltage", "ok true 240.000");
	EXPECT("getServoStatus 0", "ok true false");
	EXPECT("getServoStatus 1", "ok true false");
	/* refused: the out argument is still written, so every reply of an
	 * operation has the same number of fields */
	EXPECT("getServoStatus 2", "ok false false");
	fh.io_in[1] = 0x5A;
	EXPECT("getInput 1", "ok true 90");
	EXPECT("getInput 1.000", "ok true 90");
	EXPECT("getInput 0.1e1", "ok true 90");
	EXPECT("getInput 99", "ok false 0");
	EXPECT("clearAlarm", "ok true");
	power_up();
	EXPECT("getServoStatus 1", "ok true true");
	EXPECT("getstate", "ok true 16 \"Ready\"");
}

static void test_alarm_sequence(void **state)
{
	(void)state;
	EXPECT("moveTurn 90", "ok false");
	EXPECT("getActiveAlarm 5", "ok true 1 1 121 warning \"moveTurn refused: servo off\"");
	EXPECT("getActiveAlarm 0", "ok true 1 0");
	EXPECT("getActiveAlarm -1", "ok true 1 0");
	EXPECT("getActiveAlarm -32768", "ok true 1 0");
	EXPECT("getActiveAlarm 32767", "ok true 1 1 121 warning \"moveTurn refused: servo off\"");
	/* An alarm fits whole or not at all: 53 bytes of reply, the NUL and
	 * the count's third byte held back. */
	{
		char fit[55];

		assert_true(console_exec(&con, "getActiveAlarm 1", fit, 55));
		assert_string_equal(fit, "ok true 1 1 121 warning \"moveTurn refused: servo off\"");
		assert_true(console_exec(&con, "getActiveAlarm 1", fit, 54));
		assert_string_equal(fit, "ok true 1 0");
	}
	alarm_raise(&veh.alarms, 205, "say \"hi\" \\ \x01 back");
	EXPECT("getActiveAlarm 1", "ok true 2 1 205 fault \"say \\\"hi\\\" \\\\ \\x01 back\"");
	EXPECT("getActiveAlarm 2", "ok true 2 2 205 fault \"say \\\"hi\\\" \\\\ \\x01 back\" "
				   "121 warning \"moveTurn refused: servo off\"");
	alarm_raise(&veh.alarms, 7, "other");
	EXPECT("getActiveAlarm 1", "ok true 3 1 7 unknown \"other\"");
	EXPECT("clearAlarm", "ok true");
	EXPECT("getActiveAlarm 16", "ok true 0 0");
}

/* 16 alarms of 63 escaped characters do not fit 1024 bytes: whole alarms
 * are written while they fit, the length says how many. */
static void test_longest_reply_bounded(void **state)
{
	char src[VS_ALARM_SOURCE_MAX];
	char small[64];

	(void)state;
	memset(src, '"', sizeof(src) - 1);
	src[sizeof(src) - 1] = '\0';
	for (uint32_t k = 0; k < VS_ALARM_LIST_MAX; k++)
		alarm_raise(&veh.alarms, 100 + k, src);
	assert_true(console_exec(&con, "getActiveAlarm 16", rep, sizeof(rep)));
	/* one alarm: " 115 warning " + 2 + 126 = 141 bytes; 7 fit after
	 * "ok true 16 7" within 1023 */
	PREFIX(rep, "ok true 16 7 115 warning \"\\\"");
	assert_int_equal(strlen(rep), 12 + 7 * 141);
	assert_non_null(strstr(rep, "\" 109 warning \"\\\""));
	assert_null(strstr(rep, " 108 warning"));
	assert_string_equal(rep + strlen(rep) - 3, "\\\"\"");
	/* the byte stream path: the same line plus its newline */
	FEED("getActiveAlarm 16\n");
	assert_int_equal(out_len, 12 + 7 * 141 + 1);
	/* a small buffer: still a well-formed reply */
	assert_true(console_exec(&con, "getActiveAlarm 16", small, sizeof(small)));
	assert_string_equal(small, "ok true 16 0");
	assert_true(console_exec(&con, "getActiveAlarm 16", small, 5));
	assert_string_equal(small, "ok t");
}

/* ---- '$' extras ------------------------------------------------------------ */

static void test_help(void **state)
{
	(void)state;
	EXPECT("$help",
	       "ok clearAlarm getAccelerationLimit getActiveAlarm getBatteryVoltage "
	       "getDefaultAcceleration getDefaultVelocity getIFVersion getInput getPosition "
	       "getServoStatus getState getVelocityLimit getVersion moveCircularRel "
	       "moveContinuousRel moveCruiseAbs moveForward moveJog moveLinearAbs moveLinearRel "
	       "moveTurn pause resume setAcceleration setDigitalSensorLock setJogTimeout "
	       "setJoystick setOutput setPosition setPower setServo setVelocity stop unlock");
	EXPECT("$help moveForward", "ok 17 boolean moveForward(in double x_): Move x_ mm forward "
				    "(negative: backward). Ready-only.");
	EXPECT("$HELP getstate", "ok 11 boolean getState(out short state, out string Msg): Unit "
				 "state code and message (Ready, Busy, Warning-###, ...).");
	EXPECT(
	    "$help getActiveAlarm",
	    "ok 3 boolean getActiveAlarm(in short numOfAlarm, out short numOfActiveAlarm, out "
	    "SeqAlarm activeAlarms): Count of active alarms and up to numOfAlarm of them, newest "
	    "first.");
	EXPECT("$help setOutput", "ok 28 boolean setOutput(in unsigned long ioid, in unsigned long "
				  "output, in unsigned long mask): Set the bits of output selected "
				  "by mask on output ioid (0 is reserved).");
	EXPECT("$help stop", "ok 33 boolean stop(): Abort motion at the maximum acceleration and "
			     "discard all queued work.");
	EXPECT("$help nosuch", "error 8 $help: no operation nosuch");
	EXPECT("$help a b", "error 2 $help takes 0 or 1 argument, got 2");
}

/* Collapses whitespace to single spaces and drops it beside '(' and ')' and
 * before ',': "boolean f ( in double a ,out short b )" becomes
 * "boolean f(in double a, out short b)". */
static void idl_normalise(const char *s, size_t n, char *o, size_t cap)
{
	size_t k = 0;
	bool space = false;

	for (size_t i = 0; i < n; i++) {
		char ch = s[i];

		if (ch == ' ' || ch == '\t' || ch == '\n' || ch == '\r') {
			space = k > 0;
			continue;
		}
		if (space && ch != '(' && ch != ')' && ch != ',' && o[k - 1] != '(') {
			assert_true(k + 1 < cap);
			o[k++] = ' ';
		}
		space = ch == ',';
		assert_true(k + 1 < cap);
		o[k++] = ch;
	}
	o[k] = '\0';
}

/* $help NAME answers every operation's signature exactly as the IDL
 * (tools/corba/VehicleService.idl, the specification's appendix, which the
 * CORBA tests compare with it) declares it, read from the file here: its
 * operations in the table's order, none missing, none extra. */
static void test_help_matches_idl(void **state)
{
	static char idl[16384];
	char sig[256], want[CONSOLE_REPLY_MAX], line[64];
	FILE *f = fopen("tools/corba/VehicleService.idl", "r");
	const char *p, *end;
	unsigned ops = 0;

	(void)state;
	assert_non_null(f);
	size_t n = fread(idl, 1, sizeof(idl) - 1, f);
	fclose(f);
	assert_true(n > 0 && n < sizeof(idl) - 1);
	idl[n] = '\0';
	p = strstr(idl, "interface VehicleService");
	assert_non_null(p);
	p = strchr(p, '{');
	assert_non_null(p);
	end = strstr(p, "};");
	assert_non_null(end);
	for (p++; p < end;) {
		const char *semi = memchr(p, ';', (size_t)(end - p));
		const char *paren;

		idl_normalise(p, semi ? (size_t)(semi - p) : (size_t)(end - p), sig, sizeof(sig));
		if (!semi) {
			/* only blanks after the last declaration */
			assert_string_equal(sig, "");
			break;
		}
		p = semi + 1;
		if (strncmp(sig, "const ", 6) == 0)
			continue;
		/* every other declaration of the interface is an operation */
		assert_memory_equal(sig, "boolean ", 8);
		paren = strchr(sig, '(');
		assert_non_null(paren);
		assert_true(ops < CMD_COUNT);
		const cmd_def_t *d = &cmd_table[ops++];
		assert_int_equal((size_t)(paren - sig - 8), strlen(d->name));
		assert_memory_equal(sig + 8, d->name, strlen(d->name));
		snprintf(want, sizeof(want), "ok %u %s: %s", d->opcode, sig, d->help);
		snprintf(line, sizeof(line), "$help %s", d->name);
		EXPECT(line, want);
	}
	assert_int_equal(ops, CMD_COUNT);
	/* the normalising rule itself */
	{
		static const char raw[] = "boolean  f ( in double a ,out\n short b ) ";

		idl_normalise(raw, sizeof(raw) - 1, sig, sizeof(sig));
	}
	assert_string_equal(sig, "boolean f(in double a, out short b)");
}

static void test_version_and_diag(void **state)
{
	(void)state;
	EXPECT("$version", "ok firmware \"Ver.1.0.0\" interface \"RTC VehicleService interface: "
			   "ver.2.0.0\" protocol 1 table 0x1F09");
	EXPECT("$version x", "error 2 $version takes 0 arguments, got 1");
	EXPECT("$diag",
	       "ok ticks 0 overruns 0 late 0 max_late_us 0 mode idle queue 0 ref 0.000 0.000 0.000 "
	       "odom 0.000 0.000 0.000");
	EXPECT("setPosition 10 -20 45", "ok true");
	fake_run(&fh, &veh, 25);
	EXPECT("$DIAG", "ok ticks 25 overruns 0 late 0 max_late_us 0 mode idle queue 0 ref 10.000 "
			"-20.000 45.000 "
			"odom 10.000 -20.000 45.000");
	EXPECT("$diag 1", "error 2 $diag takes 0 arguments, got 1");
	/* extras never raise alarms */
	EXPECT("getActiveAlarm 1", "ok true 0 0");
}

/* $config: the table's names, and the running configuration's values in
 * the formats of the operations' replies (fake_hal_config: the reference
 * base with drives that follow at once). */
static void test_config(void **state)
{
	(void)state;
	EXPECT("$config",
	       "ok kinematics tick_hz wheel_diameter_mm track_width_mm wheel_base_mm "
	       "encoder_counts_per_rev vel_limit_t_mm_s vel_limit_r_deg_s acc_limit_t_mm_s2 "
	       "acc_limit_r_deg_s2 vel_default_t_mm_s vel_default_r_deg_s acc_default_t_mm_s2 "
	       "acc_default_r_deg_s2 jerk_limit_t_mm_s3 jerk_limit_r_deg_s3 "
	       "jerk_default_t_mm_s3 jerk_default_r_deg_s3 jog_timeout_default_ms wheel_kp_per_s "
	       "drive_lag_ms "
	       "following_error_mm encoder_stuck_ms drive_timeout_ms servo_on_timeout_ms "
	       "loop_late_ms link_timeout_ms "
	       "position_window_mm position_window_ms settle_timeout_ms cruise_blend_mm "
	       "caution_vel_t_mm_s battery_critical_v battery_low_v has_contact_sensor "
	       "has_obstacle_input has_estop has_joystick joystick_deadband");
	EXPECT("$config kinematics", "ok kinematics 0");
	EXPECT("$config tick_hz", "ok tick_hz 1000");
	EXPECT("$config wheel_diameter_mm", "ok wheel_diameter_mm 150.000");
	EXPECT("$config encoder_counts_per_rev", "ok encoder_counts_per_rev 16384");
	EXPECT("$config jog_timeout_default_ms", "ok jog_timeout_default_ms 500");
	EXPECT("$config drive_lag_ms", "ok drive_lag_ms 0.000 0.000 0.000 0.000");
	EXPECT("$config position_window_mm", "ok position_window_mm 0.050");
	EXPECT("$config battery_low_v", "ok battery_low_v 22.000");
	EXPECT("$config has_estop", "ok has_estop true");
	EXPECT("$CONFIG Joystick_Deadband", "ok joystick_deadband 0.050");
	/* the running configuration: what $watchdog set, what init kept */
	/* $jerk: read, set within the limits (none here), refused beyond */
	EXPECT("$jerk", "ok jerk 0.000 0.000 limit 0.000 0.000");
	EXPECT("$jerk 2000 1000", "ok jerk 2000.000 1000.000 limit 0.000 0.000");
	EXPECT("$jerk 2000", "error 2 $jerk takes 0 or 2 arguments, got 1");
	EXPECT("$jerk x 1", "error 3 $jerk: not a number");
	EXPECT("$jerk -5 0", "error 8 $jerk: -5 0 exceeds the limits or is below what the tick "
			     "rate holds");
	EXPECT("$jerk 0.001 0", "error 8 $jerk: 0.001 0 exceeds the limits or is below what the "
				"tick rate holds");
	EXPECT("$jerk 1e8 0", "error 8 $jerk: 1e8 0 exceeds the limits or is below what the tick "
			      "rate holds");
	EXPECT("$jerk", "ok jerk 2000.000 1000.000 limit 0.000 0.000");
	EXPECT("$config jerk_default_r_deg_s3", "ok jerk_default_r_deg_s3 1000.000");
	EXPECT("$jerk 0 0", "ok jerk 0.000 0.000 limit 0.000 0.000");
	EXPECT("$watchdog 250", "ok watchdog 250");
	EXPECT("$config link_timeout_ms", "ok link_timeout_ms 250");
	veh.cfg.has_joystick = false;
	veh.cfg.kinematics = VS_KIN_OMNI;
	EXPECT("$config has_joystick", "ok has_joystick false");
	EXPECT("$config kinematics", "ok kinematics 1");
	/* every row answers, with one value per element */
	for (unsigned i = 0; i < VS_CONFIG_NFIELDS; i++) {
		char line[64], want[64];
		snprintf(line, sizeof(line), "$config %s", vs_config_fields[i].name);
		snprintf(want, sizeof(want), "ok %s ", vs_config_fields[i].name);
		assert_memory_equal(ex(line), want, strlen(want));
		unsigned spaces = 0;
		for (const char *p = rep; *p; p++)
			spaces += *p == ' ';
		assert_int_equal(spaces, 1 + vs_config_fields[i].n);
	}
	EXPECT("$config nosuch", "error 8 $config: no field nosuch");
	EXPECT("$config firmware_version", "error 8 $config: no field firmware_version");
	EXPECT("$config tick_hz 1", "error 8 $config tick_hz: this unit keeps no configuration");
	/* extras never raise alarms */
	EXPECT("getActiveAlarm 1", "ok true 0 0");
}

static int extra_calls;
static bool test_extra(void *ctx, int argc, char **argv, char *reply, size_t cap)
{
	extra_calls++;
	assert_ptr_equal(ctx, &extra_calls);
	if (strcmp(argv[0], "$echo") == 0) {
		snprintf(reply, cap, "ok echo %d %s", argc, argc > 1 ? argv[argc - 1] : "-");
		return true;
	}
	if (strcmp(argv[0], "$fail") == 0) {
		snprintf(reply, cap, "error 8 failed");
		return true;
	}
	if (strcmp(argv[0], "$quiet") == 0)
		return true;
	return false;
}

static void test_extra_handler(void **state)
{
	(void)state;
	console_set_extra(&con, test_extra, &extra_calls);
	EXPECT("$echo a  b\tc", "ok echo 4 c");
	EXPECT("$fail", "error 8 failed");
	EXPECT("$quiet", "ok");
	EXPECT("$other 1", "error 1 unknown command $other");
	/* the console's own extras never reach the handler */
	extra_calls = 0;
	assert_memory_equal(ex("$help"), "ok clearAlarm", 13);
	assert_memory_equal(ex("$version"), "ok firmware", 11);
	assert_int_equal(extra_calls, 0);
	assert_int_equal(con.errors, 2);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test_setup(test_table_order_and_opcodes, setup),
	    cmocka_unit_test_setup(test_table_layouts, setup),
	    cmocka_unit_test_setup(test_table_checksum, setup),
	    cmocka_unit_test_setup(test_numparse, setup),
	    cmocka_unit_test_setup(test_error_unknown, setup),
	    cmocka_unit_test_setup(test_error_arity, setup),
	    cmocka_unit_test_setup(test_error_number, setup),
	    cmocka_unit_test_setup(test_error_range, setup),
	    cmocka_unit_test_setup(test_error_bool, setup),
	    cmocka_unit_test_setup(test_bool_forms, setup),
	    cmocka_unit_test_setup(test_number_forms_reach_the_unit, setup),
	    cmocka_unit_test_setup(test_errors_change_nothing, setup),
	    cmocka_unit_test_setup(test_line_endings, setup),
	    cmocka_unit_test_setup(test_comments_and_empty_lines, setup),
	    cmocka_unit_test_setup(test_line_length, setup),
	    cmocka_unit_test_setup(test_long_comment, setup),
	    cmocka_unit_test_setup(test_binary_garbage, setup),
	    cmocka_unit_test_setup(test_fuzz_feed, setup),
	    cmocka_unit_test_setup(test_reply_formats, setup),
	    cmocka_unit_test_setup(test_alarm_sequence, setup),
	    cmocka_unit_test_setup(test_longest_reply_bounded, setup),
	    cmocka_unit_test_setup(test_help, setup),
	    cmocka_unit_test_setup(test_help_matches_idl, setup),
	    cmocka_unit_test_setup(test_version_and_diag, setup),
	    cmocka_unit_test_setup(test_config, setup),
	    cmocka_unit_test_setup(test_extra_handler, setup),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
