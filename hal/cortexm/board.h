/* The Cortex-M board: an ARM CMSDK APB UART (as on the ARM MPS2 boards and
 * QEMU's mps2-an385/an386 machines) for the command link and the SysTick
 * timer for the control tick. Addresses and clock are build-time constants
 * (override with -D). */
#ifndef BOARD_H
#define BOARD_H

#include <stddef.h>
#include <stdint.h>

#include "../link.h"

#ifndef BOARD_CPU_HZ
#define BOARD_CPU_HZ 25000000u /* MPS2 FPGA images run the core at 25 MHz */
#endif
/* The planning a request or an idle call of the main loop takes at most
 * (vehicle_set_plan_budget): queued waypoints a corner-speed pass walks,
 * trial lines a cruise line's plan ahead runs. A whole pass over the
 * 16-deep queue costs about a period at 25 MHz (docs/performance.md). */
#define BOARD_PLAN_BUDGET 2u
#ifndef BOARD_UART_BASE
#define BOARD_UART_BASE 0x40004000u /* CMSDK UART0 */
#endif
#ifndef BOARD_UART_BAUD
#define BOARD_UART_BAUD 115200u
#endif
/* The UART's divisor, and the line speed it gives (115,207 baud at 25 MHz):
 * what the telemetry stream's budget counts with. */
#define BOARD_UART_DIV	     (BOARD_CPU_HZ / BOARD_UART_BAUD)
#define BOARD_UART_LINE_BAUD (BOARD_CPU_HZ / BOARD_UART_DIV)

/* UART: init, and the command link over it (never blocks; transmit bytes
 * wait in a ring and go out from uart_poll_tx). */
void uart_init(void);
void uart_poll_tx(void);
/* Bytes still waiting in the transmit ring, the room left in it, and the
 * bytes sent from it since uart_init (modulo 2^32). */
size_t uart_tx_pending(void);
size_t uart_tx_room(void);
uint32_t uart_tx_sent(void);
extern const vs_link_t uart_link;

/* SysTick: one interrupt per control period; the handler only counts. */
void systick_init(uint32_t tick_hz);
uint32_t systick_count(void);
/* Processor cycles since systick_init, modulo 2^32 (periods and the
 * counter's position in the current one): the cost of a piece of code is
 * the difference of two readings. */
uint32_t systick_cycles(void);
/* Microseconds since systick_init, modulo 2^32 (whole periods and the
 * counter's position): a clock whose differences hold across its wrap. */
uint32_t systick_us(void);
void SysTick_Handler(void);

#endif
