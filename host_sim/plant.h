/* Simulated plant: wheel motors with drives and encoders, the true vehicle
 * pose, main power relay, battery, discrete sensors, joystick and digital IO.
 *
 * Everything is double precision and advanced in lockstep by plant_step();
 * the firmware sees it only through sim_hal.c. Units: wheel state in encoder
 * counts (the true wheel angle, unquantised) and counts/s; pose in mm and
 * degrees; battery in volts and amperes.
 *
 * Motor model (per wheel): the speed follows the drive setpoint as a first
 * order lag, v' = (target - v) / tau, solved exactly over each step, then
 * clipped by the acceleration limit and by the current limit, where the
 * motor current is I = amp_per_mm_s2 * a + amp_per_mm_s * v (signed, wheel
 * surface units). A disabled, faulted or unpowered drive has target 0 and no
 * limits: it coasts down with the same lag. The encoder reports
 * floor(true angle in counts).
 *
 * Battery: V = ocv - r * (idle + sum |I_motor|); motors draw only while the
 * relay is closed.
 */
#ifndef PLANT_H
#define PLANT_H

#include <stdbool.h>
#include <stdint.h>

#include "../firmware/config.h"
#include "../hal/hal.h"

#define PLANT_MAX_WALLS 8

typedef struct {
	double tau_s;		/* motor velocity time constant; 0: follows at once */
	double acc_limit_mm_s2; /* wheel surface acceleration limit; 0: none */
	double current_limit_a; /* per motor; 0: none */
	double amp_per_mm_s2;	/* motor current per unit wheel acceleration */
	double amp_per_mm_s;	/* motor current per unit wheel speed */
	double idle_current_a;	/* electronics, drawn always */
	double battery_ocv_v;	/* open-circuit voltage */
	double battery_r_ohm;	/* internal resistance */
	double body_radius_mm;	/* body circle for wall contact */
	bool io_loopback;	/* wire the n-th output to the n-th input of io.xml */
} plant_params_t;

/* Typical base: 20 ms motor lag, 3000 mm/s^2, 10 A per motor, 25.2 V pack
 * with 0.1 ohm. */
void plant_params_default(plant_params_t *p);
/* For precise motion tests: no lag, no acceleration or current limit
 * (battery and IO as the default). */
void plant_params_ideal(plant_params_t *p);
/* States plant p's motor lag in the firmware's configuration (every axis):
 * the wheel loop's feed-forward leads by the configured lag, so a
 * configuration must name the drive it runs. */
void plant_config_lag(const plant_params_t *p, vs_config_t *cfg);
/* Encoder resolution for precise tests: set in the configuration, since the
 * firmware converts counts with it. Fits the HAL's Q8 setpoint range with
 * the reference limits. */
#define PLANT_HIRES_COUNTS_PER_REV (1u << 20)
/* The fine resolution for cfg: the largest power of two up to
 * PLANT_HIRES_COUNTS_PER_REV whose fastest wheel setpoint vs_config_check
 * admits (faster limits or smaller wheels need fewer counts), or cfg's own
 * resolution when that is finer. A cfg rejected for another field gets
 * PLANT_HIRES_COUNTS_PER_REV; vehicle_init then names that field. */
uint32_t plant_hires_counts_per_rev(const vs_config_t *cfg);

typedef struct {
	double pos_counts; /* true wheel angle */
	double vel_cps;	   /* true speed */
	double acc_cps2;   /* over the last step */
	double current_a;  /* signed motor current over the last step */
	int32_t setpoint_q8;
	bool enable_cmd;
	uint16_t fault_inject;	/* fault condition present (0: none) */
	uint16_t fault_latched; /* what the drive reports until reset */
	bool stuck;		/* encoder frozen at stuck_counts */
	int32_t stuck_counts;
	bool silent;	     /* replies lost: drive_read repeats `last` */
	bool hold;	     /* power stage held off (an STO): stays in Switched on */
	bool restarted;	     /* rebooted since the last read: its count starts over */
	double count_offset; /* what a reboot took off the count */
	hal_drive_state_t last;
} plant_wheel_t;

typedef struct {
	double x0, y0, x1, y1;
} plant_wall_t;

typedef enum { PLANT_RELAY_OK = 0, PLANT_RELAY_FAIL, PLANT_RELAY_DROP } plant_relay_mode_t;

