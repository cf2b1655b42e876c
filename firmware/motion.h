/* Motion engine: the queue of motion commands and the fixed-point trajectory
 * generator that turns them into one body velocity per control tick.
 *
 * Everything here is integer arithmetic (fx.h formats). The caller (vehicle.c)
 * owns the unit's state machine and refusal rules; this module only plans and
 * executes motion and reports whether it accepted a plan.
 *
 * Per tick: motion_tick(m, measured_pose, &twist). The engine advances its
 * reference pose by exactly the twist it outputs; when it is idle it follows
 * the measured (odometry) pose so that relative commands start from where
 * the unit really is.
 */
#ifndef MOTION_H
#define MOTION_H

#include <stdbool.h>
#include <stdint.h>

#include "fx.h"
#include "kin.h"
#include "traj.h"

#ifndef MOTION_QUEUE_LEN /* the MCU build sets a shorter queue */
#define MOTION_QUEUE_LEN 32
#endif

typedef struct {
	uint32_t tick_hz;
	motion_kin_t kin;
	/* Hard limits, per second, Q32 (mm/s, deg/s, mm/s^2, deg/s^2). Stops
	 * (stop, pause, contact, obstacle) decelerate at acc_limit. */
	q32_t vel_limit_t, vel_limit_r, acc_limit_t, acc_limit_r;
	/* Jerk limits (mm/s^3, deg/s^3), 0 = unlimited: stops reach acc_limit
	 * at these. */
	q32_t jerk_limit_t, jerk_limit_r;
	q32_t cruise_blend_mm;
} motion_params_t;

typedef enum {
	MCMD_NONE = 0,
	MCMD_LINE,    /* to a world pose: face, straight line, final heading (differential);
			 one straight move with blended heading (omni) */
	MCMD_FORWARD, /* straight along the current heading, signed, heading kept */
	MCMD_TURN,    /* rotate in place by an angle (may exceed a turn) */
	MCMD_ARC,     /* rigid rotation about a centre by an angle */
	MCMD_CRUISE,  /* blended waypoint */
} motion_cmd_kind_t;

typedef struct {
	uint8_t kind;	    /* motion_cmd_kind_t */
	uint8_t stage;	    /* execution progress within the command */
	bool has_heading;   /* LINE: target.th is to be reached */
	bool start_known;   /* CRUISE: sx, sy hold where its line starts */
	bool has_corner;    /* CRUISE: blended into the next waypoint */
	fx_pose_t target;   /* world frame end pose (position for every kind) */
	q32_t cx_mm, cy_mm; /* ARC centre, world frame */
	q32_t angle_deg;    /* TURN / ARC sweep, signed, unwrapped */
	q32_t sx_mm, sy_mm; /* CRUISE: start of the incoming line; ARC: centre, body frame */
	q32_t vend_pt;	    /* CRUISE: planned speed through the corner */
	q32_t line_mm;	    /* CRUISE: length of its straight part (cached) */
	q32_t len_mm;	    /* CRUISE: start to target (valid with start_known) */
	int32_t ux, uy;	    /* CRUISE: unit direction start to target, Q30 (idem) */
	/* CRUISE with a corner, planned by the backward pass: the corner's speed
	 * cap from rotation (before the translation limit), its acceleration,
	 * and the stopping distance counted beyond the end of the line and of
	 * the corner (traj.h: a speed cap ahead is a virtual stop further on). */
	q32_t corner_vrot_pt, corner_a_pt2, line_extra_mm, corner_extra_mm;
	/* CRUISE with a corner: where it ends (the waypoint plus the tangent
	 * length along the next line), fixed when it is planned. */
	q32_t exit_x_mm, exit_y_mm;
	traj_corner_t corner;
} motion_cmd_t;

