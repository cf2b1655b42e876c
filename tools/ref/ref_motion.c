/* Double-precision reference motion (see ref_motion.h). Independent of
 * firmware/: exact trigonometry, Gauss-Legendre quadrature for the
 * clothoids, closed-form profile bounds. */
#include "ref_motion.h"

#include <math.h>

#define DEG  (M_PI / 180.0)
#define TINY 1e-6

static double wrap180(double a)
{
	a = fmod(a + 180.0, 360.0);
	if (a < 0)
		a += 360.0;
	return a - 180.0;
}

/* ---- speed profile (same law as traj.h, derived again in double) ----- */

/* Distance covered braking from u by a each tick until below a. */
double ref_brake(double u, double a)
{
	if (u <= 0 || a <= 0)
		return 0;
	double n = floor(u / a);
	return n * u - a * n * (n + 1) / 2;
}

/* Largest u from which u + brake(u) <= d: with T(n) = a n (n+1) / 2 the
 * largest T(n) <= d, u = (d + T(n)) / (n + 1). */
double ref_umax(double d, double a)
{
	if (d <= 0)
		return 0;
	double n = floor((sqrt(1.0 + 8.0 * d / a) - 1.0) / 2.0);
	while (n > 0 && a * n * (n + 1) / 2 > d)
		n--;
	while (a * (n + 1) * (n + 2) / 2 <= d)
		n++;
	return (d + a * n * (n + 1) / 2) / (n + 1);
}

static double step(double v, double d, double vmax, double a)
{
	double u = v + a;
	if (u > vmax)
		u = fmax(vmax, v - a);
	if (u < 0)
		u = 0;
	if (u + ref_brake(u, a) <= d)
		return u;
	double w = ref_umax(d, a);
	return w < v - a ? v - a : w;
}

/* Largest speed that can still brake to c within d. */
static double reach(double d, double c, double a)
{
	return ref_umax(fmax(d, 0) + ref_brake(c, a) + c, a);
}

/* ---- clothoid pair ---------------------------------------------------- */

/* 5-point Gauss-Legendre nodes and weights on [-1, 1]. */
static const double gl_x[5] = {0.0, -0.5384693101056831, 0.5384693101056831, -0.9061798459386640,
			       0.9061798459386640};
static const double gl_w[5] = {0.5688888888888889, 0.4786286704993665, 0.4786286704993665,
			       0.2369268850561891, 0.2369268850561891};

/* End point of the unit half clothoid turning by psi (radians):
 * (int_0^1 cos(psi u^2) du, int_0^1 sin(psi u^2) du). */
static void unit_half(double psi, double *x1, double *y1)
{
	enum { PANELS = 256 };
	double sx = 0, sy = 0, h = 1.0 / PANELS;
	for (int k = 0; k < PANELS; k++) {
		double mid = (k + 0.5) * h;
		for (int j = 0; j < 5; j++) {
			double u = mid + gl_x[j] * h / 2;
			sx += gl_w[j] * cos(psi * u * u);
			sy += gl_w[j] * sin(psi * u * u);
		}
	}
	*x1 = sx * h / 2;
	*y1 = sy * h / 2;
}

/* Heading change at s along a corner of deflection phi, half length lh. */
static double corner_heading(const ref_piece_t *c, double s)
{
	double psi = c->phi / 2;
	if (s <= 0)
		return 0;
	if (s >= 2 * c->lh)
		return c->phi;
	if (s <= c->lh)
		return psi * (s / c->lh) * (s / c->lh);
	double r = (2 * c->lh - s) / c->lh;
	return c->phi - psi * r * r;
}

/* ---- queueing --------------------------------------------------------- */

void ref_init(ref_t *r, const ref_params_t *p, ref_pose_t start)
{
	*r = (ref_t){0};
	r->p = *p;
	r->pose = start;
}

static double vt_pt(const ref_t *r)
{
	return r->p.vt / r->p.hz;
}
static double vr_pt(const ref_t *r)
{
	return r->p.vr / r->p.hz;
}
static double at_pt(const ref_t *r)
{
	return r->p.at / (r->p.hz * r->p.hz);
}
static double ar_pt(const ref_t *r)
{
	return r->p.ar / (r->p.hz * r->p.hz);
}
static double jt_pt(const ref_t *r)
{
	return r->p.jt / (r->p.hz * r->p.hz * r->p.hz);
}
static double jr_pt(const ref_t *r)
{
	return r->p.jr / (r->p.hz * r->p.hz * r->p.hz);
}

