/* Jerk-limited profiles (derivation in traj.h, sections 4 and 5). */
#include "traj.h"

#include <stddef.h>

/* Box lengths whose product P reaches this are refused: the sampler adds
 * remainders below P in pairs. */
#define SC_P_LIMIT ((int64_t)1 << 62)

/* Out of line: it is called from the search's loop, and inlined copies of
 * 64-bit arithmetic cost flash on a 32-bit core. */
__attribute__((noinline)) int64_t traj_mul_sat(int64_t x, int64_t y)
{
	/* Both below 2^31: the product fits, no division (a library call of
	 * some 100 instructions on a 32-bit core). */
	if (((uint64_t)x | (uint64_t)y) >> 31 == 0)
		return x * y;
	return x > INT64_MAX / y ? INT64_MAX : x * y;
}

/* ceil(n / m) for n > 0, m > 0. */
FX_HELPER int64_t ceil_div(int64_t n, int64_t m)
{
	return fx_div_nn(n - 1, m) + 1;
}

/* Floor of the cube root, one bit of the root per step. */
FX_HELPER int64_t icbrt(uint64_t x)
{
	uint64_t y = 0;
	for (int s = 63; s >= 0; s -= 3) {
		y <<= 1;
		uint64_t b = 3 * y * (y + 1) + 1;
		if ((x >> s) >= b) {
			x -= b << s;
			y++;
		}
	}
	return (int64_t)y;
}

int64_t traj_sc_ticks_bound(q32_t d, q32_t a, q32_t j)
{
	/* Continuous time: 4 cbrt(d / 2J) when the jerk alone binds, else
	 * A / J + sqrt((A / J)^2 + 4 d / A) <= 2 A / J + 2 sqrt(d / A) with
	 * A / J < cbrt(d / 2J): the sum bounds both. The whole ticks and the
	 * margins add a few (section 4). */
	int64_t am = fx_max64(a - 2, 1), jm = fx_max64(j - 4, 1);
	return 4 * (icbrt((uint64_t)(d / (2 * jm))) + 1) +
	       2 * ((int64_t)fx_isqrt64((uint64_t)(d / am)) + 1) + 8;
}

/* The shortest Nv that a given Na, Nj allows (traj.h, section 4). */
static __attribute__((noinline)) int64_t sc_nv(const traj_sc_t *p, int64_t d, int64_t nv_v,
					       int64_t na, int64_t nj)
{
	int64_t nv = fx_max64(nv_v, na + nj);
	nv = fx_max64(nv, ceil_div(d, traj_mul_sat(p->am, na)));
	return fx_max64(nv, ceil_div(d, traj_mul_sat(traj_mul_sat(p->jm, na), nj)));
}

/* The continuous optimum's jerk and acceleration phases in whole ticks
 * (traj.h): the search looks around them. */
static void sc_guess(const traj_sc_t *p, int64_t d, int64_t *tj, int64_t *ta)
{
	int64_t j = fx_div_nn(p->am, p->jm); /* the acceleration limit is reached */
	j = fx_min64(j,
		     (int64_t)fx_isqrt64((uint64_t)fx_div_nn(p->vm, p->jm))); /* only the speed */
	j = fx_min64(j, icbrt((uint64_t)fx_div_nn(d, 2 * p->jm)));	      /* neither */
	j = fx_max64(j, 1);
	int64_t a = fx_div_nn(p->vm, p->am);
	/* Acceleration reached, speed not: d = A ta (ta + tj). */
	uint64_t q = (uint64_t)fx_min64(fx_div_nn(d, p->am), (int64_t)1 << 60);
	int64_t b = ((int64_t)fx_isqrt64((uint64_t)(j * j) + 4 * q) - j) / 2;
	*tj = j;
	*ta = fx_max64(j, fx_min64(a, b));
}

bool traj_sc_plan(traj_sc_t *p, q32_t d, q32_t v, q32_t a, q32_t j)
{
	*p = (traj_sc_t){.vm = v - 1, .am = a - 2, .jm = j - 4};
	if (d <= 0 || p->vm < 1 || p->am < 1 || p->jm < 1)
		return false;
	int64_t nv_v = ceil_div(d, p->vm), tj, ta, best = INT64_MAX;
	sc_guess(p, d, &tj, &ta);
	for (int64_t nj = tj; nj <= tj + 1; nj++) {
		const int64_t nas[3] = {nj, ta, ta + 1};
		for (int i = 0; i < 3; i++) {
			int64_t na = nas[i];
			if (na < nj)
				continue;
			int64_t nv = sc_nv(p, d, nv_v, na, nj);
			if (traj_mul_sat(traj_mul_sat(nv, na), nj) >= SC_P_LIMIT ||
			    nv + na + nj >= best)
				continue;
			best = nv + na + nj;
			p->nv = nv;
			p->na = na;
			p->nj = nj;
		}
	}
	if (best == INT64_MAX)
		return false;
	p->p = p->nv * p->na * p->nj;
	p->qd = d / p->p;
	p->rd = d % p->p;
	p->ticks = best - 2;
	return true;
}

