/* vehicle-fw's Modbus RTU backend against mbdrive-sim (libmodbus server,
 * two units on one bus) over a socat pty pair; the command link on a
 * second pty. Moves, a drive reporting an error, fault reset, a drive that
 * stops answering mid-move, SIGTERM. */
#include <errno.h>
#include <fcntl.h>
#include <libgen.h>
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
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include <cmocka.h>

static char BUILD_DIR[512] = "build";
static char DIR_[] = "/tmp/vsmbXXXXXX";
static char VPATH[600], IOPATH[600], LOGPATH[600], BUS_A[600], BUS_B[600];
static pid_t SOCAT = -1, SIM = -1, FW = -1;
static int MASTER = -1;

static void write_file(const char *path, const char *text)
{
	FILE *f = fopen(path, "w");
	assert_non_null(f);
	assert_true(fputs(text, f) >= 0);
	assert_int_equal(fclose(f), 0);
}

static void sleep_ms(long ms)
{
	struct timespec ts = {ms / 1000, (ms % 1000) * 1000000L};
	while (nanosleep(&ts, &ts) != 0 && errno == EINTR)
		;
}

static pid_t spawn(const char *log, char *const argv[])
{
	pid_t p = fork();
	assert_true(p >= 0);
	if (p == 0) {
		int fd = open(log ? log : "/dev/null", O_WRONLY | O_CREAT | O_TRUNC, 0644);
		dup2(fd, 2);
		int nul = open("/dev/null", O_WRONLY);
		dup2(nul, 1);
		execvp(argv[0], argv);
		_exit(127);
	}
	return p;
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
static void console(const char *line, char *reply, size_t cap)
{
	size_t n = 0;
	assert_int_equal(write(MASTER, line, strlen(line)), (ssize_t)strlen(line));
	assert_int_equal(write(MASTER, "\n", 1), 1);
	while (n + 1 < cap) {
		struct pollfd p = {.fd = MASTER, .events = POLLIN};
		assert_int_equal(poll(&p, 1, 3000), 1);
		assert_int_equal(read(MASTER, reply + n, 1), 1);
		if (reply[n] == '\n')
			break;
		n++;
	}
	reply[n] = '\0';
}

static void expect(const char *line, const char *want)
{
	char reply[512];
	console(line, reply, sizeof(reply));
	if (strcmp(reply, want) != 0)
		print_message("'%s': got '%s', expected '%s'\n", line, reply, want);
	assert_string_equal(reply, want);
}

/* Polls getState until it reads want (bounded). */
static void wait_state(const char *want, long ms)
{
	char reply[512];
	for (long t = 0; t < ms; t += 20) {
		console("getState", reply, sizeof(reply));
		if (!strcmp(reply, want))
			return;
		sleep_ms(20);
	}
	print_message("getState: '%s', expected '%s'\n", reply, want);
	fail();
}

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
	SOCAT = spawn(NULL, sa);
	for (int i = 0; i < 100 && (stat(BUS_A, &sb) || stat(BUS_B, &sb)); i++)
		sleep_ms(20);
	assert_int_equal(stat(BUS_B, &sb), 0);

	snprintf(exe, sizeof(exe), "%s/mbdrive-sim", BUILD_DIR);
	char *sm[] = {exe, "--port", BUS_A, "--units", "1,2", NULL};
	SIM = spawn(NULL, sm);
	sleep_ms(200); /* the simulator opens its port */
	return 0;
}

static int setup(void **state)
{
	char text[2048], exe[700];
	setup_bus(state);

	/* timeout x (retries + 1) = 30 ms, inside the 50 ms drive timeout. */
	snprintf(text, sizeof(text),
		 "<vehicle kinematics=\"differential\" tick_hz=\"100\">\n"
		 "  <devices contact_sensor=\"false\" obstacle_input=\"false\" estop=\"false\"\n"
		 "           joystick=\"false\"/>\n"
		 "  <backends>\n"
		 "    <modbus bus=\"0\" device=\"%s\" baud=\"115200\" timeout_ms=\"15\" retries=\"1\"\n"
		 "            reg_target_speed=\"256\" reg_position=\"258\" reg_status=\"260\"\n"
		 "            reg_alarm=\"261\" reg_servo_on=\"262\" reg_fault_reset=\"263\"/>\n"
		 "    <drive axis=\"0\" type=\"modbus\" bus=\"0\" unit=\"1\"/>\n"
		 "    <drive axis=\"1\" type=\"modbus\" bus=\"0\" unit=\"2\"/>\n"
		 "  </backends>\n"
		 "</vehicle>\n",
		 BUS_B);
	write_file(VPATH, text);
	write_file(IOPATH, "<io/>\n");

	int slave;
	assert_int_equal(openpty(&MASTER, &slave, NULL, NULL, NULL), 0);
	char port[256];
	snprintf(port, sizeof(port), "%s", ttyname(slave));
	struct termios t;
	tcgetattr(MASTER, &t);
	cfmakeraw(&t);
	tcsetattr(MASTER, TCSANOW, &t);
	snprintf(exe, sizeof(exe), "%s/vehicle-fw", BUILD_DIR);
	char *fa[] = {exe,	"--config", VPATH,	   "--io", IOPATH, "--port",
		      port, "--rt-priority", (char *)"0", NULL};
	FW = spawn(LOGPATH, fa);
	close(slave);
	sleep_ms(300);
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
	return 0;
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
	sleep_ms(200);
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
	FILE *f = fopen(LOGPATH, "r");
	assert_non_null(f);
	size_t n = fread(log, 1, sizeof(log) - 1, f);
	log[n] = '\0';
	fclose(f);
	assert_non_null(
	    strstr(log, "vehicle-fw: final state: unpowered, relay open, servo off, stopped\n"));
}

/* The simulator's register map as an independent client (pymodbus) sees
 * it: the same encoding the backend uses. */
static void test_pymodbus_crosscheck(void **state)
{
	(void)state;
	char cmd[1500], out[1024];
	snprintf(cmd, sizeof(cmd), "/usr/bin/python3 hal/linux/sim/mb_crosscheck.py %s %d 2>&1", BUS_B,
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

int main(int argc, char **argv)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test_setup_teardown(test_pymodbus_crosscheck, setup_bus, teardown),
	    cmocka_unit_test_setup_teardown(test_move_over_modbus, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_drive_error, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_drive_silent_then_sigterm, setup, teardown),
	};
	if (argc > 0) {
		char tmp[512];
		snprintf(tmp, sizeof(tmp), "%s", argv[0]);
		snprintf(BUILD_DIR, sizeof(BUILD_DIR), "%s", dirname(dirname(tmp)));
	}
	if (!mkdtemp(DIR_))
		return 1;
	snprintf(VPATH, sizeof(VPATH), "%s/vehicle.xml", DIR_);
	snprintf(IOPATH, sizeof(IOPATH), "%s/io.xml", DIR_);
	snprintf(LOGPATH, sizeof(LOGPATH), "%s/fw.log", DIR_);
	snprintf(BUS_A, sizeof(BUS_A), "%s/bus-a", DIR_);
	snprintf(BUS_B, sizeof(BUS_B), "%s/bus-b", DIR_);
	signal(SIGPIPE, SIG_IGN);
	int rc = cmocka_run_group_tests(tests, NULL, NULL);
	unlink(VPATH);
	unlink(IOPATH);
	unlink(LOGPATH);
	rmdir(DIR_);
	return rc;
}
