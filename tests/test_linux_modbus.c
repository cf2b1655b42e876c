/* vehicle-fw's Modbus RTU backend against mbdrive-sim (libmodbus server,
 * two units on one bus) over a socat pty pair; the command link on a
 * second pty. Moves, a drive reporting an error, fault reset, a drive that
 * stops answering mid-move, SIGTERM; the battery voltage from a register of
 * a drive's unit and of a BMS of its own, changing, failing and returning.
 * And the backend itself in this process against the same simulator:
 * what it reports (enabled from the status bit, phase), the speed it
 * writes (0 until the stage is on) and the polarity option.
 * Runs in the QEMU guest on its instruction-counted clock
 * (tests/qemu/fw_process.sh): its timing checks then hold on a busy host. */
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <setjmp.h>
#include <signal.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <cmocka.h>
#include <modbus/modbus.h>

#include "fw_rig.h"

#include "../hal/linux/modbus_drive.h"

static char BUS_A[600], BUS_B[600];
static pid_t SOCAT = -1, SIM = -1, FW = -1;
static int MASTER = -1, SIM_CTL = -1; /* SIM_CTL: the simulator's stdin */

static void console(const char *line, char *reply, size_t cap)
{
	fw_console(MASTER, line, reply, cap, 3000);
}

/* in: NULL, or where to put the write end of a pipe to its stdin. */
static pid_t spawn(const char *log, char *const argv[], int *in)
{
	int pfd[2] = {-1, -1};
	if (in)
		assert_int_equal(pipe(pfd), 0);
	pid_t p = fork();
	assert_true(p >= 0);
	if (p == 0) {
		int fd = open(log ? log : "/dev/null", O_WRONLY | O_CREAT | O_TRUNC, 0644);
		dup2(fd, 2);
		int nul = open("/dev/null", O_WRONLY);
		dup2(nul, 1);
		if (in) {
			dup2(pfd[0], 0);
			close(pfd[0]);
			close(pfd[1]);
		}
		execvp(argv[0], argv);
		_exit(127);
	}
	if (in) {
		close(pfd[0]);
		*in = pfd[1];
	}
	return p;
}

/* One control line to the simulator (mbdrive_sim_main.c). */
static void sim_ctl(const char *line)
{
	assert_int_equal(write(SIM_CTL, line, strlen(line)), (ssize_t)strlen(line));
	assert_int_equal(write(SIM_CTL, "\n", 1), 1);
}

static long now_ms(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return (long)t.tv_sec * 1000L + t.tv_nsec / 1000000L;
}

static void reap(pid_t *p, int sig)
{
	if (*p > 0) {
		kill(*p, sig);
		waitpid(*p, NULL, 0);
	}
	*p = -1;
}

/* One console line on the raw link; the reply line without its newline. */
static void expect(const char *line, const char *want)
{
	char reply[512];
	console(line, reply, sizeof(reply));
	if (strcmp(reply, want) != 0)
		print_message("'%s': got '%s', expected '%s'\n", line, reply, want);
	assert_string_equal(reply, want);
}

/* Polls an operation until it replies want (bounded by ms). */
static void wait_reply(const char *line, const char *want, long ms)
{
	char reply[512];
	long end = now_ms() + ms;
	do {
		console(line, reply, sizeof(reply));
		if (!strcmp(reply, want))
			return;
		fw_sleep_ms(20);
	} while (now_ms() < end);
	print_message("%s: '%s', expected '%s'\n", line, reply, want);
	fail();
}

static void wait_state(const char *want, long ms)
{
	wait_reply("getState", want, ms);
}

/* Polls vehicle-fw's log until it holds text (bounded by ms). */
static void wait_log(const char *text, long ms)
{
	char log[8192];
	long end = now_ms() + ms;
	do {
		fw_read_log(log, sizeof(log));
		if (strstr(log, text))
			return;
		fw_sleep_ms(20);
	} while (now_ms() < end);
	print_message("log without '%s':\n%s", text, log);
	fail();
}

/* The simulator's battery: on drive unit 1 (holding register 0x108, 10 mV
 * per count) or on a unit of its own, a BMS (unit 10, input registers
 * 0x201-0x202, uint32 mV). */
