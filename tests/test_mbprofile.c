/* The Modbus drive profiles (hal/modbus/mbprofile.h): the built-in ones
 * field by field, the words of every register form, the speed's scale,
 * rounding and saturation, and the text form with its refusals. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <string.h>

#include <cmocka.h>

#include "../hal/modbus/mbprofile.h"

static void test_builtins(void **state)
{
	(void)state;
	const mb_profile_t *g = mbp_builtin("generic");
	assert_non_null(g);
	assert_null(mbp_check(g));
	assert_int_equal(g->channels, 1);
	assert_int_equal(g->reg[MBP_SPEED].addr, 0x100);
	assert_int_equal(g->reg[MBP_SPEED].words, 2);
	assert_int_equal(g->reg[MBP_SPEED].flags, MBP_SIGNED);
	assert_int_equal(g->reg[MBP_COMM_TIMEOUT].words, 0);
	assert_int_equal(g->enable_on, 1);
	assert_int_equal(g->reset_value, 1);

	const mb_profile_t *z = mbp_builtin("zlac8015d");
	assert_non_null(z);
	assert_null(mbp_check(z));
	assert_int_equal(z->channels, 2);
	assert_int_equal(mbp_addr(&z->reg[MBP_SPEED], 0), 0x2088);
	assert_int_equal(mbp_addr(&z->reg[MBP_SPEED], 1), 0x2089);
	assert_int_equal(mbp_addr(&z->reg[MBP_POSITION], 1), 0x20A9);
	assert_int_equal(mbp_addr(&z->reg[MBP_ALARM], 1), 0x20A6);
	assert_int_equal(mbp_addr(&z->reg[MBP_ENABLE], 1), 0x200E);
	assert_int_equal(z->enable_on, 8);
	assert_int_equal(z->enable_off, 7);
	assert_int_equal(z->reset_value, 6);
	assert_int_equal(z->ninit, 1);
	assert_int_equal(z->init[0].addr, 0x200D);
	assert_int_equal(z->init[0].value, 3);
	assert_null(mbp_builtin("zlac"));
	assert_ptr_equal(mbp_builtin_at(0), g);
	assert_ptr_equal(mbp_builtin_at(1), z);
	assert_null(mbp_builtin_at(2));
}

static void test_words(void **state)
{
	(void)state;
	uint16_t w[2] = {0, 0};
	mbp_reg_t hi = {0, 0, 2, MBP_SIGNED}, lo = {0, 0, 2, MBP_SIGNED | MBP_LOW_FIRST};
	mbp_put(&hi, -2, w);
	assert_int_equal(w[0], 0xFFFF);
	assert_int_equal(w[1], 0xFFFE);
	assert_int_equal(mbp_get(&hi, w), -2);
	mbp_put(&lo, 0x12345678, w);
	assert_int_equal(w[0], 0x5678);
	assert_int_equal(w[1], 0x1234);
	assert_int_equal(mbp_get(&lo, w), 0x12345678);
	mbp_reg_t s16 = {0, 0, 1, MBP_SIGNED}, u16 = {0, 0, 1, 0};
	w[0] = 0x8000;
	assert_int_equal(mbp_get(&s16, w), -32768);
	assert_int_equal(mbp_get(&u16, w), 32768);
	mbp_put(&s16, -1, w);
	assert_int_equal(w[0], 0xFFFF);
}

static void test_speed_scale(void **state)
{
	(void)state;
	uint16_t w[2] = {0, 0};
	const mb_profile_t *z = mbp_builtin("zlac8015d");
	/* 4096 counts a turn: 68.27 counts/s a r/min. 6827 counts/s is
	 * 100.00 r/min; 34 counts/s rounds to 0.498 -> 0, 35 to 0.513 -> 1 */
	mbp_speed_words(z, 6827, w);
	assert_int_equal(w[0], 100);
	mbp_speed_words(z, -6827, w);
	assert_int_equal(w[0], (uint16_t)-100);
	assert_int_equal(mbp_speed_cps(z, w), -6827);
	mbp_speed_words(z, 34, w);
	assert_int_equal(w[0], 0);
	mbp_speed_words(z, 35, w);
	assert_int_equal(w[0], 1);
	mbp_speed_words(z, -35, w);
	assert_int_equal(w[0], 0xFFFF);
	/* 16 bits saturate: 3,000,000 counts/s is 43,945 r/min */
	mbp_speed_words(z, 3000000, w);
	assert_int_equal(w[0], 32767);
	mbp_speed_words(z, -3000000, w);
	assert_int_equal(w[0], 0x8000);
	/* the generic profile: counts/s as they are */
	mbp_speed_words(mbp_builtin("generic"), -2000, w);
	assert_int_equal(w[0], 0xFFFF);
	assert_int_equal(w[1], 0xF830);
	/* an unsigned 16-bit register takes no negative speed */
	mb_profile_t u = *z;
	assert_null(mbp_set(&u, "speed", "0x10+1 u16"));
	mbp_speed_words(&u, -6827, w);
	assert_int_equal(w[0], 0);
}

