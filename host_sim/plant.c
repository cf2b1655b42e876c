/* Simulated plant (model: plant.h). */
#include "plant.h"

#include <math.h>
#include <string.h>

void plant_params_default(plant_params_t *p)
{
	memset(p, 0, sizeof(*p));
	p->tau_s = 0.020;
	p->acc_limit_mm_s2 = 3000.0;
	p->current_limit_a = 10.0;
	p->amp_per_mm_s2 = 0.002; /* 1000 mm/s^2: 2 A */
	p->amp_per_mm_s = 0.002;  /* 1000 mm/s: 2 A */
	p->idle_current_a = 0.5;
	p->battery_ocv_v = 25.2;
	p->battery_r_ohm = 0.1;
	p->body_radius_mm = 300.0;
	p->io_loopback = true;
}

void plant_params_ideal(plant_params_t *p)
{
	plant_params_default(p);
	p->tau_s = 0.0;
	p->acc_limit_mm_s2 = 0.0;
	p->current_limit_a = 0.0;
}

void plant_config_lag(const plant_params_t *p, vs_config_t *cfg)
{
	for (unsigned i = 0; i < VS_MAX_AXES; i++)
		cfg->drive_lag_ms[i] = p->tau_s * 1000.0;
}

uint32_t plant_hires_counts_per_rev(const vs_config_t *cfg)
{
	/* The firmware's own check is the bound, so the two cannot disagree. */
	vs_config_t c = *cfg;
	for (uint32_t r = PLANT_HIRES_COUNTS_PER_REV; r > cfg->encoder_counts_per_rev; r >>= 1) {
		const char *bad = NULL;
		c.encoder_counts_per_rev = r;
		if (vs_config_check(&c, &bad) == 0 || !bad ||
		    strcmp(bad, "encoder_counts_per_rev") != 0)
			return r;
	}
	return cfg->encoder_counts_per_rev;
}

static int io_index(const plant_t *pl, uint32_t id)
{
	if (id == 0)
		return -1;
	for (int i = 0; i < pl->cfg.num_io; i++)
		if (pl->cfg.io[i].id == id)
			return i;
	return -1;
}

static uint32_t width_mask(uint8_t width)
{
	return width >= 32 ? 0xffffffffu : ((1u << width) - 1u);
}

void plant_init(plant_t *pl, const vs_config_t *cfg, const plant_params_t *p)
{
	memset(pl, 0, sizeof(*pl));
	pl->p = *p;
	pl->cfg = *cfg;
	pl->n = vs_config_axes(cfg);
	pl->counts_per_mm = (double)cfg->encoder_counts_per_rev / (M_PI * cfg->wheel_diameter_mm);
	pl->half_mm = cfg->kinematics == VS_KIN_OMNI
			  ? (cfg->wheel_base_mm + cfg->track_width_mm) / 2.0
			  : cfg->track_width_mm / 2.0;
	pl->battery_ocv_v = p->battery_ocv_v;
	pl->js.present = cfg->has_joystick;
	for (int i = 0; i < VS_MAX_IO; i++)
		pl->io_wire[i] = -1;
	if (p->io_loopback) {
		int in = 0;
		for (int o = 0; o < cfg->num_io; o++) {
			if (cfg->io[o].dir != VS_IO_OUT)
				continue;
			while (in < cfg->num_io && cfg->io[in].dir != VS_IO_IN)
				in++;
			if (in >= cfg->num_io)
				break;
			pl->io_wire[o] = (int8_t)in++;
		}
	}
	for (uint8_t a = 0; a < pl->n; a++)
		pl->w[a].last.fresh = true;
}

bool plant_drive_enabled(const plant_t *pl, uint8_t axis)
{
	if (axis >= pl->n)
		return false;
	const plant_wheel_t *w = &pl->w[axis];
	return w->enable_cmd && pl->relay_closed && w->fault_latched == 0 && !w->hold;
}