/* Pose where the queued motion ends. */
static ref_pose_t tail(const ref_t *r)
{
	return r->n ? r->pc[r->n - 1].p1 : r->pose;
}

static ref_piece_t *add(ref_t *r, ref_kind_t kind)
{
	if (r->n >= REF_MAX_PIECES)
		return 0;
	ref_pose_t from = tail(r);
	ref_piece_t *c = &r->pc[r->n++];
	*c = (ref_piece_t){0};
	c->kind = kind;
	c->p0 = from;
	return c;
}

static bool line_to(ref_t *r, double x, double y, double stop_short)
{
	ref_piece_t *c = add(r, REF_LINE);
	if (!c)
		return false;
	double dx = x - c->p0.x, dy = y - c->p0.y, l = hypot(dx, dy);
	c->len = l - stop_short;
	c->ux = l > 0 ? dx / l : 0;
	c->uy = l > 0 ? dy / l : 0;
	c->vmax = vt_pt(r);
	c->a = at_pt(r);
	c->j = jt_pt(r);
	c->p1 = c->p0;
	c->p1.x = c->p0.x + c->len * c->ux;
	c->p1.y = c->p0.y + c->len * c->uy;
	return true;
}

bool ref_forward(ref_t *r, double dist_mm)
{
	ref_pose_t t = tail(r);
	return line_to(r, t.x + dist_mm * cos(t.th * DEG), t.y + dist_mm * sin(t.th * DEG), 0);
}

bool ref_turn(ref_t *r, double angle_deg)
{
	ref_piece_t *c = add(r, REF_TURN);
	if (!c)
		return false;
	c->dir = angle_deg < 0 ? -1 : 1;
	c->len = fabs(angle_deg);
	c->vmax = vr_pt(r);
	c->a = ar_pt(r);
	c->j = jr_pt(r);
	c->p1 = c->p0;
	c->p1.th += angle_deg;
	return true;
}

static void arc_pose(const ref_piece_t *c, double s, ref_pose_t *o)
{
	double b = c->dir * s * DEG, co = cos(b), si = sin(b);
	double rx = c->p0.x - c->cx, ry = c->p0.y - c->cy;
	o->x = c->cx + rx * co - ry * si;
	o->y = c->cy + rx * si + ry * co;
	o->th = c->p0.th + c->dir * s;
}

bool ref_arc(ref_t *r, double cx_mm, double cy_mm, double angle_deg)
{
	ref_piece_t *c = add(r, REF_ARC);
	if (!c)
		return false;
	double th = c->p0.th * DEG;
	c->cx = c->p0.x + cx_mm * cos(th) - cy_mm * sin(th);
	c->cy = c->p0.y + cx_mm * sin(th) + cy_mm * cos(th);
	c->dir = angle_deg < 0 ? -1 : 1;
	c->len = fabs(angle_deg);
	double mm_per_deg = hypot(cx_mm, cy_mm) * DEG;
	c->vmax = fmin(vr_pt(r), vt_pt(r) / mm_per_deg);
	c->a = fmin(ar_pt(r), at_pt(r) / mm_per_deg);
	c->j = r->p.jt > 0 && r->p.jr > 0 ? fmin(jr_pt(r), jt_pt(r) / mm_per_deg) : 0;
	arc_pose(c, c->len, &c->p1);
	return true;
}

