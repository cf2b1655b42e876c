/* vehicle-fw on the host: the <backends> section, and the program itself
 * with loopback drives, its serial link on a pty driven by the client
 * library, and SIGTERM mid-move. */
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <setjmp.h>
#include <signal.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <cmocka.h>

#include "fw_rig.h"

#include "../hal/posix/config_xml.h"
#include "../hal/linux/backend_cfg.h"
#include "../hal/linux/joystick.h"
#include <linux/input.h>
#include "../proto/client/client.h"
#include "../proto/frame.h"

#define VEHICLE_HEAD                                                                               \
	"<vehicle kinematics=\"differential\" tick_hz=\"100\">\n"                                  \
	"  <devices contact_sensor=\"false\" obstacle_input=\"false\" estop=\"false\"\n"           \
	"           joystick=\"false\"/>\n"

/* ---- <backends> ------------------------------------------------------ */

static void test_backends_parsed(void **state)
{
	(void)state;
	fw_write_file(
	    FW_VPATH, VEHICLE_HEAD
	    "  <backends>\n"
	    "    <drive axis=\"1\" type=\"loopback\"/>\n"
	    "    <power settle_ms=\"35\"/>\n"
	    "    <battery source=\"iio\" path=\"/sys/x/in_voltage0_raw\" scale=\"12.5\"/>\n"
	    "    <line function=\"estop\" chip=\"gpiochip1\" line=\"3\" active_low=\"true\"/>\n"
	    "    <line function=\"servo_enable\" axis=\"1\" chip=\"vs-testchip\" line=\"9\"/>\n"
	    "  </backends>\n"
	    "</vehicle>\n");
	backend_cfg_t b;
	char err[256] = "";
	assert_int_equal(backend_cfg_load(FW_VPATH, &b, err, sizeof(err)), 0);
	assert_int_equal(b.drive_type[1], BK_DRIVE_LOOPBACK);
	assert_int_equal(b.settle_ms, 35);
	assert_int_equal(b.battery_source, BK_BATTERY_IIO);
	assert_string_equal(b.battery_path, "/sys/x/in_voltage0_raw");
	assert_true(b.battery_scale == 12.5);
	assert_true(b.lines[BK_LINE_ESTOP].used);
	assert_true(b.lines[BK_LINE_ESTOP].active_low);
	assert_int_equal(b.lines[BK_LINE_ESTOP].line, 3);
	assert_string_equal(b.lines[BK_LINE_ESTOP].chip, "gpiochip1");
	assert_true(b.lines[BK_LINE_SERVO0 + 1].used);
	assert_false(b.lines[BK_LINE_SERVO0 + 1].active_low);
	assert_int_equal(b.lines[BK_LINE_SERVO0 + 1].line, 9);
	assert_false(b.lines[BK_LINE_SERVO0].used);
	assert_false(b.lines[BK_LINE_RELAY].used);
	assert_false(b.bus[0].used);

	/* A Modbus bus and its drive. */
	fw_write_file(
	    FW_VPATH, VEHICLE_HEAD
	    "  <backends>\n"
	    "    <modbus bus=\"1\" device=\"/dev/ttyUSB0\" baud=\"57600\" parity=\"E\"\n"
	    "            stop_bits=\"2\" timeout_ms=\"25\" retries=\"3\" reg_target_speed=\"16\"\n"
	    "            reg_position=\"18\" reg_status=\"20\" reg_alarm=\"21\"\n"
	    "            reg_servo_on=\"40\" reg_fault_reset=\"41\" reg_comm_timeout=\"42\"\n"
	    "            comm_timeout_ms=\"150\"/>\n"
	    "    <drive axis=\"0\" type=\"modbus\" bus=\"1\" unit=\"7\"/>\n"
	    "  </backends>\n"
	    "</vehicle>\n");
	assert_int_equal(backend_cfg_load(FW_VPATH, &b, err, sizeof(err)), 0);
	assert_int_equal(b.drive_type[0], BK_DRIVE_MODBUS);
	assert_int_equal(b.drive_bus[0], 1);
	assert_int_equal(b.drive_unit[0], 7);
	assert_true(b.bus[1].used);
	assert_string_equal(b.bus[1].device, "/dev/ttyUSB0");
	assert_int_equal(b.bus[1].baud, 57600);
	assert_int_equal(b.bus[1].parity, 'E');
	assert_int_equal(b.bus[1].stop_bits, 2);
	assert_int_equal(b.bus[1].timeout_ms, 25);
	assert_int_equal(b.bus[1].retries, 3);
	/* today's attributes: the generic profile at these addresses */
	const mb_profile_t *p = &b.bus[1].prof;
	assert_string_equal(p->name, "generic");
	assert_int_equal(p->reg[MBP_SPEED].addr, 16);
	assert_int_equal(p->reg[MBP_SPEED].words, 2);
	assert_int_equal(p->reg[MBP_POSITION].addr, 18);
	assert_int_equal(p->reg[MBP_STATUS].addr, 20);
	assert_int_equal(p->reg[MBP_ALARM].addr, 21);
	assert_int_equal(p->reg[MBP_ENABLE].addr, 40);
	assert_int_equal(p->reg[MBP_RESET].addr, 41);
	assert_int_equal(p->reg[MBP_COMM_TIMEOUT].addr, 42);
	assert_int_equal(p->reg[MBP_COMM_TIMEOUT].words, 1);
	assert_int_equal(b.bus[1].comm_timeout_ms, 150);
	assert_false(b.bus[1].comm_stop_none);
	assert_int_equal(b.bus[1].byte_timeout_ms, 0);
	assert_int_equal(b.drive_channel[0], 0);
	assert_int_equal(b.drive_type[1], BK_DRIVE_LOOPBACK);

	/* A named profile with fields changed, two channels of one unit, no
	 * communication-loss stop acknowledged. */
	fw_write_file(FW_VPATH, VEHICLE_HEAD
		      "  <backends>\n"
		      "    <modbus bus=\"0\" device=\"/dev/ttyUSB0\" speed_scale=\"16384/600\"\n"
		      "            position=\"0x3000+2 s32 lo input\" profile=\"zlac8015d\"\n"
		      "            comm_stop=\"none\" byte_timeout_ms=\"3\"/>\n"
		      "    <drive axis=\"0\" type=\"modbus\" bus=\"0\" unit=\"4\"/>\n"
		      "    <drive axis=\"1\" type=\"modbus\" bus=\"0\" unit=\"4\" channel=\"1\"\n"
		      "           polarity=\"reverse\"/>\n"
		      "  </backends>\n</vehicle>\n");
	assert_int_equal(backend_cfg_load(FW_VPATH, &b, err, sizeof(err)), 0);
	p = &b.bus[0].prof;
	assert_string_equal(p->name, "zlac8015d");
	assert_int_equal(p->speed_num, 16384);
	assert_int_equal(p->speed_den, 600);
	assert_int_equal(p->reg[MBP_POSITION].addr, 0x3000);
	assert_int_equal(p->reg[MBP_POSITION].flags, MBP_SIGNED | MBP_LOW_FIRST | MBP_INPUT);
	assert_int_equal(p->reg[MBP_SPEED].addr, 0x2088);
	assert_true(b.bus[0].comm_stop_none);
	assert_int_equal(b.bus[0].byte_timeout_ms, 3);
	assert_int_equal(b.drive_unit[1], 4);
	assert_int_equal(b.drive_channel[1], 1);
	assert_true(b.drive_reverse[1]);

	/* The battery from a Modbus register: every attribute, then the
	 * defaults (holding register, 16 bits, 1 mV per count, 200 ms). */
	static const char mb_bus1[] =
	    "    <modbus bus=\"1\" device=\"/dev/ttyUSB1\" reg_target_speed=\"0\"\n"
	    "            reg_position=\"2\" reg_status=\"4\" reg_alarm=\"5\" reg_servo_on=\"6\"\n"
	    "            reg_fault_reset=\"7\"/>\n";
	char text[1024];
	snprintf(text, sizeof(text),
		 VEHICLE_HEAD
		 "  <backends>\n"
		 "    <battery source=\"modbus\" bus=\"1\" unit=\"10\" reg=\"513\"\n"
		 "             reg_type=\"input\" width=\"32\" scale=\"0.5\" period_ms=\"50\"/>\n"
		 "%s  </backends>\n</vehicle>\n",
		 mb_bus1);
	fw_write_file(FW_VPATH, text);
	assert_int_equal(backend_cfg_load(FW_VPATH, &b, err, sizeof(err)), 0);
	assert_int_equal(b.battery_source, BK_BATTERY_MODBUS);
	assert_int_equal(b.battery_mb.bus, 1);
	assert_int_equal(b.battery_mb.unit, 10);
	assert_int_equal(b.battery_mb.reg, 513);
	assert_true(b.battery_mb.input);
	assert_int_equal(b.battery_mb.words, 2);
	assert_true(b.battery_scale == 0.5);
	assert_int_equal(b.battery_mb.period_ms, 50);
	snprintf(text, sizeof(text),
		 VEHICLE_HEAD "  <backends>\n%s"
			      "    <battery source=\"modbus\" bus=\"1\" unit=\"3\" reg=\"264\"/>\n"
			      "  </backends>\n</vehicle>\n",
		 mb_bus1);
	fw_write_file(FW_VPATH, text);
	assert_int_equal(backend_cfg_load(FW_VPATH, &b, err, sizeof(err)), 0);
	assert_int_equal(b.battery_source, BK_BATTERY_MODBUS);
	assert_int_equal(b.battery_mb.unit, 3);
	assert_int_equal(b.battery_mb.reg, 264);
	assert_false(b.battery_mb.input);
	assert_int_equal(b.battery_mb.words, 1);
	assert_true(b.battery_scale == 1.0);
	assert_int_equal(b.battery_mb.period_ms, 200);

	/* CANopen buses and their CiA 402 drives: given and default attributes. */
	fw_write_file(FW_VPATH, VEHICLE_HEAD
		      "  <backends>\n"
		      "    <canopen bus=\"1\" interface=\"can1\" heartbeat_ms=\"50\"\n"
		      "             heartbeat_timeout_ms=\"175\" sdo_timeout_ms=\"30\"\n"
		      "             boot_timeout_ms=\"5000\" master_node=\"127\" "
		      "profile_accel=\"400000\"/>\n"
		      "    <canopen bus=\"0\" interface=\"vcan0\"/>\n"
		      "    <drive axis=\"0\" type=\"cia402\" bus=\"1\" node=\"3\"/>\n"
		      "    <drive axis=\"1\" type=\"cia402\" bus=\"0\" node=\"3\"/>\n"
		      "    <drive axis=\"2\" type=\"cia402\" bus=\"1\" node=\"126\"/>\n"
		      "  </backends>\n"
		      "</vehicle>\n");
	assert_int_equal(backend_cfg_load(FW_VPATH, &b, err, sizeof(err)), 0);
	assert_int_equal(b.drive_type[0], BK_DRIVE_CIA402);
	assert_int_equal(b.drive_bus[0], 1);
	assert_int_equal(b.drive_node[0], 3);
	assert_int_equal(b.drive_type[1], BK_DRIVE_CIA402);
	assert_int_equal(b.drive_bus[1], 0);
	assert_int_equal(b.drive_node[1], 3);
	assert_int_equal(b.drive_node[2], 126);
	assert_int_equal(b.drive_type[3], BK_DRIVE_LOOPBACK);
	assert_true(b.canopen[1].used);
	assert_string_equal(b.canopen[1].interface, "can1");
	assert_int_equal(b.canopen[1].heartbeat_ms, 50);
	assert_int_equal(b.canopen[1].heartbeat_timeout_ms, 175);
	assert_int_equal(b.canopen[1].sdo_timeout_ms, 30);
	assert_int_equal(b.canopen[1].boot_timeout_ms, 5000);
	assert_int_equal(b.canopen[1].master_node, 127);
	assert_int_equal(b.canopen[1].profile_accel, 400000);
	assert_true(b.canopen[0].used);
	assert_string_equal(b.canopen[0].interface, "vcan0");
	assert_int_equal(b.canopen[0].heartbeat_ms, 100);
	assert_int_equal(b.canopen[0].heartbeat_timeout_ms, 300);
	assert_int_equal(b.canopen[0].sdo_timeout_ms, 100);
	assert_int_equal(b.canopen[0].boot_timeout_ms, 2000);
	assert_int_equal(b.canopen[0].master_node, 0);
	assert_int_equal(b.canopen[0].profile_accel, 0);
	assert_false(b.bus[0].used);

	/* The core loader skips the section and still reads the rest. */
	vs_config_t cfg;
	assert_int_equal(config_load(FW_VPATH, NULL, &cfg, NULL, err, sizeof(err)), 0);
	assert_int_equal(cfg.tick_hz, 100);
	assert_false(cfg.has_estop);
}

