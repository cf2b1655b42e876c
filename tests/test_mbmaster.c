/* The board's Modbus RTU master (hal/modbus/mbmaster.h) on a scripted
 * port: the frames it sends byte for byte (CRC low byte first), the
 * 3.5-character gap before each, the driver enable around the frame, the
 * reply taken in pieces, the response timeout, a cut reply, a bad CRC,
 * exceptions (1 and 2 not retried, 6 retried), late bytes dropped, the
 * retries counted; then the drive bus's cycle (set-up, enable, speed,
 * sample), a drive's alarm and silence as the tick reads them, the probe of
 * a silent drive, and the drive cycle's period and the line check. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <string.h>

#include <cmocka.h>

#include "../hal/modbus/mbmaster.h"

/* ---- a scripted port ---------------------------------------------------- */

static uint8_t rxq[256];
static size_t rx_n, rx_at, rx_chunk; /* rx_chunk: bytes a read gives (0: all) */
static uint8_t txlog[512];
static size_t tx_n;
static bool tx_busy; /* the transmitter still sending */
static char delog[64];
static size_t de_n;

static size_t f_read(void *ctx, uint8_t *buf, size_t max)
{
	(void)ctx;
	size_t n = rx_n - rx_at;
	if (rx_chunk && n > rx_chunk)
		n = rx_chunk;
	if (n > max)
		n = max;
	memcpy(buf, rxq + rx_at, n);
	rx_at += n;
	return n;
}

static void f_write(void *ctx, const uint8_t *buf, size_t n)
{
	(void)ctx;
	memcpy(txlog + tx_n, buf, n);
	tx_n += n;
	delog[de_n++] = 'w';
}

static bool f_tx_done(void *ctx)
{
	(void)ctx;
	return !tx_busy;
}

static void f_de(void *ctx, bool on)
{
	(void)ctx;
	delog[de_n++] = on ? '1' : '0';
}

static const mbm_port_t port = {f_read, f_write, f_tx_done, f_de, NULL};

static int setup(void **state)
{
	(void)state;
	rx_n = rx_at = rx_chunk = tx_n = de_n = 0;
	tx_busy = false;
	memset(delog, 0, sizeof delog);
	return 0;
}

static void arrive(const uint8_t *b, size_t n)
{
	memcpy(rxq + rx_n, b, n);
	rx_n += n;
}

/* The bytes sent since the last call are exactly f. */
static void sent(const uint8_t *f, size_t n)
{
	assert_int_equal(tx_n, n);
	assert_memory_equal(txlog, f, n);
	tx_n = 0;
}

static const uint8_t RD[] = {0x01, 0x03, 0x01, 0x02, 0x00, 0x04, 0xE4, 0x35};
static const uint8_t RD_REPLY[] = {0x01, 0x03, 0x08, 0x00, 0x01, 0xE2, 0x40,
				   0x00, 0x01, 0x00, 0x00, 0xC2, 0x9A};
static const uint8_t EXC2[] = {0x01, 0x83, 0x02, 0xC0, 0xF1};
static const uint8_t EXC6[] = {0x01, 0x83, 0x06, 0xC1, 0x32};

#define TIMEOUT 50000u

static void test_crc(void **state)
{
	(void)state;
	static const uint8_t f[] = {0x01, 0x03, 0x00, 0x00, 0x00, 0x01};
	assert_int_equal(mbm_crc(f, sizeof f), 0x0A84);
	assert_int_equal(mbm_char_us(115200, 10), 87);
	assert_int_equal(mbm_char_us(9600, 11), 1146);
}

/* 115200 baud: the gap is 1750 us (fixed above 19200), a reply's bytes at
 * most 5 ms apart (the floor); at 9600 baud 3.5 characters of 11 bits and
 * the floor again (4 characters: 4.6 ms); at 2400 baud 4 characters. */
