/*
 * Guest probe for the uinput -> evdev path a joystick backend reads: creates
 * a virtual gamepad through /dev/uinput, finds its /dev/input/eventN node,
 * checks name and axis range, injects an axis move and a button press and
 * reads exactly those events back. Exit 0 only when everything matches.
 * Built by tests/qemu/run_smoke.sh, run by tests/qemu/smoke_input.sh.
 */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <linux/input.h>
#include <linux/uinput.h>
#include <poll.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <unistd.h>

#define DEV_NAME "vs-test-gamepad"

static void fail(const char *fmt, ...) __attribute__((noreturn, format(printf, 1, 2)));
static void fail(const char *fmt, ...)
{
	va_list ap;

	va_start(ap, fmt);
	fputs("uinput_probe: FAIL: ", stdout);
	vprintf(fmt, ap);
	va_end(ap);
	if (errno)
		printf(" (%s)", strerror(errno));
	putchar('\n');
	exit(1);
}

static void xioctl(int fd, unsigned long req, long arg, const char *what)
{
	errno = 0;
	if (ioctl(fd, req, arg) < 0)
		fail("ioctl %s", what);
}

static void emit(int fd, unsigned short type, unsigned short code, int value)
{
	struct input_event ev;

	memset(&ev, 0, sizeof(ev));
	ev.type = type;
	ev.code = code;
	ev.value = value;
	errno = 0;
	if (write(fd, &ev, sizeof(ev)) != (ssize_t)sizeof(ev))
		fail("write event %u/%u", type, code);
}

/* The evdev node sits under the input device's sysfs folder as eventN. */
static int open_event_node(const char *sysname)
{
	char path[320];
	struct dirent *de;
	DIR *d;
	int fd = -1;

	snprintf(path, sizeof(path), "/sys/devices/virtual/input/%s", sysname);
	errno = 0;
	d = opendir(path);
	if (!d)
		fail("opendir %s", path);
	while ((de = readdir(d)) != NULL && strncmp(de->d_name, "event", 5) != 0)
		;
	errno = 0;
	if (!de)
		fail("%s has no evdev handler (evdev module not loaded?)", path);
	snprintf(path, sizeof(path), "/dev/input/%s", de->d_name);
	closedir(d);
	/* devtmpfs creates the node asynchronously to the ioctl returning. */
	for (int i = 0; i < 100 && fd < 0; i++) {
		fd = open(path, O_RDONLY | O_NONBLOCK);
		if (fd < 0)
			usleep(20000);
	}
	if (fd < 0)
		fail("open %s", path);
	printf("uinput_probe: %s is %s\n", sysname, path);
	return fd;
}

static void expect_event(int fd, unsigned short type, unsigned short code, int value)
{
	struct pollfd p = {.fd = fd, .events = POLLIN};
	struct input_event ev;

	errno = 0;
	if (poll(&p, 1, 2000) != 1)
		fail("no event within 2 s, expected %u/%u=%d", type, code, value);
	if (read(fd, &ev, sizeof(ev)) != (ssize_t)sizeof(ev))
		fail("short read from evdev");
	if (ev.type != type || ev.code != code || ev.value != value)
		fail("event %u/%u=%d, expected %u/%u=%d", ev.type, ev.code, ev.value, type, code,
		     value);
}

int main(void)
{
	struct uinput_setup setup;
	struct uinput_abs_setup abs;
	struct input_absinfo info;
	char sysname[64] = "";
	char name[64] = "";
	int ufd, efd;

	errno = 0;
	ufd = open("/dev/uinput", O_WRONLY | O_NONBLOCK);
	if (ufd < 0)
		fail("open /dev/uinput");
	xioctl(ufd, UI_SET_EVBIT, EV_KEY, "UI_SET_EVBIT EV_KEY");
	xioctl(ufd, UI_SET_KEYBIT, BTN_SOUTH, "UI_SET_KEYBIT BTN_SOUTH");
	xioctl(ufd, UI_SET_EVBIT, EV_ABS, "UI_SET_EVBIT EV_ABS");
	xioctl(ufd, UI_SET_ABSBIT, ABS_X, "UI_SET_ABSBIT ABS_X");

	memset(&abs, 0, sizeof(abs));
	abs.code = ABS_X;
	abs.absinfo.minimum = -32768;
	abs.absinfo.maximum = 32767;
	abs.absinfo.flat = 128;
	errno = 0;
	if (ioctl(ufd, UI_ABS_SETUP, &abs) < 0)
		fail("ioctl UI_ABS_SETUP");

	memset(&setup, 0, sizeof(setup));
	setup.id.bustype = BUS_VIRTUAL;
	setup.id.vendor = 0x1d50;
	setup.id.product = 0x5656;
	strcpy(setup.name, DEV_NAME);
	errno = 0;
	if (ioctl(ufd, UI_DEV_SETUP, &setup) < 0)
		fail("ioctl UI_DEV_SETUP");
	xioctl(ufd, UI_DEV_CREATE, 0, "UI_DEV_CREATE");
	errno = 0;
	if (ioctl(ufd, UI_GET_SYSNAME(sizeof(sysname)), sysname) < 0)
		fail("ioctl UI_GET_SYSNAME");

	efd = open_event_node(sysname);
	errno = 0;
	if (ioctl(efd, EVIOCGNAME(sizeof(name)), name) < 0)
		fail("ioctl EVIOCGNAME");
	if (strcmp(name, DEV_NAME) != 0)
		fail("device name '%s', expected '%s'", name, DEV_NAME);
	if (ioctl(efd, EVIOCGABS(ABS_X), &info) < 0)
		fail("ioctl EVIOCGABS");
	if (info.minimum != -32768 || info.maximum != 32767 || info.flat != 128)
		fail("ABS_X range [%d, %d] flat %d, expected [-32768, 32767] flat 128",
		     info.minimum, info.maximum, info.flat);

	emit(ufd, EV_ABS, ABS_X, -20000);
	emit(ufd, EV_KEY, BTN_SOUTH, 1);
	emit(ufd, EV_SYN, SYN_REPORT, 0);
	expect_event(efd, EV_ABS, ABS_X, -20000);
	expect_event(efd, EV_KEY, BTN_SOUTH, 1);
	expect_event(efd, EV_SYN, SYN_REPORT, 0);
	/* The current state is queryable too, as a backend polling it would. */
	if (ioctl(efd, EVIOCGABS(ABS_X), &info) < 0 || info.value != -20000)
		fail("ABS_X state %d, expected -20000", info.value);

	xioctl(ufd, UI_DEV_DESTROY, 0, "UI_DEV_DESTROY");
	close(efd);
	close(ufd);
	puts("uinput_probe: ok");
	return 0;
}