static void test_backends_defaults(void **state)
{
	(void)state;
	fw_write_file(FW_VPATH, VEHICLE_HEAD "</vehicle>\n");
	backend_cfg_t b;
	char err[256] = "";
	assert_int_equal(backend_cfg_load(FW_VPATH, &b, err, sizeof(err)), 0);
	assert_int_equal(b.drive_type[0], BK_DRIVE_LOOPBACK);
	assert_int_equal(b.settle_ms, 20);
	assert_int_equal(b.battery_source, BK_BATTERY_FIXED);
	assert_int_equal(b.battery_mv, 24000);
	for (unsigned i = 0; i < BK_LINE_COUNT; i++)
		assert_false(b.lines[i].used);
}

/* Each bad section: the exact message, with file and line. */
static void test_backends_errors(void **state)
{
	(void)state;
	static const struct {
		const char *body, *msg;
	} cases[] = {
	    {"<drive axis=\"0\" type=\"stepper\"/>", "drive.type: unknown backend 'stepper'"},
	    {"<drive axis=\"4\" type=\"loopback\"/>", "drive.axis: out of range 0..3 '4'"},
	    {"<drive type=\"loopback\"/>", "drive.axis: required"},
	    {"<power settle_ms=\"51\"/>", "power.settle_ms: out of range 0..50 '51'"},
	    {"<power settle_ms=\"2x\"/>", "power.settle_ms: not a number '2x'"},
	    {"<battery source=\"iio\"/>", "battery.path: required with source iio"},
	    {"<battery scale=\"nan\"/>", "battery.scale: not finite 'nan'"},
	    {"<battery scale=\"0x10\"/>", "battery.scale: not a number '0x10'"},
	    {"<battery scale=\"0\"/>", "battery.scale: out of range (0, 1e6] '0'"},
	    {"<joystick x_scale=\" 0.5\"/>", "joystick.x_scale: not a number ' 0.5'"},
	    {"<line function=\"horn\" chip=\"c\" line=\"1\"/>",
	     "line.function: unknown function 'horn'"},
	    {"<line function=\"estop\" line=\"1\"/>", "line.chip: required"},
	    {"<line function=\"estop\" chip=\"c\" line=\"1\" active_low=\"yes\"/>",
	     "line.active_low: not a boolean 'yes'"},
	    {"<line function=\"servo_enable\" chip=\"c\" line=\"1\"/>",
	     "line.axis: required for servo_enable"},
	    {"<line function=\"relay\" chip=\"c\" line=\"1\" axis=\"0\"/>",
	     "line.axis: only for servo_enable"},
	    {"<line function=\"relay\" chip=\"c\" line=\"1\"/><line function=\"relay\" chip=\"c\" "
	     "line=\"2\"/>",
	     "line.function: duplicate 'relay'"},
	    {"<drive axis=\"0\" type=\"loopback\" speed=\"1\"/>", "drive.speed: unknown attribute"},
	    {"<relay/>", "relay: unknown element"},
	    {"<joystick device=\"/dev/input/event0\" x=\"ABS_FOO\" rotation=\"ABS_X\"/>",
	     "joystick.x: not an ABS_ axis 'ABS_FOO'"},
	    {"<joystick device=\"/dev/input/event0\" x=\"ABS_X\"/>", "joystick.rotation: required"},
	    {"<joystick x=\"ABS_X\" rotation=\"ABS_RX\"/>", "joystick.device: required"},
	    {"<joystick device=\"/dev/input/event0\" x=\"ABS_X\" rotation=\"ABS_RX\" "
	     "x_scale=\"1.5\"/>",
	     "joystick.x_scale: out of range 0..1 '1.5'"},
	    {"<joystick device=\"/dev/input/event0\" x=\"ABS_X\" rotation=\"ABS_RX\" "
	     "y_invert=\"maybe\"/>",
	     "joystick.y_invert: not a boolean 'maybe'"},
	    {"<drive axis=\"0\" type=\"modbus\" unit=\"1\"/>", "drive.bus: required for modbus"},
	    {"<drive axis=\"0\" type=\"modbus\" bus=\"0\" unit=\"248\"/>",
	     "drive.unit: out of range 1..247 '248'"},
	    {"<drive axis=\"0\" type=\"loopback\" unit=\"1\"/>", "drive.unit: only for modbus"},
	    {"<drive axis=\"0\" type=\"modbus\" bus=\"1\" unit=\"1\"/>",
	     "drive.bus: no <modbus bus=\"1\"> for axis 0"},
	    {"<modbus bus=\"0\" device=\"/dev/ttyUSB0\"/>", "modbus.reg_target_speed: required"},
	    {"<modbus bus=\"0\" device=\"/dev/ttyUSB0\" profile=\"zlac\"/>",
	     "modbus.profile: unknown profile (generic, zlac8015d) 'zlac'"},
	    {"<modbus bus=\"0\" device=\"/dev/ttyUSB0\" profile=\"zlac8015d\" speed=\"1 s8\"/>",
	     "modbus.speed: not a register: ADDR[+STEP] u16|s16|u32|s32 [hi|lo] [holding|input], "
	     "or none '1 s8'"},
	    {"<modbus bus=\"0\" device=\"/dev/ttyUSB0\" profile=\"zlac8015d\" status=\"none\"/>",
	     "modbus.profile: speed, position, status and enable are required 'zlac8015d'"},
	    {"<modbus bus=\"0\" device=\"/dev/ttyUSB0\" profile=\"zlac8015d\" comm_stop=\"x\"/>",
	     "modbus.comm_stop: drive or none 'x'"},
	    {"<modbus bus=\"0\" device=\"/dev/ttyUSB0\" profile=\"zlac8015d\" "
	     "comm_timeout_ms=\"5\"/>",
	     "modbus.comm_timeout_ms: out of range 10..60000 '5'"},
	    {"<modbus bus=\"0\" device=\"/dev/ttyUSB0\" profile=\"zlac8015d\"/>"
	     "<drive axis=\"0\" type=\"modbus\" bus=\"0\" unit=\"1\" channel=\"2\"/>",
	     "drive.channel: out of range 0..1 '2'"},
	    {"<modbus bus=\"0\" device=\"/dev/ttyUSB0\" profile=\"zlac8015d\"/>"
	     "<drive axis=\"0\" type=\"modbus\" bus=\"0\" unit=\"1\" channel=\"1\"/>"
	     "<drive axis=\"1\" type=\"modbus\" bus=\"0\" unit=\"1\" channel=\"1\"/>",
	     "drive.unit: also axis 0's unit and channel on modbus bus 0 '1'"},
	    {"<modbus bus=\"0\" device=\"/dev/ttyUSB0\" reg_target_speed=\"0\" reg_position=\"2\" "
	     "reg_status=\"4\" reg_alarm=\"5\" reg_servo_on=\"6\" reg_fault_reset=\"7\" "
	     "comm_stop=\"none\"/><drive axis=\"0\" type=\"modbus\" bus=\"0\" unit=\"1\" "
	     "channel=\"1\"/>",
	     "drive.channel: profile generic has 1 channel '1'"},
	    {"<modbus bus=\"0\" device=\"/dev/ttyUSB0\" reg_target_speed=\"0\" reg_position=\"2\" "
	     "reg_status=\"4\" reg_alarm=\"5\" reg_servo_on=\"6\" reg_fault_reset=\"7\"/>"
	     "<drive axis=\"0\" type=\"modbus\" bus=\"0\" unit=\"1\"/>",
	     "modbus.comm_stop: profile generic has no comm_timeout register: give "
	     "reg_comm_timeout, or comm_stop=\"none\" for drives that run on when the bus falls "
	     "silent 'drive'"},
	    {"<drive axis=\"0\" type=\"loopback\" channel=\"0\"/>",
	     "drive.channel: only for modbus"},
	    {"<modbus bus=\"0\" device=\"/dev/ttyUSB0\" parity=\"X\"/>",
	     "modbus.parity: N, E or O 'X'"},
	    {"<modbus bus=\"0\" device=\"ttyUSB0\"/>",
	     "modbus.device: not a device path 'ttyUSB0'"},
	    {"<modbus bus=\"0\" device=\"/dev/ttyUSB0\" timeout_ms=\"0\"/>",
	     "modbus.timeout_ms: out of range 1..1000 '0'"},
	    {"<battery source=\"modbus\" unit=\"1\" reg=\"5\"/>",
	     "battery.bus: required with source modbus"},
	    {"<battery source=\"modbus\" bus=\"0\" reg=\"5\"/>",
	     "battery.unit: required with source modbus"},
	    {"<battery bus=\"0\" unit=\"1\" source=\"modbus\"/>",
	     "battery.reg: required with source modbus"},
	    {"<battery source=\"modbus\" bus=\"0\" unit=\"0\" reg=\"5\"/>",
	     "battery.unit: out of range 1..247 '0'"},
	    {"<battery source=\"modbus\" bus=\"0\" unit=\"1\" reg=\"65536\"/>",
	     "battery.reg: out of range 0..65535 '65536'"},
	    {"<battery source=\"modbus\" bus=\"0\" unit=\"1\" reg=\"5\" reg_type=\"coil\"/>",
	     "battery.reg_type: holding or input 'coil'"},
	    {"<battery source=\"modbus\" bus=\"0\" unit=\"1\" reg=\"5\" width=\"8\"/>",
	     "battery.width: 16 or 32 '8'"},
	    {"<battery source=\"modbus\" bus=\"0\" unit=\"1\" reg=\"5\" period_ms=\"5\"/>",
	     "battery.period_ms: out of range 10..1000 '5'"},
	    {"<battery source=\"fixed\" mv=\"24000\" unit=\"3\"/>",
	     "battery.unit: only for source modbus"},
	    {"<battery source=\"modbus\" bus=\"1\" unit=\"1\" reg=\"5\"/>",
	     "battery.bus: no <modbus bus=\"1\"> for the battery"},
	    {"<drive axis=\"0\" type=\"cia402\" node=\"1\"/>", "drive.bus: required for cia402"},
	    {"<drive axis=\"0\" type=\"cia402\" bus=\"0\"/>", "drive.node: required for cia402"},
	    {"<drive axis=\"0\" type=\"cia402\" bus=\"0\" node=\"128\"/>",
	     "drive.node: out of range 1..127 '128'"},
	    {"<drive axis=\"0\" type=\"cia402\" bus=\"0\" node=\"0\"/>",
	     "drive.node: out of range 1..127 '0'"},
	    {"<drive axis=\"0\" type=\"cia402\" bus=\"2\" node=\"1\"/>",
	     "drive.bus: out of range 0..1 '2'"},
	    {"<drive axis=\"0\" type=\"modbus\" bus=\"0\" unit=\"1\" node=\"1\"/>",
	     "drive.node: only for cia402"},
	    {"<drive axis=\"0\" type=\"cia402\" bus=\"0\" node=\"1\" unit=\"1\"/>",
	     "drive.unit: only for modbus"},
	    {"<drive axis=\"0\" type=\"loopback\" bus=\"0\"/>",
	     "drive.bus: only for modbus and cia402"},
	    {"<drive axis=\"0\" type=\"cia402\" bus=\"1\" node=\"1\"/>",
	     "drive.bus: no <canopen bus=\"1\"> for axis 0"},
	    {"<canopen bus=\"0\"/>", "canopen.interface: required"},
	    {"<canopen interface=\"can0\"/>", "canopen.bus: required"},
	    {"<canopen bus=\"2\" interface=\"can0\"/>", "canopen.bus: out of range 0..1 '2'"},
	    {"<canopen bus=\"0\" interface=\"can0/x\"/>",
	     "canopen.interface: not an interface name 'can0/x'"},
	    {"<canopen bus=\"0\" interface=\"can0123456789abcd\"/>",
	     "canopen.interface: not an interface name 'can0123456789abcd'"},
	    {"<canopen bus=\"0\" interface=\"\"/>", "canopen.interface: not an interface name ''"},
	    {"<canopen bus=\"0\" interface=\"can0\" heartbeat_ms=\"100\" "
	     "heartbeat_timeout_ms=\"100\"/>",
	     "canopen.heartbeat_timeout_ms: not above heartbeat_ms '100'"},
	    {"<canopen bus=\"0\" interface=\"can0\" heartbeat_ms=\"400\"/>",
	     "canopen.heartbeat_timeout_ms: not above heartbeat_ms '300'"},
	    {"<canopen bus=\"0\" interface=\"can0\" heartbeat_ms=\"10001\"/>",
	     "canopen.heartbeat_ms: out of range 1..10000 '10001'"},
	    {"<canopen bus=\"0\" interface=\"can0\" sdo_timeout_ms=\"0\"/>",
	     "canopen.sdo_timeout_ms: out of range 1..10000 '0'"},
	    {"<canopen bus=\"0\" interface=\"can0\" boot_timeout_ms=\"x\"/>",
	     "canopen.boot_timeout_ms: not a number 'x'"},
	    {"<canopen bus=\"0\" interface=\"can0\" master_node=\"128\"/>",
	     "canopen.master_node: out of range 1..127 '128'"},
	    {"<canopen bus=\"0\" interface=\"can0\" profile_accel=\"0\"/>",
	     "canopen.profile_accel: out of range 1..2147483647 '0'"},
	    {"<canopen bus=\"0\" interface=\"can0\" baud=\"500000\"/>",
	     "canopen.baud: unknown attribute"},
	    {"<canopen bus=\"0\" interface=\"can0\"/><canopen bus=\"0\" interface=\"can1\"/>",
	     "canopen.bus: duplicate '0'"},
	    {"<canopen bus=\"0\" interface=\"can0\" master_node=\"1\"/>"
	     "<drive axis=\"0\" type=\"cia402\" bus=\"0\" node=\"1\"/>",
	     "drive.node: the master_node of canopen bus 0 '1'"},
	    {"<canopen bus=\"0\" interface=\"can0\"/><drive axis=\"0\" type=\"cia402\" "
	     "bus=\"0\" node=\"3\"/><drive axis=\"2\" type=\"cia402\" bus=\"0\" node=\"3\"/>",
	     "drive.node: also axis 0's node on canopen bus 0 '3'"},
	    {"<drive axis=\"0\" type=\"loopback\"><x/></drive>", "x: unknown element"},
	};
	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		char text[1024], want[1024], err[512] = "";
		backend_cfg_t b;
		snprintf(text, sizeof(text),
			 VEHICLE_HEAD "  <backends>\n%s\n  </backends>\n</vehicle>\n",
			 cases[i].body);
		fw_write_file(FW_VPATH, text);
		assert_int_equal(backend_cfg_load(FW_VPATH, &b, err, sizeof(err)), -1);
		snprintf(want, sizeof(want), "%s:5: %s", FW_VPATH, cases[i].msg);
		assert_string_equal(err, want);
	}

	/* A second section is the core loader's error. */
	fw_write_file(FW_VPATH, VEHICLE_HEAD "<backends/>\n<backends/>\n</vehicle>\n");
	vs_config_t cfg;
	char err[256], want[700];
	assert_int_equal(config_load(FW_VPATH, NULL, &cfg, NULL, err, sizeof(err)), -1);
	snprintf(want, sizeof(want), "%s:5: backends: duplicate element (first at line 4)",
		 FW_VPATH);
	assert_string_equal(err, want);
}