/* One wheel over dt: returns the travel in counts. */
static double wheel_step(plant_t *pl, uint8_t axis, double dt)
{
	plant_wheel_t *w = &pl->w[axis];
	const plant_params_t *p = &pl->p;
	bool driven = plant_drive_enabled(pl, axis);
	double target = driven ? (double)w->setpoint_q8 / 256.0 : 0.0;
	double v0 = w->vel_cps;
	double decay = p->tau_s > 0.0 ? exp(-dt / p->tau_s) : 0.0;
	double v1 = target + (v0 - target) * decay;
	double a = (v1 - v0) / dt;
	bool clipped = false;

	if (driven && p->acc_limit_mm_s2 > 0.0) {
		double amax = p->acc_limit_mm_s2 * pl->counts_per_mm;
		if (fabs(a) > amax) {
			a = copysign(amax, a);
			clipped = true;
		}
	}
	if (driven && p->current_limit_a > 0.0 && p->amp_per_mm_s2 > 0.0) {
		/* I = ka*a + kv*v in mm units; keep |I| <= limit. */
		double v_mm = v0 / pl->counts_per_mm;
		double lo = (-p->current_limit_a - p->amp_per_mm_s * v_mm) / p->amp_per_mm_s2;
		double hi = (p->current_limit_a - p->amp_per_mm_s * v_mm) / p->amp_per_mm_s2;
		double a_mm = a / pl->counts_per_mm;
		if (a_mm < lo || a_mm > hi) {
			a = (a_mm < lo ? lo : hi) * pl->counts_per_mm;
			clipped = true;
		}
	}

	double travel;
	if (clipped) {
		v1 = v0 + a * dt;
		travel = (v0 + v1) / 2.0 * dt;
	} else if (p->tau_s > 0.0) {
		/* Exact integral of the first-order response over the step. */
		travel = target * dt + (v0 - target) * p->tau_s * (1.0 - decay);
	} else {
		travel = v1 * dt; /* ideal: the new speed holds over the whole step */
	}
	w->acc_cps2 = a;
	w->vel_cps = v1;
	w->pos_counts += travel;
	w->current_a = driven ? p->amp_per_mm_s2 * a / pl->counts_per_mm +
				    p->amp_per_mm_s * v1 / pl->counts_per_mm
			      : 0.0;
	return travel;
}

void plant_step(plant_t *pl, uint32_t dt_us)
{
	if (dt_us == 0)
		return;
	double dt = (double)dt_us * 1e-6;
	double d[VS_MAX_AXES] = {0};
	double motor_a = 0.0;

	for (uint8_t a = 0; a < pl->n; a++) {
		d[a] = wheel_step(pl, a, dt) / pl->counts_per_mm;
		motor_a += fabs(pl->w[a].current_a);
	}
	pl->battery_current_a = pl->p.idle_current_a + motor_a;

	/* Body displacement from the true wheel travel (kin.h equations inverted). */
	double dx, dy, dth;
	if (pl->cfg.kinematics == VS_KIN_OMNI) {
		dx = (d[0] + d[1] + d[2] + d[3]) / 4.0;
		dy = (-d[0] + d[1] + d[2] - d[3]) / 4.0;
		dth = (-d[0] + d[1] - d[2] + d[3]) / (4.0 * pl->half_mm);
	} else {
		dx = (d[0] + d[1]) / 2.0;
		dy = 0.0;
		dth = (d[1] - d[0]) / (2.0 * pl->half_mm);
	}
	/* Exact for a constant twist over the step: the chord of the arc lies
	 * along the mid heading, shortened by sin(h)/h. */
	double h = dth / 2.0;
	double k = fabs(h) > 1e-9 ? sin(h) / h : 1.0 - h * h / 6.0;
	double mid = pl->th_rad + h;
	pl->x_mm += k * (dx * cos(mid) - dy * sin(mid));
	pl->y_mm += k * (dx * sin(mid) + dy * cos(mid));
	pl->th_rad += dth;
	pl->time_us += dt_us;
}

void plant_drive_set_velocity(plant_t *pl, uint8_t axis, int32_t cps_q8)
{
	if (axis < pl->n)
		pl->w[axis].setpoint_q8 = cps_q8;
}

bool plant_drive_hold(plant_t *pl, uint8_t axis, bool on)
{
	if (axis >= pl->n)
		return false;
	pl->w[axis].hold = on;
	return true;
}

bool plant_drive_reboot(plant_t *pl, uint8_t axis)
{
	if (axis >= pl->n)
		return false;
	plant_wheel_t *w = &pl->w[axis];
	w->enable_cmd = false;
	w->fault_latched = 0;
	w->count_offset = -floor(w->pos_counts);
	w->restarted = true;
	return true;
}

void plant_drive_enable(plant_t *pl, uint8_t axis, bool on)
{
	if (axis < pl->n)
		pl->w[axis].enable_cmd = on;
}

static int32_t encoder_counts(double pos)
{
	/* floor, then wrap like a free-running 32-bit counter */
	return (int32_t)(uint32_t)(uint64_t)(int64_t)floor(pos);
}

