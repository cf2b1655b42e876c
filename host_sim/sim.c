/* Firmware + simulated plant in lockstep, and the simulator's console
 * extras (list: sim.h). */
#include "sim.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void discard_output(void *ctx, const char *s, size_t n)
{
	(void)ctx, (void)s, (void)n;
}

int sim_init_ex(sim_t *s, const vs_config_t *cfg, const plant_params_t *pp, const char **bad_field)
{
	plant_params_t def;
	if (!pp) {
		plant_params_default(&def);
		pp = &def;
	}
	memset(s, 0, sizeof(*s));
	s->cfg = *cfg;
	plant_init(&s->plant, cfg, pp);
	sim_hal_bind(&s->hal, &s->plant);
	const char *bad = NULL;
	int rc = vehicle_init(&s->vehicle, &s->cfg, &s->hal, &bad);
	if (bad_field)
		*bad_field = bad;
	if (rc < 0)
		return rc;
	server_init(&s->srv, &s->vehicle, sim_extra, s, discard_output, NULL);
	return 0;
}

bool sim_exec(sim_t *s, const char *line, char *reply, size_t cap)
{
	bool r = console_exec(&s->srv.con, line, reply, cap);

	sim_alarm_look(s);
	return r;
}

void sim_alarm_look(sim_t *s)
{
	if (s->alarm_log)
		alarm_log_poll(s->alarm_log, &s->vehicle.alarms, s->now_us, s->alarm_fn,
			       s->alarm_ctx);
}

void sim_set_alarm_log(sim_t *s, alarm_log_t *l, alarm_log_fn fn, void *ctx)
{
	s->alarm_log = l;
	s->alarm_fn = fn;
	s->alarm_ctx = ctx;
}

void sim_tick(sim_t *s)
{
	uint64_t hz = s->cfg.tick_hz;
	/* Integer period bookkeeping: no drift at rates that do not divide 1e6. */
	uint64_t next_us = (s->ticks + 1) * 1000000u / hz;
	/* what requests since the last tick raised, then the tick's own */
	sim_alarm_look(s);
	vehicle_tick(&s->vehicle, (uint32_t)s->now_us);
	sim_alarm_look(s);
	plant_step(&s->plant, (uint32_t)(next_us - s->now_us));
	s->ticks++;
	s->now_us = next_us;
	if (s->trace)
		trace_tick(s->trace, sim_time_s(s), &s->vehicle, &s->plant);
	if (s->on_tick)
		s->on_tick(s->tick_ctx, s);
}

void sim_run_ms(sim_t *s, uint32_t ms)
{
	uint64_t end_us = s->now_us + (uint64_t)ms * 1000u;
	while (s->now_us < end_us)
		sim_tick(s);
}

void sim_set_tick_cb(sim_t *s, sim_tick_fn fn, void *ctx)
{
	s->on_tick = fn;
	s->tick_ctx = ctx;
}

void sim_set_realtime(sim_t *s, bool on)
{
	s->realtime = on;
}

void sim_set_output(sim_t *s, console_write_fn fn, void *ctx)
{
	s->srv.con.write = fn ? fn : discard_output;
	s->srv.con.wctx = ctx;
}

void sim_set_trace(sim_t *s, trace_t *t)
{
	s->trace = t;
}

/* ---- '$' extras ---- */

