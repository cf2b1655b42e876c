/* vehiclectl: drive a vehicle unit (or vehicle-sim) from a shell.
 *
 *   vehiclectl --port /dev/ttyUSB0 moveForward 500
 *   vehiclectl --can can0 getPosition
 *   vehiclectl --port /dev/pts/3 --json watch --count 5
 *   vehiclectl --port /dev/pts/3 --wait moveForward 500
 *
 * Every operation of the command table is a command; its arguments follow
 * the console's rules (numbers, true/false/on/off/1/0). Exit status: 0 the
 * operation returned true, 1 it returned false, 2 usage, 3 link failure.
 * 'wait' (and --wait after an operation that returned true) polls getState
 * until the unit is done (vc_wait_done): 0 done (Ready, or Warning-### while
 * idle), 1 stopped short (a fault, Locked, Stuck, servo or power off), 4
 * still busy or paused after --wait-limit.
 */
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "../proto/client/bboxfile.h"
#include "../proto/client/client.h"
#include "../proto/cmdtab.h"
#include "../proto/numparse.h"

static volatile sig_atomic_t stop_requested;

static void on_signal(int sig)
{
	(void)sig;
	stop_requested = 1;
}

static void usage(FILE *f)
{
	fputs(
	    "usage: vehiclectl LINK [options] COMMAND [ARGS...]\n"
	    "links:\n"
	    "  --port DEV      serial port, binary frames (docs/protocol.md)\n"
	    "  --baud N        line speed (default 115200)\n"
	    "  --console       speak the text console on the port instead of frames\n"
	    "  --can IFACE     SocketCAN interface (docs/can.md)\n"
	    "  --node N        CAN node id of the unit (default 1)\n"
	    "options:\n"
	    "  --json          one JSON object per answer\n"
	    "  --timeout MS    per attempt (default 500)\n"
	    "  --retries N     further attempts after a timeout (default 2)\n"
	    "  --wait          after an operation that returned true, wait as 'wait' does\n"
	    "  --wait-limit S  longest wait, seconds (default 300)\n"
	    "commands:\n"
	    "  OPERATION ARGS  any operation of the command table (see 'help')\n"
	    "  help [OP]       the operations, or one with its arguments\n"
	    "  info            protocol version and command table checksum of the unit\n"
	    "  wait            until the unit is done: Ready, or Warning-### while idle\n"
	    "                  (exit 0); a fault, Locked, Stuck, servo or power off (exit 1);\n"
	    "                  still busy or paused after --wait-limit (exit 4)\n"
	    "  watch [--count N] [--interval MS]\n"
	    "                  state, pose, speed, battery and alarms until Ctrl-C (over\n"
	    "                  frames: the unit's telemetry stream, every value each MS)\n"
	    "  record FILE --duration S [--interval MS]\n"
	    "                  the same as CSV rows into FILE (docs/trace.md)\n"
	    "  config [NAME [VALUE...] | NAME[K] VALUE | diff | save | defaults | reload | store]\n"
	    "                  the unit's $config (docs/console.md): prints its reply; exit 0\n"
	    "                  on ok, 1 when the unit refused (error ...)\n"
	    "  bbox FILE       the unit's black box (serial frames) into FILE as CSV rows\n"
	    "                  (docs/trace.md), its fault marked; bbox clear: empty, re-arm\n",
	    f);
}

static void print_help_op(const cmd_def_t *d)
{
	printf("%2u %s", d->opcode, d->name);
	for (unsigned i = 0; i < d->n_in; i++) {
		const char *n;
		size_t l = cmd_field_name(d->in_names, i, &n);

		printf(" <%.*s:%s>", (int)l, n, cmd_type_idl(d->in_types[i]));
	}
	if (d->n_out) {
		printf(" ->");
		for (unsigned i = 0; i < d->n_out; i++) {
			const char *n;
			size_t l = cmd_field_name(d->out_names, i, &n);

			printf(" %.*s:%s", (int)l, n, cmd_type_idl(d->out_types[i]));
		}
	}
	printf("\n    %s\n", d->help);
}