/* One pass over the file for both: the core configuration's error comes
 * first (as config_load then backend_cfg_load reported it), even after an
 * error of <backends> in the file; <backends> read alone reports its own. */
static void test_backends_one_pass(void **state)
{
	(void)state;
	static const char body[] = VEHICLE_HEAD "  <backends>\n"
						"    <power settle_ms=\"%s\"/>\n"
						"  </backends>\n"
						"  <limits vel_t_mm_s=\"%s\"/>\n"
						"</vehicle>\n";
	char text[1024], want[700], err[256];
	vs_config_t cfg;
	hal_io_map_t io;
	backend_cfg_t b;

	snprintf(text, sizeof(text), body, "51", "abc");
	fw_write_file(FW_VPATH, text);
	assert_int_equal(backend_cfg_load_all(FW_VPATH, NULL, &cfg, &io, &b, err, sizeof(err)), -1);
	snprintf(want, sizeof(want), "%s:7: limits.vel_t_mm_s: not a number 'abc'", FW_VPATH);
	assert_string_equal(err, want);
	assert_int_equal(backend_cfg_load(FW_VPATH, &b, err, sizeof(err)), -1);
	snprintf(want, sizeof(want), "%s:5: power.settle_ms: out of range 0..50 '51'", FW_VPATH);
	assert_string_equal(err, want);

	/* the core fine: the backends' error */
	snprintf(text, sizeof(text), body, "51", "900");
	fw_write_file(FW_VPATH, text);
	assert_int_equal(backend_cfg_load_all(FW_VPATH, NULL, &cfg, &io, &b, err, sizeof(err)), -1);
	assert_string_equal(err, want);

	/* both fine: both filled, io.xml too */
	snprintf(text, sizeof(text), body, "35", "900");
	fw_write_file(FW_VPATH, text);
	assert_int_equal(
	    backend_cfg_load_all(FW_VPATH, "config/io.xml", &cfg, &io, &b, err, sizeof(err)), 0);
	assert_string_equal(err, "");
	assert_int_equal(cfg.tick_hz, 100);
	assert_true(cfg.vel_limit_t_mm_s == 900.0);
	assert_int_equal(io.n, 8);
	assert_int_equal(b.settle_ms, 35);

	/* io.xml's error, like the rest of the core's, before the backends' */
	snprintf(text, sizeof(text), body, "51", "900");
	fw_write_file(FW_VPATH, text);
	assert_int_equal(backend_cfg_load_all(FW_VPATH, "tests/data/io_width.xml", &cfg, &io, &b,
					      err, sizeof(err)),
			 -1);
	assert_string_equal(err, "tests/data/io_width.xml:2: input.width: out of range '33' "
				 "(allowed 1..32)");
}

