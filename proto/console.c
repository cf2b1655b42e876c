/* Bring-up console: spec section 7, driven by the command table.
 *
 * A line is checked in this order, and the first failure is the one reply:
 * length, control/non-ASCII bytes, operation name, argument count, each
 * argument left to right. Only a line that passes all of them reaches the
 * unit, so a bad line can never change its state or its queued motion.
 */
#include "console.h"

#include <string.h>

#include "cmdtab.h"
#include "dispatch.h"
#include "numparse.h"

/* Tokens kept per line: an operation needs at most 1 + CMD_MAX_FIELDS; '$'
 * commands get a few more. Further tokens are only counted. */
#define CONSOLE_ARGV_MAX 16

/* The reply under construction (console.h). */
typedef console_out_t rbuf_t;

static void rb_init(rbuf_t *r, char *buf, size_t cap, uint32_t *errors)
{
	r->buf = buf;
	r->cap = cap;
	r->len = 0;
	r->errors = errors;
	if (cap)
		buf[0] = '\0';
}

static size_t rb_room(const rbuf_t *r)
{
	return r->cap ? r->cap - 1 - r->len : 0;
}

static void rb_putn(rbuf_t *r, const char *s, size_t n)
{
	if (n > rb_room(r))
		n = rb_room(r);
	if (!n)
		return;
	memcpy(r->buf + r->len, s, n);
	r->len += n;
	r->buf[r->len] = '\0';
}

static void rb_puts(rbuf_t *r, const char *s)
{
	rb_putn(r, s, strlen(s));
}

static void rb_real(rbuf_t *r, vs_real_t v)
{
	char tmp[NP_FIXED3_MAX];

	rb_puts(r, console_real3(v, tmp));
}

static bool needs_hex(unsigned char b)
{
	return b < 0x20 || b >= 0x7f;
}

/* Written as it is inside quotes. */
static bool plain_byte(unsigned char b)
{
	return !needs_hex(b) && b != '"' && b != '\\';
}

/* A byte that is not plain, escaped into e: \" and \\, or \xHH for control
 * and non-ASCII bytes, so that a reply is always one printable line. */
static size_t escape_byte(char e[4], unsigned char b)
{
	const char *const hex = "0123456789ABCDEF"; /* one copy, shared */

	e[0] = '\\';
	if (b == '"' || b == '\\') {
		e[1] = (char)b;
		return 2;
	}
	e[1] = 'x';
	e[2] = hex[b >> 4];
	e[3] = hex[b & 15];
	return 4;
}

/* A double-quoted string (escape_byte). */
static void rb_quoted(rbuf_t *r, const char *s)
{
	rb_puts(r, "\"");
	for (const unsigned char *p = (const unsigned char *)s; *p;) {
		const unsigned char *run = p;
		char e[4];

		/* Plain bytes in one copy: a byte at a time costs a reply of
		 * alarm texts thousands of instructions on a microcontroller. */
		while (*p && plain_byte(*p))
			p++;
		rb_putn(r, (const char *)run, (size_t)(p - run));
		if (!*p)
			break;
		rb_putn(r, e, escape_byte(e, *p));
		p++;
	}
	rb_puts(r, "\"");
}

/* v in decimal at d, no terminator: its length (at most 20). */
static size_t put_uint(char *d, unsigned long v)
{
	char tmp[20];
	size_t k = 0, n;

	do {
		tmp[k++] = (char)('0' + v % 10);
		v /= 10;
	} while (v);
	for (n = 0; k;)
		d[n++] = tmp[--k];
	return n;
}

static const char *alarm_type_name(uint8_t t)
{
	switch (t) {
	case VS_ALARM_FAULT:
		return "fault";
	case VS_ALARM_WARNING:
		return "warning";
	default:
		return "unknown";
	}
}

/* One alarm, " code type "source"", at d (at most end - d bytes): its
 * length, or 0 when it does not fit whole. One pass over the source, which
 * need not be terminated by whoever filled it (VS_ALARM_SOURCE_MAX). */
