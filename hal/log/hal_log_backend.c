/// hal_log behind hal/hal.h (see hal_log_backend.h).
#include "hal_log_backend.h"

#include <string.h>

int hal_log_backend_open(hal_ctx_t *ctx, const char *path, FILE *tx, const char *tx_iface)
{
    memset(ctx, 0, sizeof *ctx);
    ctx->tx = tx;
    (void)snprintf(ctx->tx_iface, sizeof ctx->tx_iface, "%s", tx_iface != NULL ? tx_iface : "can0");
    if (hal_log_open(&ctx->log, path) != 0) {
        return -1;
    }
    ctx->ok = true;
    return 0;
}

void hal_log_backend_close(hal_ctx_t *ctx) { hal_log_close(&ctx->log); }

/* hal_wheel_read, hal_link_read: hal/hal_frames_only.c (sensors arrive as frames). */

bool hal_can_send(hal_ctx_t *ctx, const odo_can_frame_t *frame)
{
    char line[CANDUMP_LINE_MAX];
    if (ctx->tx == NULL) {
        ctx->tx_refused++;
        return false;
    }
    const size_t n = candump_format_line(line, ctx->now_us, ctx->tx_iface, frame);
    if (fwrite(line, 1U, n, ctx->tx) != n) {
        ctx->tx_refused++;
        return false;
    }
    ctx->tx_frames++;
    return true;
}

bool hal_can_recv(hal_ctx_t *ctx, odo_can_frame_t *frame, uint64_t *t_us)
{
    if (!ctx->ok) {
        return false;
    }
    candump_line_t l;
    const hal_log_status_t s = hal_log_next(&ctx->log, &l);
    if (s != HAL_LOG_FRAME) {
        ctx->ok = false;
        ctx->at_eof = s == HAL_LOG_EOF;
        return false;
    }
    *frame = l.frame;
    *t_us = l.t_us;
    ctx->now_us = l.t_us;
    return true;
}

uint64_t hal_time_us(hal_ctx_t *ctx) { return ctx->now_us; }
