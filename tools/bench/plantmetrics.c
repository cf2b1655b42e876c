/* Motion figures on the simulated plant (plantmetrics.h). */
#include "plantmetrics.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const double Q = 4294967296.0;

void pm_trace_init(pm_trace_t *tr)
{
	memset(tr, 0, sizeof(*tr));
}

void pm_trace_free(pm_trace_t *tr)
{
	free(tr->s);
	pm_trace_init(tr);
}

static pm_pose_t fx_pose(const fx_pose_t *p)
{
	return (pm_pose_t){(double)p->x_mm / Q, (double)p->y_mm / Q, (double)p->th_deg / Q};
}

static void take(sim_t *s, pm_sample_t *o)
{
	vs_diag_t d;
	const plant_t *pl = sim_plant(s);
	vehicle_diag(sim_vehicle(s), &d);
	o->t_s = sim_time_s(s);
	o->ref = fx_pose(&d.ref_pose);
	o->odom = fx_pose(&d.odom_pose);
	plant_pose(pl, &o->truth.x, &o->truth.y, &o->truth.th);
	double hz = (double)s->cfg.tick_hz;
	double vx = (double)d.cmd_twist_pt.vx_pt / Q * hz,
	       vy = (double)d.cmd_twist_pt.vy_pt / Q * hz;
	double c = cos(o->ref.th * M_PI / 180.0), sn = sin(o->ref.th * M_PI / 180.0);
	o->cmd_vx = vx * c - vy * sn;
	o->cmd_vy = vx * sn + vy * c;
	o->cmd_w = (double)d.cmd_twist_pt.w_pt / Q * hz;
	o->wheel_mm_s = 0.0;
	for (uint8_t a = 0; a < pl->n; a++)
		o->wheel_mm_s = fmax(o->wheel_mm_s, fabs(plant_wheel_mm_s(pl, a)));
	char msg[VS_STATE_MSG_MAX];
	vs_getState(sim_vehicle(s), &o->state, msg);
}

void pm_trace_sample(pm_trace_t *tr, sim_t *s)
{
	if (tr->n == tr->cap) {
		size_t cap = tr->cap ? tr->cap * 2 : 65536;
		pm_sample_t *p = realloc(tr->s, cap * sizeof(*p));
		if (!p) {
			fprintf(stderr, "plantmetrics: out of memory\n");
			exit(2);
		}
		tr->s = p;
		tr->cap = cap;
	}
	take(s, &tr->s[tr->n++]);
}

static void on_tick(void *ctx, sim_t *s)
{
	pm_trace_sample(ctx, s);
}

void pm_trace_attach(pm_trace_t *tr, sim_t *s)
{
	sim_set_tick_cb(s, on_tick, tr);
}

void pm_limits_default(pm_limits_t *lim)
{
	lim->pos_mm = 0.05;
	lim->th_deg = 0.01;
	lim->rest_mm_s = 0.1;
	lim->drift_s = 0.5;
}

static double wrap180(double a)
{
	a = fmod(a + 180.0, 360.0);
	if (a < 0)
		a += 360.0;
	return a - 180.0;
}

static double dist(const pm_pose_t *a, const pm_pose_t *b)
{
	return hypot(a->x - b->x, a->y - b->y);
}

static double dth(const pm_pose_t *a, const pm_pose_t *b)
{
	return fabs(wrap180(a->th - b->th));
}

