/* Modbus drive profiles: where a drive keeps each value and in what form.
 *
 * Plain C data and integer code, no libc and no libmodbus: the Linux
 * backend (hal/linux/modbus_drive.c), the drive simulator
 * (host_sim/devices/mbdrive_sim_main.c) and a microcontroller's master use
 * the same definitions and the same encoding (tests/test_mbprofile.c).
 *
 * A profile names, for each value the master uses, a register (address of
 * channel 0, the step to the next channel's, 1 or 2 words, signed or not,
 * the word order of a pair, holding or input registers), and the values the
 * drive expects. A unit id may carry several motors (channels): a dual
 * hub-motor drive has two, each a <drive> of its own; a register with step
 * 0 is shared by the unit's channels (one control word for both motors).
 *
 *   speed         target speed, written; one register unit is speed_num /
 *                 speed_den counts/s (rpm: counts per motor turn / 60);
 *                 a 16-bit register saturates
 *   position      position in counts, read
 *   status        read; the power stage is on while every bit of
 *                 status_mask is set
 *   alarm         the drive's fault code, read; 0: none (optional)
 *   enable        written enable_on / enable_off
 *   reset         written reset_value after clearAlarm (optional)
 *   comm_timeout  the drive's own communication-loss stop: written once at
 *                 start, the timeout in units of comm_unit_ms (optional; a
 *                 configuration without it must say so)
 *   init          up to MBP_INIT_MAX registers written at start (a mode)
 *
 * Text form (mbp_set: the <modbus> attributes and mbdrive-sim --set):
 * a register is "ADDR[+STEP] TYPE [hi|lo] [holding|input]" or "none",
 * ADDR and STEP decimal or 0x hex, TYPE u16 s16 u32 s32 (hi: high word
 * first, the default); speed_scale "N" or "N/D" counts/s per unit;
 * init "ADDR=VALUE[,ADDR=VALUE...]".
 */
#ifndef HAL_MODBUS_MBPROFILE_H
#define HAL_MODBUS_MBPROFILE_H

#include <stdbool.h>
#include <stdint.h>

#include "../hal.h"

enum {
	MBP_SPEED = 0,
	MBP_POSITION,
	MBP_STATUS,
	MBP_ALARM,
	MBP_ENABLE,
	MBP_RESET,
	MBP_COMM_TIMEOUT,
	MBP_REG_COUNT,
};

#define MBP_SIGNED    0x01u
#define MBP_LOW_FIRST 0x02u /* of a pair: the low word at the lower address */
#define MBP_INPUT     0x04u /* input registers (function 04); else holding (03) */

#define MBP_CHANNELS_MAX 2
#define MBP_INIT_MAX	 4
#define MBP_NAME_MAX	 24

typedef struct {
	uint16_t addr; /* channel 0's register */
	uint16_t step; /* added per channel; 0: one register for every channel */
	uint8_t words; /* 1 or 2; 0: the profile has no such register */
	uint8_t flags; /* MBP_SIGNED | MBP_LOW_FIRST | MBP_INPUT */
} mbp_reg_t;

typedef struct {
	char name[MBP_NAME_MAX];
	uint8_t channels; /* motors per unit id, 1..MBP_CHANNELS_MAX */
	uint8_t block;	  /* registers one read may span (holes included) */
	mbp_reg_t reg[MBP_REG_COUNT];
	uint32_t speed_num, speed_den; /* one speed unit = num/den counts/s */
	uint16_t status_mask;
	uint16_t enable_on, enable_off, reset_value;
	uint16_t comm_unit_ms; /* one unit of the comm_timeout register */
	uint8_t ninit;
	struct {
		uint16_t addr, value;
	} init[MBP_INIT_MAX];
} mb_profile_t;

/* The generic profile's initialiser (mbprofile.c: the map of mbdrive-sim),
 * with its communication timeout at 0x109 of ct_words words (0: none): a
 * board that compiles its profile in starts from it. */
#define MBP_GENERIC(ct_words)                                                                      \
	{                                                                                          \
		.name = "generic", .channels = 1, .block = 8,                                      \
		.reg =                                                                             \
		    {                                                                              \
			[MBP_SPEED] = {0x100, 0, 2, MBP_SIGNED},                                   \
			[MBP_POSITION] = {0x102, 0, 2, MBP_SIGNED},                                \
			[MBP_STATUS] = {0x104, 0, 1, 0},                                           \
			[MBP_ALARM] = {0x105, 0, 1, 0},                                            \
			[MBP_ENABLE] = {0x106, 0, 1, 0},                                           \
			[MBP_RESET] = {0x107, 0, 1, 0},                                            \
			[MBP_COMM_TIMEOUT] = {0x109, 0, (ct_words), 0},                            \
		    },                                                                             \
		.speed_num = 1, .speed_den = 1, .status_mask = 1, .enable_on = 1, .enable_off = 0, \
		.reset_value = 1, .comm_unit_ms = 1,                                               \
	}

