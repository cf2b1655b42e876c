/* <backends> of the vehicle file; format in backend_cfg.h. The file is
 * read by hal/posix/config_xml.c, which hands this section's elements to
 * the handler here (config_section_t). */
#include "backend_cfg.h"

#include <libevdev/libevdev.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

typedef struct {
	config_reader_t *r;
	unsigned long line; /* the element's start tag */
	backend_cfg_t *b;
	unsigned long drive_line[VS_MAX_AXES];
	unsigned long at_line; /* nonzero: report this line instead of the element's */
	unsigned long battery_line;
	unsigned long modbus_line[BK_MODBUS_BUSES];
} bctx_t;

static const char *const line_names[BK_LINE_SERVO0 + 1] = {
    "contact", "obstacle", "obstacle_caution", "estop", "relay", "relay_feedback", "servo_enable",
};

const char *backend_line_name(unsigned fn)
{
	if (fn >= BK_LINE_COUNT)
		return "?";
	return line_names[fn < BK_LINE_SERVO0 ? fn : BK_LINE_SERVO0];
}

void backend_cfg_defaults(backend_cfg_t *b)
{
	memset(b, 0, sizeof(*b));
	b->settle_ms = 20;
	b->battery_source = BK_BATTERY_FIXED;
	b->battery_mv = 24000;
	b->battery_scale = 1.0;
	b->battery_mb.words = 1;
	b->battery_mb.period_ms = 200;
	for (int i = 0; i < 3; i++) {
		b->joystick.code[i] = -1;
		b->joystick.scale[i] = 1.0;
	}
}