int pm_measure(const pm_trace_t *tr, size_t from, const pm_goal_t *goal, const pm_limits_t *lim,
	       pm_result_t *out)
{
	const pm_sample_t *s = tr->s;
	size_t n = tr->n, busy = from, r, w;
	memset(out, 0, sizeof(*out));
	while (busy < n && s[busy].state == VS_STATE_READY)
		busy++;
	for (r = busy; r < n && s[r].state != VS_STATE_READY; r++)
		;
	if (r >= n)
		return -1;
	for (w = r; w < n && s[w].t_s < s[r].t_s + lim->drift_s - 1e-9; w++)
		;
	if (w >= n)
		return -1;

	/* The last ticks that commanded a twist, a translation, a rotation. */
	size_t last = from, last_t = n, last_r = n;
	for (size_t i = from; i <= r; i++) {
		bool t = s[i].cmd_vx != 0.0 || s[i].cmd_vy != 0.0;
		if (t)
			last_t = i;
		if (s[i].cmd_w != 0.0)
			last_r = i;
		if (t || s[i].cmd_w != 0.0)
			last = i;
	}
	/* The command came at the start of sample from's tick. */
	double t0 = s[from].t_s - (s[from + 1].t_s - s[from].t_s);
	double t_end = s[last].t_s;
	out->ref_end_s = t_end - t0;
	out->ready_s = s[r].t_s - t0;
	out->ready_ms = (s[r].t_s - t_end) * 1e3;
	pm_pose_t g = goal->at_ref_end ? s[last].ref : goal->target;
	out->target = g;

	out->err_odom_mm = dist(&s[r].odom, &g);
	out->err_odom_deg = dth(&s[r].odom, &g);
	out->err_true_mm = dist(&s[r].truth, &g);
	out->err_true_deg = dth(&s[r].truth, &g);

	if (last_t < n) {
		double ux = s[last_t].cmd_vx, uy = s[last_t].cmd_vy, l = hypot(ux, uy);
		for (size_t i = last_t; i <= w; i++) {
			double along = ((s[i].truth.x - g.x) * ux + (s[i].truth.y - g.y) * uy) / l;
			out->over_mm = fmax(out->over_mm, along);
		}
	}
	if (last_r < n) {
		double sign = s[last_r].cmd_w > 0.0 ? 1.0 : -1.0;
		for (size_t i = last_r; i <= w; i++)
			out->over_deg = fmax(out->over_deg, sign * wrap180(s[i].truth.th - g.th));
	}

	/* Settled for good: the last sample out of the band decides. */
	size_t j = w + 1;
	for (size_t i = w + 1; i-- > last;) {
		if (!(dist(&s[i].truth, &g) <= lim->pos_mm && dth(&s[i].truth, &g) <= lim->th_deg &&
		      s[i].wheel_mm_s <= lim->rest_mm_s)) {
			j = i;
			break;
		}
	}
	if (j == w)
		out->settle_ms = NAN;
	else if (j > w)
		out->settle_ms = 0.0;
	else
		out->settle_ms = (s[j + 1].t_s - t_end) * 1e3;

	out->drift_true_mm = dist(&s[w].truth, &s[r].truth);
	out->drift_true_deg = dth(&s[w].truth, &s[r].truth);
	out->drift_odom_mm = dist(&s[w].odom, &s[r].odom);
	out->drift_odom_deg = dth(&s[w].odom, &s[r].odom);
	for (size_t i = from; i <= r; i++) {
		out->follow_mm = fmax(out->follow_mm, dist(&s[i].ref, &s[i].odom));
		out->follow_deg = fmax(out->follow_deg, dth(&s[i].ref, &s[i].odom));
	}
	return 0;
}

/* The route of tools/bench/rig.c: corners from 22 to 117 degrees, both
 * senses, legs of 0.7 to 1.4 m. */
#define ROUTE5                                                                                     \
	"moveCruiseAbs 1000 0", "moveCruiseAbs 2000 400", "moveCruiseAbs 3000 0",                  \
	    "moveCruiseAbs 3800 800", "moveCruiseAbs 3800 1800"
#define ROUTE10                                                                                    \
	ROUTE5, "moveCruiseAbs 2800 2300", "moveCruiseAbs 1800 1800", "moveCruiseAbs 1000 2400",   \
	    "moveCruiseAbs 0 1800", "moveCruiseAbs 0 800"

const pm_move_t pm_moves[] = {
    {.name = "moveForward 10000", .cmd = {"moveForward 10000"}, .goal = {{10000, 0, 0}, false}},
    {.name = "moveTurn 360", .cmd = {"moveTurn 360"}, .goal = {{0, 0, 0}, false}},
    {.name = "moveCircularRel 0 1000 90",
     .cmd = {"moveCircularRel 0 1000 90"},
     .goal = {{1000, 1000, 90}, false}},
    {.name = "moveCruiseAbs, 10 waypoints", .cmd = {ROUTE10}, .goal = {{0, 800, -90}, false}},
    {.name = "moveForward 300", .cmd = {"moveForward 300"}, .goal = {{300, 0, 0}, false}},
    {.name = "moveForward 1000 at 1000 mm/s^2",
     .setup = {"setAcceleration 1000 180"},
     .cmd = {"moveForward 1000"},
     .goal = {{1000, 0, 0}, false}},
    {.name = "moveTurn 90", .cmd = {"moveTurn 90"}, .goal = {{0, 0, 90}, false}},
    {.name = "moveCruiseAbs, 5 waypoints", .cmd = {ROUTE5}, .goal = {{3800, 1800, 90}, false}},
    {.name = "moveContinuousRel 500 500 0",
     .cmd = {"moveContinuousRel 500 500 0"},
     .goal = {{500, 500, 0}, false}},
    {.name = "stop 1 s into moveForward 1000",
     .cmd = {"moveForward 1000"},
     .stop_after_ms = 1000,
     .goal = {{0, 0, 0}, true}},
    {.name = "moveLinearAbs 1000 300 0, 1 ms after Ready",
     .setup = {"moveForward 300"},
     .setup_wait_ms = 1,
     .cmd = {"moveLinearAbs 1000 300 0"},
     .goal = {{1000, 300, 0}, false}},
};
const size_t pm_num_moves = sizeof(pm_moves) / sizeof(pm_moves[0]);