static size_t put_alarm(char *d, const char *end, const vs_alarm_t *a)
{
	char *p = d, num[20];
	size_t k = put_uint(num, a->code);
	const char *t = alarm_type_name(a->type);
	size_t tl = strlen(t);

	if ((size_t)(end - p) < 1 + k + 1 + tl + 2)
		return 0;
	*p++ = ' ';
	memcpy(p, num, k);
	p += k;
	*p++ = ' ';
	for (size_t q = 0; q < tl; q++)
		*p++ = t[q];
	*p++ = ' ';
	*p++ = '"';
	for (size_t i = 0, j; i < VS_ALARM_SOURCE_MAX - 1 && a->source[i]; i = j + 1) {
		/* a run of plain bytes in one copy, then the byte that ends it */
		for (j = i; j < VS_ALARM_SOURCE_MAX - 1 && plain_byte((unsigned char)a->source[j]);
		     j++)
			;
		if ((size_t)(end - p) < j - i + 1)
			return 0;
		memcpy(p, a->source + i, j - i);
		p += j - i;
		if (j >= VS_ALARM_SOURCE_MAX - 1 || !a->source[j])
			break;
		char e[4];
		size_t el = escape_byte(e, (unsigned char)a->source[j]);
		if ((size_t)(end - p) < el + 1)
			return 0;
		memcpy(p, e, el);
		p += el;
	}
	*p++ = '"';
	return (size_t)(p - d);
}

/* " k", the alarm sequence's length */
static size_t put_count(char *d, uint16_t k)
{
	d[0] = ' ';
	return 1 + put_uint(d + 1, k);
}

/* The alarm sequence: its length, then "code type "source"" triples. When
 * the reply cannot hold them all (16 alarms of 63 escaped bytes would need
 * about 4.4 kB), only the alarms that fit whole are written and the length
 * says how many: the reply stays well-formed, the sequence still holds at
 * most numOfAlarm entries, and numOfActiveAlarm still tells the full count.
 * One pass over each source: measuring first and then copying cost a
 * microcontroller 2,500 instructions an alarm, a reply of 12 alarms two
 * control periods. */
static void rb_alarms(rbuf_t *r, const cmd_alarms_t *s)
{
	uint16_t n = s->n > VS_ALARM_LIST_MAX ? VS_ALARM_LIST_MAX : s->n;
	size_t at = r->len, cl;
	uint16_t k = 0;
	char cnt[3];

	if (rb_room(r) < 3)
		return;
	/* The length as if all fit (" 16" at most: 3 bytes held back), then
	 * the alarms that fit whole; in the rare reply that cuts them short,
	 * the length is put right, moving the alarms when it is shorter. */
	cl = put_count(r->buf + at, n);
	r->len += cl;
	for (; k < n; k++) {
		size_t l = put_alarm(r->buf + r->len, r->buf + r->cap - 1 - (3 - cl), &s->a[k]);

		if (!l)
			break;
		r->len += l;
	}
	if (k < n) {
		size_t kl = put_count(cnt, k);

		memmove(r->buf + at + kl, r->buf + at + cl, r->len - at - cl);
		memcpy(r->buf + at, cnt, kl);
		r->len -= cl - kl;
	}
	r->buf[r->len] = '\0';
}

static void rb_value(rbuf_t *r, char type, const cmd_value_t *v)
{
	switch (type) {
	case CMD_T_BOOL:
		rb_puts(r, v->b ? " true" : " false");
		break;
	case CMD_T_SHORT:
		console_put(r, " %d", v->h);
		break;
	case CMD_T_ULONG:
		console_put(r, " %lu", (unsigned long)v->u);
		break;
	case CMD_T_DOUBLE:
		rb_puts(r, " ");
		rb_real(r, v->d);
		break;
	case CMD_T_STRING:
		rb_puts(r, " ");
		rb_quoted(r, v->s ? v->s : "");
		break;
	case CMD_T_ALARMS:
		rb_alarms(r, &v->alarms);
		break;
	default:
		break;
	}
}

/* An extra's wrong argument count: "takes" the counts it takes, in words.
 * One format for them all (a board's flash counts its strings). */
