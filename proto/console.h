/* Bring-up console: the line protocol of spec section 7.
 *
 * Bytes from the link are collected into lines (CR, LF or CRLF end a line);
 * each complete line yields exactly one reply line (none for an empty line
 * or a '#' comment, however long). A line longer than CONSOLE_LINE_MAX bytes
 * is discarded whole and answered with one error. Interface operations come from the
 * command table (proto/commands.def); bring-up extras start with '$' and
 * never change the meaning of an operation.
 */
#ifndef CONSOLE_H
#define CONSOLE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "../firmware/vehicle.h"

#define CONSOLE_LINE_MAX  255
#define CONSOLE_REPLY_MAX 1024

/* Console error codes ("error <code> <message>"). */
enum {
	CONSOLE_E_UNKNOWN_OP = 1, /* no such operation */
	CONSOLE_E_ARITY = 2,	  /* wrong number of arguments */
	CONSOLE_E_NUMBER = 3,	  /* not a number, or not finite */
	CONSOLE_E_RANGE = 4,	  /* integer out of its IDL type's range */
	CONSOLE_E_BOOL = 5,	  /* not a boolean */
	CONSOLE_E_TOO_LONG = 6,	  /* line over CONSOLE_LINE_MAX bytes */
	CONSOLE_E_BINARY = 7,	  /* control or non-ASCII bytes in the line */
	CONSOLE_E_EXTRA = 8,	  /* a '$' bring-up command failed */
};

/* A value that is not one, after "OP FIELD" (an operation's argument) or
 * "$config NAME": one copy of each text for both. Arguments: the token,
 * then the range's ends as long long. */
#define CONSOLE_BAD_BOOL    ": bad boolean %s (true|false|1|0|on|off)"
#define CONSOLE_BAD_NUMBER  ": bad number %s"
#define CONSOLE_NOT_INTEGER ": %s is not an integer in %lld..%lld"

typedef void (*console_write_fn)(void *ctx, const char *s, size_t n);
/* Handles a '$' command the console itself does not know. Returns false if
 * it does not know it either. reply gets one line without the newline. */
typedef bool (*console_extra_fn)(void *ctx, int argc, char **argv, char *reply, size_t cap);

struct cfgkeep;

typedef struct {
	vehicle_t *v;
	struct cfgkeep *keep; /* $config's changes and store; NULL: read only */
	console_write_fn write;
	void *wctx;
	console_extra_fn extra;
	void *xctx;
	/* The line; len CONSOLE_LINE_MAX + 1: over-long, the rest discarded
	 * (the last byte kept is the first non-blank one, for a comment). */
	char line[CONSOLE_LINE_MAX + 1];
	size_t len;
	bool last_cr; /* swallow the LF of a CRLF */
	bool in_line; /* bytes of a line received since the last line ending */
	bool text;    /* ... and they are a line of text (console_in_text) */
	uint32_t lines, errors;
} console_t;

void console_init(console_t *c, vehicle_t *v, console_write_fn write, void *wctx);
void console_set_extra(console_t *c, console_extra_fn fn, void *ctx);
/* $config changes, compares and saves through keep (firmware/config_keep.h,
 * attached to the same unit); without one it only reads. */
void console_set_keep(console_t *c, struct cfgkeep *keep);
/* A reply under construction (console.c, console_config.c): never written
 * past cap, NUL-terminated when cap > 0; an error counted in *errors
 * (NULL: not counted). */
typedef struct {
	char *buf;
	size_t cap, len;
	uint32_t *errors;
} console_out_t;
/* Appends, as fmt.h formats. */
__attribute__((format(printf, 2, 3))) void console_put(console_out_t *o, const char *fmt, ...);
/* Replaces the reply with "error CODE " and the text, counts the error;
 * true (the line is answered). */
__attribute__((format(printf, 3, 4))) bool console_fail(console_out_t *o, int code, const char *fmt,
							...);
/* The $config extra (console_config.c): the reply, "ok ..." or "error ...",
 * into o, which is empty; scratch: room for the saved form while $config
 * save writes it (VS_CFGSAVE_MAX bytes, firmware/config_save.h). */
void console_config(console_t *c, char **argv, unsigned ntok, console_out_t *o, void *scratch,
		    size_t scratch_cap);
/* What the configuration store held at start, as $config store answers it
 * without "ok " (a main's log line). */
void console_config_store(const struct cfgkeep *k, char *buf, size_t cap);
/* $diag's tail: " config store ..." when the store at start was written by
 * another table or did not read; empty otherwise. */
void console_config_diag(const console_t *c, char *buf, size_t cap);
/* A real as the console writes it, exactly three decimals, a value that
 * rounds to zero as 0.000, never -0.000: in tmp (NP_FIXED3_MAX bytes,
 * numparse.h) or a constant. */
const char *console_real3(vs_real_t v, char *tmp);
/* Feed received bytes; replies are written as whole lines ending in "\n". */
void console_feed(console_t *c, const uint8_t *data, size_t n);
/* The same two as the frame receiver's sinks (frame_other_fn, frame_hold_fn
 * on a console_t): on the serial link the bytes outside frames come here,
 * and a sync byte inside a line of text stays in the line. */
void console_rx(void *console, const uint8_t *data, size_t n);
bool console_holds_sync(void *console);
/* True while a line of text is in progress: its first byte was printable
 * ASCII (0x20..0x7E) or a tab, and every byte since has been printable
 * ASCII, a tab or 0x80..0xFF (UTF-8), up to its line ending. The serial
 * link gives a sync byte to such a line instead of starting a frame, so a
 * UTF-8 comment ("# \xC2\xA5 yen") stays a comment. A control byte ends
 * the state until the line ending (the line is answered error 7). */
static inline bool console_in_text(const console_t *c)
{
	return c->text;
}
/* Run one line (no line ending). Returns false when the line gets no reply
 * (empty or comment); otherwise reply holds the line without "\n". */
bool console_exec(console_t *c, const char *line, char *reply, size_t cap);

#endif
