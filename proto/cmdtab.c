/* The command table (commands.def) as data, its checksum, and the one
 * dispatcher from decoded arguments to the vs_* operations. */
#include "cmdtab.h"

#include <string.h>

#include "numparse.h"

/* Row positions, to prove at compile time that opcodes are 1..N in order. */
enum {
#define VS_CMD(name, op, it, in, ot, on, help) CMD_IDX_##name,
#include "commands.def"
#undef VS_CMD
};

#define VS_CMD(name, op, it, in, ot, on, help)                                                     \
	_Static_assert(CMD_IDX_##name + 1 == (op), "opcode of " #name " is not its row number");   \
	_Static_assert(sizeof(it) - 1 <= CMD_MAX_FIELDS, #name ": too many in fields");            \
	_Static_assert(sizeof(ot) - 1 <= CMD_MAX_FIELDS, #name ": too many out fields");
#include "commands.def"
#undef VS_CMD

const cmd_def_t cmd_table[CMD_COUNT] = {
#define VS_CMD(name, op, it, in, ot, on, help)                                                     \
	{#name, op, (uint8_t)(sizeof(it) - 1), (uint8_t)(sizeof(ot) - 1), it, in, ot, on, help},
#include "commands.def"
#undef VS_CMD
};

static int lower(unsigned char ch)
{
	return (ch >= 'A' && ch <= 'Z') ? ch - 'A' + 'a' : ch;
}

/* strcmp, ignoring ASCII case */
static int cmp_nocase(const char *a, const char *b)
{
	while (*a && lower((unsigned char)*a) == lower((unsigned char)*b)) {
		a++;
		b++;
	}
	return lower((unsigned char)*a) - lower((unsigned char)*b);
}

/* The table's rows by name: a lookup is a binary search (comparing with
 * every row cost a microcontroller up to 1,700 instructions a request). */
static uint8_t by_name[CMD_COUNT];
static bool by_name_known;

static void by_name_sort(void)
{
	for (unsigned i = 0; i < CMD_COUNT; i++) {
		unsigned j = i;

		for (; j > 0 && cmp_nocase(cmd_table[by_name[j - 1]].name, cmd_table[i].name) > 0;
		     j--)
			by_name[j] = by_name[j - 1];
		by_name[j] = (uint8_t)i;
	}
	by_name_known = true;
}

const cmd_def_t *cmd_by_name(const char *name)
{
	unsigned lo = 0, hi = CMD_COUNT;

	if (!by_name_known)
		by_name_sort();
	while (lo < hi) {
		unsigned mid = (lo + hi) / 2;
		int c = cmp_nocase(name, cmd_table[by_name[mid]].name);

		if (c == 0)
			return &cmd_table[by_name[mid]];
		if (c < 0)
			hi = mid;
		else
			lo = mid + 1;
	}
	return NULL;
}

const cmd_def_t *cmd_by_opcode(unsigned opcode)
{
	if (opcode < 1 || opcode > CMD_COUNT)
		return NULL;
	return &cmd_table[opcode - 1];
}

size_t cmd_field_name(const char *names, unsigned i, const char **start)
{
	const char *p = names;

	for (;;) {
		size_t n;

		while (*p == ' ')
			p++;
		if (*p == '\0')
			break;
		n = strcspn(p, " ");
		if (i == 0) {
			*start = p;
			return n;
		}
		i--;
		p += n;
	}
	*start = p;
	return 0;
}

const char *cmd_type_idl(char type)
{
	switch (type) {
	case CMD_T_BOOL:
		return "boolean";
	case CMD_T_SHORT:
		return "short";
	case CMD_T_ULONG:
		return "unsigned long";
	case CMD_T_DOUBLE:
		return "double";
	case CMD_T_STRING:
		return "string";
	case CMD_T_ALARMS:
		return "SeqAlarm";
	default:
		return "?";
	}
}

uint16_t cmd_crc16(uint16_t crc, const void *data, size_t n)
{
	const uint8_t *p = data;
	uint32_t c = crc; /* unsigned arithmetic throughout, cut to 16 bits at the end */

	while (n--) {
		c ^= (uint32_t)*p++ << 8;
		for (int b = 0; b < 8; b++)
			c = (c & 0x8000u) ? (c << 1) ^ 0x1021u : c << 1;
		c &= 0xFFFFu;
	}
	return (uint16_t)c;
}

static uint16_t table_crc_compute(void)
{
	uint16_t crc = 0xFFFF;

	for (unsigned i = 0; i < CMD_COUNT; i++) {
		const cmd_def_t *d = &cmd_table[i];
		char num[4];
		unsigned op = d->opcode, k = 0;

		/* opcode in decimal, no leading zeros (at most 3 digits) */
		if (op >= 100)
			num[k++] = (char)('0' + op / 100);
		if (op >= 10)
			num[k++] = (char)('0' + op / 10 % 10);
		num[k++] = (char)('0' + op % 10);
		crc = cmd_crc16(crc, d->name, strlen(d->name));
		crc = cmd_crc16(crc, ":", 1);
		crc = cmd_crc16(crc, num, k);
		crc = cmd_crc16(crc, ":", 1);
		crc = cmd_crc16(crc, d->in_types, d->n_in);
		crc = cmd_crc16(crc, ":", 1);
		crc = cmd_crc16(crc, d->out_types, d->n_out);
		crc = cmd_crc16(crc, "\n", 1);
	}
	return crc;
}

/* The bitwise CRC over the whole table costs about 38,000 instructions on a
 * Cortex-M4, more than a 1 ms tick at 25 MHz: it runs once, from
 * console_init or canlink_init at start-up, never again from a request. */
static uint16_t table_crc;
static bool table_crc_known;

uint16_t cmd_table_crc(void)
{
	if (!by_name_known)
		by_name_sort(); /* with the checksum, at start-up (console_init) */
	if (!table_crc_known) {
		table_crc = table_crc_compute();
		table_crc_known = true;
	}
	return table_crc;
}

static vs_position_t in_pos(const cmd_value_t in[])
{
	vs_position_t p = {in[0].d, in[1].d, in[2].d};
	return p;
}

static vs_point_t in_point(const cmd_value_t in[])
{
	vs_point_t p = {in[0].d, in[1].d};
	return p;
}

static vs_velocity_t in_vel(const cmd_value_t in[])
{
	vs_velocity_t p = {in[0].d, in[1].d};
	return p;
}

bool cmd_invoke(vehicle_t *v, const cmd_def_t *d, const cmd_value_t in[], cmd_value_t out[],
		cmd_scratch_t *scratch)
{
	vs_position_t pos = {0, 0, 0};
	vs_velocity_t vel = {0, 0};
	bool r = false;

	/* Every out field starts defined, whatever the operation does. */
	for (unsigned i = 0; i < d->n_out; i++) {
		memset(&out[i], 0, sizeof(out[i]));
		if (d->out_types[i] == CMD_T_STRING)
			out[i].s = "";
		if (d->out_types[i] == CMD_T_ALARMS)
			out[i].alarms.a = scratch->alarms;
	}

	switch (d->opcode) {
	case CMD_OP_clearAlarm:
		return vs_clearAlarm(v);
	case CMD_OP_getAccelerationLimit:
		return vs_getAccelerationLimit(v, &out[0].d, &out[1].d);
	case CMD_OP_getActiveAlarm: {
		int16_t want = in[0].h;
		uint16_t len = 0;

		if (want < 0)
			want = 0;
		if (want > VS_ALARM_LIST_MAX)
			want = VS_ALARM_LIST_MAX;
		r = vs_getActiveAlarm(v, want, &out[0].h, scratch->alarms, &len);
		/* Never trust len beyond the buffer we offered. */
		out[1].alarms.n = len > (uint16_t)want ? (uint16_t)want : len;
		return r;
	}
	case CMD_OP_getBatteryVoltage:
		return vs_getBatteryVoltage(v, &out[0].d);
	case CMD_OP_getDefaultAcceleration:
		r = vs_getDefaultAcceleration(v, &vel);
		break;
	case CMD_OP_getDefaultVelocity:
		r = vs_getDefaultVelocity(v, &vel);
		break;
	case CMD_OP_getIFVersion:
		r = vs_getIFVersion(v, &out[0].s);
		if (!out[0].s)
			out[0].s = "";
		return r;
	case CMD_OP_getInput:
		return vs_getInput(v, in[0].u, &out[0].u);
	case CMD_OP_getPosition:
		r = vs_getPosition(v, &pos);
		out[0].d = pos.x;
		out[1].d = pos.y;
		out[2].d = pos.theta;
		return r;
	case CMD_OP_getServoStatus:
		return vs_getServoStatus(v, in[0].u, &out[0].b);
	case CMD_OP_getState:
		memset(scratch->msg, 0, sizeof(scratch->msg));
		r = vs_getState(v, &out[0].h, scratch->msg);
		scratch->msg[VS_STATE_MSG_MAX - 1] = '\0';
		out[1].s = scratch->msg;
		return r;
	case CMD_OP_getVelocityLimit:
		return vs_getVelocityLimit(v, &out[0].d, &out[1].d);
	case CMD_OP_getVersion:
		r = vs_getVersion(v, &out[0].s);
		if (!out[0].s)
			out[0].s = "";
		return r;
	case CMD_OP_moveCircularRel:
		return vs_moveCircularRel(v, in_point(in), in[2].d);
	case CMD_OP_moveContinuousRel:
		return vs_moveContinuousRel(v, in_pos(in));
	case CMD_OP_moveCruiseAbs:
		return vs_moveCruiseAbs(v, in_point(in));
	case CMD_OP_moveForward:
		return vs_moveForward(v, in[0].d);
	case CMD_OP_moveJog:
		return vs_moveJog(v, in[0].d, in[1].d, in[2].d);
	case CMD_OP_moveLinearAbs:
		return vs_moveLinearAbs(v, in_pos(in));
	case CMD_OP_moveLinearRel:
		return vs_moveLinearRel(v, in_pos(in));
	case CMD_OP_moveTurn:
		return vs_moveTurn(v, in[0].d);
	case CMD_OP_pause:
		return vs_pause(v);
	case CMD_OP_resume:
		return vs_resume(v);
	case CMD_OP_setAcceleration:
		return vs_setAcceleration(v, in_vel(in));
	case CMD_OP_setDigitalSensorLock:
		return vs_setDigitalSensorLock(v, in[0].b);
	case CMD_OP_setJogTimeout:
		return vs_setJogTimeout(v, in[0].h);
	case CMD_OP_setJoystick:
		return vs_setJoystick(v, in[0].b);
	case CMD_OP_setOutput:
		return vs_setOutput(v, in[0].u, in[1].u, in[2].u);
	case CMD_OP_setPosition:
		return vs_setPosition(v, in_pos(in));
	case CMD_OP_setPower:
		return vs_setPower(v, in[0].b);
	case CMD_OP_setServo:
		return vs_setServo(v, in[0].b);
	case CMD_OP_setVelocity:
		return vs_setVelocity(v, in_vel(in));
	case CMD_OP_stop:
		return vs_stop(v);
	case CMD_OP_unlock:
		return vs_unlock(v);
	default:
		return false;
	}
	/* getDefaultAcceleration / getDefaultVelocity */
	out[0].d = vel.translation;
	out[1].d = vel.rotation;
	return r;
}
