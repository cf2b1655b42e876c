/* The serial command link: one byte stream shared by the console and the
 * binary frames.
 *
 * Bytes are told apart by the frame sync byte (FRAME_SYNC, 0xA5): outside a
 * frame, a sync byte starts one unless a console line of text is in progress
 * (console_in_text: the UTF-8 of a comment may hold 0xA5), and every other
 * byte belongs to the console. The
 * bytes of a failed frame candidate after its sync go back to the console
 * path (which rejects a line with binary bytes), so both sides resynchronise.
 * Console replies and frame answers go out whole, never interleaved.
 *
 * The console extra "$link" reports the link counters:
 *   ok frames N executed N duplicates N naks N crc N oversize N truncated N
 *   other N txdrop N
 */
#ifndef LINK_H
#define LINK_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "../hal/link.h"
#include "console.h"
#include "frame.h"
#include "port.h"

typedef struct {
	port_t port;
	console_t *con;
	frame_srv_t fs;
	console_extra_fn next_extra; /* the console's own extra handler */
	void *next_xctx;
} link_t;

/* Wires con and a frame server to one port: bytes outside frames go to the
 * console, every answer to the port (port.h), "$link" in front of con's
 * extra handler. con drives v. Nothing of the link is called back: the
 * frame receiver feeds the console itself (console_rx, console_holds_sync). */
void link_init(link_t *l, console_t *con, const vs_link_t *io);
/* Processes received bytes; the owner reads the port (server_poll, or the
 * board one byte at a time). */
static inline void link_feed(link_t *l, const uint8_t *data, size_t n, uint32_t now_ms)
{
	frame_srv_feed(&l->fs, data, n, now_ms);
}
/* The counters as one "ok frames ..." line (no newline). */
void link_format_stats(const link_t *l, char *buf, size_t cap);

#endif
