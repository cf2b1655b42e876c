/* The serial link end to end through a pseudo-terminal: console lines
 * written raw as a serial terminal would, binary frames through the client
 * library (frame and console transports), bad input of every kind, and
 * vehiclectl against vehicle-sim --pty.
 *
 * The unit side runs in a thread: the link polled and the simulated plant
 * ticked in lockstep (1 ms of simulated time per loop), so the tests never
 * depend on wall-clock speed except for the frame inter-byte timeout.
 * While a stream is subscribed, the unit's time also waits for the host to
 * have read all it sent: a unit running ahead of a host that is not
 * scheduled would have the client keep more samples than it holds
 * (STREAM_KEEP) while it waits for an answer, and lose the oldest.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <errno.h>
#include <fcntl.h>
#include <libgen.h>
#include <math.h>
#include <poll.h>
#include <pthread.h>
#include <pty.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include "../host_sim/sim.h"
#include "../hal/posix/tty.h"
#include "../proto/client/client.h"
#include "../proto/server.h"

static sim_t S;
static server_serial_t SER;
static int MASTER = -1, SLAVE = -1;
static pthread_t TH;
static pthread_mutex_t MU = PTHREAD_MUTEX_INITIALIZER;
static volatile int RUN;
static char BUILD_DIR[512] = "build";

static uint32_t mono_ms(void)
{
	struct timespec ts;

	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (uint32_t)((uint64_t)ts.tv_sec * 1000u + (uint64_t)ts.tv_nsec / 1000000u);
}

static size_t m_read(void *ctx, uint8_t *b, size_t n)
{
	ssize_t r = read(*(int *)ctx, b, n);

	return r > 0 ? (size_t)r : 0;
}

/* Stream samples the host has taken (test_client_stream), and how far the
 * unit may run ahead of them: well below what the client keeps. */
static volatile uint32_t TAKEN;
#define STREAM_AHEAD 16u

/* The unit thread's port: what a poll sent, written after it in one go. */
static uint8_t OUT[2048];
static size_t OUT_N;

static size_t u_write(void *ctx, const uint8_t *b, size_t n)
{
	(void)ctx;
	if (n > sizeof(OUT) - OUT_N)
		n = sizeof(OUT) - OUT_N;
	memcpy(OUT + OUT_N, b, n);
	OUT_N += n;
	return n;
}

static void u_flush(void)
{
	ssize_t r = OUT_N ? write(MASTER, OUT, OUT_N) : 0;

	if (r > 0) {
		OUT_N -= (size_t)r;
		memmove(OUT, OUT + r, OUT_N);
	}
}

/* Set, the unit's link clock stands still (no frame times out): a test
 * whose host writes a frame in pieces then depends on no wall-clock gap. */
static volatile int FROZEN;
static uint32_t FROZEN_US;

static void *unit_thread(void *arg)
{
	(void)arg;
	while (RUN) {
		pthread_mutex_lock(&MU);
		server_poll(&S.srv, FROZEN ? FROZEN_US : (uint32_t)(mono_ms() * 1000u));
		u_flush();
		if (!SER.sub.mask || SER.sub.sent - TAKEN < STREAM_AHEAD)
			sim_tick(&S);
		pthread_mutex_unlock(&MU);
		usleep(100);
	}
	return NULL;
}

static int setup(void **state)
{
	vs_config_t cfg;
	plant_params_t pp;
	vs_link_t io = {m_read, u_write, &MASTER};

	(void)state;
	FROZEN = 0;
	OUT_N = 0;
	vs_config_defaults(&cfg);
	/* Time passes in lockstep waits with no request; the link watchdog
	 * has its own tests. */
	cfg.link_timeout_ms = 0;
	/* 1/32 mm per count: straight targets land on whole counts */
	cfg.wheel_diameter_mm = 16384.0 / (32.0 * 3.14159265358979323846);
	plant_params_default(&pp);
	if (sim_init(&S, &cfg, &pp) != 0)
		return -1;
	if (openpty(&MASTER, &SLAVE, NULL, NULL, NULL) != 0)
		return -1;
	if (tty_set_raw(SLAVE, 115200) != 0 || tty_set_raw(MASTER, 0) != 0)
		return -1;
	fcntl(MASTER, F_SETFL, fcntl(MASTER, F_GETFL) | O_NONBLOCK);
	server_serve_serial(&S.srv, &SER, &io);
	RUN = 1;
	return pthread_create(&TH, NULL, unit_thread, NULL) == 0 ? 0 : -1;
}

static int teardown(void **state)
{
	(void)state;
	RUN = 0;
	pthread_join(TH, NULL);
	close(SLAVE);
	close(MASTER);
	return 0;
}

/* Host side, raw as a serial terminal. */
static void host_write(const void *p, size_t n)
{
	const uint8_t *b = p;

	while (n) {
		ssize_t k = write(SLAVE, b, n);

		if (k < 0 && errno == EINTR)
			continue;
		assert_true(k > 0);
		b += k;
		n -= (size_t)k;
	}
}

/* Writes while discarding what the unit answers, as a host that sends more
 * than the unit's answers to it can wait for must (flow control). */
static void host_flood(const void *p, size_t n)
{
	const uint8_t *b = p;
	uint8_t junk[4096];
	uint32_t end = mono_ms() + 30000;
	int fl = fcntl(SLAVE, F_GETFL);

	fcntl(SLAVE, F_SETFL, fl | O_NONBLOCK);
	while (n) {
		struct pollfd pf = {SLAVE, POLLIN | POLLOUT, 0};
		ssize_t k;

		assert_true(mono_ms() < end);
		if (poll(&pf, 1, 100) <= 0)
			continue;
		if ((pf.revents & POLLIN) && read(SLAVE, junk, sizeof(junk)) < 0)
			assert_int_equal(errno, EAGAIN);
		if ((pf.revents & POLLOUT) && (k = write(SLAVE, b, n)) > 0) {
			b += k;
			n -= (size_t)k;
		}
	}
	fcntl(SLAVE, F_SETFL, fl);
}

/* Reads and discards what the unit answers for at least ms, and until the
 * unit has taken every byte written (a poll of its ended with the port
 * empty), holds no unfinished frame (whose NAK would come after its
 * inter-byte timeout, in host time) and sent every answer. */
static void host_settle(unsigned ms)
{
	uint8_t junk[4096];
	uint32_t t0 = mono_ms(), end = t0 + 30000, polls0;
	bool done = false;

	pthread_mutex_lock(&MU);
	polls0 = SER.st.polls;
	pthread_mutex_unlock(&MU);
	while (!done || mono_ms() - t0 < ms) {
		struct pollfd pf = {SLAVE, POLLIN, 0};

		assert_true(mono_ms() < end);
		if (poll(&pf, 1, 10) > 0 && read(SLAVE, junk, sizeof(junk)) > 0)
			continue;
		/* a poll that began after the last byte was written */
		pthread_mutex_lock(&MU);
		done = SER.st.polls - polls0 >= 2 && SER.in_at == SER.in_len && !SER.more &&
		       !SER.blocked && SER.q_len == 0 && OUT_N == 0 &&
		       !frame_rx_busy(&S.srv.serial.fs.rx);
		pthread_mutex_unlock(&MU);
	}
}

/* Exactly n bytes of the unit's, however long the host's load keeps the
 * unit thread from sending them (within 30 s). */
static void host_read_n(uint8_t *b, size_t n)
{
	uint32_t end = mono_ms() + 30000;

	while (n) {
		struct pollfd pf = {SLAVE, POLLIN, 0};
		ssize_t k;

		assert_true(mono_ms() < end);
		if (poll(&pf, 1, 100) <= 0)
			continue;
		k = read(SLAVE, b, n);
		if (k > 0) {
			b += k;
			n -= (size_t)k;
		}
	}
}

/* Discards everything the unit sent so far. */
static void host_drain(void)
{
	uint8_t junk[4096];
	struct pollfd pf = {SLAVE, POLLIN, 0};

	while (poll(&pf, 1, 50) > 0 && read(SLAVE, junk, sizeof(junk)) > 0)
		;
}

/* One reply line (without its "\n"), skipping binary answers. */
static const char *host_line(void)
{
	static char line[2048];
	size_t n = 0;
	uint32_t end = mono_ms() + 2000;

	for (;;) {
		struct pollfd pf = {SLAVE, POLLIN, 0};
		char c;

		assert_true(mono_ms() < end);
		if (poll(&pf, 1, 100) <= 0)
			continue;
		if (read(SLAVE, &c, 1) != 1)
			continue;
		if (c == '\n') {
			line[n] = '\0';
			return line;
		}
		if (n < sizeof(line) - 1)
			line[n++] = c;
	}
}

static const char *con(const char *cmd)
{
	char buf[512];
	int n = snprintf(buf, sizeof(buf), "%s\r\n", cmd);

	host_write(buf, (size_t)n);
	return host_line();
}

#define CON(cmd, reply) assert_string_equal(con(cmd), reply)

/* Lets the plant settle: ms of simulated time. */
static void wait_sim_ms(unsigned ms)
{
	uint64_t t0, t;

	pthread_mutex_lock(&MU);
	t0 = S.now_us;
	pthread_mutex_unlock(&MU);
	do {
		usleep(2000);
		pthread_mutex_lock(&MU);
		t = S.now_us;
		pthread_mutex_unlock(&MU);
	} while (t - t0 < (uint64_t)ms * 1000u);
}

static void wait_idle_console(void)
{
	for (int i = 0; i < 400; i++) {
		/* Ready, or Warning-### after a refused command: idle either way */
		if (strncmp(con("getState"), "ok true 17 ", 11) != 0) {
			wait_sim_ms(1000);
			return;
		}
		usleep(10000);
	}
	fail_msg("unit never became Ready");
}