static void test_gap_and_frame(void **state)
{
	(void)state;
	mbm_t m;
	mbm_init(&m, &port, 115200, 10, TIMEOUT, 1, 1000);
	assert_int_equal(m.gap_us, 1750);
	assert_int_equal(m.byte_us, 5000);
	assert_true(mbm_read(&m, 1, false, 0x102, 4));
	assert_false(mbm_read(&m, 1, false, 0x102, 4)); /* one at a time */
	assert_int_equal(mbm_poll(&m, 2749), MBM_BUSY);
	assert_int_equal(tx_n, 0); /* the line not yet silent for the gap */
	tx_busy = true;
	assert_int_equal(mbm_poll(&m, 2750), MBM_BUSY);
	sent(RD, sizeof RD);
	assert_string_equal(delog, "1w");
	assert_int_equal(mbm_poll(&m, 2800), MBM_BUSY);
	assert_string_equal(delog, "1w"); /* driver on until the last bit */
	tx_busy = false;
	assert_int_equal(mbm_poll(&m, 3000), MBM_BUSY);
	assert_string_equal(delog, "1w0");
	/* the reply in pieces of 5 bytes */
	rx_chunk = 5;
	arrive(RD_REPLY, sizeof RD_REPLY);
	assert_int_equal(mbm_poll(&m, 3500), MBM_BUSY);
	assert_int_equal(mbm_poll(&m, 3900), MBM_BUSY);
	assert_int_equal(mbm_poll(&m, 4300), MBM_OK);
	assert_int_equal(mbm_reg(&m, 0), 0x0001);
	assert_int_equal(mbm_reg(&m, 1), 0xE240);
	assert_int_equal(mbm_reg(&m, 2), 0x0001);
	assert_int_equal(mbm_reg(&m, 3), 0x0000);
	assert_int_equal(m.cnt.requests, 1);
	assert_int_equal(m.cnt.retries, 0);
	/* the next request waits the gap after the reply's last byte */
	assert_true(mbm_read(&m, 1, false, 0x102, 4));
	assert_int_equal(mbm_poll(&m, 6049), MBM_BUSY);
	assert_int_equal(tx_n, 0);
	assert_int_equal(mbm_poll(&m, 6050), MBM_BUSY);
	sent(RD, sizeof RD);

	mbm_init(&m, &port, 9600, 11, TIMEOUT, 1, 0);
	assert_int_equal(m.gap_us, 4011);
	assert_int_equal(m.byte_us, 5000);
	mbm_init(&m, &port, 2400, 11, TIMEOUT, 1, 0);
	assert_int_equal(m.byte_us, 18333);
}

/* Sends the request at t (the gap passed) and ends the transmission. */
static uint32_t send_at(mbm_t *m, uint32_t t)
{
	assert_int_equal(mbm_poll(m, t), MBM_BUSY);
	assert_int_equal(mbm_poll(m, t), MBM_BUSY);
	return t;
}

/* No reply: a timeout after exactly timeout_us, the request again after
 * the gap, then the result; every attempt counted. */
static void test_timeout_and_retry(void **state)
{
	(void)state;
	mbm_t m;
	mbm_init(&m, &port, 115200, 10, TIMEOUT, 1, 0);
	assert_true(mbm_read(&m, 1, false, 0x102, 4));
	uint32_t t = send_at(&m, 2000);
	sent(RD, sizeof RD);
	assert_int_equal(mbm_poll(&m, t + TIMEOUT - 1), MBM_BUSY);
	assert_int_equal(mbm_poll(&m, t + TIMEOUT), MBM_BUSY); /* retried */
	assert_int_equal(m.cnt.timeouts, 1);
	assert_int_equal(m.cnt.retries, 1);
	/* a late answer is read and dropped; the retry waits for the line to
	 * be silent for the byte timeout (5 ms) after it */
	arrive(RD_REPLY, 4);
	assert_int_equal(mbm_poll(&m, t + TIMEOUT + 1000), MBM_BUSY);
	assert_int_equal(mbm_poll(&m, t + TIMEOUT + 5999), MBM_BUSY);
	assert_int_equal(tx_n, 0);
	t = send_at(&m, t + TIMEOUT + 6000);
	sent(RD, sizeof RD);
	assert_int_equal(mbm_poll(&m, t + TIMEOUT), MBM_NO_REPLY);
	assert_int_equal(m.cnt.requests, 2);
	assert_int_equal(m.cnt.timeouts, 2);
	assert_int_equal(mbm_poll(&m, t + 2 * TIMEOUT), MBM_BUSY); /* idle */
}