void plant_drive_read(plant_t *pl, uint8_t axis, hal_drive_state_t *st)
{
	if (axis >= pl->n) {
		memset(st, 0, sizeof(*st));
		return;
	}
	plant_wheel_t *w = &pl->w[axis];
	if (w->silent) {
		*st = w->last;
		st->fresh = false;
		return;
	}
	st->position_counts =
	    w->stuck ? w->stuck_counts : encoder_counts(w->pos_counts + w->count_offset);
	st->fault_code = w->fault_latched;
	st->enabled = plant_drive_enabled(pl, axis);
	st->fresh = true;
	st->position_lost = w->restarted;
	w->restarted = false;
	if (!pl->relay_closed)
		st->phase = HAL_DRIVE_NOT_READY;
	else if (w->fault_latched)
		st->phase = HAL_DRIVE_FAULT;
	else if (st->enabled)
		st->phase = HAL_DRIVE_ENABLED;
	else
		st->phase = w->enable_cmd ? HAL_DRIVE_SWITCHED_ON : HAL_DRIVE_READY;
	w->last = *st;
}

void plant_drive_reset_fault(plant_t *pl, uint8_t axis)
{
	if (axis < pl->n)
		pl->w[axis].fault_latched = pl->w[axis].fault_inject;
}

static void relay_open(plant_t *pl)
{
	pl->relay_closed = false;
	/* The drives lose their power stage and forget the enable. */
	for (uint8_t a = 0; a < pl->n; a++)
		pl->w[a].enable_cmd = false;
}

bool plant_power_set(plant_t *pl, bool on)
{
	pl->relay_cmd = on;
	if (!on)
		relay_open(pl);
	else if (!pl->relay_fail)
		pl->relay_closed = true;
	return pl->relay_closed == on;
}

void plant_set_relay_mode(plant_t *pl, plant_relay_mode_t mode)
{
	switch (mode) {
	case PLANT_RELAY_OK:
		pl->relay_fail = false;
		break;
	case PLANT_RELAY_FAIL:
		pl->relay_fail = true;
		break;
	case PLANT_RELAY_DROP:
		relay_open(pl);
		break;
	}
}

bool plant_contact(const plant_t *pl)
{
	if (pl->contact_inject)
		return true;
	double r = pl->p.body_radius_mm;
	for (uint8_t i = 0; i < pl->num_walls; i++) {
		const plant_wall_t *wl = &pl->walls[i];
		double dx = fmax(fmax(wl->x0 - pl->x_mm, 0.0), pl->x_mm - wl->x1);
		double dy = fmax(fmax(wl->y0 - pl->y_mm, 0.0), pl->y_mm - wl->y1);
		if (dx * dx + dy * dy <= r * r)
			return true;
	}
	return false;
}

uint32_t plant_battery_mv(const plant_t *pl)
{
	double v = pl->battery_ocv_v - pl->p.battery_r_ohm * pl->battery_current_a;
	if (v <= 0.0)
		return 0;
	return (uint32_t)lround(v * 1000.0);
}

bool plant_io_read(const plant_t *pl, uint32_t id, uint32_t *value)
{
	int i = io_index(pl, id);
	if (i < 0)
		return false;
	*value = pl->io_val[i];
	return true;
}

bool plant_io_write(plant_t *pl, uint32_t id, uint32_t value)
{
	int i = io_index(pl, id);
	if (i < 0 || pl->cfg.io[i].dir != VS_IO_OUT)
		return false;
	pl->io_val[i] = value & width_mask(pl->cfg.io[i].width);
	int in = pl->io_wire[i];
	if (in >= 0)
		pl->io_val[in] = value & width_mask(pl->cfg.io[in].width);
	return true;
}

bool plant_set_input(plant_t *pl, uint32_t id, uint32_t value)
{
	int i = io_index(pl, id);
	if (i < 0 || pl->cfg.io[i].dir != VS_IO_IN)
		return false;
	pl->io_val[i] = value & width_mask(pl->cfg.io[i].width);
	return true;
}

bool plant_wire(plant_t *pl, uint32_t out_id, uint32_t in_id)
{
	int o = io_index(pl, out_id);
	if (o < 0 || pl->cfg.io[o].dir != VS_IO_OUT)
		return false;
	if (in_id == 0) {
		pl->io_wire[o] = -1;
		return true;
	}
	int i = io_index(pl, in_id);
	if (i < 0 || pl->cfg.io[i].dir != VS_IO_IN)
		return false;
	pl->io_wire[o] = (int8_t)i;
	return true;
}

static bool axis_ok(const plant_t *pl, uint8_t axis)
{
	return axis < pl->n;
}

bool plant_drive_fault(plant_t *pl, uint8_t axis, uint16_t code)
{
	if (!axis_ok(pl, axis))
		return false;
	pl->w[axis].fault_inject = code;
	if (code)
		pl->w[axis].fault_latched = code;
	return true;
}

