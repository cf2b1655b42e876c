/* hal_store_t over one file, replaced whole at each step (filestore.h). */
#include "filestore.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

static bool fs_read(void *ctx, uint32_t off, void *buf, uint32_t n)
{
	filestore_t *fs = ctx;
	if (off > sizeof fs->img || n > sizeof fs->img - off)
		return false;
	memcpy(buf, fs->img + off, n);
	return true;
}

static bool write_all(int fd, const uint8_t *p, size_t n)
{
	while (n) {
		ssize_t w = write(fd, p, n);
		if (w < 0 && errno == EINTR)
			continue;
		if (w <= 0)
			return false;
		p += w;
		n -= (size_t)w;
	}
	return true;
}

/* The image to FILE.tmp, synced, renamed over FILE, the folder synced. */
static bool replace_file(filestore_t *fs)
{
	char tmp[sizeof fs->path + 8], dir[sizeof fs->path];
	snprintf(tmp, sizeof tmp, "%s.tmp", fs->path);
	int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
	if (fd < 0)
		return false;
	bool ok = write_all(fd, fs->img, sizeof fs->img) && fsync(fd) == 0;
	ok = close(fd) == 0 && ok;
	if (!ok || rename(tmp, fs->path) != 0) {
		unlink(tmp);
		return false;
	}
	const char *slash = strrchr(fs->path, '/');
	snprintf(dir, sizeof dir, "%.*s", slash ? (int)(slash - fs->path + 1) : 1,
		 slash ? fs->path : ".");
	int dfd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
	if (dfd < 0)
		return false;
	ok = fsync(dfd) == 0;
	close(dfd);
	fs->writes++;
	return ok;
}

static bool fs_erase(void *ctx, uint32_t page)
{
	filestore_t *fs = ctx;
	if (page >= FILESTORE_PAGES)
		return false;
	memset(fs->img + (size_t)page * FILESTORE_PAGE, 0xFF, FILESTORE_PAGE);
	return replace_file(fs);
}

static bool fs_program(void *ctx, uint32_t off, const void *buf, uint32_t n)
{
	filestore_t *fs = ctx;
	if (off % FILESTORE_WORD || n % FILESTORE_WORD || off > sizeof fs->img ||
	    n > sizeof fs->img - off)
		return false;
	for (uint32_t i = 0; i < n; i++)
		if (fs->img[off + i] != 0xFF)
			return false; /* a word programmed twice */
	memcpy(fs->img + off, buf, n);
	return replace_file(fs);
}

int filestore_open(filestore_t *fs, const char *path, char *err, size_t cap)
{
	memset(fs, 0, sizeof *fs);
	if (strlen(path) >= sizeof fs->path) {
		snprintf(err, cap, "%.64s...: path too long", path);
		return -1;
	}
	snprintf(fs->path, sizeof fs->path, "%s", path);
	memset(fs->img, 0xFF, sizeof fs->img);
	int fd = open(path, O_RDONLY | O_CLOEXEC);
	if (fd < 0 && errno != ENOENT) {
		snprintf(err, cap, "%s: %s", path, strerror(errno));
		return -1;
	}
	if (fd >= 0) {
		size_t got = 0;
		ssize_t r;
		while (got < sizeof fs->img &&
		       ((r = read(fd, fs->img + got, sizeof fs->img - got)) > 0 ||
			(r < 0 && errno == EINTR)))
			got += r > 0 ? (size_t)r : 0;
		close(fd);
	}
	fs->hs = (hal_store_t){.page_size = FILESTORE_PAGE,
			       .pages = FILESTORE_PAGES,
			       .word = FILESTORE_WORD,
			       .erased_byte = 0xFF,
			       .read = fs_read,
			       .erase = fs_erase,
			       .program = fs_program,
			       .ctx = fs};
	return 0;
}
