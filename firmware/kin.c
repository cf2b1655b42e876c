/* Kinematics, wheel position loop and odometry (equations in kin.h). */
#include "kin.h"

#include "traj.h"

void kin_init(kin_t *k, const kin_params_t *p)
{
	*k = (kin_t){0};
	k->p = *p;
	k->p.n = KIN_OMNI(p->kin) ? 4 : 2;
	/* 2^16 / counts_per_mm in Q32 is mm per count in Q48. */
	k->mm_per_count_q48 = p->counts_per_mm > 0 ? fx_div((q32_t)1 << 48, p->counts_per_mm) : 0;
	k->counts_per_deg = fx_mul(p->mm_per_deg, p->counts_per_mm);
}

void kin_body_to_wheels(const kin_params_t *p, const fx_twist_t *b, q32_t w[])
{
	q32_t rot = fx_mul(b->w_pt, p->mm_per_deg);
	if (KIN_OMNI(p->kin)) {
		w[0] = b->vx_pt - b->vy_pt - rot;
		w[1] = b->vx_pt + b->vy_pt + rot;
		w[2] = b->vx_pt + b->vy_pt - rot;
		w[3] = b->vx_pt - b->vy_pt + rot;
	} else {
		w[0] = b->vx_pt - rot;
		w[1] = b->vx_pt + rot;
	}
}

void kin_wheels_to_body(const kin_params_t *p, const q32_t w[], fx_twist_t *b)
{
	if (KIN_OMNI(p->kin)) {
		b->vx_pt = (w[0] + w[1] + w[2] + w[3]) / 4;
		b->vy_pt = (-w[0] + w[1] + w[2] - w[3]) / 4;
		b->w_pt = fx_mul((-w[0] + w[1] - w[2] + w[3]) / 4, p->deg_per_mm);
	} else {
		b->vx_pt = (w[0] + w[1]) / 2;
		b->vy_pt = 0;
		b->w_pt = fx_mul((w[1] - w[0]) / 2, p->deg_per_mm);
	}
}

void kin_sync(kin_t *k, const int32_t meas[])
{
	for (uint8_t i = 0; i < k->p.n; i++) {
		k->last_meas[i] = meas[i];
		k->ref_counts_q32[i] = 0;
		k->last_travel[i] = 0;
	}
	k->synced = true;
}

static int32_t sat32(int64_t v)
{
	return v > INT32_MAX ? INT32_MAX : (v < INT32_MIN ? INT32_MIN : (int32_t)v);
}

/* One wheel of the position loop: the reference advances by travel
 * (counts, Q32), the measured step d (counts) is taken off, and the drive
 * gets the feed-forward speed plus kp times what is left. Returns the wheel's
 * |reference - measured| in counts (Q32). */
static inline int64_t wheel_step(kin_t *k, uint8_t i, q32_t travel, int32_t d, int32_t *out_cps_q8)
{
	int64_t err_q32 = k->ref_counts_q32[i] + travel - (int64_t)d * FX_ONE;
	k->ref_counts_q32[i] = err_q32;
	int64_t acc = travel - k->last_travel[i];
	k->last_travel[i] = travel;
	int64_t lead = (acc >> 16) * k->p.lag_q16[i];
	int64_t ff_q8 = ((travel + lead) * (int64_t)k->p.tick_hz) >> 24;
	int64_t fb_q8 = ((err_q32 >> 16) * k->p.kp_q16) >> 24;
	*out_cps_q8 = sat32(ff_q8 + fb_q8);
	return fx_abs64(err_q32);
}

/* Encoder step since the last tick (wrap-safe) and its length in mm. */
static inline int32_t wheel_delta(kin_t *k, uint8_t i, const int32_t meas[], q32_t *mm)
{
	int32_t d = (int32_t)((uint32_t)meas[i] - (uint32_t)k->last_meas[i]);
	k->last_meas[i] = meas[i];
	*mm = ((q32_t)d * k->mm_per_count_q48) >> 16;
	return d;
}

