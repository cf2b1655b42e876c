/* The link types a platform moves: the command link's byte stream (serial
 * console and binary frames) and a classic CAN frame (the CAN command link,
 * CAN drives). */
#ifndef HAL_LINK_H
#define HAL_LINK_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* Line speed of a serial command link unless configured (8N1). */
#define VS_LINK_DEFAULT_BAUD 115200

/* Command link byte stream. read returns the number of bytes copied (0:
 * nothing pending), never blocks; write queues bytes and returns the number
 * accepted. */
typedef struct {
	size_t (*read)(void *ctx, uint8_t *buf, size_t max);
	size_t (*write)(void *ctx, const uint8_t *buf, size_t len);
	void *ctx;
} vs_link_t;

/* A classic CAN data frame. */
typedef struct {
	uint32_t id; /* 11-bit standard identifier */
	uint8_t dlc; /* 0..8 */
	uint8_t data[8];
} canlink_frame_t;

/* A CAN port, as the command link's server sees it. recv takes one
 * received frame: 1, 0 when none is pending, -1 on an error (the port
 * reports it); it never blocks. send queues one frame, false when the port
 * cannot take it now. */
typedef struct {
	int (*recv)(void *ctx, canlink_frame_t *f);
	bool (*send)(void *ctx, const canlink_frame_t *f);
	void *ctx;
} vs_can_port_t;

#endif
