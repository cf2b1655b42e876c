/* VehicleService: the 34 operations of ../shared/spec/VehicleService.md.
 *
 * The IDL maps to C as: boolean return, in arguments by value, out
 * arguments by pointer, structs as the vs_* types below, strings as
 * NUL-terminated buffers owned by the unit (valid until the next call).
 * Numbers are vs_real_t (real.h: double on a host, Q32 on a board without
 * an FPU) only here, at the boundary; vs_api.c converts them once to the
 * fixed-point units the tick uses, and rejects NaN, infinity and values out
 * of range with false and a warning alarm.
 *
 * Nothing here blocks except vs_setPower (relay settle time, see hal.h);
 * motion happens in vehicle_tick(), one call per control period.
 */
#ifndef VEHICLE_H
#define VEHICLE_H

#include <stdbool.h>
#include <stdint.h>

#include "alarm.h"
#include "blackbox.h"
#include "config.h"
#include "kin.h"
#include "motion.h"
#include "../hal/hal.h"

#define VS_IF_VERSION	 "RTC VehicleService interface: ver.2.0.0"
#define VS_FW_VERSION	 "Ver.1.0.0"
#define VS_STATE_MSG_MAX 16

/* getState codes (spec section 4). */
enum {
	VS_STATE_READY = 0x010,
	VS_STATE_BUSY = 0x011,
	VS_STATE_WARNING = 0x012,
	VS_STATE_ALARM = 0x013,
	VS_STATE_STUCK = 0x014,
	VS_STATE_PAUSED = 0x015,
	VS_STATE_AVOID = 0x016,
	VS_STATE_LOCKED = 0x017,
	VS_STATE_POWERED = 0x018,
	VS_STATE_UNPOWERED = 0x019,
};

typedef struct {
	vs_real_t x, y;
} vs_point_t;
typedef struct {
	vs_real_t x, y, theta;
} vs_position_t;
typedef struct {
	vs_real_t translation, rotation;
} vs_velocity_t;

typedef struct vehicle vehicle_t;

/* Lifecycle. vehicle_init validates cfg (returns a negative value and the
 * field name through *bad_field when invalid) and leaves the unit Unpowered. */
int vehicle_init(vehicle_t *v, const vs_config_t *cfg, const vs_hal_t *hal, const char **bad_field);
/* One control period. now_us: a free-running microsecond clock (wraps).
 * The time between two ticks is supervised: over 1.5 periods the tick is
 * counted late, over a period plus loop_late_ms the loop has stalled (fault
 * 210). The reference advances by ticks, so lateness only delays it. */
void vehicle_tick(vehicle_t *v, uint32_t now_us);
/* The platform's measure of its own work in the last period (the tick and
 * the link service, on the CPU, without time taken by other tasks): over a
 * period is fault 209, the loop over budget. */
void vehicle_tick_busy(vehicle_t *v, uint32_t busy_us);

/* The motion is done: the reference at rest and the wheels in position
 * for the window time (or the settle time out), or the servo off. */
bool vehicle_in_position(const vehicle_t *v);
/* Planning spread over idle time (motion_set_plan_budget): the budget, and
 * the call a main loop makes between requests and ticks (true: it walked). */
void vehicle_set_plan_budget(vehicle_t *v, uint8_t n);
bool vehicle_plan_idle(vehicle_t *v);

/* The links a request can arrive on, for the link watchdog. */
typedef enum { VS_LINK_CONSOLE = 0, VS_LINK_FRAMES = 1, VS_LINK_CAN = 2 } vs_link_id_t;
/* A valid request arrived on a link: the link watchdog restarts. */
void vehicle_link_heard(vehicle_t *v, vs_link_id_t link);
/* The link watchdog's timeout in ms (0 = off), from link_timeout_ms at
 * init; the set form ($watchdog) restarts the watchdog. */
uint32_t vehicle_link_timeout(const vehicle_t *v);
void vehicle_set_link_timeout(vehicle_t *v, uint32_t ms);
/* The jerk moves run at (mm/s^3, deg/s^3; 0 = unlimited), from the
 * configuration's defaults; the set form ($jerk) takes values that fit
 * (vs_jerk_fits: within the limits, held at the tick rate) and refuses
 * others, changing nothing. A piece under way keeps its profile. */
void vehicle_jerk(const vehicle_t *v, vs_real_t *jt, vs_real_t *jr);
bool vehicle_set_jerk(vehicle_t *v, vs_real_t jt, vs_real_t jr);