static int cmd_help(int argc, char **argv)
{
	if (argc > 1) {
		const cmd_def_t *d = cmd_by_name(argv[1]);

		if (!d) {
			fprintf(stderr, "vehiclectl: no operation %s\n", argv[1]);
			return 2;
		}
		print_help_op(d);
		return 0;
	}
	printf("Operations (protocol %d, table 0x%04X):\n", CMD_PROTO_VERSION,
	       (unsigned)cmd_table_crc());
	for (unsigned i = 0; i < CMD_COUNT; i++)
		print_help_op(&cmd_table[i]);
	return 0;
}

static void json_str(FILE *f, const char *s)
{
	fputc('"', f);
	for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
		if (*p == '"' || *p == '\\')
			fprintf(f, "\\%c", *p);
		else if (*p < 0x20 || *p >= 0x7f)
			fprintf(f, "\\u%04x", *p);
		else
			fputc(*p, f);
	}
	fputc('"', f);
}

static const char *alarm_type(uint8_t t)
{
	return t == VS_ALARM_FAULT ? "fault" : t == VS_ALARM_WARNING ? "warning" : "unknown";
}

static void print_double(double d, bool json)
{
	if (json && !isfinite(d))
		printf("null");
	else
		printf("%.17g", d);
}

static void print_result(const cmd_def_t *d, bool r, const cmd_value_t out[], bool json)
{
	if (json)
		printf("{\"op\":\"%s\",\"result\":%s", d->name, r ? "true" : "false");
	else
		printf("%s", r ? "true" : "false");
	for (unsigned i = 0; i < d->n_out; i++) {
		const char *n;
		size_t l = cmd_field_name(d->out_names, i, &n);
		const cmd_value_t *v = &out[i];

		printf(json ? ",\"%.*s\":" : " %.*s=", (int)l, n);
		switch (d->out_types[i]) {
		case CMD_T_BOOL:
			printf("%s", v->b ? "true" : "false");
			break;
		case CMD_T_SHORT:
			printf("%d", v->h);
			break;
		case CMD_T_ULONG:
			printf("%lu", (unsigned long)v->u);
			break;
		case CMD_T_DOUBLE:
			print_double(v->d, json);
			break;
		case CMD_T_STRING:
			json_str(stdout, v->s);
			break;
		case CMD_T_ALARMS:
			printf(json ? "[" : "%u[", (unsigned)v->alarms.n);
			for (uint16_t k = 0; k < v->alarms.n; k++) {
				const vs_alarm_t *a = &v->alarms.a[k];

				if (json)
					printf("%s{\"code\":%lu,\"type\":\"%s\",\"source\":",
					       k ? "," : "", (unsigned long)a->code,
					       alarm_type(a->type));
				else
					printf("%s%lu %s ", k ? ", " : "", (unsigned long)a->code,
					       alarm_type(a->type));
				json_str(stdout, a->source);
				if (json)
					printf("}");
			}
			printf("]");
			break;
		default:
			break;
		}
	}
	printf(json ? "}\n" : "\n");
}

static int report_err(vc_client_t *c, int e)
{
	if (e == VC_E_NAK)
		fprintf(stderr, "vehiclectl: %s: %s\n", vc_strerror(e), wire_status_name(c->nak));
	else if (e == VC_E_REMOTE)
		fprintf(stderr, "vehiclectl: error %s\n", c->remote_msg);
	else
		fprintf(stderr, "vehiclectl: %s%s%s\n", vc_strerror(e), errno ? ": " : "",
			errno ? strerror(errno) : "");
	return 3;
}

