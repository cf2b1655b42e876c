/* The unit's command server (see server.h). */
#include "server.h"

#include <string.h>

#include "bbox_wire.h"
#include "numparse.h"

/* The console's $bbox, before the main's own extras. */
static bool bbox_extra(void *ctx, int argc, char **argv, char *reply, size_t cap)
{
	vs_server_t *s = ctx;

	if (argc >= 1 && np_streq_nocase(argv[0], "$bbox")) {
		bbox_console(s->v, argc, argv, reply, cap);
		return true;
	}
	return s->main_extra ? s->main_extra(s->main_xctx, argc, argv, reply, cap) : false;
}

void server_init(vs_server_t *s, vehicle_t *v, console_extra_fn extra, void *xctx,
		 console_write_fn write, void *wctx)
{
	memset(s, 0, sizeof(*s));
	s->v = v;
	console_init(&s->con, v, write, wctx);
	s->main_extra = extra;
	s->main_xctx = xctx;
	console_set_extra(&s->con, bbox_extra, s);
}

void server_attach_serial(vs_server_t *s, const vs_link_t *io)
{
	link_init(&s->serial, &s->con, io);
}

void server_poll(vs_server_t *s, uint32_t now_us)
{
	/* A millisecond clock that runs on across now_us's wrap (71 min): the
	 * frame timeout compares differences of it. */
	s->us_rem += now_us - s->last_us;
	s->last_us = now_us;
	s->now_ms += s->us_rem / 1000u;
	s->us_rem %= 1000u;
	if (s->poll_serial)
		s->poll_serial(s, s->now_ms);
	if (s->poll_can)
		s->poll_can(s, now_us);
}