/* A reply that stops: cut after 5 ms of silence, counted as a timeout; a
 * bad CRC, then a good reply on the retry. */
static void test_cut_and_crc(void **state)
{
	(void)state;
	mbm_t m;
	mbm_init(&m, &port, 115200, 10, TIMEOUT, 2, 0);
	assert_true(mbm_read(&m, 1, false, 0x102, 4));
	uint32_t t = send_at(&m, 2000);
	arrive(RD_REPLY, 6);
	assert_int_equal(mbm_poll(&m, t + 100), MBM_BUSY);
	assert_int_equal(mbm_poll(&m, t + 5099), MBM_BUSY);
	assert_int_equal(mbm_poll(&m, t + 5100), MBM_BUSY); /* cut: retried */
	assert_int_equal(m.cnt.timeouts, 1);
	t = send_at(&m, t + 5100);
	uint8_t bad[sizeof RD_REPLY];
	memcpy(bad, RD_REPLY, sizeof bad);
	bad[4] ^= 0x10;
	arrive(bad, sizeof bad);
	assert_int_equal(mbm_poll(&m, t + 500), MBM_BUSY); /* bad CRC: retried */
	assert_int_equal(m.cnt.crc_errors, 1);
	assert_int_equal(mbm_poll(&m, t + 5499), MBM_BUSY);
	assert_int_equal(tx_n, 16); /* two frames sent so far, the third waits */
	t = send_at(&m, t + 5500);
	arrive(RD_REPLY, sizeof RD_REPLY);
	assert_int_equal(mbm_poll(&m, t + 500), MBM_OK);
	assert_int_equal(mbm_reg(&m, 1), 0xE240);
	assert_int_equal(m.cnt.requests, 3);
	assert_int_equal(m.cnt.retries, 2);
	sent((const uint8_t[]){0x01, 0x03, 0x01, 0x02, 0x00, 0x04, 0xE4, 0x35,
			       0x01, 0x03, 0x01, 0x02, 0x00, 0x04, 0xE4, 0x35,
			       0x01, 0x03, 0x01, 0x02, 0x00, 0x04, 0xE4, 0x35},
	     24);
}

/* Exception 2 ends the request at once; 6 (busy) is retried. */
static void test_exceptions(void **state)
{
	(void)state;
	mbm_t m;
	mbm_init(&m, &port, 115200, 10, TIMEOUT, 2, 0);
	assert_true(mbm_read(&m, 1, false, 0x102, 4));
	uint32_t t = send_at(&m, 2000);
	arrive(EXC2, sizeof EXC2);
	assert_int_equal(mbm_poll(&m, t + 500), MBM_EXCEPTION);
	assert_int_equal(m.exc, 2);
	assert_int_equal(m.cnt.requests, 1);
	assert_int_equal(m.cnt.illegal, 1);

	assert_true(mbm_read(&m, 1, false, 0x102, 4));
	t = send_at(&m, t + 3000);
	arrive(EXC6, sizeof EXC6);
	assert_int_equal(mbm_poll(&m, t + 500), MBM_BUSY);
	t = send_at(&m, t + 5500);
	arrive(EXC6, sizeof EXC6);
	assert_int_equal(mbm_poll(&m, t + 500), MBM_BUSY);
	t = send_at(&m, t + 5500);
	arrive(EXC6, sizeof EXC6);
	assert_int_equal(mbm_poll(&m, t + 500), MBM_EXCEPTION);
	assert_int_equal(m.exc, 6);
	assert_int_equal(m.cnt.requests, 4);
	assert_int_equal(m.cnt.busy, 3);
	assert_int_equal(m.cnt.exceptions, 4);
}

/* Replies judged: another unit, another function, a wrong count, a wrong
 * echo, an exception with a bad CRC; incomplete ones wait. */