/* Joystick section and the axis scaling, from a device state set by hand
 * (the evdev path itself runs in the QEMU guest, tests/qemu/fw_joystick.sh). */
static void test_joystick_cfg_and_scaling(void **state)
{
	(void)state;
	fw_write_file(FW_VPATH, VEHICLE_HEAD
		      "  <backends>\n"
		      "    <joystick device=\"/dev/input/event7\" x=\"ABS_Y\" x_invert=\"true\"\n"
		      "              rotation=\"ABS_RX\" rotation_scale=\"0.5\"/>\n"
		      "  </backends>\n"
		      "</vehicle>\n");
	backend_cfg_t b;
	char err[256] = "";
	assert_int_equal(backend_cfg_load(FW_VPATH, &b, err, sizeof(err)), 0);
	assert_true(b.joystick.used);
	assert_string_equal(b.joystick.device, "/dev/input/event7");
	assert_int_equal(b.joystick.code[0], ABS_Y);
	assert_int_equal(b.joystick.code[1], -1);
	assert_int_equal(b.joystick.code[2], ABS_RX);
	assert_true(b.joystick.invert[0] && !b.joystick.invert[2]);
	assert_true(b.joystick.scale[2] == 0.5 && b.joystick.scale[0] == 1.0);

	/* 0..1023 device: ends to -+32767 (x inverted), rotation at half scale. */
	ljoy_t j;
	ljoy_init(&j, &b.joystick, 0); /* no such device: absent */
	hal_joystick_t js;
	ljoy_read(&j, &js);
	assert_false(js.present);
	j.present = true;
	for (int i = 0; i < 3; i++) {
		j.min[i] = 0;
		j.max[i] = 1023;
	}
	j.raw[0] = 1023;
	j.raw[2] = 0;
	ljoy_read(&j, &js);
	assert_true(js.present);
	assert_int_equal(js.axis[0], -32767);
	assert_int_equal(js.axis[1], 0);
	assert_int_equal(js.axis[2], -16383);
	j.raw[0] = 0;
	j.raw[2] = 1023;
	ljoy_read(&j, &js);
	assert_int_equal(js.axis[0], 32767);
	assert_int_equal(js.axis[2], 16383);
	/* 512 is half a count above centre (511.5): 32767 / 1023 = 32. */
	j.raw[0] = 512;
	ljoy_read(&j, &js);
	assert_int_equal(js.axis[0], -32);
	j.present = false;
	j.fd = -1;
	ljoy_close(&j);
}

