/* Vehicle configuration handed to the firmware at init.
 *
 * Filled outside firmware/ (the XML loader in hal/posix/, or a board's
 * own code from vs_config_defaults()) in physical units; vehicle_init() validates it again and
 * converts it once to the fixed-point parameters the tick uses.
 */
#ifndef VS_CONFIG_H
#define VS_CONFIG_H

#include <stdbool.h>
#include <stdint.h>

#include "real.h"

#define VS_MAX_AXES 4
/* io.xml entries a configuration holds (a board's build sets fewer: each
 * costs 32 bytes in every vs_config_t, the unit's own and the one $config
 * judges on the stack). */
#ifndef VS_MAX_IO
#define VS_MAX_IO 32
#endif
#define VS_IO_NAME_MAX 24

typedef enum {
	VS_KIN_DIFF = 0, /* two-wheel differential: axis 0 left, axis 1 right */
	VS_KIN_OMNI = 1, /* four-wheel mecanum: 0 front-left, 1 front-right,
			    2 rear-left, 3 rear-right */
} vs_kinematics_t;

typedef enum { VS_IO_IN = 0, VS_IO_OUT = 1 } vs_io_dir_t;

/* One io.xml entry as the firmware sees it: the id and its shape. The line
 * mapping (chip, offsets, active-low) stays with the HAL backend. */
typedef struct {
	uint32_t id;   /* 1.. ; 0 is reserved for the unit itself */
	uint8_t dir;   /* vs_io_dir_t */
	uint8_t width; /* value bits, 1..32 */
	char name[VS_IO_NAME_MAX];
} vs_io_def_t;

typedef struct {
	vs_kinematics_t kinematics;
	uint32_t tick_hz; /* control tick rate, 100..10000, default 1000 */

	/* Geometry and sensing. */
	vs_real_t wheel_diameter_mm;
	vs_real_t track_width_mm;	 /* differential: wheel to wheel; mecanum: left to right */
	vs_real_t wheel_base_mm;	 /* mecanum: front to rear axle; unused on differential */
	uint32_t encoder_counts_per_rev; /* per wheel revolution, after quadrature */

	/* Limits (getVelocityLimit / getAccelerationLimit) and start-up values. */
	vs_real_t vel_limit_t_mm_s, vel_limit_r_deg_s;
	vs_real_t acc_limit_t_mm_s2, acc_limit_r_deg_s2;
	vs_real_t vel_default_t_mm_s, vel_default_r_deg_s;
	vs_real_t acc_default_t_mm_s2, acc_default_r_deg_s2;
	/* Jerk (mm/s^3, deg/s^3), 0 = unlimited: the limit is what stops reach
	 * their acceleration with, the default what moves run at ($jerk). */
	vs_real_t jerk_limit_t_mm_s3, jerk_limit_r_deg_s3;
	vs_real_t jerk_default_t_mm_s3, jerk_default_r_deg_s3;
	uint16_t jog_timeout_default_ms;

	/* Wheel position loop and supervision. */
	vs_real_t wheel_kp_per_s; /* position loop gain, 1/s */
	/* Per axis: the drive's velocity lag, ms (its first-order time
	 * constant from setpoint to speed); 0 = follows at once. */
	vs_real_t drive_lag_ms[VS_MAX_AXES];
	vs_real_t following_error_mm; /* measured vs commanded wheel travel */
	uint32_t encoder_stuck_ms;    /* commanded motion with no encoder change */
	uint32_t drive_timeout_ms;    /* drive replies missing this long: fault */
	uint32_t servo_on_timeout_ms; /* servo on: every drive enabled within this, else fault */
	/* A tick later than its period by more than this: the loop stalled
	 * (fault 210). Lateness below it is counted, not a fault. */
	uint32_t loop_late_ms;
	/* Link watchdog: motion stops when no valid request arrived on any link
	 * for this long (warning 153). 0 = off. */
	uint32_t link_timeout_ms;
	/* In position (CiA 402's position window and window time): the motion
	 * is done once the reference is at rest and every wheel has stayed
	 * within position_window_mm of it (at least one encoder count) for
	 * position_window_ms; a unit not in position settle_timeout_ms after its
	 * reference stopped raises warning 154. */
	vs_real_t position_window_mm;
	uint32_t position_window_ms, settle_timeout_ms;

	/* Cruise blending: how far the curve may start before a waypoint. */
	vs_real_t cruise_blend_mm;
	/* Caution speed cap while the obstacle-warning input is active (0 = none). */
	vs_real_t caution_vel_t_mm_s;

	/* Battery, in volts. */
	vs_real_t battery_low_v, battery_critical_v;

	/* Which optional devices this unit has. */
	bool has_contact_sensor, has_obstacle_input, has_estop, has_joystick;
	vs_real_t joystick_deadband; /* fraction of full scale, 0..0.5 */

	const char *firmware_version; /* "Ver.x.y.z"; NULL: built-in */

	uint8_t num_io;
	vs_io_def_t io[VS_MAX_IO];
} vs_config_t;

