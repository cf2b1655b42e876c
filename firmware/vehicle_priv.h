/* VehicleService core internals shared by its files; vehicle.h is the
 * interface. vehicle.c (operations) and vehicle_tick.c (the control tick)
 * both use vehicle_fault.c; vehicle.c asks vehicle_tick.c whether the unit
 * is in position (vehicle_in_position, vehicle.h). */
#ifndef VEHICLE_PRIV_H
#define VEHICLE_PRIV_H

#include <stddef.h>
#include <stdint.h>

#include "vehicle.h"

/* Text into b (capacity cap) from pos on, kept terminated; each returns
 * the new end. */
size_t vehicle_put_str(char *b, size_t cap, size_t pos, const char *s);
size_t vehicle_put_dec(char *b, size_t cap, size_t pos, uint32_t val, unsigned min_digits);
size_t vehicle_put_hex4(char *b, size_t cap, size_t pos, uint16_t val);
size_t vehicle_put_volts(char *b, size_t cap, size_t pos, uint32_t mv);
/* "<what><axis><tail>" */
void vehicle_axis_text(char *s, size_t cap, const char *what, uint8_t axis, const char *tail);

void vehicle_servo_off(vehicle_t *v);
/* Read every drive once (vehicle_tick.c): what the tick does first. */
void vehicle_sample_drives(vehicle_t *v);
void vehicle_raise_fault(vehicle_t *v, uint32_t code, const char *text);
void vehicle_raise_fault_level(vehicle_t *v, uint32_t code, const char *text);

#endif
