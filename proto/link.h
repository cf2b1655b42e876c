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

typedef struct {
	vs_link_t io;
	console_t *con;
	frame_srv_t fs;
	console_extra_fn next_extra; /* the console's own extra handler */
	void *next_xctx;
	uint32_t tx_dropped; /* bytes the port did not take */
} link_t;

/* Takes over con's output (console replies now go to io.write) and adds
 * "$link" in front of con's extra handler. con drives v. */
void link_init(link_t *l, console_t *con, const vs_link_t *io);
/* Reads everything pending on io.read and processes it, then applies the
 * frame inter-byte timeout. Never blocks. Returns the bytes read. */
size_t link_poll(link_t *l, uint32_t now_ms);
/* Processes received bytes directly (no io.read). */
void link_feed(link_t *l, const uint8_t *data, size_t n, uint32_t now_ms);
/* The counters as one "ok frames ..." line (no newline). */
void link_format_stats(const link_t *l, char *buf, size_t cap);

#endif
