/* The CiA 402 backend on the host (hal/linux/cia402.h): the protocol
 * functions (SDO frames and replies, abort texts, statusword, controlword
 * for each transition, EMCY, heartbeat timeout on an injected clock,
 * configuration sequence), then the bus logic through a scripted frame
 * transport: start-up sequence and its errors, the tick's frames, fault
 * and reset, heartbeat loss, a drive that restarts, send errors. The
 * SocketCAN path itself runs in the QEMU guest (tests/qemu/fw_cia402.sh). */
#include <errno.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <cmocka.h>

#include "../hal/linux/cia402.h"

static void frame_hex(const canlink_frame_t *f, char *out, size_t len)
{
	int n = snprintf(out, len, "%03X#", (unsigned)f->id);
	for (unsigned i = 0; i < f->dlc && n > 0 && (size_t)n < len; i++)
		n += snprintf(out + n, len - (size_t)n, "%02X", f->data[i]);
}

#define assert_frame(f, text)                                                                      \
	do {                                                                                       \
		char hx_[40];                                                                      \
		frame_hex((f), hx_, sizeof(hx_));                                                  \
		assert_string_equal(hx_, (text));                                                  \
	} while (0)

static canlink_frame_t mk(uint32_t id, const char *hex)
{
	canlink_frame_t f = {.id = id};
	while (hex[0] && hex[1] && f.dlc < 8) {
		unsigned v;
		sscanf(hex, "%2x", &v);
		f.data[f.dlc++] = (uint8_t)v;
		hex += 2;
	}
	return f;
}

/* ---- protocol ---------------------------------------------------------- */

static void test_sdo_request_frames(void **state)
{
	(void)state;
	canlink_frame_t f;
	co_sdo_req_t r = {.index = 0x6060, .sub = 0, .size = 1, .value = 3};
	co_sdo_request_frame(&f, 1, &r);
	assert_frame(&f, "601#2F60600003000000");
	r = (co_sdo_req_t){.index = 0x1017, .sub = 0, .size = 2, .value = 100};
	co_sdo_request_frame(&f, 2, &r);
	assert_frame(&f, "602#2B17100064000000");
	r = (co_sdo_req_t){.index = 0x1400, .sub = 1, .size = 4, .value = 0x80000201u};
	co_sdo_request_frame(&f, 1, &r);
	assert_frame(&f, "601#2300140101020080");
	r = (co_sdo_req_t){.index = 0x60FF, .sub = 0, .size = 4, .value = (uint32_t)-1000};
	co_sdo_request_frame(&f, 127, &r);
	assert_frame(&f, "67F#23FF600018FCFFFF");
	r = (co_sdo_req_t){.index = 0x1000, .sub = 0, .upload = true};
	co_sdo_request_frame(&f, 3, &r);
	assert_frame(&f, "603#4000100000000000");
}

static void test_sdo_reply_decode(void **state)
{
	(void)state;
	uint32_t v = 7;
	co_sdo_req_t dl = {.index = 0x6060, .sub = 0, .size = 1, .value = 3};
	co_sdo_req_t ul = {.index = 0x1000, .sub = 0, .upload = true};
	canlink_frame_t f = mk(0x581, "6060600000000000");
	assert_int_equal(co_sdo_reply_decode(&f, 1, &dl, &v), CO_SDO_OK);
	assert_int_equal(v, 0);
	/* another node's reply, another object's */
	assert_int_equal(co_sdo_reply_decode(&f, 2, &dl, &v), CO_SDO_NOT_OURS);
	f = mk(0x581, "6040600000000000");
	assert_int_equal(co_sdo_reply_decode(&f, 1, &dl, &v), CO_SDO_NOT_OURS);
	f = mk(0x581, "6060600100000000");
	assert_int_equal(co_sdo_reply_decode(&f, 1, &dl, &v), CO_SDO_NOT_OURS);
	/* abort: the code, whatever multiplexer it names */
	f = mk(0x581, "8060600000000206");
	assert_int_equal(co_sdo_reply_decode(&f, 1, &dl, &v), CO_SDO_ABORT);
	assert_int_equal(v, 0x06020000);
	f = mk(0x581, "8000000001000405");
	assert_int_equal(co_sdo_reply_decode(&f, 1, &dl, &v), CO_SDO_ABORT);
	assert_int_equal(v, 0x05040001);
	/* download answered as an upload, short frame */
	f = mk(0x581, "4360600000000000");
	assert_int_equal(co_sdo_reply_decode(&f, 1, &dl, &v), CO_SDO_BAD);
	f = mk(0x581, "60606000");
	assert_int_equal(co_sdo_reply_decode(&f, 1, &dl, &v), CO_SDO_BAD);
	/* expedited uploads: 4, 2, 1 byte, size not indicated */
	f = mk(0x583, "4300100092010200");
	assert_int_equal(co_sdo_reply_decode(&f, 3, &ul, &v), CO_SDO_OK);
	assert_int_equal(v, 0x00020192);
	f = mk(0x583, "4B001000920102FF");
	assert_int_equal(co_sdo_reply_decode(&f, 3, &ul, &v), CO_SDO_OK);
	assert_int_equal(v, 0x0192);
	f = mk(0x583, "4F00100092FFFFFF");
	assert_int_equal(co_sdo_reply_decode(&f, 3, &ul, &v), CO_SDO_OK);
	assert_int_equal(v, 0x92);
	f = mk(0x583, "4200100001020304");
	assert_int_equal(co_sdo_reply_decode(&f, 3, &ul, &v), CO_SDO_OK);
	assert_int_equal(v, 0x04030201);
	/* segmented upload (not expedited), a download reply to an upload */
	f = mk(0x583, "4100100004000000");
	assert_int_equal(co_sdo_reply_decode(&f, 3, &ul, &v), CO_SDO_BAD);
	f = mk(0x583, "6000100000000000");
	assert_int_equal(co_sdo_reply_decode(&f, 3, &ul, &v), CO_SDO_BAD);
}

static void test_sdo_abort_text(void **state)
{
	(void)state;
	assert_string_equal(co_sdo_abort_text(0x06020000),
			    "object does not exist in the object dictionary");
	assert_string_equal(co_sdo_abort_text(0x06090011), "sub-index does not exist");
	assert_string_equal(co_sdo_abort_text(0x06010002), "attempt to write a read-only object");
	assert_string_equal(co_sdo_abort_text(0x06040041), "object cannot be mapped to the PDO");
	assert_string_equal(co_sdo_abort_text(0x05040000), "SDO protocol timed out");
	assert_string_equal(co_sdo_abort_text(0x08000022),
			    "data cannot be transferred in the present device state");
	assert_string_equal(co_sdo_abort_text(0x12345678), "unknown abort code");
	assert_string_equal(co_sdo_abort_text(0), "unknown abort code");
}

static void test_statusword(void **state)
{
	(void)state;
	static const struct {
		uint16_t sw;
		co_state_t st;
	} t[] = {
	    {0x0000, CO_ST_NOT_READY},
	    {0x0010, CO_ST_NOT_READY},
	    {0x0040, CO_ST_SWITCH_ON_DISABLED},
	    {0x0250, CO_ST_SWITCH_ON_DISABLED},
	    {0x0021, CO_ST_READY},
	    {0x0231, CO_ST_READY},
	    {0x0023, CO_ST_SWITCHED_ON},
	    {0x0233, CO_ST_SWITCHED_ON},
	    {0x0027, CO_ST_OP_ENABLED},
	    {0x0637, CO_ST_OP_ENABLED},
	    {0x0007, CO_ST_QUICK_STOP},
	    {0x0217, CO_ST_QUICK_STOP},
	    {0x000F, CO_ST_FAULT_REACTION},
	    {0x003F, CO_ST_FAULT_REACTION},
	    {0x0008, CO_ST_FAULT},
	    {0x0218, CO_ST_FAULT},
	    {0x0038, CO_ST_FAULT},
	    {0x0001, CO_ST_UNKNOWN},
	    {0x0041, CO_ST_UNKNOWN},
	    {0x0061, CO_ST_UNKNOWN},
	};
	for (size_t i = 0; i < sizeof(t) / sizeof(t[0]); i++) {
		if (co_state_of(t[i].sw) != t[i].st)
			fail_msg("statusword 0x%04X: %s, expected %s", t[i].sw,
				 co_state_name(co_state_of(t[i].sw)), co_state_name(t[i].st));
	}
	assert_string_equal(co_state_name(CO_ST_OP_ENABLED), "operation enabled");
	assert_string_equal(co_state_name(CO_ST_FAULT), "fault");
	assert_true(co_state_is_fault(CO_ST_FAULT));
	assert_true(co_state_is_fault(CO_ST_FAULT_REACTION));
	assert_false(co_state_is_fault(CO_ST_QUICK_STOP));
	/* the HAL's names of the same states */
	static const struct {
		co_state_t st;
		uint8_t ph;
	} h[] = {
	    {CO_ST_UNKNOWN, HAL_DRIVE_UNKNOWN},
	    {CO_ST_NOT_READY, HAL_DRIVE_NOT_READY},
	    {CO_ST_SWITCH_ON_DISABLED, HAL_DRIVE_SWITCH_ON_DISABLED},
	    {CO_ST_READY, HAL_DRIVE_READY},
	    {CO_ST_SWITCHED_ON, HAL_DRIVE_SWITCHED_ON},
	    {CO_ST_OP_ENABLED, HAL_DRIVE_ENABLED},
	    {CO_ST_QUICK_STOP, HAL_DRIVE_QUICK_STOP},
	    {CO_ST_FAULT_REACTION, HAL_DRIVE_FAULT_REACTION},
	    {CO_ST_FAULT, HAL_DRIVE_FAULT},
	    {(co_state_t)99, HAL_DRIVE_UNKNOWN},
	};
	for (size_t i = 0; i < sizeof(h) / sizeof(h[0]); i++)
		assert_int_equal(co_hal_phase(h[i].st), h[i].ph);
}