static int cmd_op(vc_client_t *c, const cmd_def_t *d, int argc, char **argv, bool json)
{
	cmd_value_t in[CMD_MAX_FIELDS], out[CMD_MAX_FIELDS];
	bool r = false;
	int e;

	if (argc - 1 != d->n_in) {
		fprintf(stderr, "vehiclectl: %s takes %u argument%s, got %d\n", d->name, d->n_in,
			d->n_in == 1 ? "" : "s", argc - 1);
		return 2;
	}
	memset(in, 0, sizeof(in));
	for (unsigned i = 0; i < d->n_in; i++) {
		const char *tok = argv[i + 1];
		int64_t iv = 0;
		bool ok = false;

		switch (d->in_types[i]) {
		case CMD_T_BOOL:
			ok = np_parse_bool(tok, &in[i].b);
			break;
		case CMD_T_DOUBLE:
			ok = np_parse_double(tok, &in[i].d) == NP_OK;
			break;
		case CMD_T_SHORT:
			ok = np_parse_int(tok, INT16_MIN, INT16_MAX, &iv) == NP_OK;
			in[i].h = (int16_t)iv;
			break;
		case CMD_T_ULONG:
			ok = np_parse_int(tok, 0, UINT32_MAX, &iv) == NP_OK;
			in[i].u = (uint32_t)iv;
			break;
		default:
			break;
		}
		if (!ok) {
			const char *n;
			size_t l = cmd_field_name(d->in_names, i, &n);

			fprintf(stderr, "vehiclectl: %s %.*s: not a %s: %s\n", d->name, (int)l, n,
				cmd_type_idl(d->in_types[i]), tok);
			return 2;
		}
	}
	errno = 0;
	e = vc_call(c, d, in, &r, out);
	if (e != VC_OK)
		return report_err(c, e);
	print_result(d, r, out, json);
	return r ? 0 : 1;
}

/* config ARGS: the console line "$config ARGS" run by the unit. */
static int cmd_config(vc_client_t *c, int argc, char **argv, bool json)
{
	char line[128], reply[1100];
	size_t n = (size_t)snprintf(line, sizeof(line), "$config");
	for (int i = 1; i < argc && n < sizeof(line); i++)
		n += (size_t)snprintf(line + n, sizeof(line) - n, " %s", argv[i]);
	if (n >= sizeof(line)) {
		fprintf(stderr, "vehiclectl: config: line too long\n");
		return 2;
	}
	int e = vc_console_line(c, line, reply, sizeof(reply));
	if (e == VC_E_ARG) {
		fprintf(stderr, "vehiclectl: config: a line of at most 64 bytes\n");
		return 2;
	}
	if (e != VC_OK) {
		fprintf(stderr, "vehiclectl: config: %s\n", vc_strerror(e));
		return 3;
	}
	bool ok = strncmp(reply, "ok", 2) == 0;
	if (json) {
		printf("{\"ok\": %s, \"reply\": \"", ok ? "true" : "false");
		for (const char *p = reply; *p; p++)
			printf(*p == '"' || *p == '\\' ? "\\%c" : "%c", *p);
		printf("\"}\n");
	} else {
		printf("%s\n", reply);
	}
	return ok ? 0 : 1;
}

static int cmd_info(vc_client_t *c, bool json)
{
	unsigned ver = 0, ops = 0;
	uint16_t crc = 0;
	int e;

	errno = 0;
	e = vc_info(c, &ver, &crc, &ops);
	if (e != VC_OK)
		return report_err(c, e);
	if (json)
		printf("{\"protocol\":%u,\"table\":%u,\"operations\":%u,\"match\":%s}\n", ver, crc,
		       ops, ver == CMD_PROTO_VERSION && crc == cmd_table_crc() ? "true" : "false");
	else
		printf("protocol %u table 0x%04X operations %u (%s this vehiclectl)\n", ver, crc,
		       ops,
		       ver == CMD_PROTO_VERSION && crc == cmd_table_crc() ? "matches"
									  : "DIFFERS from");
	return 0;
}

/* bbox FILE: the unit's black box into FILE (docs/trace.md, "Black box");
 * bbox clear: emptied and re-armed. */
