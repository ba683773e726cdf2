/// hal_test: a scripted HAL backend for unit and integration tests. A test sets what the next
/// reads return, and inspects the frames the firmware sent. No threads, no I/O.
#ifndef HAL_TEST_H
#define HAL_TEST_H

#include <stdbool.h>
#include <stdint.h>

#include "hal.h"

#define HAL_TEST_MAX_TX 64U
#define HAL_TEST_MAX_RX 64U

struct hal_ctx {
    uint8_t trucks;                      ///< trucks that have counters (1 or 2)
    bool has_link;                       ///< the vehicle has linkage encoders
    uint64_t now_us;                     ///< what hal_time_us returns
    odo_wheel_input_t wheel[ODO_TRUCKS]; ///< returned by hal_wheel_read, then marked not present
    odo_link_input_t link;               ///< returned by hal_link_read, then marked not present
    odo_can_frame_t tx[HAL_TEST_MAX_TX]; ///< frames sent, in order
    uint32_t n_tx;
    uint32_t refuse_tx;                  ///< refuse this many next sends (models ENOBUFS)
    odo_can_frame_t rx[HAL_TEST_MAX_RX]; ///< frames waiting to be received, FIFO
    uint64_t rx_t_us[HAL_TEST_MAX_RX];
    uint32_t rx_head, rx_tail;
};

/// Reset to an idle backend with `trucks` counter sets and optional linkage encoders.
void hal_test_init(hal_ctx_t *ctx, uint8_t trucks, bool has_link);

/// Present a wheel sample for the next hal_wheel_read of `truck`.
void hal_test_set_wheel(hal_ctx_t *ctx, uint8_t truck, uint32_t left_raw, uint32_t right_raw, uint8_t bits,
                        uint8_t seq);

/// Queue a frame to be returned by hal_can_recv. Returns false iff the queue is full.
bool hal_test_push_rx(hal_ctx_t *ctx, const odo_can_frame_t *f, uint64_t t_us);

#endif
