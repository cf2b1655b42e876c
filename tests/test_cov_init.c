/* vehicle_init and the HAL contract (hal/hal.h): every mandatory operation
 * must be present; a sensor operation only when the configuration says the
 * unit has that sensor. A missing one is refused with -4 "hal", before the
 * unit is touched. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "firmware/vehicle.h"
#include "tests/fake_hal.h"

static fake_hal_t F;
static vehicle_t V;

/* Clears operation i (0..14, hal.h order); returns the has_* flag that
 * makes it optional, or NULL for a mandatory one. */
static bool *drop_op(int i, vs_hal_ops_t *o, vs_config_t *c)
{
	switch (i) {
	case 0:
		o->drive_set_velocity = NULL;
		return NULL;
	case 1:
		o->drive_enable = NULL;
		return NULL;
	case 2:
		o->drive_read = NULL;
		return NULL;
	case 3:
		o->drive_reset_fault = NULL;
		return NULL;
	case 4:
		o->power_set = NULL;
		return NULL;
	case 5:
		o->power_feedback = NULL;
		return NULL;
	case 6:
		o->io_read = NULL;
		return NULL;
	case 7:
		o->io_write = NULL;
		return NULL;
	case 8:
		o->battery_mv = NULL;
		return NULL;
	case 9:
		o->contact = NULL;
		return &c->has_contact_sensor;
	case 10:
		o->obstacle = NULL;
		return &c->has_obstacle_input;
	case 11:
		o->obstacle_caution = NULL;
		return &c->has_obstacle_input;
	case 12:
		o->estop = NULL;
		return &c->has_estop;
	default:
		o->joystick = NULL;
		return &c->has_joystick;
	}
}

static void test_missing_hal_operation(void **state)
{
	(void)state;
	for (int i = 0; i < 14; i++) {
		vs_config_t c;
		vs_config_defaults(&c);
		fake_hal_init(&F, c.tick_hz);
		vs_hal_ops_t ops = fake_hal_ops;
		bool *has = drop_op(i, &ops, &c);
		vs_hal_t h = {&ops, &F};
		const char *bad = NULL;
		memset(&V, 0x5A, sizeof V);
		int rc = vehicle_init(&V, &c, &h, &bad);
		if (rc != -4)
			print_message("operation %d missing: init returned %d\n", i, rc);
		assert_int_equal(rc, -4);
		assert_string_equal(bad, "hal");
		/* refused before the unit state was written */
		assert_int_equal(((unsigned char *)&V)[0], 0x5A);
		bad = NULL;
		assert_int_equal(vehicle_init(&V, &c, &h, NULL), -4);
		if (has) {
			*has = false;
			assert_int_equal(vehicle_init(&V, &c, &h, &bad), 0);
			assert_null(bad);
		}
	}
}

static void test_no_hal(void **state)
{
	(void)state;
	vs_config_t c;
	vs_config_defaults(&c);
	const char *bad = NULL;
	vs_hal_t h = {NULL, &F};
	assert_int_equal(vehicle_init(&V, &c, &h, &bad), -4);
	assert_string_equal(bad, "hal");
	bad = NULL;
	assert_int_equal(vehicle_init(&V, &c, NULL, &bad), -4);
	assert_string_equal(bad, "hal");
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test(test_missing_hal_operation),
	    cmocka_unit_test(test_no_hal),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