/* The jerk count of step k: which of the four pulses covers it. */
static int sc_pulse(const traj_sc_t *p, int64_t k)
{
	if (k < p->nj)
		return 1;
	if (k >= p->na + p->nv)
		return 1;
	if ((k >= p->na && k < p->na + p->nj) || (k >= p->nv && k < p->nv + p->nj))
		return -1;
	return 0;
}

/* (q, r) += (dq, dr) over p, with r and dr in [0, p). */
FX_HELPER void qr_add(int64_t *q, int64_t *r, int64_t dq, int64_t dr, int64_t p)
{
	*q += dq;
	*r += dr;
	if (*r >= p) {
		*r -= p;
		(*q)++;
	}
}

q32_t traj_sc_next(traj_sc_t *p)
{
	if (p->k >= p->ticks)
		return 0;
	int pulse = sc_pulse(p, p->k++);
	/* -(qd, rd) is (-qd - 1, p - rd), or (-qd, 0) for rd = 0. */
	if (pulse > 0)
		qr_add(&p->aq, &p->ar, p->qd, p->rd, p->p);
	else if (pulse < 0)
		qr_add(&p->aq, &p->ar, -p->qd - (p->rd != 0), p->rd ? p->p - p->rd : 0, p->p);
	qr_add(&p->cq, &p->cr, p->aq, p->ar, p->p);
	q32_t before = p->sq;
	qr_add(&p->sq, &p->sr, p->cq, p->cr, p->p);
	return p->sq - before;
}

q32_t traj_jslew(q32_t *v, q32_t *acc, q32_t target, q32_t amax, q32_t j)
{
	q32_t e = target - *v;
	if (e == 0 && *acc == 0)
		return *v;
	/* Toward the target: its distance and the rate along it (section 5). */
	q32_t s = e < 0 || (e == 0 && *acc > 0) ? -1 : 1;
	q32_t r = s * *acc + j;
	if (r > 0) /* traj_step takes a rate from 0 up */
		r = traj_step(s * *acc, s * e, amax, j);
	*acc = s * r;
	*v += *acc;
	return *v;
}

/* A ramp's box lengths (Na >= Nj, traj.h section 6): the shortest that
 * change the speed by delta (> 0) within am and jm; amj = am / jm.
 * ceil(delta / (jm t)) is ceil(ceil(delta / jm) / t) for positive integers:
 * one wide division, then narrow ones (the core's own on a 32-bit core). */
static void ramp_shape(int64_t delta, int64_t am, int64_t jm, int64_t amj, int64_t *na, int64_t *nj)
{
	int64_t qj = fx_div_nn(delta, jm), cj = qj + (qj * jm != delta);
	/* min(amj, isqrt(qj)): no root where the acceleration limit binds. */
	int64_t t0 = amj >> 31 == 0 && amj * amj <= qj
			 ? amj
			 : fx_min64(amj, (int64_t)fx_isqrt64((uint64_t)qj));
	int64_t na0 = ceil_div(delta, am);
	if (((uint64_t)na0 | (uint64_t)cj | (uint64_t)(t0 + 2)) >> 30 == 0) {
		/* All below 2^30, as they are but for extreme limits: the
		 * candidates in the core's word, its own divisions. */
		uint32_t a0 = (uint32_t)na0, c = (uint32_t)cj, best = UINT32_MAX;
		for (uint32_t t = t0 > 1 ? (uint32_t)t0 - 1 : 1; t <= (uint32_t)t0 + 2; t++) {
			uint32_t n = (c - 1) / t + 1;
			n = n > a0 ? n : a0;
			n = n > t ? n : t;
			if (n + t < best) {
				best = n + t;
				*na = n;
				*nj = t;
			}
		}
		return;
	}
	/* Beyond (ramps of 2^30 ticks and more, under a jerk limit a million
	 * times below the acceleration's): t0 alone, which serves delta within
	 * a tick or two of the shortest. */
	*nj = fx_max64(t0, 1);
	*na = fx_max64(fx_max64(*nj, na0), ceil_div(cj, *nj));
}

/* True when boxes na, nj carry a ramp of delta within am and jm. */
static bool ramp_serves(int64_t delta, int64_t am, int64_t jm, int64_t na, int64_t nj)
{
	return delta <= traj_mul_sat(am, na) && delta <= traj_mul_sat(traj_mul_sat(jm, na), nj);
}