static void test_controlword(void **state)
{
	(void)state;
	static const struct {
		co_state_t st;
		uint16_t on, off, reset_on, reset_off;
	} t[] = {
	    /* state                   enable  disable  (with a reset request) */
	    {CO_ST_UNKNOWN, 0x06, 0x06, 0x06, 0x06},
	    {CO_ST_NOT_READY, 0x06, 0x06, 0x06, 0x06},
	    {CO_ST_SWITCH_ON_DISABLED, 0x06, 0x06, 0x06, 0x06}, /* 2: shutdown */
	    {CO_ST_READY, 0x07, 0x06, 0x07, 0x06},		/* 3: switch on */
	    {CO_ST_SWITCHED_ON, 0x0F, 0x06, 0x0F, 0x06},	/* 4: enable operation; 6 */
	    {CO_ST_OP_ENABLED, 0x0F, 0x06, 0x0F, 0x06},		/* 8: shutdown */
	    {CO_ST_QUICK_STOP, 0x00, 0x00, 0x00, 0x00},		/* 12: disable voltage */
	    {CO_ST_FAULT_REACTION, 0x00, 0x00, 0x00, 0x00},	/* 14: automatic */
	    {CO_ST_FAULT, 0x00, 0x00, 0x80, 0x80},		/* 15: fault reset */
	};
	for (size_t i = 0; i < sizeof(t) / sizeof(t[0]); i++) {
		assert_int_equal(co_controlword(t[i].st, true, false), t[i].on);
		assert_int_equal(co_controlword(t[i].st, false, false), t[i].off);
		assert_int_equal(co_controlword(t[i].st, true, true), t[i].reset_on);
		assert_int_equal(co_controlword(t[i].st, false, true), t[i].reset_off);
	}
	/* The whole enable sequence, as a drive following it would go. */
	static const uint16_t sws[] = {0x0250, 0x0231, 0x0233, 0x0237};
	static const uint16_t cws[] = {0x06, 0x07, 0x0F, 0x0F};
	for (size_t i = 0; i < 4; i++)
		assert_int_equal(co_controlword(co_state_of(sws[i]), true, false), cws[i]);
}

static void test_velocity_units(void **state)
{
	(void)state;
	assert_int_equal(co_velocity_of_q8(0), 0);
	assert_int_equal(co_velocity_of_q8(256 * 1000), 1000);
	assert_int_equal(co_velocity_of_q8(256 * 1000 + 127), 1000);
	assert_int_equal(co_velocity_of_q8(256 * 1000 + 128), 1001);
	assert_int_equal(co_velocity_of_q8(-256 * 1000 - 127), -1000);
	assert_int_equal(co_velocity_of_q8(-256 * 1000 - 128), -1001);
	assert_int_equal(co_velocity_of_q8(127), 0);
	assert_int_equal(co_velocity_of_q8(-128), -1);
	assert_int_equal(co_velocity_of_q8(INT32_MAX), 8388608);
	assert_int_equal(co_velocity_of_q8(INT32_MIN), -8388608);
}

static void test_pdo_nmt_frames(void **state)
{
	(void)state;
	canlink_frame_t f;
	co_nmt_frame(&f, CO_NMT_START, 1);
	assert_frame(&f, "000#0101");
	co_nmt_frame(&f, CO_NMT_RESET_COMM, 2);
	assert_frame(&f, "000#8202");
	co_nmt_frame(&f, CO_NMT_PREOP, 3);
	assert_frame(&f, "000#8003");
	co_sync_frame(&f);
	assert_frame(&f, "080#");
	co_heartbeat_frame(&f, 127, CO_HB_OPERATIONAL);
	assert_frame(&f, "77F#05");
	co_rpdo1_frame(&f, 1, CO_CW_ENABLE_OP, 1000);
	assert_frame(&f, "201#0F00E8030000");
	co_rpdo1_frame(&f, 2, CO_CW_FAULT_RESET, -2);
	assert_frame(&f, "202#8000FEFFFFFF");

	uint16_t sw = 0;
	int32_t pos = 0;
	int8_t mode = 0;
	f = mk(0x181, "3702FFFFFF7F03");
	assert_true(co_tpdo1_decode(&f, &sw, &pos, &mode));
	assert_int_equal(sw, 0x0237);
	assert_int_equal(pos, INT32_MAX);
	assert_int_equal(mode, 3);
	f = mk(0x181, "18020000008099");
	assert_true(co_tpdo1_decode(&f, &sw, &pos, &mode));
	assert_int_equal(sw, 0x0218);
	assert_int_equal(pos, INT32_MIN);
	assert_int_equal(mode, -103); /* 0x99: a manufacturer's mode, signed */
	/* statusword and position without the mode display: too short */
	f = mk(0x181, "370200000000");
	assert_false(co_tpdo1_decode(&f, &sw, &pos, &mode));
}

static void test_emcy_decode(void **state)
{
	(void)state;
	co_emcy_t e;
	canlink_frame_t f = mk(0x081, "102301A1B2C3D4E5");
	assert_true(co_emcy_decode(&f, &e));
	assert_int_equal(e.code, 0x2310);
	assert_int_equal(e.reg, 0x01);
	static const uint8_t mfr[5] = {0xA1, 0xB2, 0xC3, 0xD4, 0xE5};
	assert_memory_equal(e.mfr, mfr, 5);
	f = mk(0x082, "000000");
	assert_true(co_emcy_decode(&f, &e));
	assert_int_equal(e.code, 0);
	assert_int_equal(e.mfr[4], 0);
	f = mk(0x082, "3081");
	assert_false(co_emcy_decode(&f, &e));
}

static void test_heartbeat_timeout(void **state)
{
	(void)state;
	co_hb_t h;
	const uint32_t tmo = 300000;
	co_hb_arm(&h, 1000);
	assert_false(co_hb_alive(&h, 1000, tmo)); /* nothing heard yet */
	co_hb_rx(&h, CO_HB_OPERATIONAL, 5000);
	assert_true(co_hb_alive(&h, 5000, tmo));
	assert_true(co_hb_alive(&h, 5000 + tmo, tmo));
	assert_false(co_hb_alive(&h, 5000 + tmo + 1, tmo));
	/* any other NMT state is a lost drive */
	co_hb_rx(&h, CO_HB_PREOP, 6000);
	assert_false(co_hb_alive(&h, 6000, tmo));
	co_hb_rx(&h, CO_HB_STOPPED, 6000);
	assert_false(co_hb_alive(&h, 6000, tmo));
	co_hb_rx(&h, CO_HB_BOOTUP, 6000);
	assert_false(co_hb_alive(&h, 6000, tmo));
	/* across the wrap of the microsecond clock */
	co_hb_rx(&h, CO_HB_OPERATIONAL, UINT32_MAX - 100);
	assert_true(co_hb_alive(&h, tmo - 101, tmo));
	assert_false(co_hb_alive(&h, tmo - 100, tmo));
}

