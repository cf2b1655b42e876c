/* The black box as a file: the header row and one row per sample in the
 * trace's columns (proto/bbox_wire.h, docs/trace.md "Black box"), written
 * beside the path and renamed over it whole. */
#ifndef BBOXFILE_H
#define BBOXFILE_H

#include <errno.h>
#include <stdint.h>
#include <stdlib.h>

#include "../../firmware/blackbox.h"

/* The samples n of them, the one at tick trigger marked with fault (0: no
 * mark). Returns 0, or -1 with errno. */
int bbox_file_write(const char *path, const bbox_sample_t *const *s, uint32_t n, uint32_t tick_hz,
		    uint32_t trigger, uint32_t fault);
/* The unit's frozen black box; 0, or -1 with errno (EAGAIN: not frozen).
 * Inline: a client that links this file links no firmware. */
static inline int bbox_file_write_ring(const char *path, const blackbox_t *b, uint32_t tick_hz)
{
	const bbox_sample_t **s;
	int rc;

	if (b->status != BBOX_FROZEN) {
		errno = EAGAIN;
		return -1;
	}
	s = malloc(((size_t)b->count + 1u) * sizeof(const bbox_sample_t *));
	if (!s)
		return -1;
	for (uint16_t i = 0; i < b->count; i++)
		s[i] = bbox_get(b, i);
	rc = bbox_file_write(path, s, b->count, tick_hz, b->trigger, b->fault);
	free(s);
	return rc;
}

#endif