/* The shipped example loads with both loaders. */
static void test_example_config(void **state)
{
	(void)state;
	backend_cfg_t b;
	vs_config_t cfg;
	hal_io_map_t io;
	char err[512] = "";
	assert_int_equal(
	    config_load("config/vehicle-linux.xml", "config/io.xml", &cfg, &io, err, sizeof(err)),
	    0);
	assert_int_equal(backend_cfg_load("config/vehicle-linux.xml", &b, err, sizeof(err)), 0);
	assert_int_equal(cfg.tick_hz, 1000);
	assert_true(b.lines[BK_LINE_RELAY].used && b.lines[BK_LINE_RELAY_FB].used);
	assert_true(b.lines[BK_LINE_ESTOP].active_low);
	assert_true(b.lines[BK_LINE_SERVO0].used && b.lines[BK_LINE_SERVO0 + 1].used);
}

/* ---- the program ----------------------------------------------------- */

static pid_t FW_PID = -1;
static int MASTER = -1;

static void console(const char *line, char *reply, size_t cap)
{
	fw_console(MASTER, line, reply, cap, 2000);
}

/* vehicle-fw on a new port; store: its --store file, or NULL. */
static void start_fw_store(const char *store)
{
	int slave;
	char exe[600];

	char port[256];
	MASTER = fw_open_port(&slave, port, sizeof(port));

	snprintf(exe, sizeof(exe), "%s/vehicle-fw", FW_BUILD_DIR);
	FW_PID = fork();
	assert_true(FW_PID >= 0);
	if (FW_PID == 0) {
		int fd = open(FW_LOGPATH, O_WRONLY | O_CREAT | O_TRUNC, 0644);
		dup2(fd, 2);
		if (store)
			execl(exe, exe, "--config", FW_VPATH, "--io", FW_IOPATH, "--port", port,
			      "--rt-priority", "0", "--store", store, (char *)NULL);
		else
			execl(exe, exe, "--config", FW_VPATH, "--io", FW_IOPATH, "--port", port,
			      "--rt-priority", "0", (char *)NULL);
		_exit(127);
	}
	close(slave); /* vehicle-fw opens the port by name */
}