/* The fields with a default, a range and an XML attribute: one table
 * (config_fields.def), from which the firmware keeps what it needs. */
#include "config_fields.def"

/* C type of a row's member. */
typedef enum {
	VS_CFG_DOUBLE = 0,
	VS_CFG_U32 = 1,
	VS_CFG_U16 = 2,
	VS_CFG_BOOL = 3,
	VS_CFG_KIN = 4, /* vs_kinematics_t */
} vs_config_type_t;

/* When a change at run time takes effect (the table's when column). */
typedef enum {
	VS_CFG_WHEN_ANY = 0,	 /* at once, whatever the unit does */
	VS_CFG_WHEN_OFF = 1,	 /* with the servo off and no motion queued */
	VS_CFG_WHEN_RESTART = 2, /* from the next start */
} vs_config_when_t;

/* One row of the table as the firmware keeps it for readers of a running
 * configuration (the console's $config) and for vs_config_check: no XML
 * columns. vs_config_defaults is generated from the rows. The range in
 * eighths of the unit (every bound of the table is a multiple of 1/8 below
 * 2^28) fills what was the row's padding: 16 bytes a row, where a separate
 * table of ranges took 8 bytes a row more. */
typedef struct {
	const char *name; /* the member's name */
	int32_t hi8;	  /* max * 8 */
	uint16_t off;	  /* offsetof(vs_config_t, member) */
	int16_t lo8;	  /* min * 8 */
	uint8_t type;	  /* vs_config_type_t */
	uint8_t n;	  /* elements: 1, or the array's length */
	uint8_t when;	  /* vs_config_when_t */
	bool lo_excl;	  /* min < x rather than min <= x */
} vs_config_field_t;

/* Row indexes, VS_CONFIG_ROW_<member>, in the table's order. */
enum {
#define VS_CONFIG_ROW_INDEX(m, ...) VS_CONFIG_ROW_##m,
	VS_CONFIG_FIELDS(VS_CONFIG_ROW_INDEX)
#undef VS_CONFIG_ROW_INDEX
	    VS_CONFIG_NFIELDS
};

extern const vs_config_field_t vs_config_fields[VS_CONFIG_NFIELDS];

#ifndef VS_REAL_Q32
/* Element k (< f->n) of row f's member, as a double (a boolean 0 or 1).
 * Host only: the XML reader and $config. */
double vs_config_get(const vs_config_t *c, const vs_config_field_t *f, unsigned k);
/* Stores v, converted to the member's type, in element k of row f. */
void vs_config_set(vs_config_t *c, const vs_config_field_t *f, unsigned k, double v);
#endif

/* Whether c is a mecanum base. A build for one base (-DVS_KIN_ONLY=0
 * differential, 1 mecanum: a board, whose configuration is compiled in)
 * keeps that base's code only, and vs_config_check refuses the other. */
/* Whether c has a joystick. A board built without one (-DVS_NO_JOYSTICK)
 * carries no joystick code: setJoystick(true) finds none (warning 152). */
#ifdef VS_NO_JOYSTICK
#define vs_config_joystick(c) ((void)(c), false)
#else
#define vs_config_joystick(c) ((c)->has_joystick)
#endif
/* The discrete safety inputs (contact, obstacle and caution, e-stop). A
 * board built without them (-DVS_NO_INPUTS: the loopback board has none)
 * carries no code for them. */
#ifdef VS_NO_INPUTS
#define vs_config_contact(c)  ((void)(c), false)
#define vs_config_obstacle(c) ((void)(c), false)
#define vs_config_estop(c)    ((void)(c), false)
#else
#define vs_config_contact(c)  ((c)->has_contact_sensor)
#define vs_config_obstacle(c) ((c)->has_obstacle_input)
#define vs_config_estop(c)    ((c)->has_estop)
#endif

#ifdef VS_KIN_ONLY
#define vs_config_omni(c) ((void)(c), VS_KIN_ONLY == VS_KIN_OMNI)
#else
#define vs_config_omni(c) ((c)->kinematics == VS_KIN_OMNI)
#endif

/* Number of wheel axes for a kinematics type. */
static inline uint8_t vs_config_axes(const vs_config_t *c)
{
	return vs_config_omni(c) ? 4 : 2;
}

/* Fills a configuration with the reference differential base's values. */
void vs_config_defaults(vs_config_t *c);

/* Checks ranges and consistency. Returns 0 when valid, otherwise a negative
 * number and writes the offending field's name to *field. */
int vs_config_check(const vs_config_t *c, const char **field);
/* The largest jerk a configuration or $jerk takes (mm/s^3, deg/s^3). */
#define VS_JERK_MAX 1e7
/* A jerk j (mm/s^3 or deg/s^3) the profiles can hold at c's tick rate
 * (0, unlimited, always), and within limit unless that is 0. */
bool vs_jerk_fits(const vs_config_t *c, vs_real_t j, vs_real_t limit);

#endif
