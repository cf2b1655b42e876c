/* CSV trace of a simulation, one row per control tick (or every Nth).
 *
 * Columns (header row written first, exactly these names; for users in
 * docs/trace.md, which tests/python/test_plot.py holds to the header):
 *   time_s                          simulated time at the end of the tick
 *   cmd_x_mm,cmd_y_mm,cmd_th_deg    commanded (reference) pose
 *   odo_x_mm,odo_y_mm,odo_th_deg    measured pose (odometry)
 *   true_x_mm,true_y_mm,true_th_deg true plant pose
 *   cmd_vx_mm_s,cmd_vy_mm_s,cmd_w_deg_s  commanded body velocity
 *   sp0_cps..sp3_cps                wheel setpoints sent to the drives, counts/s
 *   meas0_cps..meas3_cps            true wheel speeds, counts/s
 *   state                           getState code (decimal, e.g. 17 = Busy)
 *   queue_len                       queued motion commands
 *   alarms                          active alarms (getActiveAlarm's count)
 *   newest_alarm                    code of the newest active alarm, 0: none
 *   enc0..enc3                      encoder positions the unit read, counts
 * Axes a base does not have read 0.
 */
#ifndef TRACE_H
#define TRACE_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "../firmware/vehicle.h"
#include "plant.h"

typedef struct {
	FILE *f;
	bool own;	/* opened by trace_open, closed by trace_close */
	uint32_t every; /* write every Nth call of trace_tick */
	uint32_t count;
	int16_t last_state; /* a change of state is flushed at once */
} trace_t;

/* Opens path for writing and writes the header. Returns 0 or -1 (errno). */
int trace_open(trace_t *t, const char *path, uint32_t every);
/* Uses an already open stream (e.g. open_memstream in tests). */
void trace_attach(trace_t *t, FILE *f, uint32_t every);
/* Called once per tick; writes a row on every Nth call. */
void trace_tick(trace_t *t, double time_s, vehicle_t *v, const plant_t *pl);
/* Flushes, closes an owned stream. Returns 0 or -1 if a write failed. */
int trace_close(trace_t *t);

#endif
