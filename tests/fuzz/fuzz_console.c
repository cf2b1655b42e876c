/* Fuzz target: the console line parser (proto/console.c, numparse.c,
 * cmdtab.c) on a fresh unit on the simulated plant, through the byte stream
 * a serial link delivers.
 *
 * Checked for every line: at most one reply, and it is one printable line
 * starting "ok" or "error <code> "; an "error" reply leaves the unit
 * untouched (byte for byte); an "ok false" leaves the motion engine
 * untouched (a refusal only raises a warning), unless the operation failed
 * and raised a fault (setPower's relay, setServo's drives): a fault halts
 * motion whatever raised it. '$wait' is capped so one input stays fast.
 * The console is the serial server's (server_serve_serial), so its extras
 * ($link, $stream with the text form's groups and period) are reached too.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../../host_sim/sim.h"

#define WAIT_CAP_MS 20

static sim_t S;
static bbox_sample_t bbox_ring[6];
static server_serial_t SER;
static console_extra_fn next_extra; /* the server's chain: $stream, $link, the simulator's */
static void *next_xctx;
static struct {
	unsigned replies;
	char last[CONSOLE_REPLY_MAX + 2];
} out;

static void on_write(void *ctx, const char *s, size_t n)
{
	(void)ctx;
	if (n == 0 || n > CONSOLE_REPLY_MAX + 1 || s[n - 1] != '\n')
		abort();
	for (size_t i = 0; i + 1 < n; i++) {
		unsigned char b = (unsigned char)s[i];
		if (b < 0x20 || b >= 0x7f)
			abort(); /* one printable line */
	}
	if (!(n >= 3 && memcmp(s, "ok", 2) == 0 && (s[2] == ' ' || s[2] == '\n')) &&
	    !(n > 8 && memcmp(s, "error ", 6) == 0 && s[6] >= '1' && s[6] <= '9'))
		abort();
	memcpy(out.last, s, n);
	out.last[n] = '\0';
	out.replies++;
}

/* The simulator's extras, with '$wait' capped. */
static bool extra(void *ctx, int argc, char **argv, char *reply, size_t cap)
{
	if (argc >= 2 && strcmp(argv[0], "$wait") == 0) {
		/* Read as the simulator reads it (base 0: "0x231020" is 38
		 * minutes, which a base-10 read took for 0). */
		long ms = strtol(argv[1], NULL, 0);
		if (ms > WAIT_CAP_MS || ms < 0) {
			snprintf(reply, cap, "error 8 capped");
			return true;
		}
	}
	(void)ctx;
	return next_extra(next_xctx, argc, argv, reply, cap);
}

static size_t no_read(void *ctx, uint8_t *b, size_t n)
{
	(void)ctx, (void)b, (void)n;
	return 0;
}

static size_t sink(void *ctx, const uint8_t *b, size_t n)
{
	(void)ctx, (void)b;
	return n;
}

/* setPower and setServo fail by raising a fault (the relay, the drives),
 * which may be the one already in front of the list. */
static bool may_fault(const char *line, size_t n)
{
	size_t i = 0;
	while (i < n && (line[i] == ' ' || line[i] == '\t'))
		i++;
	return n - i >= 8 && (strncasecmp(line + i, "setpower", 8) == 0 ||
			      strncasecmp(line + i, "setservo", 8) == 0);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	static vehicle_t before;
	static motion_t mbefore;
	vs_config_t cfg;

	vs_config_defaults(&cfg);
	if (sim_init(&S, &cfg, NULL) != 0)
		abort();
	/* $bbox dump has samples to index (a few, every tick of $wait) */
	vehicle_blackbox(&S.vehicle, bbox_ring, 6, 1);
	{
		const vs_link_t io = {no_read, sink, NULL};

		server_serve_serial(&S.srv, &SER, &io);
	}
	next_extra = S.srv.con.extra;
	next_xctx = S.srv.con.xctx;
	console_set_extra(&S.srv.con, extra, &S);
	sim_set_output(&S, on_write, NULL);

	/* One line at a time (with its terminator), so that each reply can be
	 * judged against the unit's state just before its line. */
	size_t start = 0;
	while (start < size) {
		size_t end = start;
		while (end < size && data[end] != '\n' && data[end] != '\r')
			end++;
		size_t n = end < size ? end - start + 1 : end - start;
		unsigned r0 = out.replies;
		before = S.vehicle;
		mbefore = S.vehicle.motion;
		console_feed(&S.srv.con, data + start, n);
		if (out.replies > r0 + 1)
			abort(); /* more than one reply for one line */
		if (out.replies == r0 + 1) {
			if (memcmp(out.last, "error", 5) == 0 &&
			    memcmp(&before, &S.vehicle, sizeof before) != 0)
				abort(); /* a rejected line changed the unit */
			if (strcmp(out.last, "ok false\n") == 0 &&
			    !(may_fault((const char *)data + start, n) &&
			      alarm_any_fault(&S.vehicle.alarms)) &&
			    memcmp(&mbefore, &S.vehicle.motion, sizeof mbefore) != 0)
				abort(); /* a refused operation touched the motion */
		}
		start += n;
	}
	/* The tail without a line end: its reply comes at the next line end. */
	console_feed(&S.srv.con, (const uint8_t *)"\n", 1);
	return 0;
}