#define BATTERY_ON_DRIVE                                                                           \
	"    <battery source=\"modbus\" bus=\"0\" unit=\"1\" reg=\"264\" scale=\"10\"/>\n"
#define BATTERY_BMS                                                                                \
	"    <battery source=\"modbus\" bus=\"0\" unit=\"10\" reg=\"513\" reg_type=\"input\"\n"    \
	"             width=\"32\" period_ms=\"100\"/>\n"
static const char *SIM_BATTERY = "1", *SIM_BATTERY_MV = "25200", *BATTERY_XML = BATTERY_ON_DRIVE;

/* socat and the simulator, no vehicle-fw. */
static int setup_bus(void **state)
{
	(void)state;
	char exe[700];
	struct stat sb;

	/* The bus: a pty pair with a path on both ends. */
	char la[700], lb[700];
	snprintf(la, sizeof(la), "pty,raw,echo=0,link=%s", BUS_A);
	snprintf(lb, sizeof(lb), "pty,raw,echo=0,link=%s", BUS_B);
	char *sa[] = {"socat", la, lb, NULL};
	SOCAT = spawn(NULL, sa, NULL);
	for (int i = 0; i < 100 && (stat(BUS_A, &sb) || stat(BUS_B, &sb)); i++)
		fw_sleep_ms(20);
	assert_int_equal(stat(BUS_B, &sb), 0);

	snprintf(exe, sizeof(exe), "%s/mbdrive-sim", FW_BUILD_DIR);
	char *sm[] = {exe,
		      "--port",
		      BUS_A,
		      "--units",
		      "1,2",
		      "--battery",
		      (char *)SIM_BATTERY,
		      "--battery-mv",
		      (char *)SIM_BATTERY_MV,
		      NULL};
	SIM = spawn(NULL, sm, &SIM_CTL);
	fw_sleep_ms(200); /* the simulator opens its port */
	return 0;
}

static long FW_START_MS;

/* vehicle-fw on the bus that setup_bus started. */
static void start_fw(void)
{
	char text[2048], exe[700];
	/* timeout x (retries + 1) = 30 ms, inside the drive timeout. That is
	 * 250 ms, not the product's 50: socat, the simulator and the bus thread
	 * share the guest's one CPU with the loop. The tick runs at SCHED_FIFO
	 * where permitted, as on the vehicle. */
	snprintf(
	    text, sizeof(text),
	    "<vehicle kinematics=\"differential\" tick_hz=\"100\">\n"
	    "  <devices contact_sensor=\"false\" obstacle_input=\"false\" estop=\"false\"\n"
	    "           joystick=\"false\"/>\n"
	    "  <supervision drive_timeout_ms=\"250\"/>\n"
	    "  <backends>\n"
	    "    <modbus bus=\"0\" device=\"%s\" baud=\"115200\" timeout_ms=\"15\" retries=\"1\"\n"
	    "            reg_target_speed=\"256\" reg_position=\"258\" reg_status=\"260\"\n"
	    "            reg_alarm=\"261\" reg_servo_on=\"262\" reg_fault_reset=\"263\"/>\n"
	    "    <drive axis=\"0\" type=\"modbus\" bus=\"0\" unit=\"1\"/>\n"
	    "    <drive axis=\"1\" type=\"modbus\" bus=\"0\" unit=\"2\"/>\n"
	    "%s"
	    "  </backends>\n"
	    "</vehicle>\n",
	    BUS_B, BATTERY_XML);
	fw_write_file(FW_VPATH, text);
	fw_write_file(FW_IOPATH, "<io/>\n");

	int slave;
	char port[256];
	MASTER = fw_open_port(&slave, port, sizeof(port));
	snprintf(exe, sizeof(exe), "%s/vehicle-fw", FW_BUILD_DIR);
	char *fa[] = {exe,	"--config", FW_VPATH,	     "--io",	   FW_IOPATH,
		      "--port", port,	    "--rt-priority", (char *)"10", NULL};
	FW_START_MS = now_ms();
	FW = spawn(FW_LOGPATH, fa, NULL);
	close(slave);
	fw_sleep_ms(300);
}

