/* Tick-cost scenarios (see scenario.h). */
#include "scenario.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void need(bool ok, const char *what)
{
	if (!ok) {
		fprintf(stderr, "tickcost: %s refused\n", what);
		exit(2);
	}
}

static long measured;

static void tick(rig_t *r, const bench_hooks_t *h, const char *label)
{
	h->tick(r, label);
	loop_hal_step(&r->plant);
	measured++;
}

/* The main loop's planning between two ticks: while it has some, up to
 * the calls that a 25 MHz board's period leaves room for after the tick
 * (each within a quarter of a period under the board's plan budget). */
static void plan_between(rig_t *r, const bench_hooks_t *h)
{
	for (int i = 0; i < 3 && h->plan(r, "plan-ahead"); i++)
		;
}

long bench_scenario(rig_t *r, const char *sc, const bench_hooks_t *h)
{
	measured = 0;
	if (strcmp(sc, "idle") == 0) {
		for (int i = 0; i < 2000; i++)
			tick(r, h, "tick");
	} else if (strcmp(sc, "line") == 0 || strcmp(sc, "line_jerk") == 0) {
		if (sc[4])
			need(vehicle_set_jerk(&r->v, VS_REAL(2000.0), VS_REAL(1000.0)), "$jerk");
		need(vs_moveForward(&r->v, VS_REAL(2000.0)), "moveForward");
		do
			tick(r, h, "tick");
		while (motion_has_work(&r->v.motion));
	} else if (strcmp(sc, "cruise") == 0 || strcmp(sc, "cruise_jerk") == 0) {
		bool jerk = sc[6] != 0;
		if (jerk)
			need(vehicle_set_jerk(&r->v, VS_REAL(2000.0), VS_REAL(1000.0)), "$jerk");
		for (int i = 0; i < ROUTE_N; i++)
			need(vs_moveCruiseAbs(&r->v, (vs_point_t){vs_real_int(route_mm[i][0]),
								  vs_real_int(route_mm[i][1])}),
			     "moveCruiseAbs");
		if (jerk) /* the main loop plans between the requests and the next tick */
			while (h->plan(r, "plan-ahead"))
				;
		do {
			tick(r, h, "tick");
			if (jerk)
				plan_between(r, h);
		} while (motion_has_work(&r->v.motion));
	} else if (strcmp(sc, "jog") == 0 || strcmp(sc, "jog_jerk") == 0) {
		if (sc[3])
			need(vehicle_set_jerk(&r->v, VS_REAL(2000.0), VS_REAL(1000.0)), "$jerk");
		for (int i = 0; i < 3000; i++) {
			if (i % 100 == 0)
				need(vs_moveJog(&r->v, VS_REAL(300.0), VS_REAL(0.0), VS_REAL(30.0)),
				     "moveJog");
			tick(r, h, "tick");
		}
	} else if (strcmp(sc, "speed_jerk") == 0) {
		need(vehicle_set_jerk(&r->v, VS_REAL(2000.0), VS_REAL(1000.0)), "$jerk");
		need(vs_moveForward(&r->v, VS_REAL(3000.0)), "moveForward");
		/* Raised on the hold, lowered on the new one: each plans a line
		 * from the speed held within a tick or two. */
		for (int i = 0; motion_has_work(&r->v.motion); i++) {
			if (i == 1500 || i == 2600) {
				vs_velocity_t s = {i == 1500 ? VS_REAL(800.0) : VS_REAL(300.0),
						   VS_REAL(90.0)};
				need(vs_setVelocity(&r->v, s), "setVelocity");
				for (int k = 0; k < 3; k++, i++)
					tick(r, h, "tick-after-speed");
			}
			tick(r, h, "tick");
		}
	} else if (strcmp(sc, "blend_jerk") == 0) {
		/* Waypoints queued while the unit runs: the line running on its
		 * plan to rest becomes a blend and glides into the new corner;
		 * the line from the speed the glide ends at is planned between
		 * ticks, as the main loop does ("plan-ahead"). */
		need(vehicle_set_jerk(&r->v, VS_REAL(2000.0), VS_REAL(1000.0)), "$jerk");
		static const int32_t wp[3][2] = {{300, 0}, {300, 300}, {600, 300}};
		for (int k = 0; k < 3; k++) {
			need(vs_moveCruiseAbs(
				 &r->v, (vs_point_t){vs_real_int(wp[k][0]), vs_real_int(wp[k][1])}),
			     "moveCruiseAbs");
			for (int i = 0; i < 10; i++) {
				plan_between(r, h);
				tick(r, h, "tick");
			}
		}
		do {
			plan_between(r, h);
			tick(r, h, "tick");
		} while (motion_has_work(&r->v.motion));
	} else if (strcmp(sc, "goal_jerk") == 0) {
		/* A continuous goal off the heading, from rest: the turn's and
		 * the translation's tails, each planned on some tick. */
		need(vehicle_set_jerk(&r->v, VS_REAL(2000.0), VS_REAL(1000.0)), "$jerk");
		need(vs_moveContinuousRel(
			 &r->v, (vs_position_t){VS_REAL(300.0), VS_REAL(200.0), VS_REAL(0.0)}),
		     "moveContinuousRel");
		do
			tick(r, h, "tick");
		while (motion_has_work(&r->v.motion));
	} else if (strcmp(sc, "retarget") == 0 || strcmp(sc, "retarget_jerk") == 0) {
		/* Under jerk limits every tick counts: a tail to rest may be
		 * planned on any of them. */
		bool jerk = sc[8] != 0;
		if (jerk)
			need(vehicle_set_jerk(&r->v, VS_REAL(2000.0), VS_REAL(1000.0)), "$jerk");
		need(vs_moveContinuousRel(
			 &r->v, (vs_position_t){VS_REAL(3000.0), VS_REAL(0.0), VS_REAL(0.0)}),
		     "moveContinuousRel");
		for (int k = 0; k < 20; k++) {
			for (int i = 0; i < 250; i++) {
				if (jerk)
					tick(r, h, "tick");
				else
					rig_tick(r);
			}
			/* Alternate left and right goals ahead: a new bearing each time. */
			vs_real_t side = (k & 1) ? VS_REAL(-400.0) : VS_REAL(400.0);
			need(h->retarget(r, (vs_position_t){VS_REAL(1500.0), side, side / 20},
					 "cmd"),
			     "moveContinuousRel");
			tick(r, h, "tick-after-cmd");
		}
	} else {
		return -1;
	}
	return measured;
}
