/// The hal.h sensor reads of a backend whose sensors arrive as CAN frames (hal/log, hal/socketcan):
/// there are no directly wired counters or linkage encoders, so these report nothing and the
/// frames reach the firmware through hal_can_recv. Compiled into each such backend library.
#include "hal.h"

bool hal_wheel_read(hal_ctx_t *ctx, uint8_t truck, odo_wheel_input_t *out)
{
    (void)ctx;
    (void)truck;
    out->present = false;
    return false;
}

bool hal_link_read(hal_ctx_t *ctx, odo_link_input_t *out)
{
    (void)ctx;
    out->rotary_present = false;
    out->linear_present = false;
    return false;
}