static void start_fw(void)
{
	start_fw_store(NULL);
}

static int stop_fw(void)
{
	int status = 0;
	assert_int_equal(kill(FW_PID, SIGTERM), 0);
	assert_int_equal(waitpid(FW_PID, &status, 0), FW_PID);
	FW_PID = -1;
	assert_true(WIFEXITED(status));
	return WEXITSTATUS(status);
}

/* One console line on the raw link; the reply line without its newline. */
static void write_fw_config(void)
{
	fw_write_file(FW_VPATH, VEHICLE_HEAD "  <backends>\n"
					     "    <drive axis=\"0\" type=\"loopback\"/>\n"
					     "    <drive axis=\"1\" type=\"loopback\"/>\n"
					     "    <battery source=\"fixed\" mv=\"23500\"/>\n"
					     "  </backends>\n"
					     "</vehicle>\n");
	fw_write_file(FW_IOPATH, "<io>\n  <input id=\"1\" name=\"dock\"/>\n</io>\n");
}

static void test_fw_link_and_sigterm_mid_move(void **state)
{
	(void)state;
	char reply[512], log[8192];
	write_fw_config();
	start_fw();

	/* The console answers first (the program may still be starting). */
	fw_sleep_ms(200);
	/* The configured 23500 mV, in the interface's 0.1 V units. */
	console("getBatteryVoltage", reply, sizeof(reply));
	assert_string_equal(reply, "ok true 235.000");
	console("$rt", reply, sizeof(reply));
	assert_memory_equal(reply, "ok period_us 10000 ticks ", 25);
	assert_non_null(strstr(reply, " sched other prio 0 "));

	/* Binary frames on the same port, through the client library. */
	vc_client_t c;
	bool ret = false;
	assert_int_equal(vc_attach_serial_fd(&c, MASTER, false), VC_OK);
	assert_int_equal(vc_setPower(&c, &ret, true), VC_OK);
	assert_true(ret);
	assert_int_equal(vc_setServo(&c, &ret, true), VC_OK);
	assert_true(ret);
	/* 2 m at the default 500 mm/s: several seconds of motion. */
	assert_int_equal(vc_moveForward(&c, &ret, 2000.0), VC_OK);
	assert_true(ret);
	fw_sleep_ms(500);
	int16_t st = 0;
	char msg[VS_STATE_MSG_MAX];
	assert_int_equal(vc_getState(&c, &ret, &st, msg), VC_OK);
	if (st != VS_STATE_BUSY) {
		/* Say why (e.g. a tick overrun on an overloaded host). */
		int16_t na = 0;
		uint16_t len = 0;
		vs_alarm_t al[4];
		vc_getActiveAlarm(&c, &ret, 4, &na, al, &len);
		for (uint16_t i = 0; i < len; i++)
			print_message("active alarm %d\n", (int)al[i].code);
	}
	assert_int_equal(st, VS_STATE_BUSY);
	vs_position_t pos;
	assert_int_equal(vc_getPosition(&c, &ret, &pos), VC_OK);
	/* Loopback drives move the odometry: accelerating, not yet at 2 m. */
	assert_true(pos.x > 20.0 && pos.x < 1500.0);
	vc_close(&c);

	assert_int_equal(stop_fw(), 0);
	fw_read_log(log, sizeof(log));
	/* Decelerated (not cut), then servo off and power off. */
	assert_non_null(strstr(log, "vehicle-fw: signal: stopping the unit\n"));
	assert_non_null(strstr(log, "vehicle-fw: shutdown: stopped after "));
	assert_non_null(
	    strstr(log, "vehicle-fw: final state: unpowered, relay open, servo off, stopped\n"));
	assert_non_null(strstr(log, "vehicle-fw: exit: "));
	close(MASTER);
	MASTER = -1;
}

