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
/* "<what><axis><tail>"; returns its length. */
size_t vehicle_axis_text(char *s, size_t cap, const char *what, uint8_t axis, const char *tail);

/* Drives that report their state, their enable and a restart (hal.h): the
 * servo on waits for them, a drive leaving Operation enabled or restarting
 * is supervised. A board whose drives are its own loopback (enabled at
 * once, never restarting) leaves this out (-DVS_NO_DRIVE_STATES). */
#ifdef VS_NO_DRIVE_STATES
#define VS_DRIVE_STATES 0
#else
#define VS_DRIVE_STATES 1
#endif

/* Servo on still waiting for a drive (always false without drive states). */
#define vehicle_servo_waiting(v) (VS_DRIVE_STATES && (v)->servo_wait)

/* The stick must come back to neutral before it drives (docs/states.md). */
#ifdef VS_NO_JOYSTICK
#define vehicle_disarm_stick(v) ((void)(v))
#else
#define vehicle_disarm_stick(v) ((v)->stick_armed = false)
#endif

void vehicle_servo_off(vehicle_t *v);
/* Read every drive once (vehicle_tick.c): what the tick does first. */
void vehicle_sample_drives(vehicle_t *v);
void vehicle_raise_fault(vehicle_t *v, uint32_t code, const char *text);
/* The state's getState code, its word and the alarm it names (NULL: none)
 * (vehicle_tick.c: the black box records it every tick). */
int16_t vehicle_state_of(const vehicle_t *v, const char **word, const vs_alarm_t **why);
/* The tick's black box sample (vehicle_tick.c), when bbox_due; global so
 * that make bench counts it by name. */
void vehicle_bbox_record(vehicle_t *v);
void vehicle_raise_fault_level(vehicle_t *v, uint32_t code, const char *text);

#endif