bool plant_drive_stuck(plant_t *pl, uint8_t axis, bool on)
{
	if (!axis_ok(pl, axis))
		return false;
	plant_wheel_t *w = &pl->w[axis];
	if (on && !w->stuck)
		w->stuck_counts = encoder_counts(w->pos_counts + w->count_offset);
	w->stuck = on;
	return true;
}

bool plant_drive_silent(plant_t *pl, uint8_t axis, bool on)
{
	if (!axis_ok(pl, axis))
		return false;
	pl->w[axis].silent = on;
	return true;
}

bool plant_drive_ok(plant_t *pl, uint8_t axis)
{
	if (!axis_ok(pl, axis))
		return false;
	pl->w[axis].fault_inject = 0;
	pl->w[axis].stuck = false;
	pl->w[axis].silent = false;
	return true;
}

bool plant_add_wall(plant_t *pl, double x0, double y0, double x1, double y1)
{
	if (pl->num_walls >= PLANT_MAX_WALLS)
		return false;
	pl->walls[pl->num_walls++] =
	    (plant_wall_t){fmin(x0, x1), fmin(y0, y1), fmax(x0, x1), fmax(y0, y1)};
	return true;
}

bool plant_push(plant_t *pl, double dx_mm, double dy_mm, double dth_deg)
{
	if (!(fabs(dx_mm) <= PLANT_PUSH_MAX_MM && fabs(dy_mm) <= PLANT_PUSH_MAX_MM &&
	      fabs(dth_deg) <= PLANT_PUSH_MAX_DEG))
		return false; /* also NaN */
	double dth = dth_deg * M_PI / 180.0;
	/* Body displacement of the steady twist whose arc ends at the push:
	 * plant_step's chord relation solved for it. */
	double h = dth / 2.0;
	double k = fabs(h) > 1e-9 ? sin(h) / h : 1.0 - h * h / 6.0;
	double vx = (dx_mm * cos(h) + dy_mm * sin(h)) / k;
	double vy = (dy_mm * cos(h) - dx_mm * sin(h)) / k;
	double r = dth * pl->half_mm;
	double d[VS_MAX_AXES] = {0};
	if (pl->cfg.kinematics == VS_KIN_OMNI) {
		d[0] = vx - vy - r;
		d[1] = vx + vy + r;
		d[2] = vx + vy - r;
		d[3] = vx - vy + r;
	} else {
		d[0] = vx - r; /* vy skids */
		d[1] = vx + r;
	}
	for (uint8_t a = 0; a < pl->n; a++)
		pl->w[a].pos_counts += d[a] * pl->counts_per_mm;
	double c = cos(pl->th_rad), s = sin(pl->th_rad);
	pl->x_mm += dx_mm * c - dy_mm * s;
	pl->y_mm += dx_mm * s + dy_mm * c;
	pl->th_rad += dth;
	return true;
}

void plant_set_battery_ocv(plant_t *pl, double volts)
{
	pl->battery_ocv_v = volts;
}

static int16_t js_axis(double f)
{
	if (!(f >= -1.0))
		f = -1.0; /* also NaN */
	if (f > 1.0)
		f = 1.0;
	return (int16_t)lround(f * 32767.0);
}

void plant_set_joystick(plant_t *pl, double x, double y, double r, bool present)
{
	pl->js.axis[0] = present ? js_axis(x) : 0;
	pl->js.axis[1] = present ? js_axis(y) : 0;
	pl->js.axis[2] = present ? js_axis(r) : 0;
	pl->js.present = present;
}

void plant_pose(const plant_t *pl, double *x_mm, double *y_mm, double *th_deg)
{
	*x_mm = pl->x_mm;
	*y_mm = pl->y_mm;
	double d = fmod(pl->th_rad * 180.0 / M_PI, 360.0);
	if (d <= -180.0)
		d += 360.0;
	else if (d > 180.0)
		d -= 360.0;
	*th_deg = d;
}

void plant_set_pose(plant_t *pl, double x_mm, double y_mm, double th_deg)
{
	pl->x_mm = x_mm;
	pl->y_mm = y_mm;
	pl->th_rad = th_deg * M_PI / 180.0;
}

double plant_wheel_mm_s(const plant_t *pl, uint8_t axis)
{
	return axis < pl->n ? pl->w[axis].vel_cps / pl->counts_per_mm : 0.0;
}

double plant_wheel_mm(const plant_t *pl, uint8_t axis)
{
	return axis < pl->n ? pl->w[axis].pos_counts / pl->counts_per_mm : 0.0;
}
