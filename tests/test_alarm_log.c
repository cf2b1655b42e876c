/* Alarm events (proto/alarm_log.c): the lines a host's log gets from two
 * looks at the unit's alarm list, the list built by the firmware's own
 * alarm_raise and alarm_clear. Every expected line is written out. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "../firmware/alarm.h"
#include "../proto/alarm_log.h"

static char got[4096]; /* the lines of one look, each ending in "\n" */

static void collect(void *ctx, const char *line)
{
	size_t n = strlen(got);

	(void)ctx;
	assert_true(n + strlen(line) + 2 < sizeof(got));
	snprintf(got + n, sizeof(got) - n, "%s\n", line);
}

static alarm_list_t L;
static alarm_log_t W;

/* One look at L at t_us: its lines, and their count checked against them. */
static const char *look(uint64_t t_us)
{
	unsigned lines = 0;

	got[0] = '\0';
	unsigned n = alarm_log_poll(&W, &L, t_us, collect, NULL);
	for (const char *p = got; (p = strchr(p, '\n')) != NULL; p++)
		lines++;
	assert_int_equal(n, lines);
	return got;
}

static int setup(void **state)
{
	(void)state;
	alarm_clear(&L);
	alarm_log_init(&W);
	return 0;
}

static void test_raised_and_cleared(void **state)
{
	(void)state;
	assert_string_equal(look(0), "");
	alarm_raise(&L, 120, "moveTurn refused: unit not ready");
	assert_string_equal(
	    look(1234567),
	    "alarm raised 120 warning \"moveTurn refused: unit not ready\" at 1.234 s\n");
	/* nothing changed: nothing logged */
	assert_string_equal(look(1300000), "");
	alarm_raise(&L, 201, "drive 0 fault 0x2310");
	alarm_raise(&L, 111, "setVelocity refused: out of limits");
	assert_string_equal(look(2000000),
			    "alarm raised 201 fault \"drive 0 fault 0x2310\" at 2.000 s\n"
			    "alarm raised 111 warning \"setVelocity refused: out of limits\" at "
			    "2.000 s\n");
	alarm_clear(&L);
	assert_string_equal(look(3723004999u),
			    "alarm cleared 120 warning \"moveTurn refused: unit not ready\" at "
			    "3723.004 s\n"
			    "alarm cleared 201 fault \"drive 0 fault 0x2310\" at 3723.004 s\n"
			    "alarm cleared 111 warning \"setVelocity refused: out of limits\" at "
			    "3723.004 s\n");
	assert_string_equal(look(3800000000u), "");
}

/* A code raised again: logged when its text changed or it moved ahead of
 * others; as the newest with the same text it is no change. */
static void test_raised_again(void **state)
{
	(void)state;
	alarm_raise(&L, 154, "not in position: 3 counts");
	alarm_raise(&L, 120, "moveTurn refused: unit not ready");
	look(0);
	alarm_raise(&L, 120, "moveTurn refused: unit not ready");
	assert_string_equal(look(1000), "");
	alarm_raise(&L, 120, "moveForward refused: unit not ready");
	assert_string_equal(
	    look(2000),
	    "alarm raised 120 warning \"moveForward refused: unit not ready\" at 0.002 s\n");
	alarm_raise(&L, 154, "not in position: 3 counts");
	assert_string_equal(look(3000),
			    "alarm raised 154 warning \"not in position: 3 counts\" at 0.003 s\n");
	/* two raises, the older one of a code already listed, between looks */
	alarm_raise(&L, 120, "moveForward refused: unit not ready");
	alarm_raise(&L, 110, "moveForward refused: invalid argument");
	assert_string_equal(
	    look(4000),
	    "alarm raised 120 warning \"moveForward refused: unit not ready\" at 0.004 s\n"
	    "alarm raised 110 warning \"moveForward refused: invalid argument\" at 0.004 s\n");
}

/* clearAlarm and a raise between two looks: the clear first. */
static void test_cleared_then_raised(void **state)
{
	(void)state;
	alarm_raise(&L, 208, "emergency stop");
	alarm_raise(&L, 128, "setServo refused: power off");
	look(0);
	alarm_clear(&L);
	alarm_raise(&L, 208, "emergency stop");
	assert_string_equal(look(5000),
			    "alarm cleared 128 warning \"setServo refused: power off\" at 0.005 s\n"
			    "alarm raised 208 fault \"emergency stop\" at 0.005 s\n");
}

/* A full list: the oldest pushed out by a new one is dropped, not cleared. */
static void test_dropped_from_a_full_list(void **state)
{
	char src[32];

	(void)state;
	for (unsigned i = 0; i < VS_ALARM_LIST_MAX; i++) {
		snprintf(src, sizeof(src), "warning %u", i);
		alarm_raise(&L, 100 + i, src);
	}
	look(0);
	alarm_raise(&L, 140, "battery below 22.0 V");
	assert_string_equal(look(60000000),
			    "alarm raised 140 warning \"battery below 22.0 V\" at 60.000 s\n"
			    "alarm dropped 100 warning \"warning 0\" at 60.000 s\n");
	alarm_raise(&L, 141, "a");
	alarm_raise(&L, 142, "b");
	assert_string_equal(look(60001000),
			    "alarm raised 141 warning \"a\" at 60.001 s\n"
			    "alarm raised 142 warning \"b\" at 60.001 s\n"
			    "alarm dropped 101 warning \"warning 1\" at 60.001 s\n"
			    "alarm dropped 102 warning \"warning 2\" at 60.001 s\n");
}

/* The source quoted as the console writes strings; the type's name. */
static void test_format(void **state)
{
	char line[ALARM_LOG_LINE_MAX];
	vs_alarm_t a = {.code = 7, .type = VS_ALARM_UNKNOWN};
	vs_alarm_t b = {.code = 201, .type = VS_ALARM_FAULT};

	(void)state;
	memcpy(a.source, "say \"hi\" \\ \x01 caf\xc3\xa9", 19);
	alarm_log_format(line, sizeof(line), "raised", &a, 999);
	assert_string_equal(
	    line, "alarm raised 7 unknown \"say \\\"hi\\\" \\\\ \\x01 caf\\xc3\\xa9\" at 0.000 s");
	/* a source of 63 bytes, each escaped, fits the line */
	memset(b.source, 1, VS_ALARM_SOURCE_MAX - 1);
	b.source[VS_ALARM_SOURCE_MAX - 1] = '\0';
	alarm_log_format(line, sizeof(line), "dropped", &b, UINT64_MAX);
	assert_int_equal(strlen(line),
			 strlen("alarm dropped 201 fault \"\" at 18446744073709.551 s") +
			     4 * (VS_ALARM_SOURCE_MAX - 1));
	{
		static const char end[] = "\\x01\" at 18446744073709.551 s";

		assert_string_equal(line + strlen(line) - (sizeof(end) - 1), end);
	}
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test_setup(test_raised_and_cleared, setup),
	    cmocka_unit_test_setup(test_raised_again, setup),
	    cmocka_unit_test_setup(test_cleared_then_raised, setup),
	    cmocka_unit_test_setup(test_dropped_from_a_full_list, setup),
	    cmocka_unit_test_setup(test_format, setup),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