static void test_console_raw(void **state)
{
	(void)state;
	host_drain();
	CON("getVersion", "ok true \"Ver.1.0.0\"");
	CON("getIFVersion", "ok true \"RTC VehicleService interface: ver.2.0.0\"");
	/* bare CR and bare LF end lines as well */
	host_write("getState\r", 9);
	assert_string_equal(host_line(), "ok true 25 \"Unpowered\"");
	host_write("\ngetState\n", 10);
	assert_string_equal(host_line(), "ok true 25 \"Unpowered\"");
	CON("nosuchop 1", "error 1 unknown operation nosuchop");
	CON("setPower true", "ok true");
	CON("setServo true", "ok true");
	CON("getState", "ok true 16 \"Ready\"");
	CON("moveForward 500", "ok true");
	CON("moveForward 500", "ok false");
	wait_idle_console();
	CON("getPosition", "ok true 500.000 0.000 0.000");
	CON("getActiveAlarm 1", "ok true 1 1 120 warning \"moveForward refused: unit not ready\"");
}

/* A UTF-8 comment holding 0xA5 (the yen sign is C2 A5) is only a comment:
 * inside a console line of text a sync byte starts no frame. */
static void test_console_utf8(void **state)
{
	(void)state;
	host_drain();
	host_write("# caf\xC3\xA9 \xC2\xA5 yen\n", 15);
	CON("getState", "ok true 25 \"Unpowered\"");
	/* in an operation line it is a byte of that line: error 7, no NAK */
	CON("getState \xC2\xA5", "error 7 binary data in line");
	/* after the line ending, a frame is a frame again */
	{
		uint8_t f[16];
		size_t k = frame_encode(f, sizeof(f), 0x31, CMD_OP_getServoStatus,
					(const uint8_t *)"\0\0\0\0", 4);
		uint8_t a[16];
		size_t n = 0;
		uint32_t end = mono_ms() + 2000;

		host_write(f, k);
		while (n < 10 && mono_ms() < end) {
			struct pollfd pf = {SLAVE, POLLIN, 0};
			ssize_t r;

			if (poll(&pf, 1, 100) > 0 && (r = read(SLAVE, a + n, 10 - n)) > 0)
				n += (size_t)r;
		}
		assert_int_equal(n, 10);
		assert_memory_equal(a, ((const uint8_t[]){0xA5, 3, 0, 0x31, 0x8A, 0, 1, 0}), 8);
	}
	CON("$link", "ok frames 1 executed 1 duplicates 0 naks 0 crc 0 oversize 0 truncated 0 "
		     "other 45 txdrop 0");
}

static vc_client_t C;

static void wait_idle_client(void)
{
	for (int i = 0; i < 400; i++) {
		int16_t st = 0;
		char msg[VS_STATE_MSG_MAX];
		bool r = false;

		assert_int_equal(vc_getState(&C, &r, &st, msg), VC_OK);
		if (st != VS_STATE_BUSY) {
			wait_sim_ms(1000);
			return;
		}
		usleep(10000);
	}
	fail_msg("unit never became Ready");
}

static void client_session(bool console)
{
	const char *s = NULL;
	bool r = false, servo = false;
	int16_t st = 0, nact = 0;
	char msg[VS_STATE_MSG_MAX];
	vs_position_t pos;
	vs_alarm_t al[4];
	uint16_t len = 99;
	unsigned ver = 0, ops = 0;
	uint16_t crc = 0;
	double a = 0, b = 0;

	host_drain();
	assert_int_equal(console ? vc_attach_console_fd(&C, SLAVE, false)
				 : vc_attach_serial_fd(&C, SLAVE, false),
			 VC_OK);
	assert_int_equal(vc_info(&C, &ver, &crc, &ops), VC_OK);
	assert_int_equal(ver, CMD_PROTO_VERSION);
	assert_int_equal(crc, cmd_table_crc());
	assert_int_equal(ops, 34);
	assert_int_equal(vc_getIFVersion(&C, &r, &s), VC_OK);
	assert_true(r);
	assert_string_equal(s, "RTC VehicleService interface: ver.2.0.0");
	assert_int_equal(vc_getState(&C, &r, &st, msg), VC_OK);
	assert_int_equal(st, VS_STATE_UNPOWERED);
	assert_string_equal(msg, "Unpowered");
	assert_int_equal(vc_getVelocityLimit(&C, &r, &a, &b), VC_OK);
	assert_true(r);
	assert_true(a > 0 && b > 0);
	/* refused: servo without power */
	assert_int_equal(vc_setServo(&C, &r, true), VC_OK);
	assert_false(r);
	assert_int_equal(vc_getActiveAlarm(&C, &r, 4, &nact, al, &len), VC_OK);
	assert_true(r);
	assert_int_equal(nact, 1);
	assert_int_equal(len, 1);
	assert_int_equal(al[0].code, ALM_W_POWER_OFF);
	assert_int_equal(al[0].type, VS_ALARM_WARNING);
	assert_int_equal(vc_clearAlarm(&C, &r), VC_OK);
	assert_int_equal(vc_setPower(&C, &r, true), VC_OK);
	assert_true(r);
	assert_int_equal(vc_setServo(&C, &r, true), VC_OK);
	assert_true(r);
	assert_int_equal(vc_getServoStatus(&C, &r, 0, &servo), VC_OK);
	assert_true(r);
	assert_true(servo);
	assert_int_equal(vc_moveForward(&C, &r, 500), VC_OK);
	assert_true(r);
	wait_idle_client();
	assert_int_equal(vc_getPosition(&C, &r, &pos), VC_OK);
	assert_true(r);
	assert_true(fabs(pos.x - 500.0) < 0.0005);
	assert_true(fabs(pos.y) < 0.0005);
	assert_true(fabs(pos.theta) < 0.0005);
	vc_close(&C);
}

static void test_binary_client(void **state)
{
	(void)state;
	client_session(false);
	assert_true(S.srv.serial.fs.st.executed >= 14);
	assert_int_equal(S.srv.serial.fs.st.naks, 0);
}

static void test_console_client(void **state)
{
	(void)state;
	client_session(true);
	assert_int_equal(S.srv.serial.fs.st.executed, 0);
}

/* The client library's stream: subscribe, samples interleaved with
 * requests (kept while the client waits for answers), consecutive sequence
 * numbers 10 ticks apart, the refusal of a rate the line cannot carry
 * (NAK rate) and none on the console transport; unsubscribe. */
static void test_client_stream(void **state)
{
	vc_stream_info_t info;
	vc_sample_t smp;
	uint32_t tick0 = 0;
	int16_t st = 0;
	char msg[VS_STATE_MSG_MAX];
	bool r = false;

	(void)state;
	host_drain();
	assert_int_equal(vc_attach_serial_fd(&C, SLAVE, false), VC_OK);
	C.timeout_ms = 5000;
	assert_int_equal(vc_stream_subscribe(&C, STREAM_MASK_ALL, 1, &info), VC_E_NAK);
	assert_int_equal(C.nak, WIRE_ST_RATE);
	TAKEN = 0;
	assert_int_equal(vc_stream_subscribe(&C, 0x09, 10, &info), VC_OK);
	assert_int_equal(info.mask, 0x09);
	assert_int_equal(info.period_ms, 10);
	assert_int_equal(info.frame_bytes, 28);
	assert_int_equal(info.min_period_ms, 4);
	assert_int_equal(info.tick_hz, 1000);
	for (unsigned k = 0; k < 50; k++) {
		if (k % 5 == 2) {
			/* a request between samples: its answer comes, the
			 * samples that arrive meanwhile are kept */
			assert_int_equal(vc_getState(&C, &r, &st, msg), VC_OK);
			assert_int_equal(st, 25);
		}
		assert_int_equal(vc_stream_next(&C, &smp, 5000), VC_OK);
		TAKEN++;
		assert_int_equal(smp.seq, (uint8_t)k);
		assert_int_equal(smp.lost, 0);
		assert_int_equal(smp.mask, 0x09);
		assert_int_equal(smp.v.state, 25);
		if (k == 0)
			tick0 = smp.tick;
		assert_int_equal(smp.tick - tick0, 10 * k);
	}
	assert_int_equal(vc_stream_unsubscribe(&C), VC_OK);
	assert_int_equal(SER.sub.mask, 0);
	/* what was sent before the unsubscription arrived, then nothing */
	while (vc_stream_next(&C, &smp, 100) == VC_OK)
		;
	assert_int_equal(vc_stream_next(&C, &smp, 100), VC_E_TIMEOUT);
	vc_close(&C);
	assert_int_equal(vc_attach_console_fd(&C, SLAVE, false), VC_OK);
	assert_int_equal(vc_stream_subscribe(&C, 0x09, 10, &info), VC_E_UNSUPPORTED);
	assert_int_equal(vc_stream_next(&C, &smp, 10), VC_E_UNSUPPORTED);
	vc_close(&C);
}

/* vc_wait_done after a refused request left a warning: the unit reads
 * Warning-111 while idle, which is done (spec 6.9); a move's wait returns
 * when the move has ended, a fault's with VC_E_STOPPED, a wait too short
 * with VC_E_NOT_DONE. */