bool ref_cruise(ref_t *r, const double (*wp)[2], int n)
{
	enum { MAXW = 32 };
	double t[MAXW] = {0}, phi[MAXW] = {0}, lh[MAXW] = {0}, cap[MAXW] = {0}, acc[MAXW] = {0};
	double hin[MAXW], vend[MAXW] = {0}, seg[MAXW];
	bool corner[MAXW] = {false};
	if (n < 1 || n > MAXW)
		return false;
	ref_pose_t start = tail(r);
	/* Legs and their headings. */
	for (int i = 0; i < n; i++) {
		double sx = i ? wp[i - 1][0] : start.x, sy = i ? wp[i - 1][1] : start.y;
		seg[i] = hypot(wp[i][0] - sx, wp[i][1] - sy);
		hin[i] = atan2(wp[i][1] - sy, wp[i][0] - sx) / DEG;
	}
	/* Corners, in the order they are planned as waypoints arrive: each
	 * takes the tangent length the previous one left free. */
	for (int i = 0; i + 1 < n; i++) {
		double d = wrap180(hin[i + 1] - hin[i]);
		double avail = seg[i] - (i && corner[i - 1] ? t[i - 1] : 0);
		double ti = fmin(r->p.blend_mm, fmin(avail, seg[i + 1] / 2));
		if (fabs(d) < TINY) {
			corner[i] = true; /* collinear: straight through */
			cap[i] = vt_pt(r);
			continue;
		}
		if (fabs(d) > 170 || ti <= TINY)
			continue;
		double x1, y1, psi = fabs(d) / 2 * DEG;
		unit_half(psi, &x1, &y1);
		corner[i] = true;
		phi[i] = d;
		t[i] = ti;
		lh[i] = ti / (x1 + y1 * tan(psi));
		/* Rotation rate v k <= vr and v^2 dk/ds + a k <= ar (traj.h). */
		double k = lh[i] / fabs(d);
		double vacc = lh[i] * sqrt(ar_pt(r) / (2 * fabs(d)));
		cap[i] = fmin(vt_pt(r), fmin(0.99 * vr_pt(r) * k, vacc));
		acc[i] = ar_pt(r) * k / 2;
	}
	/* Straight part of leg i: between the corners at its two ends. */
	double line[MAXW];
	for (int i = 0; i < n; i++)
		line[i] =
		    fmax(0, seg[i] - (i && corner[i - 1] ? t[i - 1] : 0) - (corner[i] ? t[i] : 0));
	/* Backward pass: brake to the next corner's speed, and to rest at the end. */
	double next = 0;
	/* Under a jerk limit the braking counts on A / J + 4 ticks at the
	 * line speed less of each line (the ramps' extra time, whole ticks). */
	double slack = 0;
	if (r->p.jt > 0)
		slack = vt_pt(r) * (floor(at_pt(r) / jt_pt(r) + 1e-9) + 4);
	for (int i = n - 1; i >= 0; i--) {
		if (!corner[i]) {
			next = vend[i] = 0;
			continue;
		}
		double v = cap[i];
		if (i + 1 < n)
			v = fmin(v, reach(line[i + 1] - slack, next, at_pt(r)));
		vend[i] = next = v;
	}
	for (int i = 0; i < n; i++) {
		bool moving_in = i > 0 && corner[i - 1];
		if (!moving_in) {
			ref_pose_t p = tail(r);
			double a = wrap180(hin[i] - p.th);
			if (fabs(a) > TINY && !ref_turn(r, a))
				return false;
		}
		if (!line_to(r, wp[i][0], wp[i][1], corner[i] ? t[i] : 0))
			return false;
		ref_piece_t *l = &r->pc[r->n - 1];
		l->vend = vend[i];
		l->blend = corner[i];
		l->cruise = true;
		if (!corner[i] || lh[i] == 0)
			continue;
		ref_piece_t *c = add(r, REF_CORNER);
		if (!c)
			return false;
		c->len = 2 * lh[i];
		c->phi = phi[i];
		c->lh = lh[i];
		c->vmax = cap[i];
		c->a = fmin(at_pt(r), acc[i]);
		c->after = line[i + 1];
		c->next_vend = corner[i + 1] ? vend[i + 1] : 0;
		c->blend = true;
		double ho = (c->p0.th + phi[i]) * DEG;
		c->p1.x = wp[i][0] + t[i] * cos(ho);
		c->p1.y = wp[i][1] + t[i] * sin(ho);
		c->p1.th = c->p0.th + phi[i];
	}
	return true;
}

/* ---- jerk-limited pieces (traj.h, section 4, derived again) ---------- */

/* The raw unit of the firmware's per-tick limits: its plan keeps 1, 2 and
 * 4 of them below speed, acceleration and jerk for rounding. */
#define RAW (1.0 / 4294967296.0)