static int cmd_bbox(vc_client_t *c, int argc, char **argv, bool json)
{
	static const char *const st[] = {"off", "armed", "frozen"};
	static bbox_sample_t smp[UINT16_MAX];
	static const bbox_sample_t *row[UINT16_MAX];
	bbox_page_t pg;
	size_t n = 0;
	int e;

	if (argc != 2) {
		fprintf(stderr, "vehiclectl: bbox FILE | bbox clear\n");
		return 2;
	}
	errno = 0;
	if (strcmp(argv[1], "clear") == 0)
		e = vc_bbox_clear(c, &pg);
	else
		e = vc_bbox_read(c, smp, UINT16_MAX, &n, &pg);
	if (e != VC_OK)
		return report_err(c, e);
	const char *status = pg.status < 3 ? st[pg.status] : "?";
	if (strcmp(argv[1], "clear") != 0) {
		for (size_t i = 0; i < n; i++)
			row[i] = &smp[i];
		if (bbox_file_write(argv[1], row, (uint32_t)n, pg.tick_hz, pg.trigger, pg.fault) <
		    0) {
			fprintf(stderr, "vehiclectl: %s: %s\n", argv[1], strerror(errno));
			return 3;
		}
	}
	if (json)
		printf("{\"status\":\"%s\",\"samples\":%zu,\"every\":%u,\"tick_hz\":%u,"
		       "\"trigger\":%lu,\"fault\":%lu}\n",
		       status, n, pg.every, pg.tick_hz, (unsigned long)pg.trigger,
		       (unsigned long)pg.fault);
	else
		printf("bbox %s: %zu samples, one every %u ticks at %u Hz, fault %lu at tick %lu\n",
		       status, n, pg.every, pg.tick_hz, (unsigned long)pg.fault,
		       (unsigned long)pg.trigger);
	return 0;
}

/* wait: polls until the unit is done, prints the state it ended in. */
static int cmd_wait(vc_client_t *c, double limit_s, bool json)
{
	int16_t st = 0;
	char msg[VS_STATE_MSG_MAX] = "";
	const char *how;
	int e;

	errno = 0;
	e = vc_wait_done(c, (unsigned)(limit_s * 1000.0 + 0.5), &st, msg);
	if (e != VC_OK && e != VC_E_STOPPED && e != VC_E_NOT_DONE)
		return report_err(c, e);
	how = e == VC_OK ? "done" : e == VC_E_STOPPED ? "stopped" : "timeout";
	if (json)
		printf("{\"op\":\"wait\",\"outcome\":\"%s\",\"state\":%d,\"Msg\":", how, st);
	else
		printf("%s state=%d Msg=", how, st);
	json_str(stdout, msg);
	printf(json ? "}\n" : "\n");
	return e == VC_OK ? 0 : e == VC_E_STOPPED ? 1 : 4;
}

/* One sample of the unit for watch and record. */
typedef struct {
	double t;
	int16_t state;
	char msg[VS_STATE_MSG_MAX];
	vs_position_t pos;
	double speed_t, speed_r; /* from successive poses, mm/s and deg/s */
	double battery;
	int16_t alarms;
	uint32_t code; /* newest alarm, 0 if none */
} sample_t;

static int take_sample(vc_client_t *c, sample_t *s)
{
	vs_alarm_t a[1];
	uint16_t n = 0;
	int e;

	memset(a, 0, sizeof(a));
	if ((e = vc_getState(c, NULL, &s->state, s->msg)) != VC_OK ||
	    (e = vc_getPosition(c, NULL, &s->pos)) != VC_OK ||
	    (e = vc_getBatteryVoltage(c, NULL, &s->battery)) != VC_OK ||
	    (e = vc_getActiveAlarm(c, NULL, 1, &s->alarms, a, &n)) != VC_OK)
		return e;
	s->code = n ? a[0].code : 0;
	return VC_OK;
}