static bool reply_arity(rbuf_t *r, const char *cmd, const char *takes, unsigned ntok)
{
	return console_fail(r, CONSOLE_E_ARITY, "%s takes %s, got %u", cmd, takes, ntok - 1);
}

static const char *mode_name(uint8_t m)
{
	static const char *const names[MOTION_MODE_COUNT] = {
#define MOTION_MODE_NAME(id, name) [id] = (name),
	    MOTION_MODES(MOTION_MODE_NAME)
#undef MOTION_MODE_NAME
	};

	return m < MOTION_MODE_COUNT ? names[m] : "?";
}

static void rb_q32(rbuf_t *r, q32_t v)
{
	rb_puts(r, " ");
#ifdef VS_REAL_Q32
	rb_real(r, v); /* the same number: one copy of the formatting */
#else
	char tmp[NP_FIXED3_MAX];

	np_fmt_q32_fixed3(v, tmp);
	rb_puts(r, strcmp(tmp, "-0.000") == 0 ? "0.000" : tmp);
#endif
}

static void rb_pose(rbuf_t *r, const fx_pose_t *p)
{
	rb_q32(r, p->x_mm);
	rb_q32(r, p->y_mm);
	rb_q32(r, p->th_deg);
}

/* $jerk [T R]: the jerk moves run at, mm/s^3 and deg/s^3 (0 = unlimited),
 * with the configured limits; the set form takes both or changes nothing. */
static bool exec_jerk(console_t *c, char **argv, unsigned ntok, rbuf_t *r)
{
	vs_real_t jt, jr;
	if (ntok != 1 && ntok != 3)
		return reply_arity(r, "$jerk", "0 or 2 arguments", ntok);
	if (ntok == 3) {
		if (np_parse_real(argv[1], &jt) != NP_OK || np_parse_real(argv[2], &jr) != NP_OK)
			return console_fail(r, CONSOLE_E_NUMBER, "$jerk: not a number");
		if (!vehicle_set_jerk(c->v, jt, jr))
			return console_fail(r, CONSOLE_E_EXTRA,
					    "$jerk: %s %s exceeds the limits or is below what "
					    "the tick rate holds",
					    argv[1], argv[2]);
	}
	vehicle_jerk(c->v, &jt, &jr);
	const vs_config_t *cfg = &c->v->cfg;
	const vs_real_t vals[4] = {jt, jr, cfg->jerk_limit_t_mm_s3, cfg->jerk_limit_r_deg_s3};
	rb_puts(r, "ok jerk");
	for (int i = 0; i < 4; i++) {
		rb_puts(r, i == 2 ? " limit " : " ");
		rb_real(r, vals[i]);
	}
	return true;
}

/* A row's IDL parameter list from its fields, where they are the IDL's
 * (commands.def: CMD_IDL_FLAT): "in double x_, out short state". */
static void rb_idl_flat(rbuf_t *r, const cmd_def_t *d)
{
	const char *sep = "";

	for (int out = 0; out < 2; out++) {
		const char *t = out ? d->out_types : d->in_types;

		for (unsigned k = 0; k < (out ? d->n_out : d->n_in); k++) {
			const char *p;
			size_t n = cmd_arg_name(d, out, k, &p);

			console_put(r, "%s%s %s %.*s", sep, out ? "out" : "in", cmd_type_idl(t[k]),
				    (int)n, p);
			sep = ", ";
		}
	}
}

