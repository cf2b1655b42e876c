/* vs_hal_ops_t over the simulated plant (plant.h). */
#ifndef SIM_HAL_H
#define SIM_HAL_H

#include "../hal/hal.h"
#include "plant.h"

extern const vs_hal_ops_t sim_hal_ops;

/* hal->ops = &sim_hal_ops, hal->ctx = pl. */
void sim_hal_bind(vs_hal_t *hal, plant_t *pl);

#endif
