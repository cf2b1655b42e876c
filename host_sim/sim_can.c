/* The simulated unit's CAN link (see sim_can.h). */
#include "sim_can.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

static bool can_send(void *ctx, const canlink_frame_t *f)
{
	sim_can_t *sc = ctx;

	int r = sockcan_send(&sc->sock, f);
	/* Interface down, for instance: say so once, keep serving. */
	if (r < 0 && !sc->reported) {
		fprintf(stderr, "vehicle-sim: CAN send: %s\n", strerror(errno));
		sc->reported = true;
	}
	return r > 0;
}

int sim_can_open(sim_can_t *sc, sim_t *s, const char *ifname, unsigned node, unsigned status_hz,
		 char *err, size_t cap)
{
	memset(sc, 0, sizeof(*sc));
	sc->sim = s;
	sc->sock.fd = -1;
	if (node < CANLINK_NODE_MIN || node > CANLINK_NODE_MAX) {
		snprintf(err, cap, "--node: %d..%d", CANLINK_NODE_MIN, CANLINK_NODE_MAX);
		return -1;
	}
	if (status_hz > CANLINK_STATUS_HZ_MAX) {
		snprintf(err, cap, "--status-hz: 0..%d", CANLINK_STATUS_HZ_MAX);
		return -1;
	}
	canlink_config_t cfg = {.node = (uint8_t)node, .status_hz = (uint16_t)status_hz};
	if (canlink_init(&sc->link, sim_vehicle(s), &cfg, can_send, sc) < 0) {
		snprintf(err, cap, "CAN link configuration rejected");
		return -1;
	}
	/* Only the request identifier reaches the unit; the kernel filters. */
	uint32_t id = CANLINK_ID_REQUEST + node;
	if (sockcan_open(&sc->sock, ifname, &id, 1) < 0) {
		snprintf(err, cap, "CAN interface %s: %s", ifname, strerror(errno));
		return -1;
	}
	return 0;
}

void sim_can_poll(sim_can_t *sc)
{
	uint32_t now_us = (uint32_t)sc->sim->now_us;

	for (int i = 0; i < SIM_CAN_RX_PER_POLL; i++) {
		canlink_frame_t f;
		int r = sockcan_recv(&sc->sock, &f);
		if (r == 0)
			break;
		if (r < 0) {
			if (!sc->reported)
				fprintf(stderr, "vehicle-sim: CAN receive: %s\n", strerror(errno));
			sc->reported = true;
			break;
		}
		canlink_rx(&sc->link, &f, now_us);
	}
	canlink_poll(&sc->link, now_us);
}

void sim_can_close(sim_can_t *sc)
{
	const canlink_stats_t *t = &sc->link.stats;

	/* One line of counters, for the operator and for the guest tests. */
	fprintf(stderr,
		"vehicle-sim: CAN counters: rx %lu foreign %lu bad_dlc %lu bad_pci %lu "
		"sequence %lu discarded %lu aborted %lu timeouts %lu oversize %lu short %lu "
		"requests %lu replays %lu naks %lu tx %lu tx_busy %lu tx_abandoned %lu "
		"flow_rx %lu flow_tx %lu fc_timeouts %lu overflow %lu "
		"status_sent %lu status_dropped %lu sock_tx_full %lu sock_rx_dropped %lu "
		"sock_rx_overflow %lu\n",
		(unsigned long)t->rx_frames, (unsigned long)t->rx_foreign,
		(unsigned long)t->rx_bad_dlc, (unsigned long)t->rx_bad_pci,
		(unsigned long)t->rx_sequence, (unsigned long)t->rx_discarded,
		(unsigned long)t->rx_aborted, (unsigned long)t->rx_timeouts,
		(unsigned long)t->rx_oversize, (unsigned long)t->rx_short,
		(unsigned long)t->requests, (unsigned long)t->replays, (unsigned long)t->naks,
		(unsigned long)t->tx_frames, (unsigned long)t->tx_busy,
		(unsigned long)t->tx_abandoned, (unsigned long)t->rx_flow,
		(unsigned long)t->fc_sent, (unsigned long)t->tx_fc_timeouts,
		(unsigned long)t->tx_overflow, (unsigned long)t->status_sent,
		(unsigned long)t->status_dropped, (unsigned long)sc->sock.tx_full,
		(unsigned long)sc->sock.rx_dropped, (unsigned long)sc->sock.rx_overflow);
	sockcan_close(&sc->sock);
}