static void test_text_form(void **state)
{
	(void)state;
	mb_profile_t p = *mbp_builtin("generic");
	assert_null(mbp_set(&p, "position", "0x300+4 s32 lo input"));
	assert_int_equal(p.reg[MBP_POSITION].addr, 0x300);
	assert_int_equal(p.reg[MBP_POSITION].step, 4);
	assert_int_equal(p.reg[MBP_POSITION].words, 2);
	assert_int_equal(p.reg[MBP_POSITION].flags, MBP_SIGNED | MBP_LOW_FIRST | MBP_INPUT);
	assert_null(mbp_set(&p, "alarm", "none"));
	assert_int_equal(p.reg[MBP_ALARM].words, 0);
	assert_null(mbp_set(&p, "speed_scale", "4096/600"));
	assert_int_equal(p.speed_num, 4096);
	assert_int_equal(p.speed_den, 600);
	assert_null(mbp_set(&p, "speed_scale", "3"));
	assert_int_equal(p.speed_num, 3);
	assert_int_equal(p.speed_den, 1);
	assert_null(mbp_set(&p, "status_mask", "0x0c"));
	assert_int_equal(p.status_mask, 12);
	assert_true(mbp_enabled(&p, 0x0F));
	assert_false(mbp_enabled(&p, 0x08));
	assert_null(mbp_set(&p, "init", "0x10=3,17=0x20"));
	assert_int_equal(p.ninit, 2);
	assert_int_equal(p.init[1].addr, 17);
	assert_int_equal(p.init[1].value, 0x20);
	assert_null(mbp_set(&p, "channels", "2"));
	assert_string_equal(mbp_check(&p), "speed: each channel needs its own register (step)");
	assert_null(mbp_set(&p, "speed", "0x100+2 s32"));
	assert_null(mbp_check(&p));

	static const char *const reg_bad = "not a register: ADDR[+STEP] u16|s16|u32|s32 [hi|lo] "
					   "[holding|input], or none";
	static const struct {
		const char *key, *val, *why;
	} bad[] = {
	    {"speed", "", reg_bad},
	    {"speed", "0x10000 s16", reg_bad},
	    {"speed", "12 s8", reg_bad},
	    {"speed", "12", reg_bad},
	    {"speed", "12+ s16", reg_bad},
	    {"speed", "12+256 s16", reg_bad},
	    {"speed", "12 s16 lo", reg_bad}, /* no word order for one word */
	    {"speed", "12 s16 coil", reg_bad},
	    {"speed", "none extra", reg_bad},
	    {"speed", "0x s16", reg_bad},
	    {"speed", "1x2 s16", reg_bad},
	    {"speed_scale", "0", "not N or N/D counts/s per unit, 1..1000000"},
	    {"speed_scale", "1/0", "not N or N/D counts/s per unit, 1..1000000"},
	    {"speed_scale", "1000001", "not N or N/D counts/s per unit, 1..1000000"},
	    {"speed_scale", "4096/", "not N or N/D counts/s per unit, 1..1000000"},
	    {"status_mask", "65536", "not a number 0..65535"},
	    {"enable_on", "-1", "not a number 0..65535"},
	    {"channels", "3", "not 1 or 2"},
	    {"block", "0", "not a number 1..32"},
	    {"init", "1=2,3=4,5=6,7=8,9=10", "not ADDR=VALUE[,ADDR=VALUE...] (at most 4)"},
	    {"init", "1=2,", "not ADDR=VALUE[,ADDR=VALUE...] (at most 4)"},
	    {"init", "1", "not ADDR=VALUE[,ADDR=VALUE...] (at most 4)"},
	    {"colour", "red", "unknown"},
	};
	for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
		mb_profile_t q = p;
		const char *why = mbp_set(&q, bad[i].key, bad[i].val);
		if (!why || strcmp(why, bad[i].why) != 0)
			print_message("%s=\"%s\": %s\n", bad[i].key, bad[i].val,
				      why ? why : "taken");
		assert_non_null(why);
		assert_string_equal(why, bad[i].why);
		assert_memory_equal(&q, &p, sizeof q); /* nothing changed */
	}
}

static void test_check(void **state)
{
	(void)state;
	mb_profile_t p = *mbp_builtin("generic");
	assert_null(mbp_set(&p, "status", "none"));
	assert_string_equal(mbp_check(&p), "speed, position, status and enable are required");
	p = *mbp_builtin("generic");
	assert_null(mbp_set(&p, "enable", "5 u16 input"));
	assert_string_equal(mbp_check(&p),
			    "a register the master writes cannot be an input register");
	p = *mbp_builtin("zlac8015d");
	assert_null(mbp_set(&p, "position", "0xFFFD+2 s32"));
	assert_string_equal(mbp_check(&p), "a channel's register lies beyond 65535");
	p = *mbp_builtin("generic");
	assert_null(mbp_set(&p, "status_mask", "0"));
	assert_string_equal(mbp_check(&p), "status_mask: zero");
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test(test_builtins),	cmocka_unit_test(test_words),
	    cmocka_unit_test(test_speed_scale), cmocka_unit_test(test_text_form),
	    cmocka_unit_test(test_check),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
