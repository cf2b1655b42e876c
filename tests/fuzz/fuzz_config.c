/* Fuzz target: the configuration reader (hal/posix/config_xml.c: vehicle
 * file and io.xml, expat), with and without the <backends> section's
 * handler (hal/linux/backend_cfg.c), and what the firmware makes of an
 * accepted configuration.
 *
 * Input: the vehicle file, optionally followed by a NUL byte and io.xml.
 * Checked: a rejected file gives a one-line error naming the file; an
 * accepted one passes vs_config_check, boots the unit on the simulated
 * plant (vehicle_init succeeds) Unpowered, and a few ticks later nothing
 * has moved. Read with the backends in the same pass, the core's verdict
 * comes first and is the same (error text, configuration), and the
 * backends' verdict is the same as when they are read alone.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "../../hal/linux/backend_cfg.h"
#include "../../hal/posix/config_xml.h"
#include "../../host_sim/sim.h"

/* An in-memory file the loader can open by name. */
static int mem_file(const uint8_t *data, size_t n, char *path, size_t cap)
{
	int fd = memfd_create("fuzz_config", 0);
	if (fd < 0)
		abort();
	size_t off = 0;
	while (off < n) {
		ssize_t w = write(fd, data + off, n - off);
		if (w <= 0)
			abort();
		off += (size_t)w;
	}
	snprintf(path, cap, "/proc/self/fd/%d", fd);
	return fd;
}

/* One line, naming the file. */
static void well_formed(int rc, const char *err, size_t cap)
{
	if (memchr(err, '\0', cap) == NULL || strchr(err, '\n'))
		abort();
	if (rc != 0 && (rc != -1 || strncmp(err, "/proc/self/fd/", 14) != 0))
		abort();
	if (rc == 0 && err[0] != '\0')
		abort();
}

/* The same files read with <backends> in the one pass (the core's verdict
 * first, unchanged), and <backends> alone (the same verdict when the core
 * accepts). */
static void backends_agree(const char *vpath, const char *ipath, int core_rc, const char *core_err,
			   const vs_config_t *cfg_core, const hal_io_map_t *map_core)
{
	static vs_config_t cfg_all;
	static hal_io_map_t map_all;
	static backend_cfg_t bk_all, bk_alone;
	char err_all[256], err_alone[256];

	memset(&cfg_all, 0, sizeof cfg_all);
	memset(&map_all, 0, sizeof map_all);
	memset(err_all, 'x', sizeof err_all);
	memset(err_alone, 'x', sizeof err_alone);
	int all = backend_cfg_load_all(vpath, ipath, &cfg_all, &map_all, &bk_all, err_all,
				       sizeof err_all);
	int alone = backend_cfg_load(vpath, &bk_alone, err_alone, sizeof err_alone);
	well_formed(all, err_all, sizeof err_all);
	well_formed(alone, err_alone, sizeof err_alone);
	if (core_rc != 0) {
		if (all == 0 || strcmp(err_all, core_err) != 0)
			abort(); /* the core's error comes first */
		return;
	}
	if (memcmp(&cfg_all, cfg_core, sizeof cfg_all) != 0 ||
	    memcmp(&map_all, map_core, sizeof map_all) != 0)
		abort(); /* the backends change nothing of the core's */
	if (all != alone || (all != 0 && strcmp(err_all, err_alone) != 0))
		abort();
	if (all == 0 && memcmp(&bk_all, &bk_alone, sizeof bk_all) != 0)
		abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	static sim_t S;
	static vs_config_t cfg;
	static hal_io_map_t map;
	char vpath[64], ipath[64], err[256];
	const uint8_t *nul = memchr(data, 0, size);
	size_t vlen = nul ? (size_t)(nul - data) : size;
	int vfd = mem_file(data, vlen, vpath, sizeof vpath), ifd = -1;

	if (nul)
		ifd = mem_file(nul + 1, size - vlen - 1, ipath, sizeof ipath);
	memset(err, 'x', sizeof err);
	memset(&cfg, 0, sizeof cfg); /* padding too: compared with memcmp */
	memset(&map, 0, sizeof map);
	int rc = config_load(vpath, nul ? ipath : NULL, &cfg, &map, err, sizeof err);
	backends_agree(vpath, nul ? ipath : NULL, rc, err, &cfg, &map);
	close(vfd);
	if (ifd >= 0)
		close(ifd);

	if (memchr(err, '\0', sizeof err) == NULL || strchr(err, '\n'))
		abort(); /* always terminated, one line */
	if (rc != 0) {
		if (rc != -1 || strncmp(err, "/proc/self/fd/", 14) != 0)
			abort(); /* an error names the file */
		return 0;
	}
	if (err[0] != '\0')
		abort();
	const char *bad = NULL;
	if (vs_config_check(&cfg, &bad) != 0)
		abort();
	/* Without io.xml the default io table stays and the line map is empty. */
	if (map.n != (nul ? cfg.num_io : 0))
		abort();
	for (unsigned i = 0; i < map.n; i++)
		if (map.e[i].id != cfg.io[i].id || map.e[i].dir != cfg.io[i].dir ||
		    map.e[i].width != cfg.io[i].width || !memchr(map.e[i].chip, 0, HAL_IO_CHIP_MAX))
			abort();
	/* What the loader accepts, the firmware must boot. */
	if (sim_init(&S, &cfg, NULL) != 0)
		abort();
	sim_run_ms(&S, 5);
	int16_t st = 0;
	char msg[VS_STATE_MSG_MAX];
	vs_getState(&S.vehicle, &st, msg);
	/* Unpowered, or a fault the configuration implies at once (e.g. a
	 * critical battery threshold above the pack voltage): never powered. */
	if (S.vehicle.powered || S.vehicle.servo || S.plant.relay_cmd ||
	    (st != VS_STATE_UNPOWERED && st != VS_STATE_ALARM))
		abort();
	double x, y, th;
	plant_pose(&S.plant, &x, &y, &th);
	if (x != 0.0 || y != 0.0 || th != 0.0)
		abort();
	return 0;
}