/* The serial link under a pipelined burst, as a host on a port of no speed
 * limit sends it: 2,000 getState frames written as fast as the port takes
 * them and not read for half a second, then read (the rest written
 * meanwhile). Every request gets exactly one whole answer, in order, none
 * dropped: the unit leaves what it cannot answer in the port, where a host
 * that only wrote would wait. Before that, a comment longer than a line
 * gets no reply. */
static void test_fw_pipelined_and_long_comment(void **state)
{
	enum { N = 2000, ANS = 21 }; /* true 25 "Unpowered" */
	static uint8_t req[N * FRAME_OVERHEAD], ans[N * ANS];
	char reply[512], comment[301], want[256];
	size_t len = 0, got = 0;

	(void)state;
	write_fw_config();
	start_fw();
	fw_sleep_ms(200);
	memset(comment, 'x', 300);
	memcpy(comment, "# ", 2);
	comment[300] = '\n';
	assert_int_equal(write(MASTER, comment, 301), 301);
	console("getBatteryVoltage", reply, sizeof(reply));
	assert_string_equal(reply, "ok true 235.000");

	for (unsigned i = 0; i < N; i++)
		len += frame_encode(req + len, sizeof(req) - len, (uint8_t)i, CMD_OP_getState, NULL,
				    0);
	int fl = fcntl(MASTER, F_GETFL);
	size_t sent = 0;
	fcntl(MASTER, F_SETFL, fl | O_NONBLOCK);
	for (int t = 0; t < 50; t++) {
		ssize_t k = write(MASTER, req + sent, len - sent);
		if (k > 0)
			sent += (size_t)k;
		fw_sleep_ms(10);
	}
	while (got < sizeof(ans)) {
		struct pollfd p = {.fd = MASTER,
				   .events = (short)(POLLIN | (sent < len ? POLLOUT : 0))};
		assert_int_equal(poll(&p, 1, 5000), 1);
		ssize_t k;
		if ((p.revents & POLLIN) && (k = read(MASTER, ans + got, sizeof(ans) - got)) > 0)
			got += (size_t)k;
		if ((p.revents & POLLOUT) && (k = write(MASTER, req + sent, len - sent)) > 0)
			sent += (size_t)k;
	}
	fcntl(MASTER, F_SETFL, fl);
	for (unsigned i = 0; i < N; i++) {
		const uint8_t *a = ans + i * ANS;
		const uint8_t head[] = {FRAME_SYNC,
					ANS - FRAME_OVERHEAD,
					0,
					(uint8_t)i,
					0x80 | CMD_OP_getState,
					WIRE_ST_OK,
					1,
					25,
					0,
					9};
		assert_memory_equal(a, head, sizeof(head));
		assert_memory_equal(a + sizeof(head), "Unpowered", 9);
		assert_int_equal(wire_get_u16(a + ANS - 2), cmd_crc16(0xFFFF, a + 1, ANS - 3));
	}
	/* nothing more, and the counters: the bytes of three lines (301, 18,
	 * 6) went to the console */
	console("$link", reply, sizeof(reply));
	snprintf(want, sizeof(want),
		 "ok frames %d executed %d duplicates 0 naks 0 crc 0 oversize 0 truncated 0 "
		 "other %d txdrop 0",
		 N, N, 301 + 18 + 6);
	assert_string_equal(reply, want);
	assert_int_equal(stop_fw(), 0);
	close(MASTER);
	MASTER = -1;
}

/* SIGTERM while idle and unpowered: a clean exit without a deceleration. */
static void test_fw_sigterm_idle(void **state)
{
	(void)state;
	char log[8192];
	write_fw_config();
	start_fw();
	fw_sleep_ms(200);
	assert_int_equal(stop_fw(), 0);
	fw_read_log(log, sizeof(log));
	assert_null(strstr(log, "shutdown: stopped after"));
	assert_non_null(
	    strstr(log, "vehicle-fw: final state: unpowered, relay open, servo off, stopped\n"));
	close(MASTER);
	MASTER = -1;
}

/* Each alarm goes to the log as it is raised and cleared, timed from the
 * loop's start: a refusal's warning, then clearAlarm. */
