/* Trajectory generation in fixed point.
 *
 * 1. The speed profile along a path (traj_step)
 *
 * Time is discrete: each tick the path parameter advances by the speed u
 * chosen for that tick, s[k+1] = s[k] + u[k+1]. With acceleration a per
 * tick^2, braking from u by a each tick covers
 *
 *     B(u) = (u - a) + (u - 2a) + ... + (u - n a) = n u - a n (n + 1) / 2,
 *     n = floor(u / a),
 *
 * so the unit can still stop within the remaining distance d after moving u
 * this tick exactly when G(u) = u + B(u) <= d. G is continuous and strictly
 * increasing: on [n a, (n + 1) a) it is linear, G(u) = (n + 1) u - a n (n + 1) / 2,
 * and at u = n a it equals T(n) = a n (n + 1) / 2. The fastest admissible
 * speed is therefore, with n the largest integer such that T(n) <= d,
 *
 *     Umax(d) = (d + T(n)) / (n + 1).
 *
 * Each tick picks u = min(v + a, vmax, Umax(d)). The choice is never forced
 * to brake harder than a: G(u - a) = B(u) <= d - u, so Umax(d - u) >= u - a,
 * which is the invariant that keeps every sample's |du| <= a. When d < a,
 * Umax(d) = d: the last step covers the exact remainder, so endpoints land
 * to the raw unit (2^-32 mm or deg) with no overshoot. Integer division
 * rounds u down, which keeps G(u) <= d.
 *
 * A speed cap c at distance d ahead (a blended corner) is met by braking for
 * a virtual stop at d + B(c): at the cap the speed is within one tick's
 * acceleration of c, and inside the capped piece u is clamped to c.
 *
 * 2. Blended corners (moveCruiseAbs)
 *
 * A corner of deflection phi between two straight lines is a symmetric pair
 * of clothoids (curvature linear in path length): curvature rises from 0 to
 * kmax over a half-length Lh and falls back, so the heading along the corner
 * is psi (s / Lh)^2 on the first half and phi - psi ((2 Lh - s) / Lh)^2 on
 * the second, psi = phi / 2. Rotation rate w = v k is therefore continuous:
 * no rotational acceleration step where a line meets the curve.
 * With the unit clothoid half ending at (x1, y1) = (int_0^1 cos(psi u^2) du,
 * int_0^1 sin(psi u^2) du), the corner starts and ends at the tangent
 * distance T = Lh (x1 + y1 tan psi) from the waypoint, so Lh follows from the
 * tangent length the neighbouring segments leave free. Integrating the
 * series of cos and sin term by term gives x1 + i y1 = sum_n (i psi)^n /
 * (n! (2n + 1)) (psi in radians), each term from the last by a product: 15
 * terms reach 2^-30 for psi <= 85 degrees.
 * Speed in the corner is capped so that w = v kmax <= vr and the rotational
 * acceleration v^2 dk/ds + a k <= ar: v <= vr Lh / phi,
 * v <= Lh sqrt(ar / (2 phi)), a <= ar Lh / (2 phi) (angles in degrees).
 * A backward pass over the queued waypoints lowers each corner's speed so
 * that the unit can always brake to the next corner's speed and to a stop
 * at the last waypoint. Queueing a waypoint can only raise the corner
 * speeds before it, so the pass stops at the first corner that keeps its
 * speed. A pass left unfinished (motion_set_plan_budget) leaves the corners
 * it has not reached as they were. Their caps (rotation rate, rotational
 * acceleration) are set before any pass and never wait, and what they keep
 * is safe to run on: a queued waypoint or a raised limit only raises the
 * speeds a whole pass gives, a lowered line speed caps every piece at once,
 * and a lower acceleration (accepted at rest only) leaves braking distances
 * that are shorter than the new ones, which only slows the unit.
 * The engine integrates the reference through a corner at each step's
 * midpoint heading; with the heading exact, the integration arrives within
 * nanometres of the exit T beyond the waypoint, and the corner ends on that
 * exit, so the next line is the one planned when it was queued.
 *
 * 3. Braking cost
 *
 * While braking, Umax(d) is taken each tick at a distance that shrinks by
 * about u = n a, so its n falls by one a tick: starting from the last
 * tick's n, two products confirm it and the square root is not needed.
 *
 * 4. Jerk-limited rest-to-rest profile (traj_sc_*)
 *
 * Let b_N be N ticks of 1/N (a box summing to 1). The speed profile
 *
 *     u = d (b_Nv * b_Na * b_Nj)        (* is convolution)
 *
 * covers exactly d, and its differences are those of its boxes, with
 * Delta b_N = (delta_0 - delta_N) / N:
 *
 *     speed  u <= d / Nv
 *     accel  Delta u = (d / Nv) (g - g(. - Nv)),  g = b_Na * b_Nj <= 1 / Na
 *     jerk   Delta^2 u = d / (Nv Na) (b_Nj - b_Nj(. - Na) - b_Nj(. - Nv)
 *                                     + b_Nj(. - Na - Nv)).
 *
 * With Na >= Nj and Nv >= Na + Nj the four jerk pulses (and the two
 * acceleration humps) do not overlap, so the profile never exceeds speed
 * d / Nv, acceleration d / (Nv Na) and jerk d / (Nv Na Nj): a 7-phase
 * S-curve (jerk +J, 0, -J, cruise, -J, 0, +J) whose phases are whole ticks,
 * Nv + Na + Nj - 2 ticks long. Every time-optimal continuous rest-to-rest
 * profile has this shape with Tj = min(A / J, sqrt(V / J), cbrt(d / 2J)),
 * Ta >= Tj and Tv = max(d / V, Ta + Tj) (speed and acceleration reached,
 * or only one, or neither), so the planner searches the integers around
 * them for the shortest (Nv, Na, Nj) meeting
 *
 *     d / Nv <= V,  d / (Nv Na) <= A,  d / (Nv Na Nj) <= J.
 *
 * Sampling: with P = Nv Na Nj the convolution's integer counts c_k
 * (speed), a_k = c_k - c_(k-1) and the jerk count j_k = a_k - a_(k-1) in
 * {-1, 0, +1} (which pulse covers k) give the position after step k as
 * floor(d S_k / P), S_k = c_0 + ... + c_k. So d a / P, d c / P and d S / P
 * advance by additions of (quotient, remainder) pairs over P: no
 * multiplication or division per tick, and S ends at P, so the piece lands
 * on d to the raw unit. Flooring moves a position by less than one raw
 * unit, which shifts a speed by less than 1, an acceleration by less than
 * 2 and a jerk by less than 4 units: the plan keeps that far below V, A and
 * J, so the sampled steps stay within the limits exactly.
 *
 * 5. Jerk-limited change of speed (traj_jslew)
 *
 * One derivative down, a change of speed is the profile of section 1:
 * the speed still to change plays the distance, the acceleration plays the
 * speed, the jerk the acceleration, and amax the speed cap. traj_step then
 * gives the next acceleration, which lands on the target speed exactly,
 * never changes by more than j and never exceeds amax; an acceleration
 * pointing away from the target (a new target, a brake from accelerating)
 * is first turned round at j.
 *
 * 6. Jerk-limited line between speeds (traj_ln_*)
 *
 * From speed c_in to c_out (both at zero acceleration) over exactly len:
 * a ramp to the line speed w, K ticks at w, a ramp to c_out,
 *
 *     u = c_in + (w - c_in) G1 + (c_out - w) G2(. - L1 - K),
 *
 * G = H * b_Na * b_Nj the step through two boxes (section 4): it rises
 * from 0 to 1 in L = Na + Nj - 1 ticks, at most 1 / Na a tick and 1 /
 * (Na Nj) a tick^2, so a ramp of Delta needs Delta / Na <= A and
 * Delta / (Na Nj) <= J (Na >= Nj). Its steps sum to L - (Na + Nj - 2) / 2,
 * so a ramp of Delta, sampled by traj_sc_next as the rise of a profile
 * that never comes down (Nv beyond reach, d / P = Delta / (Na Nj)), covers
 * Delta L beyond its start speed less R(Delta) = floor(Delta (Na + Nj) / 2)
 * below its end speed:
 *
 *     D(w, K) = c_in L1 +- R(|w - c_in|) + w (K + L2) - R(w - c_out).
 *
 * With the box lengths fixed (planned for the largest Delta they serve),
 * D grows with w by B = (Na1 + Nj1) / 2 + K + (Na2 + Nj2) / 2 - 1 (up to
 * the floors' 1) per raw unit, which is less than the N = L1 + K + L2
 * ticks of the line: some integer w leaves a remainder r = len - D in
 * [0, N), and r more steps of one raw unit, spread evenly (the k-th tick
 * gets floor(r (k + 1) / N) - floor(r k / N)), land the line on len. The
 * spread adds at most 1 to a speed, 1 to a change of speed and 2 to a
 * jerk, the ramps' floors at most 1 and 3 beyond the exact values: the
 * plan keeps the line speed 1, A 2 and J 5 raw units below the limits.
 * The spread's first tick adds 0 (r < N), so the line starts at c_in.
 * When even w = max(c_in, c_out) with a tick more covers too much, the
 * hold takes the rest: the remainder r as a bump above w, or what the
 * tick more covers too much as a dip below w, each the rest-to-rest
 * S-curve of section 4 (within the limits on its own, as the hold has
 * none of the ramps' acceleration; a tick at w either side), and the line
 * lands with no remainder.
 *
 * The line speed is the fastest w that fits with K = 0, to 1/256 of it,
 * by bisection; each trial plans both ramps' boxes, the shortest of four
 * candidates Nj around min(A / J, sqrt(Delta / J)) with Na = max(Nj,
 * ceil(Delta / A), ceil(Delta / (J Nj))), and ceil(Delta / (J Nj)) =
 * ceil(ceil(Delta / J) / Nj): one wide division per ramp, the rest in a
 * 32-bit core's word.
 */