/* The engine's modes and their names ($diag), from one table. */
#define MOTION_MODES(X)                                                                            \
	X(MODE_IDLE, "idle")                                                                       \
	X(MODE_PATH, "path")		 /* executing queued path commands */                      \
	X(MODE_JOG, "jog")		 /* velocity command with watchdog */                      \
	X(MODE_CONTINUOUS, "continuous") /* retargetable goal */                                   \
	X(MODE_JOYSTICK, "joystick")	 /* velocity target from the joystick */

typedef enum {
#define MOTION_MODE_ENUM(id, name) id,
	MOTION_MODES(MOTION_MODE_ENUM)
#undef MOTION_MODE_ENUM
	    MOTION_MODE_COUNT
} motion_mode_t;

typedef enum { SEG_NONE = 0, SEG_LINE, SEG_TURN, SEG_ARC, SEG_CORNER } seg_kind_t;

/* The piece of path being executed. */
typedef struct {
	uint8_t kind;	      /* seg_kind_t */
	int8_t dir;	      /* TURN/ARC: sweep sign */
	q32_t len, s;	      /* length and progress (mm, or deg for TURN/ARC) */
	fx_pose_t p0;	      /* start pose */
	fx_pose_t p_end;      /* exact end pose, taken at completion */
	int32_t ux, uy;	      /* LINE/CORNER entry: unit direction, Q30 */
	q32_t dth;	      /* LINE: heading change along it (omni) */
	q32_t cx, cy;	      /* ARC centre */
	q32_t arc_k;	      /* ARC: mm of travel per degree of sweep */
	q32_t arc_kx, arc_ky; /* ARC: body velocity per unit rotation rate (mm/deg) */
	q32_t omni_k;	      /* LINE (omni): mm per degree of heading change */
	q32_t h;	      /* CORNER: heading change at s */
	/* CORNER: the head command's, not a copy (its entry is the dearest
	 * tick of a cruise). The head stays queued until the corner ends, and
	 * nothing changes a running corner's shape (a new acceleration only
	 * its caps, which the piece does not read). */
	const traj_corner_t *corner;
} seg_t;

enum {
	LN_NEXT_NONE,
	LN_NEXT_KEY /* tried, no plan */,
	LN_NEXT_PLAN,
	LN_NEXT_PART /* planning, to go on at the next idle call */
};

