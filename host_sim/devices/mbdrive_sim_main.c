/* mbdrive-sim: Modbus RTU wheel drives for tests of vehicle-fw's modbus
 * backend, on libmodbus's server API. Several unit ids share one port.
 *
 *   mbdrive-sim --port DEV [--baud N] [--units 1,2] [--profile NAME]
 *               [--set KEY=VALUE]... [--battery UNIT [--battery-mv MV]]
 *
 * The registers are a drive profile (hal/modbus/mbprofile.h, the same
 * definitions and encoding vehicle-fw uses): --profile names a built-in one
 * (default generic, whose example map config/vehicle-linux-modbus.xml and
 * the tests use: holding 0x100-0x101 target speed int32 counts/s high word
 * first, 0x102-0x103 position, 0x104 status bit 0, 0x105 alarm code, 0x106
 * servo on 1/0, 0x107 fault reset 1), --set changes one field in the
 * profile's text form (as the <modbus> attributes do). Each unit has the
 * profile's channels (motors). A motor's stage is on from an enable_on
 * write until an enable_off write (or its communication-loss stop) while
 * its alarm register is 0; its position integrates the target speed while
 * on. reset_value to the reset register clears the alarm. A shared status
 * register (step 0) says on when every channel is on.
 *
 * Communication-loss stop: once the master wrote the comm_timeout register
 * (in comm_unit_ms), a unit that gets no request for that long stops its
 * motors (stage off, target speed 0), as a drive set up so does; logged on
 * stderr.
 *
 * Battery (--battery UNIT: one of the drives' units, or a unit of its own
 * like a BMS): the pack voltage, MV (default 24000), as input register 0x200
 * (uint16, 10 mV per count), input registers 0x201-0x202 (uint32 mV, high
 * word first) and holding register 0x108 (uint16, 10 mV per count).
 *
 * Test controls: SIGUSR1 makes the last unit of --units stop answering;
 * SIGUSR2 sets alarm code 0x31 on the first unit's channel 0. Lines on stdin
 * (when it is not a terminal): "battery MV" sets the voltage, "battery
 * silent" leaves reads of the battery registers unanswered (a BMS of its own
 * then answers nothing), "battery answer" answers them again; "unit N
 * busy|illegal|truncate|silent|answer": unit N answers every request with
 * exception 6 (busy) or 2 (illegal data address), sends the first 3 bytes
 * of each reply and stops, answers nothing, or answers normally again;
 * "clock US": from now on the drives' time is the master's, US us (a board
 * in an emulator, whose time is not the host's), advanced only by these
 * lines (a clock that goes back, a restarted board, counts nothing) and
 * acknowledged with the same line on stdout.
 * Prints "ready" once serving.
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

#include "../../hal/modbus/mbprofile.h"

#define MAX_UNITS   8
#define DRIVE_ALARM 0x31
#define BAT_INPUT   0x200 /* 0x200: 10 mV counts; 0x201-0x202: mV, uint32 */
#define BAT_NINPUT  3
#define BAT_HOLDING 0x108 /* 10 mV counts, beside the generic map's registers */

enum { ANSWER, SILENT, BUSY, ILLEGAL, TRUNCATE };

typedef struct {
	modbus_mapping_t *map;
	uint64_t last_req_us;
	int64_t pos_us[MBP_CHANNELS_MAX]; /* counts x 1e6 */
	int unit;
	int mode;
	uint32_t comm_ms;
	bool drive; /* false: only the battery (a BMS) */
	bool comm_stopped;
	bool en[MBP_CHANNELS_MAX];
} unit_t;

static mb_profile_t prof;
static uint16_t hold_lo, hold_n, in_lo, in_n;

static void span(uint16_t *lo, uint32_t *hi, uint32_t a, uint32_t n)
{
	if (a < *lo)
		*lo = (uint16_t)a;
	if (a + n > *hi)
		*hi = a + n;
}

