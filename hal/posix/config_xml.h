/* Vehicle configuration from XML files (host side, expat).
 *
 * Two files: the vehicle description and io.xml. Every attribute is
 * optional; an omitted one keeps its vs_config_defaults() value. Unknown
 * elements or attributes, text content, DOCTYPE, numbers that do not parse
 * completely, NaN/infinity and values outside the ranges below are errors.
 * After parsing, vs_config_check() judges the whole (e.g. defaults <= limits).
 *
 * The attributes, their ranges and defaults are the rows of the firmware's
 * configuration table, firmware/config_fields.def (element and attribute
 * are its last two columns): a field added there is read here with no
 * further code. Vehicle file (each section at most once, in any order):
 *
 *   <vehicle kinematics="differential|mecanum" tick_hz="100..10000">
 *     <geometry wheel_diameter_mm="150" track_width_mm="400" wheel_base_mm="0"
 *               encoder_counts_per_rev="16384"/>
 *     <limits vel_t_mm_s="1000" vel_r_deg_s="180" acc_t_mm_s2="1000" acc_r_deg_s2="360"/>
 *     <defaults vel_t_mm_s="500" vel_r_deg_s="90" acc_t_mm_s2="500" acc_r_deg_s2="180"
 *               jog_timeout_ms="500"/>
 *     <drives axis0_lag_ms="20" axis1_lag_ms="20" axis2_lag_ms="20" axis3_lag_ms="20"/>
 *               (each drive's speed lag, 0..1000 ms: firmware/kin.h)
 *     <supervision wheel_kp_per_s="20" following_error_mm="50" encoder_stuck_ms="300"
 *                  drive_timeout_ms="50" loop_late_ms="20" link_timeout_ms="1000"
 *                  position_window_mm="0.05" position_window_ms="20"
 *                  settle_timeout_ms="1000"/>
 *               (in position, docs/console.md: window > 0..100 mm, 0..1000 ms;
 *                settle 10..60000 ms)
 *     <motion cruise_blend_mm="200" caution_vel_t_mm_s="0"/>
 *     <battery low_v="22.0" critical_v="20.0"/>
 *     <devices contact_sensor="true" obstacle_input="true" estop="true" joystick="true"
 *              joystick_deadband="0.05"/>
 *     <backends>...</backends>   (vehicle-fw's hardware backends, at most once;
 *                                 read by a section handler when one is given
 *                                 to config_load_sections, see
 *                                 hal/linux/backend_cfg.h; skipped otherwise)
 *   </vehicle>
 *
 * io.xml (document order is kept; ids unique, 1..; 0 is the unit itself):
 *
 *   <io>
 *     <input id="1" name="dock" width="1" chip="gpiochip0" line="3" active_low="false"/>
 *     <output id="5" name="lamp" width="1" chip="gpiochip0" line="8"/>
 *   </io>
 *
 * id is required; name defaults to "", width to 1 (1..32). chip/line/
 * active_low are for a GPIO backend only: a value of width w occupies lines
 * line .. line+w-1 of the chip, bit 0 on `line`. An entry without chip has
 * no line mapping (served by the simulator or another backend).
 *
 * Booleans are true|false|1|0. Error strings read
 *   "<file>:<line>: <element>.<attribute>: <what> '<value>'"
 * e.g. "config/vehicle.xml:12: limits.vel_t_mm_s: not a number 'abc'".
 *
 * Sections of other readers (config_section_t): the vehicle file is parsed
 * once; the elements of a section (the section's own, then everything
 * inside it) go to its handler, which judges them with the attribute
 * helpers below (the same number syntax and message style) and reports
 * with config_fail(). The first error reported is, in this order: the core
 * configuration's (vehicle file, io.xml, vs_config_check), a section's (the
 * first in the file), a section's finish(). A section's messages always
 * carry the line ("<file>:<line>: ...").
 */
#ifndef HAL_CONFIG_XML_H
#define HAL_CONFIG_XML_H

#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "../../firmware/config.h"

#define HAL_IO_CHIP_MAX 32