static void test_fw_alarm_events(void **state)
{
	(void)state;
	char reply[512], log[8192];
	const char *raised, *cleared;
	double t1 = -1, t2 = -1;
	write_fw_config();
	start_fw();
	fw_sleep_ms(200);
	console("setServo true", reply, sizeof(reply));
	assert_string_equal(reply, "ok false");
	fw_sleep_ms(100);
	console("clearAlarm", reply, sizeof(reply));
	assert_string_equal(reply, "ok true");
	assert_int_equal(stop_fw(), 0);
	fw_read_log(log, sizeof(log));
	raised = strstr(log, "vehicle-fw: alarm raised 128 warning \"setServo refused: power off\" "
			     "at ");
	cleared = strstr(log, "vehicle-fw: alarm cleared 128 warning \"setServo refused: power "
			      "off\" at ");
	if (!raised || !cleared || cleared < raised || !strchr(cleared, '\n') ||
	    sscanf(strstr(raised, " at "), " at %lf s\n", &t1) != 1 ||
	    sscanf(strstr(cleared, " at "), " at %lf s\n", &t2) != 1 ||
	    /* cleared at least 100 ms after it was raised */
	    !(t1 > 0.0 && t1 < 60.0 && t2 - t1 >= 0.09 && t2 < 60.0) ||
	    /* nothing else */
	    strstr(strchr(raised, '\n'), "alarm raised") || strstr(strchr(cleared, '\n'), "alarm "))
		fail_msg("vehicle-fw logged:\n%s", log);
	close(MASTER);
	MASTER = -1;
}

/* Start-up errors: exit status 1 and one message. */
static void test_fw_bad_config(void **state)
{
	(void)state;
	char cmd[2048], out[1024], want[1024];
	fw_write_file(FW_VPATH,
		      VEHICLE_HEAD "<backends><power settle_ms=\"99\"/></backends></vehicle>\n");
	snprintf(cmd, sizeof(cmd), "%s/vehicle-fw --config %s --io %s --rt-priority 0 2>&1",
		 FW_BUILD_DIR, FW_VPATH, FW_IOPATH);
	FILE *p = popen(cmd, "r");
	assert_non_null(p);
	size_t n = fread(out, 1, sizeof(out) - 1, p);
	out[n] = '\0';
	assert_int_equal(pclose(p), 1 << 8);
	snprintf(want, sizeof(want),
		 "vehicle-fw: error: %s:4: power.settle_ms: out of range 0..50 '99'\n", FW_VPATH);
	assert_string_equal(out, want);
}

static int teardown(void **state)
{
	(void)state;
	if (FW_PID > 0) {
		kill(FW_PID, SIGKILL);
		waitpid(FW_PID, NULL, 0);
		FW_PID = -1;
	}
	if (MASTER >= 0)
		close(MASTER);
	MASTER = -1;
	return 0;
}

/* The configuration changed at run time, saved in the --store file, is in
 * force at the next start, and the log says what the store held; a file
 * of garbage starts the unit on the vehicle file with warning 156. */
static void test_fw_store(void **state)
{
	(void)state;
	char reply[512], log[8192], store[700];
	write_fw_config();
	snprintf(store, sizeof(store), "%s.store", FW_VPATH);
	unlink(store);
	start_fw_store(store);
	fw_sleep_ms(200);
	console("$config store", reply, sizeof(reply));
	assert_string_equal(reply, "ok store empty table 0x916B11C3");
	console("$config following_error_mm 20", reply, sizeof(reply));
	assert_string_equal(reply, "ok following_error_mm 20.000");
	console("$config save", reply, sizeof(reply));
	assert_string_equal(reply, "ok saved 1 following_error_mm");
	assert_int_equal(stop_fw(), 0);
	fw_read_log(log, sizeof(log));
	assert_non_null(strstr(log, "vehicle-fw: configuration store empty table 0x916B11C3 ("));
	close(MASTER);

	start_fw_store(store);
	fw_sleep_ms(200);
	console("$config following_error_mm", reply, sizeof(reply));
	assert_string_equal(reply, "ok following_error_mm 20.000");
	assert_int_equal(stop_fw(), 0);
	fw_read_log(log, sizeof(log));
	assert_non_null(strstr(log, "vehicle-fw: configuration store loaded seq 1 schema "
				    "0x916B11C3 applied 1 dropped 0 table 0x916B11C3 ("));
	close(MASTER);

	/* both slots garbage (a store of another program, damage) */
	static char junk[4097];
	memset(junk, 'Z', sizeof(junk) - 1);
	fw_write_file(store, junk);
	start_fw_store(store);
	fw_sleep_ms(200);
	console("$config following_error_mm", reply, sizeof(reply));
	assert_string_equal(reply, "ok following_error_mm 50.000");
	console("getActiveAlarm 1", reply, sizeof(reply));
	assert_string_equal(reply,
			    "ok true 1 1 156 warning \"saved configuration corrupt: base in use\"");
	assert_int_equal(stop_fw(), 0);
	fw_read_log(log, sizeof(log));
	assert_non_null(strstr(
	    log, "vehicle-fw: warning: configuration store corrupt table 0x916B11C3 torn ("));
	close(MASTER);
	MASTER = -1;
	unlink(store);
}

/* The host runs the configuration tests; "--process" runs the tests that
 * start vehicle-fw, in the QEMU guest on its instruction-counted clock
 * (tests/qemu/fw_process.sh), where the host's load cannot make them late. */
int main(int argc, char **argv)
{
	const struct CMUnitTest unit[] = {
	    cmocka_unit_test(test_backends_parsed), cmocka_unit_test(test_backends_defaults),
	    cmocka_unit_test(test_backends_errors), cmocka_unit_test(test_backends_one_pass),
	    cmocka_unit_test(test_example_config),  cmocka_unit_test(test_joystick_cfg_and_scaling),
	};
	const struct CMUnitTest process[] = {
	    cmocka_unit_test_teardown(test_fw_link_and_sigterm_mid_move, teardown),
	    cmocka_unit_test_teardown(test_fw_sigterm_idle, teardown),
	    cmocka_unit_test_teardown(test_fw_alarm_events, teardown),
	    cmocka_unit_test_teardown(test_fw_pipelined_and_long_comment, teardown),
	    cmocka_unit_test_teardown(test_fw_bad_config, teardown),
	    cmocka_unit_test_teardown(test_fw_store, teardown),
	};
	bool proc = argc > 1 && strcmp(argv[1], "--process") == 0;
	if (fw_rig_init(argc > 0 ? argv[0] : NULL, "vsfw") < 0)
		return 1;
	signal(SIGPIPE, SIG_IGN);
	int rc = proc ? cmocka_run_group_tests(process, NULL, NULL)
		      : cmocka_run_group_tests(unit, NULL, NULL);
	fw_rig_cleanup();
	return rc;
}