/* The register areas every unit has: the profile's, the battery's. */
static void areas(void)
{
	uint16_t hl = BAT_HOLDING, il = BAT_INPUT;
	uint32_t hh = BAT_HOLDING + 1, ih = BAT_INPUT + BAT_NINPUT;
	for (unsigned r = 0; r < MBP_REG_COUNT; r++) {
		const mbp_reg_t *g = &prof.reg[r];
		if (!g->words)
			continue;
		uint32_t last = mbp_addr(g, prof.channels - 1u);
		if (g->flags & MBP_INPUT) {
			span(&il, &ih, g->addr, 1);
			span(&il, &ih, last, g->words);
		} else {
			span(&hl, &hh, g->addr, 1);
			span(&hl, &hh, last, g->words);
		}
	}
	for (unsigned i = 0; i < prof.ninit; i++)
		span(&hl, &hh, prof.init[i].addr, 1);
	hold_lo = hl;
	hold_n = (uint16_t)(hh - hl);
	in_lo = il;
	in_n = (uint16_t)(ih - il);
}

/* A register of a unit: its words in the map. */
static uint16_t *reg(unit_t *u, unsigned r, unsigned ch)
{
	const mbp_reg_t *g = &prof.reg[r];
	uint16_t a = mbp_addr(g, ch);
	return (g->flags & MBP_INPUT) ? &u->map->tab_input_registers[a - in_lo]
				      : &u->map->tab_registers[a - hold_lo];
}

/* Appends a unit with the whole register map; NULL when out of room or
 * memory. */
