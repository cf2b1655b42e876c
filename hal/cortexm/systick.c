/* SysTick as the control-period clock. The handler only counts periods; the
 * main loop runs the tick, so the firmware is never entered from two
 * contexts at once. */
#include "board.h"

#define SYST_CSR (*(volatile uint32_t *)0xE000E010u)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014u)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018u)

static volatile uint32_t periods;

void systick_init(uint32_t tick_hz)
{
	SYST_RVR = BOARD_CPU_HZ / tick_hz - 1u;
	SYST_CVR = 0;
	SYST_CSR = 7u; /* processor clock, interrupt, enable */
}

uint32_t systick_count(void)
{
	return periods;
}

void SysTick_Handler(void)
{
	periods = periods + 1u;
}
