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

void server_poll(vs_server_t *s, uint32_t now_us)
{
	if (s->has_serial)
		link_poll(&s->serial, now_us / 1000u);
	if (s->poll_can)
		s->poll_can(s, now_us);
}
