/* Kinematics, wheel position loop and odometry (equations in kin.h). */
#include "kin.h"

#include "traj.h"

void kin_init(kin_t *k, const kin_params_t *p)
{
	*k = (kin_t){0};
	k->p = *p;
	/* 2^16 / counts_per_mm in Q32 is mm per count in Q48. */
	k->mm_per_count_q48 = p->counts_per_mm > 0 ? fx_div((q32_t)1 << 48, p->counts_per_mm) : 0;
	k->counts_per_deg = fx_mul(p->mm_per_deg, p->counts_per_mm);
}

void kin_body_to_wheels(const kin_params_t *p, const fx_twist_t *b, q32_t w[])
{
	q32_t rot = fx_mul(b->w_pt, p->mm_per_deg);
	if (p->kin == MOTION_KIN_OMNI) {
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
	if (p->kin == MOTION_KIN_OMNI) {
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
	}
	k->synced = true;
}

static int32_t sat32(int64_t v)
{
	return v > INT32_MAX ? INT32_MAX : (v < INT32_MIN ? INT32_MIN : (int32_t)v);
}

void kin_step(kin_t *k, const fx_twist_t *body, const int32_t meas[], int32_t out_cps_q8[],
	      fx_twist_t *measured_delta, int64_t *following_err_counts)
{
	/* Zeroed: n follows kin at init (vs_config_axes), but kin_params_t alone
	 * does not tie them; a mismatch reads 0, not stack garbage. */
	q32_t meas_mm[KIN_MAX_WHEELS] = {0};
	int64_t worst = 0;
	bool moved = false;
	if (!k->synced)
		kin_sync(k, meas);
	/* Body twist straight to wheel counts: at most three products a tick,
	 * none at rest. The twist is one tick of motion within the configured
	 * speed limits, whose wheel rate config.c bounds below 2^23 counts/s:
	 * the products fit. */
	q32_t x = body->vx_pt ? fx_mul_fit(body->vx_pt, k->p.counts_per_mm) : 0;
	q32_t y = body->vy_pt ? fx_mul_fit(body->vy_pt, k->p.counts_per_mm) : 0;
	q32_t r = body->w_pt ? fx_mul_fit(body->w_pt, k->counts_per_deg) : 0;
	q32_t travel[KIN_MAX_WHEELS] = {0};
	if (k->p.kin == MOTION_KIN_OMNI) {
		travel[0] = x - y - r;
		travel[1] = x + y + r;
		travel[2] = x + y - r;
		travel[3] = x - y + r;
	} else {
		travel[0] = x - r;
		travel[1] = x + r;
	}
	for (uint8_t i = 0; i < k->p.n; i++) {
		int32_t d = (int32_t)((uint32_t)meas[i] - (uint32_t)k->last_meas[i]);
		k->last_meas[i] = meas[i];
		moved |= d != 0;
		meas_mm[i] = ((q32_t)d * k->mm_per_count_q48) >> 16;

		/* The reference keeps only the error: reference minus measured. */
		k->ref_counts_q32[i] += travel[i] - (int64_t)d * FX_ONE;
		int64_t err_q32 = k->ref_counts_q32[i];

		int64_t ff_q8 = (travel[i] * (int64_t)k->p.tick_hz) >> 24;
		int64_t fb_q8 = ((err_q32 >> 16) * k->p.kp_q16) >> 24;
		out_cps_q8[i] = sat32(ff_q8 + fb_q8);
		int64_t e = fx_abs64(err_q32) >> 32;
		if (e > worst)
			worst = e;
	}
	if (measured_delta) {
		if (moved)
			kin_wheels_to_body(&k->p, meas_mm, measured_delta);
		else
			*measured_delta = (fx_twist_t){0, 0, 0};
	}
	if (following_err_counts)
		*following_err_counts = worst;
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
	pose->th_deg = fx_wrap_deg(pose->th_deg + d->w_pt);
}
