/* The board's plant behind the HAL, chosen at build time (mk/cortexm.mk,
 * MCU_DRIVES): plant_modbus.c, wheel drives over RS-485 Modbus RTU on the
 * second UART (the product), or plant_loop.c, the loopback of loop_hal.h
 * (a bare evaluation board, the board tests' reference). Both run the
 * hardware watchdog (wdog.h). */
#ifndef PLANT_H
#define PLANT_H

#include <stdbool.h>
#include <stddef.h>

#include "firmware/vehicle.h"

/* The plant's part of the compiled-in configuration (drive lag, drive
 * timeout), before the store's changes go over it. */
void plant_config(vs_config_t *cfg);
/* The plant set up for the configuration in force; its HAL. */
vs_hal_t plant_hal(const vs_config_t *cfg);
/* After vehicle_init: the restart's alarm (wdog.h). */
void plant_start(vehicle_t *v);
/* After each tick: the watchdog fed, the loopback's wheels moved. */
void plant_tick(void);
/* Each pass of the main loop: the drive bus advanced. */
void plant_poll(void);
/* The plant's '$' extras (console_extra_fn): $mb on the Modbus board, and
 * the test image's (board_test_extra). */
bool plant_extra(void *ctx, int argc, char **argv, char *reply, size_t cap);
/* From a fault handler: the drives' power line off and each drive told to
 * disable, by polling (interrupts are not served there). */
void plant_emergency_off(void);

/* The test image's extras (tests/mcu: $hang, $fault), linked there only. */
extern bool board_test_extra(int argc, char **argv, char *reply, size_t cap) __attribute__((weak));

#endif