static void wait_session(bool console)
{
	bool r = true;
	int16_t st = 0;
	char msg[VS_STATE_MSG_MAX];
	vs_position_t pos;
	char reply[CONSOLE_REPLY_MAX];

	host_drain();
	assert_int_equal(console ? vc_attach_console_fd(&C, SLAVE, false)
				 : vc_attach_serial_fd(&C, SLAVE, false),
			 VC_OK);
	assert_int_equal(vc_setPower(&C, &r, true), VC_OK);
	assert_int_equal(vc_setServo(&C, &r, true), VC_OK);
	assert_int_equal(vc_setVelocity(&C, &r, (vs_velocity_t){0.0, 10.0}), VC_OK);
	assert_false(r);
	assert_int_equal(vc_wait_done(&C, 0, &st, msg), VC_OK);
	assert_int_equal(st, VS_STATE_WARNING);
	assert_string_equal(msg, "Warning-111");

	assert_int_equal(vc_moveForward(&C, &r, 300.0), VC_OK);
	assert_true(r);
	assert_int_equal(vc_getState(&C, &r, &st, msg), VC_OK);
	assert_int_equal(st, VS_STATE_BUSY);
	assert_int_equal(vc_wait_done(&C, 60000, &st, msg), VC_OK);
	assert_int_equal(st, VS_STATE_WARNING);
	assert_string_equal(msg, "Warning-111");
	/* done means in position: every wheel within the 0.05 mm window */
	assert_int_equal(vc_getPosition(&C, &r, &pos), VC_OK);
	assert_true(fabs(pos.x - 300.0) <= 0.05);

	/* a fault while the move runs */
	assert_int_equal(vc_moveForward(&C, &r, 5000.0), VC_OK);
	assert_true(r);
	pthread_mutex_lock(&MU);
	assert_true(sim_exec(&S, "$sim drive 0 fault 0x2310", reply, sizeof(reply)));
	pthread_mutex_unlock(&MU);
	assert_int_equal(vc_wait_done(&C, 60000, &st, msg), VC_E_STOPPED);
	assert_int_equal(st, VS_STATE_ALARM);
	assert_string_equal(msg, "Alarm-201");
	assert_int_equal(vc_getPosition(&C, &r, &pos), VC_OK);
	/* stopped where the fault found it, far short of 5,300 mm */
	assert_true(pos.x > 300.0 - 0.05 && pos.x < 400.0);

	/* not done within the wait: Busy at its end; then a stop is done */
	pthread_mutex_lock(&MU);
	assert_true(sim_exec(&S, "$sim drive 0 ok", reply, sizeof(reply)));
	pthread_mutex_unlock(&MU);
	assert_int_equal(vc_clearAlarm(&C, &r), VC_OK);
	assert_int_equal(vc_setServo(&C, &r, true), VC_OK);
	assert_true(r);
	assert_int_equal(vc_moveForward(&C, &r, 5000.0), VC_OK);
	assert_true(r);
	assert_int_equal(vc_wait_done(&C, 50, &st, msg), VC_E_NOT_DONE);
	assert_int_equal(st, VS_STATE_BUSY);
	assert_string_equal(msg, "Busy");
	assert_int_equal(vc_stop(&C, &r), VC_OK);
	assert_int_equal(vc_wait_done(&C, 60000, &st, msg), VC_OK);
	assert_int_equal(st, VS_STATE_READY);
	assert_string_equal(msg, "Ready");
	vc_close(&C);
}

static void test_wait_done_frames(void **state)
{
	(void)state;
	wait_session(false);
}

static void test_wait_done_console(void **state)
{
	(void)state;
	wait_session(true);
}

/* The same frame twice: answered twice, run once. */
static void test_retransmission_runs_once(void **state)
{
	uint8_t on = 1, f[FRAME_REQ_MAX], pay[8], a1[64], a2[64];
	cmd_value_t v[1];
	size_t n, len;

	(void)state;
	host_drain();
	assert_int_equal(vc_attach_serial_fd(&C, SLAVE, false), VC_OK);
	assert_int_equal(vc_setPower(&C, NULL, true), VC_OK);
	assert_int_equal(vc_setServo(&C, NULL, true), VC_OK);
	vc_close(&C);
	(void)on;
	v[0].d = 300;
	assert_int_equal(
	    wire_encode_request(cmd_by_opcode(CMD_OP_moveForward), v, pay, sizeof(pay), &len),
	    WIRE_ST_OK);
	n = frame_encode(f, sizeof(f), 0x42, CMD_OP_moveForward, pay, len);
	pthread_mutex_lock(&MU);
	uint32_t ex0 = S.srv.serial.fs.st.executed, dup0 = S.srv.serial.fs.st.duplicates;
	pthread_mutex_unlock(&MU);
	host_drain();
	host_write(f, n);
	host_read_n(a1, 9);
	host_write(f, n);
	host_read_n(a2, 9);
	assert_memory_equal(a1, a2, 9);
	assert_int_equal(a1[5], WIRE_ST_OK);
	assert_int_equal(a1[6], 1); /* true: the one run was accepted */
	pthread_mutex_lock(&MU);
	assert_int_equal(S.srv.serial.fs.st.executed, ex0 + 1);
	assert_int_equal(S.srv.serial.fs.st.duplicates, dup0 + 1);
	pthread_mutex_unlock(&MU);
	assert_int_equal(vc_attach_serial_fd(&C, SLAVE, false), VC_OK);
	wait_idle_client();
	{
		vs_position_t p;

		assert_int_equal(vc_getPosition(&C, NULL, &p), VC_OK);
		assert_true(fabs(p.x - 300.0) < 0.0005); /* once, not 600 */
	}
	vc_close(&C);
}

static void put_frame(uint8_t seq, uint8_t op, const void *p, size_t n)
{
	uint8_t f[FRAME_RESP_MAX];
	size_t k = frame_encode(f, sizeof(f), seq, op, p, n);

	assert_int_not_equal(k, 0);
	host_write(f, k);
}

/* Bad input of every kind while a move waits in the queue (paused): every
 * piece is NAKed, rejected or dropped with a count, nothing runs, nothing
 * moves, the queued move survives and the link answers afterwards. */
static void test_bad_input(void **state)
{
	static uint8_t junk[65536];
	uint8_t f[FRAME_RESP_MAX];
	vs_diag_t d0, d1;
	frame_rx_stats_t r0, r1;
	uint32_t ex0, ex1;
	bool r = false;
	int16_t st = 0;
	char msg[VS_STATE_MSG_MAX];
	vs_position_t pos;

	(void)state;
	host_drain();
	CON("setPower true", "ok true");
	CON("setServo true", "ok true");
	CON("pause", "ok true");
	CON("moveLinearAbs 300 0 0", "ok true");
	CON("getState", "ok true 21 \"Paused\"");
	pthread_mutex_lock(&MU);
	vehicle_diag(&S.vehicle, &d0);
	r0 = S.srv.serial.fs.rx.st;
	ex0 = S.srv.serial.fs.st.executed;
	pthread_mutex_unlock(&MU);
	assert_int_equal(d0.queue_len, 1);

	/* random bytes */
	srand(4242);
	for (size_t i = 0; i < 8192; i++)
		junk[i] = (uint8_t)rand();
	host_flood(junk, 8192);
	host_settle(150);
	/* bad CRC */
	{
		size_t k = frame_encode(f, sizeof(f), 1, CMD_OP_moveForward,
					(const uint8_t *)"\0\0\0\0\0\x40\x7f\x40", 8);

		f[k - 2] ^= 0xFF;
		host_write(f, k);
	}
	/* wrong lengths: 7 and 9 bytes for one double; a getPosition with a payload */
	put_frame(2, CMD_OP_moveForward, "\0\0\0\0\0\x40\x7f", 7);
	put_frame(3, CMD_OP_moveForward, "\0\0\0\0\0\x40\x7f\x40\0", 9);
	put_frame(4, CMD_OP_getPosition, "\0", 1);
	/* unknown opcodes, a bad boolean, an answer frame */
	put_frame(5, 0x55, NULL, 0);
	put_frame(6, 0, NULL, 0);
	put_frame(7, CMD_OP_setServo, "\x02", 1);
	put_frame(8, 0x80 | CMD_OP_resume, "\0\x01", 2);
	/* oversize: declared 65 and 1000 */
	memset(junk, 0, 1100);
	put_frame(9, CMD_OP_resume, junk, 65);
	put_frame(10, CMD_OP_resume, junk, 1000);
	/* truncated: header and half a payload, then silence */
	{
		size_t k = frame_encode(f, sizeof(f), 11, CMD_OP_moveForward,
					(const uint8_t *)"\0\0\0\0\0\x40\x7f\x40", 8);

		host_write(f, k - 5);
		usleep(250000);
	}
	/* a flood at full rate: 64 KiB of sync-rich garbage with no line end */
	for (size_t i = 0; i < sizeof(junk); i++)
		junk[i] = (uint8_t)(i % 5 == 0 ? FRAME_SYNC : rand());
	host_flood(junk, sizeof(junk));
	host_settle(250);
	/* a line end closes whatever the console collected */
	host_write("\n", 1);
	host_settle(50);
	host_drain();

	pthread_mutex_lock(&MU);
	vehicle_diag(&S.vehicle, &d1);
	r1 = S.srv.serial.fs.rx.st;
	ex1 = S.srv.serial.fs.st.executed;
	pthread_mutex_unlock(&MU);
	assert_int_equal(ex1, ex0); /* nothing ran */
	assert_int_equal(d1.queue_len, 1);
	assert_memory_equal(&d1.odom_pose, &d0.odom_pose, sizeof(d0.odom_pose));
	assert_true(r1.crc_errors > r0.crc_errors);
	assert_true(r1.oversize >= r0.oversize + 2);
	assert_true(r1.truncated > r0.truncated);
	assert_true(r1.other_bytes > r0.other_bytes);
	assert_true(S.srv.serial.fs.st.naks >= 8);

	/* resynchronised: both protocols answer at once */
	CON("getState", "ok true 21 \"Paused\"");
	assert_int_equal(vc_attach_serial_fd(&C, SLAVE, false), VC_OK);
	assert_int_equal(vc_getState(&C, &r, &st, msg), VC_OK);
	assert_int_equal(st, VS_STATE_PAUSED);
	/* and the queued move is still there */
	assert_int_equal(vc_resume(&C, &r), VC_OK);
	assert_true(r);
	wait_idle_client();
	assert_int_equal(vc_getPosition(&C, &r, &pos), VC_OK);
	assert_true(fabs(pos.x - 300.0) < 0.0005);
	vc_close(&C);
}

