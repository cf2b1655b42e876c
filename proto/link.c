/* Serial link multiplexer: console lines and binary frames on one port. */
#include "link.h"

#include <string.h>

#include "fmt.h"
#include "numparse.h"

static void link_out(link_t *l, const uint8_t *data, size_t n)
{
	size_t done = 0;

	/* A port that stops taking bytes loses the rest of this answer only;
	 * the host's timeout and retry recover it. */
	while (done < n && l->io.write) {
		size_t k = l->io.write(l->io.ctx, data + done, n - done);

		if (k == 0)
			break;
		done += k;
	}
	l->tx_dropped += (uint32_t)(n - done);
}

static void frame_write(void *ctx, const uint8_t *data, size_t n)
{
	link_out(ctx, data, n);
}

static void console_write(void *ctx, const char *s, size_t n)
{
	link_out(ctx, (const uint8_t *)s, n);
}

static void console_bytes(void *ctx, const uint8_t *data, size_t n)
{
	link_t *l = ctx;

	console_feed(l->con, data, n);
}

static bool console_text(void *ctx)
{
	const link_t *l = ctx;

	return console_in_text(l->con);
}

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
		  (unsigned long)l->tx_dropped);
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

void link_init(link_t *l, console_t *con, const vs_link_t *io)
{
	memset(l, 0, sizeof(*l));
	l->io = *io;
	l->con = con;
	l->next_extra = con->extra;
	l->next_xctx = con->xctx;
	con->write = console_write;
	con->wctx = l;
	console_set_extra(con, link_extra, l);
	frame_srv_init(&l->fs, con->v, frame_write, l, console_bytes, l);
	frame_rx_set_hold(&l->fs.rx, console_text, l);
}

void link_feed(link_t *l, const uint8_t *data, size_t n, uint32_t now_ms)
{
	frame_srv_feed(&l->fs, data, n, now_ms);
}

size_t link_poll(link_t *l, uint32_t now_ms)
{
	uint8_t buf[256];
	size_t total = 0, n;
	unsigned rounds = 0;

	/* Bounded, so a flood cannot hold up the control tick. */
	while (l->io.read && rounds++ < 32 && (n = l->io.read(l->io.ctx, buf, sizeof(buf))) > 0) {
		link_feed(l, buf, n, now_ms);
		total += n;
	}
	frame_srv_poll(&l->fs, now_ms);
	return total;
}
