/* The black box on the links (docs/protocol.md "Black box"): the paged
 * readout of frame opcode 0x7C, the console's $bbox, and the text form of a
 * sample in the columns of the simulator's trace (docs/trace.md).
 *
 * Request payload, 3 bytes: u8 action (0 read, 1 clear), u16 index (read:
 * the first sample wanted, 0 the oldest, at most the count held; clear: 0).
 * Answer: the BBOX_HDR_LEN-byte header, then n samples of BBOX_SAMPLE_LEN
 * bytes (at most BBOX_PAGE), all little-endian:
 *   0 u8 status (bbox_status_t)   1 u8 n          2 u16 count held
 *   4 u16 index of the first      6 u16 capacity  8 u16 ticks per sample
 *  10 u16 tick rate, Hz          12 u32 trigger sample's tick (0: none)
 *  16 u32 fault code (0: none)
 * A sample: i64 Q32 ref x, y, th; odo x, y, th; cmd vx, vy, w (per tick);
 *   i32 setpoints 0..3 (counts/s Q8); i32 encoders 0..3 (counts); u32 tick;
 *   u32 newest alarm; i16 state; u8 queue length; u8 active alarms.
 */
#ifndef BBOX_WIRE_H
#define BBOX_WIRE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "../firmware/vehicle.h"

/* A board leaves out the text form with its help text (VS_NO_HELP_TEXT,
 * mk/cortexm.mk): its $bbox gives the status and clears; the samples go
 * out in frames. */
#ifdef VS_NO_HELP_TEXT
#define VS_NO_BBOX_TEXT
#endif

#define WIRE_OP_BBOX	0x7C
#define BBOX_REQ_LEN	3
#define BBOX_HDR_LEN	20
#define BBOX_SAMPLE_LEN 116
#define BBOX_PAGE	8
#define BBOX_RESP_MAX	(BBOX_HDR_LEN + BBOX_PAGE * BBOX_SAMPLE_LEN)
enum { BBOX_READ = 0, BBOX_CLEAR = 1 };

/* An answer's header, decoded. */
typedef struct {
	uint8_t status, n;
	uint16_t count, index, cap, every, tick_hz;
	uint32_t trigger, fault;
} bbox_page_t;

/* Serves one request (wire_dispatch's contract): the answer's length in
 * resp (room for BBOX_RESP_MAX), or 0 with *st the NAK: length, or value
 * (an unknown action, an index past the count, a clear with an index). */
size_t bbox_wire_serve(vehicle_t *v, const uint8_t *p, size_t len, uint8_t *resp, int *st);
/* A client's decoding of an answer: the header, and its samples into out
 * (room for BBOX_PAGE). False when the length does not match. */
bool bbox_wire_decode(const uint8_t *p, size_t len, bbox_page_t *pg, bbox_sample_t *out);

/* The text form: the header line's column names, and one sample's row
 * (no newline) at tick_hz; fault: the code on the trigger row, else 0. */
#define BBOX_CSV_MAX 512 /* room a row needs (0 written with less) */
extern const char bbox_csv_header[];
size_t bbox_csv_row(const bbox_sample_t *s, uint32_t tick_hz, uint32_t fault, char *buf,
		    size_t cap);

/* The console's $bbox (a console_extra_fn's reply for argv[0] "$bbox"). */
void bbox_console(vehicle_t *v, int argc, char **argv, char *reply, size_t cap);

#endif
