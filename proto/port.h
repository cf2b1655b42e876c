/* The unit's side of a serial port: what the console and the frame server
 * write their answers to. An answer goes out whole or, when the port stops
 * taking bytes, loses its rest (counted); the host's timeout and retry
 * recover it. Served by server_poll (server.h), the port is the serial
 * service's queue, which takes every answer whole; the board's UART ring
 * can refuse. The console and the frame server call the port; nothing here
 * calls them back.
 */
#ifndef PROTO_PORT_H
#define PROTO_PORT_H

#include <stddef.h>
#include <stdint.h>

#include "../hal/link.h"

typedef struct {
	vs_link_t io;
	uint32_t dropped; /* bytes the port did not take */
} port_t;

/* frame_write_fn and console_write_fn on a port_t. */
void port_send(void *port, const uint8_t *data, size_t n);
void port_send_text(void *port, const char *s, size_t n);

#endif