static bool reply_f(char *reply, size_t cap, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static bool reply_f(char *reply, size_t cap, const char *fmt, ...)
{
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(reply, cap, fmt, ap);
	va_end(ap);
	return true;
}

#define ERR(...) reply_f(reply, cap, "error 8 " __VA_ARGS__)

static bool parse_double(const char *s, double *out)
{
	char *end;
	errno = 0;
	double d = strtod(s, &end);
	if (end == s || *end != '\0' || !isfinite(d) || errno == ERANGE)
		return false;
	/* Decimal only: no hex floats, no nan/inf spellings. */
	for (const char *q = s; *q; q++)
		if (*q == 'x' || *q == 'X' || *q == 'n' || *q == 'N')
			return false;
	*out = d;
	return true;
}

/* Unsigned integer in [0, max]; base 0 so "0x2310" works for fault codes. */
static bool parse_uint(const char *s, unsigned long max, unsigned long *out)
{
	char *end;
	if (*s == '-' || *s == '+' || *s == '\0')
		return false;
	errno = 0;
	unsigned long v = strtoul(s, &end, 0);
	if (*end != '\0' || errno == ERANGE || v > max)
		return false;
	*out = v;
	return true;
}

/* Values that print as zero print as "0.000", never "-0.000". */
static double no_neg_zero(double v)
{
	return fabs(v) < 0.0005 ? 0.0 : v;
}

static int parse_onoff(const char *s)
{
	if (!strcmp(s, "on") || !strcmp(s, "true") || !strcmp(s, "1"))
		return 1;
	if (!strcmp(s, "off") || !strcmp(s, "false") || !strcmp(s, "0"))
		return 0;
	return -1;
}

static bool cmd_wait(sim_t *s, int argc, char **argv, char *reply, size_t cap)
{
	unsigned long ms;
	if (s->realtime)
		return ERR(
		    "$wait runs simulated time only with --fast; in real time the host waits");
	if (argc != 2 || !parse_uint(argv[1], SIM_WAIT_MAX_MS, &ms))
		return ERR("usage: $wait MS (0..%u)", SIM_WAIT_MAX_MS);
	sim_run_ms(s, (uint32_t)ms);
	return reply_f(reply, cap, "ok wait %lu", ms);
}

static bool cmd_drive(sim_t *s, int argc, char **argv, char *reply, size_t cap)
{
	plant_t *pl = &s->plant;
	unsigned long axis, code;
	if (argc < 4 || !parse_uint(argv[2], 255, &axis))
		return ERR("usage: $sim drive AXIS fault CODE|ok|stuck|silent|hold|reboot");
	if (axis >= pl->n)
		return ERR("no axis %lu (0..%u)", axis, pl->n - 1u);
	uint8_t a = (uint8_t)axis;
	const char *what = argv[3];
	if (!strcmp(what, "fault") && argc == 5) {
		if (!parse_uint(argv[4], 0xffff, &code) || code == 0)
			return ERR("fault code must be 1..65535, got '%s'", argv[4]);
		plant_drive_fault(pl, a, (uint16_t)code);
		return reply_f(reply, cap, "ok drive %u fault 0x%04lx", a, code);
	}
	if (argc != 4)
		return ERR("usage: $sim drive AXIS fault CODE|ok|stuck|silent|hold|reboot");
	if (!strcmp(what, "ok")) {
		plant_drive_ok(pl, a);
		plant_drive_hold(pl, a, false);
	} else if (!strcmp(what, "hold"))
		plant_drive_hold(pl, a, true);
	else if (!strcmp(what, "reboot"))
		plant_drive_reboot(pl, a);
	else if (!strcmp(what, "stuck"))
		plant_drive_stuck(pl, a, true);
	else if (!strcmp(what, "silent"))
		plant_drive_silent(pl, a, true);
	else
		return ERR("usage: $sim drive AXIS fault CODE|ok|stuck|silent|hold|reboot");
	return reply_f(reply, cap, "ok drive %u %s", a, what);
}

static bool cmd_sim(sim_t *s, int argc, char **argv, char *reply, size_t cap)
{
	plant_t *pl = &s->plant;
	if (argc < 2)
		return ERR("usage: $sim contact|obstacle|caution|estop|joystick|relay|drive|"
			   "battery|input|wire|wall|pose|push ...");
	const char *what = argv[1];

	bool *flag = NULL;
	if (!strcmp(what, "contact"))
		flag = &pl->contact_inject;
	else if (!strcmp(what, "obstacle"))
		flag = &pl->obstacle;
	else if (!strcmp(what, "caution"))
		flag = &pl->caution;
	else if (!strcmp(what, "estop"))
		flag = &pl->estop;
	if (flag) {
		int on = argc == 3 ? parse_onoff(argv[2]) : -1;
		if (on < 0)
			return ERR("usage: $sim %s on|off", what);
		*flag = on != 0;
		return reply_f(reply, cap, "ok %s %s", what, on ? "on" : "off");
	}

	if (!strcmp(what, "joystick")) {
		if (argc == 3 && !strcmp(argv[2], "lost")) {
			plant_set_joystick(pl, 0, 0, 0, false);
			return reply_f(reply, cap, "ok joystick lost");
		}
		double v[3];
		if (argc != 5)
			return ERR("usage: $sim joystick X Y R | $sim joystick lost");
		for (int i = 0; i < 3; i++)
			if (!parse_double(argv[2 + i], &v[i]) || v[i] < -1.0 || v[i] > 1.0)
				return ERR("joystick axis must be -1..1, got '%s'", argv[2 + i]);
		plant_set_joystick(pl, v[0], v[1], v[2], true);
		return reply_f(reply, cap, "ok joystick %d %d %d", pl->js.axis[0], pl->js.axis[1],
			       pl->js.axis[2]);
	}
	if (!strcmp(what, "relay")) {
		if (argc == 3 && !strcmp(argv[2], "fail"))
			plant_set_relay_mode(pl, PLANT_RELAY_FAIL);
		else if (argc == 3 && !strcmp(argv[2], "ok"))
			plant_set_relay_mode(pl, PLANT_RELAY_OK);
		else if (argc == 3 && !strcmp(argv[2], "drop"))
			plant_set_relay_mode(pl, PLANT_RELAY_DROP);
		else
			return ERR("usage: $sim relay fail|ok|drop");
		return reply_f(reply, cap, "ok relay %s", argv[2]);
	}
	if (!strcmp(what, "drive"))
		return cmd_drive(s, argc, argv, reply, cap);
	if (!strcmp(what, "battery")) {
		unsigned long mv;
		if (argc != 3 || !parse_uint(argv[2], 1000000, &mv))
			return ERR("usage: $sim battery MV (0..1000000)");
		plant_set_battery_ocv(pl, (double)mv / 1000.0);
		return reply_f(reply, cap, "ok battery %lu", mv);
	}
	if (!strcmp(what, "input")) {
		unsigned long id, val;
		if (argc != 4 || !parse_uint(argv[2], 0xffffffffu, &id) ||
		    !parse_uint(argv[3], 0xffffffffu, &val))
			return ERR("usage: $sim input ID VALUE");
		if (!plant_set_input(pl, (uint32_t)id, (uint32_t)val))
			return ERR("no input with id %lu", id);
		uint32_t now = 0;
		plant_io_read(pl, (uint32_t)id, &now);
		return reply_f(reply, cap, "ok input %lu %u", id, (unsigned)now);
	}
	if (!strcmp(what, "wire")) {
		unsigned long out, in = 0;
		if (argc != 4 || !parse_uint(argv[2], 0xffffffffu, &out) ||
		    (strcmp(argv[3], "none") != 0 && !parse_uint(argv[3], 0xffffffffu, &in)))
			return ERR("usage: $sim wire OUT IN|none");
		if (!plant_wire(pl, (uint32_t)out, (uint32_t)in))
			return ERR("cannot wire %s to %s", argv[2], argv[3]);
		return reply_f(reply, cap, "ok wire %lu %s", out, argv[3]);
	}
	if (!strcmp(what, "wall")) {
		double c[4];
		if (argc != 6)
			return ERR("usage: $sim wall X0 Y0 X1 Y1");
		for (int i = 0; i < 4; i++)
			if (!parse_double(argv[2 + i], &c[i]))
				return ERR("not a number '%s'", argv[2 + i]);
		if (!plant_add_wall(pl, c[0], c[1], c[2], c[3]))
			return ERR("at most %d walls", PLANT_MAX_WALLS);
		return reply_f(reply, cap, "ok wall %u", pl->num_walls);
	}
	if (!strcmp(what, "push")) {
		double d[3];
		if (argc != 5)
			return ERR("usage: $sim push DX DY DTH (mm forward, mm left, deg "
				   "counter-clockwise, in the base's frame)");
		for (int i = 0; i < 3; i++)
			if (!parse_double(argv[2 + i], &d[i]))
				return ERR("not a number '%s'", argv[2 + i]);
		if (!plant_push(pl, d[0], d[1], d[2]))
			return ERR("a push moves at most %.0f mm along each axis and %.0f deg",
				   PLANT_PUSH_MAX_MM, PLANT_PUSH_MAX_DEG);
		double x, y, th;
		plant_pose(pl, &x, &y, &th);
		return reply_f(reply, cap, "ok push %.3f %.3f %.3f", no_neg_zero(x), no_neg_zero(y),
			       no_neg_zero(th));
	}
	if (!strcmp(what, "pose")) {
		if (argc != 2)
			return ERR("usage: $sim pose");
		double x, y, th;
		plant_pose(pl, &x, &y, &th);
		return reply_f(reply, cap, "ok pose %.3f %.3f %.3f", no_neg_zero(x), no_neg_zero(y),
			       no_neg_zero(th));
	}
	return ERR("unknown command '$sim %s'", what);
}

bool sim_extra(void *ctx, int argc, char **argv, char *reply, size_t cap)
{
	sim_t *s = ctx;
	if (!s || argc < 1) /* no simulator behind this console: not ours */
		return false;
	const char *name = argv[0][0] == '$' ? argv[0] + 1 : argv[0];
	if (!strcmp(name, "wait"))
		return cmd_wait(s, argc, argv, reply, cap);
	if (!strcmp(name, "sim"))
		return cmd_sim(s, argc, argv, reply, cap);
	return false;
}