typedef struct {
	/* The byte-wide state first: a Cortex-M loads or stores a byte with a
	 * 16-bit instruction only within 32 bytes of the struct (the unit's
	 * code reaches the first 8 through struct vehicle, vehicle.h). */
	uint8_t mode;  /* motion_mode_t */
	bool paused;   /* held by pause (decelerating or stopped) */
	bool stopping; /* stop(): decelerating, then discard */
	bool joystick; /* joystick enabled */
	uint8_t q_head, q_count;
	bool lim_ok;   /* lim_* below hold for the active piece */
	bool jerk_any; /* a jerk is set or limited (j*_pt3 below) */
	/* The profile flags a drop clears together (plan_drop): one word. */
	bool sc_on; /* the planned jerk-limited profile runs */
	bool ln_on, glide, hold_on;
	uint8_t stop_drop;   /* commands stop() discards once at rest (the first) */
	bool rest_tick;	     /* a piece or (jerk limits) a motion stopped: the next
				tick stands still */
	uint8_t plan_budget; /* commands a pass walks per call (0: all) */
	uint8_t pass_todo;   /* the queue's first pass_todo commands await the pass */
	bool fresh, face_ok;
	uint8_t ln_i, ln_next; /* ln_next: LN_NEXT_* */
	/* The continuous goal (below): its position reached; a differential
	 * base backing toward it; per axis of its law under jerk limits the
	 * direction its tail to rest runs in, that tail running, and its
	 * being an S-curve from rest. */
	bool goal_position_done, goal_reverse;
	int8_t sk_sg[2];
	bool sk_on[2], sk_rest[2];
	motion_params_t p;
	/* Settings in per-tick units (derived once per change). */
	q32_t v_t_pt, v_r_pt, a_t_pt2, a_r_pt2;
	q32_t amax_t_pt2, amax_r_pt2, vmax_t_pt, vmax_r_pt;
	q32_t j_t_pt3, j_r_pt3, jmax_t_pt3, jmax_r_pt3; /* jerks, 0 = unlimited */
	q32_t cap_t_pt;					/* caution cap, 0 = none */

	fx_pose_t ref;	/* reference (commanded) pose */
	fx_twist_t vel; /* current commanded body velocity */
	q32_t pass_vt;	/* the line speed the corner speeds were planned for */

	seg_t seg; /* active piece (mode PATH) */
	q32_t v;   /* speed along the active piece, per tick */
	/* The active piece's speed cap, acceleration and stopping distance
	 * beyond its end, valid while lim_ok (limits_changed, motion_priv.h, drops
	 * it on any change). */
	q32_t lim_vmax, lim_a, lim_extra;
	q32_t lim_cruise; /* lim_vmax plus its braking distance (-1: not yet) */
	int64_t lim_n;	  /* the profile's last braking step count (traj_step_near) */
	q32_t lim_j;	  /* the piece's jerk limit, 0 = unlimited */
	/* Jerk-limited pieces (motion_profile.c): the planned profile
	 * (sc_on below: it runs) and the last tick's change of speed. */
	traj_sc_t sc;
	q32_t acc;
	/* A line between speeds (lnb below; ln_on: it runs; a cruise line,
	 * or after a new speed limit the line from the speed reached, planned
	 * once the acceleration is zero: glide brings it there at the jerk);
	 * plan_cap is the limit the running profile was planned for. */
	q32_t plan_cap;
	/* Jerk-limited cruise: a piece's profile is chosen on its first tick
	 * (fresh below); a corner entered at speed holds it (hold_on, hold_v);
	 * the next line's profile is planned ahead (motion_plan_idle) for the
	 * length, speeds and limits in ln_key (ln_next says what they hold). */
	q32_t hold_v;
	q32_t ln_key[6];
	/* The head cruise waypoint's (face_to) turn to face it from
	 * face_ref, worked out ahead likewise (face_ok). */
	fx_pose_t face_ref, face_to;
	q32_t face_a;

	/* Jog / joystick velocity target (body frame, per tick), and the last
	 * tick's change of velocity (the jerk-limited slew's state). */
	fx_twist_t vtarget, vacc;
	uint32_t jog_timeout_ticks, jog_age_ticks;
	/* Continuous mode goal (world frame). */
	fx_pose_t goal;
	/* The continuous goal under jerk limits (motion_seek.c): the mecanum
	 * axes' speeds, last changes and (Q30) direction; per axis the tail
	 * to rest running (sk_on, in lnb[i]), the cap it was planned under
	 * and the direction it runs in. */
	q32_t sk_v[2], sk_a[2], sk_cap[2];
	int64_t sk_dip[2]; /* the dips' bound in ticks: translation, rotation */
	int32_t sk_c, sk_s;

	/* The large members last: a Cortex-M loads a 64-bit member in one
	 * instruction only within 1020 bytes of the struct (ldrd), and the
	 * scalars above stay within it (1.5 KiB less code with the layout of
	 * struct vehicle, docs/mcu.md). */
	traj_ln_t lnb[2]; /* the line running (ln_i) and the one planned ahead */
	motion_cmd_t q[MOTION_QUEUE_LEN];
} motion_t;

void motion_init(motion_t *m, const motion_params_t *p);

/* Settings, per second, Q32. Values are validated by the caller; a new
 * velocity takes effect continuously while moving. */
void motion_set_velocity(motion_t *m, q32_t vt, q32_t vr);
void motion_set_accel(motion_t *m, q32_t at, q32_t ar);
void motion_set_jog_timeout_ms(motion_t *m, uint32_t ms);
/* Jerk (mm/s^3, deg/s^3, Q32; 0 = unlimited). A piece already under way
 * keeps the profile it was planned with. */