#ifndef TRAJ_H
#define TRAJ_H

#include <stdbool.h>
#include <stdint.h>

#include "fx.h"

/* Braking distance B(u) at a per tick^2. */
q32_t traj_brake_dist(q32_t u, q32_t a);
/* Largest u with u + B(u) <= d. */
q32_t traj_umax(q32_t d, q32_t a);
/* Next speed along a path with d remaining (d >= 0), current speed v,
 * cap vmax, acceleration a. */
q32_t traj_step(q32_t v, q32_t d, q32_t vmax, q32_t a);
/* The same results, given a guess of Umax's step count n (the largest with
 * T(n) <= d), which they update: while braking, n falls by one a tick, so
 * last tick's count replaces the square root. Any other guess (-1: none)
 * falls back to the full search. Keep the guess for one a only. */
q32_t traj_umax_near(q32_t d, q32_t a, int64_t *n_guess);
q32_t traj_step_near(q32_t v, q32_t d, q32_t vmax, q32_t a, int64_t *n_guess);
/* Largest speed from which braking at a reaches at most c within d. */
q32_t traj_reach(q32_t d, q32_t c, q32_t a);

/* An acceleration with its reciprocal, for the planning pass: the same
 * results as traj_brake_dist and traj_umax, with a product and a correction
 * step in place of each division by a (a 64-bit division is a library call
 * of some 100 instructions on a 32-bit microcontroller, and the pass over a
 * full queue of waypoints makes several per waypoint). */
