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
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <pty.h>
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
#include "../hal/modbus/mbprofile.h"

static char BUS_A[600], BUS_B[600], SIM_LOGPATH[600];
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
	console("getActiveAlarm 4", reply, sizeof(reply));
	print_message("alarms: %s\n", reply);
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

/* A bus of drives: the simulator's units and profile, and the same profile
 * in vehicle-fw's <modbus> (%s: the device) with its <drive> elements.
 * COMM_MS: the drives' communication-loss stop. */
#define COMM_MS	  200
#define COMM_MS_S "200"
typedef struct {
	const char *units;
	const char *sim_args[8]; /* the profile's, NULL-terminated */
	const char *bus_xml;
	const char *geometry_xml; /* NULL: the default geometry */
	const char *supervision;  /* more <supervision> attributes */
	int32_t counts_300mm;	  /* a 300 mm move on the 150 mm wheel */
} rig_t;

/* Today's register map: the generic profile by its reg_* addresses, with
 * the communication timeout at 0x109. */
static const rig_t GENERIC = {
    "1,2",
    {"--set", "comm_timeout=0x109 u16", NULL},
    "    <modbus bus=\"0\" device=\"%s\" baud=\"115200\" timeout_ms=\"15\" retries=\"1\"\n"
    "            reg_target_speed=\"256\" reg_position=\"258\" reg_status=\"260\"\n"
    "            reg_alarm=\"261\" reg_servo_on=\"262\" reg_fault_reset=\"263\"\n"
    "            reg_comm_timeout=\"265\" comm_timeout_ms=\"" COMM_MS_S "\"/>\n"
    "    <drive axis=\"0\" type=\"modbus\" bus=\"0\" unit=\"1\"/>\n"
    "    <drive axis=\"1\" type=\"modbus\" bus=\"0\" unit=\"2\"/>\n",
    NULL,
    "",
    10430,
};

/* The ZLAC8015D's profile: one unit, two channels, the right motor
 * mirrored; hub motors of 4096 counts a turn on the wheel, so that the
 * speed unit (1 r/min, 68 counts/s) is fine enough for the encoder
 * supervision, and a position window above the wheel loop's dead band
 * (docs/linux.md, "Connecting a real Modbus drive"). */
static const rig_t ZLAC = {
    "1",
    {"--profile", "zlac8015d", NULL},
    "    <modbus bus=\"0\" device=\"%s\" timeout_ms=\"15\" retries=\"1\"\n"
    "            profile=\"zlac8015d\" comm_timeout_ms=\"" COMM_MS_S "\"/>\n"
    "    <drive axis=\"0\" type=\"modbus\" bus=\"0\" unit=\"1\" channel=\"0\"/>\n"
    "    <drive axis=\"1\" type=\"modbus\" bus=\"0\" unit=\"1\" channel=\"1\"\n"
    "           polarity=\"reverse\"/>\n",
    "  <geometry encoder_counts_per_rev=\"4096\"/>\n",
    /* the loop's dead band: half a unit (34 counts/s) at 20/s, 1.7 counts */
    " position_window_mm=\"0.3\"",
    2608,
};

/* A profile the configuration defines: 16-bit speed in 0.1 r/min, low word
 * first position in input registers, a status mask of two bits, enable,
 * stop and reset values of its own, the timeout in 10 ms units; the same
 * fields to the simulator (--set). */
static const char *const DEFINED_SETS[] = {
    "speed=0x40 s16",	     "position=0x30 s32 lo input",
    "status=0x20 u16",	     "alarm=0x21 u16",
    "enable=0x50 u16",	     "reset=0x51 u16",
    "comm_timeout=0x52 u16", "speed_scale=16384/600",
    "status_mask=0x0104",    "enable_on=0x55",
    "enable_off=0xAA",	     "reset_value=0x99",
    "comm_unit_ms=10",
};
static const rig_t DEFINED = {
    "1,2",
    {NULL}, /* DEFINED_SETS, each after --set */
    "    <modbus bus=\"0\" device=\"%s\" timeout_ms=\"15\" retries=\"1\" profile=\"generic\"\n"
    "            comm_timeout_ms=\"" COMM_MS_S "\" speed=\"0x40 s16\"\n"
    "            position=\"0x30 s32 lo input\" status=\"0x20 u16\" alarm=\"0x21 u16\"\n"
    "            enable=\"0x50 u16\" reset=\"0x51 u16\" comm_timeout=\"0x52 u16\"\n"
    "            speed_scale=\"16384/600\" status_mask=\"0x0104\" enable_on=\"0x55\"\n"
    "            enable_off=\"0xAA\" reset_value=\"0x99\" comm_unit_ms=\"10\"/>\n"
    "    <drive axis=\"0\" type=\"modbus\" bus=\"0\" unit=\"1\"/>\n"
    "    <drive axis=\"1\" type=\"modbus\" bus=\"0\" unit=\"2\" polarity=\"reverse\"/>\n",
    NULL,
    "",
    10430,
};

