/// The HAL-driven tick (firmware/app's only link to hal/hal.h).
#ifndef ODO_LOOP_H
#define ODO_LOOP_H

#include "hal.h"
#include "odo/odo_app.h"

#ifdef __cplusplus
extern "C" {
#endif

/// One 40 ms tick on a HAL backend: read each truck's counters and the linkage into *in, run
/// odo_app_step, queue the output frames with hal_can_send. *in is left holding what the HAL gave
/// (the simulator logs it as sensor frames). A frame the HAL refuses is counted in
/// app->tx_dropped; the tick itself is never lost. Call it every params.tick_us.
void odo_loop_tick(odo_app_t *app, hal_ctx_t *hal, odo_tick_input_t *in, odo_tick_output_t *out);

#ifdef __cplusplus
}
#endif
#endif