static void test_config_list(void **state)
{
	(void)state;
	co_sdo_req_t r[CO_CFG_MAX];
	co_cfg_t c = {.heartbeat_ms = 100};
	unsigned n = co_config_list(&c, 1, r);
	static const char *const want[] = {
	    "601#4000100000000000", /* read device type */
	    "601#2B40600006000000", /* controlword: shutdown */
	    "601#23FF600000000000", /* target velocity 0 */
	    "601#2F60600003000000", /* modes of operation: profile velocity */
	    "601#2300140101020080", /* RPDO1 invalid */
	    "601#2F00160000000000", /* no objects mapped */
	    "601#2300160110004060", /* 1st: controlword */
	    "601#230016022000FF60", /* 2nd: target velocity */
	    "601#2F00160002000000", /* two objects */
	    "601#2F00140201000000", /* synchronous */
	    "601#2300140101020000", /* RPDO1 valid on 0x201 */
	    "601#2300180181010080", /* TPDO1 invalid */
	    "601#2F001A0000000000", /* no objects mapped */
	    "601#23001A0110004160", /* 1st: statusword */
	    "601#23001A0220006460", /* 2nd: position actual value */
	    "601#23001A0308006160", /* 3rd: modes of operation display */
	    "601#2F001A0003000000", /* three objects */
	    "601#2F00180201000000", /* on every SYNC */
	    "601#2300180181010000", /* TPDO1 valid on 0x181 */
	    "601#2B17100064000000", /* heartbeat every 100 ms */
	};
	assert_int_equal(n, sizeof(want) / sizeof(want[0]));
	for (unsigned i = 0; i < n; i++) {
		canlink_frame_t f;
		char hx[40];
		co_sdo_request_frame(&f, 1, &r[i]);
		frame_hex(&f, hx, sizeof(hx));
		if (strcmp(hx, want[i]) != 0)
			fail_msg("step %u: %s, expected %s", i, hx, want[i]);
	}
	assert_true(r[0].upload);
	assert_int_equal(r[0].value, 0x0192);
	assert_int_equal(r[0].mask, 0xFFFF);
	/* master heartbeat and profile acceleration */
	c = (co_cfg_t){
	    .heartbeat_ms = 50, .master_node = 127, .consumer_ms = 300, .profile_accel = 200000};
	n = co_config_list(&c, 2, r);
	assert_int_equal(n, 23);
	canlink_frame_t f;
	co_sdo_request_frame(&f, 2, &r[19]);
	assert_frame(&f, "602#2B17100032000000");
	co_sdo_request_frame(&f, 2, &r[20]);
	assert_frame(&f, "602#231610012C017F00");
	co_sdo_request_frame(&f, 2, &r[21]);
	assert_frame(&f, "602#23836000400D0300");
	co_sdo_request_frame(&f, 2, &r[22]);
	assert_frame(&f, "602#23846000400D0300");
}

/* ---- the bus, through a scripted transport ------------------------------ */

typedef struct {
	canlink_frame_t tx[1024];
	unsigned ntx, attempts;
	canlink_frame_t rx[512];
	unsigned rx_head, rx_tail;
	int send_mode; /* 1 sent, 0 queue full, ENETDOWN or EIO: that error */
	int recv_errno;
	bool respond; /* drives answer NMT reset and start, SDO, SYNC */
	bool no_boot[128], no_hb, no_tpdo, started[128];
	uint16_t abort_index, silent_index;
	uint32_t abort_code, device_type;
} fake_t;

static fake_t FK;

static void push(canlink_frame_t f)
{
	FK.rx[FK.rx_tail++ % 512] = f;
}

static int fk_send(void *ctx, const canlink_frame_t *f)
{
	(void)ctx;
	FK.attempts++;
	if (FK.send_mode == 0)
		return 0;
	if (FK.send_mode != 1) {
		errno = FK.send_mode;
		return -1;
	}
	FK.tx[FK.ntx++ % 1024] = *f;
	if (!FK.respond)
		return 1;
	if (f->id == 0 && f->data[0] == CO_NMT_RESET_COMM && !FK.no_boot[f->data[1]])
		push(mk(0x700u + f->data[1], "00"));
	if (f->id == 0 && f->data[0] == CO_NMT_START) {
		FK.started[f->data[1]] = true;
		if (!FK.no_hb)
			push(mk(0x700u + f->data[1], "05"));
	}
	for (unsigned n = 1; f->id == CO_ID_SYNC && !FK.no_tpdo && n < 128; n++)
		if (FK.started[n])
			push(mk(0x180u + n, "40020000000003"));
	if (f->id > 0x600 && f->id <= 0x67F) {
		uint16_t idx = (uint16_t)(f->data[1] | f->data[2] << 8);
		canlink_frame_t r = {.id = f->id - 0x80u, .dlc = 8};
		memcpy(r.data, f->data, 4);
		if (idx == FK.silent_index)
			return 1;
		if (idx == FK.abort_index) {
			r.data[0] = 0x80;
			for (int i = 0; i < 4; i++)
				r.data[4 + i] = (uint8_t)(FK.abort_code >> (8 * i));
		} else if (f->data[0] == 0x40) {
			r.data[0] = 0x43;
			for (int i = 0; i < 4; i++)
				r.data[4 + i] = (uint8_t)(FK.device_type >> (8 * i));
		} else {
			r.data[0] = 0x60;
		}
		push(r);
	}
	return 1;
}

static int fk_recv(void *ctx, canlink_frame_t *f)
{
	(void)ctx;
	if (FK.recv_errno) {
		errno = FK.recv_errno;
		FK.recv_errno = 0;
		return -1;
	}
	if (FK.rx_head == FK.rx_tail)
		return 0;
	*f = FK.rx[FK.rx_head++ % 512];
	return 1;
}

static int fk_wait(void *ctx, int timeout_ms)
{
	(void)ctx;
	if (FK.rx_head != FK.rx_tail)
		return 1;
	(void)timeout_ms; /* a short nap: the caller loops to its deadline */
	struct timespec ts = {0, 1000000L};
	nanosleep(&ts, NULL);
	return 0;
}

static co_bus_t BUS;
/* The modes of operation display that feed() sends for nodes 1, 2. */
static int8_t MODE[2] = {3, 3};

static bk_canopen_bus_t test_cfg(uint32_t master)
{
	return (bk_canopen_bus_t){.used = true,
				  .interface = "vcan9",
				  .heartbeat_ms = 100,
				  .heartbeat_timeout_ms = 300,
				  .sdo_timeout_ms = 5,
				  .boot_timeout_ms = 20,
				  .master_node = master,
				  .fault_reset_ms = 200};
}

/* Answering drives on a working transport. */
static void fake_reset(void)
{
	memset(&FK, 0, sizeof(FK));
	FK.send_mode = 1;
	FK.respond = true;
	FK.device_type = 0x00020192;
	FK.abort_index = FK.silent_index = 0xFFFF;
	MODE[0] = MODE[1] = 3;
}

/* Polarity of axes 0, 1 for the next start (reset after it). */
static bool REVERSE[2];

/* Drives with these node ids on axes 0, 1, ... */
static int start_nodes(uint32_t master, const uint8_t *nodes, unsigned n, char *err, size_t len)
{
	bk_canopen_bus_t cfg = test_cfg(master);
	co_bus_init(&BUS, 0, &cfg);
	for (unsigned i = 0; i < n; i++)
		assert_int_equal(co_bus_add(&BUS, (uint8_t)i, nodes[i], i < 2 && REVERSE[i]), i);
	memset(REVERSE, 0, sizeof(REVERSE));
	BUS.io = (co_io_t){fk_send, fk_recv, fk_wait, NULL};
	return co_bus_start(&BUS, err, len);
}

/* Two drives (axis 0 node 1, axis 1 node 2) on the fake transport. */
static int bus_start(uint32_t master, char *err, size_t len)
{
	static const uint8_t two[] = {1, 2};
	fake_reset();
	return start_nodes(master, two, 2, err, len);
}

/* stderr into a file while a check runs, for the log lines. */
static char LOGF[] = "/tmp/vscoXXXXXX";
static int saved_err = -1;
static void capture(void)
{
	fflush(stderr);
	saved_err = dup(2);
	int fd = mkstemp(LOGF);
	assert_true(fd >= 0);
	dup2(fd, 2);
	close(fd);
}
static void captured(char *buf, size_t len)
{
	fflush(stderr);
	dup2(saved_err, 2);
	close(saved_err);
	FILE *f = fopen(LOGF, "r");
	assert_non_null(f);
	size_t n = fread(buf, 1, len - 1, f);
	buf[n] = '\0';
	fclose(f);
	unlink(LOGF);
	strcpy(LOGF, "/tmp/vscoXXXXXX");
}

static void test_bus_startup_sequence(void **state)
{
	(void)state;
	char err[256] = "";
	assert_int_equal(bus_start(0, err, sizeof(err)), 0);
	assert_string_equal(err, "");
	/* reset communication for each, 20 SDO each, start each, one SYNC */
	assert_int_equal(FK.ntx, 2 + 20 + 20 + 2 + 1);
	assert_frame(&FK.tx[0], "000#8201");
	assert_frame(&FK.tx[1], "000#8202");
	assert_frame(&FK.tx[2], "601#4000100000000000");
	assert_frame(&FK.tx[5], "601#2F60600003000000");
	assert_frame(&FK.tx[21], "601#2B17100064000000");
	assert_frame(&FK.tx[22], "602#4000100000000000");
	assert_frame(&FK.tx[25], "602#2F60600003000000");
	assert_frame(&FK.tx[42], "000#0101");
	assert_frame(&FK.tx[43], "000#0102");
	assert_frame(&FK.tx[44], "080#");
	/* the first tick starts from the positions of that SYNC */
	assert_true(BUS.d[0].have_status);
	assert_int_equal(BUS.d[1].status, 0x0240);
	assert_true(BUS.started);
	assert_int_equal(BUS.d[0].phase, CO_PHASE_RUN);
	/* with the master's heartbeat: consumed by each drive, 21 SDO each */
	assert_int_equal(bus_start(127, err, sizeof(err)), 0);
	assert_int_equal(FK.ntx, 2 + 21 + 21 + 2 + 1);
	assert_frame(&FK.tx[22], "601#231610012C017F00");
}

