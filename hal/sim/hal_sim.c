/// hal_sim: HAL backend over the HCTL-1100-style decoder emulators. See hal_sim.h.
#include "hal_sim.h"

#include <math.h>
#include <string.h>

static void inc32(uint32_t *c)
{
    if (*c != UINT32_MAX) {
        (*c)++;
    }
}

static odosim_hctl_config_t decoder_config(const hal_sim_config_t *cfg)
{
    odosim_hctl_config_t d;
    memset(&d, 0, sizeof d);
    d.f_clk_hz = cfg->f_clk_hz;
    d.convention = cfg->convention;
    d.force_per_edge = cfg->force_per_edge;
    return d;
}

bool hal_sim_init(hal_ctx_t *ctx, uint8_t trucks, bool has_link, const hal_sim_config_t *cfg)
{
    if (ctx == NULL) {
        return false;
    }
    memset(ctx, 0, sizeof *ctx);
    if (cfg == NULL || trucks < 1U || trucks > ODO_TRUCKS || cfg->rotary_bits < HAL_SIM_ROTARY_BITS_MIN ||
        cfg->rotary_bits > HAL_SIM_ROTARY_BITS_MAX || cfg->linear_resolution_um < 1U) {
        return false;
    }
    const odosim_hctl_config_t d = decoder_config(cfg);
    for (uint8_t t = 0U; t < trucks; ++t) {
        for (uint8_t w = 0U; w < 2U; ++w) {
            if (!odosim_hctl_init(&ctx->dec[t][w], &d, 0.0, 0.0)) {
                memset(ctx, 0, sizeof *ctx); /* bad f_CLK or convention */
                return false;
            }
        }
    }
    ctx->cfg = *cfg;
    ctx->trucks = trucks;
    ctx->has_link = has_link;
    return true;
}

odosim_hctl_t *hal_sim_decoder(hal_ctx_t *ctx, uint8_t truck, uint8_t wheel)
{
    if (truck >= ctx->trucks || wheel > ODO_RIGHT) {
        return NULL;
    }
    return &ctx->dec[truck][wheel];
}

bool hal_sim_set_wheel_phase(hal_ctx_t *ctx, uint8_t truck, uint8_t wheel, double t_s, double phase_counts)
{
    odosim_hctl_t *h = hal_sim_decoder(ctx, truck, wheel);
    if (h == NULL || !odosim_hctl_advance(h, t_s, phase_counts)) {
        inc32(&ctx->faults.bad_wheel_inputs);
        return false;
    }
    return true;
}

bool hal_sim_quantise_angle(double angle_rad, uint8_t bits, uint16_t *out_bam16)
{
    if (!isfinite(angle_rad) || bits < HAL_SIM_ROTARY_BITS_MIN || bits > HAL_SIM_ROTARY_BITS_MAX) {
        return false;
    }
    const double two_pi = 2.0 * M_PI;
    double turns = fmod(angle_rad, two_pi) / two_pi; /* (-1, 1) */
    if (turns < 0.0) {
        turns += 1.0;
    }
    const double steps = ldexp(1.0, bits);
    double code = floor(turns * steps);
    if (code >= steps) { /* turns rounded up to 1.0 from just below a full turn */
        code = 0.0;
    }
    *out_bam16 = (uint16_t)((uint32_t)code << (16U - bits));
    return true;
}

bool hal_sim_set_link(hal_ctx_t *ctx, double alpha_rad, double beta_rad, double length_mm, uint8_t valid)
{
    if (!ctx->has_link) {
        return false;
    }
    odo_link_input_t *l = &ctx->link;
    uint8_t rot = (uint8_t)(valid & (ODO_LINK_STATUS_ALPHA_VALID | ODO_LINK_STATUS_BETA_VALID));
    uint8_t lin = (uint8_t)(valid & ODO_LINK_STATUS_LENGTH_VALID);
    uint16_t code = 0U;
    l->alpha_bam16 = 0U;
    l->beta_bam16 = 0U;
    if ((rot & ODO_LINK_STATUS_ALPHA_VALID) != 0U) {
        if (hal_sim_quantise_angle(alpha_rad, ctx->cfg.rotary_bits, &code)) {
            l->alpha_bam16 = code;
        } else {
            rot = (uint8_t)(rot & ~ODO_LINK_STATUS_ALPHA_VALID);
            inc32(&ctx->faults.bad_link_inputs);
        }
    }
    if ((rot & ODO_LINK_STATUS_BETA_VALID) != 0U) {
        if (hal_sim_quantise_angle(beta_rad, ctx->cfg.rotary_bits, &code)) {
            l->beta_bam16 = code;
        } else {
            rot = (uint8_t)(rot & ~ODO_LINK_STATUS_BETA_VALID);
            inc32(&ctx->faults.bad_link_inputs);
        }
    }
    l->length_um = 0U;
    if (lin != 0U) {
        const double res = (double)ctx->cfg.linear_resolution_um;
        const double steps = floor(length_mm * 1000.0 / res);
        const double um = steps * res;
        if (isfinite(um) && um >= 0.0 && um <= (double)UINT32_MAX) {
            l->length_um = (uint32_t)um;
        } else {
            lin = 0U;
            inc32(&ctx->faults.bad_link_inputs);
        }
    }
    l->rotary_status = rot;
    l->linear_status = lin;
    l->rotary_present = true;
    l->linear_present = true;
    l->rotary_seq++;
    l->linear_seq++;
    return true;
}

