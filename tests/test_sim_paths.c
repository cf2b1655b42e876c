/* vehicle-sim's configuration search (host_sim/sim_paths.h): the folders
 * follow the program, never the working folder, and the first that has the
 * file wins. The program itself, built and installed, is run from other
 * folders by tests/run_install_tests.sh. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "host_sim/sim_paths.h"

static char tmp[128];
#define LONG 4096 /* room for three folders and a file name */

static int make_tmp(void **state)
{
	char made[] = "/tmp/test_sim_paths.XXXXXX", real[PATH_MAX];

	(void)state;
	/* Canonical, as the search's answers are. */
	if (!mkdtemp(made) || !realpath(made, real) || strlen(real) >= sizeof(tmp))
		return -1;
	memcpy(tmp, real, strlen(real) + 1); /* the length is checked above */
	return 0;
}

static int remove_tmp(void **state)
{
	char cmd[300];

	(void)state;
	snprintf(cmd, sizeof(cmd), "rm -rf '%s'", tmp);
	return system(cmd) == 0 ? 0 : -1;
}

static void touch(const char *dir, const char *name)
{
	char cmd[3 * LONG];

	snprintf(cmd, sizeof(cmd), "mkdir -p '%s' && : >'%s/%s'", dir, dir, name);
	assert_int_equal(system(cmd), 0);
}

static void folders_follow_the_program(void **state)
{
	char dirs[SIM_PATHS_N][SIM_PATHS_MAX];

	(void)state;
	assert_int_equal(sim_paths_dirs("/opt/v/bin/vehicle-sim", dirs), 3);
	assert_string_equal(dirs[0], "/opt/v/bin/../share/vehicle");
	/* The build's way back to the checkout, then the fixed data folder. */
	assert_memory_equal(dirs[1], "/opt/v/bin/", 11);
	assert_string_equal(dirs[1] + strlen(dirs[1]) - 7, "/config");
	assert_int_equal(dirs[2][0], '/');
	assert_string_equal(dirs[2] + strlen(dirs[2]) - 14, "/share/vehicle");
	/* Unknown program: the data folder alone. */
	char only[SIM_PATHS_N][SIM_PATHS_MAX];
	assert_int_equal(sim_paths_dirs(NULL, only), 1);
	assert_string_equal(only[0], dirs[2]);
}

static void first_folder_with_the_file_wins(void **state)
{
	char dirs[3][SIM_PATHS_MAX], out[LONG], want[LONG];

	(void)state;
	snprintf(dirs[0], sizeof(dirs[0]), "%s/bin/../share/vehicle", tmp);
	snprintf(dirs[1], sizeof(dirs[1]), "%s/tree/config", tmp);
	snprintf(dirs[2], sizeof(dirs[2]), "%s/data", tmp);

	/* None has it: where it looked, in order. */
	assert_int_equal(sim_paths_find(dirs, 3, "vehicle.xml", out, sizeof(out)), -1);
	snprintf(want, sizeof(want), "no vehicle.xml in %s, %s, %s", dirs[0], dirs[1], dirs[2]);
	assert_string_equal(out, want);

	touch(dirs[2], "vehicle.xml");
	assert_int_equal(sim_paths_find(dirs, 3, "vehicle.xml", out, sizeof(out)), 0);
	snprintf(want, sizeof(want), "%s/data/vehicle.xml", tmp);
	assert_string_equal(out, want);

	touch(dirs[1], "vehicle.xml");
	assert_int_equal(sim_paths_find(dirs, 3, "vehicle.xml", out, sizeof(out)), 0);
	snprintf(want, sizeof(want), "%s/tree/config/vehicle.xml", tmp);
	assert_string_equal(out, want);

	/* The installed layout first; the path comes back without "..". */
	snprintf(want, sizeof(want), "%s/bin", tmp);
	assert_int_equal(mkdir(want, 0755), 0);
	snprintf(want, sizeof(want), "%s/share/vehicle", tmp);
	touch(want, "vehicle.xml");
	assert_int_equal(sim_paths_find(dirs, 3, "vehicle.xml", out, sizeof(out)), 0);
	snprintf(want, sizeof(want), "%s/share/vehicle/vehicle.xml", tmp);
	assert_string_equal(out, want);

	/* Each file on its own: io.xml only in the last folder. */
	touch(dirs[2], "io.xml");
	assert_int_equal(sim_paths_find(dirs, 3, "io.xml", out, sizeof(out)), 0);
	snprintf(want, sizeof(want), "%s/data/io.xml", tmp);
	assert_string_equal(out, want);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test(folders_follow_the_program),
	    cmocka_unit_test_setup_teardown(first_folder_with_the_file_wins, make_tmp, remove_tmp),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
