/// hal_socketcan behind hal/hal.h (see hal_socketcan_backend.h).
#include "hal_socketcan_backend.h"

/* hal_wheel_read, hal_link_read: hal/hal_frames_only.c (sensors arrive as frames). */

bool hal_can_send(hal_ctx_t *ctx, const odo_can_frame_t *frame) { return hal_socketcan_send(&ctx->sc, frame); }

bool hal_can_recv(hal_ctx_t *ctx, odo_can_frame_t *frame, uint64_t *t_us)
{
    return hal_socketcan_recv(&ctx->sc, frame, t_us) == HAL_SC_FRAME;
}

uint64_t hal_time_us(hal_ctx_t *ctx)
{
    (void)ctx;
    return hal_socketcan_now_us();
}