/* The shortest whole-tick triple (Nv, Na, Nj), Na >= Nj, Nv >= Na + Nj,
 * with len / Nv <= v, len / (Nv Na) <= a, len / (Nv Na Nj) <= j: every Nj
 * and Na up to the continuous phases and a few beyond. */
static void sc_plan(ref_piece_t *c)
{
	/* The firmware holds its per-tick limits in whole raw units, rounded
	 * down. */
	double v = (floor(c->vmax / RAW) - 1) * RAW, a = (floor(c->a / RAW) - 2) * RAW;
	double j = (floor(c->j / RAW) - 4) * RAW, d = c->len;
	long best = -1;
	long nj_hi = (long)ceil(a / j) + 2, na_hi = (long)ceil(v / a) + 2;
	for (long nj = 1; nj <= nj_hi; nj++) {
		for (long na = nj; na <= na_hi + nj && na + nj < REF_TRI_MAX; na++) {
			double nv = fmax(fmax(ceil(d / v), ceil(d / (a * na))),
					 fmax(ceil(d / (j * na * nj)), (double)(na + nj)));
			long t = (long)nv + na + nj;
			if (best < 0 || t < best) {
				best = t;
				c->nv = (long)nv;
				c->na = na;
				c->nj = nj;
			}
		}
	}
	/* The Na and Nj boxes convolved: a trapezoid of counts, summed. */
	double sum = 0;
	for (long m = 0; m < c->na + c->nj - 1; m++) {
		long lo = m - c->nj + 1 > 0 ? m - c->nj + 1 : 0;
		long hi = m < c->na - 1 ? m : c->na - 1;
		sum += (double)(hi - lo + 1);
		c->tri_cum[m] = sum;
	}
}

/* Counts of the three boxes convolved, up to step k: the speed count is
 * the trapezoid's cumulative count less the same Nv steps later. */
static double sc_count(const ref_piece_t *c, long k)
{
	long last = c->na + c->nj - 2;
	double a = k < 0 ? 0 : c->tri_cum[k > last ? last : k];
	long k2 = k - c->nv;
	double b = k2 < 0 ? 0 : c->tri_cum[k2 > last ? last : k2];
	return a - b;
}

/* ---- jerk-limited lines between speeds (traj.h, section 6, derived again) */

static void advance(ref_t *r, const ref_piece_t *c, double s0, double s1);

/* The shortest whole-tick ramp boxes (Na >= Nj, Na + Nj least, the
 * smaller Nj on a tie) that change the speed by delta > 0 within a and j:
 * delta <= a Na and delta <= j Na Nj. */
static void ramp_boxes(double delta, double a, double j, long *na, long *nj)
{
	long best = -1, hi = (long)ceil(a / j) + 2;
	for (long t = 1; t <= hi; t++) {
		double n = fmax((double)t, fmax(ceil(delta / a), ceil(delta / (j * t))));
		if (best < 0 || (long)n + t < best) {
			best = (long)n + t;
			*na = (long)n;
			*nj = t;
		}
	}
}

/* The line's length for speed w and k ticks at it on the boxes in c: the
 * ramp of delta on (Na, Nj) covers delta (Na + Nj) / 2 over its L = Na +
 * Nj - 1 ticks beyond the speed it starts from. */
static double ln_len(const ref_piece_t *c, double w, long k)
{
	double l1 = (double)(c->na1 + c->nj1 - 1), l2 = (double)(c->na2 + c->nj2 - 1);
	double d1 = w - c->cin;
	return c->cin * l1 + d1 * (double)(c->na1 + c->nj1) / 2 + w * ((double)k + l2) -
	       (w - c->cout) * (double)(c->na2 + c->nj2) / 2;
}

/* The boxes for top speed w (one tick at least each, as the firmware
 * keeps); w1 shapes the first ramp. */
static void ln_boxes(ref_piece_t *c, double w1, double w2, double a, double j)
{
	c->na1 = c->nj1 = c->na2 = c->nj2 = 1;
	if (fabs(w1 - c->cin) > 0)
		ramp_boxes(fabs(w1 - c->cin), a, j, &c->na1, &c->nj1);
	if (w2 - c->cout > 0)
		ramp_boxes(w2 - c->cout, a, j, &c->na2, &c->nj2);
}

