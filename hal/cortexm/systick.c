/* SysTick as the control-period clock. The handler only counts periods; the
 * main loop runs the tick, so the firmware is never entered from two
 * contexts at once. */
#include "board.h"

#define SYST_CSR       (*(volatile uint32_t *)0xE000E010u)
#define SYST_RVR       (*(volatile uint32_t *)0xE000E014u)
#define SYST_CVR       (*(volatile uint32_t *)0xE000E018u)
#define SCB_ICSR       (*(volatile uint32_t *)0xE000ED04u)
#define ICSR_PENDSTSET (1u << 26)

#define CYCLES_PER_US (BOARD_CPU_HZ / 1000000u)

static volatile uint32_t periods;
static uint32_t period_cycles;

void systick_init(uint32_t tick_hz)
{
	period_cycles = BOARD_CPU_HZ / tick_hz;
	SYST_RVR = period_cycles - 1u;
	SYST_CVR = 0;
	SYST_CSR = 7u; /* processor clock, interrupt, enable */
}

uint32_t systick_count(void)
{
	return periods;
}

/* The periods counted and the counter, read together: with interrupts
 * held, a wrap not yet counted by the handler shows as PENDSTSET; count it
 * here, and read the counter again after it. */
static uint32_t snapshot(uint32_t *v)
{
	uint32_t primask, p;

	__asm volatile("mrs %0, primask\n\tcpsid i" : "=r"(primask)::"memory");
	p = periods;
	*v = SYST_CVR;
	if (SCB_ICSR & ICSR_PENDSTSET) {
		p++;
		*v = SYST_CVR;
	}
	__asm volatile("msr primask, %0" ::"r"(primask) : "memory");
	return p;
}

uint32_t systick_cycles(void)
{
	uint32_t v, p = snapshot(&v);
	return p * period_cycles + (period_cycles - 1u - v);
}

uint32_t systick_us(void)
{
	uint32_t v, p = snapshot(&v);
	return p * (period_cycles / CYCLES_PER_US) + (period_cycles - 1u - v) / CYCLES_PER_US;
}

void SysTick_Handler(void)
{
	periods = periods + 1u;
}