/* ---- flow control over the pty ------------------------------------------ */

/* What came back, in the order it came: frames and console lines, each
 * checked against the one answer getIFVersion has. */
enum { PIPE_N = 6000 };
typedef struct {
	int kind; /* 1 frame, 2 console line */
	uint8_t seq, op;
	bool good;
} ev_t;
static ev_t EV[PIPE_N + 1];
static size_t NEV;
static char EVLINE[1100];
static size_t EVLINE_N;
static const char IFV[] = "RTC VehicleService interface: ver.2.0.0";

static ev_t *ev_next(void)
{
	return &EV[NEV < PIPE_N ? NEV++ : (NEV = PIPE_N + 1, PIPE_N)];
}

static void ev_frame(void *ctx, const frame_t *f)
{
	ev_t *e = ev_next();

	(void)ctx;
	e->kind = 1;
	e->seq = f->seq;
	e->op = f->op;
	e->good = f->status == WIRE_ST_OK && f->len == 3 + sizeof(IFV) - 1 &&
		  f->payload[0] == WIRE_ST_OK && f->payload[1] == 1 &&
		  f->payload[2] == sizeof(IFV) - 1 &&
		  memcmp(f->payload + 3, IFV, sizeof(IFV) - 1) == 0;
}

static void ev_other(void *ctx, const uint8_t *d, size_t n)
{
	(void)ctx;
	for (size_t i = 0; i < n; i++) {
		if (d[i] == '\n') {
			char want[80];
			ev_t *e = ev_next();

			snprintf(want, sizeof(want), "ok true \"%s\"", IFV);
			EVLINE[EVLINE_N] = '\0';
			e->kind = 2;
			e->good = strcmp(EVLINE, want) == 0;
			EVLINE_N = 0;
		} else if (EVLINE_N < sizeof(EVLINE) - 1) {
			EVLINE[EVLINE_N++] = (char)d[i];
		}
	}
}

/* Request i of the pipeline: every 8th a console line, the others frames
 * with sequence number i (mod 256), all getIFVersion. */
static size_t pipeline(uint8_t *buf, size_t cap)
{
	size_t n = 0;

	for (unsigned i = 0; i < PIPE_N; i++) {
		if (i % 8 == 7) {
			assert_true(cap - n >= 13);
			memcpy(buf + n, "getIFVersion\n", 13);
			n += 13;
		} else {
			size_t k = frame_encode(buf + n, cap - n, (uint8_t)i, CMD_OP_getIFVersion,
						NULL, 0);

			assert_int_not_equal(k, 0);
			n += k;
		}
	}
	return n;
}

/* Requests run by the unit so far: frames and console lines. */
static uint32_t unit_ran(void)
{
	uint32_t n;

	pthread_mutex_lock(&MU);
	n = S.srv.serial.fs.st.executed + S.srv.con.lines;
	pthread_mutex_unlock(&MU);
	return n;
}

/* 6,000 requests pipelined (frames and console lines), not read until the
 * unit stops taking them, then read: the unit ran only what it could
 * answer (its answers waiting, the rest left in the port), and in the end
 * every request has exactly one whole answer, in order, none dropped. */
static void test_pipelined_flow_control(void **state)
{
	static uint8_t req[PIPE_N * FRAME_OVERHEAD + PIPE_N / 8 * 13];
	uint8_t rxbuf[FRAME_RESP_MAX];
	frame_rx_t rx;
	size_t len, sent = 0;
	uint32_t ran0, ran, end;
	int fl;

	(void)state;
	host_drain();
	len = pipeline(req, sizeof(req));
	ran0 = unit_ran();
	pthread_mutex_lock(&MU);
	/* The host writes frames in pieces as the port takes them. */
	FROZEN_US = (uint32_t)(mono_ms() * 1000u);
	FROZEN = 1;
	pthread_mutex_unlock(&MU);
	fl = fcntl(SLAVE, F_GETFL);
	fcntl(SLAVE, F_SETFL, fl | O_NONBLOCK);

	/* Not reading: write until the unit leaves the rest in the port. */
	end = mono_ms() + 30000;
	for (bool blocked = false; !blocked;) {
		ssize_t k = sent < len ? write(SLAVE, req + sent, len - sent) : 0;

		if (k > 0) {
			sent += (size_t)k;
			continue;
		}
		assert_true(k == 0 || errno == EAGAIN);
		assert_true(mono_ms() < end);
		usleep(1000);
		pthread_mutex_lock(&MU);
		blocked = SER.blocked;
		pthread_mutex_unlock(&MU);
	}
	/* It stopped as soon as more than the backlog of answers waited
	 * (49 bytes a frame's, 50 a line's), far short of the pipeline. (The
	 * pty's kernel side frees room late on a loaded host, so the unit may
	 * take some more later; it never holds more than that, below.) */
	ran = unit_ran() - ran0;
	assert_true(ran < PIPE_N);
	pthread_mutex_lock(&MU);
	assert_true(SER.q_len > SERVER_SERIAL_BACKLOG);
	assert_true(SER.q_len <= SERVER_SERIAL_BACKLOG + 50);
	assert_int_equal(S.srv.serial.port.dropped, 0);
	pthread_mutex_unlock(&MU);

	/* Reading now, and writing the rest as the port takes it. */
	NEV = 0;
	EVLINE_N = 0;
	frame_rx_init(&rx, rxbuf, FRAME_RESP_PAYLOAD_MAX, ev_frame, ev_other, NULL);
	while (NEV < PIPE_N) {
		struct pollfd pf = {SLAVE, (short)(POLLIN | (sent < len ? POLLOUT : 0)), 0};
		uint8_t b[4096];
		ssize_t k;

		assert_true(mono_ms() < end);
		if (poll(&pf, 1, 100) <= 0)
			continue;
		if ((pf.revents & POLLIN) && (k = read(SLAVE, b, sizeof(b))) > 0)
			frame_rx_feed(&rx, b, (size_t)k, 0);
		if ((pf.revents & POLLOUT) && (k = write(SLAVE, req + sent, len - sent)) > 0)
			sent += (size_t)k;
	}
	/* and nothing after the last */
	{
		struct pollfd pf = {SLAVE, POLLIN, 0};

		assert_int_equal(poll(&pf, 1, 200), 0);
	}
	fcntl(SLAVE, F_SETFL, fl);
	FROZEN = 0;
	assert_int_equal(sent, len);
	assert_int_equal(NEV, PIPE_N);
	for (unsigned i = 0; i < PIPE_N; i++) {
		if (!EV[i].good || EV[i].kind != (i % 8 == 7 ? 2 : 1) ||
		    (EV[i].kind == 1 &&
		     (EV[i].seq != (uint8_t)i || EV[i].op != (0x80 | CMD_OP_getIFVersion))))
			fail_msg("answer %u: kind %d seq %u op 0x%02X good %d", i, EV[i].kind,
				 EV[i].seq, EV[i].op, EV[i].good);
	}
	assert_int_equal(rx.st.crc_errors + rx.st.oversize + rx.st.truncated, 0);
	assert_int_equal(unit_ran() - ran0, PIPE_N);
	pthread_mutex_lock(&MU);
	assert_int_equal(S.srv.serial.port.dropped, 0);
	assert_int_equal(S.srv.serial.fs.st.naks, 0);
	assert_true(SER.st.room_stops > 0);
	assert_true(SER.st.max_queued <= SERVER_SERIAL_BACKLOG + 50);
	assert_int_equal(SER.q_len, 0);
	pthread_mutex_unlock(&MU);
}

/* ---- the budget per poll, on a port of no speed limit ------------------- */

/* A port as fast as memory: everything the host sent is there at once, and
 * it takes every answer, or none while full. The unit is polled by the test
 * alone, its clock standing (no frame times out). */
typedef struct {
	const uint8_t *in;
	size_t in_len, in_at;
	uint8_t out[1 << 20];
	size_t out_len;
	bool full;
} fport_t;

static fport_t FP;
static sim_t F;
static server_serial_t FSER;

static size_t fp_read(void *ctx, uint8_t *b, size_t max)
{
	fport_t *p = ctx;
	size_t k = p->in_len - p->in_at < max ? p->in_len - p->in_at : max;

	memcpy(b, p->in + p->in_at, k);
	p->in_at += k;
	return k;
}

static size_t fp_write(void *ctx, const uint8_t *b, size_t n)
{
	fport_t *p = ctx;

	if (p->full)
		return 0;
	assert_true(p->out_len + n <= sizeof(p->out));
	memcpy(p->out + p->out_len, b, n);
	p->out_len += n;
	return n;
}

static int fake_setup(void **state)
{
	vs_config_t cfg;
	plant_params_t pp;
	vs_link_t io = {fp_read, fp_write, &FP};

	(void)state;
	vs_config_defaults(&cfg);
	cfg.link_timeout_ms = 0;
	plant_params_default(&pp);
	memset(&FP, 0, sizeof(FP));
	if (sim_init(&F, &cfg, &pp) != 0)
		return -1;
	server_serve_serial(&F.srv, &FSER, &io);
	return 0;
}

static uint32_t f_executed(void)
{
	return F.srv.serial.fs.st.executed;
}

/* Polls until the unit has taken every byte and the port every answer. */
static void f_settle(void)
{
	for (int p = 0; FP.in_at < FP.in_len || FSER.in_at < FSER.in_len || FSER.q_len ||
			server_serial_more(&F.srv) || server_serial_blocked(&F.srv);
	     p++) {
		assert_true(p < 100000);
		server_poll(&F.srv, 0);
	}
}

