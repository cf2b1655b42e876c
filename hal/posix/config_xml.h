/* Vehicle configuration from XML files (host side, expat).
 *
 * Two files: the vehicle description and io.xml. Every attribute is
 * optional; an omitted one keeps its vs_config_defaults() value. Unknown
 * elements or attributes, text content, DOCTYPE, numbers that do not parse
 * completely, NaN/infinity and values outside the ranges below are errors.
 * After parsing, vs_config_check() judges the whole (e.g. defaults <= limits).
 *
 * Vehicle file (each section at most once, in any order):
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
 *                                 skipped here, see hal/linux/backend_cfg.h)
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
 */
#ifndef HAL_CONFIG_XML_H
#define HAL_CONFIG_XML_H

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

#endif
