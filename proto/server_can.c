/* The server's CAN command link (see server.h). */
#include "server.h"

#include "fmt.h"

static bool can_send(void *ctx, const canlink_frame_t *f)
{
	const vs_server_t *s = ctx;

	return s->can_port.send(s->can_port.ctx, f);
}

static void poll_can(vs_server_t *s, uint32_t now_us)
{
	for (int i = 0; i < SERVER_CAN_RX_PER_POLL; i++) {
		canlink_frame_t f;
		int r = s->can_port.recv(s->can_port.ctx, &f);

		if (r == 0)
			break;
		if (r < 0) {
			s->can_port_errors++;
			break;
		}
		canlink_rx(s->can, &f, now_us);
	}
	canlink_poll(s->can, now_us);
}

int server_attach_can(vs_server_t *s, canlink_t *can, const vs_can_port_t *port,
		      const canlink_config_t *cfg)
{
	if (canlink_init(can, s->v, cfg, can_send, s) < 0)
		return -1;
	s->can = can;
	s->can_port = *port;
	s->poll_can = poll_can;
	return 0;
}

void server_can_counters(const vs_server_t *s, char *buf, size_t cap)
{
	const canlink_stats_t *t = &s->can->stats;

	fmt_print(
	    buf, cap,
	    "rx %lu foreign %lu bad_dlc %lu bad_pci %lu sequence %lu discarded %lu "
	    "aborted %lu timeouts %lu oversize %lu short %lu requests %lu replays %lu "
	    "naks %lu tx %lu tx_busy %lu tx_abandoned %lu flow_rx %lu flow_tx %lu "
	    "fc_timeouts %lu overflow %lu status_sent %lu status_dropped %lu",
	    (unsigned long)t->rx_frames, (unsigned long)t->rx_foreign, (unsigned long)t->rx_bad_dlc,
	    (unsigned long)t->rx_bad_pci, (unsigned long)t->rx_sequence,
	    (unsigned long)t->rx_discarded, (unsigned long)t->rx_aborted,
	    (unsigned long)t->rx_timeouts, (unsigned long)t->rx_oversize,
	    (unsigned long)t->rx_short, (unsigned long)t->requests, (unsigned long)t->replays,
	    (unsigned long)t->naks, (unsigned long)t->tx_frames, (unsigned long)t->tx_busy,
	    (unsigned long)t->tx_abandoned, (unsigned long)t->rx_flow, (unsigned long)t->fc_sent,
	    (unsigned long)t->tx_fc_timeouts, (unsigned long)t->tx_overflow,
	    (unsigned long)t->status_sent, (unsigned long)t->status_dropped);
}
