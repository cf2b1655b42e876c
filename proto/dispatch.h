/* The unit's side of the command table: running an operation from decoded
 * arguments (cmd_invoke) and answering a binary request (wire_dispatch).
 * Only the unit links it (dispatch.c): the host's client library uses the
 * table (cmdtab.h) and the encoding (wire.h) alone. */
#ifndef DISPATCH_H
#define DISPATCH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cmdtab.h"
#include "../firmware/vehicle.h"
#include "wire.h"

/* Runs one operation: in[] holds d->n_in values of d->in_types, out[]
 * receives d->n_out values (always all of them, zero/empty when the
 * operation leaves one unset). Returns the operation's boolean. The alarm
 * sequence of getActiveAlarm is clamped to max(numOfAlarm, 0) and to
 * VS_ALARM_LIST_MAX entries. */
bool cmd_invoke(vehicle_t *v, const cmd_def_t *d, const cmd_value_t in[], cmd_value_t out[],
		cmd_scratch_t *scratch);

/* Server side of every binary link: decodes the request payload of opcode,
 * runs the operation (cmd_invoke) and encodes the response payload into
 * resp. Returns the response length with *status = WIRE_ST_OK, or 0 with
 * the NAK reason in *status (unknown opcode, bad length or value); in that
 * case nothing was executed. WIRE_OP_INFO is answered here too.
 * cap >= WIRE_RESP_MAX always suffices. */
size_t wire_dispatch(vehicle_t *v, unsigned opcode, const uint8_t *req, size_t len, uint8_t *resp,
		     size_t cap, int *status);

#endif