static void test_bus_startup_errors(void **state)
{
	(void)state;
	static const uint8_t one[] = {1}, five[] = {5}, two[] = {1, 2};
	char err[256] = "";

	/* an SDO abort: node, index, sub-index, code and its meaning */
	fake_reset();
	FK.abort_index = 0x6060;
	FK.abort_code = 0x06020000;
	assert_int_equal(start_nodes(0, two, 2, err, sizeof(err)), -1);
	assert_string_equal(err, "canopen bus 0 (vcan9): node 1 (axis 0): SDO write 0x6060:00 "
				 "aborted with 0x06020000 (object does not exist in the object "
				 "dictionary)");
	assert_false(BUS.started);

	/* no reply to one SDO */
	fake_reset();
	FK.silent_index = 0x1800;
	assert_int_equal(start_nodes(0, two, 2, err, sizeof(err)), -1);
	assert_string_equal(err, "canopen bus 0 (vcan9): node 1 (axis 0): SDO write 0x1800:01: "
				 "no reply within 5 ms");

	/* an upload aborted */
	fake_reset();
	FK.abort_index = 0x1000;
	FK.abort_code = 0x08000000;
	assert_int_equal(start_nodes(0, five, 1, err, sizeof(err)), -1);
	assert_string_equal(err, "canopen bus 0 (vcan9): node 5 (axis 0): SDO read 0x1000:00 "
				 "aborted with 0x08000000 (general error)");

	/* not a CiA 402 device */
	fake_reset();
	FK.device_type = 0x00000191;
	assert_int_equal(start_nodes(0, one, 1, err, sizeof(err)), -1);
	assert_string_equal(err, "canopen bus 0 (vcan9): node 1 (axis 0): device type 0x00000191 "
				 "is not a CiA 402 drive (profile 401, expected 402)");

	/* node 2 never boots */
	fake_reset();
	FK.no_boot[2] = true;
	assert_int_equal(start_nodes(0, two, 2, err, sizeof(err)), -1);
	assert_string_equal(err, "canopen bus 0 (vcan9): node 2 (axis 1): no boot-up message "
				 "within 20 ms of reset communication");

	/* the interface is down */
	fake_reset();
	FK.send_mode = ENETDOWN;
	assert_int_equal(start_nodes(0, one, 1, err, sizeof(err)), -1);
	assert_string_equal(err, "canopen bus 0 (vcan9): interface is down");
	assert_int_equal(BUS.tx_down, 1);

	/* another send error */
	fake_reset();
	FK.send_mode = EIO;
	assert_int_equal(start_nodes(0, one, 1, err, sizeof(err)), -1);
	assert_string_equal(err, "canopen bus 0 (vcan9): node 1 (axis 0): send failed: "
				 "Input/output error");

	/* started, but no heartbeat says operational */
	fake_reset();
	FK.no_hb = true;
	assert_int_equal(start_nodes(0, two, 2, err, sizeof(err)), -1);
	assert_string_equal(err, "canopen bus 0 (vcan9): node 1 (axis 0): no operational heartbeat "
				 "within 300 ms of NMT start");

	/* no TPDO1 on the SYNC */
	fake_reset();
	FK.no_tpdo = true;
	assert_int_equal(start_nodes(0, five, 1, err, sizeof(err)), -1);
	assert_string_equal(err,
			    "canopen bus 0 (vcan9): node 5 (axis 0): no TPDO1 within 5 ms of SYNC");

	/* the transmit queue stays full */
	fake_reset();
	FK.send_mode = 0;
	assert_int_equal(start_nodes(0, one, 1, err, sizeof(err)), -1);
	assert_string_equal(err,
			    "canopen bus 0 (vcan9): node 1 (axis 0): transmit queue full for 5 ms");
	assert_true(BUS.tx_full >= 1);
}

/* The frames sent by one tick, as text, one per line. */
static void tick(uint32_t now_us, char *out, size_t len)
{
	unsigned from = FK.ntx;
	co_bus_pre_tick(&BUS, now_us);
	size_t n = 0;
	out[0] = '\0';
	for (unsigned i = from; i < FK.ntx && n < len; i++) {
		char hx[40];
		frame_hex(&FK.tx[i], hx, sizeof(hx));
		n += (size_t)snprintf(out + n, len - n, "%s%s", i > from ? " " : "", hx);
	}
}

static void feed(uint16_t sw1, int32_t pos1, uint16_t sw2, int32_t pos2, bool hb)
{
	canlink_frame_t f = {.id = 0x181, .dlc = 7};
	f.data[0] = (uint8_t)sw1;
	f.data[1] = (uint8_t)(sw1 >> 8);
	memcpy(f.data + 2, &pos1, 4); /* little-endian host */
	f.data[6] = (uint8_t)MODE[0];
	push(f);
	f.id = 0x182;
	f.data[0] = (uint8_t)sw2;
	f.data[1] = (uint8_t)(sw2 >> 8);
	memcpy(f.data + 2, &pos2, 4);
	f.data[6] = (uint8_t)MODE[1];
	push(f);
	if (hb) {
		push(mk(0x701, "05"));
		push(mk(0x702, "05"));
	}
}

static void test_bus_tick_enable_sequence(void **state)
{
	(void)state;
	char err[256], out[512];
	hal_drive_state_t st;
	assert_int_equal(bus_start(127, err, sizeof(err)), 0);
	FK.respond = false;
	/* first tick: master heartbeat, both drives shutdown + 0, one SYNC */
	tick(1000, out, sizeof(out));
	assert_string_equal(out, "77F#05 201#060000000000 202#060000000000 080#");
	co_drive_read(&BUS, 0, &st);
	assert_true(st.fresh); /* the TPDO1 of the start-up's SYNC */
	assert_int_equal(st.position_counts, 0);
	co_drive_read(&BUS, 0, &st);
	assert_false(st.fresh);
	feed(0x0240, 100, 0x0240, -5, true);
	tick(2000, out, sizeof(out));
	assert_string_equal(out, "201#060000000000 202#060000000000 080#");
	co_drive_read(&BUS, 0, &st);
	assert_true(st.fresh);
	assert_false(st.enabled);
	assert_int_equal(st.position_counts, 100);
	assert_int_equal(st.fault_code, 0);
	co_drive_read(&BUS, 0, &st);
	assert_false(st.fresh); /* one TPDO, one fresh read */
	co_drive_read(&BUS, 1, &st);
	assert_true(st.fresh);
	assert_int_equal(st.position_counts, -5);

	/* Enabled with a setpoint: the velocity stays 0 until the drive
	 * reports Operation enabled (no step as its stage comes on). */
	co_drive_enable(&BUS, 0, true);
	co_drive_set_velocity(&BUS, 0, 256 * 1000 + 128);
	feed(0x0240, 100, 0x0240, -5, false);
	tick(3000, out, sizeof(out));
	assert_string_equal(out, "201#060000000000 202#060000000000 080#");
	co_drive_read(&BUS, 0, &st);
	assert_false(st.enabled); /* the command alone enables nothing */
	assert_int_equal(st.phase, HAL_DRIVE_SWITCH_ON_DISABLED);
	feed(0x0231, 100, 0x0231, -5, false);
	tick(4000, out, sizeof(out));
	assert_string_equal(out, "201#070000000000 202#060000000000 080#");
	co_drive_read(&BUS, 0, &st);
	assert_false(st.enabled);
	assert_int_equal(st.phase, HAL_DRIVE_READY);
	feed(0x0233, 100, 0x0231, -5, false);
	tick(5000, out, sizeof(out));
	assert_string_equal(out, "201#0F0000000000 202#060000000000 080#");
	co_drive_read(&BUS, 0, &st);
	assert_false(st.enabled);
	assert_int_equal(st.phase, HAL_DRIVE_SWITCHED_ON);
	feed(0x0237, 110, 0x0231, -5, false);
	tick(6000, out, sizeof(out));
	assert_string_equal(out, "201#0F00E9030000 202#060000000000 080#");
	co_drive_set_velocity(&BUS, 0, -256 * 20);
	feed(0x0237, 110, 0x0231, -5, false);
	tick(6500, out, sizeof(out));
	assert_string_equal(out, "201#0F00ECFFFFFF 202#060000000000 080#");
	co_drive_read(&BUS, 0, &st);
	assert_true(st.fresh);
	assert_true(st.enabled);
	assert_int_equal(st.phase, HAL_DRIVE_ENABLED);
	assert_int_equal(st.position_counts, 110);
	/* the drive drops to switched on by itself (an STO): reported at
	 * once, and the setpoint is 0 again while the master still asks */
	feed(0x0233, 110, 0x0231, -5, false);
	tick(6800, out, sizeof(out));
	assert_string_equal(out, "201#0F0000000000 202#060000000000 080#");
	co_drive_read(&BUS, 0, &st);
	assert_false(st.enabled);
	assert_int_equal(st.phase, HAL_DRIVE_SWITCHED_ON);
	/* disabled by the firmware: shutdown, velocity 0 */
	co_drive_enable(&BUS, 0, false);
	feed(0x0237, 110, 0x0231, -5, false);
	tick(7000, out, sizeof(out));
	assert_string_equal(out, "201#060000000000 202#060000000000 080#");
	/* the master's heartbeat every 100 ms, SYNC every tick */
	tick(100999, out, sizeof(out));
	assert_string_equal(out, "201#060000000000 202#060000000000 080#");
	tick(101000, out, sizeof(out));
	assert_string_equal(out, "77F#05 201#060000000000 202#060000000000 080#");
}

