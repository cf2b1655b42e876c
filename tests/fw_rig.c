/* Shared set-up of the vehicle-fw process tests (fw_rig.h). */
#include "fw_rig.h"

#include <errno.h>
#include <libgen.h>
#include <poll.h>
#include <pty.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include <cmocka.h>

char FW_BUILD_DIR[512] = "build";
char FW_VPATH[600], FW_IOPATH[600], FW_LOGPATH[600];
char FW_DIR[32];

int fw_rig_init(const char *argv0, const char *tag)
{
	if (argv0) {
		char tmp[512];
		snprintf(tmp, sizeof(tmp), "%s", argv0);
		snprintf(FW_BUILD_DIR, sizeof(FW_BUILD_DIR), "%s", dirname(dirname(tmp)));
	}
	snprintf(FW_DIR, sizeof(FW_DIR), "/tmp/%.8sXXXXXX", tag);
	if (!mkdtemp(FW_DIR))
		return -1;
	snprintf(FW_VPATH, sizeof(FW_VPATH), "%s/vehicle.xml", FW_DIR);
	snprintf(FW_IOPATH, sizeof(FW_IOPATH), "%s/io.xml", FW_DIR);
	snprintf(FW_LOGPATH, sizeof(FW_LOGPATH), "%s/fw.log", FW_DIR);
	return 0;
}

void fw_rig_cleanup(void)
{
	unlink(FW_VPATH);
	unlink(FW_IOPATH);
	unlink(FW_LOGPATH);
	rmdir(FW_DIR);
}

void fw_write_file(const char *path, const char *text)
{
	FILE *f = fopen(path, "w");
	assert_non_null(f);
	assert_true(fputs(text, f) >= 0);
	assert_int_equal(fclose(f), 0);
}

void fw_read_log(char *buf, size_t cap)
{
	FILE *f = fopen(FW_LOGPATH, "r");
	assert_non_null(f);
	size_t n = fread(buf, 1, cap - 1, f);
	buf[n] = '\0';
	fclose(f);
}

void fw_sleep_ms(long ms)
{
	struct timespec ts = {ms / 1000, (ms % 1000) * 1000000L};
	while (nanosleep(&ts, &ts) != 0 && errno == EINTR)
		;
}

int fw_open_port(int *slave, char *port, size_t cap)
{
	int master;
	assert_int_equal(openpty(&master, slave, NULL, NULL, NULL), 0);
	const char *name = ttyname(*slave);
	assert_non_null(name);
	snprintf(port, cap, "%s", name);
	struct termios t;
	assert_int_equal(tcgetattr(master, &t), 0);
	cfmakeraw(&t);
	assert_int_equal(tcsetattr(master, TCSANOW, &t), 0);
	return master;
}

void fw_console(int master, const char *line, char *reply, size_t cap, int timeout_ms)
{
	size_t n = 0;
	assert_int_equal(write(master, line, strlen(line)), (ssize_t)strlen(line));
	assert_int_equal(write(master, "\n", 1), 1);
	while (n + 1 < cap) {
		struct pollfd p = {.fd = master, .events = POLLIN};
		assert_int_equal(poll(&p, 1, timeout_ms), 1);
		assert_int_equal(read(master, reply + n, 1), 1);
		if (reply[n] == '\n')
			break;
		n++;
	}
	reply[n] = '\0';
}
