/// The board port: start-up, the hal.h backend and the tick (odo_board_port.h).
#include "odo_board_port.h"

#include <string.h>

#include "odo/odo_can.h"
#include "odo_iwdg.h"
#include "odo_reg.h"
#include "odo_timer.h"

/// Frames drained per tick at most: a full FIFO (3) refilled many times over at 1 Mbit/s in 40 ms
/// would be ~350 frames; the bound keeps a babbling bus from stalling the step.
#define ODO_BOARD_RX_PER_TICK 64U

/// The identifiers the filters pass: the sensor frames of odo/odo_can.h. WHEEL_COUNTS are passed
/// even for trucks with local counters so that a misconfigured sensor shows up as UNKNOWN_ID.
static const uint32_t k_consumed_ids[] = {
    ODO_CAN_ID_WHEEL_COUNTS_A,
    ODO_CAN_ID_WHEEL_COUNTS_B,
    ODO_CAN_ID_LINK_ROTARY,
    ODO_CAN_ID_LINK_LINEAR,
};

static void pin_af(odo_stm32_rcc_t *rcc, const odo_pin_t *p, bool pull_up)
{
    if (p->port == NULL) {
        return;
    }
    odo_reg_modify(&rcc->AHB1ENR, 0U, ODO_RCC_AHB1ENR_GPIO(p->port_index));
    const uint32_t sh2 = 2U * p->pin, sh4 = 4U * (p->pin & 7U);
    odo_reg_modify(&p->port->AFR[p->pin >> 3], (uint32_t)0xFU << sh4, (uint32_t)(p->af & 0xFU) << sh4);
    odo_reg_modify(&p->port->PUPDR, 3U << sh2, pull_up ? (uint32_t)ODO_GPIO_PULL_UP << sh2 : 0U);
    odo_reg_modify(&p->port->MODER, 3U << sh2, (uint32_t)ODO_GPIO_MODE_AF << sh2);
}

static bool any_source(const odo_board_config_t *cfg, odo_wheel_source_t s)
{
    return cfg->truck[ODO_TRUCK_A].source == s || cfg->truck[ODO_TRUCK_B].source == s;
}

void odo_board_init(hal_ctx_t *hal, const odo_board_config_t *cfg)
{
    memset(hal, 0, sizeof *hal);
    hal->cfg = cfg;
    odo_board_rx_init(&hal->rx, cfg->truck[ODO_TRUCK_A].source == ODO_WHEELS_CAN,
                      cfg->truck[ODO_TRUCK_B].source == ODO_WHEELS_CAN);
    hal->status.clock = odo_clock_init(cfg->rcc, cfg->flash, cfg->hse_hz, cfg->polls);
    odo_stm32_rcc_t *rcc = cfg->rcc;

    for (uint8_t t = 0U; t < ODO_TRUCKS; ++t) {
        const odo_truck_io_t *io = &cfg->truck[t];
        if (io->source != ODO_WHEELS_ENCODER) {
            continue;
        }
        for (uint8_t w = 0U; w < 2U; ++w) {
            odo_reg_modify(&rcc->APB1ENR, 0U, io->tim_apb1enr[w]);
            pin_af(rcc, &io->ti[w][0], true); /* open-collector encoders need the pull-up */
            pin_af(rcc, &io->ti[w][1], true);
            (void)odo_encoder_init(io->tim[w], io->tim_bits[w], cfg->encoder_filter, io->invert[w]);
        }
    }
    if (any_source(cfg, ODO_WHEELS_HCTL)) {
        odo_reg_modify(&rcc->AHB1ENR, 0U,
                       ODO_RCC_AHB1ENR_GPIO(cfg->hctl_port_index[0]) | ODO_RCC_AHB1ENR_GPIO(cfg->hctl_port_index[1]));
        odo_hctl_bus_init(&cfg->hctl);
    }

    odo_reg_modify(&rcc->APB1ENR, 0U, ODO_RCC_APB1ENR_CAN1);
    pin_af(rcc, &cfg->can_rx, true);
    pin_af(rcc, &cfg->can_tx, false);
    hal->status.can = odo_bxcan_init(cfg->can, hal->status.clock.pclk1_hz, cfg->can_bitrate, k_consumed_ids,
                                     (uint8_t)(sizeof k_consumed_ids / sizeof k_consumed_ids[0]), cfg->polls);

    odo_reg_modify(&rcc->APB1ENR, 0U, cfg->tick_tim_apb1enr);
    hal->status.tick_ok = odo_tick_timer_init(cfg->tick_tim, hal->status.clock.tim_apb1_hz, cfg->tick_us);
    if (cfg->watchdog_ms != 0U) {
        hal->status.watchdog_ok = odo_iwdg_start(cfg->iwdg, cfg->watchdog_ms, cfg->polls);
    }
}