static void test_check(void **state)
{
	(void)state;
	static const uint8_t W16[] = {0x01, 0x10, 0x01, 0x00, 0x00, 0x02, 0x04,
				      0x00, 0x00, 0x03, 0xE8, 0xFE, 0x81};
	static const uint8_t ECHO[] = {0x01, 0x10, 0x01, 0x00, 0x00, 0x02, 0x40, 0x34};
	uint8_t exc = 0, r[16];
	assert_int_equal(mbm_check(W16, ECHO, 7, &exc), MBM_MORE);
	assert_int_equal(mbm_check(W16, ECHO, 8, &exc), MBM_OK);
	memcpy(r, ECHO, 8);
	r[0] = 2;
	assert_int_equal(mbm_check(W16, r, 1, &exc), MBM_BAD);
	memcpy(r, ECHO, 8);
	r[5] = 3; /* another count, its CRC made good */
	uint16_t c = mbm_crc(r, 6);
	r[6] = (uint8_t)(c & 0xFF);
	r[7] = (uint8_t)(c >> 8);
	assert_int_equal(mbm_check(W16, r, 8, &exc), MBM_BAD);
	assert_int_equal(mbm_check(RD, RD_REPLY, 12, &exc), MBM_MORE);
	assert_int_equal(mbm_check(RD, (const uint8_t[]){0x01, 0x04}, 2, &exc), MBM_BAD);
	assert_int_equal(mbm_check(RD, (const uint8_t[]){0x01, 0x03, 0x06}, 3, &exc), MBM_BAD);
	assert_int_equal(mbm_check(RD, (const uint8_t[]){0x01, 0x83, 0x02, 0xC0, 0xF0}, 5, &exc),
			 MBM_CRC);
	assert_int_equal(mbm_check(RD, EXC2, 4, &exc), MBM_MORE);
	/* the write frames: 06 for one register, 16 for a pair */
	mbm_t m;
	mbm_init(&m, &port, 115200, 10, TIMEOUT, 0, 0);
	assert_true(mbm_write(&m, 1, 0x100, 2, (const uint16_t[]){0, 1000}));
	send_at(&m, 2000);
	sent(W16, sizeof W16);
	arrive(ECHO, sizeof ECHO);
	assert_int_equal(mbm_poll(&m, 2500), MBM_OK);
	assert_true(mbm_write(&m, 1, 0x106, 1, (const uint16_t[]){1}));
	send_at(&m, 5000);
	sent((const uint8_t[]){0x01, 0x06, 0x01, 0x06, 0x00, 0x01, 0xA9, 0xF7}, 8);
	assert_false(mbm_write(&m, 1, 0x106, 3, (const uint16_t[]){1, 2, 3}));
}

/* ---- the drive bus ------------------------------------------------------ */

static const uint8_t EN0[] = {0x01, 0x06, 0x01, 0x06, 0x00, 0x00, 0x68, 0x37};
static const uint8_t EN1[] = {0x01, 0x06, 0x01, 0x06, 0x00, 0x01, 0xA9, 0xF7};
static const uint8_t COMM[] = {0x01, 0x06, 0x01, 0x09, 0x00, 0x64, 0x59, 0xDF};
static const uint8_t SP0[] = {0x01, 0x10, 0x01, 0x00, 0x00, 0x02, 0x04,
			      0x00, 0x00, 0x00, 0x00, 0xFE, 0x3F};
static const uint8_t SP_ECHO[] = {0x01, 0x10, 0x01, 0x00, 0x00, 0x02, 0x40, 0x34};
static const uint8_t SAMPLE[] = {0x01, 0x03, 0x08, 0x00, 0x00, 0x03, 0xE8,
				 0x00, 0x01, 0x00, 0x00, 0xA4, 0x33};
static const uint8_t SAMPLE_AL[] = {0x01, 0x03, 0x08, 0x00, 0x00, 0x00, 0x00,
				    0x00, 0x01, 0x00, 0x31, 0x05, 0xC3};

static mb_profile_t prof;

