/* vehicle-fw's backend section of the vehicle file.
 *
 * The one reader of the file (hal/posix/config_xml.c) hands the elements of
 * <backends> to the handler here (config_load_sections), in the same pass
 * as the core configuration and with the same error style:
 *   "<file>:<line>: <element>.<attribute>: <what> '<value>'"
 *
 *   <vehicle ...>
 *     <backends>
 *       <drive axis="0" type="loopback"/>      one per axis; type: loopback | modbus | cia402
 *       <drive axis="1" type="modbus" bus="0" unit="2"/>
 *       <drive axis="2" type="cia402" bus="0" node="1" polarity="reverse"/>
 *       <canopen bus="0" interface="can0" heartbeat_ms="100" heartbeat_timeout_ms="300"
 *                sdo_timeout_ms="100" boot_timeout_ms="2000" master_node="127"
 *                profile_accel="100000" fault_reset_ms="200"/>
 *       <modbus bus="0" device="/dev/ttyUSB0" baud="115200" parity="N" stop_bits="1"
 *               timeout_ms="20" retries="1" reg_target_speed="0" reg_position="2"
 *               reg_status="4" reg_alarm="5" reg_servo_on="6" reg_fault_reset="7"
 *               reg_comm_timeout="9" comm_timeout_ms="200"/>
 *       <modbus bus="1" device="/dev/ttyUSB1" profile="zlac8015d" speed_scale="4096/60"/>
 *       <drive axis="0" type="modbus" bus="1" unit="1" channel="0"/>
 *       <power settle_ms="20"/>                relay settle time, 0..50
 *       <battery source="fixed" mv="24000"/>   source: fixed | iio (path, scale) | modbus
 *       <battery source="modbus" bus="0" unit="10" reg="512" reg_type="input" width="16"
 *                scale="10" period_ms="200"/>
 *       <line function="estop" chip="gpiochip0" line="3" active_low="true"/>
 *       <joystick device="/dev/input/event3" x="ABS_Y" x_invert="true"
 *                 rotation="ABS_X" rotation_invert="true" x_scale="1.0"/>
 *     </backends>
 *   </vehicle>
 *
 * line functions: contact, obstacle, obstacle_caution, estop (inputs), relay
 * (output), relay_feedback (input), servo_enable (output, with axis="N").
 * A function not given has no line: its input reads inactive; without a
 * relay line the relay is simulated (feedback follows the command); without
 * relay_feedback a relay line's feedback is its commanded state.
 *
 * modbus drive: Modbus RTU over libmodbus, one thread per bus (hal/linux/
 * modbus_drive.h for the semantics). profile: a built-in drive profile
 * (hal/modbus/mbprofile.h: generic, the default, or zlac8015d); any of its
 * fields may be given as an attribute in the profile's text form (speed,
 * position, ..., speed_scale, status_mask, enable_on, ...). The generic
 * profile takes its addresses from reg_target_speed, reg_position,
 * reg_status, reg_alarm, reg_servo_on, reg_fault_reset (each required
 * unless its register is given in text form) and reg_comm_timeout
 * (optional). comm_timeout_ms 10..60000 (default 200) is written to the
 * drives' comm_timeout register at start; a profile without one needs
 * comm_stop="none", which says the drives keep their last speed when the
 * bus falls silent. byte_timeout_ms 1..1000: the longest gap inside a
 * reply (default: 4 characters at the baud rate, at least 5 ms). drive
 * channel: the motor of a multi-channel unit (0..channels-1, default 0);
 * unit and channel once per bus.
 *
 * modbus battery: bus (a <modbus> element, which still needs its reg_*),
 * unit, reg required; reg_type holding (default) | input; width 16
 * (default, unsigned) | 32 (unsigned, high word first); scale mV per count
 * (default 1); period_ms 10..1000 (default 200). Failure handling in
 * modbus_drive.h.
 *
 * cia402 drive: CANopen CiA 402 over SocketCAN, profile velocity mode
 * (hal/linux/cia402.h). <canopen>: interface (required), heartbeat_ms the
 * drives' heartbeat period 1..10000 (default 100), heartbeat_timeout_ms
 * above heartbeat_ms, up to 60000 (default 300), sdo_timeout_ms 1..10000
 * (100), boot_timeout_ms 1..60000 (2000), master_node 1..127 (optional: the
 * vehicle computer then sends its heartbeat on 0x700+master_node and each
 * drive stops itself when it misses it for heartbeat_timeout_ms),
 * profile_accel counts/s^2 (optional, written to 0x6083 and 0x6084),
 * fault_reset_ms 10..10000 (200: how long the fault reset bit is held while
 * the drive stays in fault). node 1..127, unique on its bus and not the
 * master_node.
 *
 * drive polarity (modbus, cia402): normal (default) | reverse, for a motor
 * mounted mirrored: the master negates the velocity setpoint and the
 * position it reads (it never writes the drive's polarity object). One
 * <drive> per axis: a second one for the same axis is an error.
 *
 * joystick: an evdev device (libevdev). x, y, rotation name the absolute
 * axes (ABS_*; y may be omitted); each axis's range maps to +-32767 (full
 * velocity limit), times its *_scale (0..1), sign flipped by *_invert. The
 * firmware applies <devices joystick_deadband>. Without <joystick> the
 * joystick reads absent.
 *
 * loopback drive: an ideal drive in software (position integrates the
 * velocity setpoint), for bench runs of the Linux build without hardware.
 * An axis without <drive> defaults to loopback.
 */
