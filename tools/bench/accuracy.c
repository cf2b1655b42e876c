/* Trajectory accuracy of the fixed-point motion engine against the
 * double-precision reference (tools/ref), tick by tick, and the cost of
 * both.
 *
 * The engine runs alone (motion_tick, its reference pose fed back as the
 * measured pose: a perfect plant), reference configuration: 1 kHz,
 * 500 mm/s, 90 deg/s, 500 mm/s^2, 180 deg/s^2, corner blend 200 mm.
 * For each motion it prints the endpoint error, the largest distance
 * between the two poses at the same tick, and the largest path deviation
 * (distance from each engine sample to the reference's sampled path).
 *
 * Under callgrind (tools/bench/accuracy.sh) the engine's and the
 * reference's ticks are counted separately (eng_tick, ref_tick), with one
 * dump per motion.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <valgrind/callgrind.h>

#include "firmware/motion.h"
#include "tools/bench/rig.h"
#include "tools/ref/ref_motion.h"

#define HZ	  1000
#define MAX_TICKS 100000
static const double Q = 4294967296.0;

static q32_t q(double v)
{
	return (q32_t)llround(v * Q);
}
static double d(q32_t v)
{
	return (double)v / Q;
}

typedef struct {
	double x, y, th;
} pt_t;

static pt_t eng_path[MAX_TICKS], ref_path[MAX_TICKS];
static motion_t eng;
static ref_t ref;

__attribute__((noinline)) void eng_tick(motion_t *m);
__attribute__((noinline)) bool ref_tick(ref_t *r);

void eng_tick(motion_t *m)
{
	fx_twist_t t;
	fx_pose_t meas = m->ref;
	motion_tick(m, &meas, &t);
}

bool ref_tick(ref_t *r)
{
	return ref_step(r);
}

static double wrap180(double a)
{
	a = fmod(a + 180.0, 360.0);
	if (a < 0)
		a += 360.0;
	return a - 180.0;
}

/* Distance from p to the segment a-b. */
static double seg_dist(pt_t p, pt_t a, pt_t b)
{
	double vx = b.x - a.x, vy = b.y - a.y, l2 = vx * vx + vy * vy;
	double t = l2 > 0 ? ((p.x - a.x) * vx + (p.y - a.y) * vy) / l2 : 0;
	t = t < 0 ? 0 : (t > 1 ? 1 : t);
	return hypot(p.x - a.x - t * vx, p.y - a.y - t * vy);
}

static int first_move(const pt_t *p, int n)
{
	for (int i = 0; i < n; i++)
		if (hypot(p[i].x, p[i].y) > 1e-8 || fabs(p[i].th) > 1e-8)
			return i;
	return 0;
}

/* Jerk for the jerk-limited runs (mm/s^3, deg/s^3; 0: none). */
static double jerk_t, jerk_r;

static void setup(void)
{
	motion_params_t p = {
	    .tick_hz = HZ,
	    .kin = MOTION_KIN_DIFF,
	    .vel_limit_t = q(1000),
	    .vel_limit_r = q(180),
	    .acc_limit_t = q(1000),
	    .acc_limit_r = q(360),
	    .cruise_blend_mm = q(200),
	};
	motion_init(&eng, &p);
	motion_set_velocity(&eng, q(500), q(90));
	motion_set_accel(&eng, q(500), q(180));
	motion_set_jerk(&eng, q(jerk_t), q(jerk_r));
	ref_params_t rp = {.hz = HZ,
			   .vt = 500,
			   .vr = 90,
			   .at = 500,
			   .ar = 180,
			   .jt = jerk_t,
			   .jr = jerk_r,
			   .blend_mm = 200};
	ref_init(&ref, &rp, (ref_pose_t){0, 0, 0});
}

static void fail(const char *what)
{
	fprintf(stderr, "accuracy: %s refused\n", what);
	exit(2);
}

