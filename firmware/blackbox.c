/* The black box ring (blackbox.h). */
#include "blackbox.h"

#include <stddef.h>

FX_OUTLINE void bbox_init(blackbox_t *b, bbox_sample_t *buf, uint16_t cap, uint16_t every)
{
	b->buf = buf;
	b->cap = buf ? cap : 0;
	b->every = every ? every : 1;
	b->status = b->cap ? BBOX_ARMED : BBOX_OFF;
	b->head = 0;
	b->count = 0;
	b->phase = 0;
	b->pending = false;
	b->fault = 0;
	b->trigger = 0;
}

void bbox_commit(blackbox_t *b)
{
	uint32_t tick = b->buf[b->head].tick;

	b->head = (uint16_t)(b->head + 1u == b->cap ? 0u : b->head + 1u);
	if (b->count < b->cap)
		b->count++;
	if (b->pending) {
		b->pending = false;
		b->status = BBOX_FROZEN;
		b->trigger = tick;
	}
}

void bbox_fault(blackbox_t *b, uint32_t code)
{
	if (b->status != BBOX_ARMED || b->pending)
		return;
	b->pending = true;
	b->fault = code;
}

void bbox_clear(blackbox_t *b)
{
	if (b->status != BBOX_OFF)
		bbox_init(b, b->buf, b->cap, b->every);
}

const bbox_sample_t *bbox_get(const blackbox_t *b, uint16_t i)
{
	if (i >= b->count)
		return NULL;
	/* The oldest is at head once the ring has wrapped, else at 0. */
	uint32_t at = (b->count == b->cap ? b->head : 0u) + (uint32_t)i;
	if (at >= b->cap)
		at -= b->cap;
	return &b->buf[at];
}