static int setup(void **state)
{
	setup_bus(state);
	start_fw();
	return 0;
}

static int teardown(void **state)
{
	(void)state;
	reap(&FW, SIGKILL);
	reap(&SIM, SIGTERM);
	reap(&SOCAT, SIGTERM);
	if (MASTER >= 0)
		close(MASTER);
	MASTER = -1;
	if (SIM_CTL >= 0)
		close(SIM_CTL);
	SIM_CTL = -1;
	return 0;
}

/* The battery on a BMS of its own (unit 10), starting at 24.68 V. */
static int setup_bms(void **state)
{
	SIM_BATTERY = "10";
	SIM_BATTERY_MV = "24680";
	BATTERY_XML = BATTERY_BMS;
	return setup(state);
}

static int teardown_bms(void **state)
{
	SIM_BATTERY = "1";
	SIM_BATTERY_MV = "25200";
	BATTERY_XML = BATTERY_ON_DRIVE;
	return teardown(state);
}

static void test_move_over_modbus(void **state)
{
	(void)state;
	char reply[512];
	expect("setPower true", "ok true");
	expect("setServo true", "ok true");
	wait_state("ok true 16 \"Ready\"", 1000);
	/* status bit 0 of both drives, read back over the bus */
	expect("getServoStatus 0", "ok true true");
	expect("getServoStatus 1", "ok true true");
	/* The battery from drive unit 1's register 0x108: 2520 x 10 mV, in
	 * the interface's 0.1 V units. */
	expect("getBatteryVoltage", "ok true 252.000");
	expect("moveForward 300", "ok true");
	wait_state("ok true 16 \"Ready\"", 4000);
	/* Odometry from the drives' position registers: the 300 mm move,
	 * within a fraction of a millimetre. */
	console("getPosition", reply, sizeof(reply));
	double x = 0, y = 0, th = 0;
	assert_int_equal(sscanf(reply, "ok true %lf %lf %lf", &x, &y, &th), 3);
	assert_true(x > 299.5 && x < 300.5);
	assert_true(y > -0.5 && y < 0.5);
}

/* The drive sets its alarm register mid-move: fault 201 with the drive's
 * code, unit stopped, servo off; clearAlarm resets the drive's fault. */
static void test_drive_error(void **state)
{
	(void)state;
	expect("setPower true", "ok true");
	expect("setServo true", "ok true");
	expect("moveForward 2000", "ok true");
	wait_state("ok true 17 \"Busy\"", 1000);
	assert_int_equal(kill(SIM, SIGUSR2), 0);
	wait_state("ok true 19 \"Alarm-201\"", 1000);
	expect("getActiveAlarm 2", "ok true 1 1 201 fault \"drive 0 fault 0x0031\"");
	expect("getServoStatus 0", "ok true false");
	expect("clearAlarm", "ok true");
	/* The reset went to the drive: its alarm stays clear. */
	fw_sleep_ms(200);
	expect("getState", "ok true 24 \"Powered\"");
	expect("setServo true", "ok true");
	wait_state("ok true 16 \"Ready\"", 1000);
}

/* Unit 2 stops answering mid-move: fault 202 naming axis 1 (not the drive
 * sharing its bus), unit stopped; SIGTERM then ends cleanly. */
static void test_drive_silent_then_sigterm(void **state)
{
	(void)state;
	char log[8192];
	expect("setPower true", "ok true");
	expect("setServo true", "ok true");
	expect("moveForward 2000", "ok true");
	wait_state("ok true 17 \"Busy\"", 1000);
	assert_int_equal(kill(SIM, SIGUSR1), 0);
	wait_state("ok true 19 \"Alarm-202\"", 1000);
	expect("getActiveAlarm 3", "ok true 1 1 202 fault \"drive 1 not answering\"");
	int status = 0;
	assert_int_equal(kill(FW, SIGTERM), 0);
	assert_int_equal(waitpid(FW, &status, 0), FW);
	FW = -1;
	assert_true(WIFEXITED(status));
	assert_int_equal(WEXITSTATUS(status), 0);
	FILE *f = fopen(FW_LOGPATH, "r");
	assert_non_null(f);
	size_t n = fread(log, 1, sizeof(log) - 1, f);
	log[n] = '\0';
	fclose(f);
	assert_non_null(
	    strstr(log, "vehicle-fw: final state: unpowered, relay open, servo off, stopped\n"));
}