static void test_bus_heartbeat_loss(void **state)
{
	(void)state;
	char err[256], out[512], log[2048];
	hal_drive_state_t st;
	assert_int_equal(bus_start(0, err, sizeof(err)), 0);
	FK.respond = false;
	capture();
	tick(1000, out, sizeof(out));
	feed(0x0240, 0, 0x0240, 0, true); /* heartbeats heard at 2000 */
	tick(2000, out, sizeof(out));
	co_drive_read(&BUS, 0, &st);
	assert_true(st.fresh);
	feed(0x0240, 0, 0x0240, 0, false);
	tick(2000 + 300000, out, sizeof(out));
	co_drive_read(&BUS, 0, &st);
	assert_true(st.fresh); /* exactly the timeout: still present */
	feed(0x0240, 0, 0x0240, 0, false);
	push(mk(0x702, "05"));
	tick(2000 + 300001, out, sizeof(out));
	co_drive_read(&BUS, 0, &st);
	assert_false(st.fresh); /* TPDO arrives, heartbeat overdue */
	co_drive_read(&BUS, 1, &st);
	assert_true(st.fresh);
	/* heard again */
	feed(0x0240, 0, 0x0240, 0, false);
	push(mk(0x701, "05"));
	tick(400000, out, sizeof(out));
	co_drive_read(&BUS, 0, &st);
	assert_true(st.fresh);
	/* NMT stopped: lost at once */
	feed(0x0240, 0, 0x0240, 0, false);
	push(mk(0x701, "04"));
	push(mk(0x702, "05"));
	tick(401000, out, sizeof(out));
	co_drive_read(&BUS, 0, &st);
	assert_false(st.fresh);
	captured(log, sizeof(log));
	assert_non_null(strstr(log, "vehicle-fw: canopen bus 0 (vcan9): node 1 (axis 0): "
				    "operational\n"));
	assert_non_null(strstr(log, "vehicle-fw: error: canopen bus 0 (vcan9): node 1 (axis 0): "
				    "lost: no heartbeat for more than 300 ms\n"));
	assert_non_null(strstr(log, "vehicle-fw: canopen bus 0 (vcan9): node 1 (axis 0): "
				    "operational again\n"));
	assert_non_null(strstr(log, "vehicle-fw: error: canopen bus 0 (vcan9): node 1 (axis 0): "
				    "lost: heartbeat says NMT state 0x04\n"));
}

static void test_bus_emcy_fault_and_reset(void **state)
{
	(void)state;
	char err[256], out[512], log[2048];
	hal_drive_state_t st;
	assert_int_equal(bus_start(0, err, sizeof(err)), 0);
	FK.respond = false;
	tick(1000, out, sizeof(out));
	feed(0x0237, 0, 0x0237, 0, true);
	tick(2000, out, sizeof(out));
	co_drive_read(&BUS, 0, &st);
	assert_int_equal(st.fault_code, 0);
	/* EMCY, then the statusword's fault: the drive's code */
	capture();
	push(mk(0x081, "102301A1B2C3D4E5"));
	feed(0x0237, 0, 0x0237, 0, false);
	tick(3000, out, sizeof(out));
	co_drive_read(&BUS, 0, &st);
	assert_int_equal(st.fault_code, 0); /* not in fault yet */
	feed(0x021F, 0, 0x0237, 0, false);
	tick(4000, out, sizeof(out));
	co_drive_read(&BUS, 0, &st);
	assert_int_equal(st.fault_code, 0x2310);
	assert_false(st.enabled);
	feed(0x0218, 0, 0x0237, 0, false);
	tick(5000, out, sizeof(out));
	assert_string_equal(out, "201#000000000000 202#060000000000 080#");
	co_drive_read(&BUS, 0, &st);
	assert_int_equal(st.fault_code, 0x2310);
	captured(log, sizeof(log));
	assert_string_equal(log, "vehicle-fw: error: canopen bus 0 (vcan9): node 1 (axis 0): "
				 "EMCY 0x2310, error register 0x01, manufacturer bytes A1 B2 C3 D4 "
				 "E5\n");
	assert_int_equal(BUS.emcy, 1);

	/* fault reset: bit 7 rises and is held while the drive stays in
	 * fault, the code reads 0 meanwhile; at the bound (200 ms from the
	 * request at 5000) it is low again and the fault is reported again */
	co_drive_reset_fault(&BUS, 0);
	co_drive_read(&BUS, 0, &st);
	assert_int_equal(st.fault_code, 0);
	assert_int_equal(st.phase, HAL_DRIVE_FAULT);
	feed(0x0218, 0, 0x0237, 0, false);
	tick(6000, out, sizeof(out));
	assert_string_equal(out, "201#800000000000 202#060000000000 080#");
	feed(0x0218, 0, 0x0237, 0, false);
	tick(7000, out, sizeof(out));
	assert_string_equal(out, "201#800000000000 202#060000000000 080#");
	co_drive_read(&BUS, 0, &st);
	assert_int_equal(st.fault_code, 0);
	feed(0x0218, 0, 0x0237, 0, false);
	tick(5000 + 200000 - 1, out, sizeof(out));
	assert_string_equal(out, "201#800000000000 202#060000000000 080#");
	co_drive_read(&BUS, 0, &st);
	assert_int_equal(st.fault_code, 0);
	feed(0x0218, 0, 0x0237, 0, false);
	tick(5000 + 200000, out, sizeof(out));
	assert_string_equal(out, "201#000000000000 202#060000000000 080#");
	co_drive_read(&BUS, 0, &st);
	assert_int_equal(st.fault_code, 0x2310);
	/* a new request: low for that SYNC, so this is a new rising edge */
	co_drive_reset_fault(&BUS, 0);
	feed(0x0218, 0, 0x0237, 0, false);
	tick(206000, out, sizeof(out));
	assert_string_equal(out, "201#800000000000 202#060000000000 080#");
	/* the drive leaves fault: the bit drops with the first statusword
	 * that says so */
	feed(0x0240, 0, 0x0237, 0, false);
	tick(207000, out, sizeof(out));
	assert_string_equal(out, "201#060000000000 202#060000000000 080#");
	assert_false(BUS.d[0].reset_req);
	/* out of fault: the code is forgotten; a fault without EMCY: generic */
	feed(0x0240, 0, 0x0237, 0, false);
	tick(300000, out, sizeof(out));
	co_drive_read(&BUS, 0, &st);
	assert_int_equal(st.fault_code, 0);
	feed(0x0218, 0, 0x0237, 0, false);
	tick(301000, out, sizeof(out));
	co_drive_read(&BUS, 0, &st);
	assert_int_equal(st.fault_code, CO_GENERIC_FAULT);
	/* EMCY 0x0000 (error reset) forgets the code too */
	push(mk(0x082, "103201"));
	feed(0x0218, 0, 0x0218, 0, false);
	tick(302000, out, sizeof(out));
	co_drive_read(&BUS, 1, &st);
	assert_int_equal(st.fault_code, 0x3210);
	push(mk(0x082, "0000000000000000"));
	feed(0x0218, 0, 0x0218, 0, false);
	tick(303000, out, sizeof(out));
	co_drive_read(&BUS, 1, &st);
	assert_int_equal(st.fault_code, CO_GENERIC_FAULT);
	/* a reset request while not in fault sends no 0x80 */
	co_drive_reset_fault(&BUS, 0);
	feed(0x0240, 0, 0x0218, 0, false);
	tick(304000, out, sizeof(out));
	tick(305000, out, sizeof(out));
	assert_string_equal(out, "201#060000000000 202#000000000000 080#");
}

