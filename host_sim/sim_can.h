/* vehicle-sim --can IFACE: the simulated unit's CAN link on a SocketCAN
 * interface (proto/canlink.h on hal/socketcan.h). Call sim_can_poll once per
 * simulator tick; it never blocks.
 */
#ifndef SIM_CAN_H
#define SIM_CAN_H

#include <stddef.h>

#include "../hal/socketcan.h"
#include "../proto/canlink.h"
#include "sim.h"

/* Most frames taken from the socket per poll, so a flood cannot hold up the
 * tick; the rest wait in the socket buffer (and overflow there, counted by
 * the kernel) until the next tick. */
#define SIM_CAN_RX_PER_POLL 256

typedef struct {
	sim_t *sim;
	sockcan_t sock;
	canlink_t link;
	bool reported; /* a socket error was reported (once) */
} sim_can_t;

/* Returns 0, or -1 with a message in err (no such interface, bad node or
 * rate). */
int sim_can_open(sim_can_t *sc, sim_t *s, const char *ifname, unsigned node, unsigned status_hz,
		 char *err, size_t cap);
void sim_can_poll(sim_can_t *sc);
void sim_can_close(sim_can_t *sc);

#endif
