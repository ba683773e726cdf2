#include "hal_test.h"

#include <string.h>

void hal_test_init(hal_ctx_t *ctx, uint8_t trucks, bool has_link)
{
    memset(ctx, 0, sizeof *ctx);
    ctx->trucks = trucks;
    ctx->has_link = has_link;
}

void hal_test_set_wheel(hal_ctx_t *ctx, uint8_t truck, uint32_t left_raw, uint32_t right_raw, uint8_t bits, uint8_t seq)
{
    odo_wheel_input_t *w = &ctx->wheel[truck];
    w->present = true;
    w->left_raw = left_raw;
    w->right_raw = right_raw;
    w->bits = bits;
    w->seq = seq;
    w->status = 0U;
}

bool hal_test_push_rx(hal_ctx_t *ctx, const odo_can_frame_t *f, uint64_t t_us)
{
    if (ctx->rx_tail - ctx->rx_head >= HAL_TEST_MAX_RX) {
        return false;
    }
    ctx->rx[ctx->rx_tail % HAL_TEST_MAX_RX] = *f;
    ctx->rx_t_us[ctx->rx_tail % HAL_TEST_MAX_RX] = t_us;
    ctx->rx_tail++;
    return true;
}

bool hal_wheel_read(hal_ctx_t *ctx, uint8_t truck, odo_wheel_input_t *out)
{
    if (truck >= ctx->trucks) {
        return false;
    }
    *out = ctx->wheel[truck];
    ctx->wheel[truck].present = false; /* a sample is delivered once */
    return true;
}

bool hal_link_read(hal_ctx_t *ctx, odo_link_input_t *out)
{
    if (!ctx->has_link) {
        return false;
    }
    *out = ctx->link;
    ctx->link.rotary_present = false;
    ctx->link.linear_present = false;
    return true;
}

bool hal_can_send(hal_ctx_t *ctx, const odo_can_frame_t *frame)
{
    if (ctx->refuse_tx > 0U) {
        ctx->refuse_tx--;
        return false;
    }
    if (ctx->n_tx >= HAL_TEST_MAX_TX) {
        return false;
    }
    ctx->tx[ctx->n_tx++] = *frame;
    return true;
}

bool hal_can_recv(hal_ctx_t *ctx, odo_can_frame_t *frame, uint64_t *t_us)
{
    if (ctx->rx_head == ctx->rx_tail) {
        return false;
    }
    *frame = ctx->rx[ctx->rx_head % HAL_TEST_MAX_RX];
    *t_us = ctx->rx_t_us[ctx->rx_head % HAL_TEST_MAX_RX];
    ctx->rx_head++;
    return true;
}

uint64_t hal_time_us(hal_ctx_t *ctx) { return ctx->now_us; }