static void test_bus_restarted_drive(void **state)
{
	(void)state;
	char err[256], out[512], log[4096];
	hal_drive_state_t st;
	assert_int_equal(bus_start(0, err, sizeof(err)), 0);
	FK.respond = false;
	tick(1000, out, sizeof(out));
	feed(0x0240, 1000, 0x0240, 0, true);
	tick(2000, out, sizeof(out));
	co_drive_read(&BUS, 0, &st);
	assert_int_equal(st.position_counts, 1000);
	/* node 1 boots again: configured again in the tick, one SDO per tick */
	FK.respond = true;
	capture();
	push(mk(0x701, "00"));
	feed(0x0240, 1000, 0x0240, 0, false);
	tick(3000, out, sizeof(out));
	assert_string_equal(out, "601#4000100000000000 202#060000000000 080#");
	co_drive_read(&BUS, 0, &st);
	assert_false(st.fresh);
	assert_false(st.position_lost); /* with the first sample, not before */
	assert_int_equal(st.phase, HAL_DRIVE_NOT_OPERATIONAL);
	uint32_t t = 4000;
	for (unsigned i = 1; i < 20; i++, t += 1000) {
		tick(t, out, sizeof(out));
		assert_int_equal(strncmp(out, "601#", 4), 0);
	}
	assert_string_equal(out, "601#2B17100064000000 202#060000000000 080#");
	tick(t, out, sizeof(out));
	assert_string_equal(out, "000#0101 201#060000000000 202#060000000000 080#");
	/* its position continues from the last one reported, and the first
	 * sample says the position is lost, once */
	feed(0x0240, 0, 0x0240, 0, false);
	push(mk(0x701, "05"));
	tick(t + 1000, out, sizeof(out));
	co_drive_read(&BUS, 0, &st);
	assert_true(st.fresh);
	assert_true(st.position_lost);
	assert_int_equal(st.position_counts, 1000);
	co_drive_read(&BUS, 1, &st);
	assert_false(st.position_lost); /* the other drive did not restart */
	feed(0x0240, 25, 0x0240, 0, false);
	tick(t + 2000, out, sizeof(out));
	co_drive_read(&BUS, 0, &st);
	assert_true(st.fresh);
	assert_false(st.position_lost);
	assert_int_equal(st.position_counts, 1025);
	assert_int_equal(BUS.d[0].restarts, 1);

	/* pre-operational after operational: configured again as well; an
	 * abort then waits CO_RETRY_US before the next attempt */
	FK.abort_index = 0x6060;
	FK.abort_code = 0x06090030;
	push(mk(0x702, "05"));
	tick(t + 3000, out, sizeof(out));
	push(mk(0x702, "7F"));
	tick(t + 4000, out, sizeof(out));
	assert_string_equal(out, "602#4000100000000000 201#060000000000 080#");
	for (unsigned i = 0; i < 3; i++)
		tick(t + 5000 + i * 1000, out, sizeof(out));
	assert_string_equal(out, "602#2F60600003000000 201#060000000000 080#");
	tick(t + 8000, out, sizeof(out));
	assert_string_equal(out, "201#060000000000 080#");
	tick(t + 8000 + CO_RETRY_US - 1, out, sizeof(out));
	assert_string_equal(out, "201#060000000000 080#");
	/* a drive that does not answer: no reply within sdo_timeout_ms */
	FK.abort_index = 0xFFFF;
	FK.silent_index = 0x1000;
	tick(t + 8000 + CO_RETRY_US, out, sizeof(out));
	assert_string_equal(out, "602#4000100000000000 201#060000000000 080#");
	tick(t + 8000 + CO_RETRY_US + 5000, out, sizeof(out));
	assert_string_equal(out, "201#060000000000 080#");
	assert_true(BUS.d[1].sdo_pending);
	tick(t + 8000 + CO_RETRY_US + 5001, out, sizeof(out));
	assert_string_equal(out, "201#060000000000 080#");
	assert_false(BUS.d[1].sdo_pending);
	captured(log, sizeof(log));
	assert_string_equal(
	    log, "vehicle-fw: warning: canopen bus 0 (vcan9): node 1 (axis 0): boot-up message "
		 "(the drive restarted): configuring it again\n"
		 "vehicle-fw: canopen bus 0 (vcan9): node 1 (axis 0): configured again and "
		 "started\n"
		 "vehicle-fw: canopen bus 0 (vcan9): node 1 (axis 0): operational\n"
		 "vehicle-fw: warning: canopen bus 0 (vcan9): node 2 (axis 1): pre-operational "
		 "after operational: configuring it again\n"
		 "vehicle-fw: error: canopen bus 0 (vcan9): node 2 (axis 1): SDO write 0x6060:00 "
		 "aborted with 0x06090030 (invalid value for the parameter); again every 1000 "
		 "ms\n"
		 "vehicle-fw: error: canopen bus 0 (vcan9): node 1 (axis 0): lost: no heartbeat "
		 "for more than 300 ms\n");
}

/* 0x6061 must confirm profile velocity before the drive counts as enabled:
 * otherwise it is held switched on (0x07), gets velocity 0, reads not
 * enabled, and the reason is logged once per occurrence. */
static void test_bus_mode_not_confirmed(void **state)
{
	(void)state;
	char err[256], out[512], log[2048];
	hal_drive_state_t st;
	assert_int_equal(bus_start(0, err, sizeof(err)), 0);
	FK.respond = false;
	tick(1000, out, sizeof(out));
	MODE[0] = 1; /* profile position */
	co_drive_enable(&BUS, 0, true);
	co_drive_set_velocity(&BUS, 0, 256 * 500);
	capture();
	feed(0x0233, 7, 0x0240, 0, true);
	tick(2000, out, sizeof(out));
	assert_string_equal(out, "201#070000000000 202#060000000000 080#");
	feed(0x0233, 7, 0x0240, 0, false);
	tick(3000, out, sizeof(out));
	assert_string_equal(out, "201#070000000000 202#060000000000 080#");
	co_drive_read(&BUS, 0, &st);
	assert_true(st.fresh);
	assert_false(st.enabled);
	assert_int_equal(st.phase, HAL_DRIVE_SWITCHED_ON);
	/* in Operation enabled by some other hand, still mode 1: disable
	 * operation, not enabled, no velocity */
	feed(0x0237, 7, 0x0240, 0, false);
	tick(4000, out, sizeof(out));
	assert_string_equal(out, "201#070000000000 202#060000000000 080#");
	co_drive_read(&BUS, 0, &st);
	assert_false(st.enabled);
	assert_int_equal(st.phase, HAL_DRIVE_ENABLED);
	/* the mode confirms: enable operation, then enabled, then velocity */
	MODE[0] = 3;
	feed(0x0233, 7, 0x0240, 0, false);
	tick(5000, out, sizeof(out));
	assert_string_equal(out, "201#0F0000000000 202#060000000000 080#");
	co_drive_read(&BUS, 0, &st);
	assert_false(st.enabled);
	feed(0x0237, 7, 0x0240, 0, false);
	tick(6000, out, sizeof(out));
	assert_string_equal(out, "201#0F00F4010000 202#060000000000 080#");
	co_drive_read(&BUS, 0, &st);
	assert_true(st.enabled);
	/* it changes under way: not enabled at once, logged again */
	MODE[0] = 0;
	feed(0x0237, 7, 0x0240, 0, false);
	tick(7000, out, sizeof(out));
	assert_string_equal(out, "201#070000000000 202#060000000000 080#");
	co_drive_read(&BUS, 0, &st);
	assert_false(st.enabled);
	assert_int_equal(st.phase, HAL_DRIVE_ENABLED);
	captured(log, sizeof(log));
	assert_string_equal(log, "vehicle-fw: warning: canopen bus 0 (vcan9): node 1 (axis 0): "
				 "modes of operation display 0x6061 reads 1, not 3 (profile "
				 "velocity): held switched on, not enabled\n"
				 "vehicle-fw: warning: canopen bus 0 (vcan9): node 1 (axis 0): "
				 "modes of operation display 0x6061 reads 0, not 3 (profile "
				 "velocity): held switched on, not enabled\n");
}

/* A heartbeat that says stopped: not operational, not enabled whatever
 * the last statusword said, and velocity 0. */
static void test_bus_not_operational(void **state)
{
	(void)state;
	char err[256], out[512];
	hal_drive_state_t st;
	assert_int_equal(bus_start(0, err, sizeof(err)), 0);
	FK.respond = false;
	tick(1000, out, sizeof(out));
	co_drive_enable(&BUS, 1, true);
	co_drive_set_velocity(&BUS, 1, 256 * 100);
	feed(0x0240, 0, 0x0237, 0, true);
	tick(2000, out, sizeof(out));
	assert_string_equal(out, "201#060000000000 202#0F0064000000 080#");
	co_drive_read(&BUS, 1, &st);
	assert_true(st.enabled);
	assert_int_equal(st.phase, HAL_DRIVE_ENABLED);
	feed(0x0240, 0, 0x0237, 0, false);
	push(mk(0x702, "04"));
	tick(3000, out, sizeof(out));
	assert_string_equal(out, "201#060000000000 202#0F0000000000 080#");
	co_drive_read(&BUS, 1, &st);
	assert_false(st.fresh);
	assert_false(st.enabled);
	assert_int_equal(st.phase, HAL_DRIVE_NOT_OPERATIONAL);
	co_drive_read(&BUS, 0, &st);
	assert_int_equal(st.phase, HAL_DRIVE_SWITCH_ON_DISABLED);
	/* operational again: its statusword counts again */
	feed(0x0240, 0, 0x0237, 0, false);
	push(mk(0x702, "05"));
	tick(4000, out, sizeof(out));
	assert_string_equal(out, "201#060000000000 202#0F0064000000 080#");
	co_drive_read(&BUS, 1, &st);
	assert_true(st.fresh);
	assert_true(st.enabled);
	assert_int_equal(st.phase, HAL_DRIVE_ENABLED);
}