#ifndef HAL_LINUX_BACKEND_CFG_H
#define HAL_LINUX_BACKEND_CFG_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "../../firmware/config.h"
#include "../modbus/mbprofile.h"
#include "../posix/config_xml.h"

enum { BK_DRIVE_LOOPBACK = 0, BK_DRIVE_MODBUS = 1, BK_DRIVE_CIA402 = 2 };
#define BK_MODBUS_BUSES	 2
#define BK_CANOPEN_BUSES 2 /* as many as Modbus buses: one drive.bus range */

typedef struct {
	bool used;
	char device[128];
	uint32_t baud;
	char parity; /* 'N', 'E', 'O' */
	uint32_t stop_bits;
	uint32_t timeout_ms;	  /* per request: the wait for a reply's first byte */
	uint32_t byte_timeout_ms; /* between two bytes of a reply; 0: from the baud rate */
	uint32_t retries;	  /* further attempts after the first */
	mb_profile_t prof;	  /* the drives' registers (generic unless named) */
	uint32_t comm_timeout_ms; /* written to the drives' comm_timeout register */
	bool comm_stop_none;	  /* comm_stop="none": the drives have no such stop */
} bk_modbus_bus_t;

typedef struct {
	bool used;
	char interface[16];	       /* IFNAMSIZ */
	uint32_t heartbeat_ms;	       /* drives' heartbeat producer time (0x1017) */
	uint32_t heartbeat_timeout_ms; /* no heartbeat this long: the drive is lost */
	uint32_t sdo_timeout_ms;       /* per SDO request (start-up, configuration) */
	uint32_t boot_timeout_ms;      /* boot-up after reset communication */
	uint32_t master_node;	       /* 0: no master heartbeat */
	uint32_t profile_accel;	       /* 0: not written */
	uint32_t fault_reset_ms;       /* longest hold of the fault reset bit */
} bk_canopen_bus_t;

enum { BK_BATTERY_FIXED = 0, BK_BATTERY_IIO = 1, BK_BATTERY_MODBUS = 2 };

/* Battery voltage from a register of a unit on a Modbus bus (a drive's unit
 * or a BMS of its own), read by that bus's thread every period_ms. */
typedef struct {
	uint8_t bus;
	uint8_t unit;	    /* 1..247 */
	uint16_t reg;	    /* address 0..65535 */
	bool input;	    /* input register (function 04); else holding (03) */
	uint8_t words;	    /* 1: uint16; 2: uint32 in two registers, high word first */
	uint32_t period_ms; /* 10..1000, default 200 */
} bk_battery_modbus_t;

enum {
	BK_LINE_CONTACT = 0,
	BK_LINE_OBSTACLE,
	BK_LINE_CAUTION,
	BK_LINE_ESTOP,
	BK_LINE_RELAY,
	BK_LINE_RELAY_FB,
	BK_LINE_SERVO0, /* servo_enable of axis 0; axis i at BK_LINE_SERVO0 + i */
	BK_LINE_COUNT = BK_LINE_SERVO0 + VS_MAX_AXES,
};

typedef struct {
	bool used;
	bool active_low;
	uint32_t line;
	char chip[HAL_IO_CHIP_MAX];
} bk_line_t;

typedef struct {
	bool used;
	char device[256];
	int code[3]; /* ABS_* of x, y, rotation; -1: none */
	bool invert[3];
	double scale[3];
} bk_joystick_t;

typedef struct {
	uint8_t drive_type[VS_MAX_AXES];
	uint8_t drive_bus[VS_MAX_AXES];	    /* modbus, cia402: bus index */
	uint8_t drive_unit[VS_MAX_AXES];    /* modbus: unit id 1..247 */
	uint8_t drive_channel[VS_MAX_AXES]; /* modbus: motor of a multi-channel unit */
	uint8_t drive_node[VS_MAX_AXES];    /* cia402: node id 1..127 */
	/* modbus, cia402: the motor is mounted mirrored; the master negates
	 * setpoint and position (the drive's own polarity is left alone) */
	bool drive_reverse[VS_MAX_AXES];
	bk_modbus_bus_t bus[BK_MODBUS_BUSES];
	bk_canopen_bus_t canopen[BK_CANOPEN_BUSES];
	uint32_t settle_ms;
	uint8_t battery_source;
	uint32_t battery_mv;	/* fixed */
	char battery_path[256]; /* iio: a sysfs *_raw file */
	double battery_scale;	/* iio, modbus: mV per raw count */
	bk_battery_modbus_t battery_mb;
	bk_line_t lines[BK_LINE_COUNT];
	bk_joystick_t joystick;
} backend_cfg_t;

void backend_cfg_defaults(backend_cfg_t *b);
/* config_load (vehicle file and io.xml into cfg and io_map) and <backends>
 * into b (absent: defaults), in one pass over the vehicle file. -1 with one
 * line in err on error: the core configuration's first, as config_load
 * reports it, then the backends'. */
int backend_cfg_load_all(const char *vehicle_path, const char *io_path, vs_config_t *cfg,
			 hal_io_map_t *io_map, backend_cfg_t *b, char *err, size_t errlen);
/* <backends> alone (the rest of the file is not judged). */
int backend_cfg_load(const char *path, backend_cfg_t *b, char *err, size_t errlen);
/* Name of a line function, for messages. */
const char *backend_line_name(unsigned fn);

#endif
