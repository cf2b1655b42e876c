/* Command link over the CMSDK APB UART, polled. Receive: whatever the data
 * register holds when the main loop asks. Transmit: a ring the main loop
 * drains while the transmitter has room, so a reply never stalls the control
 * loop; when the ring is full the rest of a reply is refused and the link
 * layer counts it. */
#include <string.h>

#include "board.h"

typedef struct {
	volatile uint32_t data;
	volatile uint32_t state; /* bit 0: TX full, bit 1: RX full */
	volatile uint32_t ctrl;	 /* bit 0: TX enable, bit 1: RX enable */
	volatile uint32_t intstatus;
	volatile uint32_t bauddiv;
} cmsdk_uart_t;

#define UART	   ((cmsdk_uart_t *)BOARD_UART_BASE)
#define ST_TX_FULL 1u
#define ST_RX_FULL 2u

#define TX_RING 1024u /* power of two; holds a whole console reply (CONSOLE_REPLY_MAX) */

static uint8_t tx_ring[TX_RING];
static uint32_t tx_head, tx_tail; /* free-running; head - tail = bytes queued */

void uart_init(void)
{
	UART->bauddiv = BOARD_UART_DIV;
	UART->ctrl = 3u;
}

/* At most a FIFO's worth a call: the main loop calls it once a pass, and a
 * long reply then goes out between ticks, never as one long stretch (a
 * model whose transmitter is never full, like QEMU's, would otherwise send
 * a whole reply in one go). */
#define TX_BURST 16u

void uart_poll_tx(void)
{
	for (unsigned k = 0; k < TX_BURST && tx_tail != tx_head && !(UART->state & ST_TX_FULL);
	     k++) {
		UART->data = tx_ring[tx_tail % TX_RING];
		tx_tail++;
	}
}

size_t uart_tx_pending(void)
{
	return tx_head - tx_tail;
}

size_t uart_tx_room(void)
{
	return TX_RING - (tx_head - tx_tail);
}

uint32_t uart_tx_sent(void)
{
	return tx_tail;
}

static size_t u_read(void *ctx, uint8_t *buf, size_t max)
{
	(void)ctx;
	size_t n = 0;
	while (n < max && (UART->state & ST_RX_FULL))
		buf[n++] = (uint8_t)UART->data;
	return n;
}

/* In at most two copies (the ring's end, then its start): a byte at a time,
 * a 1 KiB reply cost some 9,000 instructions. */
static size_t u_write(void *ctx, const uint8_t *buf, size_t len)
{
	(void)ctx;
	size_t room = uart_tx_room();
	size_t n = len < room ? len : room;
	size_t at = tx_head % TX_RING, first = TX_RING - at;
	if (first > n)
		first = n;
	memcpy(tx_ring + at, buf, first);
	memcpy(tx_ring, buf + first, n - first);
	tx_head += (uint32_t)n;
	return n;
}

const vs_link_t uart_link = {u_read, u_write, NULL};
