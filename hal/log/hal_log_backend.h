/// hal_log as a hal/hal.h backend (library `hal_log`): hal_can_recv returns the log's frames in
/// file order with their timestamps, hal_time_us is the timestamp of the frame last received,
/// hal_can_send appends candump -l lines to a stream. The vehicle's counters arrive as CAN frames,
/// so hal_wheel_read and hal_link_read return false (no direct counters): a caller assembles tick
/// inputs from the frames (tools/replay does).
#ifndef HAL_LOG_BACKEND_H
#define HAL_LOG_BACKEND_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "hal.h"
#include "hal_log.h"

struct hal_ctx {
    hal_log_t log;
    bool ok; ///< false after EOF or an error (log.err)
    bool at_eof;
    uint64_t now_us; ///< timestamp of the frame last received
    FILE *tx;        ///< where hal_can_send writes; NULL: sends refused
    char tx_iface[CANDUMP_IFACE_MAX + 1];
    uint64_t tx_frames;  ///< frames written
    uint64_t tx_refused; ///< sends refused (no stream, write error)
};

/// Open the log at `path` and send to `tx` (may be NULL) as interface `tx_iface`. Returns 0, or -1
/// with ctx->log.err set.
int hal_log_backend_open(hal_ctx_t *ctx, const char *path, FILE *tx, const char *tx_iface);

/// Close the log (not tx).
void hal_log_backend_close(hal_ctx_t *ctx);

#endif