/* Polls until a frame has gone out (at most 20 polls 1 ms apart): it must
 * be f; then the answer a arrives (NULL: none). */
static uint32_t exchange(mbd_bus_t *b, uint32_t t, const uint8_t *f, size_t n, const uint8_t *a,
			 size_t an)
{
	for (unsigned i = 0; i < 20 && tx_n == 0; i++)
		mbd_poll(b, t += 1000);
	sent(f, n);
	mbd_poll(b, t); /* transmitter done */
	if (a)
		arrive(a, an);
	mbd_poll(b, t += 200);
	return t;
}

static void bus_one(mbd_bus_t *b)
{
	prof = *mbp_builtin("generic");
	prof.reg[MBP_COMM_TIMEOUT] = (mbp_reg_t){0x109, 0, 1, 0};
	mbd_init(b, &prof, &port, 115200, 10, TIMEOUT, 1, 0);
	b->comm_timeout_ms = 100;
	assert_int_equal(mbd_add(b, 1, 0, false), 0);
}

/* One drive: its comm_timeout (100 ms), the enable off, the speed 0, the
 * sample; then servo on: enable on, the speed only once the status says on;
 * the tick reads one fresh sample per cycle. */
static void test_bus_cycle(void **state)
{
	(void)state;
	mbd_bus_t b;
	hal_drive_state_t st;
	bus_one(&b);
	mbd_read(&b, 0, &st);
	assert_false(st.fresh);
	assert_int_equal(st.phase, HAL_DRIVE_UNKNOWN);
	uint32_t t = exchange(&b, 0, COMM, sizeof COMM, COMM, sizeof COMM);
	t = exchange(&b, t, EN0, sizeof EN0, EN0, sizeof EN0);
	t = exchange(&b, t, SP0, sizeof SP0, SP_ECHO, sizeof SP_ECHO);
	t = exchange(&b, t, RD, sizeof RD, SAMPLE, sizeof SAMPLE);
	mbd_read(&b, 0, &st);
	assert_true(st.fresh);
	assert_int_equal(st.position_counts, 1000);
	assert_true(st.enabled);
	assert_int_equal(st.phase, HAL_DRIVE_ENABLED);
	assert_int_equal(st.fault_code, 0);
	mbd_read(&b, 0, &st);
	assert_false(st.fresh); /* once per sample */

	/* servo on, 1000 counts/s: enable on, then the speed */
	mbd_enable(&b, 0, true);
	mbd_set_velocity(&b, 0, 1000 * 256 + 100);
	t = exchange(&b, t, EN1, sizeof EN1, EN1, sizeof EN1);
	static const uint8_t SP1000[] = {0x01, 0x10, 0x01, 0x00, 0x00, 0x02, 0x04,
					 0x00, 0x00, 0x03, 0xE8, 0xFE, 0x81};
	t = exchange(&b, t, SP1000, sizeof SP1000, SP_ECHO, sizeof SP_ECHO);
	t = exchange(&b, t, RD, sizeof RD, SAMPLE_AL, sizeof SAMPLE_AL);
	mbd_read(&b, 0, &st);
	assert_int_equal(st.fault_code, 0x31);
	assert_int_equal(st.phase, HAL_DRIVE_FAULT);
	assert_int_equal(st.position_counts, 0);
	assert_int_equal(b.d[0].samples, 2);
	/* a fault reset asked: the reset register (0x107 = 1) before the rest */
	mbd_reset_fault(&b, 0);
	static const uint8_t RST[] = {0x01, 0x06, 0x01, 0x07, 0x00, 0x01, 0xF8, 0x37};
	t = exchange(&b, t, RST, sizeof RST, RST, sizeof RST);
	t = exchange(&b, t, SP1000, sizeof SP1000, SP_ECHO, sizeof SP_ECHO);
	(void)t;
}

/* A drive that does not answer: two attempts, the cycle fails, the tick
 * reads it not fresh (no reply); it is probed once per MBD_PROBE_US from
 * then on, one attempt, and set up again when it answers. Exceptions say
 * why: 6 busy, 2 the map. */