typedef struct {
	q32_t a;
	uint64_t inv; /* floor((2^64 - 1) / a), 0 for a <= 0 */
} traj_rate_t;
void traj_rate_init(traj_rate_t *r, q32_t a);
q32_t traj_brake_dist_r(q32_t u, const traj_rate_t *r);
q32_t traj_umax_r(q32_t d, const traj_rate_t *r);

/* A planned jerk-limited rest-to-rest profile and its sampler (section 4).
 * Limits per tick (speed), tick^2, tick^3, in raw units. */
typedef struct {
	int64_t vm, am, jm;	    /* the limits less the rounding margins */
	int64_t nv, na, nj, p;	    /* box lengths, P = Nv Na Nj */
	int64_t ticks, k;	    /* steps in all, steps taken */
	int64_t qd, rd;		    /* d = qd P + rd */
	int64_t aq, ar, cq, cr, sq; /* d a / P, d c / P, d S / P: quotient, remainder */
	int64_t sr;
} traj_sc_t;

/* Plans d (> 0) at speed v, acceleration a and jerk j; false when the
 * limits leave no room for the rounding margins or the profile is too long
 * to sample (P >= 2^62). */
bool traj_sc_plan(traj_sc_t *p, q32_t d, q32_t v, q32_t a, q32_t j);
/* The next step (0 once the profile is complete); the steps sum to d. */
q32_t traj_sc_next(traj_sc_t *p);
/* An upper bound on traj_sc_plan's ticks for d (> 0) at a and j with no
 * speed cap. */
int64_t traj_sc_ticks_bound(q32_t d, q32_t a, q32_t j);
/* x y for x >= 0, y > 0, saturating at INT64_MAX. */
int64_t traj_mul_sat(int64_t x, int64_t y);
/* A planned jerk-limited line between speeds and its sampler (section 6). */
typedef struct {
	int64_t dsign;		    /* a dip above w (1), below (-1), or none (0) */
	int64_t na1, nj1, na2, nj2; /* the ramps' box lengths (0: no ramp) */
	int64_t cin, w, cout;	    /* speeds in, on the line, out */
	int64_t l1, hold, n;	    /* ticks: first ramp, at w, in all (< 0: planning) */
	int64_t r, racc, k;	    /* the spread remainder, its sum, ticks taken */
	/* Last: a plan sets the members above afresh, these as it needs them. */
	traj_sc_t ramp; /* the ramp running (phases 0 and 2) */
	traj_sc_t dip;	/* off w in the hold, when dsign is not 0 */
} traj_ln_t;

