/* The command table: proto/commands.def as data, for the console, the binary
 * frames, the CAN mapping and the host client library.
 *
 * Every operation's in and out arguments are listed with a type code each
 * (CMD_T_*), so a transport can encode and decode any operation generically
 * into cmd_value_t arrays and run it with cmd_invoke() (dispatch.h).
 *
 * Table checksum (cmd_table_crc): CRC-16/CCITT-FALSE (poly 0x1021, init
 * 0xFFFF, no reflection, no final xor) over the rows in opcode order, each
 * serialised as the ASCII text
 *     <name> ':' <opcode in decimal> ':' <in type codes> ':' <out type codes> '\n'
 * e.g. "clearAlarm:1::\n" ... "getPosition:9::ddd\n". A host builds the same
 * text from its own copy of the table and compares, to know it speaks the
 * same command set as the unit.
 */
#ifndef CMDTAB_H
#define CMDTAB_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "../firmware/vehicle.h"

/* Bumped whenever a row's name, opcode or types change. */
#define CMD_PROTO_VERSION 1
/* Most in or out arguments of any operation (flattened). */
#define CMD_MAX_FIELDS 3

typedef enum {
	CMD_T_BOOL = 'b',
	CMD_T_SHORT = 'h',
	CMD_T_ULONG = 'u',
	CMD_T_DOUBLE = 'd',
	CMD_T_STRING = 's',
	CMD_T_ALARMS = 'a', /* sequence<Alarm> */
} cmd_type_t;

/* Opcodes, CMD_OP_<name>, fixed by the table. */
enum {
#define VS_CMD(name, op, it, in, ot, on, idl, help) CMD_OP_##name = (op),
#include "commands.def"
#undef VS_CMD
};

enum {
	CMD_COUNT = 0
/* One "+1" term per row; a fragment of the sum, so it cannot be parenthesised. */
#define VS_CMD(name, op, it, in, ot, on, idl, help) +1 /* NOLINT(bugprone-macro-parentheses) */
#include "commands.def"
#undef VS_CMD
};

#ifdef VS_CMD_PACKED
/* A board's row, 16 bytes rather than 28 (its flash counts them): the types
 * inline and not NUL-terminated, the in then the out field names in one
 * text, the IDL list after that text's NUL ("" where CMD_IDL_FLAT), and the
 * opcode the row's place. Read through the accessors below. */
typedef struct {
	const char *name;
	const char *names;
	char in_types[CMD_MAX_FIELDS], out_types[CMD_MAX_FIELDS];
	uint8_t n_in, n_out;
} cmd_def_t;
#else
typedef struct {
	const char *name;
	uint8_t opcode;
	uint8_t n_in, n_out;
	const char *in_types; /* cmd_type_t codes, one per field */
	const char *in_names; /* space-separated field names */
	const char *out_types;
	const char *out_names;
	const char *idl; /* the IDL's parameter list with structs whole ("in
			  * Point cruisePoint"); NULL where it is the fields'
			  * own ("in double x_"), which $help writes */
#ifndef VS_NO_HELP_TEXT
	const char *help;
#endif
} cmd_def_t;
#endif

/* The rows in opcode order: row i has opcode i + 1. */
extern const cmd_def_t cmd_table[CMD_COUNT];

/* A row's opcode, and its IDL parameter list (NULL where it is the fields'
 * own, CMD_IDL_FLAT), whichever the row's form. */
#ifdef VS_CMD_PACKED
#define cmd_opcode(d) ((unsigned)((d)-cmd_table) + 1u)
const char *cmd_idl(const cmd_def_t *d);
#else
#define cmd_opcode(d) ((unsigned)(d)->opcode)
#define cmd_idl(d)    ((d)->idl)
#endif

/* NULL when unknown. Names match case-insensitively. */
const cmd_def_t *cmd_by_name(const char *name);
const cmd_def_t *cmd_by_opcode(unsigned opcode);

/* Field i of a space-separated names list: returns its length and points
 * *start at it (length 0 when there is no such field). */
size_t cmd_field_name(const char *names, unsigned i, const char **start);
/* In (out false) or out (out true) field k of a row, as cmd_field_name. */
size_t cmd_arg_name(const cmd_def_t *d, bool out, unsigned k, const char **start);
/* IDL spelling of a type code ("boolean", "unsigned long", ...). */
const char *cmd_type_idl(char type);

/* CRC-16/CCITT-FALSE, continuing from crc (start with 0xFFFF). */
uint16_t cmd_crc16(uint16_t crc, const void *data, size_t n);
/* Checksum of the table (see the header comment). Computed on the first call
 * and kept: servers call it at start-up (console_init, canlink_init) so that
 * no request pays for it. A board built with VS_TABLE_CRC_CONST answers
 * CMD_TABLE_CRC instead (0.3 KiB of flash less); the tests assert that the
 * two agree, so a change to the table changes both. */
uint16_t cmd_table_crc(void);
#define CMD_TABLE_CRC 0x1F09

/* One decoded argument. Strings and alarms point into the unit or into the
 * caller's cmd_scratch_t and stay valid until the next call. */
typedef struct {
	const vs_alarm_t *a;
	uint16_t n;
} cmd_alarms_t;

typedef union {
	bool b;
	int16_t h;
	uint32_t u;
	vs_real_t d; /* real.h: a double on a host, Q32 on a board */
	const char *s;
	cmd_alarms_t alarms;
} cmd_value_t;

typedef struct {
	vs_alarm_t alarms[VS_ALARM_LIST_MAX];
	char msg[VS_STATE_MSG_MAX];
} cmd_scratch_t;

#endif
