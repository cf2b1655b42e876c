/* The whole unit in-process: firmware + console + simulated plant, driven
 * through sim_exec exactly as a host drives the console. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "hal/posix/config_xml.h"
#include "host_sim/sim.h"

static sim_t sim;
static char BUILD_DIR[512] = "build"; /* where vehicle-sim is: beside tests/ */

static void expect(const char *line, const char *want)
{
	char reply[CONSOLE_REPLY_MAX];
	assert_true(sim_exec(&sim, line, reply, sizeof(reply)));
	if (strcmp(reply, want) != 0)
		fail_msg("'%s' -> '%s', expected '%s'", line, reply, want);
}

static void start(bool ideal)
{
	vs_config_t cfg;
	plant_params_t pp;
	vs_config_defaults(&cfg);
	/* Time passes in lockstep waits with no request; the link watchdog
	 * has its own tests. */
	cfg.link_timeout_ms = 0;
	if (ideal) {
		plant_params_ideal(&pp);
		cfg.encoder_counts_per_rev = plant_hires_counts_per_rev(&cfg);
		plant_config_lag(&pp, &cfg);
	} else {
		plant_params_default(&pp);
	}
	assert_int_equal(sim_init(&sim, &cfg, &pp), 0);
}

static void move_forward_end_to_end(void **state)
{
	(void)state;
	start(true);
	expect("getState", "ok true 25 \"Unpowered\"");
	expect("setPower true", "ok true");
	expect("setServo true", "ok true");
	expect("getState", "ok true 16 \"Ready\"");
	expect("moveForward 1000", "ok true");
	expect("$wait 100", "ok wait 100");
	expect("getState", "ok true 17 \"Busy\"");
	/* 1000 mm at 500 mm/s and 500 mm/s^2: 3 s; margin for settling. */
	expect("$wait 3900", "ok wait 3900");
	expect("getPosition", "ok true 1000.000 0.000 0.000");
	expect("$sim pose", "ok pose 1000.000 0.000 0.000");
	expect("getState", "ok true 16 \"Ready\"");
	assert_int_equal(sim.now_us, 4000000);
	assert_int_equal(sim.ticks, 4000);
}

/* With motor lag, limits and 16384-count encoders the odometry is good to
 * an encoder count and the truth to a fraction of a millimetre. */
static void move_forward_realistic_plant(void **state)
{
	(void)state;
	start(false);
	expect("setPower true", "ok true");
	expect("setServo true", "ok true");
	expect("moveForward 1000", "ok true");
	sim_run_ms(&sim, 4000);
	vs_position_t pos;
	assert_true(vs_getPosition(sim_vehicle(&sim), &pos));
	double count_mm = M_PI * 150.0 / 16384.0;
	assert_true(fabs(pos.x - 1000.0) <= count_mm);
	double x, y, th;
	plant_pose(sim_plant(&sim), &x, &y, &th);
	assert_true(fabs(x - 1000.0) < 0.1);
	assert_true(fabs(y) < 0.1);
	assert_true(fabs(th) < 0.01);
}

