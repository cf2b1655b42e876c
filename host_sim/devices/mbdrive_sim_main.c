/* mbdrive-sim: Modbus RTU wheel drives for tests of vehicle-fw's modbus
 * backend, on libmodbus's server API. Several unit ids share one port.
 *
 *   mbdrive-sim --port DEV [--baud N] [--units 1,2] [--battery UNIT [--battery-mv MV]]
 *
 * Register map (holding, base 0x100; the one config/vehicle-linux-modbus.xml
 * and the tests use): 0x100-0x101 target speed (int32 counts/s, high word
 * first), 0x102-0x103 position (int32 counts), 0x104 status (bit 0 power
 * stage on), 0x105 alarm code, 0x106 servo on (write 1/0), 0x107 fault
 * reset (write 1). The stage is on while servo on is 1 and no alarm is set;
 * the position integrates the target speed while the stage is on.
 *
 * Battery (--battery UNIT: one of the drives' units, or a unit of its own
 * like a BMS): the pack voltage, MV (default 24000), as input register 0x200
 * (uint16, 10 mV per count), input registers 0x201-0x202 (uint32 mV, high
 * word first) and holding register 0x108 (uint16, 10 mV per count).
 *
 * Test controls: SIGUSR1 makes the last unit of --units stop answering;
 * SIGUSR2 sets alarm code 0x31 on the first unit. With --battery, lines on
 * stdin: "battery MV" sets the voltage, "battery silent" leaves reads of the
 * battery registers unanswered (a BMS of its own then answers nothing),
 * "battery answer" answers them again. Prints "ready" once serving.
 */
#include <errno.h>
#include <getopt.h>
#include <modbus/modbus.h>
#include <poll.h>
#include <signal.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#define BASE	    0x100
#define NREG	    16
#define MAX_UNITS   8
#define DRIVE_ALARM 0x31
#define BAT_INPUT   0x200 /* 0x200: 10 mV counts; 0x201-0x202: mV, uint32 */
#define BAT_NINPUT  3
#define BAT_HOLDING 0x108 /* 10 mV counts, beside the drive's registers */

enum { R_SPEED = 0, R_POS = 2, R_STATUS = 4, R_ALARM = 5, R_SERVO = 6, R_RESET = 7 };

typedef struct {
	modbus_mapping_t *map;
	int64_t pos_us; /* counts x 1e6 */
	int unit;
	bool silent;
	bool drive; /* false: only the battery (a BMS) */
} unit_t;

/* Appends a unit with the whole register map; NULL when out of room or
 * memory. */
static unit_t *add_unit(unit_t *u, int *nu, int id, bool drive)
{
	if (*nu >= MAX_UNITS)
		return NULL;
	unit_t *n = &u[*nu];
	n->map = modbus_mapping_new_start_address(0, 0, 0, 0, BASE, NREG, BAT_INPUT, BAT_NINPUT);
	if (!n->map)
		return NULL;
	n->pos_us = 0;
	n->unit = id;
	n->silent = false;
	n->drive = drive;
	(*nu)++;
	return n;
}

static volatile sig_atomic_t stop, go_silent, raise_alarm;

static void on_signal(int sig)
{
	if (sig == SIGUSR1)
		go_silent = 1;
	else if (sig == SIGUSR2)
		raise_alarm = 1;
	else
		stop = 1;
}

static uint64_t mono_us(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return (uint64_t)t.tv_sec * 1000000u + (uint64_t)t.tv_nsec / 1000u;
}

static uint16_t crc16(const uint8_t *p, int n)
{
	uint16_t c = 0xffff;
	for (int i = 0; i < n; i++) {
		c ^= p[i];
		for (int b = 0; b < 8; b++)
			c = (c & 1) ? (uint16_t)((c >> 1) ^ 0xa001) : (uint16_t)(c >> 1);
	}
	return c;
}

/* Length of a request for the function codes the drive serves; 0 otherwise. */
static int req_len(const uint8_t *q, int avail)
{
	switch (q[1]) {
	case 0x03:
	case 0x04:
	case 0x06:
		return 8;
	case 0x10:
		return avail >= 7 ? 9 + q[6] : 0;
	default:
		return 0;
	}
}

