/* VehicleService core: the texts the alarms carry (no libc) and raising a
 * fault, shared by the operations (vehicle.c) and the tick (vehicle_tick.c). */
#include "vehicle_priv.h"

size_t vehicle_put_str(char *b, size_t cap, size_t pos, const char *s)
{
	while (*s != '\0' && pos + 1 < cap)
		b[pos++] = *s++;
	if (pos < cap)
		b[pos] = '\0';
	return pos;
}

/* Decimal, at least min_digits (zero padded). */
size_t vehicle_put_dec(char *b, size_t cap, size_t pos, uint32_t val, unsigned min_digits)
{
	char t[10];
	unsigned n = 0;
	do {
		t[n++] = (char)('0' + val % 10u);
		val /= 10u;
	} while (val != 0 && n < sizeof t);
	while (n < min_digits && n < sizeof t)
		t[n++] = '0';
	while (n > 0 && pos + 1 < cap)
		b[pos++] = t[--n];
	if (pos < cap)
		b[pos] = '\0';
	return pos;
}

size_t vehicle_put_hex4(char *b, size_t cap, size_t pos, uint16_t val)
{
	const char *const hex = "0123456789ABCDEF"; /* one copy, shared */
	pos = vehicle_put_str(b, cap, pos, "0x");
	for (int sh = 12; sh >= 0; sh -= 4) {
		if (pos + 1 < cap)
			b[pos++] = hex[((unsigned)val >> (unsigned)sh) & 0xFu];
	}
	if (pos < cap)
		b[pos] = '\0';
	return pos;
}

/* Volts with one decimal from millivolts: 22000 -> "22.0". */
size_t vehicle_put_volts(char *b, size_t cap, size_t pos, uint32_t mv)
{
	uint32_t dv = (mv + 50u) / 100u;
	pos = vehicle_put_dec(b, cap, pos, dv / 10u, 1);
	pos = vehicle_put_str(b, cap, pos, ".");
	pos = vehicle_put_dec(b, cap, pos, dv % 10u, 1);
	return vehicle_put_str(b, cap, pos, " V");
}

void vehicle_servo_off(vehicle_t *v)
{
	for (uint8_t i = 0; i < v->naxes; i++) {
		v->hal.ops->drive_enable(v->hal.ctx, i, false);
		v->drive[i].enabled = false;
		v->wheel_cps_q8[i] = 0;
	}
	v->servo = false;
	if (VS_DRIVE_STATES)
		v->servo_wait = false;
}

/* Every fault: drop the motion at once and switch the servo off (spec 6.9). */
void vehicle_raise_fault(vehicle_t *v, uint32_t code, const char *text)
{
	alarm_raise(&v->alarms, code, text);
	bbox_fault(&v->bbox, code);
	motion_halt(&v->motion);
	vehicle_servo_off(v);
}

/* A condition that persists (e-stop held, battery critical): raised once
 * while its code is active, and again after clearAlarm if still present. */
void vehicle_raise_fault_level(vehicle_t *v, uint32_t code, const char *text)
{
	for (unsigned i = 0; i < v->alarms.n; i++) {
		if (v->alarms.a[i].code == code)
			return;
	}
	vehicle_raise_fault(v, code, text);
}

size_t vehicle_axis_text(char *s, size_t cap, const char *what, uint8_t axis, const char *tail)
{
	size_t pos = vehicle_put_str(s, cap, 0, what);
	pos = vehicle_put_dec(s, cap, pos, axis, 1);
	return vehicle_put_str(s, cap, pos, tail);
}
