/* Shared set-up of the tests that run vehicle-fw as a process
 * (tests/test_linux_*.c): a private temporary folder with the vehicle file,
 * io.xml and the log, the binaries beside the test's build folder, a raw
 * pty for the console, and the console's one-line request/reply. */
#ifndef TESTS_FW_RIG_H
#define TESTS_FW_RIG_H

#include <stddef.h>

extern char FW_BUILD_DIR[512]; /* where vehicle-fw and the simulators are */
extern char FW_VPATH[600], FW_IOPATH[600], FW_LOGPATH[600];
extern char FW_DIR[32]; /* the temporary folder */

/* From argv[0] (build/tests/test_x -> build); mkdtemp of /tmp/<tag>XXXXXX.
 * -1 when the folder cannot be made. */
int fw_rig_init(const char *argv0, const char *tag);
/* Removes the three files and the folder (files the test added itself are
 * its own to remove first). */
void fw_rig_cleanup(void);

void fw_write_file(const char *path, const char *text);
void fw_read_log(char *buf, size_t cap);
void fw_sleep_ms(long ms);
/* A raw pty: returns the master, *slave and the slave's name in port. */
int fw_open_port(int *slave, char *port, size_t cap);
/* Sends line on the console and reads one reply line (timeout_ms for each
 * byte). */
void fw_console(int master, const char *line, char *reply, size_t cap, int timeout_ms);

#endif