/* Plans len (> 0) from speed cin to cout (each at most v - 1) at speed at
 * most v, acceleration a and jerk j; false when the line is too short to
 * go from cin to cout with w >= cout, or the limits leave no room for the
 * margins. */
bool traj_ln_plan(traj_ln_t *p, q32_t len, q32_t cin, q32_t cout, q32_t v, q32_t a, q32_t j);
/* The same plan in parts: at most `fits` trial lines of the search (the
 * rest counts as two), then it returns -1 with p->n < 0, and a call with
 * the same inputs and p as left goes on; 1: planned, 0: as a false from
 * traj_ln_plan. A call with p->n >= 0 begins afresh. */
int traj_ln_plan_part(traj_ln_t *p, q32_t len, q32_t cin, q32_t cout, q32_t v, q32_t a, q32_t j,
		      int64_t fits);
/* The next step: the steps sum to len over p->n ticks, then cout each. */
q32_t traj_ln_next(traj_ln_t *p);
/* One tick of a jerk-limited change of the speed *v toward target (section
 * 5); *acc is the last tick's change and becomes this tick's. Returns the
 * new speed. */
q32_t traj_jslew(q32_t *v, q32_t *acc, q32_t target, q32_t amax, q32_t j);

/* Geometry of a blended corner with tangent length t_mm and deflection
 * phi_deg (signed, |phi| < 180). */
typedef struct {
	q32_t phi_deg;	/* signed deflection */
	q32_t lh_mm;	/* half length */
	q32_t t_mm;	/* tangent length: waypoint to corner start and end */
	q32_t k_mm_deg; /* Lh / |phi|: speed cap per unit rotation rate */
	q32_t vacc_pt;	/* Lh sqrt(ar / (2 |phi|)): speed cap from rotational acceleration */
	q32_t acc_pt2;	/* ar Lh / (2 |phi|): path acceleration cap in the corner */
	q32_t inv_lh;	/* 2^(62 + TRAJ_INV_LH_SH) / Lh (raw): see traj_corner_u */
} traj_corner_t;

/* The reciprocal of Lh carries 20 bits more than s / Lh in Q30 needs: 30 or
 * more significant bits for any Lh up to 2^20 mm (the bare 2^62 / Lh had 22
 * at Lh = 168 mm, and the two clothoid halves met with a 2.5e-5 degree
 * step). Lh of at least 2^20 raw (2.4e-4 mm) keeps it below 2^63. */
#define TRAJ_INV_LH_SH 20

/* x / Lh in Q30 for 0 <= x <= 2 Lh (the product stays below 2^52). */
static inline int64_t traj_corner_u(const traj_corner_t *c, q32_t x)
{
	return fx_mul_fit(x, c->inv_lh) >> TRAJ_INV_LH_SH;
}

/* Plans a corner: returns false when no blend is possible (deflection too
 * close to a reversal, or no room). ar_pt2 is the rotational acceleration
 * in force (deg/tick^2, Q32). */
bool traj_corner_plan(traj_corner_t *c, q32_t phi_deg, q32_t t_avail_mm, q32_t ar_pt2);
/* The caps of a planned corner that follow from ar_pt2 (> 0): vacc_pt and
 * acc_pt2. The shape does not depend on it, so a new rotational
 * acceleration changes only these. */
void traj_corner_rates(traj_corner_t *c, q32_t ar_pt2);
/* Heading change from the corner start at path length s (0..2 Lh); inline,
 * as every corner tick evaluates it. */
static inline q32_t traj_corner_heading(const traj_corner_t *c, q32_t s)
{
	q32_t psi = c->phi_deg / 2;
	q32_t lh = c->lh_mm;
	if (s <= 0)
		return 0;
	if (s >= 2 * lh)
		return c->phi_deg;
	/* u = s / Lh (Q30) by the reciprocal: no division on the tick path. */
	bool second = s > lh;
	int64_t u = traj_corner_u(c, second ? 2 * lh - s : s);
	if (u > FX_Q30_ONE)
		u = FX_Q30_ONE;
	int32_t u2 = (int32_t)((u * u) >> 30);
	q32_t th = fx_mul_q30(psi, u2);
	return second ? c->phi_deg - th : th;
}

#endif
