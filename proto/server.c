/* The unit's command server (see server.h). */
#include "server.h"

#include <string.h>

void server_init(vs_server_t *s, vehicle_t *v, console_extra_fn extra, void *xctx,
		 console_write_fn write, void *wctx)
{
	memset(s, 0, sizeof(*s));
	s->v = v;
	console_init(&s->con, v, write, wctx);
	if (extra)
		console_set_extra(&s->con, extra, xctx);
}

void server_attach_serial(vs_server_t *s, const vs_link_t *io)
{
	link_init(&s->serial, &s->con, io);
	s->has_serial = true;
}

/* What the port has, in bounded rounds so that a flood cannot hold up the
 * tick, then the frame receiver's inter-byte timeout. */
static void poll_serial(link_t *l, uint32_t now_ms)
{
	uint8_t buf[256];
	size_t n;
	unsigned rounds = 0;

	while (l->port.io.read && rounds++ < 32 &&
	       (n = l->port.io.read(l->port.io.ctx, buf, sizeof(buf))) > 0)
		frame_srv_feed(&l->fs, buf, n, now_ms);
	frame_srv_poll(&l->fs, now_ms);
}

void server_poll(vs_server_t *s, uint32_t now_us)
{
	/* A millisecond clock that runs on across now_us's wrap (71 min): the
	 * frame timeout compares differences of it. */
	s->us_rem += now_us - s->last_us;
	s->last_us = now_us;
	s->now_ms += s->us_rem / 1000u;
	s->us_rem %= 1000u;
	if (s->has_serial)
		poll_serial(&s->serial, s->now_ms);
	if (s->poll_can)
		s->poll_can(s, now_us);
}