/* n frames of op with payload p (seq 0, 1, ...) into buf. */
static size_t frames(uint8_t *buf, size_t cap, unsigned n, uint8_t op, const void *p, size_t plen)
{
	size_t len = 0;

	for (unsigned i = 0; i < n; i++) {
		size_t k = frame_encode(buf + len, cap - len, (uint8_t)i, op, p, plen);

		assert_int_not_equal(k, 0);
		len += k;
	}
	return len;
}

/* The answers on the port: n frames, seq 0, 1, ..., each of op and size. */
static void check_answers(unsigned n, uint8_t op, size_t size)
{
	size_t at = 0;

	for (unsigned i = 0; i < n; i++) {
		const uint8_t *a = FP.out + at;

		assert_true(at + size <= FP.out_len);
		assert_int_equal(a[0], FRAME_SYNC);
		assert_int_equal(wire_get_u16(a + 1), size - FRAME_OVERHEAD);
		assert_int_equal(a[3], (uint8_t)i);
		assert_int_equal(a[4], 0x80 | op);
		assert_int_equal(a[5], WIRE_ST_OK);
		assert_int_equal(wire_get_u16(a + size - 2), cmd_crc16(0xFFFF, a + 1, size - 3));
		at += size;
	}
	assert_int_equal(at, FP.out_len);
}

/* getState frames flooding in: 8 run a poll, each answered whole (21 bytes:
 * true 25 "Unpowered"), and of the port's bytes only what the unit reads at
 * once (256) is taken ahead; the rest waits in the port. */
static void test_budget_requests(void **state)
{
	enum { N = 1000 };
	static uint8_t in[N * FRAME_OVERHEAD];
	unsigned polls = 0;

	(void)state;
	FP.in = in;
	FP.in_len = frames(in, sizeof(in), N, CMD_OP_getState, NULL, 0);
	server_poll(&F.srv, 0);
	assert_int_equal(f_executed(), 8);
	assert_int_equal(FP.out_len, 8 * 21);
	assert_int_equal(FP.in_at, SERVER_SERIAL_IN);
	assert_true(server_serial_more(&F.srv));
	for (polls = 1; f_executed() < N; polls++) {
		server_poll(&F.srv, 0);
		assert_int_equal(f_executed(), 8 * (polls + 1));
	}
	assert_int_equal(polls, N / 8);
	server_poll(&F.srv, 0);
	assert_false(server_serial_more(&F.srv));
	assert_int_equal(FSER.st.max_answers, 8);
	assert_int_equal(FSER.st.budget_stops, N / 8);
	assert_int_equal(FSER.st.room_stops, 0);
	assert_int_equal(F.srv.serial.port.dropped, 0);
	check_answers(N, CMD_OP_getState, 21);
}

/* getActiveAlarm 16 with 11 alarms of 50-byte sources: 628-byte answers,
 * whose bytes bound a poll first: 7 a poll (4,396 bytes; six were 3,768,
 * under 4,096). */
static void test_budget_answer_bytes(void **state)
{
	enum { N = 700 };
	static uint8_t in[N * (FRAME_OVERHEAD + 2)];
	const uint8_t count[2] = {16, 0};

	(void)state;
	for (int k = 0; k < 11; k++) {
		char src[51];

		memset(src, 'a' + k, 50);
		src[50] = '\0';
		alarm_raise(&F.vehicle.alarms, (uint32_t)(100 + k), src);
	}
	FP.in = in;
	FP.in_len = frames(in, sizeof(in), N, CMD_OP_getActiveAlarm, count, 2);
	for (unsigned p = 1; p <= N / 7; p++) {
		server_poll(&F.srv, 0);
		assert_int_equal(f_executed(), 7 * p);
		assert_int_equal(FP.out_len, 7 * 628 * p);
	}
	assert_int_equal(FSER.st.max_answers, 7);
	assert_int_equal(FSER.st.max_bytes, 7 * 628);
	check_answers(N, CMD_OP_getActiveAlarm, 628);
}

/* Comments get no answer: 64 KiB of them are bounded by the bytes a poll
 * reads, 8 KiB. */
static void test_budget_bytes_read(void **state)
{
	static uint8_t in[64 * 1024];

	(void)state;
	for (size_t i = 0; i < sizeof(in); i += 64) {
		memset(in + i, 'c', 63);
		memcpy(in + i, "# ", 2);
		in[i + 63] = '\n';
	}
	FP.in = in;
	FP.in_len = sizeof(in);
	for (unsigned p = 1; p <= 8; p++) {
		server_poll(&F.srv, 0);
		assert_int_equal(FP.in_at, SERVER_SERIAL_RX_PER_POLL * p);
		assert_true(server_serial_more(&F.srv));
	}
	server_poll(&F.srv, 0);
	assert_false(server_serial_more(&F.srv));
	assert_int_equal(FP.out_len, 0);
	assert_int_equal(F.srv.con.lines, 0);
}

/* A port that takes nothing: the unit runs requests while at most 4,096
 * bytes of answers wait, 196 getState (195 x 21 = 4,095), and then leaves
 * the rest in the port: of its 7,000 bytes it read 1,536 (six reads of 256
 * for the 1,372 bytes of 196 frames). When the port takes again, every
 * request is answered whole and in order. */
static void test_flow_port_full(void **state)
{
	enum { N = 1000 };
	static uint8_t in[N * FRAME_OVERHEAD];

	(void)state;
	FP.full = true;
	FP.in = in;
	FP.in_len = frames(in, sizeof(in), N, CMD_OP_getState, NULL, 0);
	for (int p = 0; p < 100; p++)
		server_poll(&F.srv, 0);
	assert_int_equal(f_executed(), 196);
	assert_int_equal(FSER.q_len, 196 * 21);
	assert_int_equal(FP.in_at, 1536);
	assert_true(server_serial_blocked(&F.srv));
	assert_false(server_serial_more(&F.srv));
	assert_int_equal(server_serial_queued(&F.srv), 196 * 21);
	assert_int_equal(FSER.st.room_stops, 100 - 24);
	FP.full = false;
	f_settle();
	assert_int_equal(f_executed(), N);
	assert_int_equal(F.srv.serial.port.dropped, 0);
	check_answers(N, CMD_OP_getState, 21);
}

/* The most one byte can cause: the byte that completes a damaged frame
 * whose bytes, read again, hold ten "$help" lines. Taken with 4,032 bytes
 * already waiting (192 answers, the backlog not exceeded), its twelve
 * answers (the NAK, error 7 for the length bytes' line, ten $help replies)
 * go into the queue whole, over the backlog and the poll's budget; then
 * nothing more is taken until the port takes them. */
static void test_flow_damaged_frame(void **state)
{
	enum { N = 192 };
	static uint8_t in[N * FRAME_OVERHEAD + 128];
	uint8_t *d;
	char help[CONSOLE_REPLY_MAX], err7[64];
	size_t len, hl, want;
	uint16_t crc;

	(void)state;
	assert_true(sim_exec(&F, "$help", help, sizeof(help)));
	hl = strlen(help) + 1;
	snprintf(err7, sizeof(err7), "error %d binary data in line\n", CONSOLE_E_BINARY);
	len = frames(in, sizeof(in), N, CMD_OP_getState, NULL, 0);
	/* A5, length 64 ("@" NUL), seq '\n', op '$', "help\n" and nine
	 * "$help\n", "    \n", then a check that is not the frame's ("xy") */
	d = in + len;
	d[0] = FRAME_SYNC;
	memcpy(d + 1, "@\0\n$help\n", 9);
	for (int k = 0; k < 9; k++)
		memcpy(d + 10 + 6 * k, "$help\n", 6);
	memcpy(d + 64, "    \nxy", 7);
	crc = cmd_crc16(0xFFFF, d + 1, 4 + 64);
	assert_int_not_equal(crc, wire_get_u16((const uint8_t *)"xy"));
	len += 71;
	in[len++] = '\n'; /* ends the line "xy" */
	len += frame_encode(in + len, sizeof(in) - len, 200, CMD_OP_getState, NULL, 0);
	FP.in = in;
	FP.in_len = len;
	FP.full = true;
	for (int p = 0; p < 40; p++)
		server_poll(&F.srv, 0);
	want = N * 21 + FRAME_OVERHEAD + 1 + strlen(err7) + 10 * hl;
	assert_int_equal(FSER.q_len, want);
	assert_int_equal(F.srv.serial.port.dropped, 0);
	assert_int_equal(FSER.st.max_answers, 12);
	assert_true(server_serial_blocked(&F.srv));
	assert_int_equal(f_executed(), N);
	/* the port takes again: the rest, then the line "xy" and the frame */
	FP.full = false;
	f_settle();
	{
		const uint8_t *o = FP.out + N * 21;
		uint8_t nak[FRAME_OVERHEAD + 1];
		char tail[CONSOLE_REPLY_MAX * 12];
		size_t tl = 0;

		assert_int_equal(
		    frame_encode_response(nak, sizeof(nak), '\n', 0, WIRE_ST_CRC, NULL, 0),
		    sizeof(nak));
		assert_memory_equal(o, nak, sizeof(nak));
		o += sizeof(nak);
		tl += (size_t)snprintf(tail + tl, sizeof(tail) - tl, "%s", err7);
		for (int k = 0; k < 10; k++)
			tl += (size_t)snprintf(tail + tl, sizeof(tail) - tl, "%s\n", help);
		tl += (size_t)snprintf(tail + tl, sizeof(tail) - tl,
				       "error %d unknown operation xy\n", CONSOLE_E_UNKNOWN_OP);
		assert_memory_equal(o, tail, tl);
		o += tl;
		assert_int_equal(FP.out + FP.out_len - o, 21);
		assert_int_equal(o[3], 200);
	}
	assert_int_equal(f_executed(), N + 1);
	assert_int_equal(F.srv.serial.port.dropped, 0);
}

