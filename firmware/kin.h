/* Kinematics, wheel position loop and odometry, all fixed point.
 *
 * Body twist (vx, vy, w) <-> wheel surface travel per tick:
 *   differential: left = vx - w*T/2, right = vx + w*T/2      (w in rad)
 *   mecanum:      fl = vx - vy - w*(L+T)/2, fr = vx + vy + w*(L+T)/2,
 *                 rl = vx + vy - w*(L+T)/2, rr = vx - vy + w*(L+T)/2
 * with T the track width and L the wheel base.
 *
 * Each wheel follows a reference position integrated from the commanded
 * travel; the setpoint sent to the drive is the feed-forward speed plus
 * kp * (reference - measured), so drive lag and quantisation never
 * accumulate into pose error.
 *
 * Drive lag. A drive whose speed v follows its setpoint u with time
 * constant tau (v' = (u - v) / tau) tracks a reference speed v_r that
 * accelerates at a without error when u = v_r + tau * a: then
 * (v - v_r)' = -(v - v_r) / tau, and an error that is zero stays zero.
 * Without that term the wheel trails by tau * a while the reference
 * accelerates and, since the position loop has to win it back, overshoots
 * every stop by about tau * a * (braking time) * kp (1 mm at 1 m/s^2 on a
 * 20 ms drive). The reference is exact and discrete: its acceleration is
 * the change of its travel per tick, t_k - t_(k-1). The loop compares the
 * reference at the end of this tick with the position measured at its
 * start, so the wheel runs one tick ahead of the reference, and the
 * feed-forward leads by that tick as well:
 *   u_k = (t_k + (tau / h + 1) * (t_k - t_(k-1))) / h
 * (lag_q16 holds tau / h + 1; 0 for a drive configured without lag).
 * Measured on the simulated 20 ms drive: moveForward 1000 at 1 m/s^2
 * overshoots 0.014 mm instead of 1.06 mm (docs/performance.md).
 */
#ifndef KIN_H
#define KIN_H

#include <stdbool.h>
#include <stdint.h>

#include "fx.h"

/* The wheel arrangement: differential (two wheels) or mecanum (four). */
typedef enum {
	MOTION_KIN_DIFF = 0,
	MOTION_KIN_OMNI = 1,
} motion_kin_t;

/* Whether kin is mecanum (a build for one base knows: config.h). */
#ifdef VS_KIN_ONLY
#define KIN_OMNI(kin) ((void)(kin), VS_KIN_ONLY == MOTION_KIN_OMNI)
#else
#define KIN_OMNI(kin) ((kin) == MOTION_KIN_OMNI)
#endif

#define KIN_MAX_WHEELS 4

typedef struct {
	uint8_t kin; /* motion_kin_t */
	uint8_t n;   /* wheels: kin_init sets it from kin (2 or 4) */
	uint32_t tick_hz;
	q32_t counts_per_mm; /* Q32 */
	/* Wheel travel (mm) per degree of body rotation, Q32: (T/2)*pi/180 on a
	 * differential base, ((L+T)/2)*pi/180 on mecanum. */
	q32_t mm_per_deg;
	q32_t deg_per_mm; /* inverse of mm_per_deg, Q32 */
	int64_t kp_q16;	  /* position loop gain, 1/s, Q16 */
	/* Per wheel: the feed-forward's lead, tau / h + 1 ticks, Q16 (see
	 * above); 0 for a drive that follows its setpoint at once. */
	int64_t lag_q16[KIN_MAX_WHEELS];
} kin_params_t;

typedef struct {
	kin_params_t p;
	/* Per wheel: reference minus measured position in counts (Q32), and the
	 * last measured counts. */
	int64_t ref_counts_q32[KIN_MAX_WHEELS];
	int32_t last_meas[KIN_MAX_WHEELS];
	q32_t last_travel[KIN_MAX_WHEELS]; /* the reference's previous step */
	int64_t mm_per_count_q48; /* derived: odometry needs more than Q32 over kilometres */
	q32_t counts_per_deg;	  /* derived: wheel counts per degree of body rotation */
	bool synced;
} kin_t;

void kin_init(kin_t *k, const kin_params_t *p);

/* Body twist per tick -> wheel travel per tick (mm, Q32). */
void kin_body_to_wheels(const kin_params_t *p, const fx_twist_t *body, q32_t wheel_mm_pt[]);
/* Wheel travel (mm, Q32) -> body displacement (mm, deg, Q32). */
void kin_wheels_to_body(const kin_params_t *p, const q32_t wheel_mm[], fx_twist_t *body);

/* Take the measured encoder counts as the new reference (servo on, after a
 * fault, after setPosition); no motion results. */
void kin_sync(kin_t *k, const int32_t meas_counts[]);

/* One tick of the wheel loop: advance the references by the body twist,
 * read the measured counts, return drive setpoints (counts/s, Q8) and the
 * measured body displacement since the previous call (for odometry).
 * following_err_q32 (optional) receives the largest |ref - meas|, counts
 * in Q32. */
void kin_step(kin_t *k, const fx_twist_t *body, const int32_t meas_counts[], int32_t out_cps_q8[],
	      fx_twist_t *measured_delta, int64_t *following_err_q32);

/* The body displacement the wheel loop still has to make (every wheel's
 * reference minus measured, as a twist, mm and deg, Q32). */
void kin_pending(const kin_t *k, fx_twist_t *body);
/* Moves the wheel references by a body displacement with no feed-forward:
 * the position loop alone makes it, as it returns a pushed wheel. */
void kin_offset(kin_t *k, const fx_twist_t *body);

/* Integrate a body-frame displacement into a world pose (midpoint heading).
 * tc (optional) keeps the last heading's sine and cosine between calls. */
void odom_integrate(fx_pose_t *pose, const fx_twist_t *delta_body, fx_trig_cache_t *tc);

#endif
