/* Double-precision reference of the motion the firmware produces for a
 * straight move, a turn in place, an arc and a blended waypoint route.
 *
 * Written from the motion law (firmware/traj.h: discrete-time profile with
 * exact landing, clothoid-pair corners, backward speed pass; with jerk
 * limits, the whole-tick S-curve of section 4 for a piece from rest to
 * rest, planned by exhaustive search and sampled by counting, and a cruise's
 * lines between the corner speeds on section 6's ramps, corners holding the
 * speed they are entered at) in plain double
 * arithmetic with libm, sharing no code with firmware/: the benchmarks
 * compare the fixed-point engine against it tick by tick. Lengths in mm,
 * angles in degrees, time in ticks.
 */
#ifndef REF_MOTION_H
#define REF_MOTION_H

#include <stdbool.h>

#define REF_MAX_PIECES 64
#define REF_TRI_MAX    4096 /* Na + Nj - 1 of a jerk-limited piece */

typedef struct {
	double x, y, th; /* th unwrapped: a full turn ends at 360 */
} ref_pose_t;

typedef struct {
	double hz;
	double vt, vr, at, ar; /* set values: mm/s, deg/s, mm/s^2, deg/s^2 */
	double jt, jr;	       /* jerks, mm/s^3, deg/s^3 (0: acceleration-limited) */
	double blend_mm;       /* corner tangent length limit */
} ref_params_t;

typedef enum { REF_LINE, REF_TURN, REF_ARC, REF_CORNER } ref_kind_t;

typedef struct {
	ref_kind_t kind;
	double len;	  /* mm (LINE, CORNER) or deg (TURN, ARC) */
	double vmax, a;	  /* per tick, per tick^2 */
	double vend;	  /* LINE into a corner: speed planned through it */
	double after;	  /* CORNER: length of the following line */
	double next_vend; /* CORNER: speed planned through the next corner (0: stop) */
	bool blend;	  /* flows into the next piece without stopping */
	bool cruise;	  /* a line of a cruise route */
	ref_pose_t p0;	  /* start pose */
	double ux, uy;	  /* LINE direction */
	double cx, cy;	  /* ARC centre */
	double dir;	  /* TURN/ARC sense, +-1 */
	double phi, lh;	  /* CORNER deflection (signed) and half length */
	ref_pose_t p1;	  /* end pose */
	double j;	  /* jerk per tick^3 (0: none): a whole-tick S-curve */
	long nv, na, nj;  /* its box lengths, planned when the piece starts */
	/* A cruise line under a jerk limit, between speeds (traj.h section 6):
	 * ramp cin -> w on boxes (na1, nj1), hold nk ticks, ramp w -> cout on
	 * (na2, nj2); planned on the line's first tick. */
	double cin, w, cout;
	long na1, nj1, na2, nj2, nk;
	double tri_cum[REF_TRI_MAX]; /* cumulative counts of the Na, Nj boxes */
} ref_piece_t;

typedef struct {
	ref_params_t p;
	ref_piece_t pc[REF_MAX_PIECES];
	int n, cur;
	double s, v;	/* progress in the current piece, speed per tick */
	long k;		/* ticks into a jerk-limited piece */
	double s_count; /* its position count S_k */
	double c1, c2;	/* a line between speeds: its ramps' counts so far */
	bool settle;	/* a jerk-limited piece landed: a tick at rest next */
	ref_pose_t pose;
} ref_t;

void ref_init(ref_t *r, const ref_params_t *p, ref_pose_t start);
/* Queue one motion; false when the pieces do not fit. */
bool ref_forward(ref_t *r, double dist_mm);
bool ref_turn(ref_t *r, double angle_deg);
/* Arc about a centre given in the vehicle frame at the start. */
bool ref_arc(ref_t *r, double cx_mm, double cy_mm, double angle_deg);
/* A blended route through n absolute waypoints, starting along the current
 * heading toward the first one (which must lie ahead). */
bool ref_cruise(ref_t *r, const double (*wp)[2], int n);
/* One tick; returns false once everything has been executed. */
bool ref_step(ref_t *r);

/* The profile primitives (per tick units), exposed for the self-check. */
double ref_brake(double u, double a);
double ref_umax(double d, double a);

#endif
