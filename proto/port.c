/* A serial port's transmit side (see port.h). */
#include "port.h"

void port_send(void *port, const uint8_t *data, size_t n)
{
	port_t *p = port;
	size_t done = 0;

	while (done < n && p->io.write) {
		size_t k = p->io.write(p->io.ctx, data + done, n - done);

		if (k == 0)
			break;
		done += k;
	}
	p->dropped += (uint32_t)(n - done);
}

void port_send_text(void *port, const char *s, size_t n)
{
	port_send(port, (const uint8_t *)s, n);
}
