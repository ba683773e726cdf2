/// The imperative shell around odo_app_step: read the HAL, step, publish. This file and the HAL
/// backends are the only places where the firmware touches the world.
#include "odo_loop.h"

#include "hal.h"

void odo_loop_tick(odo_app_t *app, hal_ctx_t *hal, odo_tick_input_t *in, odo_tick_output_t *out)
{
    memset(in, 0, sizeof *in);
    in->t_us = hal_time_us(hal);
    for (uint8_t i = 0U; i < app->trucks; ++i) {
        if (!hal_wheel_read(hal, i, &in->wheel[i])) {
            in->wheel[i].present = false;
        }
    }
    if (!hal_link_read(hal, &in->link)) {
        in->link.rotary_present = false;
        in->link.linear_present = false;
    }
    odo_app_step(app, in, out);
    for (uint8_t k = 0U; k < out->n_frames; ++k) {
        /* A refused frame is counted, never retried here: the next tick carries newer data. */
        if (!hal_can_send(hal, &out->frames[k]) && app->tx_dropped != UINT32_MAX) {
            app->tx_dropped++;
        }
    }
}