/* A configuration changed at run time (config_keep.h judges it first with
 * vs_config_check and by the table's when column). vehicle_config_idle: the
 * servo off and no motion queued, when a field of class OFF may change.
 * vehicle_reconfigure (only then): everything derived from the
 * configuration is derived again as at init, the unit's state (power,
 * alarms, pose) kept; a speed, acceleration or jog timeout in force stays
 * while within its new limits and its default is unchanged, else it is
 * the new default. vehicle_config_live: a change of class ANY fields only
 * (link timeout, jerk in force, battery thresholds), at any time. */
bool vehicle_config_idle(const vehicle_t *v);
void vehicle_reconfigure(vehicle_t *v, const vs_config_t *cfg);
void vehicle_config_live(vehicle_t *v, const vs_config_t *cfg);

/* The operations, in spec order. */
bool vs_clearAlarm(vehicle_t *v);
bool vs_getAccelerationLimit(vehicle_t *v, vs_real_t *accLimitT, vs_real_t *accLimitR);
/* activeAlarms has room for max(numOfAlarm, 0) entries (the caller's
 * buffer); *len receives how many were written. */
bool vs_getActiveAlarm(vehicle_t *v, int16_t numOfAlarm, int16_t *numOfActiveAlarm,
		       vs_alarm_t *activeAlarms, uint16_t *len);
bool vs_getBatteryVoltage(vehicle_t *v, vs_real_t *voltage);
bool vs_getDefaultAcceleration(vehicle_t *v, vs_velocity_t *defaultAccel);
bool vs_getDefaultVelocity(vehicle_t *v, vs_velocity_t *defaultVel);
bool vs_getIFVersion(vehicle_t *v, const char **version);
bool vs_getInput(vehicle_t *v, uint32_t ioid, uint32_t *input);
bool vs_getPosition(vehicle_t *v, vs_position_t *pos);
bool vs_getServoStatus(vehicle_t *v, uint32_t axisid, bool *status);
bool vs_getState(vehicle_t *v, int16_t *state, char msg[VS_STATE_MSG_MAX]);
bool vs_getVelocityLimit(vehicle_t *v, vs_real_t *velLimitT, vs_real_t *velLimitR);
bool vs_getVersion(vehicle_t *v, const char **ver);
bool vs_moveCircularRel(vehicle_t *v, vs_point_t centerPoint, vs_real_t theta);
bool vs_moveContinuousRel(vehicle_t *v, vs_position_t pos);
bool vs_moveCruiseAbs(vehicle_t *v, vs_point_t cruisePoint);
bool vs_moveForward(vehicle_t *v, vs_real_t x_);
bool vs_moveJog(vehicle_t *v, vs_real_t xVel, vs_real_t yVel, vs_real_t thetaVel);
bool vs_moveLinearAbs(vehicle_t *v, vs_position_t pos);
bool vs_moveLinearRel(vehicle_t *v, vs_position_t pos);
bool vs_moveTurn(vehicle_t *v, vs_real_t theta_);
bool vs_pause(vehicle_t *v);
bool vs_resume(vehicle_t *v);
bool vs_setAcceleration(vehicle_t *v, vs_velocity_t accel);
bool vs_setDigitalSensorLock(vehicle_t *v, bool OnOff);
bool vs_setJogTimeout(vehicle_t *v, int16_t timeout);
bool vs_setJoystick(vehicle_t *v, bool OnOff);
bool vs_setOutput(vehicle_t *v, uint32_t ioid, uint32_t output, uint32_t mask);
bool vs_setPosition(vehicle_t *v, vs_position_t pos);
bool vs_setPower(vehicle_t *v, bool OnOff);
bool vs_setServo(vehicle_t *v, bool OnOff);
bool vs_setVelocity(vehicle_t *v, vs_velocity_t vel);
bool vs_stop(vehicle_t *v);
bool vs_unlock(vehicle_t *v);

/* Diagnostics for the bring-up console, traces and tests (not interface
 * operations). */
typedef struct {
	fx_pose_t ref_pose;		   /* commanded */
	fx_pose_t odom_pose;		   /* measured (odometry) */
	fx_twist_t cmd_twist_pt;	   /* commanded body velocity per tick */
	fx_twist_t meas_twist_pt;	   /* measured (odometry's) body motion of the last tick */
	int32_t wheel_cps_q8[VS_MAX_AXES]; /* drive setpoints */
	uint32_t ticks;			   /* control ticks since init */
	uint32_t overruns;		   /* periods whose work took over a period */
	uint32_t late_ticks;		   /* ticks over half a period late */
	uint32_t max_late_us;		   /* the latest tick, past its period */
	uint8_t queue_len;
	uint8_t mode; /* motion_mode_t */
} vs_diag_t;
void vehicle_diag(const vehicle_t *v, vs_diag_t *d);
/* The black box (blackbox.h) records into cap samples at buf, one every
 * `every` ticks; off until given storage. Read it at v->bbox. */
