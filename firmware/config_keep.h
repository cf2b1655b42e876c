/* The configuration a unit runs with, changed at run time and kept in the
 * store (cfgstore.h) in its saved form (config_save.h).
 *
 * Three configurations: the base (the vehicle file on a computer, the
 * compiled-in one on a board; read-only), the saved one (the base with the
 * store's overlay, as loaded or last saved) and the wanted one (the running
 * configuration with the changes that wait for a restart). A change is
 * judged whole by vs_config_check, as the file is, then by the table's when
 * column (config_fields.def): a field of class OFF changes only while
 * vehicle_config_idle, a RESTART one is kept for the next start (the unit
 * runs on with its value), an ANY one changes at once. A save writes what
 * the wanted configuration has that the base has not.
 *
 * The keeper holds the three as their rows only (cfgkeep_rows_t, 280 bytes
 * on a board where a vs_config_t has 1.3 KiB): a change is judged on the
 * stack, a copy of the running configuration with the wanted rows; the
 * saved form is read at start into the stack, and written from the
 * caller's scratch (the console's), so that a board's RAM holds no more
 * than the rows.
 */
#ifndef VS_CONFIG_KEEP_H
#define VS_CONFIG_KEEP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cfgstore.h"
#include "config.h"
#include "vehicle.h"

/* The largest saved form: every field differs (a bound, checked at build). */
#define CFGKEEP_PAYLOAD_MAX 1536

/* What the load at start found. */
typedef enum {
	CFGKEEP_BOOT_NO_STORE = 0, /* the platform was given none */
	CFGKEEP_BOOT_EMPTY,	   /* never saved (or cleared): the base */
	CFGKEEP_BOOT_LOADED,	   /* the saved configuration is in force */
	/* Unreadable: the unit runs on the base (warning 156). */
	CFGKEEP_BOOT_CORRUPT,	/* no valid record, and the slots not erased */
	CFGKEEP_BOOT_IO,	/* the store reported an error */
	CFGKEEP_BOOT_MALFORMED, /* a valid record whose payload does not parse */
	CFGKEEP_BOOT_FOREIGN,	/* another payload version or platform's numbers */
	CFGKEEP_BOOT_REJECTED,	/* the overlay fails vs_config_check (bad_field) */
} cfgkeep_boot_result_t;

typedef struct {
	uint8_t result;	       /* cfgkeep_boot_result_t */
	bool other_torn;       /* a save was cut short (cfgstore_info_t) */
	uint32_t seq, schema;  /* the record's (LOADED and later) */
	uint16_t applied;      /* fields the overlay set */
	uint16_t dropped;      /* ... that this table no longer has */
	const char *bad_field; /* REJECTED: the field vs_config_check named */
} cfgkeep_boot_t;

typedef enum {
	CFGKEEP_OK = 0,	     /* in force now (or nothing changed) */
	CFGKEEP_PENDING,     /* kept; in force from the next start (RESTART fields) */
	CFGKEEP_REJECTED,    /* vs_config_check refuses it: *field */
	CFGKEEP_NOT_IDLE,    /* *field changes only with the servo off, nothing queued */
	CFGKEEP_NO_STORE,    /* save: the unit has no store */
	CFGKEEP_STORE_ERROR, /* save: the store failed (*field: what it said) */
} cfgkeep_result_t;

/* The table's rows of a configuration: the bytes of vs_config_t before
 * firmware_version, each row at its offset (config_keep.c asserts that every
 * row lies there). */
#define CFGKEEP_ROWS_BYTES offsetof(vs_config_t, firmware_version)
typedef union {
	uint8_t b[CFGKEEP_ROWS_BYTES];
	vs_real_t align; /* the members' alignment */
} cfgkeep_rows_t;

typedef struct cfgkeep {
	vehicle_t *v;
	const hal_store_t *store; /* NULL: none */
	cfgkeep_boot_t boot;
	cfgkeep_rows_t base, saved, want;
} cfgkeep_t;

/* Before vehicle_init: keeps base, reads the store (NULL: none) and fills
 * *start with what the unit starts with: the base with the saved overlay
 * when it reads and passes vs_config_check, else the base. */
void cfgkeep_load(cfgkeep_t *k, const vs_config_t *base, const hal_store_t *store,
		  vs_config_t *start);
/* After vehicle_init(v, start): the unit its changes go to; an unreadable
 * store raises warning 156 (ALM_W_CONFIG_STORE). */
void cfgkeep_attach(cfgkeep_t *k, vehicle_t *v);

/* Row f becomes row (every element, the member's type and bytes). */
cfgkeep_result_t cfgkeep_set(cfgkeep_t *k, const vs_config_field_t *f, const void *row,
			     const char **field);
/* Every field as in the base (defaults) or as saved (reload). */
cfgkeep_result_t cfgkeep_restore(cfgkeep_t *k, bool saved, const char **field);
/* Writes the wanted configuration to the store; buf (cap bytes, the
 * caller's scratch: VS_CFGSAVE_MAX suffice) holds its saved form meanwhile. */
cfgkeep_result_t cfgkeep_save(cfgkeep_t *k, uint8_t *buf, size_t cap, const char **field);

/* The ANY rows of the wanted configuration as the unit runs them (what
 * $watchdog and $jerk set): before the queries below. */
void cfgkeep_sync(cfgkeep_t *k);
/* Row f differs between the wanted configuration and: the running one
 * (pending for a restart), the saved one, the base. */
bool cfgkeep_pending(const cfgkeep_t *k, const vs_config_field_t *f);
bool cfgkeep_unsaved(const cfgkeep_t *k, const vs_config_field_t *f);
bool cfgkeep_changed(const cfgkeep_t *k, const vs_config_field_t *f);

#endif