static void sim_extras_replies(void **state)
{
	(void)state;
	start(false);
	plant_t *pl = sim_plant(&sim);
	expect("$sim contact on", "ok contact on");
	assert_true(pl->contact_inject);
	expect("$sim contact off", "ok contact off");
	assert_false(pl->contact_inject);
	expect("$sim obstacle on", "ok obstacle on");
	assert_true(pl->obstacle);
	expect("$sim caution on", "ok caution on");
	assert_true(pl->caution);
	expect("$sim estop off", "ok estop off");
	expect("$sim contact maybe", "error 8 usage: $sim contact on|off");
	expect("$sim joystick 0.5 -1 0", "ok joystick 16384 -32767 0");
	expect("$sim joystick 1.5 0 0", "error 8 joystick axis must be -1..1, got '1.5'");
	expect("$sim joystick lost", "ok joystick lost");
	assert_false(pl->js.present);
	expect("$sim relay drop", "ok relay drop");
	expect("$sim relay sideways", "error 8 usage: $sim relay fail|ok|drop");
	expect("$sim drive 1 fault 0x2310", "ok drive 1 fault 0x2310");
	assert_int_equal(pl->w[1].fault_latched, 0x2310);
	expect("$sim drive 1 fault 0", "error 8 fault code must be 1..65535, got '0'");
	expect("$sim drive 0 stuck", "ok drive 0 stuck");
	expect("$sim drive 0 silent", "ok drive 0 silent");
	expect("$sim drive 0 ok", "ok drive 0 ok");
	assert_false(pl->w[0].stuck);
	assert_false(pl->w[0].silent);
	expect("$sim drive 2 ok", "error 8 no axis 2 (0..1)");
	expect("$sim drive x ok",
	       "error 8 usage: $sim drive AXIS fault CODE|ok|stuck|silent|hold|reboot");
	expect("$sim battery 21500", "ok battery 21500");
	assert_true(pl->battery_ocv_v == 21.5);
	expect("$sim battery -1", "error 8 usage: $sim battery MV (0..1000000)");
	expect("$sim input 1 300", "ok input 1 44"); /* 8-bit input: 300 & 0xff */
	expect("$sim input 3 1", "error 8 no input with id 3");
	expect("$sim wire 3 2", "ok wire 3 2");
	expect("$sim wire 3 none", "ok wire 3 none");
	expect("$sim wire 1 2", "error 8 cannot wire 1 to 2");
	expect("$sim wall 1000 -500 1100 500", "ok wall 1");
	expect("$sim wall 1000 -500 1100 nan", "error 8 not a number 'nan'");
	expect("$sim pose", "ok pose 0.000 0.000 0.000");
	expect("$sim pose 1", "error 8 usage: $sim pose");
	expect("$sim teleport", "error 8 unknown command '$sim teleport'");
	/* A push moves the truth in the base's frame; a wrong one moves nothing. */
	expect("$sim push 100 0 90", "ok push 100.000 0.000 90.000");
	expect("$sim push 0 50 0", "ok push 50.000 0.000 90.000"); /* left of +y is -x */
	expect("$sim push 1 2", "error 8 usage: $sim push DX DY DTH (mm forward, mm left, deg "
				"counter-clockwise, in the base's frame)");
	expect("$sim push 1 2 3 4", "error 8 usage: $sim push DX DY DTH (mm forward, mm left, deg "
				    "counter-clockwise, in the base's frame)");
	expect("$sim push 1 x 3", "error 8 not a number 'x'");
	expect("$sim push nan 0 0", "error 8 not a number 'nan'");
	expect("$sim push 1e9 0 0", "error 8 a push moves at most 1000 mm along each axis and 180 "
				    "deg");
	expect("$sim push 0 0 -180.5", "error 8 a push moves at most 1000 mm along each axis and "
				       "180 deg");
	expect("$sim pose", "ok pose 50.000 0.000 90.000");
	expect("$wait -5", "error 8 usage: $wait MS (0..3600000)");
	expect("$wait 3600001", "error 8 usage: $wait MS (0..3600000)");
	expect("$wait", "error 8 usage: $wait MS (0..3600000)");
	assert_int_equal(sim.now_us, 0); /* none of that ran time */
	expect("$wait 0", "ok wait 0");
	assert_int_equal(sim.now_us, 0);
	/* Real time runs by itself: '$wait' is refused, nothing waits. */
	sim_set_realtime(&sim, true);
	expect("$wait 500", "error 8 $wait runs simulated time only with --fast; in real time the "
			    "host waits");
	assert_int_equal(sim.now_us, 0);
	sim_set_realtime(&sim, false);
	expect("$wait 1", "ok wait 1");
	assert_int_equal(sim.now_us, 1000);
}

static void relay_failure_through_console(void **state)
{
	(void)state;
	start(false);
	expect("$sim relay fail", "ok relay fail");
	expect("setPower true", "ok false");
	expect("getState", "ok true 19 \"Alarm-205\"");
	expect("$sim relay ok", "ok relay ok");
	expect("clearAlarm", "ok true");
	expect("setPower true", "ok true");
	expect("getState", "ok true 24 \"Powered\"");
}

