/* The vehicle unit on a Cortex-M board: reference configuration, loopback
 * plant (loop_hal.h) behind the HAL, console and binary frames on the UART,
 * one vehicle_tick per SysTick period.
 *
 * Between ticks the main loop serves the link and drains the UART. A
 * period that passes while the previous tick or a command still runs is
 * seen by the firmware through now_us (its overrun fault), never silently
 * absorbed.
 */
#include "board.h"
#include "firmware/vehicle.h"
#include "loop_hal.h"
#include "proto/console.h"
#include "proto/link.h"

static loop_hal_t plant;
static vehicle_t unit;
static console_t con;
static link_t lnk;

/* The configuration lives on the stack only while vehicle_init copies it:
 * 1.2 KiB of RAM that is not held for good. */
static __attribute__((noinline)) uint32_t unit_init(void)
{
	vs_config_t cfg;
	vs_hal_t hal = {&loop_hal_ops, &plant};
	vs_config_defaults(&cfg);
	cfg.has_joystick = false;
	loop_hal_init(&plant, cfg.tick_hz);
	if (vehicle_init(&unit, &cfg, &hal, NULL) != 0)
		for (;;)
			;
	return cfg.tick_hz;
}

int main(void)
{
	uint32_t tick_hz = unit_init();
	uart_init();
	console_init(&con, &unit, NULL, NULL);
	link_init(&lnk, &con, &uart_link);
	systick_init(tick_hz);

	uint32_t done = systick_count();
	uint32_t period_us = 1000000u / tick_hz;
	for (;;) {
		uint32_t now = systick_count();
		if (now != done) {
			/* Late by several periods: the clock jumps, and the firmware
			 * sees it. */
			done = now;
			vehicle_tick(&unit, done * period_us);
			loop_hal_step(&plant);
			continue;
		}
		link_poll(&lnk, done * period_us / 1000u);
		uart_poll_tx();
	}
}