/* The battery on a BMS of its own: exact values as they change, a silent
 * BMS that keeps the last value (the drives unaffected) until 2 s without
 * a reading give 0 V and fault 207, then its return. */
static void test_battery_bms(void **state)
{
	(void)state;
	char reply[512], log[8192], want[1024];
	expect("getBatteryVoltage", "ok true 246.800");
	expect("setPower true", "ok true");
	expect("setServo true", "ok true");
	wait_state("ok true 16 \"Ready\"", 1000);

	/* Below the 22.0 V low threshold: warning 140, nothing stops. */
	sim_ctl("battery 21500");
	wait_reply("getBatteryVoltage", "ok true 215.000", 1000);
	expect("getActiveAlarm 4", "ok true 1 1 140 warning \"battery below 22.0 V\"");
	sim_ctl("battery 23000");
	wait_reply("getBatteryVoltage", "ok true 230.000", 1000);
	expect("clearAlarm", "ok true");
	expect("getState", "ok true 16 \"Ready\"");

	/* Silent for 1 s: the last value holds, the failed reads are counted,
	 * the unit stays ready (its drives still answer). */
	sim_ctl("battery silent");
	long t0 = now_ms();
	fw_sleep_ms(1000);
	expect("getBatteryVoltage", "ok true 230.000");
	expect("getState", "ok true 16 \"Ready\"");
	console("$rt", reply, sizeof(reply));
	const char *e = strstr(reply, " battery_errors ");
	assert_non_null(e);
	long errors = strtol(e + 16, NULL, 10);
	/* one read per 100 ms period (at most 11 in the second), each failing
	 * after its 15 ms timeout; a busy host may delay some */
	if (errors < 3 || errors > 11)
		print_message("$rt: '%s'\n", reply);
	assert_true(errors >= 3 && errors <= 11);

	/* 2 s without a reading: 0 V, the critical fault stops the unit. */
	wait_state("ok true 19 \"Alarm-207\"", 2000);
	long dt = now_ms() - t0;
	if (dt < 1850)
		print_message("fault 207 after %ld ms of silence\n", dt);
	assert_true(dt >= 1850);
	expect("getBatteryVoltage", "ok true 0.000");
	expect("getActiveAlarm 4", "ok true 2 2 140 warning \"battery below 22.0 V\" 207 fault "
				   "\"battery below 20.0 V\"");
	expect("getServoStatus 0", "ok true false");
	/* While it stays silent the fault is raised again. */
	expect("clearAlarm", "ok true");
	wait_state("ok true 19 \"Alarm-207\"", 500);

	/* The BMS answers again: the voltage is back, clearAlarm holds. */
	sim_ctl("battery answer");
	wait_reply("getBatteryVoltage", "ok true 230.000", 1000);
	expect("clearAlarm", "ok true");
	expect("getState", "ok true 24 \"Powered\"");
	fw_read_log(log, sizeof(log));
	snprintf(
	    want, sizeof(want),
	    "vehicle-fw: warning: battery: no reading from unit 10 on %s for 2000 ms: it reads 0 "
	    "V until it answers\n",
	    BUS_B);
	assert_non_null(strstr(log, want));
	snprintf(want, sizeof(want), "vehicle-fw: battery: unit 10 on %s answers again: 23000 mV\n",
		 BUS_B);
	assert_non_null(strstr(log, want));
}

/* A BMS that does not answer at start: vehicle-fw waits for it 2 s, then
 * starts with 0 V (fault 207) and takes its first reading when it comes. */
static int setup_bms_silent(void **state)
{
	SIM_BATTERY = "10";
	SIM_BATTERY_MV = "24680";
	BATTERY_XML = BATTERY_BMS;
	setup_bus(state);
	sim_ctl("battery silent");
	fw_sleep_ms(50);
	start_fw();
	return 0;
}