bool odo_board_wait_tick(hal_ctx_t *hal)
{
    if (!hal->status.tick_ok) {
        return false;
    }
    while (!odo_tick_timer_elapsed(hal->cfg->tick_tim)) {
    }
    hal->periods++;
    /* Another period already over: the last tick ran long (counted, not caught up). */
    if (odo_tick_timer_elapsed(hal->cfg->tick_tim)) {
        hal->periods++;
        if (hal->status.tick_overruns != UINT32_MAX) {
            hal->status.tick_overruns++;
        }
    }
    return true;
}

static void drain_rx(hal_ctx_t *hal)
{
    if (hal->status.can != ODO_BXCAN_OK) {
        return;
    }
    odo_can_frame_t f;
    uint8_t raw_dlc = 0U;
    bool overrun = false;
    for (uint32_t n = 0U; n < ODO_BOARD_RX_PER_TICK && odo_bxcan_recv(hal->cfg->can, &f, &raw_dlc, &overrun); ++n) {
        odo_board_rx_frame(&hal->rx, &f, raw_dlc);
    }
    if (overrun) {
        odo_board_rx_overrun(&hal->rx);
    }
    if (odo_bxcan_bus_off(hal->cfg->can)) {
        odo_board_rx_bus_off(&hal->rx);
    }
}

void odo_board_tick(hal_ctx_t *hal, odo_app_t *app, odo_tick_input_t *in, odo_tick_output_t *out)
{
    memset(in, 0, sizeof *in);
    in->t_us = hal_time_us(hal);
    drain_rx(hal);
    odo_board_rx_take(&hal->rx, hal->can_wheel, &hal->link, &in->rx_faults);
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
        if (!hal_can_send(hal, &out->frames[k]) && app->tx_dropped != UINT32_MAX) {
            app->tx_dropped++;
        }
    }
    if (hal->cfg->watchdog_ms != 0U) {
        odo_iwdg_refresh(hal->cfg->iwdg);
    }
}

/* ---- hal.h -------------------------------------------------------------------------------- */

bool hal_wheel_read(hal_ctx_t *ctx, uint8_t truck, odo_wheel_input_t *out)
{
    if (truck >= ODO_TRUCKS) {
        return false;
    }
    const odo_truck_io_t *io = &ctx->cfg->truck[truck];
    memset(out, 0, sizeof *out);
    switch (io->source) {
    case ODO_WHEELS_ENCODER: {
        const uint8_t bits = io->tim_bits[0] < io->tim_bits[1] ? io->tim_bits[0] : io->tim_bits[1];
        const uint32_t mask = bits >= 32U ? UINT32_MAX : (((uint32_t)1U << bits) - 1U);
        out->left_raw = odo_encoder_read(io->tim[0]) & mask;
        out->right_raw = odo_encoder_read(io->tim[1]) & mask;
        out->bits = bits;
        break;
    }
    case ODO_WHEELS_HCTL:
        out->left_raw = odo_hctl_read_position(&ctx->cfg->hctl, io->hctl_chip[0]);
        out->right_raw = odo_hctl_read_position(&ctx->cfg->hctl, io->hctl_chip[1]);
        out->bits = ODO_HCTL_BITS;
        break;
    case ODO_WHEELS_CAN: *out = ctx->can_wheel[truck]; return true;
    case ODO_WHEELS_NONE:
    default: return false;
    }
    out->present = true;
    out->seq = ctx->seq[truck]++;
    return true;
}

bool hal_link_read(hal_ctx_t *ctx, odo_link_input_t *out)
{
    *out = ctx->link;
    return true;
}

bool hal_can_send(hal_ctx_t *ctx, const odo_can_frame_t *frame)
{
    if (ctx->status.can != ODO_BXCAN_OK || !odo_bxcan_send(ctx->cfg->can, frame)) {
        if (ctx->status.tx_refused != UINT32_MAX) {
            ctx->status.tx_refused++;
        }
        return false;
    }
    return true;
}

bool hal_can_recv(hal_ctx_t *ctx, odo_can_frame_t *frame, uint64_t *t_us)
{
    uint8_t raw_dlc = 0U;
    bool overrun = false;
    if (ctx->status.can != ODO_BXCAN_OK || !odo_bxcan_recv(ctx->cfg->can, frame, &raw_dlc, &overrun)) {
        return false;
    }
    *t_us = hal_time_us(ctx);
    return true;
}

uint64_t hal_time_us(hal_ctx_t *ctx)
{
    const uint64_t base = ctx->periods * ctx->cfg->tick_us;
    return ctx->status.tick_ok ? base + odo_tick_timer_us(ctx->cfg->tick_tim) : base;
}