/* Node 1's heartbeat says hb (boot-up or pre-operational) at now_us: it
 * is configured again, one SDO per tick, and started; returns the time of
 * the tick after NMT start. */
static uint32_t reconfigure_node1(uint32_t now_us, const char *hb)
{
	char out[512];
	hal_drive_state_t st;
	FK.respond = true;
	FK.no_tpdo = true; /* the test feeds the TPDOs itself */
	push(mk(0x701, hb));
	for (unsigned i = 0; i < 20; i++, now_us += 1000) {
		tick(now_us, out, sizeof(out));
		assert_int_equal(strncmp(out, "601#", 4), 0);
		co_drive_read(&BUS, 0, &st);
		assert_false(st.fresh);
		assert_false(st.enabled);
		assert_false(st.position_lost);
		assert_int_equal(st.phase, HAL_DRIVE_NOT_OPERATIONAL);
	}
	tick(now_us, out, sizeof(out));
	assert_string_equal(out, "000#0101 201#060000000000 202#060000000000 080#");
	FK.respond = false;
	return now_us + 1000;
}

/* A drive that drops to pre-operational by itself (its heartbeat consumer
 * timed out) and comes back without restarting keeps its count: what it
 * travelled meanwhile stays in the position. Only a boot-up message
 * re-bases the count and reports the position lost, once. */
static void test_bus_comeback_keeps_count(void **state)
{
	(void)state;
	char err[256], out[512], log[2048];
	hal_drive_state_t st;
	assert_int_equal(bus_start(0, err, sizeof(err)), 0);
	FK.respond = false;
	tick(1000, out, sizeof(out));
	feed(0x0240, 1000, 0x0240, 0, true);
	tick(2000, out, sizeof(out));
	co_drive_read(&BUS, 0, &st);
	assert_int_equal(st.position_counts, 1000);
	capture();
	/* it leaves operational by itself: configured again, no re-base */
	uint32_t t = reconfigure_node1(3000, "7F");
	/* the wheel went on 61 counts while nobody watched */
	feed(0x0240, 1061, 0x0240, 0, false);
	push(mk(0x701, "05"));
	tick(t, out, sizeof(out));
	co_drive_read(&BUS, 0, &st);
	assert_true(st.fresh);
	assert_false(st.position_lost);
	assert_int_equal(st.position_counts, 1061);
	assert_int_equal(st.phase, HAL_DRIVE_SWITCH_ON_DISABLED);
	/* now it really restarts: its count starts over at 0, the reported
	 * one goes on from 1061 and says lost, on one read */
	t = reconfigure_node1(t + 1000, "00");
	feed(0x0240, 0, 0x0240, 0, false);
	push(mk(0x701, "05"));
	tick(t, out, sizeof(out));
	co_drive_read(&BUS, 0, &st);
	assert_true(st.fresh);
	assert_true(st.position_lost);
	assert_int_equal(st.position_counts, 1061);
	feed(0x0240, 40, 0x0240, 0, false);
	tick(t + 1000, out, sizeof(out));
	co_drive_read(&BUS, 0, &st);
	assert_false(st.position_lost);
	assert_int_equal(st.position_counts, 1101);
	/* and leaves operational again: the offset of the restart stays, the
	 * drive's 0x6064 goes on from 40 to 95 */
	push(mk(0x701, "05"));
	tick(t + 2000, out, sizeof(out));
	t = reconfigure_node1(t + 3000, "7F");
	feed(0x0240, 95, 0x0240, 0, false);
	push(mk(0x701, "05"));
	tick(t, out, sizeof(out));
	co_drive_read(&BUS, 0, &st);
	assert_true(st.fresh);
	assert_false(st.position_lost);
	assert_int_equal(st.position_counts, 1156);
	assert_int_equal(BUS.d[0].restarts, 3);
	captured(log, sizeof(log));
	assert_non_null(strstr(log, "vehicle-fw: warning: canopen bus 0 (vcan9): node 1 (axis 0): "
				    "pre-operational after operational: configuring it again\n"));
	assert_non_null(strstr(log,
			       "vehicle-fw: warning: canopen bus 0 (vcan9): node 1 (axis 0): "
			       "boot-up message (the drive restarted): configuring it again\n"));
}

/* Polarity reverse: the master negates velocity and position itself. */
static void test_bus_polarity(void **state)
{
	(void)state;
	char err[256], out[512];
	hal_drive_state_t st;
	fake_reset();
	static const uint8_t two[] = {1, 2};
	REVERSE[0] = true;
	assert_int_equal(start_nodes(0, two, 2, err, sizeof(err)), 0);
	FK.respond = false;
	tick(1000, out, sizeof(out));
	co_drive_enable(&BUS, 0, true);
	co_drive_enable(&BUS, 1, true);
	co_drive_set_velocity(&BUS, 0, 256 * 1000);
	co_drive_set_velocity(&BUS, 1, 256 * 1000);
	feed(0x0237, 1000, 0x0237, 1000, true);
	tick(2000, out, sizeof(out));
	assert_string_equal(out, "201#0F0018FCFFFF 202#0F00E8030000 080#");
	co_drive_read(&BUS, 0, &st);
	assert_int_equal(st.position_counts, -1000);
	co_drive_read(&BUS, 1, &st);
	assert_int_equal(st.position_counts, 1000);
	/* the count wraps as the drive's does */
	feed(0x0237, INT32_MIN, 0x0237, INT32_MIN, false);
	co_drive_set_velocity(&BUS, 0, -256 * 7);
	tick(3000, out, sizeof(out));
	assert_string_equal(out, "201#0F0007000000 202#0F00E8030000 080#");
	co_drive_read(&BUS, 0, &st);
	assert_int_equal(st.position_counts, INT32_MIN);
	feed(0x0237, INT32_MIN + 1, 0x0237, 0, false);
	tick(4000, out, sizeof(out));
	co_drive_read(&BUS, 0, &st);
	assert_int_equal(st.position_counts, INT32_MAX);
}

/* A reset requested during the fault reaction waits for Fault, then rises
 * and is held; the request bound runs from the request. */
static void test_bus_fault_reset_waits_reaction(void **state)
{
	(void)state;
	char err[256], out[512];
	hal_drive_state_t st;
	assert_int_equal(bus_start(0, err, sizeof(err)), 0);
	FK.respond = false;
	tick(1000, out, sizeof(out));
	feed(0x021F, 0, 0x0240, 0, true);
	tick(2000, out, sizeof(out));
	co_drive_read(&BUS, 0, &st);
	assert_int_equal(st.fault_code, CO_GENERIC_FAULT);
	assert_int_equal(st.phase, HAL_DRIVE_FAULT_REACTION);
	co_drive_reset_fault(&BUS, 0);
	feed(0x021F, 0, 0x0240, 0, false);
	tick(3000, out, sizeof(out));
	assert_string_equal(out, "201#000000000000 202#060000000000 080#");
	co_drive_read(&BUS, 0, &st);
	assert_int_equal(st.fault_code, 0);
	for (uint32_t t = 4000; t <= 6000; t += 1000) {
		feed(0x0218, 0, 0x0240, 0, false);
		tick(t, out, sizeof(out));
		assert_string_equal(out, "201#800000000000 202#060000000000 080#");
	}
	feed(0x0240, 0, 0x0240, 0, false);
	tick(7000, out, sizeof(out));
	assert_string_equal(out, "201#060000000000 202#060000000000 080#");
	co_drive_read(&BUS, 0, &st);
	assert_int_equal(st.fault_code, 0);
	assert_int_equal(st.phase, HAL_DRIVE_SWITCH_ON_DISABLED);
	/* a drive that stays in fault reaction past the bound (200 ms from
	 * the request at 7000): never a rising edge into the reaction, and
	 * the fault reads again at the bound */
	feed(0x021F, 0, 0x0240, 0, false);
	tick(7500, out, sizeof(out));
	co_drive_reset_fault(&BUS, 0);
	feed(0x021F, 0, 0x0240, 0, false);
	tick(7500 + 199999, out, sizeof(out));
	assert_string_equal(out, "201#000000000000 202#060000000000 080#");
	co_drive_read(&BUS, 0, &st);
	assert_int_equal(st.fault_code, 0);
	feed(0x021F, 0, 0x0240, 0, false);
	tick(7500 + 200000, out, sizeof(out));
	co_drive_read(&BUS, 0, &st);
	assert_int_equal(st.fault_code, CO_GENERIC_FAULT);
	assert_false(BUS.d[0].reset_req);
}

/* <backends>: one <drive> per axis, the polarity and the fault reset
 * bound (the rest of the parser: tests/test_linux_fw.c). */