static void test_battery_absent_at_start(void **state)
{
	(void)state;
	/* The link is served once the start-up wait is over. */
	wait_log("battery: no reading from unit 10 on ", 4000);
	assert_true(now_ms() - FW_START_MS >= 1950);
	wait_state("ok true 19 \"Alarm-207\"", 1000);
	expect("getBatteryVoltage", "ok true 0.000");
	sim_ctl("battery answer");
	wait_reply("getBatteryVoltage", "ok true 246.800", 1000);
	expect("clearAlarm", "ok true");
	expect("getState", "ok true 25 \"Unpowered\"");
}

/* The simulator's register map as an independent client (pymodbus) sees
 * it: the same encoding the backend uses. */
static void test_pymodbus_crosscheck(void **state)
{
	(void)state;
	char cmd[1500], out[1024];
	/* Above 65535 mV: the 32-bit register pair has a high word. */
	sim_ctl("battery 71850");
	fw_sleep_ms(50);
	snprintf(cmd, sizeof(cmd),
		 "/usr/bin/python3 host_sim/devices/mb_crosscheck.py %s %d 1 71850 2>&1", BUS_B,
		 (int)SIM);
	FILE *p = popen(cmd, "r");
	assert_non_null(p);
	size_t n = fread(out, 1, sizeof(out) - 1, p);
	out[n] = '\0';
	int st = pclose(p);
	if (st != 0)
		print_message("%s", out);
	assert_int_equal(st, 0);
	assert_string_equal(out, "crosscheck: PASS\n");
}

/* ---- the backend in this process, against the simulator ---------------- */

/* The bus thread stops; its port stays open for raw reads (b->ctx), with
 * a timeout a loaded host cannot miss. */
static void bus_pause(mb_bus_t *b)
{
	b->stop = true;
	pthread_join(b->th, NULL);
	b->running = false;
	b->stop = false;
	modbus_set_response_timeout(b->ctx, 1, 0);
}

/* The bus thread again, with the bus's own response timeout. */
static void bus_resume(mb_bus_t *b)
{
	char err[256] = "";
	modbus_set_response_timeout(b->ctx, 0, b->cfg.timeout_ms * 1000u);
	if (mb_bus_start(b, err, sizeof(err)) != 0)
		fail_msg("%s", err);
}

/* Polls the backend's sample of drive i until ok(st) (bounded by ms). */
static void wait_drive(mb_bus_t *b, unsigned i, bool (*ok)(const hal_drive_state_t *), long ms,
		       hal_drive_state_t *st)
{
	long end = now_ms() + ms;
	do {
		mb_drive_read(b, i, st);
		if (st->fresh && ok(st))
			return;
		fw_sleep_ms(5);
	} while (now_ms() < end);
	print_message("drive %u: enabled %d phase %u fault 0x%04X\n", i, st->enabled, st->phase,
		      st->fault_code);
	fail();
}

static bool is_ready(const hal_drive_state_t *st)
{
	return st->phase == HAL_DRIVE_READY;
}

static bool is_enabled(const hal_drive_state_t *st)
{
	return st->enabled;
}

static bool is_fault(const hal_drive_state_t *st)
{
	return st->fault_code != 0;
}

/* One raw int32 pair (high word first) of a unit, on the paused bus. */
static int32_t raw32(mb_bus_t *b, int unit, int addr)
{
	uint16_t r[2] = {0, 0};
	modbus_set_slave(b->ctx, unit);
	assert_int_equal(modbus_read_registers(b->ctx, addr, 2, r), 2);
	return (int32_t)(((uint32_t)r[0] << 16) | r[1]);
}

/* enabled is the drive's status bit, never the servo on command; the speed
 * written is 0 until that bit is on; polarity reverse negates the speed
 * written and the position read (unit 1 reverse, unit 2 normal). */