static int exec_all(sim_t *s, const char *const *lines, const char **bad_line)
{
	char reply[CONSOLE_REPLY_MAX];
	for (int i = 0; i < PM_MAX_LINES && lines[i]; i++) {
		if (!sim_exec(s, lines[i], reply, sizeof(reply)) || strcmp(reply, "ok true") != 0) {
			if (bad_line)
				*bad_line = lines[i];
			return PM_REFUSED;
		}
	}
	return PM_OK;
}

static int16_t last_state(const pm_trace_t *tr)
{
	return tr->s[tr->n - 1].state;
}

/* Ticks until Ready; with after_busy, a Ready before the first Busy tick
 * does not count. */
static int run_until_ready(sim_t *s, const pm_trace_t *tr, bool after_busy)
{
	uint32_t limit = 120u * s->cfg.tick_hz;
	bool busy = !after_busy;
	for (uint32_t i = 0; i < limit; i++) {
		sim_tick(s);
		if (last_state(tr) != VS_STATE_READY)
			busy = true;
		else if (busy)
			return PM_OK;
	}
	return PM_NO_READY;
}

int pm_run(const pm_move_t *m, const vs_config_t *cfg, const plant_params_t *pp,
	   const pm_limits_t *lim, pm_trace_t *tr, size_t *from, pm_result_t *out,
	   const char **bad_line)
{
	static const char *const start[] = {"setPower true", "setServo true", NULL};
	static const char *const stop[] = {"stop", NULL};
	vs_config_t c = *cfg;
	c.link_timeout_ms = 0;	  /* no host polls the unit */
	plant_config_lag(pp, &c); /* the configuration names the drive it runs */
	sim_t *s = calloc(1, sizeof(*s));
	if (!s)
		return PM_BAD_CONFIG;
	int rc = PM_BAD_CONFIG;
	if (sim_init_ex(s, &c, pp, NULL) != 0)
		goto done;
	tr->n = 0;
	pm_trace_attach(tr, s);
	if ((rc = exec_all(s, start, bad_line)) != PM_OK || (rc = exec_all(s, m->setup, bad_line)))
		goto done;
	if (m->setup[0]) {
		if ((rc = run_until_ready(s, tr, false)) != PM_OK)
			goto done;
		sim_run_ms(s, m->setup_wait_ms);
	}
	*from = tr->n;
	if ((rc = exec_all(s, m->cmd, bad_line)) != PM_OK)
		goto done;
	if (m->stop_after_ms) {
		sim_run_ms(s, m->stop_after_ms);
		if ((rc = exec_all(s, stop, bad_line)) != PM_OK)
			goto done;
	}
	if ((rc = run_until_ready(s, tr, true)) != PM_OK)
		goto done;
	sim_run_ms(s, (uint32_t)ceil(lim->drift_s * 1e3));
	rc = pm_measure(tr, *from, &m->goal, lim, out) == 0 ? PM_OK : PM_NO_READY;
done:
	free(s);
	return rc;
}

bool pm_push(sim_t *s, double dx_mm, double dy_mm, double dth_deg, uint32_t watch_ms,
	     pm_push_t *out)
{
	pm_sample_t a;
	take(s, &a);
	if (!plant_push(sim_plant(s), dx_mm, dy_mm, dth_deg))
		return false;
	out->truth_before = a.truth;
	out->odom_before = a.odom;
	take(s, &a);
	out->truth_pushed = a.truth;
	sim_run_ms(s, watch_ms);
	take(s, &a);
	out->truth_after = a.truth;
	out->odom_after = a.odom;
	out->state_after = a.state;
	return true;
}
