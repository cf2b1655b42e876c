/* The CMSDK APB watchdog (MPS2: 0x40008000, clocked at the core's 25 MHz,
 * its interrupt wired to NMI) and what survives a reset.
 *
 * The tick feeds it (wdog_feed). A loop that stops ticking lets it run out:
 * the first expiry raises NMI, whose handler turns the drives off
 * (plant_emergency_off) and notes the cause; the second expiry, one period
 * later, resets the board. A HardFault does the same in its own handler and
 * requests the reset at once. The cause is a record in .noinit, RAM that
 * the start-up code never clears (a reset keeps it; a power-up leaves
 * garbage, which its check word rejects): QEMU's MPS2 has no reset-cause
 * register, and on a part that has one the record still says more (where
 * the core was).
 */
#ifndef WDOG_H
#define WDOG_H

#include <stddef.h>
#include <stdint.h>

/* Watchdog period: the tick must feed within it. */
#define WDOG_PERIOD_MS 100u

enum { WDOG_CAUSE_NONE = 0, WDOG_CAUSE_WATCHDOG = 1, WDOG_CAUSE_HARDFAULT = 2 };

/* The first expiry (NMI) and a HardFault: drives off, then the reset. */
void NMI_Handler(void);
void HardFault_Handler(void);

void wdog_start(void);
void wdog_feed(void);
/* The cause of the last reset as the handlers left it (WDOG_CAUSE_*) and
 * where the core was (*pc); the record is cleared. */
uint32_t wdog_reset_cause(uint32_t *pc);
/* The restart's alarm text ("reset by the watchdog at 0x...", "reset by a
 * HardFault at 0x..."): its length, 0 when the last start was not such a
 * reset. */
size_t wdog_restart_text(char *buf, size_t cap);

#endif
