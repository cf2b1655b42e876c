/* Serial link multiplexer: console lines and binary frames on one port. */
#include "link.h"

#include <string.h>

#include "fmt.h"
#include "numparse.h"

void link_format_stats(const link_t *l, char *buf, size_t cap)
{
	const frame_rx_stats_t *r = &l->fs.rx.st;
	const frame_srv_stats_t *s = &l->fs.st;

	fmt_print(buf, cap,
		  "ok frames %lu executed %lu duplicates %lu naks %lu crc %lu oversize %lu "
		  "truncated %lu other %lu txdrop %lu",
		  (unsigned long)r->frames, (unsigned long)s->executed,
		  (unsigned long)s->duplicates, (unsigned long)s->naks,
		  (unsigned long)r->crc_errors, (unsigned long)r->oversize,
		  (unsigned long)r->truncated, (unsigned long)r->other_bytes,
		  (unsigned long)l->port.dropped);
}

static bool link_extra(void *ctx, int argc, char **argv, char *reply, size_t cap)
{
	link_t *l = ctx;

	if (argc >= 1 && np_streq_nocase(argv[0], "$link")) {
		if (argc != 1)
			fmt_print(reply, cap, "error %d $link takes 0 arguments, got %d",
				  CONSOLE_E_ARITY, argc - 1);
		else
			link_format_stats(l, reply, cap);
		return true;
	}
	return l->next_extra ? l->next_extra(l->next_xctx, argc, argv, reply, cap) : false;
}

static bool link_line(void *ctx, const char *line, char *reply, size_t cap)
{
	return console_exec(ctx, line, reply, cap);
}

void link_init(link_t *l, console_t *con, const vs_link_t *io)
{
	memset(l, 0, sizeof(*l));
	l->port.io = *io;
	l->con = con;
	l->next_extra = con->extra;
	l->next_xctx = con->xctx;
	con->write = port_send_text;
	con->wctx = &l->port;
	console_set_extra(con, link_extra, l);
	frame_srv_init(&l->fs, con->v, port_send, &l->port, console_rx, con);
	frame_rx_set_hold(&l->fs.rx, console_holds_sync, con);
	frame_srv_set_line(&l->fs, link_line, con);
}
