/* Motion figures of the whole firmware on the simulated plant
 * (docs/performance.md, section 2b): per move, the error at Ready, the
 * overshoot, the time from the reference's end to Ready, the settle time,
 * the drift after Ready and the peak following error.
 *
 * A trace holds one sample per control tick (pm_trace_attach records every
 * tick of a sim); pm_measure computes the figures of one move from it;
 * pm_run runs a move of the table pm_moves on a new unit and does both, so
 * the bench (plantbench.c) and a test get the same figures from the same
 * run. Host only, doubles. Headings are compared modulo a turn.
 */
#ifndef BENCH_PLANTMETRICS_H
#define BENCH_PLANTMETRICS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "host_sim/sim.h"

typedef struct {
	double x, y, th; /* mm, mm, deg */
} pm_pose_t;

typedef struct {
	double t_s;	 /* simulated time at the end of the tick */
	pm_pose_t ref;	 /* the firmware's reference pose (vehicle_diag) */
	pm_pose_t odom;	 /* its odometry */
	pm_pose_t truth; /* the plant's true pose */
	/* Commanded twist in the world frame: mm/s, mm/s, deg/s. */
	double cmd_vx, cmd_vy, cmd_w;
	double wheel_mm_s; /* largest |true wheel speed| */
	int16_t state;	   /* getState code */
} pm_sample_t;

typedef struct {
	pm_sample_t *s;
	size_t n, cap;
} pm_trace_t;

void pm_trace_init(pm_trace_t *tr);
void pm_trace_free(pm_trace_t *tr);
/* Appends the state of s after its last tick (exits when out of memory). */
void pm_trace_sample(pm_trace_t *tr, sim_t *s);
/* Samples every later tick of s into tr (sim_set_tick_cb). */
void pm_trace_attach(pm_trace_t *tr, sim_t *s);

typedef struct {
	pm_pose_t target;
	bool at_ref_end; /* the target is where the reference ends (a stop) */
} pm_goal_t;

typedef struct {
	double pos_mm, th_deg; /* in-position band of the settle time */
	double rest_mm_s;      /* wheels at rest: every |speed| at most this */
	double drift_s;	       /* the window after Ready */
} pm_limits_t;

/* 0.05 mm, 0.01 deg, 0.1 mm/s (slower, a wheel moves less than the band
 * in the window), 0.5 s. */
void pm_limits_default(pm_limits_t *lim);

/* All times from the move's command; distances and angles are magnitudes. */
typedef struct {
	pm_pose_t target; /* the goal's, or where the reference ended */
	double ref_end_s; /* the end of the last tick with a commanded twist */
	double ready_s;	  /* the first Ready sample after the unit was Busy */
	double ready_ms;  /* ready_s - ref_end_s */
	/* From the reference's end until the true pose stays within the band
	 * round the target with the wheels at rest up to the window's end;
	 * NAN when it does not. */
	double settle_ms;
	double err_odom_mm, err_odom_deg; /* at Ready: odometry - target */
	double err_true_mm, err_true_deg; /* at Ready: true pose - target */
	/* Largest true travel past the target along the last commanded
	 * direction of travel (of rotation), from the last tick that commanded
	 * one to the window's end; 0 when never past or never commanded. */
	double over_mm, over_deg;
	double drift_true_mm, drift_true_deg; /* Ready to Ready + drift_s */
	double drift_odom_mm, drift_odom_deg;
	double follow_mm, follow_deg; /* largest reference - odometry, command to Ready */
} pm_result_t;

/* The figures of the move commanded just before sample `from` of tr.
 * Returns 0, or -1 when tr has no Ready after a Busy sample from `from` on,
 * or ends before Ready + lim->drift_s. */
int pm_measure(const pm_trace_t *tr, size_t from, const pm_goal_t *goal, const pm_limits_t *lim,
	       pm_result_t *out);

#define PM_MAX_LINES 12

typedef struct {
	const char *name;
	/* Console lines run first, then the unit runs until Ready and
	 * setup_wait_ms more (NULL-terminated; each must answer "ok true"). */
	const char *setup[PM_MAX_LINES];
	uint32_t setup_wait_ms;
	const char *cmd[PM_MAX_LINES]; /* the measured move, sent in one period */
	uint32_t stop_after_ms;	       /* nonzero: "stop" that long after cmd */
	pm_goal_t goal;
} pm_move_t;

/* The moves of section 2b (the unit at the origin, heading 0). */
extern const pm_move_t pm_moves[];
extern const size_t pm_num_moves;

enum { PM_OK = 0, PM_REFUSED = -1, PM_NO_READY = -2, PM_BAD_CONFIG = -3 };

/* Runs m on a new unit (cfg without the link watchdog, plant pp), powered
 * and servo on at the origin, until Ready and lim->drift_s after it,
 * recording every tick into tr (initialised; emptied first); *from receives the index of
 * the first sample after the measured command. PM_REFUSED when a line does
 * not answer "ok true" (the line in *bad_line when not NULL), PM_NO_READY
 * when Ready does not come within 120 s, PM_BAD_CONFIG when the unit does
 * not start (cfg rejected, or no memory). */
int pm_run(const pm_move_t *m, const vs_config_t *cfg, const plant_params_t *pp,
	   const pm_limits_t *lim, pm_trace_t *tr, size_t *from, pm_result_t *out,
	   const char **bad_line);

/* The base pushed at rest (plant_push: its own frame, mm, mm, deg). */
typedef struct {
	pm_pose_t truth_before, odom_before;
	pm_pose_t truth_pushed;		   /* right after the push */
	pm_pose_t truth_after, odom_after; /* watch_ms later */
	int16_t state_after;
} pm_push_t;

/* Pushes the base of s, runs watch_ms and reports where it was, where the
 * push put it and where it and its odometry are at the end: how the unit
 * answers a disturbance. False (nothing moves or runs) when plant_push
 * refuses the push. */
bool pm_push(sim_t *s, double dx_mm, double dy_mm, double dth_deg, uint32_t watch_ms,
	     pm_push_t *out);

#endif