/* ---- long comments on vehicle-sim's consoles ----------------------------- */

static void start_sim(void);
static void sim_line(const char *line, const char *want);
static void stop_sim(void);
static int sim_teardown(void **state);

/* Runs cmd in a shell; its stdout in out. */
static void run_capture(const char *cmd, char *out, size_t cap)
{
	FILE *f = popen(cmd, "r");
	size_t n;

	assert_non_null(f);
	n = fread(out, 1, cap - 1, f);
	out[n] = '\0';
	assert_int_equal(pclose(f), 0);
}

/* A comment longer than a line (300 bytes) gets no reply on every console
 * of vehicle-sim: stdin (--fast), stdin beside the port (--pty --fast), and
 * the port. Replies on stdin beside the port are whole up to 1,023 bytes
 * ($config's list, over 511, where they were cut). */
static void test_sim_long_comment(void **state)
{
	char comment[301], path[64], cmd[1200], want[2048], out[4096], cfg[CONSOLE_REPLY_MAX];
	FILE *f;

	(void)state;
	memset(comment, 'x', 300);
	memcpy(comment, "# ", 2);
	comment[300] = '\0';
	assert_true(sim_exec(&F, "$config", cfg, sizeof(cfg)));
	assert_true(strlen(cfg) > 511); /* was cut at 511 */
	snprintf(want, sizeof(want), "ok true 25 \"Unpowered\"\n%s\n", cfg);
	snprintf(path, sizeof(path), "/tmp/vslc-%d.txt", (int)getpid());
	f = fopen(path, "w");
	assert_non_null(f);
	fprintf(f, "%s\ngetState\n   %s\r\n$config\n", comment, comment);
	fclose(f);

	snprintf(cmd, sizeof(cmd),
		 "%s/vehicle-sim --fast --config config/vehicle.xml --io config/io.xml "
		 "< %s 2>/dev/null",
		 BUILD_DIR, path);
	run_capture(cmd, out, sizeof(out));
	assert_string_equal(out, want);

	snprintf(cmd, sizeof(cmd),
		 "%s/vehicle-sim --pty --fast --config config/vehicle.xml --io config/io.xml "
		 "< %s 2>/dev/null",
		 BUILD_DIR, path);
	run_capture(cmd, out, sizeof(out));
	assert_memory_equal(out, "/dev/", 5);
	assert_non_null(strchr(out, '\n'));
	assert_string_equal(strchr(out, '\n') + 1, want);
	unlink(path);

	start_sim();
	snprintf(cmd, sizeof(cmd), "%s\ngetState\n", comment);
	sim_line(cmd, "ok true 25 \"Unpowered\"\n");
	stop_sim();
}

/* Client-side failures: a silent unit is a timeout with retries, not a hang. */
static void test_client_timeout(void **state)
{
	int fds[2];
	bool r;

	(void)state;
	assert_int_equal(pipe(fds), 0);
	/* write end discards into a pipe nobody answers on */
	{
		int m, s;

		assert_int_equal(openpty(&m, &s, NULL, NULL, NULL), 0);
		assert_int_equal(tty_set_raw(s, 115200), 0);
		assert_int_equal(vc_attach_serial_fd(&C, s, true), VC_OK);
		C.timeout_ms = 50;
		C.retries = 2;
		assert_int_equal(vc_stop(&C, &r), VC_E_TIMEOUT);
		/* info handshake (1 attempt) + 3 attempts of stop */
		assert_int_equal(C.stats.retries, 2);
		assert_int_equal(C.stats.timeouts, 4);
		{
			/* the retries repeated the same sequence number */
			uint8_t b[256];
			size_t k = 0;
			struct pollfd pf = {.fd = m, .events = POLLIN};

			/* A pty hands the bytes over in pieces: read all four
			 * requests, or what arrived within 2 s. */
			while (k < 4 * 7 && poll(&pf, 1, 2000) > 0) {
				ssize_t n = read(m, b + k, sizeof(b) - k);
				if (n <= 0)
					break;
				k += (size_t)n;
			}
			assert_int_equal(k, 4 * 7);
			assert_int_equal(b[7 + 4], CMD_OP_stop);
			assert_memory_equal(b + 7, b + 14, 7);
			assert_memory_equal(b + 7, b + 21, 7);
		}
		vc_close(&C);
		close(m);
	}
	close(fds[0]);
	close(fds[1]);
}

/* vehiclectl against vehicle-sim --pty, as a user would. */
static pid_t SIM_PID;
static char PTY_PATH[256];
/* Set: the simulator's stderr (its log) goes to this file. */
static const char *SIM_STDERR;

static void start_sim_traced(const char *trace)
{
	int p[2];
	char exe[600];
	FILE *f;

	snprintf(exe, sizeof(exe), "%s/vehicle-sim", BUILD_DIR);
	assert_int_equal(pipe(p), 0);
	SIM_PID = fork();
	assert_true(SIM_PID >= 0);
	if (SIM_PID == 0) {
		dup2(p[1], 1);
		close(p[0]);
		if (SIM_STDERR && !freopen(SIM_STDERR, "w", stderr))
			_exit(126);
		if (trace)
			execl(exe, exe, "--pty", "--config", "config/vehicle.xml", "--io",
			      "config/io.xml", "--trace", trace, (char *)NULL);
		else
			execl(exe, exe, "--pty", "--config", "config/vehicle.xml", "--io",
			      "config/io.xml", (char *)NULL);
		_exit(127);
	}
	close(p[1]);
	f = fdopen(p[0], "r");
	assert_non_null(f);
	assert_non_null(fgets(PTY_PATH, sizeof(PTY_PATH), f));
	PTY_PATH[strcspn(PTY_PATH, "\n")] = '\0';
	assert_memory_equal(PTY_PATH, "/dev/", 5);
	fclose(f);
}

static void start_sim(void)
{
	start_sim_traced(NULL);
}

/* One console line to the simulator's port, its reply checked. */
static void sim_line(const char *line, const char *want)
{
	char got[128];
	size_t n = 0;
	int fd = open(PTY_PATH, O_RDWR | O_NOCTTY);
	struct termios t;
	assert_true(fd >= 0);
	assert_int_equal(tcgetattr(fd, &t), 0);
	cfmakeraw(&t);
	assert_int_equal(tcsetattr(fd, TCSANOW, &t), 0);
	assert_int_equal(write(fd, line, strlen(line)), (ssize_t)strlen(line));
	while (n + 1 < sizeof(got) && (n == 0 || got[n - 1] != '\n')) {
		ssize_t r = read(fd, got + n, 1);
		assert_true(r == 1);
		n++;
	}
	got[n] = '\0';
	close(fd);
	assert_string_equal(got, want);
}

static void stop_sim(void)
{
	int status = 0;

	kill(SIM_PID, SIGTERM);
	waitpid(SIM_PID, &status, 0);
	assert_true(WIFEXITED(status));
	assert_int_equal(WEXITSTATUS(status), 0);
}

