/// HCTL-1100-style quadrature decoder emulator. The model is specified in hctl1100.h; comments here
/// say which data-sheet section each behaviour comes from and why the arithmetic is exact.
#include "hctl1100.h"

#include <math.h>
#include <string.h>

#define PEND_NONE INT64_MAX

/// Quadrature state s = floor(phase) mod 4 -> CHA << 1 | CHB (table in hctl1100.h).
static const uint8_t STATE_TO_AB[4] = {0x3U, 0x2U, 0x0U, 0x1U};
/// CHA << 1 | CHB -> quadrature state (the inverse of STATE_TO_AB).
static const uint8_t AB_TO_STATE[4] = {2U, 3U, 1U, 0U};

static void inc32(uint32_t *c)
{
    if (*c != UINT32_MAX) {
        (*c)++;
    }
}

static uint8_t state_ab(int64_t state)
{
    return STATE_TO_AB[(uint64_t)state & 3U]; /* two's complement: -1 & 3 == 3 == -1 mod 4 */
}

/// +1 when the counter counts up for rising phase (HCTL-1100: B leads A), -1 for HCTL-20xx.
static int64_t conv_sign(const odosim_hctl_t *h) { return h->cfg.convention == ODOSIM_HCTL_CONV_20XX ? -1 : 1; }

static void add_counts(odosim_hctl_t *h, int64_t delta)
{
    /* "Actual Position Registers R12H-R14H": a 24-bit two's-complement counter; it wraps. */
    h->position = (uint32_t)(((uint64_t)h->position + (uint64_t)delta) & ODOSIM_HCTL_POS_MASK);
}

/// The decoder sees a new filtered state ("Quadrature Decoder", 4x decoding).
static void decode(odosim_hctl_t *h, uint8_t new_ab)
{
    const unsigned from = AB_TO_STATE[h->filt_ab];
    const unsigned to = AB_TO_STATE[new_ab];
    const unsigned step = (to - from) & 3U;
    h->filt_ab = new_ab;
    if (step == 1U) {
        add_counts(h, conv_sign(h));
    } else if (step == 3U) {
        add_counts(h, -conv_sign(h));
    } else if (step == 2U) {
        /* Both channels changed on one edge: an illegal transition; the count is left alone. */
        inc32(&h->diag.skipped_states);
    }
}

/// Clock every filter settle at an edge before `k_limit` ("Digital Filter": the pending state was
/// sampled on three consecutive rising edges).
static void settle_before(odosim_hctl_t *h, int64_t k_limit)
{
    if (h->pend_edge < k_limit) {
        h->pend_edge = PEND_NONE;
        decode(h, state_ab(h->raw_state));
    }
}

/// The input state changes to `state` at the edge-time `k0` = ceil(tau * f_CLK).
static void input_change(odosim_hctl_t *h, int64_t k0, int64_t state)
{
    settle_before(h, k0); /* the old state had samples k0_old .. k0-1 */
    h->raw_state = state;
    /* "Digital Filter": the new state passes at edge k0 + 2 unless it changes before that edge. */
    h->pend_edge = state_ab(state) != h->filt_ab ? k0 + 2 : PEND_NONE;
    h->diag.changes_per_edge++;
}

static bool finite_in(double x, double max) { return isfinite(x) && fabs(x) <= max; }

bool odosim_hctl_init(odosim_hctl_t *h, const odosim_hctl_config_t *cfg, double t0_s, double phase0_counts)
{
    memset(h, 0, sizeof *h);
    if (cfg == NULL || cfg->f_clk_hz < ODOSIM_HCTL_F_CLK_MIN_HZ || cfg->f_clk_hz > ODOSIM_HCTL_F_CLK_MAX_HZ ||
        (cfg->convention != ODOSIM_HCTL_CONV_1100 && cfg->convention != ODOSIM_HCTL_CONV_20XX) ||
        !finite_in(t0_s, ODOSIM_HCTL_T_MAX_S) || !finite_in(phase0_counts, ODOSIM_HCTL_PHASE_MAX_COUNTS)) {
        return false;
    }
    h->cfg = *cfg;
    h->f_clk = (double)cfg->f_clk_hz;
    h->t_s = t0_s;
    h->phase_counts = phase0_counts;
    h->raw_state = (int64_t)floor(phase0_counts);
    h->filt_ab = state_ab(h->raw_state); /* "Operating Modes", Reset: the filter has long settled on the input */
    h->pend_edge = PEND_NONE;
    return true;
}