static double now_s(void)
{
	struct timespec ts;

	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static void sleep_until(double t)
{
	double d = t - now_s();

	if (d > 0) {
		struct timespec ts = {(time_t)d, (long)((d - floor(d)) * 1e9)};

		nanosleep(&ts, NULL);
	}
}

static void derive_speed(sample_t *s, const sample_t *prev)
{
	double dt = s->t - prev->t, dth;

	if (dt <= 0)
		return;
	s->speed_t = hypot(s->pos.x - prev->pos.x, s->pos.y - prev->pos.y) / dt;
	dth = fmod(s->pos.theta - prev->pos.theta + 540.0, 360.0) - 180.0;
	s->speed_r = dth / dt;
}

static int sample_loop(vc_client_t *c, FILE *csv, bool json, long count, double duration,
		       unsigned interval_ms)
{
	sample_t prev = {0}, s;
	double t0 = now_s(), next = t0;
	bool have_prev = false;
	long k = 0;

	if (csv)
		fprintf(csv, "t_s,state,msg,x_mm,y_mm,theta_deg,speed_mm_s,speed_deg_s,"
			     "battery_0_1V,alarms,newest_alarm\n");
	while (!stop_requested && (count < 0 || k < count) &&
	       (duration < 0 || now_s() - t0 <= duration)) {
		int e;

		memset(&s, 0, sizeof(s));
		s.t = now_s() - t0;
		errno = 0;
		e = take_sample(c, &s);
		if (e != VC_OK)
			return report_err(c, e);
		if (have_prev)
			derive_speed(&s, &prev);
		if (csv) {
			fprintf(csv, "%.3f,%d,%s,%.3f,%.3f,%.3f,%.3f,%.3f,%.1f,%d,%lu\n", s.t,
				s.state, s.msg, s.pos.x, s.pos.y, s.pos.theta, s.speed_t, s.speed_r,
				s.battery, s.alarms, (unsigned long)s.code);
			fflush(csv);
		} else if (json) {
			printf("{\"t\":%.3f,\"state\":%d,\"msg\":", s.t, s.state);
			json_str(stdout, s.msg);
			printf(",\"x\":%.3f,\"y\":%.3f,\"theta\":%.3f,\"speed\":%.3f,"
			       "\"rotation\":%.3f,\"battery\":%.1f,\"alarms\":%d,\"newest\":%lu}\n",
			       s.pos.x, s.pos.y, s.pos.theta, s.speed_t, s.speed_r, s.battery,
			       s.alarms, (unsigned long)s.code);
		} else {
			printf("%8.3f s  %-12s x %9.3f y %9.3f th %8.3f  v %8.3f mm/s %8.3f deg/s  "
			       "bat %5.1f  alarms %d%s",
			       s.t, s.msg, s.pos.x, s.pos.y, s.pos.theta, s.speed_t, s.speed_r,
			       s.battery / 10.0, s.alarms, s.code ? " newest " : "");
			if (s.code)
				printf("%lu", (unsigned long)s.code);
			printf("\n");
		}
		fflush(stdout);
		prev = s;
		have_prev = true;
		k++;
		next += interval_ms / 1000.0;
		sleep_until(next);
	}
	return 0;
}

/* ---- watch and record over the telemetry stream (serial frames) ---- */

static unsigned long line_baud = VC_DEFAULT_BAUD;

static void stream_csv_row(FILE *f, double t, const vc_sample_t *s)
{
	const stream_sample_t *v = &s->v;

	fprintf(f,
		"%.3f,%lu,%u,%lu,%.1f,%.1f,%.3f,%d,%d,%.1f,%d,%d,%.1f,%u,%u,%lu,%u,%.1f,%u,%u,%u\n",
		t, (unsigned long)s->tick, s->seq, (unsigned long)s->lost, v->x_dmm / 10.0,
		v->y_dmm / 10.0, v->theta_mdeg / 1000.0, v->vx_mm_s, v->vy_mm_s, v->w_ddeg_s / 10.0,
		v->mvx_mm_s, v->mvy_mm_s, v->mw_ddeg_s / 10.0, v->state, v->alarms,
		(unsigned long)v->alarm_code, v->alarm_type, v->battery_cV / 10.0, v->queue,
		v->inputs, v->outputs);
}

static void stream_print(double t, const vc_sample_t *s, bool json)
{
	const stream_sample_t *v = &s->v;

	if (json) {
		printf("{\"t\":%.3f,\"tick\":%lu,\"seq\":%u,\"lost\":%lu,\"state\":%u,"
		       "\"x\":%.1f,\"y\":%.1f,\"theta\":%.3f,\"vx\":%d,\"vy\":%d,\"w\":%.1f,"
		       "\"mvx\":%d,\"mvy\":%d,\"mw\":%.1f,\"battery\":%.1f,\"alarms\":%u,"
		       "\"newest\":%lu,\"queue\":%u,\"inputs\":%u,\"outputs\":%u}\n",
		       t, (unsigned long)s->tick, s->seq, (unsigned long)s->lost, v->state,
		       v->x_dmm / 10.0, v->y_dmm / 10.0, v->theta_mdeg / 1000.0, v->vx_mm_s,
		       v->vy_mm_s, v->w_ddeg_s / 10.0, v->mvx_mm_s, v->mvy_mm_s,
		       v->mw_ddeg_s / 10.0, v->battery_cV / 10.0, v->alarms,
		       (unsigned long)v->alarm_code, v->queue, v->inputs, v->outputs);
		return;
	}
	printf("%8.3f s  state %2u  x %9.1f y %9.1f th %8.3f  v %5d mm/s %7.1f deg/s  "
	       "meas %5d %7.1f  bat %5.2f  queue %u  alarms %u",
	       t, v->state, v->x_dmm / 10.0, v->y_dmm / 10.0, v->theta_mdeg / 1000.0, v->vx_mm_s,
	       v->w_ddeg_s / 10.0, v->mvx_mm_s, v->mw_ddeg_s / 10.0, v->battery_cV / 100.0,
	       v->queue, v->alarms);
	if (v->alarm_code)
		printf(" newest %lu", (unsigned long)v->alarm_code);
	if (s->lost)
		printf("  (%lu lost)", (unsigned long)s->lost);
	printf("\n");
}

/* stream_loop: the unit has no stream (an older unit, or a board image
 * from before the board carried it, NAKs the subscription's opcode), so
 * the caller polls instead. */
#define STREAM_UNSUPPORTED (-1)

/* Every group every interval_ms, as the unit sends it: time is the unit's
 * (its tick count), not the host's. Passive: the stream keeps no motion
 * alive (docs/protocol.md). Unsubscribes at the end. */
static int stream_loop(vc_client_t *c, FILE *csv, bool json, long count, double duration,
		       unsigned interval_ms)
{
	vc_stream_info_t info;
	vc_sample_t s;
	uint32_t tick0 = 0;
	long k = 0;
	int e = vc_stream_subscribe(c, STREAM_MASK_ALL, interval_ms, &info);

	if (e == VC_E_NAK && c->nak == WIRE_ST_RATE) {
		fprintf(stderr,
			"vehiclectl: the line (%lu baud) cannot carry every value every %u ms; "
			"--interval %lu or more\n",
			line_baud, interval_ms,
			(unsigned long)stream_min_period_ms(STREAM_MASK_ALL, (uint32_t)line_baud));
		return 2;
	}
	if (e == VC_E_NAK && c->nak == WIRE_ST_OPCODE)
		return STREAM_UNSUPPORTED;
	if (e != VC_OK)
		return report_err(c, e);
	if (csv)
		fprintf(csv, "t_s,tick,seq,lost,x_mm,y_mm,theta_deg,cmd_vx_mm_s,cmd_vy_mm_s,"
			     "cmd_w_deg_s,meas_vx_mm_s,meas_vy_mm_s,meas_w_deg_s,state,alarms,"
			     "newest_alarm,alarm_type,battery_0_1V,queue_len,inputs,outputs\n");
	while (!stop_requested && (count < 0 || k < count)) {
		double t;

		e = vc_stream_next(c, &s, interval_ms + 1000u);
		if (e != VC_OK) {
			if (stop_requested)
				break;
			fprintf(stderr, "vehiclectl: stream: %s\n", vc_strerror(e));
			vc_stream_unsubscribe(c);
			return 1;
		}
		if (k == 0)
			tick0 = s.tick;
		t = (double)(s.tick - tick0) / (info.tick_hz ? info.tick_hz : 1000);
		if (duration >= 0 && t > duration + 1e-9)
			break;
		if (csv) {
			stream_csv_row(csv, t, &s);
			fflush(csv);
		} else {
			stream_print(t, &s, json);
		}
		fflush(stdout);
		k++;
	}
	e = vc_stream_unsubscribe(c);
	return e == VC_OK ? 0 : report_err(c, e);
}

static bool parse_ulong(const char *s, unsigned long max, unsigned long *out)
{
	char *end;

	errno = 0;
	*out = strtoul(s, &end, 10);
	return *s && !*end && errno == 0 && *out <= max;
}

/* watch/record options after the command word. */
static int loop_cmd(vc_client_t *c, int argc, char **argv, bool json, bool record)
{
	long count = -1;
	double duration = -1;
	unsigned long interval = 200, v;
	const char *file = NULL;
	FILE *csv = NULL;
	int rc;

	for (int i = 1; i < argc; i++) {
		if (strcmp(argv[i], "--count") == 0 && i + 1 < argc &&
		    parse_ulong(argv[i + 1], 1000000000, &v)) {
			count = (long)v;
			i++;
		} else if (strcmp(argv[i], "--interval") == 0 && i + 1 < argc &&
			   parse_ulong(argv[i + 1], 3600000, &v) && v > 0) {
			interval = v;
			i++;
		} else if (strcmp(argv[i], "--duration") == 0 && i + 1 < argc &&
			   np_parse_double(argv[i + 1], &duration) == NP_OK && duration >= 0) {
			i++;
		} else if (record && !file && argv[i][0] != '-') {
			file = argv[i];
		} else {
			fprintf(stderr, "vehiclectl: %s: bad option %s\n", argv[0], argv[i]);
			return 2;
		}
	}
	if (record) {
		if (!file || (duration < 0 && count < 0)) {
			fprintf(stderr, "vehiclectl: record FILE --duration S [--interval MS]\n");
			return 2;
		}
		csv = fopen(file, "w");
		if (!csv) {
			fprintf(stderr, "vehiclectl: %s: %s\n", file, strerror(errno));
			return 3;
		}
	}
	rc = c->t.stream_next ? stream_loop(c, csv, json, count, duration, (unsigned)interval)
			      : STREAM_UNSUPPORTED;
	if (rc == STREAM_UNSUPPORTED)
		rc = sample_loop(c, csv, json, count, duration, (unsigned)interval);
	if (csv && fclose(csv) != 0) {
		fprintf(stderr, "vehiclectl: %s: write failed\n", file);
		rc = 3;
	}
	return rc;
}

int main(int argc, char **argv)
{
	const char *port = NULL, *can = NULL;
	unsigned long baud = VC_DEFAULT_BAUD, node = 1, timeout = VC_DEFAULT_TIMEOUT_MS,
		      retries = VC_DEFAULT_RETRIES;
	bool console = false, json = false, wait = false;
	double wait_limit = 300.0;
	vc_client_t *c;
	const cmd_def_t *d = NULL;
	int rc, e, o;

	enum {
		O_PORT = 1,
		O_BAUD,
		O_CONSOLE,
		O_CAN,
		O_NODE,
		O_JSON,
		O_TIMEOUT,
		O_RETRIES,
		O_WAIT,
		O_WAIT_LIMIT,
		O_HELP
	};
	static const struct option opts[] = {
	    {"port", required_argument, NULL, O_PORT},
	    {"baud", required_argument, NULL, O_BAUD},
	    {"console", no_argument, NULL, O_CONSOLE},
	    {"can", required_argument, NULL, O_CAN},
	    {"node", required_argument, NULL, O_NODE},
	    {"json", no_argument, NULL, O_JSON},
	    {"timeout", required_argument, NULL, O_TIMEOUT},
	    {"retries", required_argument, NULL, O_RETRIES},
	    {"wait", no_argument, NULL, O_WAIT},
	    {"wait-limit", required_argument, NULL, O_WAIT_LIMIT},
	    {"help", no_argument, NULL, O_HELP},
	    {NULL, 0, NULL, 0},
	};

	/* '+': options end at the command, so negative numbers pass through. */
	while ((o = getopt_long(argc, argv, "+", opts, NULL)) != -1) {
		switch (o) {
		case O_PORT:
			port = optarg;
			break;
		case O_CAN:
			can = optarg;
			break;
		case O_CONSOLE:
			console = true;
			break;
		case O_JSON:
			json = true;
			break;
		case O_WAIT:
			wait = true;
			break;
		case O_WAIT_LIMIT:
			if (np_parse_double(optarg, &wait_limit) != NP_OK || wait_limit < 0 ||
			    wait_limit > 86400.0) {
				fprintf(stderr, "vehiclectl: --wait-limit: seconds, 0..86400\n");
				return 2;
			}
			break;
		case O_BAUD:
		case O_NODE:
		case O_TIMEOUT:
		case O_RETRIES: {
			unsigned long *dst = o == O_BAUD      ? &baud
					     : o == O_NODE    ? &node
					     : o == O_TIMEOUT ? &timeout
							      : &retries;

			if (!parse_ulong(optarg,
					 o == O_BAUD   ? 4000000
					 : o == O_NODE ? 127
						       : 60000,
					 dst)) {
				fprintf(stderr, "vehiclectl: bad number %s\n", optarg);
				return 2;
			}
			break;
		}
		case O_HELP:
			usage(stdout);
			return 0;
		default:
			usage(stderr);
			return 2;
		}
	}
	argc -= optind;
	argv += optind;
	if (argc < 1) {
		usage(stderr);
		return 2;
	}
	if (strcmp(argv[0], "help") == 0)
		return cmd_help(argc, argv);
	if (strcmp(argv[0], "info") != 0 && strcmp(argv[0], "watch") != 0 &&
	    strcmp(argv[0], "record") != 0 && strcmp(argv[0], "wait") != 0 &&
	    strcmp(argv[0], "config") != 0 && strcmp(argv[0], "bbox") != 0) {
		d = cmd_by_name(argv[0]);
		if (!d) {
			fprintf(stderr, "vehiclectl: no operation %s (try 'vehiclectl help')\n",
				argv[0]);
			return 2;
		}
	}
	if (strcmp(argv[0], "wait") == 0 && argc != 1) {
		fprintf(stderr, "vehiclectl: wait takes no argument (its limit: --wait-limit S)\n");
		return 2;
	}
	if (!port == !can) {
		fprintf(stderr, "vehiclectl: give one link: --port DEV or --can IFACE\n");
		return 2;
	}

	c = calloc(1, sizeof(*c));
	if (!c)
		return 3;
	errno = 0;
	if (port)
		e = console ? vc_open_console(c, port, (unsigned)baud)
			    : vc_open_serial(c, port, (unsigned)baud);
	else
		e = vc_open_can(c, can, (unsigned)node);
	if (e != VC_OK) {
		fprintf(stderr, "vehiclectl: %s: %s\n", port ? port : can,
			errno ? strerror(errno) : vc_strerror(e));
		free(c);
		return 3;
	}
	c->timeout_ms = (unsigned)timeout;
	c->retries = (unsigned)retries;
	line_baud = baud;

	{
		struct sigaction sa;

		memset(&sa, 0, sizeof(sa));
		sa.sa_handler = on_signal;
		sigemptyset(&sa.sa_mask);
		sigaction(SIGINT, &sa, NULL);
		sigaction(SIGTERM, &sa, NULL);
	}

	if (d) {
		rc = cmd_op(c, d, argc, argv, json);
		if (rc == 0 && wait)
			rc = cmd_wait(c, wait_limit, json);
	} else if (strcmp(argv[0], "wait") == 0) {
		rc = cmd_wait(c, wait_limit, json);
	} else if (strcmp(argv[0], "info") == 0) {
		rc = cmd_info(c, json);
	} else if (strcmp(argv[0], "config") == 0) {
		rc = cmd_config(c, argc, argv, json);
	} else if (strcmp(argv[0], "bbox") == 0) {
		rc = cmd_bbox(c, argc, argv, json);
	} else {
		rc = loop_cmd(c, argc, argv, json, strcmp(argv[0], "record") == 0);
	}
	vc_close(c);
	free(c);
	return rc;
}
