/* Serial port set-up (see tty.h). */
#include "tty.h"

#include <errno.h>
#include <fcntl.h>
#include <termios.h>
#include <unistd.h>

static speed_t baud_code(unsigned baud)
{
	switch (baud) {
	case 9600:
		return B9600;
	case 19200:
		return B19200;
	case 38400:
		return B38400;
	case 57600:
		return B57600;
	case 115200:
		return B115200;
	case 230400:
		return B230400;
	case 460800:
		return B460800;
	case 921600:
		return B921600;
	default:
		return 0;
	}
}

int tty_set_raw(int fd, unsigned baud)
{
	struct termios t;

	if (!isatty(fd))
		return 0; /* a pipe or socket: nothing to set */
	if (tcgetattr(fd, &t) != 0)
		return -1;
	cfmakeraw(&t);
	/* 8N1, no flow control, receiver on, modem lines ignored. */
	t.c_cflag &= ~(tcflag_t)(CSIZE | PARENB | CSTOPB | CRTSCTS);
	t.c_cflag |= CS8 | CREAD | CLOCAL;
	t.c_iflag &= ~(tcflag_t)(IXON | IXOFF | IXANY);
	t.c_cc[VMIN] = 0;
	t.c_cc[VTIME] = 0;
	if (baud) {
		speed_t sp = baud_code(baud);

		if (!sp) {
			errno = EINVAL;
			return -1;
		}
		cfsetispeed(&t, sp);
		cfsetospeed(&t, sp);
	}
	return tcsetattr(fd, TCSANOW, &t);
}

int tty_open(const char *dev, unsigned baud)
{
	int fd = open(dev, O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);

	if (fd < 0)
		return -1;
	if (tty_set_raw(fd, baud) != 0) {
		int e = errno;

		close(fd);
		errno = e;
		return -1;
	}
	return fd;
}
