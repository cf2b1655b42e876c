/* Hardware abstraction: the only way the firmware touches the plant.
 *
 * One const table of operations plus a context pointer, as libmodbus does for
 * its backends: one build can then hold several implementations (a CiA 402
 * drive on one axis, a Modbus drive on another, the simulated plant in
 * tests). Every call is non-blocking on the tick path except power_set,
 * which may wait for the relay's settle time (documented per backend, at most
 * 50 ms) and is only called from a command, never from the tick.
 *
 * Units: wheel velocity setpoints in encoder counts per second, Q8 (x256);
 * encoder position in counts, free-running and wrapping; battery in mV.
 */
#ifndef HAL_H
#define HAL_H

#include <stdbool.h>
#include <stdint.h>

/* A drive's own power state as its last report gave it (CiA 402's state
 * machine; other drives map onto it). HAL_DRIVE_UNKNOWN: the backend does
 * not know it (the firmware then goes by .enabled alone). */
typedef enum {
	HAL_DRIVE_UNKNOWN = 0,
	HAL_DRIVE_NOT_READY,	      /* Not ready to switch on */
	HAL_DRIVE_SWITCH_ON_DISABLED, /* Switch on disabled */
	HAL_DRIVE_READY,	      /* Ready to switch on */
	HAL_DRIVE_SWITCHED_ON,	      /* Switched on: power stage off (an STO holds it here) */
	HAL_DRIVE_ENABLED,	      /* Operation enabled */
	HAL_DRIVE_QUICK_STOP,	      /* Quick stop active */
	HAL_DRIVE_FAULT_REACTION,     /* Fault reaction active */
	HAL_DRIVE_FAULT,	      /* Fault */
	HAL_DRIVE_NOT_OPERATIONAL,    /* its communication is not operational (NMT) */
	HAL_DRIVE_STATE_COUNT
} hal_drive_phase_t;

/* Why a drive's report is not fresh, when the backend knows more than
 * silence: the drive answers, but not with a sample. */
enum {
	HAL_SILENT_NO_REPLY = 0, /* nothing usable came back */
	HAL_SILENT_BUSY = 1,	 /* the drive answers "busy" (Modbus exception 6) */
	HAL_SILENT_MAP = 2,	 /* the drive rejects the registers the master uses
				    (Modbus exception 1 or 2: the register map is wrong) */
};

/* Eight bytes (the flags are bits): the tick copies one a drive, in one
 * register on a 64-bit host (12 bytes cost the cruise tick 8 instructions a
 * drive, tools/bench/tickcost.sh). */
typedef struct {
	int32_t position_counts; /* free-running, wraps; compare by difference */
	uint16_t fault_code;	 /* 0: no fault; otherwise the drive's own code */
	uint8_t phase;		 /* hal_drive_phase_t */
	/* Power stage actually on, in the mode the master set (CiA 402:
	 * Operation enabled and 0x6061 confirmed; Modbus: the status bit). Never
	 * a copy of the command: the firmware's servo on waits for it. */
	bool enabled : 1;
	bool fresh : 1; /* a reply arrived since the previous read */
	/* The drive restarted (or its count jumped in a way the backend cannot
	 * bridge) since the previous read: position_counts no longer continues
	 * the old count. Reported on one read; the firmware latches it and
	 * refuses motion until setPosition. A drive that comes back without
	 * restarting keeps counting and does not set it. */
	bool position_lost : 1;
	/* With fresh false: HAL_SILENT_*, why no sample came. */
	uint8_t silent_why : 2;
} hal_drive_state_t;
#ifndef __cplusplus
_Static_assert(sizeof(hal_drive_state_t) == 8, "the drive report is eight bytes");
#endif

typedef struct {
	int16_t axis[3]; /* x (forward), y (left), rotation (CCW); +-32767 full scale */
	bool present;	 /* false: no device, or the device was lost */
} hal_joystick_t;

typedef struct vs_hal_ops {
	/* Wheel drives, axis 0..n-1 (see vs_kinematics_t for the order). */
	void (*drive_set_velocity)(void *ctx, uint8_t axis, int32_t counts_per_s_q8);
	void (*drive_enable)(void *ctx, uint8_t axis, bool on);
	void (*drive_read)(void *ctx, uint8_t axis, hal_drive_state_t *st);
	void (*drive_reset_fault)(void *ctx, uint8_t axis);

	/* Main drive-power relay: command it and report the feedback contact. */
	bool (*power_set)(void *ctx, bool on);
	bool (*power_feedback)(void *ctx);

	/* Digital IO by io.xml id. false: the id is not served by this backend. */
	bool (*io_read)(void *ctx, uint32_t ioid, uint32_t *value);
	bool (*io_write)(void *ctx, uint32_t ioid, uint32_t value);

	/* Discrete safety and sensor inputs, sampled once per tick. */
	bool (*contact)(void *ctx);
	bool (*obstacle)(void *ctx);
	bool (*obstacle_caution)(void *ctx);
	bool (*estop)(void *ctx);
	void (*joystick)(void *ctx, hal_joystick_t *js);
	uint32_t (*battery_mv)(void *ctx);
} vs_hal_ops_t;

typedef struct {
	const vs_hal_ops_t *ops;
	void *ctx;
} vs_hal_t;

/* A small non-volatile store with the rules of a microcontroller's flash
 * (firmware/cfgstore.h keeps the saved configuration in it): pages of
 * page_size bytes are the unit of erase; after an erase every byte reads
 * erased_byte; a program writes whole words (word bytes, aligned) that are
 * erased, once each; a power cut may leave the page or word under way half
 * done. On Linux a file replaced whole at each step (written new, synced,
 * renamed over); on a board its flash pages, or a RAM region a reset keeps. */
typedef struct hal_store {
	uint32_t page_size; /* a multiple of word */
	uint32_t pages;
	uint32_t word; /* 4 or 8 */
	uint8_t erased_byte;
	/* false: the part reported an error (nothing is assumed done). */
	bool (*read)(void *ctx, uint32_t off, void *buf, uint32_t n);
	bool (*erase)(void *ctx, uint32_t page);
	bool (*program)(void *ctx, uint32_t off, const void *buf, uint32_t n);
	void *ctx;
} hal_store_t;

#endif