typedef struct {
	plant_params_t p;
	vs_config_t cfg;
	uint8_t n; /* wheel axes */
	double counts_per_mm;
	double half_mm; /* wheel travel per radian of body rotation */

	/* True pose; theta unwrapped, radians. */
	double x_mm, y_mm, th_rad;
	plant_wheel_t w[VS_MAX_AXES];

	bool relay_cmd, relay_closed, relay_fail;
	bool contact_inject, obstacle, caution, estop;
	hal_joystick_t js;
	double battery_ocv_v, battery_current_a;

	uint32_t io_val[VS_MAX_IO]; /* by cfg.io index */
	int8_t io_wire[VS_MAX_IO];  /* output index -> input index, -1: none */

	plant_wall_t walls[PLANT_MAX_WALLS];
	uint8_t num_walls;
	uint64_t time_us;
} plant_t;

void plant_init(plant_t *pl, const vs_config_t *cfg, const plant_params_t *p);
/* Advance dt_us of time with the current setpoints. */
void plant_step(plant_t *pl, uint32_t dt_us);

/* Drive side, as the HAL sees it. */
void plant_drive_set_velocity(plant_t *pl, uint8_t axis, int32_t cps_q8);
void plant_drive_enable(plant_t *pl, uint8_t axis, bool on);
void plant_drive_read(plant_t *pl, uint8_t axis, hal_drive_state_t *st);
void plant_drive_reset_fault(plant_t *pl, uint8_t axis);
bool plant_drive_enabled(const plant_t *pl, uint8_t axis);
/* Relay: returns true when the contact reached the commanded state. */
bool plant_power_set(plant_t *pl, bool on);
bool plant_contact(const plant_t *pl);
uint32_t plant_battery_mv(const plant_t *pl);
bool plant_io_read(const plant_t *pl, uint32_t id, uint32_t *value);
bool plant_io_write(plant_t *pl, uint32_t id, uint32_t value);

/* Injection. Axis-taking calls return false for a bad axis. */
void plant_set_relay_mode(plant_t *pl, plant_relay_mode_t mode);
bool plant_drive_fault(plant_t *pl, uint8_t axis, uint16_t code);
bool plant_drive_stuck(plant_t *pl, uint8_t axis, bool on);
bool plant_drive_silent(plant_t *pl, uint8_t axis, bool on);
/* The power stage held off (as a safe torque off does): the drive stays in
 * Switched on whatever the master asks. */
bool plant_drive_hold(plant_t *pl, uint8_t axis, bool on);
/* The drive reboots: it forgets the enable, and its count starts at 0
 * (reported as a lost position on the next read). */
bool plant_drive_reboot(plant_t *pl, uint8_t axis);
/* Clears fault condition, stuck and silent; a latched fault stays until
 * drive_reset_fault, as on a real drive. */
bool plant_drive_ok(plant_t *pl, uint8_t axis);
/* Sets an input's value (masked to its width); false if id is not an input. */
bool plant_set_input(plant_t *pl, uint32_t id, uint32_t value);
/* Wire output id to input id (in_id 0: unwire); false if either is wrong. */
bool plant_wire(plant_t *pl, uint32_t out_id, uint32_t in_id);
bool plant_add_wall(plant_t *pl, double x0, double y0, double x1, double y1);
void plant_set_battery_ocv(plant_t *pl, double volts);
/* An external force moves the base, at once, by (dx_mm, dy_mm) in its own
 * frame at the start of the push (x forward, y to the left) and turns it by
 * dth_deg counter-clockwise. The wheels are back-driven as they would turn
 * along the steady twist that ends there (the arc of plant_step), so the
 * encoders count the push as the kinematics of kin.h relate it; wheel
 * speeds are kept. A differential base cannot roll sideways: its wheels skid
 * through the twist's lateral part and do not turn for it. False, and
 * nothing moves, for a value that is not finite or beyond
 * PLANT_PUSH_MAX_MM on either axis or PLANT_PUSH_MAX_DEG. */
#define PLANT_PUSH_MAX_MM  1000.0
#define PLANT_PUSH_MAX_DEG 180.0
bool plant_push(plant_t *pl, double dx_mm, double dy_mm, double dth_deg);
/* Joystick axes as fractions of full scale (clamped to +-1). */
void plant_set_joystick(plant_t *pl, double x, double y, double r, bool present);

/* Truth, for tests and traces. Theta in (-180, 180]. */
void plant_pose(const plant_t *pl, double *x_mm, double *y_mm, double *th_deg);
void plant_set_pose(plant_t *pl, double x_mm, double y_mm, double th_deg);
double plant_wheel_mm_s(const plant_t *pl, uint8_t axis);
double plant_wheel_mm(const plant_t *pl, uint8_t axis);

#endif