static bool exec_extra(console_t *c, int argc, char **argv, unsigned ntok, rbuf_t *r,
		       cmd_scratch_t *scratch)
{
	static const char *const names[] = {"$help",	 "$jerk",    "$config",
					    "$watchdog", "$version", "$diag"};
	const char *cmd = argv[0];
	unsigned x = 0;

	/* one comparison loop for the console's own extras */
	while (x < sizeof names / sizeof names[0] && !np_streq_nocase(cmd, names[x]))
		x++;
	if (x == 0) {
		if (ntok == 1) {
			rb_puts(r, "ok");
			for (unsigned i = 0; i < CMD_COUNT; i++) {
				rb_puts(r, " ");
				rb_puts(r, cmd_table[i].name);
			}
			return true;
		}
		if (ntok == 2) {
			const cmd_def_t *d = cmd_by_name(argv[1]);

			if (!d)
				return console_fail(r, CONSOLE_E_EXTRA, "$help: no operation %s",
						    argv[1]);
			/* The IDL's own signature, structs whole. */
			const char *idl = cmd_idl(d);

			console_put(r, "ok %u boolean %s(", cmd_opcode(d), d->name);
			if (idl)
				rb_puts(r, idl);
			else
				rb_idl_flat(r, d);
			rb_puts(r, ")");
#ifndef VS_NO_HELP_TEXT
			if (d->help[0])
				console_put(r, ": %s", d->help);
#endif
			return true;
		}
		return reply_arity(r, "$help", "0 or 1 argument", ntok);
	}
	if (x == 1)
		return exec_jerk(c, argv, ntok, r);
	if (x == 2) {
#ifdef VS_NO_CONFIG_EXTRA
		/* Its configuration is compiled in. */
		(void)scratch;
		return console_fail(r, CONSOLE_E_EXTRA, "$config is not in this build");
#else
		/* $config save writes the saved form from the operations'
		 * scratch, free on a console line. */
		console_config(c, argv, ntok, r, scratch, sizeof *scratch);
		return true;
#endif
	}
	if (x == 3) {
		/* The link watchdog's timeout: read, or set for this run (0 =
		 * off; hands-on bring-up, a lockstep harness). */
		int64_t ms = 0;
		if (ntok > 2)
			return reply_arity(r, "$watchdog", "0 or 1 argument", ntok);
		if (ntok == 2 && np_parse_int(argv[1], 0, 60000, &ms) != NP_OK)
			return console_fail(r, CONSOLE_E_RANGE,
					    "$watchdog: %s is not a time in 0..60000 ms", argv[1]);
		if (ntok == 2)
			vehicle_set_link_timeout(c->v, (uint32_t)ms);
		console_put(r, "ok watchdog %lu", (unsigned long)vehicle_link_timeout(c->v));
		return true;
	}
	if (x < sizeof names / sizeof names[0]) {
		bool version = x == 4;

		if (ntok != 1)
			return reply_arity(r, cmd, "0 arguments", ntok);
		if (version) {
			const char *fw = "", *ifv = "";

			vs_getVersion(c->v, &fw);
			vs_getIFVersion(c->v, &ifv);
			rb_puts(r, "ok firmware ");
			rb_quoted(r, fw ? fw : "");
			rb_puts(r, " interface ");
			rb_quoted(r, ifv ? ifv : "");
			console_put(r, " protocol %d table 0x%04X", CMD_PROTO_VERSION,
				    (unsigned)cmd_table_crc());
		} else {
			vs_diag_t d;

			memset(&d, 0, sizeof(d));
			vehicle_diag(c->v, &d);
			console_put(r,
				    "ok ticks %lu overruns %lu late %lu max_late_us %lu mode %s "
				    "queue %u ref",
				    (unsigned long)d.ticks, (unsigned long)d.overruns,
				    (unsigned long)d.late_ticks, (unsigned long)d.max_late_us,
				    mode_name(d.mode), (unsigned)d.queue_len);
			rb_pose(r, &d.ref_pose);
			rb_puts(r, " odom");
			rb_pose(r, &d.odom_pose);
#ifndef VS_NO_CONFIG_EXTRA
			char tail[160];
			console_config_diag(c, tail, sizeof tail);
			rb_puts(r, tail);
#endif
		}
		return true;
	}
	if (c->extra && r->cap) {
		r->buf[0] = '\0';
		if (c->extra(c->xctx, argc, argv, r->buf, r->cap)) {
			r->buf[r->cap - 1] = '\0';
			r->len = strlen(r->buf);
			if (r->len == 0)
				rb_puts(r, "ok");
			if (strncmp(r->buf, "error", 5) == 0)
				c->errors++;
			return true;
		}
		r->buf[0] = '\0';
		r->len = 0;
	}
	return console_fail(r, CONSOLE_E_UNKNOWN_OP, "unknown command %s", cmd);
}