static void set_battery(unit_t *u, long mv)
{
	uint16_t *in = u->map->tab_input_registers;
	uint16_t counts = (uint16_t)(mv / 10 > 65535 ? 65535 : mv / 10);
	in[0] = counts;
	in[1] = (uint16_t)((uint32_t)mv >> 16);
	in[2] = (uint16_t)((uint32_t)mv & 0xffffu);
	u->map->tab_registers[BAT_HOLDING - BASE] = counts;
}

/* A request the silent battery leaves unanswered: any read of its
 * registers. */
static bool battery_read(const uint8_t *q)
{
	int addr = q[2] << 8 | q[3], n = q[4] << 8 | q[5];
	if (q[1] == 0x04)
		return true;
	return q[1] == 0x03 && addr <= BAT_HOLDING && addr + n > BAT_HOLDING;
}

static long parse_mv(const char *s)
{
	char *end;
	long mv = strtol(s, &end, 10);
	return end == s || *end != '\0' || mv < 0 || mv > 4000000000L ? -1 : mv;
}

/* One control line on stdin; false: not understood. */
static bool control(const char *line, unit_t *bat, bool *bat_silent)
{
	if (!strcmp(line, "battery silent"))
		*bat_silent = true;
	else if (!strcmp(line, "battery answer"))
		*bat_silent = false;
	else if (!strncmp(line, "battery ", 8) && parse_mv(line + 8) >= 0)
		set_battery(bat, parse_mv(line + 8));
	else
		return false;
	return true;
}

static void step(unit_t *u, uint64_t dt)
{
	uint16_t *r = u->map->tab_registers;
	if (r[R_RESET]) {
		r[R_ALARM] = 0;
		r[R_RESET] = 0;
	}
	bool on = r[R_SERVO] == 1 && r[R_ALARM] == 0;
	r[R_STATUS] = on ? 1 : 0;
	if (on) {
		int32_t sp = (int32_t)(((uint32_t)r[R_SPEED] << 16) | r[R_SPEED + 1]);
		u->pos_us += (int64_t)sp * (int64_t)dt;
	}
	int32_t pos = (int32_t)(u->pos_us / 1000000);
	r[R_POS] = (uint16_t)((uint32_t)pos >> 16);
	r[R_POS + 1] = (uint16_t)((uint32_t)pos & 0xffffu);
}