static void run(const char *name, const char *what, pt_t target)
{
	int ne = 0, nr = 0;
	while (motion_has_work(&eng) && ne < MAX_TICKS) {
		eng_tick(&eng);
		eng_path[ne++] = (pt_t){d(eng.ref.x_mm), d(eng.ref.y_mm), d(eng.ref.th_deg)};
	}
	while (nr < MAX_TICKS && ref_tick(&ref))
		ref_path[nr++] = (pt_t){ref.pose.x, ref.pose.y, ref.pose.th};
	CALLGRIND_DUMP_STATS_AT(name);
	if (ne == 0 || nr == 0 || ne >= MAX_TICKS || nr >= MAX_TICKS) {
		fprintf(stderr, "accuracy: %s did not run to the end\n", name);
		exit(2);
	}
	/* Align the starts: ticks in which a side moves by less than 1e-6 mm
	 * and 1e-6 deg (a null turn) are not motion. */
	int e0 = first_move(eng_path, ne), r0 = first_move(ref_path, nr), off = e0 - r0;
	double same = 0, same_th = 0, dev = 0;
	int same_at = 0, dev_at = 0;
	int n = ne - off < nr ? ne - off : nr;
	for (int i = off < 0 ? -off : 0; i < n; i++) {
		pt_t ep = eng_path[i + off];
		double e = hypot(ep.x - ref_path[i].x, ep.y - ref_path[i].y);
		double et = fabs(wrap180(ep.th - ref_path[i].th));
		if (e > same) {
			same = e;
			same_at = i;
		}
		if (et > same_th)
			same_th = et;
	}
	/* Path deviation: nearest reference segment within +-200 ticks. */
	for (int i = 0; i < ne; i++) {
		double best = INFINITY;
		int lo = i - 200 < 0 ? 0 : i - 200, hi = i + 200 >= nr ? nr - 1 : i + 200;
		pt_t prev = lo == 0 ? (pt_t){0, 0, 0} : ref_path[lo - 1];
		for (int k = lo; k <= hi; k++) {
			double s = seg_dist(eng_path[i], prev, ref_path[k]);
			if (s < best)
				best = s;
			prev = ref_path[k];
		}
		if (best > dev) {
			dev = best;
			dev_at = i;
		}
	}
	pt_t ee = eng_path[ne - 1], re = ref_path[nr - 1];
	printf("%s: %s\n", name, what);
	printf("  ticks: engine %d, reference %d\n", ne, nr);
	printf("  endpoint: engine - reference %.3g mm, %.3g deg; engine - command %.3g mm, %.3g "
	       "deg\n",
	       hypot(ee.x - re.x, ee.y - re.y), fabs(wrap180(ee.th - re.th)),
	       hypot(ee.x - target.x, ee.y - target.y), fabs(wrap180(ee.th - target.th)));
	if (off != 0)
		printf(
		    "  the engine starts moving %d tick(s) later than the reference (at tick %d: "
		    "heading %.3g deg)\n",
		    off, e0, eng_path[e0 > 0 ? e0 - 1 : 0].th);
	printf("  largest distance at the same tick: %.3g mm (tick %d), %.3g deg\n", same, same_at,
	       same_th);
	printf("  largest path deviation: %.3g mm (tick %d)\n", dev, dev_at);
	printf("  calls: %s engine %d reference %d\n", name, ne, nr);
}

/* The single-piece moves, at the jerk set in jerk_t, jerk_r; sfx names
 * them ("" or "_jerk"). */
static void single_moves(const char *sfx, const char *at)
{
	char name[32], what[128];
	setup();
	if (!motion_forward(&eng, q(10000)) || !ref_forward(&ref, 10000))
		fail("forward");
	snprintf(name, sizeof(name), "line%s", sfx);
	snprintf(what, sizeof(what), "moveForward 10000 (10 m)%s", at);
	run(name, what, (pt_t){10000, 0, 0});

	setup();
	if (!motion_turn(&eng, q(360)) || !ref_turn(&ref, 360))
		fail("turn");
	snprintf(name, sizeof(name), "turn%s", sfx);
	snprintf(what, sizeof(what), "moveTurn 360%s", at);
	run(name, what, (pt_t){0, 0, 0});

	setup();
	if (!motion_circular_rel(&eng, 0, q(1000), q(90)) || !ref_arc(&ref, 0, 1000, 90))
		fail("arc");
	snprintf(name, sizeof(name), "arc%s", sfx);
	snprintf(what, sizeof(what), "moveCircularRel centre (0, 1000), 90 deg (1 m radius)%s", at);
	run(name, what, (pt_t){1000, 1000, 90});
}

/* The 10-waypoint route of tools/bench/rig.c, at the jerk set. */
static void route(const char *name, const char *what)
{
	double wp[ROUTE_N][2];

	setup();
	for (int i = 0; i < ROUTE_N; i++) {
		wp[i][0] = route_mm[i][0];
		wp[i][1] = route_mm[i][1];
		if (!motion_cruise_abs(&eng, q(wp[i][0]), q(wp[i][1])))
			fail(name);
	}
	if (!ref_cruise(&ref, (const double(*)[2])wp, ROUTE_N))
		fail("reference route");
	double hl = atan2(wp[ROUTE_N - 1][1] - wp[ROUTE_N - 2][1],
			  wp[ROUTE_N - 1][0] - wp[ROUTE_N - 2][0]) *
		    180 / M_PI;
	run(name, what, (pt_t){wp[ROUTE_N - 1][0], wp[ROUTE_N - 1][1], hl});
}

int main(void)
{
	single_moves("", "");

	route("cruise", "10-waypoint moveCruiseAbs route (tools/bench/rig.c)");

	/* The jerk-limited S-curve (traj.h, section 4) against the reference's
	 * own search and counting. */
	jerk_t = 2000;
	jerk_r = 1000;
	single_moves("_jerk", ", jerk 2000 mm/s^3, 1000 deg/s^3");

	/* The blended cruise under jerk limits: lines between the corner
	 * speeds (traj.h section 6), corners holding theirs. */
	route("cruise_jerk", "10-waypoint moveCruiseAbs route, jerk 2000 mm/s^3, 1000 deg/s^3");

	/* The continuous goal's online law (motion_seek.c) from rest against
	 * the reference's time-optimal S-curve over the same 1000 mm: how far
	 * the law that can be retargeted falls behind the planned profile. */
	setup();
	fx_pose_t g = {q(1000), 0, 0};
	if (!motion_continuous_rel(&eng, &g) || !ref_forward(&ref, 1000))
		fail("continuous");
	run("continuous_jerk",
	    "moveContinuousRel 1000 0 0 from rest, jerk 2000 mm/s^3, against the reference's "
	    "moveForward 1000",
	    (pt_t){1000, 0, 0});
	return 0;
}