void hal_sim_set_time_us(hal_ctx_t *ctx, uint64_t t_us)
{
    if (t_us < ctx->now_us) {
        inc32(&ctx->faults.bad_times);
        return;
    }
    ctx->now_us = t_us;
}

bool hal_sim_take_tx(hal_ctx_t *ctx, odo_can_frame_t *frame, uint64_t *t_us)
{
    if (ctx->tx_count == 0U) {
        return false;
    }
    *frame = ctx->tx[ctx->tx_head];
    *t_us = ctx->tx_t_us[ctx->tx_head];
    ctx->tx_head = (ctx->tx_head + 1U) % HAL_SIM_MAX_TX;
    ctx->tx_count--;
    return true;
}

bool hal_sim_push_rx(hal_ctx_t *ctx, const odo_can_frame_t *frame, uint64_t t_us)
{
    if (ctx->rx_count >= HAL_SIM_MAX_RX) {
        inc32(&ctx->faults.rx_overflows);
        return false;
    }
    const uint32_t i = (ctx->rx_head + ctx->rx_count) % HAL_SIM_MAX_RX;
    ctx->rx[i] = *frame;
    ctx->rx_t_us[i] = t_us;
    ctx->rx_count++;
    return true;
}

/* ---- hal.h ---- */

bool hal_wheel_read(hal_ctx_t *ctx, uint8_t truck, odo_wheel_input_t *out)
{
    if (truck >= ctx->trucks) {
        return false;
    }
    static const uint8_t SKIPPED[2] = {ODO_WHEEL_STATUS_LEFT_SKIPPED, ODO_WHEEL_STATUS_RIGHT_SKIPPED};
    memset(out, 0, sizeof *out);
    out->present = true; /* a direct read is always a fresh sample */
    out->bits = ODOSIM_HCTL_POS_BITS;
    out->seq = ctx->wheel_seq[truck]++;
    for (uint8_t w = 0U; w < 2U; ++w) {
        odosim_hctl_t *h = &ctx->dec[truck][w];
        /* Only the register protocol, in the data sheet's order R14H, R13H, R12H. */
        const uint32_t pos = odosim_hctl_read_position(h);
        if (w == ODO_LEFT) {
            out->left_raw = pos;
        } else {
            out->right_raw = pos;
        }
        const uint32_t skipped = odosim_hctl_skipped(h);
        if (skipped != ctx->skipped_seen[truck][w]) {
            out->status = (uint8_t)(out->status | SKIPPED[w]);
            ctx->skipped_seen[truck][w] = skipped;
        }
    }
    return true;
}

bool hal_link_read(hal_ctx_t *ctx, odo_link_input_t *out)
{
    if (!ctx->has_link) {
        return false;
    }
    *out = ctx->link;
    ctx->link.rotary_present = false; /* a reading is delivered once */
    ctx->link.linear_present = false;
    return true;
}

bool hal_can_send(hal_ctx_t *ctx, const odo_can_frame_t *frame)
{
    if (ctx->tx_count >= HAL_SIM_MAX_TX) {
        inc32(&ctx->faults.tx_overflows);
        return false;
    }
    const uint32_t i = (ctx->tx_head + ctx->tx_count) % HAL_SIM_MAX_TX;
    ctx->tx[i] = *frame;
    ctx->tx_t_us[i] = ctx->now_us;
    ctx->tx_count++;
    return true;
}

bool hal_can_recv(hal_ctx_t *ctx, odo_can_frame_t *frame, uint64_t *t_us)
{
    if (ctx->rx_count == 0U) {
        return false;
    }
    *frame = ctx->rx[ctx->rx_head];
    *t_us = ctx->rx_t_us[ctx->rx_head];
    ctx->rx_head = (ctx->rx_head + 1U) % HAL_SIM_MAX_RX;
    ctx->rx_count--;
    return true;
}

uint64_t hal_time_us(hal_ctx_t *ctx) { return ctx->now_us; }