static bool is_space(char ch)
{
	return ch == ' ' || ch == '\t' || ch == '\r' || ch == '\n';
}

/* One line of len bytes (it may hold NUL bytes, which are garbage); the
 * reply goes to r, which keeps its length (a strlen over a long reply cost a
 * microcontroller 1,500 instructions). */
static bool exec_line(console_t *c, const char *line, size_t len, rbuf_t *r)
{
	char buf[CONSOLE_LINE_MAX + 1];
	char *argv[CONSOLE_ARGV_MAX + 1];
	unsigned ntok = 0;
	size_t i = 0;
	const cmd_def_t *d;
	cmd_value_t in[CMD_MAX_FIELDS], out[CMD_MAX_FIELDS];
	cmd_scratch_t scratch;
	bool ok;

	while (i < len && (line[i] == ' ' || line[i] == '\t'))
		i++;
	/* A comment is ignored whatever it holds (scripts may carry UTF-8) and
	 * however long it is. */
	if (i < len && line[i] == '#')
		return false;
	if (len > CONSOLE_LINE_MAX) {
		c->lines++;
		return console_fail(r, CONSOLE_E_TOO_LONG, "line too long (max %d bytes)",
				    CONSOLE_LINE_MAX);
	}
	for (size_t k = 0; k < len; k++) {
		unsigned char b = (unsigned char)line[k];

		if ((b < 0x20 && b != '\t' && b != '\r' && b != '\n') || b >= 0x7f) {
			c->lines++;
			return console_fail(r, CONSOLE_E_BINARY, "binary data in line");
		}
	}
	memcpy(buf, line, len);
	buf[len] = '\0';
	for (char *p = buf; *p;) {
		while (is_space(*p))
			*p++ = '\0';
		if (!*p)
			break;
		if (ntok < CONSOLE_ARGV_MAX)
			argv[ntok] = p;
		ntok++;
		while (*p && !is_space(*p))
			p++;
	}
	if (ntok == 0)
		return false;
	argv[ntok < CONSOLE_ARGV_MAX ? ntok : CONSOLE_ARGV_MAX] = NULL;
	c->lines++;

	if (argv[0][0] == '$') {
		if (ntok > CONSOLE_ARGV_MAX)
			return console_fail(r, CONSOLE_E_ARITY, "%s: too many arguments (%u)",
					    argv[0], ntok - 1);
		bool said = exec_extra(c, (int)ntok, argv, ntok, r, &scratch);
		if (said && r->len >= 2 && r->buf[0] == 'o' && r->buf[1] == 'k')
			vehicle_link_heard(c->v, VS_LINK_CONSOLE);
		return said;
	}

	d = cmd_by_name(argv[0]);
	if (!d)
		return console_fail(r, CONSOLE_E_UNKNOWN_OP, "unknown operation %s", argv[0]);
	if (ntok - 1 != d->n_in)
		return console_fail(r, CONSOLE_E_ARITY, "%s takes %u argument%s, got %u", d->name,
				    d->n_in, d->n_in == 1 ? "" : "s", ntok - 1);

	for (unsigned k = 0; k < d->n_in; k++) {
		const char *tok = argv[k + 1], *fn, *why = NULL;
		int fl = (int)cmd_arg_name(d, false, k, &fn), code = CONSOLE_E_NUMBER;
		char t = d->in_types[k];
		bool sh = t == CMD_T_SHORT;
		int64_t iv = 0, lo = sh ? INT16_MIN : 0, hi = sh ? INT16_MAX : (int64_t)UINT32_MAX;

		if (t == CMD_T_BOOL) {
			if (!np_parse_bool(tok, &in[k].b)) {
				why = CONSOLE_BAD_BOOL;
				code = CONSOLE_E_BOOL;
			}
		} else if (t == CMD_T_DOUBLE) {
			if (np_parse_real(tok, &in[k].d) != NP_OK)
				why = CONSOLE_BAD_NUMBER;
		} else if (sh || t == CMD_T_ULONG) {
			np_result_t pr = np_parse_int(tok, lo, hi, &iv);

			if (pr == NP_SYNTAX) {
				why = CONSOLE_BAD_NUMBER;
			} else if (pr == NP_RANGE) {
				why = CONSOLE_NOT_INTEGER;
				code = CONSOLE_E_RANGE;
			} else if (sh) {
				in[k].h = (int16_t)iv;
			} else {
				in[k].u = (uint32_t)iv;
			}
		} else {
			/* The table never has other in types; refuse rather than guess. */
			return console_fail(r, CONSOLE_E_NUMBER, "%s: unsupported argument type",
					    d->name);
		}
		if (why) {
			/* "CODE OP FIELD", then the text $config shares */
			console_fail(r, code, "%s %.*s", d->name, fl, fn);
			console_put(r, why, tok, (long long)lo, (long long)hi);
			return true;
		}
	}

	vehicle_link_heard(c->v, VS_LINK_CONSOLE);
	ok = cmd_invoke(c->v, d, in, out, &scratch);
	rb_puts(r, ok ? "ok true" : "ok false");
	for (unsigned k = 0; k < d->n_out; k++)
		rb_value(r, d->out_types[k], &out[k]);
	return true;
}

