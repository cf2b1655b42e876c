/* The command table (commands.def) as data, its checksum, and the one
 * dispatcher from decoded arguments to the vs_* operations. */
#include "cmdtab.h"

#include <string.h>

#include "numparse.h"

/* Row positions, to prove at compile time that opcodes are 1..N in order. */
enum {
#define VS_CMD(name, op, it, in, ot, on, idl, help) CMD_IDX_##name,
#include "commands.def"
#undef VS_CMD
};

#define VS_CMD(name, op, it, in, ot, on, idl, help)                                                \
	_Static_assert(CMD_IDX_##name + 1 == (op), "opcode of " #name " is not its row number");   \
	_Static_assert(sizeof(it) - 1 <= CMD_MAX_FIELDS, #name ": too many in fields");            \
	_Static_assert(sizeof(ot) - 1 <= CMD_MAX_FIELDS, #name ": too many out fields");
#include "commands.def"
#undef VS_CMD

/* A build short of flash (the Cortex-M4 board) leaves out the help lines:
 * $help NAME then gives the signature alone. */
#ifdef VS_NO_HELP_TEXT
#define CMD_HELP(h)
#else
#define CMD_HELP(h) , h
#endif

#ifdef VS_CMD_PACKED
/* The field names and the IDL list in one text: "in names out names\0idl"
 * (cmd_field_name skips the blank between them). */
#define CMD_IDL_FLAT ""

const cmd_def_t cmd_table[CMD_COUNT] = {
#define VS_CMD(name, op, it, in, ot, on, idl, help)                                                \
	{#name, in " " on "\0" idl, it, ot, (uint8_t)(sizeof(it) - 1), (uint8_t)(sizeof(ot) - 1)},
#include "commands.def"
#undef VS_CMD
};

const char *cmd_idl(const cmd_def_t *d)
{
	const char *idl = d->names + strlen(d->names) + 1;

	return *idl ? idl : NULL;
}

size_t cmd_arg_name(const cmd_def_t *d, bool out, unsigned k, const char **start)
{
	return cmd_field_name(d->names, out ? d->n_in + k : k, start);
}
#else
/* A row whose IDL list is its fields' (commands.def). */
#define CMD_IDL_FLAT NULL

const cmd_def_t cmd_table[CMD_COUNT] = {
#define VS_CMD(name, op, it, in, ot, on, idl, help)                                                \
	{#name, op, (uint8_t)(sizeof(it) - 1), (uint8_t)(sizeof(ot) - 1), it, in,                  \
	 ot,	on, idl CMD_HELP(help)},
#include "commands.def"
#undef VS_CMD
};

size_t cmd_arg_name(const cmd_def_t *d, bool out, unsigned k, const char **start)
{
	return cmd_field_name(out ? d->out_names : d->in_names, k, start);
}
#endif

/* A lookup is a binary search (comparing with every row cost a
 * microcontroller up to 1,700 instructions a request) over the rows as they
 * stand: the spec's order is the names' order, case aside
 * (tests/test_console.c asserts it), so no index by name is kept. */
const cmd_def_t *cmd_by_name(const char *name)
{
	unsigned lo = 0, hi = CMD_COUNT;

	while (lo < hi) {
		unsigned mid = (lo + hi) / 2;
		int c = np_cmp_nocase(name, cmd_table[mid].name);

		if (c == 0)
			return &cmd_table[mid];
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

/* Four bits at a time: the register's top nibble shifted out through the
 * polynomial (entry i: i << 12 after four shifts). A fifth of the bitwise
 * loop's instructions, for 32 bytes of table: every answer and stream
 * frame is checked. */
static const uint16_t crc_nibble[16] = {0x0000, 0x1021, 0x2042, 0x3063, 0x4084, 0x50A5,
					0x60C6, 0x70E7, 0x8108, 0x9129, 0xA14A, 0xB16B,
					0xC18C, 0xD1AD, 0xE1CE, 0xF1EF};

uint16_t cmd_crc16(uint16_t crc, const void *data, size_t n)
{
	const uint8_t *p = data;
	uint32_t c = crc; /* unsigned arithmetic throughout, cut to 16 bits at the end */

	while (n--) {
		c ^= (uint32_t)*p++ << 8;
		c = ((c << 4) & 0xFFFFu) ^ crc_nibble[(c >> 12) & 0xFu];
		c = ((c << 4) & 0xFFFFu) ^ crc_nibble[(c >> 12) & 0xFu];
	}
	return (uint16_t)c;
}

#ifndef VS_TABLE_CRC_CONST
static uint16_t table_crc_compute(void)
{
	uint16_t crc = 0xFFFF;

	for (unsigned i = 0; i < CMD_COUNT; i++) {
		const cmd_def_t *d = &cmd_table[i];
		char num[4];
		unsigned op = cmd_opcode(d), k = 0;

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
#endif

uint16_t cmd_table_crc(void)
{
#ifdef VS_TABLE_CRC_CONST
	return CMD_TABLE_CRC;
#else
	if (!table_crc_known) {
		table_crc = table_crc_compute();
		table_crc_known = true;
	}
	return table_crc;
#endif
}