static void test_bus_silent_and_exceptions(void **state)
{
	(void)state;
	mbd_bus_t b;
	hal_drive_state_t st;
	bus_one(&b);
	uint32_t t = exchange(&b, 0, COMM, sizeof COMM, NULL, 0);
	t = exchange(&b, t + TIMEOUT, COMM, sizeof COMM, NULL, 0); /* the retry */
	mbd_poll(&b, t += TIMEOUT);
	assert_int_equal(b.d[0].failures, 1);
	assert_true(b.d[0].silent);
	mbd_read(&b, 0, &st);
	assert_false(st.fresh);
	assert_int_equal(st.silent_why, HAL_SILENT_NO_REPLY);
	/* nothing until the probe is due */
	for (unsigned i = 0; i < 50; i++)
		mbd_poll(&b, t += 1000);
	assert_int_equal(tx_n, 0);
	t += MBD_PROBE_US - 50000u;
	t = exchange(&b, t, COMM, sizeof COMM, NULL, 0);
	mbd_poll(&b, t += TIMEOUT);
	assert_int_equal(b.d[0].failures, 2);
	assert_int_equal(b.m.cnt.requests, 3); /* a probe: no retry */
	/* it answers busy: asked again next cycle, why busy */
	t = exchange(&b, t + MBD_PROBE_US, COMM, sizeof COMM, COMM, sizeof COMM);
	t = exchange(&b, t, EN0, sizeof EN0, EN0, sizeof EN0);
	t = exchange(&b, t, SP0, sizeof SP0, SP_ECHO, sizeof SP_ECHO);
	static const uint8_t EXC6_RD[] = {0x01, 0x83, 0x06, 0xC1, 0x32};
	t = exchange(&b, t, RD, sizeof RD, EXC6_RD, sizeof EXC6_RD);
	mbd_read(&b, 0, &st);
	assert_false(st.fresh);
	assert_int_equal(st.silent_why, HAL_SILENT_BUSY);
	assert_false(b.d[0].silent);
	/* the map rejected: not retried, why map */
	t = exchange(&b, t, SP0, sizeof SP0, SP_ECHO, sizeof SP_ECHO);
	(void)exchange(&b, t, RD, sizeof RD, EXC2, sizeof EXC2);
	mbd_read(&b, 0, &st);
	assert_int_equal(st.silent_why, HAL_SILENT_MAP);
	assert_int_equal(b.d[0].failures, 3 + 1);
}

/* The drive cycle at 115200 baud, 10-bit characters: per drive 84
 * half-characters (a 16 write of 13 bytes and its 8, a 03 read of 8 and
 * its 13), and per request the gap the master waits (1750 us above 19200
 * baud, 3.5 characters below) and 1 ms of turnaround: two drives
 * 7,292 + 4 x 2,750 us. */