static int fail(bctx_t *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static int fail(bctx_t *c, const char *fmt, ...)
{
	va_list ap;
	va_start(ap, fmt);
	int rc = config_vfail(c->r, c->at_line ? c->at_line : c->line, fmt, ap);
	va_end(ap);
	return rc;
}

/* Whole-string unsigned integer in [min, max]. */
static int get_uint(bctx_t *c, const char *el, const char *at, const char *v, unsigned long min,
		    unsigned long max, uint32_t *out)
{
	return config_attr_uint(c->r, c->line, el, at, v, min, max, out);
}

static int get_bool(bctx_t *c, const char *el, const char *at, const char *v, bool *out)
{
	return config_attr_bool(c->r, c->line, el, at, v, out);
}

/* Number within [lo, hi] ((lo, hi] when lo_excl; range names it for the
 * message), in the core loader's syntax. */
static int get_double(bctx_t *c, const char *el, const char *at, const char *v, double lo,
		      bool lo_excl, double hi, const char *range, double *out)
{
	return config_attr_number(c->r, c->line, el, at, v, lo, lo_excl, hi, range, out);
}

/* drive.bus is one range for both bus types */
_Static_assert(BK_CANOPEN_BUSES == BK_MODBUS_BUSES, "drive.bus range");

static int drive_elem(bctx_t *c, const char **a)
{
	uint32_t axis = UINT32_MAX, bus = UINT32_MAX, unit = UINT32_MAX, node = UINT32_MAX;
	uint32_t channel = UINT32_MAX;
	int type = -1, reverse = -1;
	for (; a[0]; a += 2) {
		if (!strcmp(a[0], "axis")) {
			if (get_uint(c, "drive", "axis", a[1], 0, VS_MAX_AXES - 1, &axis))
				return -1;
		} else if (!strcmp(a[0], "type")) {
			if (!strcmp(a[1], "loopback"))
				type = BK_DRIVE_LOOPBACK;
			else if (!strcmp(a[1], "modbus"))
				type = BK_DRIVE_MODBUS;
			else if (!strcmp(a[1], "cia402"))
				type = BK_DRIVE_CIA402;
			else
				return fail(c, "drive.type: unknown backend '%s'", a[1]);
		} else if (!strcmp(a[0], "bus")) {
			if (get_uint(c, "drive", "bus", a[1], 0, BK_MODBUS_BUSES - 1, &bus))
				return -1;
		} else if (!strcmp(a[0], "unit")) {
			if (get_uint(c, "drive", "unit", a[1], 1, 247, &unit))
				return -1;
		} else if (!strcmp(a[0], "node")) {
			if (get_uint(c, "drive", "node", a[1], 1, 127, &node))
				return -1;
		} else if (!strcmp(a[0], "channel")) {
			if (get_uint(c, "drive", "channel", a[1], 0, MBP_CHANNELS_MAX - 1,
				     &channel))
				return -1;
		} else if (!strcmp(a[0], "polarity")) {
			if (strcmp(a[1], "normal") != 0 && strcmp(a[1], "reverse") != 0)
				return fail(c, "drive.polarity: normal or reverse '%s'", a[1]);
			reverse = a[1][0] == 'r';
		} else {
			return fail(c, "drive.%s: unknown attribute", a[0]);
		}
	}
	if (axis == UINT32_MAX)
		return fail(c, "drive.axis: required");
	if (type < 0)
		return fail(c, "drive.type: required");
	/* a second element for one axis would silently replace the first */
	if (c->drive_line[axis])
		return fail(c, "drive.axis: duplicate '%u'", axis);
	if (type == BK_DRIVE_MODBUS) {
		if (bus == UINT32_MAX || unit == UINT32_MAX)
			return fail(c, "drive.%s: required for modbus",
				    bus == UINT32_MAX ? "bus" : "unit");
		c->b->drive_bus[axis] = (uint8_t)bus;
		c->b->drive_unit[axis] = (uint8_t)unit;
		c->b->drive_channel[axis] = channel == UINT32_MAX ? 0 : (uint8_t)channel;
	} else if (type == BK_DRIVE_CIA402) {
		if (bus == UINT32_MAX || node == UINT32_MAX)
			return fail(c, "drive.%s: required for cia402",
				    bus == UINT32_MAX ? "bus" : "node");
		c->b->drive_bus[axis] = (uint8_t)bus;
		c->b->drive_node[axis] = (uint8_t)node;
	} else if (bus != UINT32_MAX) {
		return fail(c, "drive.bus: only for modbus and cia402");
	}
	if (unit != UINT32_MAX && type != BK_DRIVE_MODBUS)
		return fail(c, "drive.unit: only for modbus");
	if (channel != UINT32_MAX && type != BK_DRIVE_MODBUS)
		return fail(c, "drive.channel: only for modbus");
	if (node != UINT32_MAX && type != BK_DRIVE_CIA402)
		return fail(c, "drive.node: only for cia402");
	if (reverse >= 0 && type == BK_DRIVE_LOOPBACK)
		return fail(c, "drive.polarity: only for modbus and cia402");
	c->b->drive_type[axis] = (uint8_t)type;
	c->b->drive_reverse[axis] = reverse > 0;
	c->drive_line[axis] = c->line;
	return 0;
}

/* The generic profile's addresses, in MBP_* order. */
static const char *const reg_names[MBP_REG_COUNT] = {
    "reg_target_speed", "reg_position",	   "reg_status",       "reg_alarm",
    "reg_servo_on",	"reg_fault_reset", "reg_comm_timeout",
};

/* The profile first (attributes come in document order): the others
 * change its fields. */
static int modbus_profile(bctx_t *c, const char **a, mb_profile_t *p)
{
	const mb_profile_t *base = mbp_builtin("generic");
	for (; a[0]; a += 2) {
		if (strcmp(a[0], "profile") != 0)
			continue;
		base = mbp_builtin(a[1]);
		if (!base)
			return fail(c, "modbus.profile: unknown profile (generic, zlac8015d) '%s'",
				    a[1]);
	}
	*p = *base;
	return 0;
}

/* One attribute of the profile's text form or a reg_* address; *hit false
 * when the name is neither. */
static int modbus_prof_attr(bctx_t *c, const char **a, bk_modbus_bus_t *m, bool *given, bool *hit)
{
	*hit = true;
	for (int i = 0; i < MBP_REG_COUNT; i++) {
		if (strcmp(a[0], reg_names[i]) != 0)
			continue;
		uint32_t v;
		if (get_uint(c, "modbus", a[0], a[1], 0, 65535, &v))
			return -1;
		mbp_reg_t *r = &m->prof.reg[i];
		r->addr = (uint16_t)v;
		if (r->words == 0) /* reg_comm_timeout: one register of ms */
			r->words = 1;
		given[i] = true;
		return 0;
	}
	const char *why = mbp_set(&m->prof, a[0], a[1]);
	if (why && !strcmp(why, "unknown")) {
		*hit = false;
		return 0;
	}
	if (why)
		return fail(c, "modbus.%s: %s '%s'", a[0], why, a[1]);
	for (int i = 0; i < MBP_REG_COUNT; i++)
		given[i] = given[i] || !strcmp(a[0], mbp_reg_name((unsigned)i));
	return 0;
}

static int modbus_elem(bctx_t *c, const char **a)
{
	bk_modbus_bus_t m = {.baud = 115200,
			     .parity = 'N',
			     .stop_bits = 1,
			     .timeout_ms = 20,
			     .retries = 1,
			     .comm_timeout_ms = 200};
	uint32_t bus = UINT32_MAX;
	bool given[MBP_REG_COUNT] = {false};
	if (modbus_profile(c, a, &m.prof))
		return -1;
	for (; a[0]; a += 2) {
		bool hit = false;
		if (modbus_prof_attr(c, a, &m, given, &hit))
			return -1;
		if (hit || !strcmp(a[0], "profile"))
			continue;
		if (!strcmp(a[0], "bus")) {
			if (get_uint(c, "modbus", "bus", a[1], 0, BK_MODBUS_BUSES - 1, &bus))
				return -1;
		} else if (!strcmp(a[0], "device")) {
			if (a[1][0] != '/' || strlen(a[1]) >= sizeof(m.device))
				return fail(c, "modbus.device: not a device path '%s'", a[1]);
			snprintf(m.device, sizeof(m.device), "%s", a[1]);
		} else if (!strcmp(a[0], "baud")) {
			if (get_uint(c, "modbus", "baud", a[1], 1200, 4000000, &m.baud))
				return -1;
		} else if (!strcmp(a[0], "parity")) {
			if (strcmp(a[1], "N") != 0 && strcmp(a[1], "E") != 0 &&
			    strcmp(a[1], "O") != 0)
				return fail(c, "modbus.parity: N, E or O '%s'", a[1]);
			m.parity = a[1][0];
		} else if (!strcmp(a[0], "stop_bits")) {
			if (get_uint(c, "modbus", "stop_bits", a[1], 1, 2, &m.stop_bits))
				return -1;
		} else if (!strcmp(a[0], "timeout_ms")) {
			if (get_uint(c, "modbus", "timeout_ms", a[1], 1, 1000, &m.timeout_ms))
				return -1;
		} else if (!strcmp(a[0], "byte_timeout_ms")) {
			if (get_uint(c, "modbus", "byte_timeout_ms", a[1], 1, 1000,
				     &m.byte_timeout_ms))
				return -1;
		} else if (!strcmp(a[0], "retries")) {
			if (get_uint(c, "modbus", "retries", a[1], 0, 10, &m.retries))
				return -1;
		} else if (!strcmp(a[0], "comm_timeout_ms")) {
			if (get_uint(c, "modbus", "comm_timeout_ms", a[1], 10, 60000,
				     &m.comm_timeout_ms))
				return -1;
		} else if (!strcmp(a[0], "comm_stop")) {
			if (strcmp(a[1], "none") != 0 && strcmp(a[1], "drive") != 0)
				return fail(c, "modbus.comm_stop: drive or none '%s'", a[1]);
			m.comm_stop_none = a[1][0] == 'n';
		} else {
			return fail(c, "modbus.%s: unknown attribute", a[0]);
		}
	}
	if (bus == UINT32_MAX)
		return fail(c, "modbus.bus: required");
	if (!m.device[0])
		return fail(c, "modbus.device: required");
	/* The generic profile has no addresses of its own. */
	if (!strcmp(m.prof.name, "generic"))
		for (int i = 0; i < MBP_COMM_TIMEOUT; i++)
			if (!given[i])
				return fail(c, "modbus.%s: required", reg_names[i]);
	const char *why = mbp_check(&m.prof);
	if (why)
		return fail(c, "modbus.profile: %s '%s'", why, m.prof.name);
	if (c->b->bus[bus].used)
		return fail(c, "modbus.bus: duplicate '%u'", bus);
	m.used = true;
	c->b->bus[bus] = m;
	c->modbus_line[bus] = c->line;
	return 0;
}

static int canopen_elem(bctx_t *c, const char **a)
{
	bk_canopen_bus_t m = {.heartbeat_ms = 100,
			      .heartbeat_timeout_ms = 300,
			      .sdo_timeout_ms = 100,
			      .boot_timeout_ms = 2000,
			      .fault_reset_ms = 200};
	const struct {
		const char *name;
		uint32_t *dst;
		unsigned long min, max;
	} num[] = {
	    {"heartbeat_ms", &m.heartbeat_ms, 1, 10000},
	    {"heartbeat_timeout_ms", &m.heartbeat_timeout_ms, 2, 60000},
	    {"sdo_timeout_ms", &m.sdo_timeout_ms, 1, 10000},
	    {"boot_timeout_ms", &m.boot_timeout_ms, 1, 60000},
	    {"master_node", &m.master_node, 1, 127},
	    {"profile_accel", &m.profile_accel, 1, 0x7FFFFFFFul},
	    {"fault_reset_ms", &m.fault_reset_ms, 10, 10000},
	};
	uint32_t bus = UINT32_MAX;
	for (; a[0]; a += 2) {
		size_t k = 0;
		while (k < sizeof(num) / sizeof(num[0]) && strcmp(a[0], num[k].name) != 0)
			k++;
		if (k < sizeof(num) / sizeof(num[0])) {
			if (get_uint(c, "canopen", a[0], a[1], num[k].min, num[k].max, num[k].dst))
				return -1;
		} else if (!strcmp(a[0], "bus")) {
			if (get_uint(c, "canopen", "bus", a[1], 0, BK_CANOPEN_BUSES - 1, &bus))
				return -1;
		} else if (!strcmp(a[0], "interface")) {
			if (a[1][0] == '\0' || strlen(a[1]) >= sizeof(m.interface) ||
			    strchr(a[1], '/') || strchr(a[1], ' '))
				return fail(c, "canopen.interface: not an interface name '%s'",
					    a[1]);
			snprintf(m.interface, sizeof(m.interface), "%s", a[1]);
		} else {
			return fail(c, "canopen.%s: unknown attribute", a[0]);
		}
	}
	if (bus == UINT32_MAX)
		return fail(c, "canopen.bus: required");
	if (!m.interface[0])
		return fail(c, "canopen.interface: required");
	if (m.heartbeat_timeout_ms <= m.heartbeat_ms)
		return fail(c, "canopen.heartbeat_timeout_ms: not above heartbeat_ms '%u'",
			    m.heartbeat_timeout_ms);
	if (c->b->canopen[bus].used)
		return fail(c, "canopen.bus: duplicate '%u'", bus);
	m.used = true;
	c->b->canopen[bus] = m;
	return 0;
}

static int power_elem(bctx_t *c, const char **a)
{
	for (; a[0]; a += 2) {
		if (strcmp(a[0], "settle_ms") != 0)
			return fail(c, "power.%s: unknown attribute", a[0]);
		if (get_uint(c, "power", "settle_ms", a[1], 0, 50, &c->b->settle_ms))
			return -1;
	}
	return 0;
}

/* The attributes of source="modbus"; judged after the loop, as source may
 * come last. */
static int battery_modbus_attr(bctx_t *c, const char **a, bool *hit)
{
	bk_battery_modbus_t *m = &c->b->battery_mb;
	uint32_t v = 0;
	*hit = true;
	if (!strcmp(a[0], "bus")) {
		if (get_uint(c, "battery", "bus", a[1], 0, BK_MODBUS_BUSES - 1, &v))
			return -1;
		m->bus = (uint8_t)v;
	} else if (!strcmp(a[0], "unit")) {
		if (get_uint(c, "battery", "unit", a[1], 1, 247, &v))
			return -1;
		m->unit = (uint8_t)v;
	} else if (!strcmp(a[0], "reg")) {
		if (get_uint(c, "battery", "reg", a[1], 0, 65535, &v))
			return -1;
		m->reg = (uint16_t)v;
	} else if (!strcmp(a[0], "reg_type")) {
		if (strcmp(a[1], "holding") != 0 && strcmp(a[1], "input") != 0)
			return fail(c, "battery.reg_type: holding or input '%s'", a[1]);
		m->input = a[1][0] == 'i';
	} else if (!strcmp(a[0], "width")) {
		if (strcmp(a[1], "16") != 0 && strcmp(a[1], "32") != 0)
			return fail(c, "battery.width: 16 or 32 '%s'", a[1]);
		m->words = a[1][0] == '3' ? 2 : 1;
	} else if (!strcmp(a[0], "period_ms")) {
		if (get_uint(c, "battery", "period_ms", a[1], 10, 1000, &m->period_ms))
			return -1;
	} else {
		*hit = false;
	}
	return 0;
}

static int battery_elem(bctx_t *c, const char **a)
{
	backend_cfg_t *b = c->b;
	const char *mb_attr = NULL; /* the first modbus-only attribute given */
	bool have_bus = false, have_unit = false, have_reg = false;
	c->battery_line = c->line;
	for (; a[0]; a += 2) {
		bool mb = false;
		if (battery_modbus_attr(c, a, &mb))
			return -1;
		if (mb) {
			mb_attr = mb_attr ? mb_attr : a[0];
			have_bus = have_bus || !strcmp(a[0], "bus");
			have_unit = have_unit || !strcmp(a[0], "unit");
			have_reg = have_reg || !strcmp(a[0], "reg");
		} else if (!strcmp(a[0], "source")) {
			if (!strcmp(a[1], "fixed"))
				b->battery_source = BK_BATTERY_FIXED;
			else if (!strcmp(a[1], "iio"))
				b->battery_source = BK_BATTERY_IIO;
			else if (!strcmp(a[1], "modbus"))
				b->battery_source = BK_BATTERY_MODBUS;
			else
				return fail(c, "battery.source: unknown source '%s'", a[1]);
		} else if (!strcmp(a[0], "mv")) {
			if (get_uint(c, "battery", "mv", a[1], 0, 1000000, &b->battery_mv))
				return -1;
		} else if (!strcmp(a[0], "path")) {
			if (strlen(a[1]) >= sizeof(b->battery_path) || a[1][0] != '/')
				return fail(c, "battery.path: not an absolute path '%s'", a[1]);
			snprintf(b->battery_path, sizeof(b->battery_path), "%s", a[1]);
		} else if (!strcmp(a[0], "scale")) {
			if (get_double(c, "battery", "scale", a[1], 0.0, true, 1e6, "(0, 1e6]",
				       &b->battery_scale))
				return -1;
		} else {
			return fail(c, "battery.%s: unknown attribute", a[0]);
		}
	}
	if (b->battery_source == BK_BATTERY_IIO && b->battery_path[0] == '\0')
		return fail(c, "battery.path: required with source iio");
	if (b->battery_source == BK_BATTERY_MODBUS) {
		const char *missing = !have_reg ? "reg" : NULL;
		missing = !have_unit ? "unit" : missing;
		missing = !have_bus ? "bus" : missing;
		if (missing)
			return fail(c, "battery.%s: required with source modbus", missing);
	}
	if (b->battery_source != BK_BATTERY_MODBUS && mb_attr)
		return fail(c, "battery.%s: only for source modbus", mb_attr);
	return 0;
}

static int line_elem(bctx_t *c, const char **a)
{
	bk_line_t l = {0};
	int fn = -1;
	uint32_t axis = UINT32_MAX;
	bool have_line = false;
	for (; a[0]; a += 2) {
		if (!strcmp(a[0], "function")) {
			for (int i = 0; i <= BK_LINE_SERVO0; i++)
				if (!strcmp(a[1], line_names[i]))
					fn = i;
			if (fn < 0)
				return fail(c, "line.function: unknown function '%s'", a[1]);
		} else if (!strcmp(a[0], "chip")) {
			if (a[1][0] == '\0' || strlen(a[1]) >= sizeof(l.chip))
				return fail(c, "line.chip: bad chip name '%s'", a[1]);
			snprintf(l.chip, sizeof(l.chip), "%s", a[1]);
		} else if (!strcmp(a[0], "line")) {
			if (get_uint(c, "line", "line", a[1], 0, 65535, &l.line))
				return -1;
			have_line = true;
		} else if (!strcmp(a[0], "active_low")) {
			if (get_bool(c, "line", "active_low", a[1], &l.active_low))
				return -1;
		} else if (!strcmp(a[0], "axis")) {
			if (get_uint(c, "line", "axis", a[1], 0, VS_MAX_AXES - 1, &axis))
				return -1;
		} else {
			return fail(c, "line.%s: unknown attribute", a[0]);
		}
	}
	if (fn < 0)
		return fail(c, "line.function: required");
	if (!l.chip[0] || !have_line)
		return fail(c, "line.%s: required", l.chip[0] ? "line" : "chip");
	if (fn == BK_LINE_SERVO0) {
		if (axis == UINT32_MAX)
			return fail(c, "line.axis: required for servo_enable");
		fn += (int)axis;
	} else if (axis != UINT32_MAX) {
		return fail(c, "line.axis: only for servo_enable");
	}
	if (c->b->lines[fn].used)
		return fail(c, "line.function: duplicate '%s'",
			    line_names[fn < BK_LINE_SERVO0 ? fn : BK_LINE_SERVO0]);
	l.used = true;
	c->b->lines[fn] = l;
	return 0;
}

static int joystick_elem(bctx_t *c, const char **a)
{
	static const char *const ax[3] = {"x", "y", "rotation"};
	bk_joystick_t *j = &c->b->joystick;
	if (j->used)
		return fail(c, "joystick: duplicate element");
	for (; a[0]; a += 2) {
		int hit = 0;
		if (!strcmp(a[0], "device")) {
			if (a[1][0] != '/' || strlen(a[1]) >= sizeof(j->device))
				return fail(c, "joystick.device: not a device path '%s'", a[1]);
			snprintf(j->device, sizeof(j->device), "%s", a[1]);
			continue;
		}
		for (int i = 0; i < 3 && !hit; i++) {
			char n[32];
			if (!strcmp(a[0], ax[i])) {
				int code = libevdev_event_code_from_name(EV_ABS, a[1]);
				if (code < 0)
					return fail(c, "joystick.%s: not an ABS_ axis '%s'", a[0],
						    a[1]);
				j->code[i] = code;
				hit = 1;
			}
			snprintf(n, sizeof(n), "%s_invert", ax[i]);
			if (!hit && !strcmp(a[0], n)) {
				if (get_bool(c, "joystick", n, a[1], &j->invert[i]))
					return -1;
				hit = 1;
			}
			snprintf(n, sizeof(n), "%s_scale", ax[i]);
			if (!hit && !strcmp(a[0], n)) {
				if (get_double(c, "joystick", n, a[1], 0.0, false, 1.0, "0..1",
					       &j->scale[i]))
					return -1;
				hit = 1;
			}
		}
		if (!hit)
			return fail(c, "joystick.%s: unknown attribute", a[0]);
	}
	if (!j->device[0])
		return fail(c, "joystick.device: required");
	if (j->code[0] < 0 || j->code[2] < 0)
		return fail(c, "joystick.%s: required", j->code[0] < 0 ? "x" : "rotation");
	j->used = true;
	return 0;
}

/* Each element of <backends>: the section's own (depth 0), its children. */
static int backends_start(void *ctx, config_reader_t *r, const char *name, const char **atts,
			  int depth, unsigned long line)
{
	bctx_t *c = ctx;
	c->r = r;
	c->line = line;
	if (depth == 0)
		return atts[0] ? fail(c, "backends.%s: unknown attribute", atts[0]) : 0;
	if (depth != 1)
		return fail(c, "%s: unknown element", name);
	if (!strcmp(name, "drive"))
		return drive_elem(c, atts);
	if (!strcmp(name, "modbus"))
		return modbus_elem(c, atts);
	if (!strcmp(name, "canopen"))
		return canopen_elem(c, atts);
	if (!strcmp(name, "power"))
		return power_elem(c, atts);
	if (!strcmp(name, "battery"))
		return battery_elem(c, atts);
	if (!strcmp(name, "line"))
		return line_elem(c, atts);
	if (!strcmp(name, "joystick"))
		return joystick_elem(c, atts);
	return fail(c, "%s: unknown element", name);
}

/* A Modbus drive against its bus: the bus exists, the channel is one of
 * its profile's, unit and channel are its own, and the bus says how its
 * drives stop when the bus falls silent. */
static int modbus_drive_check(bctx_t *c, unsigned i)
{
	const backend_cfg_t *b = c->b;
	const bk_modbus_bus_t *m = &b->bus[b->drive_bus[i]];
	c->at_line = c->drive_line[i];
	if (!m->used)
		return fail(c, "drive.bus: no <modbus bus=\"%u\"> for axis %u", b->drive_bus[i], i);
	if (b->drive_channel[i] >= m->prof.channels)
		return fail(c, "drive.channel: profile %s has %u channel%s '%u'", m->prof.name,
			    m->prof.channels, m->prof.channels > 1 ? "s" : "", b->drive_channel[i]);
	for (unsigned j = 0; j < i; j++)
		if (b->drive_type[j] == BK_DRIVE_MODBUS && b->drive_bus[j] == b->drive_bus[i] &&
		    b->drive_unit[j] == b->drive_unit[i] &&
		    b->drive_channel[j] == b->drive_channel[i])
			return fail(
			    c, "drive.unit: also axis %u's unit and channel on modbus bus %u '%u'",
			    j, b->drive_bus[i], b->drive_unit[i]);
	if (m->prof.reg[MBP_COMM_TIMEOUT].words == 0 && !m->comm_stop_none) {
		c->at_line = c->modbus_line[b->drive_bus[i]];
		return fail(c,
			    "modbus.comm_stop: profile %s has no comm_timeout register: give "
			    "reg_comm_timeout, or comm_stop=\"none\" for drives that run on when "
			    "the bus falls silent '%s'",
			    m->prof.name, "drive");
	}
	return 0;
}

/* Cross-references, once every element is known. */
static int backends_finish(void *ctx, config_reader_t *r)
{
	bctx_t *c = ctx;
	const backend_cfg_t *b = c->b;
	c->r = r;
	for (unsigned i = 0; i < VS_MAX_AXES; i++)
		if (b->drive_type[i] == BK_DRIVE_MODBUS && modbus_drive_check(c, i))
			return -1;
	if (b->battery_source == BK_BATTERY_MODBUS && !b->bus[b->battery_mb.bus].used) {
		c->at_line = c->battery_line;
		return fail(c, "battery.bus: no <modbus bus=\"%u\"> for the battery",
			    b->battery_mb.bus);
	}
	for (unsigned i = 0; i < VS_MAX_AXES; i++) {
		if (b->drive_type[i] != BK_DRIVE_CIA402)
			continue;
		const bk_canopen_bus_t *co = &b->canopen[b->drive_bus[i]];
		c->at_line = c->drive_line[i];
		if (!co->used)
			return fail(c, "drive.bus: no <canopen bus=\"%u\"> for axis %u",
				    b->drive_bus[i], i);
		if (b->drive_node[i] == co->master_node)
			return fail(c, "drive.node: the master_node of canopen bus %u '%u'",
				    b->drive_bus[i], b->drive_node[i]);
		for (unsigned j = 0; j < i; j++)
			if (b->drive_type[j] == BK_DRIVE_CIA402 &&
			    b->drive_bus[j] == b->drive_bus[i] &&
			    b->drive_node[j] == b->drive_node[i])
				return fail(
				    c, "drive.node: also axis %u's node on canopen bus %u '%u'", j,
				    b->drive_bus[i], b->drive_node[i]);
	}
	return 0;
}

int backend_cfg_load_all(const char *vehicle_path, const char *io_path, vs_config_t *cfg,
			 hal_io_map_t *io_map, backend_cfg_t *b, char *err, size_t errlen)
{
	bctx_t c = {.b = b};
	const config_section_t sec = {
	    .name = "backends", .start = backends_start, .finish = backends_finish, .ctx = &c};
	backend_cfg_defaults(b);
	return config_load_sections(vehicle_path, io_path, cfg, io_map, &sec, 1, err, errlen);
}

int backend_cfg_load(const char *path, backend_cfg_t *b, char *err, size_t errlen)
{
	return backend_cfg_load_all(path, NULL, NULL, NULL, b, err, errlen);
}