static void io_loopback_through_console(void **state)
{
	(void)state;
	start(false);
	/* Default io table: output 3 (8 bits) loops back to input 1. */
	expect("setOutput 3 255 15", "ok true");
	expect("getInput 1", "ok true 15");
	expect("setOutput 3 0 5", "ok true");
	expect("getInput 1", "ok true 10");
	expect("$sim input 2 1", "ok input 2 1");
	expect("getInput 2", "ok true 1");
}

static void contact_with_wall_locks(void **state)
{
	(void)state;
	start(true);
	expect("$sim wall 700 -1000 800 1000", "ok wall 1");
	expect("setDigitalSensorLock true", "ok true");
	expect("setPower true", "ok true");
	expect("setServo true", "ok true");
	expect("moveForward 1000", "ok true");
	expect("$wait 4000", "ok wait 4000");
	expect("getState", "ok true 23 \"Locked\"");
	double x, y, th;
	plant_pose(sim_plant(&sim), &x, &y, &th);
	/* Touched at x = 400 (wall at 700, body radius 300), then braked. */
	assert_true(x >= 400.0 && x < 700.0);
}

typedef struct {
	unsigned calls;
	double last_time_s;
} tick_rec_t;

static void on_tick(void *ctx, sim_t *s)
{
	tick_rec_t *r = ctx;
	r->calls++;
	r->last_time_s = sim_time_s(s);
}

static void tick_callback_and_trace(void **state)
{
	(void)state;
	start(false);
	tick_rec_t rec = {0};
	sim_set_tick_cb(&sim, on_tick, &rec);
	char *buf = NULL;
	size_t len = 0;
	FILE *f = open_memstream(&buf, &len);
	assert_non_null(f);
	trace_t tr;
	trace_attach(&tr, f, 5);
	sim_set_trace(&sim, &tr);
	expect("$wait 20", "ok wait 20");
	assert_int_equal(rec.calls, 20);
	assert_true(rec.last_time_s == 0.020);
	assert_int_equal(trace_close(&tr), 0);
	fclose(f);

	/* Header + rows at ticks 1, 6, 11, 16. */
	int lines = 0;
	for (size_t i = 0; i < len; i++)
		lines += buf[i] == '\n';
	assert_int_equal(lines, 5);
	assert_memory_equal(buf,
			    "time_s,cmd_x_mm,cmd_y_mm,cmd_th_deg,odo_x_mm,odo_y_mm,odo_th_deg,"
			    "true_x_mm,true_y_mm,true_th_deg,cmd_vx_mm_s,cmd_vy_mm_s,cmd_w_deg_s,"
			    "sp0_cps,sp1_cps,sp2_cps,sp3_cps,meas0_cps,meas1_cps,meas2_cps,"
			    "meas3_cps,state,queue_len,alarms,newest_alarm,enc0,enc1,enc2,enc3\n",
			    strlen("time_s,cmd_x_mm,cmd_y_mm,cmd_th_deg,odo_x_mm,odo_y_mm,"
				   "odo_th_deg,true_x_mm,true_y_mm,true_th_deg,cmd_vx_mm_s,"
				   "cmd_vy_mm_s,cmd_w_deg_s,sp0_cps,sp1_cps,sp2_cps,sp3_cps,"
				   "meas0_cps,meas1_cps,meas2_cps,meas3_cps,state,queue_len,alarms,"
				   "newest_alarm,enc0,enc1,enc2,enc3\n"));
	const char *row1 = strchr(buf, '\n') + 1;
	const char *want =
	    "0.001000,0.0000,0.0000,0.0000,0.0000,0.0000,0.0000,0.0000,0.0000,"
	    "0.0000,0.000,0.000,0.000,0.00,0.00,0.00,0.00,0.00,0.00,0.00,0.00,25,0,0,0,0,0,0,0\n";
	assert_memory_equal(row1, want, strlen(want));
	free(buf);
}