/* Runs vehiclectl; returns its exit status, output in out. */
static int ctl(char *out, size_t cap, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static int ctl(char *out, size_t cap, const char *fmt, ...)
{
	char args[512], cmd[1200];
	va_list ap;
	FILE *f;
	size_t n;
	int st;

	va_start(ap, fmt);
	vsnprintf(args, sizeof(args), fmt, ap);
	va_end(ap);
	snprintf(cmd, sizeof(cmd), "%s/vehiclectl %s 2>&1", BUILD_DIR, args);
	f = popen(cmd, "r");
	assert_non_null(f);
	n = fread(out, 1, cap - 1, f);
	out[n] = '\0';
	st = pclose(f);
	return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

static void test_vehiclectl(void **state)
{
	static char out[16384];
	unsigned lines = 0;
	FILE *f;
	char row[512];

	(void)state;
	assert_int_equal(ctl(out, sizeof(out), "help"), 0);
	for (char *p = out; (p = strstr(p, "\n    ")) != NULL; p++)
		lines++;
	assert_int_equal(lines, CMD_COUNT);
	assert_non_null(strstr(out, " 9 getPosition -> x:double y:double theta:double\n"));
	assert_non_null(strstr(out, "17 moveForward <x_:double>\n"));

	start_sim();
	/* The case pauses between requests as long as a loaded host makes it
	 * (a process per request): no link watchdog, which has its own test. */
	sim_line("$watchdog 0\n", "ok watchdog 0\n");
	assert_int_equal(ctl(out, sizeof(out), "--port %s getVersion", PTY_PATH), 0);
	assert_string_equal(out, "true ver=\"Ver.1.0.0\"\n");
	assert_int_equal(ctl(out, sizeof(out), "--port %s --json getState", PTY_PATH), 0);
	assert_string_equal(
	    out, "{\"op\":\"getState\",\"result\":true,\"state\":25,\"Msg\":\"Unpowered\"}\n");
	/* refused: exit 1, the answer still printed */
	assert_int_equal(ctl(out, sizeof(out), "--port %s moveForward 500", PTY_PATH), 1);
	assert_string_equal(out, "false\n");
	assert_int_equal(ctl(out, sizeof(out), "--port %s --console getState", PTY_PATH), 0);
	assert_string_equal(out, "true state=25 Msg=\"Unpowered\"\n");
	assert_int_equal(ctl(out, sizeof(out), "--port %s setPower true", PTY_PATH), 0);
	assert_int_equal(ctl(out, sizeof(out), "--port %s setservo on", PTY_PATH), 0);
	assert_int_equal(ctl(out, sizeof(out), "--port %s moveTurn -90", PTY_PATH), 0);
	/* usage errors: exit 2 */
	assert_int_equal(ctl(out, sizeof(out), "--port %s moveForward", PTY_PATH), 2);
	assert_int_equal(ctl(out, sizeof(out), "--port %s moveForward abc", PTY_PATH), 2);
	assert_int_equal(ctl(out, sizeof(out), "--port %s nosuchop", PTY_PATH), 2);
	/* link failure: exit 3 */
	assert_int_equal(ctl(out, sizeof(out), "--port /dev/nonexistent-tty getState"), 3);
	assert_int_equal(ctl(out, sizeof(out), "--port %s info", PTY_PATH), 0);
	assert_non_null(strstr(out, "matches"));
	assert_int_equal(
	    ctl(out, sizeof(out), "--port %s --json watch --count 3 --interval 50", PTY_PATH), 0);
	lines = 0;
	for (char *p = out; (p = strstr(p, "{\"t\":")) != NULL; p++)
		lines++;
	assert_int_equal(lines, 3);
	assert_non_null(strstr(out, "\"battery\":"));
	assert_int_equal(
	    ctl(out, sizeof(out),
		"--port %s record /tmp/vehiclectl_test_%d.csv --duration 0.3 --interval 100",
		PTY_PATH, (int)getpid()),
	    0);
	snprintf(row, sizeof(row), "/tmp/vehiclectl_test_%d.csv", (int)getpid());
	f = fopen(row, "r");
	assert_non_null(f);
	assert_non_null(fgets(row, sizeof(row), f));
	/* over frames, the unit's telemetry stream: a row per 100 ms of the
	 * unit's own time, 0 to 0.3 s, whatever the host's load */
	assert_string_equal(row, "t_s,tick,seq,lost,x_mm,y_mm,theta_deg,cmd_vx_mm_s,cmd_vy_mm_s,"
				 "cmd_w_deg_s,meas_vx_mm_s,meas_vy_mm_s,meas_w_deg_s,state,alarms,"
				 "newest_alarm,alarm_type,battery_0_1V,queue_len,inputs,outputs\n");
	lines = 0;
	while (fgets(row, sizeof(row), f)) {
		unsigned long tick, seq, lost;
		double t;

		assert_int_equal(sscanf(row, "%lf,%lu,%lu,%lu,", &t, &tick, &seq, &lost), 4);
		assert_true(fabs(t - 0.1 * lines) < 1e-9);
		assert_int_equal(seq, lines);
		assert_int_equal(lost, 0);
		lines++;
	}
	fclose(f);
	snprintf(row, sizeof(row), "/tmp/vehiclectl_test_%d.csv", (int)getpid());
	unlink(row);
	assert_int_equal(lines, 4);
	/* the unit is left without a subscription */
	sim_line("$stream\n", "ok stream mask 0x00 period 0 sent 0 skipped 0\n");
	/* the turn finished: the pose reads back (polling, as a host does, keeps
	 * the link watchdog fed; bounded at 20 s) */
	for (int i = 0; i < 100; i++) {
		assert_int_equal(ctl(out, sizeof(out), "--port %s getState", PTY_PATH), 0);
		if (!strstr(out, "Busy"))
			break;
		usleep(200000);
	}
	assert_int_equal(ctl(out, sizeof(out), "--port %s getState", PTY_PATH), 0);
	assert_null(strstr(out, "Busy"));
	assert_int_equal(ctl(out, sizeof(out), "--port %s getPosition", PTY_PATH), 0);
	{
		double x = 1, y = 1, th = 0;

		assert_int_equal(sscanf(out, "true x=%lf y=%lf theta=%lf", &x, &y, &th), 3);
		if (!(fabs(x) < 0.5 && fabs(y) < 0.5 && fabs(th + 90.0) < 0.05)) {
			ctl(row, sizeof(row), "--port %s getActiveAlarm 4", PTY_PATH);
			fail_msg("pose %s, alarms %s", out, row);
		}
	}
	stop_sim();
}

/* vehiclectl config: $config over frames (WIRE_OP_CONSOLE) and over the
 * console, the unit's reply printed; exit 1 for a refusal. */
static void test_vehiclectl_config(void **state)
{
	static char out[4096];
	(void)state;
	start_sim();
	sim_line("$watchdog 0\n", "ok watchdog 0\n");
	assert_int_equal(ctl(out, sizeof(out), "--port %s config wheel_diameter_mm", PTY_PATH), 0);
	assert_string_equal(out, "ok wheel_diameter_mm 150.000\n");
	assert_int_equal(ctl(out, sizeof(out), "--port %s config wheel_diameter_mm 160", PTY_PATH),
			 0);
	assert_string_equal(out, "ok wheel_diameter_mm 160.000\n");
	assert_int_equal(ctl(out, sizeof(out), "--port %s config tick_hz 500", PTY_PATH), 0);
	assert_string_equal(out, "ok tick_hz 1000 pending 500\n");
	assert_int_equal(ctl(out, sizeof(out), "--port %s --console config diff", PTY_PATH), 0);
	/* $watchdog 0 changed link_timeout_ms for the run */
	assert_string_equal(out, "ok unsaved 3 tick_hz wheel_diameter_mm link_timeout_ms changed 3 "
				 "tick_hz wheel_diameter_mm link_timeout_ms pending 1 tick_hz\n");
	assert_int_equal(ctl(out, sizeof(out), "--port %s config save", PTY_PATH), 1);
	assert_string_equal(out, "error 8 $config save: this unit has no store\n");
	assert_int_equal(ctl(out, sizeof(out), "--port %s --json config store", PTY_PATH), 0);
	assert_string_equal(out, "{\"ok\": true, \"reply\": \"ok store none table "
				 "0x916B11C3\"}\n");
	assert_int_equal(ctl(out, sizeof(out), "--port %s setPower true", PTY_PATH), 0);
	assert_int_equal(ctl(out, sizeof(out), "--port %s setServo true", PTY_PATH), 0);
	assert_int_equal(
	    ctl(out, sizeof(out), "--port %s --console config wheel_diameter_mm 170", PTY_PATH), 1);
	assert_string_equal(out, "error 8 $config wheel_diameter_mm: wheel_diameter_mm changes "
				 "only with the servo off and no motion queued\n");
	assert_int_equal(ctl(out, sizeof(out), "--port %s config defaults", PTY_PATH), 1);
	assert_string_equal(out, "error 8 $config defaults: wheel_diameter_mm changes only with "
				 "the servo off and no motion queued\n");
	assert_int_equal(ctl(out, sizeof(out), "--port %s setServo false", PTY_PATH), 0);
	assert_int_equal(ctl(out, sizeof(out), "--port %s config defaults", PTY_PATH), 0);
	assert_string_equal(out, "ok defaults pending 0\n");
	sim_line("$watchdog 0\n", "ok watchdog 0\n");
	/* a line over what a frame carries */
	assert_int_equal(ctl(out, sizeof(out),
			     "--port %s config drive_lag_ms 1.000000000 2.000000000 3.000000000 "
			     "4.000000000",
			     PTY_PATH),
			 2);
	assert_string_equal(out, "vehiclectl: config: a line of at most 64 bytes\n");
	stop_sim();
}

/* vehiclectl wait and --wait, after a refused request left warning 111:
 * done when the move has ended (exit 0), stopped short by a fault (exit 1),
 * not done within --wait-limit (exit 4). */
static void test_vehiclectl_wait(void **state)
{
	static char out[4096];
	char log[64], line[256], events[2048] = "";
	double x = 0, y = 1, th = 1;
	FILE *f;

	(void)state;
	snprintf(log, sizeof(log), "/tmp/vsls-%d.log", (int)getpid());
	SIM_STDERR = log;
	start_sim();
	SIM_STDERR = NULL;
	/* a process per request: pauses as long as a loaded host makes them */
	sim_line("$watchdog 0\n", "ok watchdog 0\n");
	assert_int_equal(ctl(out, sizeof(out), "--port %s wait now", PTY_PATH), 2);
	assert_string_equal(out,
			    "vehiclectl: wait takes no argument (its limit: --wait-limit S)\n");
	assert_int_equal(ctl(out, sizeof(out), "--port %s --wait-limit x wait", PTY_PATH), 2);
	assert_int_equal(ctl(out, sizeof(out), "--port %s wait", PTY_PATH), 1);
	assert_string_equal(out, "stopped state=25 Msg=\"Unpowered\"\n");
	assert_int_equal(ctl(out, sizeof(out), "--port %s setPower true", PTY_PATH), 0);
	assert_int_equal(ctl(out, sizeof(out), "--port %s setServo true", PTY_PATH), 0);
	assert_int_equal(ctl(out, sizeof(out), "--port %s setVelocity 0 10", PTY_PATH), 1);
	assert_int_equal(ctl(out, sizeof(out), "--port %s --wait moveForward 300", PTY_PATH), 0);
	assert_string_equal(out, "true\ndone state=18 Msg=\"Warning-111\"\n");
	assert_int_equal(ctl(out, sizeof(out), "--port %s getPosition", PTY_PATH), 0);
	assert_int_equal(sscanf(out, "true x=%lf y=%lf theta=%lf", &x, &y, &th), 3);
	/* in position: the wheels within the 0.05 mm window */
	assert_true(fabs(x - 300.0) <= 0.05);
	assert_true(fabs(y) <= 0.05 && fabs(th) <= 0.01);
	/* refused: no wait, exit 1 */
	assert_int_equal(ctl(out, sizeof(out), "--port %s --wait moveForward 1e9", PTY_PATH), 1);
	assert_string_equal(out, "false\n");

	assert_int_equal(ctl(out, sizeof(out), "--port %s moveForward 5000", PTY_PATH), 0);
	sim_line("$sim drive 1 fault 0x2310\n", "ok drive 1 fault 0x2310\n");
	assert_int_equal(ctl(out, sizeof(out), "--port %s --json wait", PTY_PATH), 1);
	assert_string_equal(
	    out, "{\"op\":\"wait\",\"outcome\":\"stopped\",\"state\":19,\"Msg\":\"Alarm-201\"}\n");

	sim_line("$sim drive 1 ok\n", "ok drive 1 ok\n");
	assert_int_equal(ctl(out, sizeof(out), "--port %s clearAlarm", PTY_PATH), 0);
	assert_int_equal(ctl(out, sizeof(out), "--port %s setServo true", PTY_PATH), 0);
	assert_int_equal(
	    ctl(out, sizeof(out), "--port %s --wait-limit 0.1 --wait moveForward 5000", PTY_PATH),
	    4);
	assert_string_equal(out, "true\ntimeout state=17 Msg=\"Busy\"\n");
	assert_int_equal(ctl(out, sizeof(out), "--port %s --wait stop", PTY_PATH), 0);
	assert_string_equal(out, "true\ndone state=16 Msg=\"Ready\"\n");
	stop_sim();
	/* its log: every alarm as it was raised and cleared (in real time: the
	 * lines without their times) */
	f = fopen(log, "r");
	assert_non_null(f);
	while (fgets(line, sizeof(line), f)) {
		char *at = strstr(line, " at ");

		if (strncmp(line, "vehicle-sim: alarm ", 19) != 0)
			continue;
		assert_non_null(at);
		assert_string_equal(at + strlen(at) - 3, " s\n");
		strcpy(at, "\n");
		strncat(events, line + 13, sizeof(events) - strlen(events) - 1);
	}
	fclose(f);
	unlink(log);
	assert_string_equal(events,
			    "alarm raised 111 warning \"setVelocity refused: out of limits\"\n"
			    "alarm raised 110 warning \"moveForward refused: invalid argument\"\n"
			    "alarm raised 201 fault \"drive 1 fault 0x2310\"\n"
			    "alarm cleared 111 warning \"setVelocity refused: out of limits\"\n"
			    "alarm cleared 110 warning \"moveForward refused: invalid argument\"\n"
			    "alarm cleared 201 fault \"drive 1 fault 0x2310\"\n");
}

/* A failed test leaves no simulator behind. */
static int sim_teardown(void **state)
{
	(void)state;
	if (SIM_PID > 0) {
		kill(SIM_PID, SIGKILL);
		waitpid(SIM_PID, NULL, 0);
		SIM_PID = 0;
	}
	return 0;
}

/* The last row of a CSV trace that the simulator is writing. */
static bool trace_last_row(const char *path, char *row, size_t cap)
{
	FILE *f = fopen(path, "r");
	char line[512];
	bool got = false;

	if (!f)
		return false;
	while (fgets(line, sizeof(line), f))
		if (strchr(line, '\n') && line[0] != 't') {
			snprintf(row, cap, "%s", line);
			got = true;
		}
	fclose(f);
	return got;
}

/* Column k (0-based) of a trace row. */
static double trace_col(const char *row, int k)
{
	const char *p = row;
	for (int i = 0; i < k && p; i++) {
		p = strchr(p, ',');
		if (p)
			p++;
	}
	return p ? atof(p) : NAN;
}

/* The host process (binary frames through the client library) dies
 * mid-route; vehicle-sim --pty in real time, link_timeout_ms 1000 from
 * config/vehicle.xml. The test then waits without a request, watching the
 * simulator's trace, so that only the dead host's silence counts. The unit
 * stops within timeout x v + v^2 / (2 a_max) + 2 ticks of travel from the
 * pose of the last request, with warning 153 and the queue discarded, and
 * a new command afterwards runs. The bound is in the simulator's own time,
 * which a busy host slows but never makes irregular. */
static void test_link_watchdog_host_killed(void **state)
{
	char trace[64], row[512];
	int p[2];
	double x0 = 0;

	(void)state;
	snprintf(trace, sizeof(trace), "/tmp/vswd-%d.csv", (int)getpid());
	start_sim_traced(trace);
	assert_int_equal(pipe(p), 0);
	pid_t host = fork();
	assert_true(host >= 0);
	if (host == 0) {
		vc_client_t h;
		bool r = false;
		vs_position_t pos = {0, 0, 0};
		close(p[0]);
		if (vc_open_serial(&h, PTY_PATH, 115200) != VC_OK || vc_setPower(&h, &r, true) ||
		    vc_setServo(&h, &r, true) || vc_moveForward(&h, &r, 5000.0) || !r ||
		    vc_moveLinearAbs(&h, &r, (vs_position_t){0, 0, 0}) || !r)
			_exit(1);
		/* A status stream while the route runs: getPosition every 100 ms
		 * for 2 s (at cruise speed from 1 s on). */
		for (int i = 0; i < 20; i++) {
			usleep(100000);
			if (vc_getPosition(&h, &r, &pos))
				_exit(2);
		}
		/* The pose the unit had at the last request it will hear. */
		if (write(p[1], &pos.x, sizeof pos.x) != (ssize_t)sizeof pos.x)
			_exit(3);
		pause(); /* killed here, mid-route */
		_exit(4);
	}
	close(p[1]);
	assert_int_equal(read(p[0], &x0, sizeof x0), (ssize_t)sizeof x0);
	close(p[0]);
	assert_int_equal(kill(host, SIGKILL), 0);
	waitpid(host, NULL, 0);
	assert_true(x0 > 500.0 && x0 < 1500.0);

	/* Wait, silent, until the trace shows the unit no longer Busy. */
	int tries = 0;
	do {
		usleep(50000);
	} while ((!trace_last_row(trace, row, sizeof row) || trace_col(row, 21) == 17) &&
		 ++tries < 600);
	assert_true(trace_col(row, 21) != 17);
	/* then at rest: the drives stop and the motors' lag settles */
	usleep(500000);

	vc_client_t c;
	bool r = false;
	vs_position_t pos;
	int16_t st = 0, na = 0;
	uint16_t len = 0;
	char msg[VS_STATE_MSG_MAX];
	vs_alarm_t al[4];
	assert_int_equal(vc_open_serial(&c, PTY_PATH, 115200), VC_OK);
	assert_int_equal(vc_getState(&c, &r, &st, msg), VC_OK);
	assert_int_equal(st, VS_STATE_WARNING);
	assert_string_equal(msg, "Warning-153");
	assert_int_equal(vc_getActiveAlarm(&c, &r, 4, &na, al, &len), VC_OK);
	assert_int_equal(na, 1);
	assert_int_equal(al[0].code, 153);
	assert_string_equal(al[0].source, "link lost: frames silent 1000 ms");
	assert_int_equal(vc_getPosition(&c, &r, &pos), VC_OK);
	/* 500 mm/s, 1000 mm/s^2 limit, 1 kHz */
	double bound = 1.0 * 500.0 + 500.0 * 500.0 / (2.0 * 1000.0) + 2.0 * 0.5;
	assert_true(pos.x - x0 <= bound);
	assert_true(pos.x - x0 > bound - 3.0);
	/* the queued moveLinearAbs 0 0 0 is gone: the unit stays */
	usleep(300000);
	vs_position_t pos2;
	assert_int_equal(vc_getPosition(&c, &r, &pos2), VC_OK);
	assert_true(fabs(pos2.x - pos.x) < 0.05);
	/* a new command runs normally */
	assert_int_equal(vc_moveForward(&c, &r, 100.0), VC_OK);
	assert_true(r);
	tries = 0;
	do {
		usleep(100000);
		assert_int_equal(vc_getState(&c, &r, &st, msg), VC_OK);
	} while (st == VS_STATE_BUSY && ++tries < 100);
	assert_int_equal(vc_getPosition(&c, &r, &pos2), VC_OK);
	/* the default plant's 20 ms motor lag still shows at Ready */
	assert_true(fabs(pos2.x - pos.x - 100.0) < 1.0);
	vc_close(&c);
	stop_sim();
	SIM_PID = 0;
	unlink(trace);
}

int main(int argc, char **argv)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test_setup_teardown(test_console_raw, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_console_utf8, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_binary_client, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_client_stream, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_console_client, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_wait_done_frames, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_wait_done_console, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_retransmission_runs_once, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_bad_input, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_pipelined_flow_control, setup, teardown),
	    cmocka_unit_test_setup(test_budget_requests, fake_setup),
	    cmocka_unit_test_setup(test_budget_answer_bytes, fake_setup),
	    cmocka_unit_test_setup(test_budget_bytes_read, fake_setup),
	    cmocka_unit_test_setup(test_flow_port_full, fake_setup),
	    cmocka_unit_test_setup(test_flow_damaged_frame, fake_setup),
	    cmocka_unit_test_setup_teardown(test_sim_long_comment, fake_setup, sim_teardown),
	    cmocka_unit_test(test_client_timeout),
	    cmocka_unit_test(test_vehiclectl),
	    cmocka_unit_test(test_vehiclectl_config),
	    cmocka_unit_test_teardown(test_vehiclectl_wait, sim_teardown),
	    cmocka_unit_test_teardown(test_link_watchdog_host_killed, sim_teardown),
	};

	if (argc > 0) {
		char tmp[512];

		/* BUILD/tests/test_link_serial -> BUILD */
		snprintf(tmp, sizeof(tmp), "%s", argv[0]);
		snprintf(BUILD_DIR, sizeof(BUILD_DIR), "%s", dirname(dirname(tmp)));
	}
	signal(SIGPIPE, SIG_IGN);
	return cmocka_run_group_tests(tests, NULL, NULL);
}