void motion_set_jerk(motion_t *m, q32_t jt, q32_t jr);
/* Caution speed cap (obstacle-warning input); 0 removes it. */
void motion_set_caution(motion_t *m, q32_t vt_cap);

/* Redefine the reference pose (setPosition). */
void motion_set_pose(motion_t *m, const fx_pose_t *p);

/* Path commands. Each returns false, changing nothing, when the queue is
 * full or the geometry cannot be executed by this kinematics. Relative
 * commands are resolved against the reference pose at the call. */
bool motion_forward(motion_t *m, q32_t dist_mm);
bool motion_turn(motion_t *m, q32_t angle_deg);
bool motion_linear_rel(motion_t *m, const fx_pose_t *rel);
bool motion_linear_abs(motion_t *m, const fx_pose_t *abs_pose);
bool motion_circular_rel(motion_t *m, q32_t cx_mm, q32_t cy_mm, q32_t angle_deg);
bool motion_cruise_abs(motion_t *m, q32_t x_mm, q32_t y_mm);
/* Spread the corner-speed planning of the queue over calls: each request
 * walks at most n queued commands beyond the ones its change touches (0:
 * all, the default), and motion_plan_idle walks n more of what is left
 * (true: it had some). For a platform whose requests run between two ticks
 * (the Cortex-M board): a pass over a full queue costs it about a period. */
void motion_set_plan_budget(motion_t *m, uint8_t n);
bool motion_plan_idle(motion_t *m);

/* Velocity and goal modes. These take over from jog/continuous/joystick
 * with continuous velocity; they are refused (false) while queued path
 * motion runs. Continuous: the newest goal wins; velocity stays continuous,
 * so a goal nearer than the stopping distance is passed and then reached
 * by backing along the line (a differential base drives toward a goal that
 * lies behind it in reverse rather than turning round). */
bool motion_continuous_rel(motion_t *m, const fx_pose_t *rel);
/* Body-frame velocity per second, Q32. All zero: decelerate to a stop. */
bool motion_jog(motion_t *m, q32_t vx, q32_t vy, q32_t w);
/* Joystick: enable/disable, and the input each tick (Q15 of full scale). */
void motion_joystick_enable(motion_t *m, bool on);
void motion_joystick_input(motion_t *m, int16_t x, int16_t y, int16_t r, bool present);

/* pause: decelerate at the acceleration limit, keep all work; resume
 * continues it. stop: decelerate at the acceleration limit along the path
 * (through queued corners if it must) and discard the work queued so far
 * once at rest; commands queued while it brakes run after. halt: zero
 * velocity at once and discard everything (servo is off or power is gone;
 * nothing to decelerate). */
void motion_pause(motion_t *m);
void motion_resume(motion_t *m);
void motion_stop(motion_t *m);
void motion_halt(motion_t *m);

/* Advance one tick. measured: odometry pose (followed while idle). */
void motion_tick(motion_t *m, const fx_pose_t *measured, fx_twist_t *out);

/* Queries. */
bool motion_is_moving(const motion_t *m); /* velocity not zero */
bool motion_has_work(const motion_t *m);  /* moving, or anything pending */
/* Motion a host commanded that is still under way by its command: path
 * commands queued or running (not those a stop brakes through), a jog
 * within its timeout with a target, a continuous goal; not a stop, a jog's
 * own timeout braking, the joystick. What the link watchdog guards. */
bool motion_host_work(const motion_t *m);
/* The translation speed in force (set velocity or caution cap), per tick. */
q32_t motion_speed_cap(const motion_t *m);
/* The set translation acceleration, per tick^2. */
static inline q32_t motion_accel_set(const motion_t *m)
{
	return m->a_t_pt2;
}
bool motion_is_paused(const motion_t *m);
uint8_t motion_queue_len(const motion_t *m);
uint8_t motion_mode(const motion_t *m);
static inline const fx_pose_t *motion_ref_pose(const motion_t *m)
{
	return &m->ref;
}

#endif
