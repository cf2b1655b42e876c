/* Helpers shared by the fd-based client transports (internal to proto/). */
#ifndef CLIENT_IO_H
#define CLIENT_IO_H

#include <stddef.h>
#include <stdint.h>

/* Monotonic milliseconds. */
uint64_t vcio_now_ms(void);
/* Writes all n bytes of a non-blocking fd within timeout_ms: VC_OK,
 * VC_E_TIMEOUT or VC_E_LINK. */
int vcio_write_all(int fd, const uint8_t *p, size_t n, unsigned timeout_ms);
/* Waits until deadline (vcio_now_ms time) for bytes: VC_OK with *got > 0,
 * VC_E_TIMEOUT, or VC_E_LINK on an error or hang-up. */
int vcio_read_some(int fd, uint8_t *buf, size_t cap, uint64_t deadline, size_t *got);

#endif
