/* Trajectory generation (derivation in traj.h). */
#include "traj.h"

/* T(n) = a n (n + 1) / 2 (fx.h: FX_HELPER) */
FX_HELPER q32_t tri(int64_t n, q32_t a)
{
	return (n * (n + 1) / 2) * a;
}

q32_t traj_brake_dist(q32_t u, q32_t a)
{
	if (u <= 0 || a <= 0)
		return 0;
	int64_t n = u / a;
	return n * u - tri(n, a);
}

static q32_t g_of(q32_t u, q32_t a)
{
	return u + traj_brake_dist(u, a);
}

/* Umax's step count, the largest n with T(n) <= d, given q = floor(d / a):
 * n ~ sqrt(2 q), then corrected by whole steps. */
static int64_t umax_steps(q32_t d, q32_t a, uint64_t q)
{
	int64_t n = (int64_t)fx_isqrt64(2 * q);
	while (n > 0 && tri(n, a) > d)
		n--;
	while (tri(n + 1, a) <= d)
		n++;
	return n;
}

q32_t traj_umax_near(q32_t d, q32_t a, int64_t *n_guess)
{
	if (d <= 0)
		return 0;
	if (a <= 0)
		return d;
	int64_t n = *n_guess;
	if (n >= 1 && tri(n, a) > d && tri(n - 1, a) <= d) {
		n--; /* braking: one step fewer than the tick before */
	} else if (n < 0 || tri(n, a) > d || tri(n + 1, a) <= d) {
		n = umax_steps(d, a, (uint64_t)(d / a));
	}
	*n_guess = n;
	return (d + tri(n, a)) / (n + 1);
}

q32_t traj_umax(q32_t d, q32_t a)
{
	int64_t n = -1;
	return traj_umax_near(d, a, &n);
}

q32_t traj_step(q32_t v, q32_t d, q32_t vmax, q32_t a)
{
	int64_t n = -1;
	return traj_step_near(v, d, vmax, a, &n);
}

q32_t traj_step_near(q32_t v, q32_t d, q32_t vmax, q32_t a, int64_t *n_guess)
{
	q32_t cand = v + a;
	if (cand > vmax)
		cand = fx_max64(vmax, v - a);
	if (cand < 0)
		cand = 0;
	/* G is increasing, so G(cand) <= d exactly when cand <= Umax(d). Not
	 * braking, G(cand) is the cheaper test; braking (a step count kept),
	 * Umax is needed anyway and decides alone. */
	if (*n_guess < 0 && g_of(cand, a) <= d)
		return cand;
	q32_t u = traj_umax_near(d, a, n_guess);
	if (cand <= u)
		return cand;
	/* The invariant keeps u >= v - a unless the limits were lowered under
	 * the unit; braking harder than a is never chosen. */
	if (u < v - a)
		u = v - a;
	return u;
}

q32_t traj_reach(q32_t d, q32_t c, q32_t a)
{
	if (d < 0)
		d = 0;
	return traj_umax(d + traj_brake_dist(c, a) + c, a);
}

void traj_rate_init(traj_rate_t *r, q32_t a)
{
	r->a = a;
	r->inv = a > 0 ? UINT64_MAX / (uint64_t)a : 0;
}

/* floor(x / a) for x >= 0, a > 0: the reciprocal's quotient is short by at
 * most 1 (inv is less than 1 below 2^64 / a, and x < 2^63). */
static int64_t rate_div(const traj_rate_t *r, q32_t x)
{
	uint64_t a = (uint64_t)r->a, q = fx_mulhi_u64((uint64_t)x, r->inv);
	while ((q + 1) * a <= (uint64_t)x)
		q++;
	return (int64_t)q;
}

q32_t traj_brake_dist_r(q32_t u, const traj_rate_t *r)
{
	if (u <= 0 || r->a <= 0)
		return 0;
	int64_t n = rate_div(r, u);
	return n * u - tri(n, r->a);
}

q32_t traj_umax_r(q32_t d, const traj_rate_t *r)
{
	q32_t a = r->a;
	if (d <= 0)
		return 0;
	if (a <= 0)
		return d;
	int64_t n = umax_steps(d, a, (uint64_t)rate_div(r, d));
	if (n + 1 < 0x10000)
		return (q32_t)fx_udiv64_small((uint64_t)(d + tri(n, a)), (uint32_t)(n + 1));
	return (d + tri(n, a)) / (n + 1);
}

