/* Command link byte stream (serial console and binary frames).
 * read returns the number of bytes copied (0: nothing pending), never blocks;
 * write queues bytes and returns the number accepted. */
#ifndef HAL_LINK_H
#define HAL_LINK_H

#include <stddef.h>
#include <stdint.h>

typedef struct {
	size_t (*read)(void *ctx, uint8_t *buf, size_t max);
	size_t (*write)(void *ctx, const uint8_t *buf, size_t len);
	void *ctx;
} vs_link_t;

#endif