/* The fine encoder is the finest power of two that vs_config_check admits:
 * 2^20 on the reference base; the mecanum base's fastest wheel (800 mm/s
 * along x and y plus 120 deg/s on a 425 mm lever, 2490 mm/s on 100 mm
 * wheels) allows 2^19; a configured finer resolution stays. */
static void hires_resolution_follows_the_limits(void **state)
{
	(void)state;
	vs_config_t cfg;
	char err[256];
	vs_config_defaults(&cfg);
	assert_int_equal(plant_hires_counts_per_rev(&cfg), 1u << 20);
	assert_int_equal(
	    config_load("config/vehicle-omni.xml", "config/io.xml", &cfg, NULL, err, sizeof(err)),
	    0);
	assert_int_equal(plant_hires_counts_per_rev(&cfg), 1u << 19);
	cfg.vel_limit_t_mm_s = 1600; /* defaults stay below the limits */
	assert_int_equal(plant_hires_counts_per_rev(&cfg), 1u << 18);
	cfg.encoder_counts_per_rev = 300000; /* admitted, and finer than 2^18 */
	assert_int_equal(plant_hires_counts_per_rev(&cfg), 300000);
	/* Rejected for another field: the fine default, and init names the field. */
	vs_config_defaults(&cfg);
	cfg.tick_hz = 5;
	assert_int_equal(plant_hires_counts_per_rev(&cfg), 1u << 20);
}

/* What a shell line prints (stdout and what it redirects), which must
 * exit 0. */
static void run_shell(const char *cmd, char *out, size_t cap)
{
	FILE *f = popen(cmd, "r");
	assert_non_null(f);
	size_t n = fread(out, 1, cap - 1, f);
	out[n] = '\0';
	assert_int_equal(pclose(f), 0);
}

/* The mecanum base of config/vehicle-omni.xml on the ideal plant moves
 * diagonally and turns to the exact pose, in-process and through
 * vehicle-sim --ideal. */
static void omni_config_on_ideal_plant(void **state)
{
	(void)state;
	vs_config_t cfg;
	plant_params_t pp;
	char err[256];
	assert_int_equal(
	    config_load("config/vehicle-omni.xml", "config/io.xml", &cfg, NULL, err, sizeof(err)),
	    0);
	cfg.link_timeout_ms = 0;
	plant_params_ideal(&pp);
	cfg.encoder_counts_per_rev = plant_hires_counts_per_rev(&cfg);
	plant_config_lag(&pp, &cfg);
	assert_int_equal(sim_init(&sim, &cfg, &pp), 0);
	expect("setPower true", "ok true");
	expect("setServo true", "ok true");
	expect("moveLinearRel 300 -200 0", "ok true");
	expect("$wait 3000", "ok wait 3000");
	expect("moveTurn 90", "ok true");
	expect("$wait 3000", "ok wait 3000");
	expect("getPosition", "ok true 300.000 -200.000 90.000");
	expect("$sim pose", "ok pose 300.000 -200.000 90.000");
	expect("getState", "ok true 16 \"Ready\"");

	char cmd[1200], out[2048];
	snprintf(cmd, sizeof(cmd),
		 "printf '$watchdog 0\\nsetPower true\\nsetServo true\\nmoveLinearRel 300 -200 "
		 "0\\n$wait 3000\\nmoveTurn 90\\n$wait 3000\\ngetPosition\\n' | %s/vehicle-sim "
		 "--fast --ideal --config config/vehicle-omni.xml --io config/io.xml 2>&1",
		 BUILD_DIR);
	run_shell(cmd, out, sizeof out);
	const char *want =
	    "vehicle-sim: mecanum base, 4 axes, 1000 Hz, ideal plant, 524288-count encoders, fast "
	    "mode (config/vehicle-omni.xml, config/io.xml)\n"
	    "ok watchdog 0\nok true\nok true\nok true\nok wait 3000\nok true\nok wait 3000\n"
	    "ok true 300.000 -200.000 90.000\n";
	if (strcmp(out, want) != 0)
		fail_msg("vehicle-sim printed:\n%s", out);
}