static unit_t *add_unit(unit_t *u, int *nu, int id, bool drive)
{
	if (*nu >= MAX_UNITS)
		return NULL;
	unit_t *n = &u[*nu];
	memset(n, 0, sizeof(*n));
	n->map = modbus_mapping_new_start_address(0, 0, 0, 0, hold_lo, hold_n, in_lo, in_n);
	if (!n->map)
		return NULL;
	n->unit = id;
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

/* The master's clock ("clock US"): its last value and the drives' time. */
static bool clock_given;
static uint64_t clock_last_us, clock_us;

static uint64_t mono_us(void)
{
	if (clock_given)
		return clock_us;
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return (uint64_t)t.tv_sec * 1000000u + (uint64_t)t.tv_nsec / 1000u;
}

static bool set_clock(const char *arg)
{
	char *end;
	unsigned long long us = strtoull(arg, &end, 10);
	if (end == arg || *end)
		return false;
	if (!clock_given)
		clock_us = mono_us();
	clock_us += clock_given && us > clock_last_us ? us - clock_last_us : 0;
	clock_last_us = us;
	clock_given = true;
	printf("clock %llu\n", us);
	fflush(stdout);
	return true;
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
	uint16_t *in = &u->map->tab_input_registers[BAT_INPUT - in_lo];
	uint16_t counts = (uint16_t)(mv / 10 > 65535 ? 65535 : mv / 10);
	in[0] = counts;
	in[1] = (uint16_t)((uint32_t)mv >> 16);
	in[2] = (uint16_t)((uint32_t)mv & 0xffffu);
	u->map->tab_registers[BAT_HOLDING - hold_lo] = counts;
}

/* A request the silent battery leaves unanswered: any read of its
 * registers. */
static bool battery_read(const uint8_t *q)
{
	int addr = q[2] << 8 | q[3], n = q[4] << 8 | q[5];
	if (q[1] == 0x04)
		return addr <= BAT_INPUT + BAT_NINPUT - 1 && addr + n > BAT_INPUT;
	return q[1] == 0x03 && addr <= BAT_HOLDING && addr + n > BAT_HOLDING;
}

static long parse_mv(const char *s)
{
	char *end;
	long mv = strtol(s, &end, 10);
	return end == s || *end != '\0' || mv < 0 || mv > 4000000000L ? -1 : mv;
}

/* One control line on stdin; false: not understood. */
static bool control(const char *line, unit_t *u, int nu, unit_t *bat, bool *bat_silent)
{
	static const char *const modes[] = {"answer", "silent", "busy", "illegal", "truncate"};
	if (!strncmp(line, "clock ", 6))
		return set_clock(line + 6);
	if (!strncmp(line, "unit ", 5)) {
		char *end;
		long id = strtol(line + 5, &end, 10);
		if (end == line + 5 || *end != ' ')
			return false;
		for (int i = 0; i < nu; i++)
			for (int k = 0; k < 5; k++)
				if (u[i].unit == id && !strcmp(end + 1, modes[k])) {
					u[i].mode = k;
					return true;
				}
		return false;
	}
	if (!bat)
		return false;
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

static uint16_t alarm_of(unit_t *u, unsigned ch)
{
	return prof.reg[MBP_ALARM].words ? *reg(u, MBP_ALARM, ch) : 0;
}

/* Time passes: the communication-loss stop, the stage, the position. */
static void step(unit_t *u, uint64_t now, uint64_t dt)
{
	if (u->comm_ms && !u->comm_stopped && now - u->last_req_us > u->comm_ms * 1000ull) {
		u->comm_stopped = true;
		for (unsigned ch = 0; ch < prof.channels; ch++) {
			u->en[ch] = false;
			mbp_put(&prof.reg[MBP_SPEED], 0, reg(u, MBP_SPEED, ch));
		}
		fprintf(stderr, "mbdrive-sim: unit %d: no request for %u ms: motors stopped\n",
			u->unit, u->comm_ms);
	}
	bool all_on = true;
	for (unsigned ch = 0; ch < prof.channels; ch++)
		all_on = all_on && u->en[ch] && alarm_of(u, ch) == 0;
	for (unsigned ch = 0; ch < prof.channels; ch++) {
		bool on = u->en[ch] && alarm_of(u, ch) == 0;
		uint16_t *st = reg(u, MBP_STATUS, ch);
		bool shown = prof.reg[MBP_STATUS].step ? on : all_on;
		*st = shown ? (uint16_t)(*st | prof.status_mask)
			    : (uint16_t)(*st & ~prof.status_mask);
		if (on)
			u->pos_us[ch] +=
			    (int64_t)mbp_speed_cps(&prof, reg(u, MBP_SPEED, ch)) * (int64_t)dt;
		mbp_put(&prof.reg[MBP_POSITION], (int32_t)(u->pos_us[ch] / 1000000),
			reg(u, MBP_POSITION, ch));
	}
}

/* A register written: the commands it carries. */
static void written(unit_t *u, uint16_t addr, uint16_t v)
{
	const mbp_reg_t *ct = &prof.reg[MBP_COMM_TIMEOUT];
	if (ct->words && addr == ct->addr)
		u->comm_ms = (uint32_t)v * prof.comm_unit_ms;
	for (unsigned ch = 0; ch < prof.channels; ch++) {
		if (prof.reg[MBP_RESET].words && addr == mbp_addr(&prof.reg[MBP_RESET], ch) &&
		    v == prof.reset_value && prof.reg[MBP_ALARM].words)
			*reg(u, MBP_ALARM, ch) = 0;
		if (addr == mbp_addr(&prof.reg[MBP_ENABLE], ch)) {
			if (v == prof.enable_on)
				u->en[ch] = true;
			else if (v == prof.enable_off)
				u->en[ch] = false;
		}
	}
}

/* The writes of a request (06, 16) to a unit. */
static void apply_writes(unit_t *u, const uint8_t *q)
{
	uint16_t addr = (uint16_t)(q[2] << 8 | q[3]);
	if (q[1] == 0x06) {
		written(u, addr, (uint16_t)(q[4] << 8 | q[5]));
	} else if (q[1] == 0x10) {
		int n = q[4] << 8 | q[5];
		for (int i = 0; i < n && 7 + 2 * i + 1 < 9 + q[6]; i++)
			written(u, (uint16_t)(addr + i),
				(uint16_t)(q[7 + 2 * i] << 8 | q[8 + 2 * i]));
	}
}

/* Answers one whole request addressed to unit u. */
static void serve(modbus_t *m, int fd, unit_t *u, const uint8_t *q, int len, bool bat_silent)
{
	if (u->mode == SILENT || bat_silent)
		return;
	modbus_set_slave(m, u->unit);
	if (u->mode == BUSY) {
		modbus_reply_exception(m, q, MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY);
	} else if (u->mode == ILLEGAL) {
		modbus_reply_exception(m, q, MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
	} else if (u->mode == TRUNCATE) {
		uint8_t r[3] = {q[0], q[1], 4}; /* a reply's start, then nothing */
		if (write(fd, r, sizeof r) != (ssize_t)sizeof r)
			fprintf(stderr, "mbdrive-sim: write: %s\n", strerror(errno));
	} else if (modbus_reply(m, q, len, u->map) > 0 && u->drive) {
		apply_writes(u, q);
	}
}

static bool set_profile(const char *name, const char *const *sets, int nsets)
{
	const mb_profile_t *p = mbp_builtin(name);
	if (!p) {
		fprintf(stderr, "mbdrive-sim: unknown profile '%s'\n", name);
		return false;
	}
	prof = *p;
	for (int i = 0; i < nsets; i++) {
		char key[32];
		const char *eq = strchr(sets[i], '=');
		if (!eq || (size_t)(eq - sets[i]) >= sizeof key) {
			fprintf(stderr, "mbdrive-sim: --set KEY=VALUE '%s'\n", sets[i]);
			return false;
		}
		memcpy(key, sets[i], (size_t)(eq - sets[i]));
		key[eq - sets[i]] = '\0';
		const char *why = mbp_set(&prof, key, eq + 1);
		if (why) {
			fprintf(stderr, "mbdrive-sim: --set %s: %s\n", sets[i], why);
			return false;
		}
	}
	const char *why = mbp_check(&prof);
	if (why) {
		fprintf(stderr, "mbdrive-sim: profile %s: %s\n", prof.name, why);
		return false;
	}
	areas();
	return true;
}

/* Cuts the requests out of the bytes read (length from the function code,
 * CRC) and answers each; returns the bytes left over. */
static int take_requests(modbus_t *m, int fd, uint8_t *q, int have, unit_t *u, int nu,
			 const unit_t *bat, bool bat_silent)
{
	for (;;) {
		int len = have >= 2 ? req_len(q, have) : 0;
		if (have >= 2 && len == 0)
			return 0; /* unknown function: resynchronise */
		if (len == 0 || have < len)
			return have;
		if (crc16(q, len - 2) == (uint16_t)(q[len - 2] | q[len - 1] << 8)) {
			uint64_t now = mono_us();
			for (int i = 0; i < nu; i++) {
				if (u[i].unit != q[0])
					continue;
				u[i].last_req_us = now;
				u[i].comm_stopped = false;
				serve(m, fd, &u[i], q, len,
				      &u[i] == bat && bat_silent && battery_read(q));
				if (u[i].drive)
					step(&u[i], now, 0); /* enable/reset take effect at once */
			}
		}
		memmove(q, q + len, (size_t)(have - len));
		have -= len;
	}
}

int main(int argc, char **argv)
{
	const char *port = NULL, *units = "1", *pname = "generic";
	const char *sets[32];
	int nsets = 0;
	long baud = 115200, bat_unit = 0, bat_mv = 24000;
	static const struct option opts[] = {
	    {"port", required_argument, NULL, 'p'},	  {"baud", required_argument, NULL, 'b'},
	    {"units", required_argument, NULL, 'u'},	  {"battery", required_argument, NULL, 'B'},
	    {"battery-mv", required_argument, NULL, 'm'}, {"profile", required_argument, NULL, 'P'},
	    {"set", required_argument, NULL, 's'},	  {NULL, 0, NULL, 0}};
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
		else if (o == 'P')
			pname = optarg;
		else if (o == 's' && nsets < 32)
			sets[nsets++] = optarg;
		else
			return 2;
	}
	if (!port || baud <= 0 || bat_unit < 0 || bat_unit > 247 || bat_mv < 0) {
		fprintf(stderr, "usage: mbdrive-sim --port DEV [--baud N] [--units 1,2] "
				"[--profile NAME] [--set KEY=VALUE]... "
				"[--battery UNIT [--battery-mv MV]]\n");
		return 2;
	}
	if (!set_profile(pname, sets, nsets))
		return 2;
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
	/* Control lines unless stdin is a terminal. */
	int ctl = isatty(STDIN_FILENO) ? -1 : STDIN_FILENO;
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
				step(&u[i], now, now - last);
		last = now;
		if (go_silent) {
			u[ndrives - 1].mode = SILENT;
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
					if (!control(cbuf, u, nu, bat, &bat_silent))
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
			if (prof.reg[MBP_ALARM].words)
				*reg(&u[0], MBP_ALARM, 0) = DRIVE_ALARM;
			raise_alarm = 0;
		}
		if (pr <= 0 || !(p[0].revents & POLLIN)) {
			if (pr == 0)
				have = 0; /* silence: drop a partial frame */
			continue;
		}
		ssize_t r = read(fd, q + have, sizeof(q) - (size_t)have);
		if ((r < 0 && errno == EIO) || (r == 0 && (p[0].revents & POLLHUP))) {
			/* the line's other end closed (a pty's): poll would
			 * return at once for ever */
			fprintf(stderr, "mbdrive-sim: the line hung up\n");
			break;
		}
		if (r <= 0)
			continue;
		have = take_requests(m, fd, q, have + (int)r, u, nu, bat, bat_silent);
	}
	modbus_close(m);
	modbus_free(m);
	return 0;
}
