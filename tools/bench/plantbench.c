/* Motion on the default plant (docs/performance.md, section 2b): each move
 * of plantmetrics.c through the whole firmware on the simulated plant with
 * motor lag and limits, and on the ideal plant beside it, for the
 * differential and the mecanum configuration. Run from the top folder.
 *   plantbench [VEHICLE.xml ...]   (default: config/vehicle.xml
 *                                   config/vehicle-omni.xml
 *                                   config/vehicle-jerk.xml
 *                                   config/vehicle-omni-jerk.xml)
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "hal/posix/config_xml.h"
#include "tools/bench/plantmetrics.h"

static void print_row(const char *name, const char *plant, const pm_result_t *r)
{
	char settle[16];
	if (isnan(r->settle_ms))
		snprintf(settle, sizeof(settle), "never");
	else
		snprintf(settle, sizeof(settle), "%.0f", r->settle_ms);
	printf("  %-42s %-7s %7.4f %7.4f %7.4f %7.4f  %7.4f %7.4f  %6.0f %6s  %7.4f %7.4f  %7.3f "
	       "%7.4f\n",
	       name, plant, r->err_odom_mm, r->err_odom_deg, r->err_true_mm, r->err_true_deg,
	       r->over_mm, r->over_deg, r->ready_ms, settle, r->drift_true_mm, r->drift_true_deg,
	       r->follow_mm, r->follow_deg);
}

static int run_config(const char *path)
{
	vs_config_t cfg;
	char err[512];
	if (config_load(path, "config/io.xml", &cfg, NULL, err, sizeof(err)) < 0) {
		fprintf(stderr, "plantbench: %s\n", err);
		return 1;
	}
	vs_config_t fine = cfg;
	fine.encoder_counts_per_rev = plant_hires_counts_per_rev(&cfg);
	plant_params_t def, ideal;
	plant_params_default(&def);
	plant_params_ideal(&ideal);
	pm_limits_t lim;
	pm_limits_default(&lim);
	printf("%s (%s base, %u-count encoders; ideal: %u), set %.0f mm/s, %.0f deg/s, "
	       "%.0f mm/s^2, %.0f deg/s^2\n",
	       path, cfg.kinematics == VS_KIN_OMNI ? "mecanum" : "differential",
	       (unsigned)cfg.encoder_counts_per_rev, (unsigned)fine.encoder_counts_per_rev,
	       cfg.vel_default_t_mm_s, cfg.vel_default_r_deg_s, cfg.acc_default_t_mm_s2,
	       cfg.acc_default_r_deg_s2);
	printf("  %-42s %-7s %15s %15s  %15s  %6s %6s  %15s  %15s\n", "", "", "Ready: odometry",
	       "true", "overshoot", "Ready", "settle", "drift", "following");
	printf("  %-42s %-7s %7s %7s %7s %7s  %7s %7s  %6s %6s  %7s %7s  %7s %7s\n", "move",
	       "plant", "mm", "deg", "mm", "deg", "mm", "deg", "ms", "ms", "mm", "deg", "mm",
	       "deg");
	pm_trace_t tr;
	pm_trace_init(&tr);
	int rc = 0;
	for (size_t i = 0; i < pm_num_moves; i++) {
		const pm_move_t *m = &pm_moves[i];
		for (int p = 0; p < 2; p++) {
			pm_result_t r;
			size_t from;
			const char *bad = NULL;
			int res = pm_run(m, p ? &fine : &cfg, p ? &ideal : &def, &lim, &tr, &from,
					 &r, &bad);
			if (res == PM_OK) {
				print_row(m->name, p ? "ideal" : "default", &r);
			} else if (res == PM_REFUSED) {
				printf("  %-42s %-7s refused: %s\n", m->name,
				       p ? "ideal" : "default", bad ? bad : "?");
			} else {
				printf("  %-42s %-7s no Ready within 120 s\n", m->name,
				       p ? "ideal" : "default");
				rc = 1;
			}
		}
	}
	pm_trace_free(&tr);
	return rc;
}

int main(int argc, char **argv)
{
	static const char *const defaults[] = {"config/vehicle.xml", "config/vehicle-omni.xml",
					       "config/vehicle-jerk.xml",
					       "config/vehicle-omni-jerk.xml"};
	int rc = 0;
	if (argc > 1) {
		for (int i = 1; i < argc; i++)
			rc |= run_config(argv[i]);
	} else {
		for (size_t i = 0; i < sizeof defaults / sizeof defaults[0]; i++)
			rc |= run_config(defaults[i]);
	}
	return rc;
}