void kin_step(kin_t *k, const fx_twist_t *body, const int32_t meas[], int32_t out_cps_q8[],
	      fx_twist_t *measured_delta, int64_t *following_err_q32)
{
	q32_t mm[KIN_MAX_WHEELS];
	int32_t d[KIN_MAX_WHEELS];
	int64_t worst;
	if (!k->synced)
		kin_sync(k, meas);
	/* Body twist straight to wheel counts: at most three products a tick,
	 * none at rest. The twist is one tick of motion within the configured
	 * speed limits, whose wheel rate config.c bounds below 2^23 counts/s:
	 * the products fit. */
	q32_t x = body->vx_pt ? fx_mul_fit(body->vx_pt, k->p.counts_per_mm) : 0;
	q32_t r = body->w_pt ? fx_mul_fit(body->w_pt, k->counts_per_deg) : 0;
	/* The wheel count is fixed by the kinematics (kin_init): each form is
	 * written out whole, with no per-wheel table. */
	if (KIN_OMNI(k->p.kin)) {
		q32_t y = body->vy_pt ? fx_mul_fit(body->vy_pt, k->p.counts_per_mm) : 0;
		for (uint8_t i = 0; i < 4; i++)
			d[i] = wheel_delta(k, i, meas, &mm[i]);
		worst = wheel_step(k, 0, x - y - r, d[0], &out_cps_q8[0]);
		worst = fx_max64(worst, wheel_step(k, 1, x + y + r, d[1], &out_cps_q8[1]));
		worst = fx_max64(worst, wheel_step(k, 2, x + y - r, d[2], &out_cps_q8[2]));
		worst = fx_max64(worst, wheel_step(k, 3, x - y + r, d[3], &out_cps_q8[3]));
		if (measured_delta) {
			if (d[0] | d[1] | d[2] | d[3])
				kin_wheels_to_body(&k->p, mm, measured_delta);
			else
				*measured_delta = (fx_twist_t){0, 0, 0};
		}
	} else {
		d[0] = wheel_delta(k, 0, meas, &mm[0]);
		d[1] = wheel_delta(k, 1, meas, &mm[1]);
		worst = wheel_step(k, 0, x - r, d[0], &out_cps_q8[0]);
		worst = fx_max64(worst, wheel_step(k, 1, x + r, d[1], &out_cps_q8[1]));
		if (measured_delta) {
			/* kin_wheels_to_body's differential form, inline. */
			measured_delta->vx_pt = (mm[0] + mm[1]) / 2;
			measured_delta->vy_pt = 0;
			measured_delta->w_pt =
			    (d[0] | d[1]) ? fx_mul((mm[1] - mm[0]) / 2, k->p.deg_per_mm) : 0;
		}
	}
	if (following_err_q32)
		*following_err_q32 = worst;
}

void kin_pending(const kin_t *k, fx_twist_t *body)
{
	q32_t mm[KIN_MAX_WHEELS] = {0};
	/* counts (Q16) times mm per count (Q32): mm in Q48, to Q32 */
	for (uint8_t i = 0; i < k->p.n; i++)
		mm[i] = ((k->ref_counts_q32[i] >> 16) * (k->mm_per_count_q48 >> 16)) >> 16;
	kin_wheels_to_body(&k->p, mm, body);
}

void kin_offset(kin_t *k, const fx_twist_t *body)
{
	q32_t mm[KIN_MAX_WHEELS] = {0};
	kin_body_to_wheels(&k->p, body, mm);
	for (uint8_t i = 0; i < k->p.n; i++)
		k->ref_counts_q32[i] += fx_mul(mm[i], k->p.counts_per_mm);
}

void odom_integrate(fx_pose_t *pose, const fx_twist_t *d, fx_trig_cache_t *tc)
{
	if (d->vx_pt == 0 && d->vy_pt == 0) {
		if (d->w_pt != 0)
			pose->th_deg = fx_wrap_deg(pose->th_deg + d->w_pt);
		return;
	}
	uint32_t mid = fx_deg_to_bam(pose->th_deg + d->w_pt / 2);
	int32_t c, s;
	if (tc)
		fx_sincos_cached(tc, mid, &s, &c);
	else
		fx_sincos_bam(mid, &s, &c);
	pose->x_mm += fx_mul_q30(d->vx_pt, c);
	pose->y_mm += fx_mul_q30(d->vx_pt, s);
	if (d->vy_pt != 0) { /* mecanum only */
		pose->x_mm -= fx_mul_q30(d->vy_pt, s);
		pose->y_mm += fx_mul_q30(d->vy_pt, c);
	}
	if (d->w_pt != 0)
		pose->th_deg = fx_wrap_deg(pose->th_deg + d->w_pt);
}
