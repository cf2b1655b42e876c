/* CSV trace writer (columns: trace.h, docs/trace.md). */
#include "trace.h"

#include <string.h>

static const char header[] =
    "time_s,cmd_x_mm,cmd_y_mm,cmd_th_deg,odo_x_mm,odo_y_mm,odo_th_deg,"
    "true_x_mm,true_y_mm,true_th_deg,cmd_vx_mm_s,cmd_vy_mm_s,cmd_w_deg_s,"
    "sp0_cps,sp1_cps,sp2_cps,sp3_cps,meas0_cps,meas1_cps,meas2_cps,meas3_cps,"
    "state,queue_len,alarms,newest_alarm,enc0,enc1,enc2,enc3\n";

static double q32(q32_t v)
{
	return (double)v / 4294967296.0;
}

void trace_attach(trace_t *t, FILE *f, uint32_t every)
{
	memset(t, 0, sizeof(*t));
	t->f = f;
	t->every = every ? every : 1;
	fputs(header, f);
}

int trace_open(trace_t *t, const char *path, uint32_t every)
{
	FILE *f = fopen(path, "w");
	if (!f)
		return -1;
	trace_attach(t, f, every);
	t->own = true;
	return 0;
}

void trace_tick(trace_t *t, double time_s, vehicle_t *v, const plant_t *pl)
{
	if (!t->f || t->count++ % t->every != 0)
		return;
	vs_diag_t d;
	vehicle_diag(v, &d);
	int16_t state = 0;
	char msg[VS_STATE_MSG_MAX];
	vs_getState(v, &state, msg);
	double hz = (double)v->cfg.tick_hz;
	double tx, ty, tth;
	plant_pose(pl, &tx, &ty, &tth);

	fprintf(t->f, "%.6f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.3f,%.3f,%.3f", time_s,
		q32(d.ref_pose.x_mm), q32(d.ref_pose.y_mm), q32(d.ref_pose.th_deg),
		q32(d.odom_pose.x_mm), q32(d.odom_pose.y_mm), q32(d.odom_pose.th_deg), tx, ty, tth,
		q32(d.cmd_twist_pt.vx_pt) * hz, q32(d.cmd_twist_pt.vy_pt) * hz,
		q32(d.cmd_twist_pt.w_pt) * hz);
	for (int a = 0; a < VS_MAX_AXES; a++)
		fprintf(t->f, ",%.2f", a < pl->n ? (double)d.wheel_cps_q8[a] / 256.0 : 0.0);
	for (int a = 0; a < VS_MAX_AXES; a++)
		fprintf(t->f, ",%.2f", a < pl->n ? pl->w[a].vel_cps : 0.0);
	/* The alarm list as getActiveAlarm gives it, as vehiclectl record
	 * writes it: a plot marks each alarm raised. */
	int16_t alarms = 0;
	vs_alarm_t newest;
	uint16_t got = 0;
	vs_getActiveAlarm(v, 1, &alarms, &newest, &got);
	fprintf(t->f, ",%d,%u,%d,%lu", state, (unsigned)d.queue_len, alarms,
		got ? (unsigned long)newest.code : 0ul);
	/* The encoders as the unit read them: the black box's measurement. */
	for (int a = 0; a < VS_MAX_AXES; a++)
		fprintf(t->f, ",%ld", (long)v->meas_counts[a]);
	fputc('\n', t->f);
	/* A reader that follows the file while the simulator runs (a test
	 * waiting for a stop without asking the unit) sees each change. */
	if (state != t->last_state)
		fflush(t->f);
	t->last_state = state;
}

int trace_close(trace_t *t)
{
	if (!t->f)
		return 0;
	int rc = ferror(t->f) ? -1 : 0;
	if (fflush(t->f) != 0)
		rc = -1;
	if (t->own && fclose(t->f) != 0)
		rc = -1;
	t->f = NULL;
	return rc;
}
