/* GPIO lines through libgpiod (the 1.6 API of Debian 12).
 *
 * Lines are requested once at start-up; reads and writes on the tick are
 * single ioctls on the character device, never blocking. Active-low is
 * handled by the kernel (the request flag), so values here are logical:
 * true means "active" (e-stop pressed, relay commanded closed).
 */
#ifndef HAL_LINUX_GPIO_H
#define HAL_LINUX_GPIO_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "backend_cfg.h"

#define LGPIO_MAX_CHIPS 8

struct gpiod_chip;
struct gpiod_line;

typedef struct {
	uint32_t id;
	uint8_t width;
	bool out;
	struct gpiod_line *l[32];
} lgpio_io_t;

typedef struct {
	struct gpiod_chip *chip[LGPIO_MAX_CHIPS];
	char chip_name[LGPIO_MAX_CHIPS][HAL_IO_CHIP_MAX];
	unsigned nchips;
	struct gpiod_line *fn[BK_LINE_COUNT];
	lgpio_io_t io[VS_MAX_IO];
	unsigned nio;
	uint32_t errors; /* failed line reads/writes since open */
} lgpio_t;

/* Requests the function lines of bk and every mapped io.xml entry. -1 with
 * a message naming the chip and line on failure (everything released). */
int lgpio_open(lgpio_t *g, const backend_cfg_t *bk, const hal_io_map_t *io, char *err,
	       size_t errlen);
void lgpio_close(lgpio_t *g);
bool lgpio_has_fn(const lgpio_t *g, unsigned fn);
/* A function line's logical value; false when it has no line or the read
 * failed (counted in errors). */
bool lgpio_get_fn(lgpio_t *g, unsigned fn);
void lgpio_set_fn(lgpio_t *g, unsigned fn, bool on);
/* io.xml ids with a line mapping; false: the id is not mapped here. */
bool lgpio_io_read(lgpio_t *g, uint32_t id, uint32_t *value);
bool lgpio_io_write(lgpio_t *g, uint32_t id, uint32_t value);

#endif
