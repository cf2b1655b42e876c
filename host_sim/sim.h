/* The firmware on the simulated plant, in one process, in lockstep.
 *
 * Used by vehicle-sim and by tests: sim_exec runs one console line exactly as
 * the serial console would (including the '$wait' and '$sim ...' extras
 * below), sim_run_ms advances simulated time. Time advances only in
 * sim_tick / sim_run_ms; each tick is vehicle_tick(now) then plant_step over
 * the period. A sim_t holds pointers into itself: do not copy or move it
 * after sim_init.
 *
 * Simulator extras (one reply line each, "ok ..." or "error 8 <message>"):
 *   $wait MS                       run MS ms (0..3600000) of simulated time
 *   $sim contact|obstacle|caution|estop on|off
 *   $sim joystick X Y R            axes as fractions of full scale, -1..1
 *   $sim joystick lost
 *   $sim relay fail|ok|drop        fail: next close fails; drop: opens now
 *   $sim drive AXIS fault CODE|ok|stuck|silent|hold|reboot   AXIS 0-based;
 *                                  hold: its power stage held off (Switched
 *                                  on, as an STO); reboot: it restarts, its
 *                                  count from 0; ok clears all
 *   $sim battery MV                open-circuit voltage, mV
 *   $sim input ID VALUE            set an input's value
 *   $sim wire OUT IN|none          loop an output back to an input
 *   $sim wall X0 Y0 X1 Y1          add a wall (axis-aligned rectangle, mm)
 *   $sim pose                      true plant pose: "ok pose X Y THETA"
 *   $sim push DX DY DTH            an external force moves the base at once:
 *                                  DX mm forward, DY mm left, DTH deg
 *                                  counter-clockwise, in its own frame (each
 *                                  at most 1000 mm, 180 deg); the wheels turn
 *                                  with it, a differential base's skid through
 *                                  the sideways part; "ok push X Y THETA" (the
 *                                  true pose after it)
 */
#ifndef SIM_H
#define SIM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "../firmware/vehicle.h"
#include "../proto/alarm_log.h"
#include "../proto/server.h"
#include "plant.h"
#include "sim_hal.h"
#include "trace.h"

#define SIM_WAIT_MAX_MS 3600000u

typedef struct sim sim_t;
typedef void (*sim_tick_fn)(void *ctx, sim_t *s);

struct sim {
	vs_config_t cfg;
	plant_t plant;
	vs_hal_t hal;
	vehicle_t vehicle;
	vs_server_t srv; /* the console; vehicle-sim attaches its links here */
	uint64_t ticks;
	uint64_t now_us; /* simulated time; the firmware sees it modulo 2^32 */
	sim_tick_fn on_tick;
	void *tick_ctx;
	/* vehicle-sim in real time: time runs by itself and '$wait' is refused
	 * (answering it early, then holding the port, would stall the link). */
	bool realtime;
	trace_t *trace;
	/* vehicle-sim: alarm events to its log (proto/alarm_log.h); NULL: none */
	alarm_log_t *alarm_log;
	alarm_log_fn alarm_fn;
	void *alarm_ctx;
};

/* Returns 0, or vehicle_init's negative value (invalid configuration; the
 * field name goes to *bad_field when bad_field is not NULL). */
int sim_init_ex(sim_t *s, const vs_config_t *cfg, const plant_params_t *pp, const char **bad_field);
static inline int sim_init(sim_t *s, const vs_config_t *cfg, const plant_params_t *pp)
{
	return sim_init_ex(s, cfg, pp, NULL);
}

/* One console line (no line ending). Returns false when the line gets no
 * reply (empty or comment); otherwise reply holds the line without "\n". */
bool sim_exec(sim_t *s, const char *line, char *reply, size_t cap);
void sim_tick(sim_t *s);
void sim_run_ms(sim_t *s, uint32_t ms);

void sim_set_tick_cb(sim_t *s, sim_tick_fn fn, void *ctx);
void sim_set_realtime(sim_t *s, bool on);
/* Where console_feed replies go (vehicle-sim: stdout). */
void sim_set_output(sim_t *s, console_write_fn fn, void *ctx);
/* Trace every tick into t (NULL: none); the caller owns t. */
void sim_set_trace(sim_t *s, trace_t *t);
/* Alarm events through l to fn (l NULL: none); the caller owns l. The list
 * is looked at before and after every tick and after every sim_exec; a main
 * that runs requests otherwise (the server's links, console_feed) calls
 * sim_alarm_look after them. */
void sim_set_alarm_log(sim_t *s, alarm_log_t *l, alarm_log_fn fn, void *ctx);
void sim_alarm_look(sim_t *s);

static inline plant_t *sim_plant(sim_t *s)
{
	return &s->plant;
}
static inline vehicle_t *sim_vehicle(sim_t *s)
{
	return &s->vehicle;
}
static inline double sim_time_s(const sim_t *s)
{
	return (double)s->now_us * 1e-6;
}

/* The '$' extra handler (console_extra_fn); ctx is the sim_t. */
bool sim_extra(void *ctx, int argc, char **argv, char *reply, size_t cap);

#endif
