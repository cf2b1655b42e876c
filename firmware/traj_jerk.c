/* Jerk-limited profiles (derivation in traj.h, sections 4 and 5). */
#include "traj.h"

/* Box lengths whose product P reaches this are refused: the sampler adds
 * remainders below P in pairs. */
#define SC_P_LIMIT ((int64_t)1 << 62)

/* x y for x, y > 0, saturating. Out of line: it is called from the
 * search's loop, and inlined copies of 64-bit arithmetic cost flash on a
 * 32-bit core. */
static __attribute__((noinline)) int64_t mul_sat(int64_t x, int64_t y)
{
	/* Both below 2^31: the product fits, no division (a library call of
	 * some 100 instructions on a 32-bit core). */
	if (((uint64_t)x | (uint64_t)y) >> 31 == 0)
		return x * y;
	return x > INT64_MAX / y ? INT64_MAX : x * y;
}

/* ceil(n / m) for n > 0, m > 0. */
static int64_t ceil_div(int64_t n, int64_t m)
{
	return (n - 1) / m + 1;
}

/* Floor of the cube root, one bit of the root per step. */
static int64_t icbrt(uint64_t x)
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

/* The shortest Nv that a given Na, Nj allows (traj.h, section 4). */
static __attribute__((noinline)) int64_t sc_nv(const traj_sc_t *p, int64_t d, int64_t nv_v,
					       int64_t na, int64_t nj)
{
	int64_t nv = fx_max64(nv_v, na + nj);
	nv = fx_max64(nv, ceil_div(d, mul_sat(p->am, na)));
	return fx_max64(nv, ceil_div(d, mul_sat(mul_sat(p->jm, na), nj)));
}

/* The continuous optimum's jerk and acceleration phases in whole ticks
 * (traj.h): the search looks around them. */
static void sc_guess(const traj_sc_t *p, int64_t d, int64_t *tj, int64_t *ta)
{
	int64_t j = p->am / p->jm; /* the acceleration limit is reached */
	j = fx_min64(j, (int64_t)fx_isqrt64((uint64_t)(p->vm / p->jm))); /* only the speed */
	j = fx_min64(j, icbrt((uint64_t)(d / (2 * p->jm))));		 /* neither */
	j = fx_max64(j, 1);
	int64_t a = p->vm / p->am;
	/* Acceleration reached, speed not: d = A ta (ta + tj). */
	uint64_t q = (uint64_t)fx_min64(d / p->am, (int64_t)1 << 60);
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
			if (mul_sat(mul_sat(nv, na), nj) >= SC_P_LIMIT || nv + na + nj >= best)
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
static inline void qr_add(int64_t *q, int64_t *r, int64_t dq, int64_t dr, int64_t p)
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