bool odosim_hctl_advance(odosim_hctl_t *h, double t_end_s, double phase_end_counts)
{
    if (h->cfg.f_clk_hz == 0U || !finite_in(t_end_s, ODOSIM_HCTL_T_MAX_S) ||
        !finite_in(phase_end_counts, ODOSIM_HCTL_PHASE_MAX_COUNTS) || t_end_s < h->t_s) {
        inc32(&h->diag.bad_inputs);
        return false;
    }
    const double t0 = h->t_s;
    const double p0 = h->phase_counts;
    const int64_t s0 = h->raw_state;
    const int64_t s1 = (int64_t)floor(phase_end_counts);
    if (s1 != s0) {
        const int64_t dir = s1 > s0 ? 1 : -1;
        const int64_t n = s1 > s0 ? s1 - s0 : s0 - s1;
        const double dt = t_end_s - t0;
        const double dp = phase_end_counts - p0;
        /* Seconds per state along this segment; 0 for a jump. Multiplying and adding a constant
         * is monotone in IEEE arithmetic, so the event times below never run backwards. */
        const double s_per_count = dt / dp;
        const bool fast_ok = !h->cfg.force_per_edge && fabs(s_per_count) * h->f_clk > ODOSIM_HCTL_FAST_PERIODS;
        int64_t j = 1;
        while (j <= n) {
            /* Event j enters state s0 + dir*j: rising phase reaches the boundary s0 + j, falling
             * phase drops below s0 - j + 1. */
            const double boundary = (double)(dir > 0 ? s0 + j : s0 - j + 1);
            double tau = t0 + (boundary - p0) * s_per_count;
            tau = tau < t0 ? t0 : (tau > t_end_s ? t_end_s : tau);
            const int64_t k0 = (int64_t)ceil(tau * h->f_clk);
            settle_before(h, k0);
            if (fast_ok && j < n && h->pend_edge == PEND_NONE) {
                /* Fast path. Nothing is in the filter, and states j .. n-1 each last more than
                 * ODOSIM_HCTL_FAST_PERIODS > 3 clock periods: each is sampled at least three
                 * times, passes the filter before the next arrives, and is one state from the
                 * last: one count each, exactly what input_change() would do one by one. */
                const int64_t m = n - j;
                add_counts(h, dir * conv_sign(h) * m);
                h->raw_state = s0 + dir * (n - 1);
                h->filt_ab = state_ab(h->raw_state);
                h->diag.changes_fast += (uint64_t)m;
                j = n;
                continue;
            }
            input_change(h, k0, s0 + dir * j);
            j++;
        }
    }
    /* Edges strictly before t_end are clocked now; an edge at exactly t_end belongs to the next
     * segment, whose first change may happen at t_end and be sampled by it. */
    settle_before(h, (int64_t)ceil(t_end_s * h->f_clk));
    h->t_s = t_end_s;
    h->phase_counts = phase_end_counts;
    return true;
}