static void load_backends(const char *body, backend_cfg_t *b, char *err, size_t len, int want)
{
	char path[] = "/tmp/vscfgXXXXXX";
	int fd = mkstemp(path);
	assert_true(fd >= 0);
	FILE *f = fdopen(fd, "w");
	assert_non_null(f);
	fprintf(f,
		"<vehicle kinematics=\"differential\" tick_hz=\"100\">\n"
		"  <devices contact_sensor=\"false\" obstacle_input=\"false\" estop=\"false\"\n"
		"           joystick=\"false\"/>\n"
		"  <backends>\n"
		"    <canopen bus=\"0\" interface=\"can0\"/>\n"
		"%s"
		"  </backends>\n"
		"</vehicle>\n",
		body);
	fclose(f);
	err[0] = '\0';
	int rc = backend_cfg_load(path, b, err, len);
	if (rc != want)
		fail_msg("%s: %d (%s), expected %d", body, rc, err, want);
	/* the message without the temporary file's name */
	size_t n = strlen(path);
	if (!strncmp(err, path, n))
		memmove(err, err + n, strlen(err + n) + 1);
	unlink(path);
}

static void test_backends_drive(void **state)
{
	(void)state;
	backend_cfg_t b;
	char err[256];
	/* a second <drive> for an axis is refused, not silently taken */
	load_backends("    <drive axis=\"0\" type=\"cia402\" bus=\"0\" node=\"1\"/>\n"
		      "    <drive axis=\"1\" type=\"cia402\" bus=\"0\" node=\"2\"/>\n"
		      "    <drive axis=\"0\" type=\"loopback\"/>\n",
		      &b, err, sizeof(err), -1);
	assert_string_equal(err, ":8: drive.axis: duplicate '0'");
	load_backends("    <drive axis=\"1\" type=\"cia402\" bus=\"0\" node=\"2\"/>\n"
		      "    <drive axis=\"1\" type=\"cia402\" bus=\"0\" node=\"3\"/>\n",
		      &b, err, sizeof(err), -1);
	assert_string_equal(err, ":7: drive.axis: duplicate '1'");
	/* polarity */
	load_backends(
	    "    <modbus bus=\"1\" device=\"/dev/ttyUSB0\" reg_target_speed=\"0\"\n"
	    "            reg_position=\"2\" reg_status=\"4\" reg_alarm=\"5\"\n"
	    "            reg_servo_on=\"6\" reg_fault_reset=\"7\" reg_comm_timeout=\"8\"/>\n"
	    "    <drive axis=\"0\" type=\"cia402\" bus=\"0\" node=\"1\" "
	    "polarity=\"reverse\"/>\n"
	    "    <drive axis=\"1\" type=\"cia402\" bus=\"0\" node=\"2\" "
	    "polarity=\"normal\"/>\n"
	    "    <drive axis=\"2\" type=\"modbus\" bus=\"1\" unit=\"4\" "
	    "polarity=\"reverse\"/>\n"
	    "    <drive axis=\"3\" type=\"modbus\" bus=\"1\" unit=\"5\"/>\n",
	    &b, err, sizeof(err), 0);
	assert_true(b.drive_reverse[0]);
	assert_false(b.drive_reverse[1]);
	assert_true(b.drive_reverse[2]);
	assert_false(b.drive_reverse[3]);
	assert_int_equal(b.drive_type[2], BK_DRIVE_MODBUS);
	assert_int_equal(b.canopen[0].fault_reset_ms, 200);
	load_backends("    <drive axis=\"0\" type=\"cia402\" bus=\"0\" node=\"1\" "
		      "polarity=\"mirrored\"/>\n",
		      &b, err, sizeof(err), -1);
	assert_string_equal(err, ":6: drive.polarity: normal or reverse 'mirrored'");
	load_backends("    <drive axis=\"0\" type=\"loopback\" polarity=\"reverse\"/>\n", &b, err,
		      sizeof(err), -1);
	assert_string_equal(err, ":6: drive.polarity: only for modbus and cia402");
	/* the fault reset bound */
	load_backends("    <canopen bus=\"1\" interface=\"can1\" fault_reset_ms=\"1500\"/>\n", &b,
		      err, sizeof(err), 0);
	assert_int_equal(b.canopen[1].fault_reset_ms, 1500);
	load_backends("    <canopen bus=\"1\" interface=\"can1\" fault_reset_ms=\"9\"/>\n", &b, err,
		      sizeof(err), -1);
	assert_string_equal(err, ":6: canopen.fault_reset_ms: out of range 10..10000 '9'");
}

static void test_bus_send_errors(void **state)
{
	(void)state;
	char err[256], out[512], log[2048], cnt[200];
	assert_int_equal(bus_start(0, err, sizeof(err)), 0);
	FK.respond = false;
	unsigned sent = BUS.tx, got = BUS.rx;
	/* queue full: counted, not retried in the tick */
	FK.send_mode = 0;
	FK.attempts = 0;
	tick(1000, out, sizeof(out));
	assert_int_equal(FK.attempts, 3);
	assert_int_equal(BUS.tx_full, 3);
	assert_false(BUS.down);
	/* interface down: counted, logged once; up again: logged */
	capture();
	FK.send_mode = ENETDOWN;
	tick(2000, out, sizeof(out));
	tick(3000, out, sizeof(out));
	assert_int_equal(FK.attempts, 9);
	assert_int_equal(BUS.tx_down, 6);
	assert_true(BUS.down);
	FK.send_mode = 1;
	tick(4000, out, sizeof(out));
	assert_false(BUS.down);
	/* receive side: ENETDOWN from the socket too */
	FK.recv_errno = ENETDOWN;
	FK.send_mode = EIO;
	tick(5000, out, sizeof(out));
	assert_true(BUS.down);
	assert_int_equal(BUS.tx_errors, 3);
	FK.recv_errno = EIO;
	FK.send_mode = 1;
	tick(6000, out, sizeof(out));
	captured(log, sizeof(log));
	assert_string_equal(log, "vehicle-fw: error: canopen bus 0 (vcan9): interface is down: "
				 "no frames go out or arrive\n"
				 "vehicle-fw: canopen bus 0 (vcan9): interface is up again\n"
				 "vehicle-fw: error: canopen bus 0 (vcan9): interface is down: "
				 "no frames go out or arrive\n"
				 "vehicle-fw: canopen bus 0 (vcan9): interface is up again\n");
	assert_int_equal(BUS.rx_errors, 1);
	/* frames of other nodes (the filters normally keep them out) */
	push(mk(0x185, "370200000000"));
	push(mk(0x181, "3702"));
	tick(7000, out, sizeof(out));
	assert_int_equal(BUS.rx_bad, 2);
	co_bus_counters(&BUS, cnt, sizeof(cnt));
	char want[200];
	snprintf(want, sizeof(want),
		 "canopen0 vcan9 tx %u tx_full 3 tx_down 6 tx_errors 3 rx %u rx_errors 1 emcy 0",
		 sent + 9, got + 2);
	assert_string_equal(cnt, want);
}

static void test_bus_close(void **state)
{
	(void)state;
	char err[256], out[512];
	assert_int_equal(bus_start(127, err, sizeof(err)), 0);
	tick(1000, out, sizeof(out));
	unsigned from = FK.ntx;
	co_bus_close(&BUS);
	/* shutdown, velocity 0, the consumer off, then pre-operational */
	assert_int_equal(FK.ntx - from, 8);
	assert_frame(&FK.tx[from + 0], "601#2B40600006000000");
	assert_frame(&FK.tx[from + 1], "601#23FF600000000000");
	assert_frame(&FK.tx[from + 2], "601#2316100100000000");
	assert_frame(&FK.tx[from + 3], "000#8001");
	assert_frame(&FK.tx[from + 7], "000#8002");
	assert_false(BUS.used);
	co_bus_close(&BUS); /* twice: nothing more */
	assert_int_equal(FK.ntx - from, 8);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test(test_sdo_request_frames),
	    cmocka_unit_test(test_sdo_reply_decode),
	    cmocka_unit_test(test_sdo_abort_text),
	    cmocka_unit_test(test_statusword),
	    cmocka_unit_test(test_controlword),
	    cmocka_unit_test(test_velocity_units),
	    cmocka_unit_test(test_pdo_nmt_frames),
	    cmocka_unit_test(test_emcy_decode),
	    cmocka_unit_test(test_heartbeat_timeout),
	    cmocka_unit_test(test_config_list),
	    cmocka_unit_test(test_bus_startup_sequence),
	    cmocka_unit_test(test_bus_startup_errors),
	    cmocka_unit_test(test_bus_tick_enable_sequence),
	    cmocka_unit_test(test_bus_heartbeat_loss),
	    cmocka_unit_test(test_bus_emcy_fault_and_reset),
	    cmocka_unit_test(test_bus_restarted_drive),
	    cmocka_unit_test(test_bus_mode_not_confirmed),
	    cmocka_unit_test(test_bus_not_operational),
	    cmocka_unit_test(test_bus_comeback_keeps_count),
	    cmocka_unit_test(test_bus_polarity),
	    cmocka_unit_test(test_bus_fault_reset_waits_reaction),
	    cmocka_unit_test(test_backends_drive),
	    cmocka_unit_test(test_bus_send_errors),
	    cmocka_unit_test(test_bus_close),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
