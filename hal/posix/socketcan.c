/* Linux SocketCAN raw socket (see socketcan.h). */
#include "socketcan.h"

#include <errno.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include "rt.h"

/* Most receive filters one socket installs. */
#define SOCKCAN_MAX_FILTERS 16

int sockcan_open(sockcan_t *s, const char *ifname, const uint32_t *ids, size_t n)
{
	struct sockaddr_can addr;
	struct ifreq ifr;

	memset(s, 0, sizeof(*s));
	s->fd = -1;
	if (strlen(ifname) >= sizeof(ifr.ifr_name) || n > SOCKCAN_MAX_FILTERS) {
		errno = EINVAL;
		return -1;
	}
	int fd = socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
	if (fd < 0)
		return -1;
	memset(&ifr, 0, sizeof(ifr));
	memcpy(ifr.ifr_name, ifname, strlen(ifname)); /* fits, checked above; NUL from memset */
	if (ioctl(fd, SIOCGIFINDEX, &ifr) < 0)
		goto fail;
	if (ids) {
		struct can_filter flt[SOCKCAN_MAX_FILTERS];
		for (size_t i = 0; i < n; i++) {
			flt[i].can_id = ids[i] & CAN_SFF_MASK;
			/* exact standard id, and neither extended nor remote */
			flt[i].can_mask = CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG;
		}
		if (setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, flt,
			       (socklen_t)(n * sizeof(flt[0]))) < 0)
			goto fail;
	}
	/* The kernel counts frames it dropped for a full receive buffer. */
	int on = 1;
	(void)setsockopt(fd, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof(on));
	memset(&addr, 0, sizeof(addr));
	addr.can_family = AF_CAN;
	addr.can_ifindex = ifr.ifr_ifindex;
	if (bind(fd, (struct sockaddr *)&addr, sizeof(addr)) < 0)
		goto fail;
	s->fd = fd;
	return 0;
fail : {
	int e = errno;
	close(fd);
	errno = e;
	return -1;
}
}

int sockcan_send(sockcan_t *s, const canlink_frame_t *f)
{
	struct can_frame cf;

	if (f->dlc > 8 || f->id > CAN_SFF_MASK) {
		s->tx_errors++;
		errno = EINVAL;
		return -1;
	}
	memset(&cf, 0, sizeof(cf));
	cf.can_id = f->id;
	cf.len = f->dlc;
	memcpy(cf.data, f->data, f->dlc);
	for (;;) {
		ssize_t r = write(s->fd, &cf, sizeof(cf));
		if (r == (ssize_t)sizeof(cf)) {
			s->tx_frames++;
			return 1;
		}
		if (r < 0 && errno == EINTR)
			continue;
		if (r < 0 && (errno == ENOBUFS || errno == EAGAIN)) {
			s->tx_full++;
			return 0;
		}
		s->tx_errors++;
		if (r >= 0)
			errno = EIO;
		return -1;
	}
}

int sockcan_recv(sockcan_t *s, canlink_frame_t *f)
{
	struct can_frame cf;
	union {
		char buf[CMSG_SPACE(sizeof(uint32_t))];
		struct cmsghdr align;
	} ctl;

	for (;;) {
		struct iovec iov = {.iov_base = &cf, .iov_len = sizeof(cf)};
		struct msghdr msg = {.msg_iov = &iov,
				     .msg_iovlen = 1,
				     .msg_control = ctl.buf,
				     .msg_controllen = sizeof(ctl.buf)};
		ssize_t r = recvmsg(s->fd, &msg, 0);
		if (r < 0) {
			if (errno == EINTR)
				continue;
			if (errno == EAGAIN)
				return 0;
			s->rx_errors++;
			return -1;
		}
		for (struct cmsghdr *c = CMSG_FIRSTHDR(&msg); c; c = CMSG_NXTHDR(&msg, c))
			if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL)
				memcpy(&s->rx_overflow, CMSG_DATA(c), sizeof(s->rx_overflow));
		if (r != (ssize_t)sizeof(cf) ||
		    (cf.can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG | CAN_ERR_FLAG)) || cf.len > 8) {
			s->rx_dropped++;
			continue;
		}
		memset(f, 0, sizeof(*f));
		f->id = cf.can_id & CAN_SFF_MASK;
		f->dlc = cf.len;
		memcpy(f->data, cf.data, cf.len);
		s->rx_frames++;
		return 1;
	}
}

int sockcan_wait(sockcan_t *s, int timeout_ms)
{
	struct pollfd p = {.fd = s->fd, .events = POLLIN};

	for (;;) {
		int r = poll(&p, 1, timeout_ms);
		if (r < 0 && errno == EINTR)
			continue;
		if (r < 0)
			return -1;
		return r > 0 ? 1 : 0;
	}
}

void sockcan_close(sockcan_t *s)
{
	if (s->fd >= 0)
		close(s->fd);
	s->fd = -1;
}

static void report_once(sockcan_t *s, const char *what)
{
	if (!s->reported)
		rt_log(LOG_ERR, "CAN %s: %s", what, strerror(errno));
	s->reported = true;
}

static int port_recv(void *ctx, canlink_frame_t *f)
{
	int r = sockcan_recv(ctx, f);

	if (r < 0)
		report_once(ctx, "receive");
	return r;
}

/* Interface down, for instance: say so once, keep serving. */
static bool port_send(void *ctx, const canlink_frame_t *f)
{
	int r = sockcan_send(ctx, f);

	if (r < 0)
		report_once(ctx, "send");
	return r > 0;
}

vs_can_port_t sockcan_port(sockcan_t *s)
{
	vs_can_port_t p = {port_recv, port_send, s};
	return p;
}

void sockcan_counters(const sockcan_t *s, char *buf, size_t cap)
{
	snprintf(buf, cap, "sock_tx_full %lu sock_rx_dropped %lu sock_rx_overflow %lu",
		 (unsigned long)s->tx_full, (unsigned long)s->rx_dropped,
		 (unsigned long)s->rx_overflow);
}