void vehicle_blackbox(vehicle_t *v, bbox_sample_t *buf, uint16_t cap, uint16_t every);

/* Firmware-internal: the fixed-point core that vs_api.c (the double
 * boundary) calls after converting and range-checking the arguments. */
typedef enum {
	VEHICLE_GATE_READY = 0, /* Ready-only operation */
	VEHICLE_GATE_SERVO = 1, /* Servo-on operation, queued while paused */
	VEHICLE_GATE_JOG = 2,	/* Servo-on velocity command: refused while paused */
} vehicle_gate_t;
/* Raises the warning "<op> refused: <reason of code>"; returns false. */
bool vehicle_refuse(vehicle_t *v, const char *op, uint32_t code);
/* State checks of a move* operation; false (with the warning) when refused. */
bool vehicle_move_gate(vehicle_t *v, const char *op, vehicle_gate_t gate);
/* A motion_* call returned false: raise the most specific warning, return
 * false. velocity_mode: jog or continuous (refused while path motion runs). */
bool vehicle_motion_refused(vehicle_t *v, const char *op, bool velocity_mode);

/* Implementation detail: static allocation by the caller, fields private. */
struct vehicle {
	vs_hal_t hal;
	/* The byte-wide state next: within the 32 bytes a Cortex-M reaches
	 * with a 16-bit byte load or store (motion.h). */
	uint8_t naxes;
	/* Unit state. */
	bool powered, servo, locked, stuck, sensor_lock, joystick_on;
	/* The stick may drive: it was seen at neutral since the last stop,
	 * pause, fault, servo off or hand-over (docs/states.md). */
	bool stick_armed;
	/* Servo on waits for every drive to report enabled (servo_wait, for
	 * servo_wait_ticks so far); a drive that restarted lost its count:
	 * motion is refused until setPosition (pose_lost). */
	bool servo_wait, pose_lost;
	bool have_now;
	uint8_t link_last; /* vs_link_id_t heard last */
	/* Supervision's last inputs. */
	bool contact_prev, obstacle_prev, caution_prev, battery_low_armed;
	/* The tick's words next: within the 124 bytes a Cortex-M reaches with
	 * a 16-bit word load or store. */
	uint32_t servo_wait_ticks, servo_on_timeout_ticks;
	uint32_t ticks, overruns, last_now_us;
	uint32_t late_ticks, max_late_us, loop_late_us;
	uint32_t link_timeout_ticks, link_silent_ticks;
	/* Supervision limits, fixed point, derived from cfg at init. */
	uint32_t period_us;
	uint32_t drive_timeout_ticks, encoder_stuck_ticks;
	/* The commanded speed T (counts/s Q8) that must move the encoder, as
	 * T - 1 and 2T - 1 (supervise_encoder's one compare). */
	uint32_t encoder_stuck_off, encoder_stuck_span;
	uint32_t window_ticks, settle_timeout_ticks;
	uint32_t battery_low_mv, battery_critical_mv;
	uint32_t battery_mv;
	/* In position: ticks within the window, ticks at rest out of it
	 * (past settle_timeout_ticks: warning 154 raised, taken as done). */
	uint32_t inpos_ticks, settle_ticks;
	int32_t wheel_cps_q8[VS_MAX_AXES];
	motion_t motion; /* first of the rest: its scalars within reach of one load (motion.h) */
	kin_t kin;
	fx_pose_t odom;
	fx_trig_cache_t odom_trig; /* odometry's last heading */
	/* Settings in force (interface units, as accepted). */
	vs_velocity_t vel_set, acc_set;
	int16_t jog_timeout_ms;
	uint32_t out_shadow[VS_MAX_IO];
	fx_twist_t cmd;
	fx_twist_t meas; /* the odometry's body displacement of the last tick */
	/* Latest drive samples; .enabled also follows drive_enable commands. */
	hal_drive_state_t drive[VS_MAX_AXES];
	int32_t meas_counts[VS_MAX_AXES];
	int64_t following_err_max_q32; /* counts (Q32) */
	int64_t window_q32;	       /* position window, counts (Q32) */
	q32_t caution_vel_t;	       /* mm/s, Q32 */
	int32_t joystick_deadband_q15;
	/* Supervision. */
	uint32_t drive_silent_ticks[VS_MAX_AXES];
	uint16_t drive_fault_reported[VS_MAX_AXES]; /* fault code already raised */
	bool drive_timeout_reported[VS_MAX_AXES];
	uint32_t encoder_still_ticks[VS_MAX_AXES];
	char state_msg[VS_STATE_MSG_MAX];
	/* Large and seldom read: last. */
	blackbox_t bbox;
	alarm_list_t alarms;
	vs_config_t cfg;
};

#endif