/* The built-in profiles by name (mbprofile.c: generic, zlac8015d); NULL
 * when unknown. */
const mb_profile_t *mbp_builtin(const char *name);
/* The i-th built-in profile, NULL past the last. */
const mb_profile_t *mbp_builtin_at(unsigned i);
/* The register names of the text form ("speed", ...), by MBP_*. */
const char *mbp_reg_name(unsigned r);

/* The register of channel ch. */
static inline uint16_t mbp_addr(const mbp_reg_t *r, unsigned ch)
{
	return (uint16_t)(r->addr + r->step * ch);
}
/* The value of a register from its words as read (1 or 2 words; sign
 * extended when signed), and the words of a value (a 16-bit register takes
 * the low 16 bits). Always inline: a board's compiled-in profile (MBD_PROFILE,
 * mbmaster.h) folds them to a few moves. */
static inline __attribute__((always_inline)) int32_t mbp_get(const mbp_reg_t *r, const uint16_t *w)
{
	if (r->words == 2) {
		uint32_t hi = (r->flags & MBP_LOW_FIRST) ? w[1] : w[0];
		uint32_t lo = (r->flags & MBP_LOW_FIRST) ? w[0] : w[1];
		return (int32_t)(hi << 16 | lo); /* u32 above 2^31 wraps: callers use s32 */
	}
	return (r->flags & MBP_SIGNED) ? (int32_t)(int16_t)w[0] : (int32_t)w[0];
}

static inline __attribute__((always_inline)) void mbp_put(const mbp_reg_t *r, int32_t v,
							  uint16_t *w)
{
	uint32_t u = (uint32_t)v;
	if (r->words == 2) {
		w[(r->flags & MBP_LOW_FIRST) ? 1 : 0] = (uint16_t)(u >> 16);
		w[(r->flags & MBP_LOW_FIRST) ? 0 : 1] = (uint16_t)(u & 0xFFFFu);
	} else {
		w[0] = (uint16_t)(u & 0xFFFFu);
	}
}
/* Target speed: counts/s to the register's words (rounded to the nearest
 * unit, saturated to the register's range), and back. */
void mbp_speed_words(const mb_profile_t *p, int32_t cps, uint16_t *w);
int32_t mbp_speed_cps(const mb_profile_t *p, const uint16_t *w);
/* The power stage is on in this status word. */
static inline bool mbp_enabled(const mb_profile_t *p, uint16_t status)
{
	return (status & p->status_mask) == p->status_mask;
}

/* One read of a drive's sample: n registers from addr, holding or input. */
typedef struct {
	uint16_t addr;
	uint8_t n;
	bool input;
} mbp_read_t;

/* Position, status and alarm of channel ch in as few reads as the
 * profile's block allows (never more than max registers; reads never mix
 * holding and input registers); the number of reads, at most 3. */
unsigned mbp_read_plan(const mb_profile_t *p, unsigned ch, unsigned max, mbp_read_t rd[3]);
/* The words of register r from a read that covers it (false when it does
 * not): w gets its 1 or 2 words. */
bool mbp_from_read(const mb_profile_t *p, unsigned r, unsigned ch, const mbp_read_t *rd,
		   const uint16_t *regs, uint16_t *w);

/* The words of position, status and alarm from one read of the sample
 * into val (by MBP_*), those the read covers. */
void mbp_take_read(const mb_profile_t *p, unsigned ch, const mbp_read_t *rd, const uint16_t *regs,
		   uint16_t val[MBP_REG_COUNT][2]);

/* A drive's latest sample as a master keeps it for the tick (the board's
 * hal/modbus/mbmaster.c and Linux's hal/linux/modbus_drive.c). */
typedef struct {
	int32_t pos;
	uint16_t status, alarm;
	bool fresh;   /* not yet reported */
	bool sampled; /* one sample since start */
	uint8_t why;  /* HAL_SILENT_* of the last failed cycle */
} mbp_sample_t;

/* A whole sample from its registers (val: mbp_take_read's). */
void mbp_sample_set(const mb_profile_t *p, mbp_sample_t *s, const uint16_t val[MBP_REG_COUNT][2]);
/* The tick's report of the sample (reverse: the drive's polarity); fresh
 * once per sample. */
void mbp_report(const mb_profile_t *p, mbp_sample_t *s, bool reverse, hal_drive_state_t *st);

/* One attribute of the text form. Returns NULL, or why the value is not
 * taken (a constant string); unknown keys: "unknown". */
const char *mbp_set(mb_profile_t *p, const char *key, const char *val);
/* NULL when the profile can run a drive, else what is missing or wrong. */
const char *mbp_check(const mb_profile_t *p);

#endif