void console_init(console_t *c, vehicle_t *v, console_write_fn write, void *wctx)
{
	memset(c, 0, sizeof(*c));
	c->v = v;
	c->write = write;
	c->wctx = wctx;
	(void)cmd_table_crc(); /* now, so that $version and protocol info cost no tick */
}

void console_set_extra(console_t *c, console_extra_fn fn, void *ctx)
{
	c->extra = fn;
	c->xctx = ctx;
}

bool console_exec(console_t *c, const char *line, char *reply, size_t cap)
{
	/* Look no further than one byte past the limit beyond the leading
	 * blanks: enough to know the line is too long, and whether it is a
	 * comment. */
	size_t len = strspn(line, " \t");
	rbuf_t r;

	len += strnlen(line + len, CONSOLE_LINE_MAX + 1);

	rb_init(&r, reply, cap, &c->errors);
	return exec_line(c, line, len, &r);
}

static void emit(console_t *c, char *reply, size_t len)
{
	reply[len] = '\n';
	if (c->write)
		c->write(c->wctx, reply, len + 1);
}

static void end_line(console_t *c)
{
	char reply[CONSOLE_REPLY_MAX + 1];
	rbuf_t r;

	rb_init(&r, reply, CONSOLE_REPLY_MAX, &c->errors);
	if (exec_line(c, c->line, c->len, &r))
		emit(c, reply, r.len);
	c->len = 0;
}

void console_feed(console_t *c, const uint8_t *data, size_t n)
{
	for (size_t i = 0; i < n; i++) {
		uint8_t b = data[i];

		if (b == '\n' && c->last_cr) {
			c->last_cr = false;
			continue;
		}
		c->last_cr = b == '\r';
		if (b == '\r' || b == '\n') {
			c->in_line = c->text = false;
			end_line(c);
			continue;
		}
		{
			bool ascii = (b >= 0x20 && b < 0x7F) || b == '\t';

			c->text = c->in_line ? c->text && (ascii || b >= 0x80) : ascii;
			c->in_line = true;
		}
		if (c->len > CONSOLE_LINE_MAX) {
			/* Over-long: discarded whole at its ending, silently if it
			 * is a comment. Of the rest only the first non-blank byte
			 * matters, should the kept bytes all be blanks. */
			if (c->line[CONSOLE_LINE_MAX] == ' ' || c->line[CONSOLE_LINE_MAX] == '\t')
				c->line[CONSOLE_LINE_MAX] = (char)b;
			continue;
		}
		c->line[c->len++] = (char)b;
	}
}

void console_rx(void *console, const uint8_t *data, size_t n)
{
	console_feed(console, data, n);
}

bool console_holds_sync(void *console)
{
	return console_in_text(console);
}
