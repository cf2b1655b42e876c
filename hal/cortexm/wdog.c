/* Watchdog, fault handlers and the reset's record; see wdog.h. */
#include "wdog.h"

#include "board.h"
#include "plant.h"
#include "proto/fmt.h"

typedef struct {
	volatile uint32_t load, value, ctrl, intclr, ris, mis;
} cmsdk_wdog_t;

#define WDOG	    ((cmsdk_wdog_t *)0x40008000u)
#define WDOG_LOCK   (*(volatile uint32_t *)0x40008C00u)
#define WDOG_UNLOCK 0x1ACCE551u
#define WDOG_INTEN  1u
#define WDOG_RESEN  2u
#define SCB_AIRCR   (*(volatile uint32_t *)0xE000ED0Cu)
#define AIRCR_RESET 0x05FA0004u /* VECTKEY, SYSRESETREQ */
#define NOTE_CHECK  0x5AFEC0DEu

/* In .noinit: the start-up code neither loads nor clears it. */
static struct {
	uint32_t cause, pc, check;
} note __attribute__((section(".noinit")));

void wdog_start(void)
{
	WDOG_LOCK = WDOG_UNLOCK;
	WDOG->load = BOARD_CPU_HZ / 1000u * WDOG_PERIOD_MS;
	WDOG->intclr = 1u;
	WDOG->ctrl = WDOG_INTEN | WDOG_RESEN;
	WDOG_LOCK = 0; /* locked: a stray write cannot stop it */
}

void wdog_feed(void)
{
	WDOG_LOCK = WDOG_UNLOCK;
	WDOG->intclr = 1u; /* reloads the counter */
	WDOG_LOCK = 0;
}

uint32_t wdog_reset_cause(uint32_t *pc)
{
	uint32_t c = note.check == (NOTE_CHECK ^ note.cause ^ note.pc) ? note.cause : 0;
	*pc = note.pc;
	note.check = 0;
	return c;
}

size_t wdog_restart_text(char *buf, size_t cap)
{
	uint32_t pc = 0, c = wdog_reset_cause(&pc);
	if (c != WDOG_CAUSE_WATCHDOG && c != WDOG_CAUSE_HARDFAULT)
		return 0;
	size_t n =
	    fmt_print(buf, cap, "reset by %s at 0x%08X",
		      c == WDOG_CAUSE_WATCHDOG ? "the watchdog" : "a HardFault", (unsigned)pc);
	size_t end = n < cap ? n : cap ? cap - 1u : 0u;
	/* the console's hexadecimal is upper-case: the address's 8 digits
	 * lowered (a digit has that bit set already) */
	for (size_t i = n - 8u; i < end; i++)
		buf[i] = (char)(buf[i] | 0x20);
	return end;
}

/* Both handlers: the drives off first, then the record. sp: the exception
 * frame (r0-r3, r12, lr, pc, xpsr). */
void fault_entry(const uint32_t *sp, uint32_t cause);
__attribute__((used)) void fault_entry(const uint32_t *sp, uint32_t cause)
{
	plant_emergency_off();
	note.cause = cause;
	note.pc = sp[6];
	note.check = NOTE_CHECK ^ note.cause ^ note.pc;
	if (cause == WDOG_CAUSE_HARDFAULT)
		SCB_AIRCR = AIRCR_RESET;
	/* the watchdog's second expiry resets the board */
	for (;;)
		;
}

/* The board runs on the main stack only: the frame is at msp. */
__attribute__((naked)) void NMI_Handler(void)
{
	__asm volatile("mrs r0, msp\n\t"
		       "movs r1, #1\n\t"
		       "ldr r2, =fault_entry\n\t"
		       "bx r2\n\t"
		       ".ltorg");
}

__attribute__((naked)) void HardFault_Handler(void)
{
	__asm volatile("mrs r0, msp\n\t"
		       "movs r1, #2\n\t"
		       "ldr r2, =fault_entry\n\t"
		       "bx r2\n\t"
		       ".ltorg");
}
