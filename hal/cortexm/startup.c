/* Reset and exception entry for Cortex-M0/M4 (ARMv6-M / ARMv7-M): the vector
 * table, .data copied from flash, .bss cleared, then main. Symbols come from
 * cortex-m4.ld / cortex-m0.ld. */
#include <stdint.h>

#include "board.h"

extern uint32_t _sidata, _sdata, _edata, _sbss, _ebss, _estack;
int main(void);

void Reset_Handler(void);
void Default_Handler(void);
void HardFault_Handler(void);
void NMI_Handler(void);

void Reset_Handler(void)
{
	uint32_t *src = &_sidata, *dst = &_sdata;
	/* The linker's symbols bound one region each: comparing them is the
	 * point, though C sees distinct objects. */
	// cppcheck-suppress comparePointers
	while (dst < &_edata)
		*dst++ = *src++;
	// cppcheck-suppress comparePointers
	for (dst = &_sbss; dst < &_ebss;)
		*dst++ = 0;
	main();
	for (;;)
		;
}

/* Unexpected interrupt: stop here with the drives' last setpoint expiring
 * in the drives' own watchdog. */
void Default_Handler(void)
{
	for (;;)
		;
}

/* wdog.c's handlers take the drives off and reset the board; an image
 * without them stops here. */
void NMI_Handler(void) __attribute__((weak, alias("Default_Handler")));
void HardFault_Handler(void) __attribute__((weak, alias("Default_Handler")));
void SVC_Handler(void) __attribute__((weak, alias("Default_Handler")));
void PendSV_Handler(void) __attribute__((weak, alias("Default_Handler")));

typedef void (*vector_t)(void);

/* Core exceptions only: the board uses no peripheral interrupt (the UART is
 * polled between ticks). */
__attribute__((section(".isr_vector"), used)) static const vector_t vectors[16] = {
    /* word 0 is the initial stack pointer, an address the core loads */
    // NOLINTNEXTLINE(performance-no-int-to-ptr)
    (vector_t)(uintptr_t)&_estack,
    Reset_Handler,
    NMI_Handler,
    HardFault_Handler,
    Default_Handler, /* MemManage (ARMv7-M) */
    Default_Handler, /* BusFault (ARMv7-M) */
    Default_Handler, /* UsageFault (ARMv7-M) */
    0,
    0,
    0,
    0,
    SVC_Handler,
    Default_Handler, /* DebugMon (ARMv7-M) */
    0,
    PendSV_Handler,
    SysTick_Handler,
};
