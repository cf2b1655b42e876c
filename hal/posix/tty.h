/* Serial port set-up shared by vehicle-fw, vehicle-sim and the client
 * library: raw 8N1, no flow control, non-blocking. */
#ifndef HAL_POSIX_TTY_H
#define HAL_POSIX_TTY_H

/* Opens dev raw 8N1 at baud (0: keep its speed), non-blocking; -1 with
 * errno (EINVAL: a speed termios has no code for). */
int tty_open(const char *dev, unsigned baud);
/* The same on an open descriptor; a pipe or socket is left alone. */
int tty_set_raw(int fd, unsigned baud);

#endif