/* The ramp of delta on boxes na, nj (delta = 0: none) as the rise of an
 * S-curve that never comes down (traj.h, section 6). */
FX_HELPER void ramp_start(traj_sc_t *s, int64_t delta, int64_t na, int64_t nj)
{
	*s = (traj_sc_t){.nv = INT64_MAX / 4, .na = na, .nj = nj, .ticks = INT64_MAX};
	s->p = na * nj;
	s->qd = delta / s->p;
	s->rd = delta % s->p;
}

/* The line's distance at speed w with k ticks at it, on the boxes in p:
 * D(w, K) of traj.h, section 6. */
static int64_t ln_dist(const traj_ln_t *p, int64_t w, int64_t k)
{
	int64_t d1 = w - p->cin, l1 = p->na1 + p->nj1 - 1, l2 = p->na2 + p->nj2 - 1;
	int64_t r1 = traj_mul_sat(fx_abs64(d1), p->na1 + p->nj1) / 2;
	int64_t r2 = traj_mul_sat(w - p->cout, p->na2 + p->nj2) / 2;
	return p->cin * l1 + (d1 < 0 ? -r1 : r1) + traj_mul_sat(w, k + l2) - r2;
}

/* The ramps' boxes for line speed w (one at least, so that L >= 1). */
static void ln_shapes(traj_ln_t *p, int64_t w1, int64_t w2, int64_t am, int64_t jm)
{
	int64_t amj = fx_div_nn(am, jm);
	p->na1 = p->nj1 = p->na2 = p->nj2 = 1;
	if (w1 != p->cin)
		ramp_shape(fx_abs64(w1 - p->cin), am, jm, amj, &p->na1, &p->nj1);
	if (w2 != p->cout)
		ramp_shape(w2 - p->cout, am, jm, amj, &p->na2, &p->nj2);
}

static bool ln_fits(traj_ln_t *p, int64_t w, int64_t len, int64_t am, int64_t jm)
{
	ln_shapes(p, w, w, am, jm);
	return ln_dist(p, w, 0) <= len;
}

/* Whether the search for the line speed still has a bracket to halve:
 * it ends within 1/256 of lo. */
static bool ln_open(int64_t lo, int64_t hi)
{
	return hi - lo > 1 && hi - lo > lo >> 8;
}

/* The line's top speed lo: the fastest that fits with no ticks at it, by
 * bisection, at most *fits trial lines in this call; the bracket (lo, hi)
 * kept in p->w and p->hold between calls (p->n = -1). A call with p->n >= 0
 * begins afresh. False when not even the ramp from cin to cout fits. */
static bool ln_search(traj_ln_t *p, q32_t len, q32_t cin, q32_t cout, int64_t vm, int64_t am,
		      int64_t jm, int64_t wmin, int64_t *fits)
{
	int64_t lo = vm, hi = wmin;
	if (p->n >= 0) {
		/* The members before the S-curves (ramp_start and traj_sc_plan
		 * set those): a third of the struct to clear on a tick that
		 * plans a tail. */
		__builtin_memset(p, 0, offsetof(traj_ln_t, ramp));
		p->cin = cin;
		p->cout = cout;
		if (len <= 0 || am < 1 || jm < 1 || cin < 0 || cout < 0 || cout > vm)
			return false;
		if (cin > vm) {
			ln_shapes(p, wmin, vm, am, jm);
			if (ln_dist(p, vm, 0) > len)
				return false;
		} else if (!ln_fits(p, vm, len, am, jm)) {
			lo = wmin;
			hi = vm;
			if (!ln_fits(p, lo, len, am, jm))
				return false;
		}
		*fits -= 2;
	} else {
		lo = p->w;
		hi = p->hold;
	}
	while (ln_open(lo, hi) && (*fits)-- > 0) {
		int64_t mid = lo + (hi - lo) / 2;
		if (ln_fits(p, mid, len, am, jm))
			lo = mid;
		else
			hi = mid;
	}
	p->w = lo;
	p->hold = hi;
	p->n = -1;
	return true;
}

