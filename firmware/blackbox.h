/* The black box: the last samples of the control loop in a ring that
 * freezes on the first fault (docs/protocol.md "Black box").
 *
 * The vehicle tick records one sample every `every` ticks, and always the
 * tick in which a fault was raised (or, for a fault raised between ticks,
 * the next tick): that sample is the trigger, the last one kept. Later
 * faults leave a frozen ring as it is (its fault code stays the first's).
 * bbox_clear empties the ring and re-arms it. Storage is the caller's, given
 * at init; a ring without storage records nothing.
 */
#ifndef BLACKBOX_H
#define BLACKBOX_H

#include <stdbool.h>
#include <stdint.h>

#include "config.h"
#include "fx.h"

/* One tick's sample, the columns of the simulator's trace the unit knows
 * (docs/trace.md): the end of the tick. */
typedef struct {
	fx_pose_t ref;		    /* commanded pose */
	fx_pose_t odo;		    /* odometry */
	fx_twist_t cmd;		    /* commanded body velocity per tick */
	int32_t sp_q8[VS_MAX_AXES]; /* wheel setpoints, counts/s Q8 */
	int32_t enc[VS_MAX_AXES];   /* encoder positions read, counts */
	uint32_t tick;		    /* ticks since init, this one counted */
	uint32_t newest_alarm;	    /* code of the newest active alarm, 0: none */
	int16_t state;		    /* getState code */
	uint8_t queue_len, alarms;  /* queued motions, active alarms */
} bbox_sample_t;

typedef enum { BBOX_OFF = 0, BBOX_ARMED = 1, BBOX_FROZEN = 2 } bbox_status_t;

typedef struct {
	bbox_sample_t *buf;
	uint16_t cap, every;  /* samples held; one sample every `every` ticks */
	uint16_t head, count; /* next slot to write; samples held */
	uint16_t phase;	      /* ticks since the last sample */
	uint8_t status;	      /* bbox_status_t */
	bool pending;	      /* a fault waits for its tick's sample */
	uint32_t fault;	      /* the fault that froze (or will freeze) it */
	uint32_t trigger;     /* the trigger sample's tick */
} blackbox_t;

/* cap samples at buf, one every `every` ticks (0 taken as 1); buf NULL or
 * cap 0: off, nothing recorded. */
void bbox_init(blackbox_t *b, bbox_sample_t *buf, uint16_t cap, uint16_t every);
/* The tick's decision: a sample due now (the decimation's turn, or a fault
 * waiting). Counts the tick. */
static inline bool bbox_due(blackbox_t *b)
{
	if (b->status != BBOX_ARMED)
		return false;
	if (++b->phase >= b->every || b->pending) {
		b->phase = 0;
		return true;
	}
	return false;
}
/* The slot the due sample goes to; bbox_commit keeps it (and freezes the
 * ring when a fault waits). */
static inline bbox_sample_t *bbox_slot(blackbox_t *b)
{
	return &b->buf[b->head];
}
void bbox_commit(blackbox_t *b);
/* A fault was raised: the first one while armed freezes the ring at the
 * sample of this tick (or of the next, between ticks). */
void bbox_fault(blackbox_t *b, uint32_t code);
/* Empties the ring and re-arms it (no effect when off). */
void bbox_clear(blackbox_t *b);
/* Sample i, 0 the oldest; NULL when i >= count. */
const bbox_sample_t *bbox_get(const blackbox_t *b, uint16_t i);

#endif