static void test_backend_report_and_polarity(void **state)
{
	(void)state;
	char err[256] = "";
	hal_drive_state_t st;
	bk_modbus_bus_t cfg = {.used = true,
			       .baud = 115200,
			       .parity = 'N',
			       .stop_bits = 1,
			       .timeout_ms = 50,
			       .retries = 1,
			       .reg = {256, 258, 260, 261, 262, 263}};
	assert_true(strlen(BUS_B) < sizeof(cfg.device));
	memcpy(cfg.device, BUS_B, strlen(BUS_B) + 1);
	static mb_bus_t b;
	if (mb_bus_open(&b, &cfg, err, sizeof(err)) != 0)
		fail_msg("%s", err);
	assert_int_equal(mb_bus_add(&b, 1, true), 0);
	assert_int_equal(mb_bus_add(&b, 2, false), 1);
	mb_drive_read(&b, 0, &st);
	assert_false(st.fresh);
	assert_int_equal(st.phase, HAL_DRIVE_UNKNOWN); /* nothing read yet */
	assert_int_equal(mb_bus_start(&b, err, sizeof(err)), 0);

	/* a speed without servo on: the stage stays off, nothing written */
	mb_drive_set_velocity(&b, 0, 256 * 2000);
	mb_drive_set_velocity(&b, 1, 256 * 2000);
	wait_drive(&b, 0, is_ready, 1000, &st);
	assert_false(st.enabled);
	assert_int_equal(st.position_counts, 0);
	bus_pause(&b);
	assert_int_equal(raw32(&b, 1, 256), 0);
	assert_int_equal(raw32(&b, 2, 256), 0);
	bus_resume(&b);

	/* servo on: enabled once the drive's status bit says so */
	mb_drive_enable(&b, 0, true);
	mb_drive_enable(&b, 1, true);
	wait_drive(&b, 0, is_enabled, 1000, &st);
	assert_int_equal(st.phase, HAL_DRIVE_ENABLED);
	wait_drive(&b, 1, is_enabled, 1000, &st);
	fw_sleep_ms(100);
	/* unit 1 (reverse) was sent -2000 counts/s, unit 2 +2000 */
	bus_pause(&b);
	assert_int_equal(raw32(&b, 1, 256), -2000);
	assert_int_equal(raw32(&b, 2, 256), 2000);
	assert_true(raw32(&b, 1, 258) < -100);
	assert_true(raw32(&b, 2, 258) > 100);
	bus_resume(&b);

	/* unit 1 raises its alarm: the stage goes off while servo on is still
	 * commanded; not enabled, phase fault, the speed written is 0 */
	assert_int_equal(kill(SIM, SIGUSR2), 0);
	wait_drive(&b, 0, is_fault, 1000, &st);
	assert_int_equal(st.fault_code, 0x31);
	assert_false(st.enabled);
	assert_int_equal(st.phase, HAL_DRIVE_FAULT);
	/* two more samples: the position stands (stage off) */
	wait_drive(&b, 0, is_fault, 1000, &st);
	wait_drive(&b, 0, is_fault, 1000, &st);
	int32_t reported = st.position_counts;
	assert_true(reported > 100);
	bus_pause(&b);
	assert_int_equal(raw32(&b, 1, 256), 0);
	assert_int_equal(raw32(&b, 1, 258), -reported);
	assert_int_equal(raw32(&b, 2, 256), 2000);
	mb_bus_close(&b);
}

int main(int argc, char **argv)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test_setup_teardown(test_pymodbus_crosscheck, setup_bus, teardown),
	    cmocka_unit_test_setup_teardown(test_backend_report_and_polarity, setup_bus, teardown),
	    cmocka_unit_test_setup_teardown(test_move_over_modbus, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_drive_error, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_drive_silent_then_sigterm, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_battery_bms, setup_bms, teardown_bms),
	    cmocka_unit_test_setup_teardown(test_battery_absent_at_start, setup_bms_silent,
					    teardown_bms),
	};
	if (fw_rig_init(argc > 0 ? argv[0] : NULL, "vsmb") < 0)
		return 1;
	snprintf(BUS_A, sizeof(BUS_A), "%s/bus-a", FW_DIR);
	snprintf(BUS_B, sizeof(BUS_B), "%s/bus-b", FW_DIR);
	signal(SIGPIPE, SIG_IGN);
	int rc = cmocka_run_group_tests(tests, NULL, NULL);
	fw_rig_cleanup();
	return rc;
}