int traj_ln_plan_part(traj_ln_t *p, q32_t len, q32_t cin, q32_t cout, q32_t v, q32_t a, q32_t j,
		      int64_t fits)
{
	int64_t vm = v - 1, am = a - 2, jm = j - 5, w, budget = fits;
	/* The lowest speed the search for the remainder may go down to.
	 * Above the limit (a lowered one): down to it first, and no faster;
	 * the first ramp's boxes serve down to 1/64 below it, which leaves
	 * the search below room. Else max(cin, cout): from there up the
	 * distance grows with w; below, the two ramps one way are longer than
	 * the one ramp that w = cin gives (their times add up to more, the
	 * extra A / J or sqrt term), so when that does not fit, nothing
	 * does. */
	int64_t wmin = cin > vm ? vm - (vm >> 6) : fx_max64(cin, cout);
	if (!ln_search(p, len, cin, cout, vm, am, jm, wmin, &fits))
		return 0;
	int64_t lo = p->w;
	/* The rest takes two fits' worth: a call of its own unless the
	 * budget has them left. */
	if (ln_open(lo, p->hold) || (fits < 2 && fits < budget))
		return -1;
	p->n = 0;
	if (lo < 1)
		return 0;
	if (cin <= vm)
		ln_shapes(p, lo, lo, am, jm); /* the boxes for lo (above: as planned) */
	/* The ticks at it, and what is left. On the boxes planned for lo
	 * (they serve every w from max(cin, cout) to lo), D grows with w by
	 * about B a raw unit, less than N (traj.h): a remainder of N or more
	 * takes one tick more at the fastest w from wmin that still fits,
	 * which leaves less than B + 1. */
	int64_t k = (len - ln_dist(p, lo, 0)) / lo;
	w = lo;
	int64_t dw = ln_dist(p, w, k); /* D(w, k), kept as w moves */
	if (len - dw >= p->na1 + p->nj1 + k + p->na2 + p->nj2 - 2) {
		k++;
		int64_t top = lo;
		w = wmin;
		dw = ln_dist(p, w, k);
		int64_t over = dw - len;
		if (over > 0) {
			/* Even at wmin a tick more covers too much: the hold at lo
			 * covers the remainder as a bump above lo (an S-curve at
			 * the limits, inside the hold), or the hold at wmin gives
			 * back what is too much as a dip below it; or the line
			 * cannot go. */
			int64_t rem = len - ln_dist(p, lo, k - 1);
			if (lo < vm && traj_sc_plan(&p->dip, rem, vm - lo + 1, a, j) &&
			    p->dip.ticks + 2 <= k - 1) {
				p->dsign = 1;
				k--;
				w = lo;
			} else if (traj_sc_plan(&p->dip, over, w + 1, a, j) &&
				   p->dip.ticks + 2 <= k) {
				p->dsign = -1;
			} else {
				return 0;
			}
			top = w;
		}
		if (top > w) {
			/* D is linear in w but for the floors (slope B, twice it
			 * b2): a step from wmin, then a unit or two either way. */
			int64_t b2 = p->na1 + p->nj1 + p->na2 + p->nj2 + 2 * k - 2;
			w = fx_min64(top, w - 2 * over / b2);
			dw = ln_dist(p, w, k);
			while (w > wmin && dw > len)
				dw = ln_dist(p, --w, k);
			for (int64_t dn; w < top && (dn = ln_dist(p, w + 1, k)) <= len; w++)
				dw = dn;
		}
	}
	if (w < cout || w > vm || w < 1 ||
	    !ramp_serves(fx_abs64(w - cin), am, jm, p->na1, p->nj1) ||
	    !ramp_serves(w - cout, am, jm, p->na2, p->nj2))
		return 0;
	p->w = w;
	p->hold = k;
	p->l1 = p->na1 + p->nj1 - 1;
	p->n = p->l1 + k + p->na2 + p->nj2 - 1;
	p->r = p->dsign ? 0 : len - dw; /* a bump or dip takes it all */
	ramp_start(&p->ramp, fx_abs64(w - cin), p->na1, p->nj1);
	return 1;
}

/* Out of line: each inlined call passes its seven arguments again. */
__attribute__((noinline)) bool traj_ln_plan(traj_ln_t *p, q32_t len, q32_t cin, q32_t cout, q32_t v,
					    q32_t a, q32_t j)
{
	p->n = 0;
	return traj_ln_plan_part(p, len, cin, cout, v, a, j, INT64_MAX) > 0;
}

q32_t traj_ln_next(traj_ln_t *p)
{
	if (p->k >= p->n)
		return p->cout;
	int64_t k = p->k++, u;
	if (k < p->l1) {
		q32_t s = traj_sc_next(&p->ramp);
		u = p->w >= p->cin ? p->cin + s : p->cin - s;
	} else if (k < p->l1 + p->hold) {
		/* A tick at w either side of a dip: its jerks and the ramps'
		 * never meet. */
		u = k > p->l1 && p->dsign ? p->w + p->dsign * traj_sc_next(&p->dip) : p->w;
	} else {
		if (k == p->l1 + p->hold)
			ramp_start(&p->ramp, p->w - p->cout, p->na2, p->nj2);
		u = p->w - traj_sc_next(&p->ramp);
	}
	/* The remainder, spread (traj.h, section 6). */
	p->racc += p->r;
	if (p->racc >= p->n) {
		p->racc -= p->n;
		u++;
	}
	return u;
}
