/* Trajectory generation (see traj.c header comment for the derivation). */
#ifndef TRAJ_H
#define TRAJ_H

#include <stdbool.h>
#include <stdint.h>

#include "fx.h"

/* Execution state of the active segment or velocity mode. */
typedef struct {
	uint8_t phase;
	q32_t s, len;         /* progress and length along the active primitive */
	q32_t v;              /* speed along it, per tick, >= 0 */
	q32_t ux_q30_dummy;
	int32_t ux, uy;       /* unit direction, Q30 */
	q32_t x0, y0, th0;    /* primitive start */
	q32_t cx, cy, r_mm;   /* arc centre and radius */
	q32_t sweep;          /* arc / turn sweep (signed) */
	int32_t sign;
} traj_exec_t;

#endif
