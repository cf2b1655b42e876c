/* Linux SocketCAN raw socket for the CAN link (classic frames, 11-bit ids).
 *
 * Non-blocking throughout: a send the kernel cannot queue now (ENOBUFS,
 * EAGAIN) is counted and reported as "try later", never waited for, so a
 * full bus or a missing peer cannot stall the control tick. Received
 * extended, remote, error and CAN FD frames are dropped with a counter:
 * the link speaks only 11-bit data frames.
 */
#ifndef HAL_SOCKETCAN_H
#define HAL_SOCKETCAN_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "../link.h"

typedef struct {
	int fd;
	uint32_t tx_frames, tx_full, tx_errors;
	uint32_t rx_frames, rx_dropped, rx_errors;
	uint32_t rx_overflow; /* dropped by the kernel: receive buffer full (cumulative) */
	bool reported;	      /* a send or receive error was logged (once) */
} sockcan_t;

/* Opens and binds a raw CAN socket on ifname. When ids is not NULL the
 * kernel passes only standard data frames with those n identifiers.
 * Returns 0, or -1 with errno set (ENODEV: no such interface). */
int sockcan_open(sockcan_t *s, const char *ifname, const uint32_t *ids, size_t n);
/* 1 sent, 0 transmit queue full (counted; try again later), -1 error. */
int sockcan_send(sockcan_t *s, const canlink_frame_t *f);
/* 1 frame received, 0 nothing pending, -1 error. */
int sockcan_recv(sockcan_t *s, canlink_frame_t *f);
/* Waits up to timeout_ms (-1: forever) for a frame to read: 1 readable,
 * 0 timeout, -1 error. */
int sockcan_wait(sockcan_t *s, int timeout_ms);
void sockcan_close(sockcan_t *s);

/* s as the command server's CAN port (hal/link.h). The first send or
 * receive error is logged (rt_log), the rest only counted; serving goes on. */
vs_can_port_t sockcan_port(sockcan_t *s);
/* The socket's counters as one "sock_tx_full N ..." line (no newline). */
void sockcan_counters(const sockcan_t *s, char *buf, size_t cap);

#endif