static void test_cycle_and_check(void **state)
{
	(void)state;
	const mb_profile_t *g = mbp_builtin("generic");
	assert_int_equal(mbd_cycle_us(g, 2, 115200, 10, 1000), 18292);
	assert_int_equal(mbd_cycle_us(g, 4, 115200, 10, 1000), 36584);
	assert_int_equal(mbd_cycle_us(g, 4, 9600, 11, 1000), 232588);
	/* the compile-time form a board checks its constants with */
	assert_int_equal(
	    MBD_CYCLE_US(2, MBD_GENERIC_HALFCHARS, MBD_GENERIC_REQUESTS, 115200, 10, 1000), 18292);
	assert_int_equal(
	    MBD_CYCLE_US(4, MBD_GENERIC_HALFCHARS, MBD_GENERIC_REQUESTS, 9600, 11, 1000), 232588);
	assert_true(MBD_LINE_OK(18292, 50000, 2, 500));
	assert_false(MBD_LINE_OK(232588, 50000, 2, 500));
	assert_null(mbd_check(g, 2, 115200, 10, 50000, 2, 500));
	assert_null(mbd_check(g, 4, 115200, 10, 50000, 2, 500));
	/* 9600 baud, four drives: 233 ms a cycle, not within 500 ms twice */
	assert_string_equal(mbd_check(g, 4, 9600, 11, 50000, 2, 500),
			    "the line does not carry the drive cycle: a cycle and a failed request "
			    "must fit twice in drive_timeout_ms");
	/* 19200 baud, two drives, 20 ms timeout, one retry: 2 x (55 + 40) ms
	 * fits 200 ms; with 50 ms timeout and 2 retries it does not */
	assert_int_equal(mbd_cycle_us(g, 2, 19200, 10, 1000), 55046);
	assert_null(mbd_check(g, 2, 19200, 10, 20000, 1, 200));
	assert_non_null(mbd_check(g, 2, 19200, 10, 50000, 2, 200));
	assert_non_null(mbd_check(g, 5, 115200, 10, 50000, 2, 500));
	assert_non_null(mbd_check(g, 2, 600, 10, 50000, 2, 500));
	/* zlac8015d, block 5: status and alarm in one read (0x20A2..0x20A5 for
	 * channel 0, ..0x20A6 for channel 1), the position pair in another */
	const mb_profile_t *z = mbp_builtin("zlac8015d");
	mbp_read_t rd[3];
	assert_int_equal(mbp_read_plan(z, 0, MBM_READ_MAX, rd), 2);
	assert_int_equal(rd[0].addr, 0x20A2);
	assert_int_equal(rd[0].n, 4);
	assert_int_equal(rd[1].addr, 0x20A7);
	assert_int_equal(rd[1].n, 2);
	assert_int_equal(mbp_read_plan(z, 1, MBM_READ_MAX, rd), 2);
	assert_int_equal(rd[0].n, 5);
	assert_int_equal(rd[1].addr, 0x20A9);
	uint16_t w[2] = {0, 0};
	const uint16_t regs[5] = {1, 0, 0, 0, 0x31};
	assert_true(mbp_from_read(z, MBP_ALARM, 1, &rd[0], regs, w));
	assert_int_equal(w[0], 0x31);
	assert_false(mbp_from_read(z, MBP_POSITION, 1, &rd[0], regs, w));
	/* a block of 1 splits every register */
	mb_profile_t one = *g;
	one.block = 1;
	assert_int_equal(mbp_read_plan(&one, 0, MBM_READ_MAX, rd), 3);
	assert_int_equal(rd[0].n, 2);
}

/* The fault handlers' frame: enable_off to the drive's enable register. */
static void test_off_frame(void **state)
{
	(void)state;
	mbd_bus_t b;
	uint8_t f[MBM_ADU_MAX];
	bus_one(&b);
	mbd_add(&b, 2, 0, true);
	assert_int_equal(mbd_off_frame(&b, 0, f), 8);
	assert_memory_equal(f, EN0, 8);
	assert_int_equal(mbd_off_frame(&b, 1, f), 8);
	assert_memory_equal(f, ((const uint8_t[]){0x02, 0x06, 0x01, 0x06, 0x00, 0x00, 0x68, 0x04}),
			    8);
	/* polarity reverse: the speed written and the position read negated */
	mbd_set_velocity(&b, 1, -256 * 500);
	assert_int_equal(b.d[1].cmd_cps, 500);
	b.d[1].s.pos = 77;
	hal_drive_state_t st;
	mbd_read(&b, 1, &st);
	assert_int_equal(st.position_counts, -77);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test_setup(test_crc, setup),
	    cmocka_unit_test_setup(test_gap_and_frame, setup),
	    cmocka_unit_test_setup(test_timeout_and_retry, setup),
	    cmocka_unit_test_setup(test_cut_and_crc, setup),
	    cmocka_unit_test_setup(test_exceptions, setup),
	    cmocka_unit_test_setup(test_check, setup),
	    cmocka_unit_test_setup(test_bus_cycle, setup),
	    cmocka_unit_test_setup(test_bus_silent_and_exceptions, setup),
	    cmocka_unit_test_setup(test_cycle_and_check, setup),
	    cmocka_unit_test_setup(test_off_frame, setup),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