/* vehicle-sim logs each alarm as it is raised and cleared, in simulated
 * time (lockstep: the same lines on every run): refusals at once, a drive
 * fault at the tick that finds it, clearAlarm's clearing. */
static void sim_logs_alarm_events(void **state)
{
	(void)state;
	char cmd[1200], out[2048];
	snprintf(
	    cmd, sizeof(cmd),
	    "printf 'setServo true\\nsetPower true\\nsetServo true\\nmoveForward 300\\n"
	    "moveTurn 5\\n$wait 100\\n$sim drive 0 fault 0x2310\\n$wait 50\\n$sim drive 0 ok\\n"
	    "clearAlarm\\n$wait 10\\nsetVelocity 0 1\\n$wait 10\\n' | %s/vehicle-sim --fast "
	    "--config config/vehicle.xml --io config/io.xml 2>&1 >/dev/null",
	    BUILD_DIR);
	run_shell(cmd, out, sizeof out);
	const char *want =
	    "vehicle-sim: differential base, 2 axes, 1000 Hz, fast mode (config/vehicle.xml, "
	    "config/io.xml)\n"
	    "vehicle-sim: alarm raised 128 warning \"setServo refused: power off\" at 0.000 s\n"
	    "vehicle-sim: alarm raised 120 warning \"moveTurn refused: unit not ready\" at 0.000 "
	    "s\n"
	    "vehicle-sim: alarm raised 201 fault \"drive 0 fault 0x2310\" at 0.100 s\n"
	    "vehicle-sim: alarm cleared 128 warning \"setServo refused: power off\" at 0.150 s\n"
	    "vehicle-sim: alarm cleared 120 warning \"moveTurn refused: unit not ready\" at 0.150 "
	    "s\n"
	    "vehicle-sim: alarm cleared 201 fault \"drive 0 fault 0x2310\" at 0.150 s\n"
	    "vehicle-sim: alarm raised 111 warning \"setVelocity refused: out of limits\" at "
	    "0.160 s\n";
	if (strcmp(out, want) != 0)
		fail_msg("vehicle-sim logged:\n%s", out);
}

static void bad_config_rejected(void **state)
{
	(void)state;
	vs_config_t cfg;
	vs_config_defaults(&cfg);
	/* Time passes in lockstep waits with no request; the link watchdog
	 * has its own tests. */
	cfg.link_timeout_ms = 0;
	cfg.tick_hz = 5;
	const char *bad = NULL;
	assert_true(sim_init_ex(&sim, &cfg, NULL, &bad) < 0);
	assert_string_equal(bad, "tick_hz");
}

int main(int argc, char **argv)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test(move_forward_end_to_end),
	    cmocka_unit_test(move_forward_realistic_plant),
	    cmocka_unit_test(sim_extras_replies),
	    cmocka_unit_test(relay_failure_through_console),
	    cmocka_unit_test(io_loopback_through_console),
	    cmocka_unit_test(contact_with_wall_locks),
	    cmocka_unit_test(tick_callback_and_trace),
	    cmocka_unit_test(bad_config_rejected),
	    cmocka_unit_test(hires_resolution_follows_the_limits),
	    cmocka_unit_test(omni_config_on_ideal_plant),
	    cmocka_unit_test(sim_logs_alarm_events),
	};
	/* build/tests/test_sim -> build */
	if (argc > 0 && strrchr(argv[0], '/')) {
		snprintf(BUILD_DIR, sizeof(BUILD_DIR), "%s", argv[0]);
		*strrchr(BUILD_DIR, '/') = '\0';
		char *up = strrchr(BUILD_DIR, '/');
		if (up)
			*up = '\0';
		else
			snprintf(BUILD_DIR, sizeof(BUILD_DIR), ".");
	}
	return cmocka_run_group_tests(tests, NULL, NULL);
}