uint8_t odosim_hctl_read(odosim_hctl_t *h, uint8_t reg)
{
    const uint8_t live_msb = (uint8_t)(h->position >> 16);
    const uint8_t live_mid = (uint8_t)(h->position >> 8);
    const uint8_t live_lsb = (uint8_t)h->position;
    switch (reg) {
    case ODOSIM_HCTL_REG_ACT_POS_LSB:
        /* "Actual Position Registers R12H-R14H": reading the LSB latches the upper bytes so that
         * the following R13H and R12H reads belong to the same count. A second R14H re-latches. */
        h->latch_msb = live_msb;
        h->latch_mid = live_mid;
        h->latched = true;
        return live_lsb;
    case ODOSIM_HCTL_REG_ACT_POS_MID: return h->latched ? h->latch_mid : live_mid;
    case ODOSIM_HCTL_REG_ACT_POS_MSB:
        /* Model: the MSB read ends the sequence and releases the latch; without a pending latch
         * (R14H not read first) the upper bytes are live and may belong to another count. */
        if (h->latched) {
            h->latched = false;
            return h->latch_msb;
        }
        return live_msb;
    default: inc32(&h->diag.bad_registers); return 0U;
    }
}

bool odosim_hctl_write(odosim_hctl_t *h, uint8_t reg, uint8_t value)
{
    switch (reg) {
    case ODOSIM_HCTL_REG_ACT_POS_MID:
        /* "Actual Position Registers R12H-R14H": a write of any value to R13H clears the actual
         * position counter (all 24 bits). A pending latch would hold the old count: drop it. */
        h->position = 0U;
        h->latched = false;
        return true;
    case ODOSIM_HCTL_REG_CMD_POS_MSB:
    case ODOSIM_HCTL_REG_CMD_POS_MID:
    case ODOSIM_HCTL_REG_CMD_POS_LSB:
        /* "Idle mode / Preset" (model): position registers take a preset only in idle mode;
         * in any control mode the write is ignored. */
        if (!h->idle) {
            inc32(&h->diag.ignored_writes);
            return false;
        }
        if (reg == ODOSIM_HCTL_REG_CMD_POS_MSB) {
            h->preset_msb = value;
        } else if (reg == ODOSIM_HCTL_REG_CMD_POS_MID) {
            h->preset_mid = value;
        } else {
            /* The LSB write completes the preset and loads the counter, mirroring the read
             * protocol where the LSB is the byte that acts on all three. */
            h->position = ((uint32_t)h->preset_msb << 16) | ((uint32_t)h->preset_mid << 8) | value;
            h->latched = false;
        }
        return true;
    default: inc32(&h->diag.bad_registers); return false;
    }
}

void odosim_hctl_set_idle(odosim_hctl_t *h, bool idle) { h->idle = idle; }

void odosim_hctl_index(odosim_hctl_t *h)
{
    /* "Commutator" / "Pin Description": INDEX serves commutator alignment only; the actual
     * position counter is deliberately not touched. */
    inc32(&h->diag.index_pulses);
}

uint32_t odosim_hctl_read_position(odosim_hctl_t *h)
{
    /* The data sheet's order: LSB first (it latches), then the latched middle byte and MSB. */
    const uint32_t lsb = odosim_hctl_read(h, ODOSIM_HCTL_REG_ACT_POS_LSB);
    const uint32_t mid = odosim_hctl_read(h, ODOSIM_HCTL_REG_ACT_POS_MID);
    const uint32_t msb = odosim_hctl_read(h, ODOSIM_HCTL_REG_ACT_POS_MSB);
    return (msb << 16) | (mid << 8) | lsb;
}

uint8_t odosim_hctl_input_ab(double phase_counts)
{
    if (!finite_in(phase_counts, ODOSIM_HCTL_PHASE_MAX_COUNTS)) {
        return 0U;
    }
    return state_ab((int64_t)floor(phase_counts));
}

int32_t odosim_hctl_to_signed(uint32_t position24)
{
    const uint32_t p = position24 & ODOSIM_HCTL_POS_MASK;
    return (int32_t)((p & 0x800000UL) != 0U ? (int64_t)p - 0x1000000 : (int64_t)p);
}

uint32_t odosim_hctl_skipped(const odosim_hctl_t *h) { return h->diag.skipped_states; }

const odosim_hctl_diag_t *odosim_hctl_diag(const odosim_hctl_t *h) { return &h->diag; }