/* Plans the line of len from cin to cout: the fastest top speed whose
 * ramps fit with no tick at it (to 1/256 of it, as the firmware searches),
 * the ticks at it that the rest fills, and the top speed that then covers
 * len exactly (the firmware spreads a remainder of raw units instead).
 * False when even the ramp from cin to cout does not fit. */
static bool ln_plan(ref_piece_t *c, double len, double cin, double cout)
{
	double vm = (floor(c->vmax / RAW) - 1) * RAW, a = (floor(c->a / RAW) - 2) * RAW;
	double j = (floor(c->j / RAW) - 5) * RAW, lo, wmin;
	c->cin = cin;
	c->cout = cout = fmin(cout, vm);
	if (cin > vm) {
		lo = vm;
		wmin = vm - vm / 64;
		ln_boxes(c, wmin, lo, a, j);
		if (ln_len(c, lo, 0) > len)
			return false;
	} else {
		double hi = vm;
		lo = wmin = fmax(cin, cout);
		ln_boxes(c, hi, hi, a, j);
		if (ln_len(c, hi, 0) <= len) {
			lo = hi;
		} else {
			ln_boxes(c, lo, lo, a, j);
			if (ln_len(c, lo, 0) > len)
				return false;
			while (hi - lo > RAW && hi - lo > lo / 256) {
				double mid = lo + (hi - lo) / 2;
				ln_boxes(c, mid, mid, a, j);
				if (ln_len(c, mid, 0) <= len)
					lo = mid;
				else
					hi = mid;
			}
		}
		ln_boxes(c, lo, lo, a, j);
	}
	/* On these boxes the length is linear in w, slope b. */
	long k = (long)floor((len - ln_len(c, lo, 0)) / lo);
	double b = (double)(c->na1 + c->nj1 + c->na2 + c->nj2) / 2 + (double)k - 1;
	double w = lo + (len - ln_len(c, lo, k)) / b;
	double n = (double)(c->na1 + c->nj1 + c->na2 + c->nj2 - 2 + k);
	if (len - ln_len(c, lo, k) >= n * RAW) {
		/* A tick more, the top speed lowered to fit, down to wmin. */
		k++;
		b += 1;
		w = lo + (len - ln_len(c, lo, k)) / b;
		if (w < wmin) {
			k--;
			b -= 1;
			w = lo + (len - ln_len(c, lo, k)) / b;
		}
	}
	c->w = w;
	c->nk = k;
	return true;
}

/* The count of the Na and Nj boxes convolved at step m (a trapezoid). */
static double trap(long m, long na, long nj)
{
	long lo = m - nj + 1 > 0 ? m - nj + 1 : 0, hi = m < na - 1 ? m : na - 1;
	return hi >= lo ? (double)(hi - lo + 1) : 0;
}

/* One tick of a cruise line between speeds: the ramps' speeds are their
 * boxes' cumulative counts over Na Nj of the way. */
static double ln_speed(ref_t *r, const ref_piece_t *c)
{
	long k = r->k, l1 = c->na1 + c->nj1 - 1;
	if (k < l1) {
		r->c1 += trap(k, c->na1, c->nj1);
		return c->cin + (c->w - c->cin) * r->c1 / (double)(c->na1 * c->nj1);
	}
	if (k < l1 + c->nk)
		return c->w;
	r->c2 += trap(k - l1 - c->nk, c->na2, c->nj2);
	return c->w - (c->w - c->cout) * r->c2 / (double)(c->na2 * c->nj2);
}

/* A cruise line under a jerk limit: planned on its first tick from the
 * speed it is entered at, over what is left of it, into its corner's
 * speed (rest at the route's end); it lands on its end on its last tick,
 * and the corner after it holds that speed. */
static void ln_step(ref_t *r, ref_piece_t *c)
{
	if (r->k == 0) {
		r->c1 = r->c2 = 0;
		double cout = c->blend ? fmin(c->vend, c->vmax - RAW) : 0;
		if (!ln_plan(c, c->len - r->s, r->v, cout)) {
			c->j = 0; /* as the firmware: brake, plan at rest */
			return;
		}
	}
	long n = c->na1 + c->nj1 + c->na2 + c->nj2 - 2 + c->nk;
	double u = ln_speed(r, c);
	r->k++;
	if (r->k >= n) {
		r->pose = c->p1;
		r->v = c->cout;
		r->s = 0;
		r->k = 0;
		r->cur++;
		if (!c->blend) {
			r->v = 0;
			r->settle = true;
		}
		return;
	}
	advance(r, c, r->s, r->s + u);
	r->s += u;
	r->v = u;
}

