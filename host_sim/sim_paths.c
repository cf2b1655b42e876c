/* Configuration search of vehicle-sim (sim_paths.h). */
#include "sim_paths.h"

#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The build defines both from PREFIX and BUILD (mk/linux.mk); these are
 * make's defaults, for tools that read the file alone. */
#ifndef VEHICLE_DATADIR
#define VEHICLE_DATADIR "/usr/local/share/vehicle"
#endif
#ifndef VEHICLE_TREE_CONFIG
#define VEHICLE_TREE_CONFIG "../config"
#endif

size_t sim_paths_dirs(const char *exe, char dirs[SIM_PATHS_N][SIM_PATHS_MAX])
{
	size_t n = 0;
	const char *slash = exe ? strrchr(exe, '/') : NULL;

	if (slash) {
		int len = (int)(slash - exe);

		snprintf(dirs[n++], SIM_PATHS_MAX, "%.*s/../share/vehicle", len, exe);
		snprintf(dirs[n++], SIM_PATHS_MAX, "%.*s/%s", len, exe, VEHICLE_TREE_CONFIG);
	}
	snprintf(dirs[n++], SIM_PATHS_MAX, "%s", VEHICLE_DATADIR);
	return n;
}

int sim_paths_find(char dirs[][SIM_PATHS_MAX], size_t n, const char *name, char *out, size_t cap)
{
	char path[SIM_PATHS_MAX + 64], real[PATH_MAX];
	size_t len;

	for (size_t i = 0; i < n; i++) {
		snprintf(path, sizeof(path), "%s/%s", dirs[i], name);
		if (realpath(path, real)) {
			snprintf(out, cap, "%s", real);
			return 0;
		}
	}
	snprintf(out, cap, "no %s in", name);
	for (size_t i = 0; i < n; i++) {
		len = strlen(out);
		snprintf(out + len, cap - len, "%s %s", i ? "," : "", dirs[i]);
	}
	return -1;
}
