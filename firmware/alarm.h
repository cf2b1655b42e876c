/* Alarms: stable numbered codes, each a fault or a warning, newest first.
 *
 * Codes 1xx are warnings (a refused command, a soft limit); they never
 * block motion. Codes 2xx are faults: motion stops, the servo goes off and
 * motion commands are refused until clearAlarm. The full table with its
 * meaning and recovery is docs/alarms.md; alarm.c holds the texts.
 */
#ifndef ALARM_H
#define ALARM_H

#include <stdbool.h>
#include <stdint.h>

#define VS_ALARM_SOURCE_MAX 64
#define VS_ALARM_LIST_MAX   16

typedef enum { VS_ALARM_UNKNOWN = 0, VS_ALARM_FAULT = 1, VS_ALARM_WARNING = 2 } vs_alarm_type_t;

typedef struct {
	uint32_t code;
	uint8_t type; /* vs_alarm_type_t */
	char source[VS_ALARM_SOURCE_MAX];
} vs_alarm_t;

/* Warning codes: why a command was refused, or a soft condition. */
enum {
	ALM_W_BAD_ARGUMENT = 110,    /* not finite, or out of range */
	ALM_W_OVER_LIMIT = 111,	     /* velocity/acceleration over the limit or <= 0 */
	ALM_W_KINEMATICS = 112,	     /* motion this base cannot make (y on differential) */
	ALM_W_NOT_READY = 120,	     /* Ready-only command while not idle with servo on */
	ALM_W_SERVO_OFF = 121,	     /* Servo-on command with servo off */
	ALM_W_MOVING = 122,	     /* refused while moving (setAcceleration, busy mode) */
	ALM_W_FAULT_ACTIVE = 123,    /* motion refused: a fault is active */
	ALM_W_LOCKED = 124,	     /* motion refused: contact lock */
	ALM_W_QUEUE_FULL = 125,	     /* motion queue full */
	ALM_W_BAD_IOID = 126,	     /* unknown or reserved io id */
	ALM_W_BAD_AXIS = 127,	     /* unknown axis id */
	ALM_W_POWER_OFF = 128,	     /* setServo with main power off */
	ALM_W_PAUSED = 129,	     /* jog refused while paused */
	ALM_W_STUCK = 130,	     /* motion refused: obstacle present */
	ALM_W_JOYSTICK = 131,	     /* motion refused: joystick in use */
	ALM_W_POSE_LOST = 132,	     /* motion refused: a drive lost its position */
	ALM_W_BATTERY_LOW = 140,     /* battery below the low threshold */
	ALM_W_CONTACT = 150,	     /* contact sensor tripped: unit Locked */
	ALM_W_OBSTACLE = 151,	     /* obstacle input tripped: unit Stuck */
	ALM_W_JOYSTICK_LOST = 152,   /* joystick lost while in use: stopped */
	ALM_W_LINK_LOST = 153,	     /* no request within link_timeout_ms: stopped */
	ALM_W_NOT_IN_POSITION = 154, /* not settled settle_timeout_ms after the reference */
	ALM_W_DRIVE_RESTARTED = 155, /* a drive restarted: its count starts over */
	ALM_W_CONFIG_STORE = 156,    /* the saved configuration unreadable: base in use */
	ALM_W_RESTARTED = 157,	     /* the board was reset by its watchdog or a fault */
};

/* Fault codes. */
enum {
	ALM_F_DRIVE = 201,	   /* a drive reported a fault */
	ALM_F_DRIVE_TIMEOUT = 202, /* a drive stopped answering */
	ALM_F_ENCODER_STUCK = 203, /* commanded motion, encoder does not move */
	ALM_F_FOLLOWING = 204,	   /* encoder runaway: measured departs from commanded */
	ALM_F_POWER_ON = 205,	   /* main relay did not close */
	ALM_F_POWER_LOST = 206,	   /* main power dropped while on */
	ALM_F_BATTERY_CRITICAL = 207,
	ALM_F_ESTOP = 208,
	ALM_F_OVERRUN = 209,	       /* the loop's own work took longer than a period */
	ALM_F_LOOP_STALL = 210,	       /* a tick came later than loop_late_ms */
	ALM_F_DRIVE_NOT_ENABLED = 211, /* servo on: a drive did not reach Operation enabled */
	ALM_F_DRIVE_DISABLED = 212,    /* an enabled drive left Operation enabled */
	ALM_F_DRIVE_MAP = 213,	       /* a drive rejects the registers the master uses */
};

typedef struct {
	vs_alarm_t a[VS_ALARM_LIST_MAX]; /* a[0] newest */
	uint8_t n;
} alarm_list_t;

void alarm_clear(alarm_list_t *l);
/* Raise an alarm; the oldest is dropped when full. source is copied
 * (truncated to fit). A code already active moves to the front. */
void alarm_raise(alarm_list_t *l, uint32_t code, const char *source);
vs_alarm_type_t alarm_type_of(uint32_t code);
bool alarm_any_fault(const alarm_list_t *l);
/* Newest active alarm of a type, or NULL. */
const vs_alarm_t *alarm_newest(const alarm_list_t *l, vs_alarm_type_t type);

#endif
