/* The configuration store (hal_store_t, hal/hal.h) on a computer: one file
 * holding every page, replaced whole at each erase and each program (the
 * new image written to FILE.tmp, synced, renamed over FILE, the folder
 * synced), so that a power cut leaves the file as it was before the step
 * or after it. The page and word rules are a flash part's: an erase sets a
 * page to 0xFF, a program writes whole erased words only (anything else is
 * refused as an error, as a part would leave it damaged).
 *
 * A missing file reads erased and is written at the first save. A file of
 * another size is read as far as it goes (the rest erased): the store's
 * records then fail their checks and the unit says so. */
#ifndef HAL_POSIX_FILESTORE_H
#define HAL_POSIX_FILESTORE_H

#include <stddef.h>
#include <stdint.h>

#include "../hal.h"

#define FILESTORE_PAGE	1024u
#define FILESTORE_PAGES 4u
#define FILESTORE_WORD	8u

typedef struct {
	char path[4096];
	uint8_t img[FILESTORE_PAGE * FILESTORE_PAGES];
	uint32_t writes; /* file replacements made */
	hal_store_t hs;
} filestore_t;

/* 0, or -1 with the reason in err (a path too long, a file unreadable). */
int filestore_open(filestore_t *fs, const char *path, char *err, size_t cap);

#endif
