/* Fuzz target: the configuration loader (hal/config_xml.c: vehicle file and
 * io.xml, expat) and what the firmware makes of an accepted configuration.
 *
 * Input: the vehicle file, optionally followed by a NUL byte and io.xml.
 * Checked: a rejected file gives a one-line error naming the file; an
 * accepted one passes vs_config_check, boots the unit on the simulated
 * plant (vehicle_init succeeds) Unpowered, and a few ticks later nothing
 * has moved.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

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
	int rc = config_load(vpath, nul ? ipath : NULL, &cfg, &map, err, sizeof err);
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
