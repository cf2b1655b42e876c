/* Client transport over the text console (docs/console.md): the same
 * client API for a unit reached only through its bring-up console.
 *
 * Each request becomes one console line, its "ok ..." reply is parsed back
 * into the wire encoding, so the library core cannot tell the links apart.
 * A console line carries no sequence number: only queries (get*, protocol
 * info) are retried, because a repeated motion line would run twice.
 * Doubles travel as %.17g text and return with the console's three
 * decimals.
 */
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "client.h"
#include "client_io.h"
#include "../console.h"
#include "../numparse.h"
#include "../../hal/posix/tty.h"

typedef struct {
	int fd;
	bool own;
	vc_client_t *c;
	char line[CONSOLE_REPLY_MAX + 2];
	size_t len;
	/* Bytes read past the end of the last line. */
	uint8_t pend[512];
	size_t npend;
} con_t;

/* Appends text to the request line; false when it does not fit. */
static bool put(char *buf, size_t cap, size_t *len, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static bool put(char *buf, size_t cap, size_t *len, const char *fmt, ...)
{
	va_list ap;
	int n;

	va_start(ap, fmt);
	n = vsnprintf(buf + *len, cap - *len, fmt, ap);
	va_end(ap);
	if (n < 0 || (size_t)n >= cap - *len)
		return false;
	*len += (size_t)n;
	return true;
}

/* One reply line into s->line (no line ending). */
static int read_line(con_t *s, uint64_t deadline)
{
	s->len = 0;
	for (;;) {
		while (s->npend) {
			uint8_t b = s->pend[0];

			memmove(s->pend, s->pend + 1, --s->npend);
			if (b == '\n' || b == '\r') {
				if (s->len == 0)
					continue; /* the LF of a CRLF, or a blank line */
				s->line[s->len] = '\0';
				return VC_OK;
			}
			/* An over-long line is cut; the parse then fails cleanly. */
			if (s->len < sizeof(s->line) - 1)
				s->line[s->len++] = (char)b;
		}
		{
			size_t got = 0;
			int e = vcio_read_some(s->fd, s->pend, sizeof(s->pend), deadline, &got);

			if (e != VC_OK)
				return e;
			s->npend = got;
			s->c->stats.bytes_rx += (uint32_t)got;
		}
	}
}

/* Next token of a reply: a bare word, or a quoted string with its escapes
 * undone into out. */
static bool next_tok(const char **pp, char *out, size_t cap)
{
	const char *p = *pp;
	size_t n = 0;

	while (*p == ' ')
		p++;
	if (!*p)
		return false;
	if (*p == '"') {
		p++;
		while (*p && *p != '"') {
			char ch = *p++;

			if (ch == '\\') {
				if (*p == 'x' && p[1] && p[2]) {
					char hex[3] = {p[1], p[2], 0};
					char *end;
					long v = strtol(hex, &end, 16);

					if (*end)
						return false;
					ch = (char)v;
					p += 3;
				} else if (*p == '"' || *p == '\\') {
					ch = *p++;
				} else {
					return false;
				}
			}
			if (n + 1 >= cap)
				return false;
			out[n++] = ch;
		}
		if (*p != '"')
			return false;
		p++;
	} else {
		while (*p && *p != ' ') {
			if (n + 1 >= cap)
				return false;
			out[n++] = *p++;
		}
	}
	out[n] = '\0';
	*pp = p;
	return true;
}

static bool parse_value(const char **pp, char type, cmd_value_t *v, char *str, size_t scap,
			vs_alarm_t *alarms)
{
	char tok[WIRE_STR_MAX + 1];
	int64_t iv;

	if (type != CMD_T_STRING && !next_tok(pp, tok, sizeof(tok)))
		return false;
	switch (type) {
	case CMD_T_BOOL:
		return np_parse_bool(tok, &v->b);
	case CMD_T_SHORT:
		if (np_parse_int(tok, INT16_MIN, INT16_MAX, &iv) != NP_OK)
			return false;
		v->h = (int16_t)iv;
		return true;
	case CMD_T_ULONG:
		if (np_parse_int(tok, 0, UINT32_MAX, &iv) != NP_OK)
			return false;
		v->u = (uint32_t)iv;
		return true;
	case CMD_T_DOUBLE:
		return np_parse_double(tok, &v->d) == NP_OK;
	case CMD_T_STRING:
		if (!next_tok(pp, str, scap))
			return false;
		v->s = str;
		return true;
	case CMD_T_ALARMS:
		if (np_parse_int(tok, 0, VS_ALARM_LIST_MAX, &iv) != NP_OK)
			return false;
		v->alarms.a = alarms;
		v->alarms.n = (uint16_t)iv;
		for (uint16_t i = 0; i < v->alarms.n; i++) {
			vs_alarm_t *a = &alarms[i];

			memset(a, 0, sizeof(*a));
			if (!next_tok(pp, tok, sizeof(tok)) ||
			    np_parse_int(tok, 0, UINT32_MAX, &iv) != NP_OK)
				return false;
			a->code = (uint32_t)iv;
			if (!next_tok(pp, tok, sizeof(tok)))
				return false;
			a->type = strcmp(tok, "fault") == 0	? VS_ALARM_FAULT
				  : strcmp(tok, "warning") == 0 ? VS_ALARM_WARNING
								: VS_ALARM_UNKNOWN;
			if (!next_tok(pp, a->source, sizeof(a->source)))
				return false;
		}
		return true;
	default:
		return false;
	}
}

static int build_line(unsigned opcode, const uint8_t *req, size_t req_len, char *line, size_t cap,
		      size_t *len)
{
	const cmd_def_t *d;
	cmd_value_t in[CMD_MAX_FIELDS];
	static wire_store_t st;

	*len = 0;
	if (opcode == WIRE_OP_INFO)
		return put(line, cap, len, "$version\n") ? VC_OK : VC_E_ARG;
	if (opcode == WIRE_OP_CONSOLE)
		return put(line, cap, len, "%.*s\n", (int)req_len, (const char *)req) ? VC_OK
										      : VC_E_ARG;
	d = cmd_by_opcode(opcode);
	if (!d || wire_decode_request(d, req, req_len, in, &st) != WIRE_ST_OK)
		return VC_E_ARG;
	if (!put(line, cap, len, "%s", d->name))
		return VC_E_ARG;
	for (unsigned i = 0; i < d->n_in; i++) {
		bool ok;

		switch (d->in_types[i]) {
		case CMD_T_BOOL:
			ok = put(line, cap, len, " %s", in[i].b ? "true" : "false");
			break;
		case CMD_T_SHORT:
			ok = put(line, cap, len, " %d", in[i].h);
			break;
		case CMD_T_ULONG:
			ok = put(line, cap, len, " %lu", (unsigned long)in[i].u);
			break;
		case CMD_T_DOUBLE:
			ok = put(line, cap, len, " %.17g", in[i].d);
			break;
		default:
			ok = false; /* no operation takes strings or sequences in */
			break;
		}
		if (!ok)
			return VC_E_ARG;
	}
	return put(line, cap, len, "\n") ? VC_OK : VC_E_ARG;
}

/* "ok protocol N table 0xHHHH" out of the $version reply. */
static int parse_info(const char *line, uint8_t *resp, size_t cap, size_t *resp_len)
{
	static const char tab[] = " table 0x";
	const char *p = strstr(line, " protocol ");
	char *end;
	unsigned long ver, crc;

	if (!p || cap < WIRE_INFO_LEN)
		return VC_E_PROTO;
	p += strlen(" protocol ");
	/* strtoul alone would take a sign or blanks: digits must follow. */
	if (*p < '0' || *p > '9')
		return VC_E_PROTO;
	ver = strtoul(p, &end, 10);
	if (ver > 255 || strncmp(end, tab, sizeof(tab) - 1) != 0)
		return VC_E_PROTO;
	p = end + sizeof(tab) - 1;
	if (!((*p >= '0' && *p <= '9') || (*p >= 'a' && *p <= 'f') || (*p >= 'A' && *p <= 'F')))
		return VC_E_PROTO;
	crc = strtoul(p, &end, 16);
	if (crc > 0xFFFF)
		return VC_E_PROTO;
	wire_info(resp); /* sizes and count as this host knows them */
	resp[0] = (uint8_t)ver;
	wire_put_u16(resp + 1, (uint16_t)crc);
	*resp_len = WIRE_INFO_LEN;
	return VC_OK;
}

static int parse_reply(con_t *s, unsigned opcode, uint8_t *resp, size_t cap, size_t *resp_len,
		       int *nak)
{
	static char strs[CMD_MAX_FIELDS][WIRE_STR_MAX + 1];
	static vs_alarm_t alarms[VS_ALARM_LIST_MAX];
	const cmd_def_t *d;
	const char *p = s->line;
	cmd_value_t out[CMD_MAX_FIELDS];
	char tok[16];
	bool r;

	if (opcode == WIRE_OP_CONSOLE) {
		/* the reply line itself, as a frame carries it */
		size_t n = strnlen(p, cap + 1);
		if (n > cap)
			return VC_E_PROTO;
		for (size_t i = 0; i < n; i++)
			resp[i] = (uint8_t)p[i];
		*resp_len = n;
		return VC_OK;
	}
	if (strncmp(p, "error ", 6) == 0) {
		long code = strtol(p + 6, NULL, 10);

		*nak = (int)code;
		snprintf(s->c->remote_msg, sizeof(s->c->remote_msg), "%s", p + 6);
		return VC_E_REMOTE;
	}
	if (strncmp(p, "ok", 2) != 0 || (p[2] != ' ' && p[2] != '\0'))
		return VC_E_PROTO;
	if (opcode == WIRE_OP_INFO)
		return parse_info(p, resp, cap, resp_len);
	d = cmd_by_opcode(opcode);
	p += 2;
	if (!d || !next_tok(&p, tok, sizeof(tok)) || !np_parse_bool(tok, &r))
		return VC_E_PROTO;
	for (unsigned i = 0; i < d->n_out; i++)
		if (!parse_value(&p, d->out_types[i], &out[i], strs[i], sizeof(strs[i]), alarms))
			return VC_E_PROTO;
	while (*p == ' ')
		p++;
	if (*p)
		return VC_E_PROTO;
	return wire_encode_response(d, r, out, resp, cap, resp_len) == WIRE_ST_OK ? VC_OK
										  : VC_E_PROTO;
}

static bool is_query(unsigned opcode)
{
	const cmd_def_t *d = cmd_by_opcode(opcode);

	return opcode == WIRE_OP_INFO || (d && strncmp(d->name, "get", 3) == 0);
}

static int con_exchange(void *ctx, unsigned opcode, const uint8_t *req, size_t req_len,
			uint8_t *resp, size_t cap, size_t *resp_len, int *nak, unsigned timeout_ms,
			unsigned retries)
{
	con_t *s = ctx;
	char line[CONSOLE_LINE_MAX + 2];
	size_t len;
	int e = build_line(opcode, req, req_len, line, sizeof(line), &len);

	if (e != VC_OK)
		return e;
	if (!is_query(opcode))
		retries = 0;
	s->c->stats.requests++;
	for (unsigned attempt = 0; attempt <= retries; attempt++) {
		uint64_t deadline;

		if (attempt)
			s->c->stats.retries++;
		/* Forget what a timed-out attempt may have left behind. */
		s->npend = 0;
		{
			uint8_t junk[256];

			while (read(s->fd, junk, sizeof(junk)) > 0)
				;
		}
		e = vcio_write_all(s->fd, (const uint8_t *)line, len, timeout_ms);
		if (e == VC_E_LINK)
			return e;
		s->c->stats.bytes_tx += (uint32_t)len;
		deadline = vcio_now_ms() + timeout_ms;
		for (;;) {
			e = read_line(s, deadline);
			if (e != VC_OK)
				break;
			/* Only "ok" and "error" lines answer a request. */
			if (strncmp(s->line, "ok", 2) == 0 || strncmp(s->line, "error", 5) == 0)
				break;
		}
		if (e == VC_E_LINK)
			return e;
		if (e == VC_OK)
			return parse_reply(s, opcode, resp, cap, resp_len, nak);
		s->c->stats.timeouts++;
	}
	return VC_E_TIMEOUT;
}

static void con_close(void *ctx)
{
	con_t *s = ctx;

	if (s->own)
		close(s->fd);
	free(s);
}

int vc_attach_console_fd(vc_client_t *c, int fd, bool own)
{
	con_t *s = calloc(1, sizeof(*s));
	vc_transport_t t = {0};

	if (!s) {
		errno = ENOMEM;
		return VC_E_LINK;
	}
	s->fd = fd;
	s->own = own;
	t.exchange = con_exchange;
	t.close = con_close;
	t.ctx = s;
	t.name = "console";
	vc_init(c, &t);
	s->c = c;
	return VC_OK;
}

int vc_open_console(vc_client_t *c, const char *dev, unsigned baud)
{
	int fd = tty_open(dev, baud);

	if (fd < 0)
		return VC_E_LINK;
	return vc_attach_console_fd(c, fd, true);
}