int main(int argc, char **argv)
{
	const char *port = NULL, *units = "1";
	long baud = 115200, bat_unit = 0, bat_mv = 24000;
	static const struct option opts[] = {
	    {"port", required_argument, NULL, 'p'},	  {"baud", required_argument, NULL, 'b'},
	    {"units", required_argument, NULL, 'u'},	  {"battery", required_argument, NULL, 'B'},
	    {"battery-mv", required_argument, NULL, 'm'}, {NULL, 0, NULL, 0}};
	int o;
	while ((o = getopt_long(argc, argv, "", opts, NULL)) != -1) {
		if (o == 'p')
			port = optarg;
		else if (o == 'b')
			baud = strtol(optarg, NULL, 10);
		else if (o == 'u')
			units = optarg;
		else if (o == 'B')
			bat_unit = strtol(optarg, NULL, 10);
		else if (o == 'm')
			bat_mv = parse_mv(optarg);
		else
			return 2;
	}
	if (!port || baud <= 0 || bat_unit < 0 || bat_unit > 247 || bat_mv < 0) {
		fprintf(stderr, "usage: mbdrive-sim --port DEV [--baud N] [--units 1,2] "
				"[--battery UNIT [--battery-mv MV]]\n");
		return 2;
	}
	unit_t u[MAX_UNITS];
	int nu = 0;
	for (const char *s = units; *s && nu < MAX_UNITS;) {
		char *end;
		long id = strtol(s, &end, 10);
		if (end == s || id < 1 || id > 247 || !add_unit(u, &nu, (int)id, true))
			return 2;
		s = *end == ',' ? end + 1 : end;
	}
	int ndrives = nu;
	if (ndrives == 0)
		return 2;
	unit_t *bat = NULL;
	for (int i = 0; i < nu; i++)
		if (u[i].unit == bat_unit)
			bat = &u[i];
	if (bat_unit && !bat && !(bat = add_unit(u, &nu, (int)bat_unit, false)))
		return 2;
	if (bat)
		set_battery(bat, bat_mv);
	bool bat_silent = false;
	/* Control lines only with a battery: stdin may be a terminal. */
	int ctl = bat ? STDIN_FILENO : -1;
	char cbuf[128];
	size_t clen = 0;
	modbus_t *m = modbus_new_rtu(port, (int)baud, 'N', 8, 1);
	if (!m || modbus_connect(m) != 0) {
		fprintf(stderr, "mbdrive-sim: %s: %s\n", port, modbus_strerror(errno));
		return 1;
	}
	if (getenv("MBDRIVE_DEBUG")) {
		setvbuf(stdout, NULL, _IONBF, 0);
		modbus_set_debug(m, 1);
	}

	struct sigaction sa;
	memset(&sa, 0, sizeof(sa));
	sa.sa_handler = on_signal;
	sigaction(SIGTERM, &sa, NULL);
	sigaction(SIGINT, &sa, NULL);
	sigaction(SIGUSR1, &sa, NULL);
	sigaction(SIGUSR2, &sa, NULL);
	printf("ready\n");
	fflush(stdout);

	/* libmodbus's receive serves one unit id per context and, for another
	 * unit's write request, leaves the rest of the frame on the line. So
	 * the frames are cut here (length from the function code, CRC, a gap
	 * of 5 ms resynchronises), and modbus_reply answers as the addressed
	 * unit. */
	uint8_t q[MODBUS_RTU_MAX_ADU_LENGTH];
	int have = 0;
	int fd = modbus_get_socket(m);
	uint64_t last = mono_us();
	while (!stop) {
		struct pollfd p[2] = {{.fd = fd, .events = POLLIN}, {.fd = ctl, .events = POLLIN}};
		int pr = poll(p, ctl >= 0 ? 2 : 1, 5);
		uint64_t now = mono_us();
		for (int i = 0; i < nu; i++)
			if (u[i].drive)
				step(&u[i], now - last);
		last = now;
		if (go_silent) {
			u[ndrives - 1].silent = true;
			go_silent = 0;
		}
		if (ctl >= 0 && pr > 0 && p[1].revents) {
			ssize_t r = read(ctl, cbuf + clen, sizeof(cbuf) - 1 - clen);
			if (r <= 0) {
				ctl = -1; /* end of the control input */
			} else {
				clen += (size_t)r;
				char *nl;
				while ((nl = memchr(cbuf, '\n', clen)) != NULL) {
					*nl = '\0';
					if (!control(cbuf, bat, &bat_silent))
						fprintf(stderr,
							"mbdrive-sim: unknown control '%s'\n",
							cbuf);
					clen -= (size_t)(nl + 1 - cbuf);
					memmove(cbuf, nl + 1, clen);
				}
				if (clen == sizeof(cbuf) - 1)
					clen = 0; /* an overlong line: dropped */
			}
		}
		if (raise_alarm) {
			u[0].map->tab_registers[R_ALARM] = DRIVE_ALARM;
			raise_alarm = 0;
		}
		if (pr <= 0 || !(p[0].revents & POLLIN)) {
			if (pr == 0)
				have = 0; /* silence: drop a partial frame */
			continue;
		}
		ssize_t r = read(fd, q + have, sizeof(q) - (size_t)have);
		if (r <= 0)
			continue;
		have += (int)r;
		for (;;) {
			int len = have >= 2 ? req_len(q, have) : 0;
			if (have >= 2 && len == 0) {
				have = 0; /* unknown function: resynchronise */
				break;
			}
			if (len == 0 || have < len)
				break;
			if (crc16(q, len - 2) == (uint16_t)(q[len - 2] | q[len - 1] << 8)) {
				for (int i = 0; i < nu; i++) {
					if (u[i].unit != q[0] || u[i].silent ||
					    (&u[i] == bat && bat_silent && battery_read(q)))
						continue;
					modbus_set_slave(m, u[i].unit);
					modbus_reply(m, q, len, u[i].map);
					if (u[i].drive)
						step(&u[i],
						     0); /* servo_on/reset take effect at once */
				}
			}
			memmove(q, q + len, (size_t)(have - len));
			have -= len;
		}
	}
	modbus_close(m);
	modbus_free(m);
	return 0;
}