/* Unit clothoid half with total turn psi: end point (x1, y1), Q30. The
 * integrals of cos(psi u^2) and sin(psi u^2) over u in 0..1, term by term:
 * x1 = sum_k (-1)^k psi^2k / ((2k)! (4k+1)), y1 the odd powers alike, i.e.
 * the n-th term is +-p_n / (2n + 1) with p_n = psi^n / n!. For psi <= 85
 * degrees (1.484 rad) the terms fall below 2^-30 by n = 15. Products with
 * Q32 reciprocals only: a 64-bit division costs a microcontroller some 100
 * instructions, and this runs in the request that queues a waypoint (65
 * sines and cosines by Simpson's rule cost 20,000 on the Cortex-M4). */
static void clothoid_half(q32_t psi_deg, int64_t *x1, int64_t *y1)
{
	/* 2^32 / n (n = 2..15) and 2^32 / (2n + 1) (n = 1..15), rounded */
	static const uint32_t inv_n[15] = {0u,	       2147483648u, 1431655765u, 1073741824u,
					   858993459u, 715827883u,  613566757u,	 536870912u,
					   477218588u, 429496730u,  390451572u,	 357913941u,
					   330382100u, 306783378u,  286331153u};
	static const uint32_t inv_odd[15] = {1431655765u, 858993459u, 613566757u, 477218588u,
					     390451572u,  330382100u, 286331153u, 252645135u,
					     226050910u,  204522252u, 186737709u, 171798692u,
					     159072863u,  148102321u, 138547332u};
	/* psi in Q30 radians: 85 degrees of Q32 times pi/180 in Q30 stays
	 * below 2^63. */
	int64_t w = (psi_deg * 18740330) >> 32;
	int64_t p = (int64_t)1 << 30, sx = p, sy = 0;
	for (int n = 1; n <= 15; n++) {
		p = (p * w) >> 30;
		if (n > 1)
			p = (p * inv_n[n - 1]) >> 32;
		int64_t t = (p * inv_odd[n - 1]) >> 32;
		int64_t sgn = ((n >> 1) & 1) ? -t : t;
		if (n & 1)
			sy += sgn;
		else
			sx += sgn;
	}
	*x1 = sx;
	*y1 = sy;
}

bool traj_corner_plan(traj_corner_t *c, q32_t phi_deg, q32_t t_avail_mm, q32_t ar_pt2)
{
	q32_t aphi = fx_abs64(phi_deg);
	if (aphi > fx_from_int(170) || t_avail_mm <= 0 || ar_pt2 <= 0)
		return false;
	q32_t psi = aphi / 2;
	int64_t x1, y1;
	clothoid_half(psi, &x1, &y1);
	uint32_t b = fx_deg_to_bam(psi);
	int64_t sn = fx_sin_bam(b), cs = fx_cos_bam(b);
	/* T / Lh = x1 + y1 tan(psi), Q30 */
	int64_t ratio = x1 + (y1 * sn) / cs;
	c->phi_deg = phi_deg;
	c->t_mm = t_avail_mm;
	c->lh_mm = fx_div(t_avail_mm, ratio * 4); /* ratio is Q30; times 4 makes it Q32 */
	if (c->lh_mm < ((q32_t)1 << TRAJ_INV_LH_SH))
		return false; /* no room */
	c->k_mm_deg = fx_div(c->lh_mm, aphi);
	c->inv_lh = fx_div((q32_t)1 << (30 + TRAJ_INV_LH_SH), c->lh_mm);
	traj_corner_rates(c, ar_pt2);
	return true;
}

void traj_corner_rates(traj_corner_t *c, q32_t ar_pt2)
{
	q32_t aphi = fx_abs64(c->phi_deg);
	/* sqrt(ar / (2 phi)) in 1/tick, Q32. The ratio is tiny (1e-6 at 1 kHz):
	 * form it with 24 extra fraction bits before the square root. */
	q32_t ratio_q56 = fx_div(ar_pt2 << 24, 2 * aphi);
	q32_t rt = (q32_t)(fx_isqrt64((uint64_t)ratio_q56) << 4);
	c->vacc_pt = fx_mul(c->lh_mm, rt);
	c->acc_pt2 = fx_mul(ar_pt2, c->k_mm_deg) / 2;
}