/* Line mapping of one io.xml entry, for a GPIO backend. */
typedef struct {
	uint32_t id;
	uint8_t dir;   /* vs_io_dir_t */
	uint8_t width; /* number of consecutive lines */
	bool mapped;   /* chip and line given */
	bool active_low;
	uint32_t line; /* first line offset on the chip */
	char chip[HAL_IO_CHIP_MAX];
} hal_io_line_t;

typedef struct {
	uint8_t n;
	hal_io_line_t e[VS_MAX_IO]; /* same order as vs_config_t.io */
} hal_io_map_t;

/* The loader's value syntax, for other parsers of the same files: a strict
 * decimal number (optional sign, digits, fraction, exponent; no nan, inf,
 * hex or blanks), -1 with why = "not a number" | "not finite" | "out of
 * range"; a boolean true/false/1/0, -1 otherwise. */
int config_parse_number(const char *s, double *out, const char **why);
int config_parse_bool(const char *s, bool *out);

/* Loads vehicle_path, then io_path (NULL: keep the default io table, empty
 * map). io_map may be NULL. On error returns -1, writes one line to err and
 * leaves *out and *io_map in an unspecified but valid state. */
int config_load(const char *vehicle_path, const char *io_path, vs_config_t *out,
		hal_io_map_t *io_map, char *err, size_t errlen);

/* ---- sections of other readers ------------------------------------------ */

/* One section being read (opaque): what a handler reports through. */
typedef struct config_reader config_reader_t;

#define CONFIG_MAX_SECTIONS 4

typedef struct {
	const char *name; /* element right under <vehicle>, e.g. "backends" */
	/* Each element of the section in document order: the section's own
	 * at depth 0, its children at 1, and so on; atts as expat gives them
	 * (name, value, ..., NULL); line: where the start tag begins. Returns
	 * 0, or -1 after config_fail(); after an error the handler hears no
	 * more. */
	int (*start)(void *ctx, config_reader_t *r, const char *elem, const char **atts, int depth,
		     unsigned long line);
	/* The end of each element, same depth (NULL: not wanted). */
	void (*end)(void *ctx, const char *elem, int depth);
	/* Once the files are read without error (NULL: nothing to do): checks
	 * across the section's elements. 0, or -1 after config_fail(). */
	int (*finish)(void *ctx, config_reader_t *r);
	void *ctx;
} config_section_t;

/* The section's error: "<file>:<line>: <fmt ...>". The first one counts.
 * Returns -1. */
int config_fail(config_reader_t *r, unsigned long line, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
int config_vfail(config_reader_t *r, unsigned long line, const char *fmt, va_list ap)
    __attribute__((format(printf, 3, 0)));

/* Attribute values for section handlers, each 0 or -1 after config_fail()
 * with "<elem>.<attr>: <what> '<value>'":
 *   uint    decimal digits only, within min..max ("not a number",
 *           "out of range <min>..<max>")
 *   number  config_parse_number within [lo, hi], (lo, hi] when lo_excl
 *           ("not a number" | "not finite" | "out of range" from the parse,
 *           or "out of range <range>", range as the caller words it)
 *   bool    config_parse_bool ("not a boolean") */
int config_attr_uint(config_reader_t *r, unsigned long line, const char *elem, const char *attr,
		     const char *val, unsigned long min, unsigned long max, uint32_t *out);
int config_attr_number(config_reader_t *r, unsigned long line, const char *elem, const char *attr,
		       const char *val, double lo, bool lo_excl, double hi, const char *range,
		       double *out);
int config_attr_bool(config_reader_t *r, unsigned long line, const char *elem, const char *attr,
		     const char *val, bool *out);

/* config_load, and the n sections (at most CONFIG_MAX_SECTIONS) in the same
 * pass over the vehicle file. out NULL: the sections only (io_path and
 * io_map are then ignored, and the core configuration is not judged; a file
 * that cannot be read is still an error). */
int config_load_sections(const char *vehicle_path, const char *io_path, vs_config_t *out,
			 hal_io_map_t *io_map, const config_section_t *sections, size_t n,
			 char *err, size_t errlen);

#endif
