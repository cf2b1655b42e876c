/* The black box as a file (bboxfile.h). */
#include "bboxfile.h"

#include <errno.h>
#include <stdio.h>

#include "../bbox_wire.h"

static int write_rows(FILE *f, const bbox_sample_t *const *s, uint32_t n, uint32_t tick_hz,
		      uint32_t trigger, uint32_t fault)
{
	char row[BBOX_CSV_MAX];

	fprintf(f, "%s\n", bbox_csv_header);
	for (uint32_t i = 0; i < n; i++) {
		bbox_csv_row(s[i], tick_hz, s[i]->tick == trigger ? fault : 0u, row, sizeof(row));
		fprintf(f, "%s\n", row);
	}
	return ferror(f) ? -1 : 0;
}

int bbox_file_write(const char *path, const bbox_sample_t *const *s, uint32_t n, uint32_t tick_hz,
		    uint32_t trigger, uint32_t fault)
{
	char tmp[4096];
	FILE *f;
	int rc;

	if ((size_t)snprintf(tmp, sizeof(tmp), "%s.tmp", path) >= sizeof(tmp)) {
		errno = ENAMETOOLONG;
		return -1;
	}
	f = fopen(tmp, "w");
	if (!f)
		return -1;
	rc = write_rows(f, s, n, tick_hz, trigger, fault);
	if (fclose(f) != 0)
		rc = -1;
	if (rc == 0 && rename(tmp, path) != 0)
		rc = -1;
	if (rc != 0) {
		int e = errno;
		remove(tmp);
		errno = e;
	}
	return rc;
}