/* ---- execution -------------------------------------------------------- */

static double horizon(const ref_piece_t *c, double rem)
{
	if (c->kind == REF_LINE && c->blend)
		return rem + ref_brake(c->vend, c->a) + c->vend;
	if (c->kind == REF_CORNER)
		return rem + c->after + ref_brake(c->next_vend, c->a) + c->next_vend;
	return rem;
}

/* Advance the pose along piece c from s0 to s1. */
static void advance(ref_t *r, const ref_piece_t *c, double s0, double s1)
{
	switch (c->kind) {
	case REF_LINE:
		r->pose.x = c->p0.x + s1 * c->ux;
		r->pose.y = c->p0.y + s1 * c->uy;
		break;
	case REF_TURN:
		r->pose.th = c->p0.th + c->dir * s1;
		break;
	case REF_ARC:
		arc_pose(c, s1, &r->pose);
		break;
	case REF_CORNER: {
		/* Integrate the heading along the step in sub-steps of 0.25 mm. */
		int m = (int)ceil((s1 - s0) / 0.25);
		double h = (s1 - s0) / (m ? m : 1);
		for (int k = 0; k < m; k++) {
			double mid = s0 + (k + 0.5) * h;
			for (int j = 0; j < 5; j++) {
				double th =
				    (c->p0.th + corner_heading(c, mid + gl_x[j] * h / 2)) * DEG;
				r->pose.x += gl_w[j] * h / 2 * cos(th);
				r->pose.y += gl_w[j] * h / 2 * sin(th);
			}
		}
		r->pose.th = c->p0.th + corner_heading(c, s1);
		break;
	}
	}
}

/* One tick of a jerk-limited piece: the position is len S_k / P. */
static void sc_step(ref_t *r, ref_piece_t *c)
{
	if (r->k == 0)
		sc_plan(c);
	double p = (double)c->nv * (double)c->na * (double)c->nj;
	r->s_count += sc_count(c, r->k);
	r->k++;
	double s = c->len * r->s_count / p;
	if (r->k >= c->nv + c->na + c->nj - 2) {
		r->pose = c->p1;
		r->s = 0;
		r->s_count = 0;
		r->k = 0;
		r->cur++;
		r->settle = true;
		return;
	}
	advance(r, c, r->s, s);
	r->s = s;
}

bool ref_step(ref_t *r)
{
	if (r->cur >= r->n)
		return false;
	ref_piece_t *c = &r->pc[r->cur];
	if (c->kind == REF_LINE && c->j > 0 && c->cruise && (c->blend || r->v > 0)) {
		if (r->settle && r->k == 0 && r->v == 0) {
			r->settle = false; /* a tick at rest after the turn */
			return true;
		}
		ln_step(r, c);
		if (c->j > 0)
			return true;
	}
	if (c->j > 0 && !c->blend && r->v == 0) {
		if (r->settle && r->k == 0) {
			r->settle = false; /* a tick at rest between two pieces */
			return true;
		}
		sc_step(r, c);
		return true;
	}
	/* A corner under a jerk limit holds the speed it is entered at. */
	if (!(c->kind == REF_CORNER && r->p.jt > 0))
		r->v = step(r->v, horizon(c, c->len - r->s), c->vmax, c->a);
	double budget = r->v;
	for (;;) {
		c = &r->pc[r->cur];
		double rem = c->len - r->s;
		if (budget < rem) {
			advance(r, c, r->s, r->s + budget);
			r->s += budget;
			break;
		}
		/* Piece complete: land on its end, carry the rest of the step on
		 * when the next piece blends. */
		r->pose = c->p1;
		budget -= rem;
		r->s = 0;
		r->cur++;
		if (!c->blend || r->cur >= r->n) {
			r->v = 0;
			break;
		}
		if (budget == 0)
			break;
	}
	return true;
}