static const rig_t *RIG = &GENERIC;

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
	char *sm[48] = {exe,
			"--port",
			BUS_A,
			"--units",
			(char *)RIG->units,
			"--battery",
			(char *)SIM_BATTERY,
			"--battery-mv",
			(char *)SIM_BATTERY_MV};
	unsigned n = 9;
	for (unsigned i = 0; RIG->sim_args[i]; i++)
		sm[n++] = (char *)RIG->sim_args[i];
	for (unsigned i = 0; RIG == &DEFINED && i < sizeof DEFINED_SETS / sizeof DEFINED_SETS[0];
	     i++) {
		sm[n++] = "--set";
		sm[n++] = (char *)DEFINED_SETS[i];
	}
	sm[n] = NULL;
	SIM = spawn(SIM_LOGPATH, sm, &SIM_CTL);
	fw_sleep_ms(200); /* the simulator opens its port */
	return 0;
}

static long FW_START_MS;
static const char *IO_FILE; /* NULL: an empty io.xml of the test's own */

/* vehicle-fw on the bus that setup_bus started. */
static void start_fw(void)
{
	char text[4096], bus[2048], exe[700];
	/* timeout x (retries + 1) = 30 ms, inside the drive timeout. That is
	 * 250 ms, not the product's 50: socat, the simulator and the bus thread
	 * share the guest's one CPU with the loop. The tick runs at SCHED_FIFO
	 * where permitted, as on the vehicle. */
	snprintf(bus, sizeof(bus), RIG->bus_xml, BUS_B);
	snprintf(text, sizeof(text),
		 "<vehicle kinematics=\"differential\" tick_hz=\"100\">\n"
		 "  <devices contact_sensor=\"false\" obstacle_input=\"false\" estop=\"false\"\n"
		 "           joystick=\"false\"/>\n"
		 "  <supervision drive_timeout_ms=\"250\"%s/>\n"
		 "%s"
		 "  <backends>\n"
		 "%s%s"
		 "  </backends>\n"
		 "</vehicle>\n",
		 RIG->supervision, RIG->geometry_xml ? RIG->geometry_xml : "", bus, BATTERY_XML);
	fw_write_file(FW_VPATH, text);
	fw_write_file(FW_IOPATH, "<io/>\n");
	const char *io = IO_FILE ? IO_FILE : FW_IOPATH;

	int slave;
	char port[256];
	MASTER = fw_open_port(&slave, port, sizeof(port));
	snprintf(exe, sizeof(exe), "%s/vehicle-fw", FW_BUILD_DIR);
	char *fa[] = {exe,	"--config", FW_VPATH,	     "--io",	   (char *)io,
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
	RIG = &GENERIC;
	IO_FILE = NULL;
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

/* The generic profile at the simulator's map (0x100..), no communication
 * timeout written (raw reads pause the bus thread). */
static void bus_cfg(bk_modbus_bus_t *cfg, uint32_t timeout_ms)
{
	memset(cfg, 0, sizeof(*cfg));
	cfg->used = true;
	cfg->baud = 115200;
	cfg->parity = 'N';
	cfg->stop_bits = 1;
	cfg->timeout_ms = timeout_ms;
	cfg->retries = 1;
	cfg->prof = *mbp_builtin("generic");
	cfg->comm_stop_none = true;
	assert_true(strlen(BUS_B) < sizeof(cfg->device));
	memcpy(cfg->device, BUS_B, strlen(BUS_B) + 1);
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
	bk_modbus_bus_t cfg;
	bus_cfg(&cfg, 50);
	static mb_bus_t b;
	if (mb_bus_open(&b, &cfg, err, sizeof(err)) != 0)
		fail_msg("%s", err);
	assert_int_equal(mb_bus_add(&b, 1, 0, true), 0);
	assert_int_equal(mb_bus_add(&b, 2, 0, false), 1);
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

/* The counters of the in-process bus, as `$rt` shows them. */
static void counters(mb_bus_t *b, char *buf, size_t cap)
{
	mb_bus_counters(b, 0, buf, cap);
}

/* One number after a label in a line of counters: "unit1 timeouts 3" ->
 * label "unit1 timeouts " gives 3. */
static long counter(const char *line, const char *label)
{
	const char *p = strstr(line, label);
	if (!p) {
		print_message("no '%s' in '%s'\n", label, line);
		fail();
	}
	return strtol(p + strlen(label), NULL, 10);
}

/* Unit 1 stops mid-reply (the first 3 bytes of each reply, then nothing):
 * the byte timeout cuts each attempt short, so unit 2's samples keep
 * coming. Bound on the time between two of them: the faulty drive's
 * failing cycle, both attempts waiting at most the response timeout for a
 * first byte and the byte timeout after the last, 2 x (15 + 5) ms, plus
 * unit 2's own cycle (two requests, 3.6 ms on the wire at 115200, and the
 * 1 ms pause) and 5 ms for the processes sharing the CPU: 50 ms. With
 * libmodbus's default 500 ms byte timeout it was above 1000 ms. */
static void test_backend_reply_cut_short(void **state)
{
	(void)state;
	char err[256] = "", c[1024];
	hal_drive_state_t st;
	bk_modbus_bus_t cfg;
	bus_cfg(&cfg, 15);
	static mb_bus_t b;
	if (mb_bus_open(&b, &cfg, err, sizeof(err)) != 0)
		fail_msg("%s", err);
	assert_int_equal(b.byte_timeout_us, 5000); /* 4 characters are 0.35 ms: the floor */
	mb_bus_add(&b, 1, 0, false);
	mb_bus_add(&b, 2, 0, false);
	assert_int_equal(mb_bus_start(&b, err, sizeof(err)), 0);
	wait_drive(&b, 0, is_ready, 1000, &st);
	wait_drive(&b, 1, is_ready, 1000, &st);

	sim_ctl("unit 1 truncate");
	fw_sleep_ms(100); /* unit 1's first failing cycle is over: it is probed */
	counters(&b, c, sizeof(c));
	long t_before = counter(c, "unit1 timeouts ");
	long t0 = now_ms(), last = t0, gap = 0, n1 = 0, n0 = 0;
	mb_drive_read(&b, 0, &st);
	while (now_ms() - t0 < 1500) {
		mb_drive_read(&b, 1, &st);
		if (st.fresh) {
			long t = now_ms();
			gap = t - last > gap ? t - last : gap;
			last = t;
			n1++;
		}
		mb_drive_read(&b, 0, &st);
		n0 += st.fresh;
		fw_sleep_ms(1);
	}
	print_message("unit 2: %ld samples in 1500 ms, the longest gap %ld ms\n", n1, gap);
	assert_true(gap <= 50);
	assert_int_equal(n0, 0);
	assert_false(st.fresh);
	assert_int_equal(st.silent_why, HAL_SILENT_NO_REPLY);
	/* One attempt per 200 ms probe: 7 or 8 in 1.5 s. */
	counters(&b, c, sizeof(c));
	long probes = counter(c, "unit1 timeouts ") - t_before;
	if (probes < 7 || probes > 8)
		print_message("%s\n", c);
	assert_true(probes >= 7 && probes <= 8);
	assert_non_null(strstr(
	    c, " unit2 timeouts 0 crc_errors 0 bad_replies 0 exceptions 0 busy 0 illegal 0"));
	assert_int_equal(counter(c, "unit1 timeouts "), counter(c, " timeouts "));

	/* It answers again: sampled within one probe period. */
	sim_ctl("unit 1 answer");
	wait_drive(&b, 0, is_ready, 500, &st);
	mb_bus_close(&b);
}

/* Unit 1 stops mid-reply while the unit moves: the fault names drive 0,
 * the faulty one, and only it (drive 1 keeps answering). */
static void test_reply_cut_short_names_the_drive(void **state)
{
	(void)state;
	char reply[1024];
	expect("setPower true", "ok true");
	expect("setServo true", "ok true");
	expect("moveForward 2000", "ok true");
	wait_state("ok true 17 \"Busy\"", 1000);
	sim_ctl("unit 1 truncate");
	wait_state("ok true 19 \"Alarm-202\"", 1000);
	expect("getActiveAlarm 3", "ok true 1 1 202 fault \"drive 0 not answering\"");
	console("$rt", reply, sizeof(reply));
	assert_true(counter(reply, " unit1 timeouts ") >= 2);
	assert_non_null(strstr(
	    reply, " unit2 timeouts 0 crc_errors 0 bad_replies 0 exceptions 0 busy 0 illegal 0"));
}

/* A drive that answers "busy": a short spell is retried and costs
 * nothing; a drive that stays busy for the drive timeout is 202 saying
 * so. Every exception counted, per bus and per drive. */
static void test_drive_busy(void **state)
{
	(void)state;
	char reply[1024];
	expect("setPower true", "ok true");
	expect("setServo true", "ok true");
	wait_state("ok true 16 \"Ready\"", 1000);
	sim_ctl("unit 2 busy");
	fw_sleep_ms(60);
	sim_ctl("unit 2 answer");
	fw_sleep_ms(400);
	expect("getState", "ok true 16 \"Ready\"");
	/* several busy replies, each counted, none a timeout */
	console("$rt", reply, sizeof(reply));
	long busy = counter(reply, " unit2 timeouts 0 crc_errors 0 bad_replies 0 exceptions ");
	char want[200];
	snprintf(want, sizeof(want),
		 " unit2 timeouts 0 crc_errors 0 bad_replies 0 exceptions %ld busy %ld illegal 0",
		 busy, busy);
	assert_true(busy >= 2);
	assert_non_null(strstr(reply, want));

	long t0 = now_ms();
	sim_ctl("unit 2 busy");
	wait_state("ok true 19 \"Alarm-202\"", 1500);
	long dt = now_ms() - t0;
	if (dt < 230)
		print_message("202 after %ld ms of busy\n", dt);
	assert_true(dt >= 230); /* the 250 ms drive timeout, less the last sample's age */
	expect("getActiveAlarm 3", "ok true 1 1 202 fault \"drive 1 not answering: busy\"");
	console("$rt", reply, sizeof(reply));
	long ex = counter(reply, " unit2 timeouts 0 crc_errors 0 bad_replies 0 exceptions ");
	snprintf(want, sizeof(want),
		 " unit2 timeouts 0 crc_errors 0 bad_replies 0 exceptions %ld busy %ld illegal 0",
		 ex, ex);
	assert_non_null(strstr(reply, want));
	assert_true(ex > busy);
	assert_non_null(strstr(
	    reply, " unit1 timeouts 0 crc_errors 0 bad_replies 0 exceptions 0 busy 0 illegal 0"));
	/* the bus's own group counts the same exceptions */
	snprintf(want, sizeof(want),
		 "timeouts 0 crc_errors 0 bad_replies 0 exceptions %ld busy %ld illegal 0 unit1",
		 ex, ex);
	assert_non_null(strstr(reply, want));
}

/* A drive that answers "illegal data address" to the registers vehicle-fw
 * uses: the register map is wrong, fault 213 (not "not answering"), and
 * the log names the function and the register. */
static void test_drive_rejects_map(void **state)
{
	(void)state;
	char reply[1024], want[1000];
	expect("setPower true", "ok true");
	expect("setServo true", "ok true");
	wait_state("ok true 16 \"Ready\"", 1000);
	sim_ctl("unit 1 illegal");
	wait_state("ok true 19 \"Alarm-213\"", 1000);
	expect("getActiveAlarm 3", "ok true 1 1 213 fault \"drive 0 rejects its register map\"");
	snprintf(
	    want, sizeof(want),
	    "vehicle-fw: error: modbus bus %s: unit 1: function 16 (write registers) at 0x0100 "
	    "(2 registers): Illegal data address: the drive profile 'generic' does not match "
	    "the drive\n",
	    BUS_B);
	wait_log(want, 1000);
	console("$rt", reply, sizeof(reply));
	long ex = counter(reply, " unit1 timeouts 0 crc_errors 0 bad_replies 0 exceptions ");
	char grp[200];
	snprintf(grp, sizeof(grp),
		 " unit1 timeouts 0 crc_errors 0 bad_replies 0 exceptions %ld busy 0 illegal %ld",
		 ex, ex);
	assert_non_null(strstr(reply, grp));
	/* logged once while it lasts */
	char log[16384];
	fw_read_log(log, sizeof(log));
	const char *first = strstr(log, want);
	assert_non_null(first);
	assert_null(strstr(first + 1, want));
	/* The right map again: clearAlarm, servo on, ready. */
	sim_ctl("unit 1 answer");
	fw_sleep_ms(100);
	expect("clearAlarm", "ok true");
	expect("setServo true", "ok true");
	wait_state("ok true 16 \"Ready\"", 1000);
}

/* Raw registers of the simulator with the bus free (vehicle-fw gone). */
static modbus_t *raw_open(void)
{
	modbus_t *m = modbus_new_rtu(BUS_B, 115200, 'N', 8, 1);
	assert_non_null(m);
	assert_int_equal(modbus_connect(m), 0);
	modbus_set_response_timeout(m, 1, 0);
	modbus_flush(m); /* a killed master's last reply may wait in the port */
	return m;
}

static uint16_t raw_reg(modbus_t *m, int unit, int addr, bool input)
{
	uint16_t v = 0;
	modbus_set_slave(m, unit);
	int r = input ? modbus_read_input_registers(m, addr, 1, &v)
		      : modbus_read_registers(m, addr, 1, &v);
	if (r != 1)
		print_message("unit %d register 0x%04X: %s\n", unit, (unsigned)addr,
			      modbus_strerror(errno));
	assert_int_equal(r, 1);
	return v;
}

/* A 32-bit count from its high and low word registers. */
static int32_t raw_reg32(modbus_t *m, int unit, int hi, int lo, bool input)
{
	return (int32_t)((uint32_t)raw_reg(m, unit, hi, input) << 16 | raw_reg(m, unit, lo, input));
}

/* vehicle-fw killed mid-move (SIGKILL: nothing written at exit): each drive
 * stops by itself when no request came for its communication timeout,
 * which vehicle-fw wrote at start. */
static void test_killed_master_stops_drives(void **state)
{
	(void)state;
	expect("setPower true", "ok true");
	expect("setServo true", "ok true");
	expect("moveForward 2000", "ok true");
	wait_state("ok true 17 \"Busy\"", 1000);
	fw_sleep_ms(300);
	assert_int_equal(kill(FW, SIGKILL), 0);
	assert_int_equal(waitpid(FW, NULL, 0), FW);
	FW = -1;
	fw_sleep_ms(COMM_MS + 150);
	modbus_t *m = raw_open();
	/* the timeout vehicle-fw wrote, the speeds zeroed, the stages off */
	for (int unit = 1; unit <= 2; unit++) {
		assert_int_equal(raw_reg(m, unit, 0x109, false), COMM_MS);
		assert_int_equal(raw_reg(m, unit, 0x100, false), 0);
		assert_int_equal(raw_reg(m, unit, 0x101, false), 0);
		assert_int_equal(raw_reg(m, unit, 0x104, false), 0);
	}
	uint16_t p1 = raw_reg(m, 1, 0x103, false), p2 = raw_reg(m, 2, 0x103, false);
	assert_true(p1 > 1000); /* it had moved */
	fw_sleep_ms(300);
	assert_int_equal(raw_reg(m, 1, 0x103, false), p1);
	assert_int_equal(raw_reg(m, 2, 0x103, false), p2);
	modbus_close(m);
	modbus_free(m);
	char log[4096] = "";
	FILE *f = fopen(SIM_LOGPATH, "r");
	assert_non_null(f);
	size_t n = fread(log, 1, sizeof(log) - 1, f);
	log[n] = '\0';
	fclose(f);
	assert_non_null(
	    strstr(log, "mbdrive-sim: unit 1: no request for " COMM_MS_S " ms: motors stopped\n"));
	assert_non_null(
	    strstr(log, "mbdrive-sim: unit 2: no request for " COMM_MS_S " ms: motors stopped\n"));
}

/* The line's other end closes (a pty's master, as a bench's relay ends):
 * the simulator says so and ends, where it used to spin on the hung-up
 * line for ever. */
static void test_sim_ends_when_the_line_hangs_up(void **state)
{
	(void)state;
	int m = -1, s = -1;
	char name[128];
	assert_int_equal(openpty(&m, &s, name, NULL, NULL), 0);
	/* the simulator must not hold the master too */
	assert_int_equal(fcntl(m, F_SETFD, FD_CLOEXEC), 0);
	assert_int_equal(fcntl(s, F_SETFD, FD_CLOEXEC), 0);
	char exe[700];
	snprintf(exe, sizeof(exe), "%s/mbdrive-sim", FW_BUILD_DIR);
	char *sm[] = {exe, "--port", name, "--units", "1,2", NULL};
	unlink(SIM_LOGPATH);
	pid_t p = spawn(SIM_LOGPATH, sm, NULL);
	fw_sleep_ms(200); /* the simulator opens its port */
	close(m);
	close(s);
	int status = -1;
	pid_t w = 0;
	for (int i = 0; i < 500 && (w = waitpid(p, &status, WNOHANG)) == 0; i++)
		fw_sleep_ms(10);
	if (w != p)
		kill(p, SIGKILL);
	assert_int_equal(w, p);
	assert_true(WIFEXITED(status));
	assert_int_equal(WEXITSTATUS(status), 0);
	char log[4096];
	FILE *f = fopen(SIM_LOGPATH, "r");
	assert_non_null(f);
	log[fread(log, 1, sizeof(log) - 1, f)] = '\0';
	fclose(f);
	assert_string_equal(log, "mbdrive-sim: the line hung up\n");
}

/* SIGTERM after a 300 mm move; the registers vehicle-fw left. */
static void move_then_exit(void)
{
	test_move_over_modbus(NULL);
	int status = 0;
	assert_int_equal(kill(FW, SIGTERM), 0);
	assert_int_equal(waitpid(FW, &status, 0), FW);
	FW = -1;
	assert_true(WIFEXITED(status) && WEXITSTATUS(status) == 0);
}

/* 300 mm on a 150 mm wheel: 10430 counts of 16384 a turn, 2608 of 4096;
 * the odometry lands within 0.5 mm (17 and 4.3 counts). */
static void assert_travel(int32_t counts)
{
	int32_t want = RIG->counts_300mm, tol = want / 600 + 1;
	if (counts < want - tol || counts > want + tol)
		print_message("travel %d counts, expected %d +- %d\n", counts, want, tol);
	assert_true(counts >= want - tol && counts <= want + tol);
}

/* The ZLAC8015D's registers after a move on its two channels, read raw:
 * velocity mode, the communication timeout in ms, the control word at
 * "stop" (written at exit), the speeds zero, each channel's position high
 * word first, the mirrored right motor's negative. */
static void test_zlac8015d_registers(void **state)
{
	(void)state;
	move_then_exit();
	modbus_t *m = raw_open();
	assert_int_equal(raw_reg(m, 1, 0x200D, false), 3);
	assert_int_equal(raw_reg(m, 1, 0x2000, false), COMM_MS);
	assert_int_equal(raw_reg(m, 1, 0x200E, false), 7);
	assert_int_equal(raw_reg(m, 1, 0x2088, false), 0);
	assert_int_equal(raw_reg(m, 1, 0x2089, false), 0);
	assert_travel(raw_reg32(m, 1, 0x20A7, 0x20A8, false));
	assert_travel(-raw_reg32(m, 1, 0x20A9, 0x20AA, false));
	modbus_close(m);
	modbus_free(m);
}

/* The profile the configuration defines, read raw the same way: the enable
 * register at its own "off" value, the timeout in 10 ms units, the
 * position low word first in input registers. */
static void test_defined_profile_registers(void **state)
{
	(void)state;
	move_then_exit();
	modbus_t *m = raw_open();
	for (int unit = 1; unit <= 2; unit++) {
		assert_int_equal(raw_reg(m, unit, 0x52, false), COMM_MS / 10);
		assert_int_equal(raw_reg(m, unit, 0x50, false), 0xAA);
		assert_int_equal(raw_reg(m, unit, 0x40, false), 0);
		assert_int_equal(raw_reg(m, unit, 0x20, false), 0); /* stage off */
	}
	assert_travel(raw_reg32(m, 1, 0x31, 0x30, true));
	assert_travel(-raw_reg32(m, 2, 0x31, 0x30, true));
	modbus_close(m);
	modbus_free(m);
}

static int setup_zlac(void **state)
{
	RIG = &ZLAC;
	return setup(state);
}

static int setup_defined(void **state)
{
	RIG = &DEFINED;
	return setup(state);
}

/* The simulator on the ZLAC8015D's profile as pymodbus sees it. */
static void test_pymodbus_crosscheck_zlac(void **state)
{
	(void)state;
	char cmd[1500], out[1024];
	snprintf(cmd, sizeof(cmd),
		 "/usr/bin/python3 host_sim/devices/mb_crosscheck.py --profile zlac8015d %s %d "
		 "2>&1",
		 BUS_B, (int)SIM);
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

static int setup_bus_zlac(void **state)
{
	RIG = &ZLAC;
	return setup_bus(state);
}

/* A Modbus-only installation: the shipped config/io-modbus.xml maps no
 * GPIO line, so vehicle-fw runs with no gpiochip open (whether the
 * computer has one or not: this guest has a test chip, the host may have
 * none); the relay is the software one. */
static void test_io_without_gpio(void **state)
{
	(void)state;
	expect("getState", "ok true 25 \"Unpowered\"");
	expect("setPower true", "ok true");
	expect("setServo true", "ok true");
	wait_state("ok true 16 \"Ready\"", 1000);
	char dir[64], path[400], link[256];
	snprintf(dir, sizeof(dir), "/proc/%d/fd", (int)FW);
	DIR *d = opendir(dir);
	assert_non_null(d);
	unsigned fds = 0;
	for (struct dirent *e; (e = readdir(d)) != NULL;) {
		if (e->d_name[0] == '.')
			continue;
		snprintf(path, sizeof(path), "%s/%s", dir, e->d_name);
		ssize_t n = readlink(path, link, sizeof(link) - 1);
		assert_true(n > 0);
		link[n] = '\0';
		if (strncmp(link, "/dev/gpiochip", 13) == 0)
			print_message("vehicle-fw has %s open\n", link);
		assert_int_not_equal(strncmp(link, "/dev/gpiochip", 13), 0);
		fds++;
	}
	closedir(d);
	assert_true(fds >= 4); /* its stdio, the link's pty, the bus */
}

static int setup_io_modbus(void **state)
{
	IO_FILE = "config/io-modbus.xml";
	return setup(state);
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
	    cmocka_unit_test_setup_teardown(test_backend_reply_cut_short, setup_bus, teardown),
	    cmocka_unit_test_setup_teardown(test_reply_cut_short_names_the_drive, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_drive_busy, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_drive_rejects_map, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_killed_master_stops_drives, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_pymodbus_crosscheck_zlac, setup_bus_zlac,
					    teardown),
	    cmocka_unit_test_setup_teardown(test_zlac8015d_registers, setup_zlac, teardown),
	    cmocka_unit_test_setup_teardown(test_drive_error, setup_defined, teardown),
	    cmocka_unit_test_setup_teardown(test_defined_profile_registers, setup_defined,
					    teardown),
	    cmocka_unit_test_setup_teardown(test_io_without_gpio, setup_io_modbus, teardown),
	    cmocka_unit_test(test_sim_ends_when_the_line_hangs_up),
	};
	if (fw_rig_init(argc > 0 ? argv[0] : NULL, "vsmb") < 0)
		return 1;
	snprintf(BUS_A, sizeof(BUS_A), "%s/bus-a", FW_DIR);
	snprintf(BUS_B, sizeof(BUS_B), "%s/bus-b", FW_DIR);
	snprintf(SIM_LOGPATH, sizeof(SIM_LOGPATH), "%s/sim.log", FW_DIR);
	signal(SIGPIPE, SIG_IGN);
	/* MB_TEST=name runs that test alone (a bring-up aid) */
	struct CMUnitTest one[1];
	const char *only = getenv("MB_TEST");
	int rc;
	size_t k = 0;
	while (only && k < sizeof(tests) / sizeof(tests[0]) && strcmp(tests[k].name, only) != 0)
		k++;
	if (only && k < sizeof(tests) / sizeof(tests[0])) {
		one[0] = tests[k];
		rc = _cmocka_run_group_tests("one", one, 1, NULL, NULL);
	} else {
		rc = cmocka_run_group_tests(tests, NULL, NULL);
	}
	unlink(SIM_LOGPATH);
	fw_rig_cleanup();
	return rc;
}
