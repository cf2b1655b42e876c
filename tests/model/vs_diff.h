/* The differential harness: one sequence of operations, inputs and time,
 * read from bytes, run on the lockstep simulator (the firmware through its
 * console, the default or ideal plant) and on the model (vs_model.h), with
 * every reply, refusal code, state and alarm list compared, and the
 * invariants that no state may break checked after every control tick:
 *
 *   - no motion without a motion command since the last stop, fault,
 *     pause or joystick hand-over (vm_may_move false: the commanded twist
 *     is zero);
 *   - the link watchdog covers every host-commanded motion (the model's
 *     watchdog, compared through the alarm list and the state);
 *   - speed and acceleration bounds as vector bounds, in every mode: the
 *     commanded translation within the velocity limit, the set velocity
 *     and the caution cap (the larger of the old and new set velocity
 *     for brake_ms after a change), its change per tick within the
 *     acceleration limit, and at rest (the position hold) every wheel's
 *     setpoint within the set velocity and the caution cap.
 *
 * Byte 0 picks the base (bit 0: mecanum), the plant (bit 1: ideal), jerk
 * limits (bit 2). Then actions, each an action byte and its arguments.
 */
#ifndef VS_DIFF_H
#define VS_DIFF_H

#include <stddef.h>
#include <stdint.h>

/* 0: no divergence. 1: a divergence, described in why (the step, the
 * action, what the model allowed and what the unit did). */
int diff_run(const uint8_t *data, size_t n, char *why, size_t cap);
/* Actions of the last run, for the figures of a long run. */
unsigned long diff_last_actions(void);
/* A hash of every tick of the last run (command, setpoints, odometry,
 * reference, mode): a change that should not change behaviour keeps it. */
uint64_t diff_last_hash(void);

#endif
