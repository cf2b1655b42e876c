/* ujoy: a virtual joystick through /dev/uinput, for vehicle-fw's joystick
 * tests in the QEMU guest. Axes ABS_X, ABS_Y, ABS_RX with range 0..1023
 * (centre 511.5: not symmetric around 0, so a backend must scale by the
 * device's range). Prints "ujoy: /dev/input/eventN" once the node exists,
 * then reads commands on stdin, one per line, answering "ok" to each:
 *   x V | y V | r V     set that axis (and SYN_REPORT)
 *   quit                destroy the device (the joystick is unplugged)
 */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <linux/input.h>
#include <limits.h>
#include <linux/uinput.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <unistd.h>

static int die(const char *what)
{
	printf("ujoy: FAIL: %s: %s\n", what, strerror(errno));
	return 1;
}

static void emit(int fd, unsigned short type, unsigned short code, int value)
{
	struct input_event ev;
	memset(&ev, 0, sizeof(ev));
	ev.type = type;
	ev.code = code;
	ev.value = value;
	if (write(fd, &ev, sizeof(ev)) != (ssize_t)sizeof(ev))
		printf("ujoy: write failed: %s\n", strerror(errno));
}

int main(void)
{
	static const unsigned short codes[3] = {ABS_X, ABS_Y, ABS_RX};
	setvbuf(stdout, NULL, _IOLBF, 0);
	int fd = open("/dev/uinput", O_WRONLY | O_NONBLOCK);
	if (fd < 0)
		return die("open /dev/uinput");
	if (ioctl(fd, UI_SET_EVBIT, EV_KEY) < 0 || ioctl(fd, UI_SET_KEYBIT, BTN_TRIGGER) < 0 ||
	    ioctl(fd, UI_SET_EVBIT, EV_ABS) < 0)
		return die("UI_SET_*BIT");
	for (int i = 0; i < 3; i++) {
		struct uinput_abs_setup a;
		memset(&a, 0, sizeof(a));
		a.code = codes[i];
		a.absinfo.minimum = 0;
		a.absinfo.maximum = 1023;
		a.absinfo.value = 512;
		if (ioctl(fd, UI_SET_ABSBIT, codes[i]) < 0 || ioctl(fd, UI_ABS_SETUP, &a) < 0)
			return die("UI_ABS_SETUP");
	}
	struct uinput_setup s;
	memset(&s, 0, sizeof(s));
	s.id.bustype = BUS_VIRTUAL;
	s.id.vendor = 0x1d6b;
	s.id.product = 0x0104;
	snprintf(s.name, sizeof(s.name), "vs-test-joystick");
	if (ioctl(fd, UI_DEV_SETUP, &s) < 0 || ioctl(fd, UI_DEV_CREATE) < 0)
		return die("UI_DEV_CREATE");
	char sys[64] = "", path[320];
	if (ioctl(fd, UI_GET_SYSNAME(sizeof(sys)), sys) < 0)
		return die("UI_GET_SYSNAME");
	snprintf(path, sizeof(path), "/sys/devices/virtual/input/%s", sys);
	DIR *d = opendir(path);
	struct dirent *de = NULL;
	while (d && (de = readdir(d)) != NULL && strncmp(de->d_name, "event", 5) != 0)
		;
	if (!de)
		return die("no eventN node");
	snprintf(path, sizeof(path), "/dev/input/%s", de->d_name);
	closedir(d);
	for (int i = 0; i < 100 && access(path, R_OK) != 0; i++)
		usleep(20000); /* devtmpfs creates the node asynchronously */
	printf("ujoy: %s\n", path);

	char line[64];
	while (fgets(line, sizeof(line), stdin)) {
		char axis = line[0], *end = NULL;
		long v = 0;
		if (!strncmp(line, "quit", 4))
			break;
		if (axis && strchr("xyr", axis))
			v = strtol(line + 1, &end, 10);
		if (end && end != line + 1 && v >= INT_MIN && v <= INT_MAX) {
			emit(fd, EV_ABS, codes[axis == 'x' ? 0 : axis == 'y' ? 1 : 2], (int)v);
			emit(fd, EV_SYN, SYN_REPORT, 0);
			printf("ok\n");
		} else {
			printf("ujoy: bad command\n");
		}
	}
	ioctl(fd, UI_DEV_DESTROY);
	close(fd);
	printf("ok\n");
	return 0;
}
