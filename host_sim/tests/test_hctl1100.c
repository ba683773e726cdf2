/// The HCTL-1100-style decoder emulator against the HCTL-1100 data sheet ("Quadrature Decoder",
/// "Digital Filter", "Actual Position Registers R12H-R14H", "Idle mode / Preset"): 4x counting and
/// its direction convention, 24-bit wrap, the filter's count limit, the byte-wise read protocol
/// and its tearing, and the fast path agreeing with the per-edge path.
#include <check.h>

#include <math.h>
#include <stdlib.h>

#include "check_support.h"
#include "hctl1100.h"
#include "test_support.h"

static odosim_hctl_t make(odosim_hctl_conv_t conv, uint32_t f_clk_hz, bool force_per_edge, double phase0)
{
    odosim_hctl_t h;
    const odosim_hctl_config_t cfg = {f_clk_hz, conv, force_per_edge};
    ck_assert(odosim_hctl_init(&h, &cfg, 0.0, phase0));
    return h;
}

/// Drive at a constant rate in 1 ms steps (a physics step) from the current (t, phase).
static void drive(odosim_hctl_t *h, double rate_counts_per_s, double seconds)
{
    const double t0 = h->t_s, p0 = h->phase_counts;
    const long steps = lround(seconds * 1000.0);
    for (long i = 1; i <= steps; ++i) {
        const double t = t0 + (double)i * 1e-3;
        ck_assert(odosim_hctl_advance(h, t, p0 + rate_counts_per_s * (t - t0)));
    }
    /* Hold still for a step so that the last state has passed the filter. */
    ck_assert(odosim_hctl_advance(h, h->t_s + 1e-3, h->phase_counts));
}

START_TEST(counts_four_per_line_up_when_b_leads_a)
{
    /* HCTL-1100 "Quadrature Decoder": 4x decoding; counts up when CHB leads CHA. */
    /* Rising phase: B rises at state 3, A one state later at state 0: B leads A. */
    ck_assert_uint_eq(0x0U, odosim_hctl_input_ab(2.5));
    ck_assert_uint_eq(0x1U, odosim_hctl_input_ab(3.5));
    ck_assert_uint_eq(0x3U, odosim_hctl_input_ab(4.5));
    ck_assert_uint_eq(0x2U, odosim_hctl_input_ab(5.5)); /* B falls first too */

    odosim_hctl_t h = make(ODOSIM_HCTL_CONV_1100, 1000000U, false, 0.5);
    ck_assert(odosim_hctl_advance(&h, 1.0, 400.5)); /* 100 lines forward */
    ck_assert_uint_eq(400U, odosim_hctl_read_position(&h));
    ck_assert(odosim_hctl_advance(&h, 2.0, -3.5)); /* 101 lines back */
    ck_assert_uint_eq(0xFFFFFCU, odosim_hctl_read_position(&h));
    ck_assert_int_eq(-4, odosim_hctl_to_signed(odosim_hctl_read_position(&h)));
    ck_assert_uint_eq(0U, odosim_hctl_skipped(&h));

    /* HCTL-20xx convention: the same motion counts the other way. */
    odosim_hctl_t g = make(ODOSIM_HCTL_CONV_20XX, 1000000U, false, 0.5);
    ck_assert(odosim_hctl_advance(&g, 1.0, 400.5));
    ck_assert_int_eq(-400, odosim_hctl_to_signed(odosim_hctl_read_position(&g)));
    ck_assert(odosim_hctl_advance(&g, 2.0, -3.5));
    ck_assert_int_eq(4, odosim_hctl_to_signed(odosim_hctl_read_position(&g)));
}
END_TEST

START_TEST(position_wraps_at_24_bits_both_ways)
{
    /* HCTL-1100 "Actual Position Registers R12H-R14H": 24-bit two's complement, wraps. */
    odosim_hctl_t h = make(ODOSIM_HCTL_CONV_1100, 2000000U, false, 0.5);
    const double top = 8388608.0;                         /* 2^23 */
    ck_assert(odosim_hctl_advance(&h, 100.0, top - 2.5)); /* 84 kstates/s: fast path */
    ck_assert_uint_eq(0x7FFFFDU, odosim_hctl_read_position(&h));
    uint32_t last = odosim_hctl_read_position(&h);
    for (int i = 1; i <= 6; ++i) { /* one count at a time across +2^23 */
        ck_assert(odosim_hctl_advance(&h, 100.0 + i * 1e-3, top - 2.5 + i));
        const uint32_t now = odosim_hctl_read_position(&h);
        ck_assert_uint_eq(1U, (now - last) & ODOSIM_HCTL_POS_MASK);
        ck_assert_uint_eq(ts_wrap_counter((int64_t)floor(top - 2.5 + i), 24U), now);
        last = now;
    }
    ck_assert_int_eq(-8388605, odosim_hctl_to_signed(last)); /* 2^23 + 3 reads negative */

    ck_assert(odosim_hctl_advance(&h, 300.0, -top - 3.5)); /* back past -2^23 */
    const uint32_t back = odosim_hctl_read_position(&h);
    ck_assert_uint_eq(ts_wrap_counter((int64_t)-top - 4, 24U), back);
    ck_assert_int_eq(8388604, odosim_hctl_to_signed(back));
    ck_assert_uint_eq(0U, odosim_hctl_skipped(&h));
    ck_assert_uint_gt(odosim_hctl_diag(&h)->changes_fast, 16000000U);
}
END_TEST

START_TEST(fast_path_and_per_edge_path_count_identically)
{
    /* HCTL-1100 "Digital Filter": the arithmetic fast path is exact wherever it applies. */
    static const uint32_t clocks[] = {100000U, 333333U, 1000000U, 2000000U};
    ts_rng_t r;
    ts_rng_seed(&r, 1100U);
    uint64_t fast_total = 0U, edge_total = 0U;
    for (int traj = 0; traj < 40; ++traj) {
        const uint32_t f = clocks[traj % 4];
        const odosim_hctl_conv_t conv = (traj & 4) ? ODOSIM_HCTL_CONV_20XX : ODOSIM_HCTL_CONV_1100;
        const double p0 = ts_rng_uniform(&r, -10.0, 10.0);
        odosim_hctl_t fast = make(conv, f, false, p0);
        odosim_hctl_t slow = make(conv, f, true, p0);
        double t = 0.0, p = p0;
        for (int step = 0; step < 500; ++step) {
            /* Rates from standstill to twice the fast-path limit, either way, with reversals
             * that put successive edges arbitrarily close across a step boundary. */
            const double limit = (double)f / ODOSIM_HCTL_FAST_PERIODS;
            const double rate =
                ts_rng_uniform(&r, -2.0, 2.0) * limit * (step % 7 == 0 ? 1.0 : ts_rng_uniform(&r, 0.0, 0.5));
            const double dt = (step % 5 == 0) ? ts_rng_uniform(&r, 1e-6, 1e-4) : 1e-3;
            t += dt;
            p += rate * dt;
            ck_assert(odosim_hctl_advance(&fast, t, p));
            ck_assert(odosim_hctl_advance(&slow, t, p));
            ck_assert_uint_eq(odosim_hctl_read_position(&slow), odosim_hctl_read_position(&fast));
            ck_assert_uint_eq(odosim_hctl_skipped(&slow), odosim_hctl_skipped(&fast));
        }
        ck_assert_uint_eq(0U, odosim_hctl_diag(&slow)->changes_fast);
        fast_total += odosim_hctl_diag(&fast)->changes_fast;
        edge_total += odosim_hctl_diag(&fast)->changes_per_edge;
    }
    /* Both paths were exercised, the fast one doing most of the work. */
    ck_assert_uint_gt(fast_total, 500000U);
    ck_assert_uint_gt(edge_total, 10000U);
    ck_assert_uint_lt(edge_total, fast_total);

    /* Slow motion: both paths count every state, so the count is the true phase change. */
    odosim_hctl_t a = make(ODOSIM_HCTL_CONV_1100, 1000000U, false, 0.25);
    odosim_hctl_t b = make(ODOSIM_HCTL_CONV_1100, 1000000U, true, 0.25);
    double t = 0.0, p = 0.25;
    for (int step = 0; step < 2000; ++step) {
        t += 1e-3;
        p += ts_rng_uniform(&r, -200.0, 200.0); /* <= 200 kstates/s, below f_CLK/4 */
        ck_assert(odosim_hctl_advance(&a, t, p));
        ck_assert(odosim_hctl_advance(&b, t, p));
    }
    t += 1e-3;
    ck_assert(odosim_hctl_advance(&a, t, p)); /* let the last state through the filter */
    ck_assert(odosim_hctl_advance(&b, t, p));
    const uint32_t truth = ts_wrap_counter((int64_t)floor(p), 24U);
    ck_assert_uint_eq(truth, odosim_hctl_read_position(&a));
    ck_assert_uint_eq(truth, odosim_hctl_read_position(&b));
}
END_TEST

START_TEST(counts_are_lost_above_the_filter_limit)
{
    /* HCTL-1100 "Digital Filter": inputs must be stable for 3 rising CLK edges: f_CLK/3 limit. */
    odosim_hctl_t ok = make(ODOSIM_HCTL_CONV_1100, 100000U, false, 0.3);
    drive(&ok, 20000.0, 1.0); /* 5 clock periods per state */
    ck_assert_uint_eq(20000U, odosim_hctl_read_position(&ok));
    ck_assert_uint_eq(0U, odosim_hctl_skipped(&ok));

    odosim_hctl_t lost = make(ODOSIM_HCTL_CONV_1100, 100000U, false, 0.3);
    drive(&lost, 50000.0, 1.0); /* 2 clock periods per state: no state is sampled 3 times */
    ck_assert_int_lt(abs(odosim_hctl_to_signed(odosim_hctl_read_position(&lost))), 100);

    /* 2.5 periods per state: every other state passes, two states on: skipped, not counted. */
    odosim_hctl_t skip = make(ODOSIM_HCTL_CONV_1100, 100000U, false, 0.3);
    drive(&skip, 40000.0, 1.0);
    ck_assert_int_lt(odosim_hctl_to_signed(odosim_hctl_read_position(&skip)), 40000 / 2);
    ck_assert_uint_gt(odosim_hctl_skipped(&skip), 10000U);

    /* Just below f_CLK/3 (3.2 periods per state) nothing is lost yet. */
    odosim_hctl_t edge = make(ODOSIM_HCTL_CONV_1100, 100000U, false, 0.3);
    drive(&edge, 31250.0, 1.0);
    ck_assert_uint_eq(31250U, odosim_hctl_read_position(&edge));
}
END_TEST

START_TEST(short_glitches_are_filtered_out)
{
    /* HCTL-1100 "Digital Filter": a state held for fewer than three CLK edges never counts. */
    odosim_hctl_t h = make(ODOSIM_HCTL_CONV_1100, 1000000U, false, 0.5);
    ck_assert(odosim_hctl_advance(&h, 1.0, 0.5));
    ck_assert(odosim_hctl_advance(&h, 1.0 + 0.9e-6, 1.5)); /* into state 1 ... */
    ck_assert(odosim_hctl_advance(&h, 1.0 + 1.8e-6, 0.5)); /* ... and out, 1.8 us later */
    ck_assert(odosim_hctl_advance(&h, 2.0, 0.5));
    ck_assert_uint_eq(0U, odosim_hctl_read_position(&h));
    ck_assert(odosim_hctl_advance(&h, 2.0 + 0.9e-6, 1.5)); /* held 5 us: passes */
    ck_assert(odosim_hctl_advance(&h, 2.0 + 5.9e-6, 0.5));
    ck_assert_uint_eq(1U, odosim_hctl_read_position(&h)); /* the way back is still filtering */
    ck_assert(odosim_hctl_advance(&h, 3.0, 0.5));
    ck_assert_uint_eq(0U, odosim_hctl_read_position(&h)); /* +1 then -1 */
    ck_assert_uint_eq(4U, odosim_hctl_diag(&h)->changes_per_edge);
    ck_assert_uint_eq(0U, odosim_hctl_skipped(&h));
}
END_TEST

START_TEST(torn_read_when_upper_bytes_are_read_before_r14h)
{
    /* HCTL-1100 "Actual Position Registers R12H-R14H": reading R14H latches R12H/R13H; read
     * R14H first. In the wrong order the bytes belong to different counts. */
    odosim_hctl_t h = make(ODOSIM_HCTL_CONV_1100, 1000000U, false, 255.5);
    ck_assert(odosim_hctl_write(&h, ODOSIM_HCTL_REG_ACT_POS_MID, 0U)); /* clear */
    odosim_hctl_set_idle(&h, true);
    ck_assert(odosim_hctl_write(&h, ODOSIM_HCTL_REG_CMD_POS_MSB, 0x00U));
    ck_assert(odosim_hctl_write(&h, ODOSIM_HCTL_REG_CMD_POS_MID, 0x00U));
    ck_assert(odosim_hctl_write(&h, ODOSIM_HCTL_REG_CMD_POS_LSB, 0xFFU));
    odosim_hctl_set_idle(&h, false);
    ck_assert_uint_eq(0x0000FFU, odosim_hctl_read_position(&h));

    /* Wrong order: MSB, middle, then one count (0x00FF -> 0x0100 carry), then LSB. */
    const uint32_t msb = odosim_hctl_read(&h, ODOSIM_HCTL_REG_ACT_POS_MSB);
    const uint32_t mid = odosim_hctl_read(&h, ODOSIM_HCTL_REG_ACT_POS_MID);
    ck_assert(odosim_hctl_advance(&h, 1.0, 256.5));
    const uint32_t lsb = odosim_hctl_read(&h, ODOSIM_HCTL_REG_ACT_POS_LSB);
    const uint32_t torn = (msb << 16) | (mid << 8) | lsb;
    ck_assert_uint_eq(0x000000U, torn);
    const uint32_t truth = 0x000100U;
    ck_assert_uint_ne(truth, torn);
    ck_assert_uint_eq(0U, ((truth - torn) & ODOSIM_HCTL_POS_MASK) % 256U); /* off by 256 */

    /* Right order: R14H latches, the count moves on, R13H and R12H still give the latched
     * count: the value is the position at the R14H read, not a mix. */
    ck_assert_uint_eq(0x000100U, odosim_hctl_read_position(&h)); /* also releases the latch */
    ck_assert(odosim_hctl_advance(&h, 2.0, 0.5));                /* back to 0x0000 (256 counts) */
    ck_assert(odosim_hctl_advance(&h, 3.0, 255.5));              /* 0x00FF */
    const uint32_t l2 = odosim_hctl_read(&h, ODOSIM_HCTL_REG_ACT_POS_LSB);
    ck_assert(odosim_hctl_advance(&h, 4.0, 256.5)); /* 0x0100 while the read is under way */
    const uint32_t m2 = odosim_hctl_read(&h, ODOSIM_HCTL_REG_ACT_POS_MID);
    const uint32_t h2 = odosim_hctl_read(&h, ODOSIM_HCTL_REG_ACT_POS_MSB);
    ck_assert_uint_eq(0x0000FFU, (h2 << 16) | (m2 << 8) | l2);
    ck_assert_uint_eq(0x000100U, odosim_hctl_read_position(&h));

    /* The same across the MSB carry 0x00FFFF -> 0x010000: off by a multiple of 256 (65536). */
    odosim_hctl_set_idle(&h, true);
    ck_assert(odosim_hctl_write(&h, ODOSIM_HCTL_REG_CMD_POS_MSB, 0x00U));
    ck_assert(odosim_hctl_write(&h, ODOSIM_HCTL_REG_CMD_POS_MID, 0xFFU));
    ck_assert(odosim_hctl_write(&h, ODOSIM_HCTL_REG_CMD_POS_LSB, 0xFFU));
    odosim_hctl_set_idle(&h, false);
    const uint32_t m3 = odosim_hctl_read(&h, ODOSIM_HCTL_REG_ACT_POS_MSB);
    ck_assert(odosim_hctl_advance(&h, 5.0, 257.5));
    const uint32_t i3 = odosim_hctl_read(&h, ODOSIM_HCTL_REG_ACT_POS_MID);
    const uint32_t l3 = odosim_hctl_read(&h, ODOSIM_HCTL_REG_ACT_POS_LSB);
    const uint32_t torn3 = (m3 << 16) | (i3 << 8) | l3;
    ck_assert_uint_eq(0x000000U, torn3);
    ck_assert_uint_eq(0x010000U, odosim_hctl_read_position(&h));
}
END_TEST

START_TEST(writing_r13h_clears_the_position)
{
    /* HCTL-1100 "Actual Position Registers R12H-R14H": a write to R13H clears the counter. */
    odosim_hctl_t h = make(ODOSIM_HCTL_CONV_1100, 1000000U, false, 0.5);
    ck_assert(odosim_hctl_advance(&h, 1.0, 1234.5));
    ck_assert_uint_eq(1234U, odosim_hctl_read_position(&h));
    (void)odosim_hctl_read(&h, ODOSIM_HCTL_REG_ACT_POS_LSB); /* leave a latch pending */
    ck_assert(odosim_hctl_write(&h, ODOSIM_HCTL_REG_ACT_POS_MID, 0xA5U));
    ck_assert_uint_eq(0U, odosim_hctl_read(&h, ODOSIM_HCTL_REG_ACT_POS_MSB)); /* no stale latch */
    ck_assert_uint_eq(0U, odosim_hctl_read_position(&h));
    ck_assert(odosim_hctl_advance(&h, 2.0, 1244.5)); /* counting goes on from zero */
    ck_assert_uint_eq(10U, odosim_hctl_read_position(&h));
}
END_TEST

START_TEST(presets_load_only_in_idle_mode)
{
    /* HCTL-1100 "Idle mode / Preset": position presets take effect only in idle mode. */
    odosim_hctl_t h = make(ODOSIM_HCTL_CONV_1100, 1000000U, false, 0.5);
    ck_assert(odosim_hctl_advance(&h, 1.0, 10.5));
    ck_assert(!odosim_hctl_write(&h, ODOSIM_HCTL_REG_CMD_POS_MSB, 0x12U));
    ck_assert(!odosim_hctl_write(&h, ODOSIM_HCTL_REG_CMD_POS_MID, 0x34U));
    ck_assert(!odosim_hctl_write(&h, ODOSIM_HCTL_REG_CMD_POS_LSB, 0x56U));
    ck_assert_uint_eq(10U, odosim_hctl_read_position(&h));
    ck_assert_uint_eq(3U, odosim_hctl_diag(&h)->ignored_writes);

    odosim_hctl_set_idle(&h, true);
    ck_assert(odosim_hctl_write(&h, ODOSIM_HCTL_REG_CMD_POS_MSB, 0x12U));
    ck_assert(odosim_hctl_write(&h, ODOSIM_HCTL_REG_CMD_POS_MID, 0x34U));
    ck_assert_uint_eq(10U, odosim_hctl_read_position(&h)); /* loads on the LSB write */
    ck_assert(odosim_hctl_write(&h, ODOSIM_HCTL_REG_CMD_POS_LSB, 0x56U));
    ck_assert_uint_eq(0x123456U, odosim_hctl_read_position(&h));
    odosim_hctl_set_idle(&h, false);
    ck_assert(odosim_hctl_advance(&h, 2.0, 12.5)); /* counts on from the preset */
    ck_assert_uint_eq(0x123458U, odosim_hctl_read_position(&h));
}
END_TEST

START_TEST(index_pulses_leave_the_position_alone)
{
    /* HCTL-1100 "Commutator" / "Pin Description": INDEX does not touch the position counter. */
    odosim_hctl_t h = make(ODOSIM_HCTL_CONV_1100, 1000000U, false, 0.5);
    ck_assert(odosim_hctl_advance(&h, 1.0, 77.5));
    for (int i = 0; i < 5; ++i) {
        odosim_hctl_index(&h);
    }
    ck_assert_uint_eq(77U, odosim_hctl_read_position(&h));
    ck_assert_uint_eq(5U, odosim_hctl_diag(&h)->index_pulses);
}
END_TEST

START_TEST(bad_inputs_are_refused_and_counted)
{
    /* Never assert on external input (STYLE.md 4): refusals and fault counters. */
    odosim_hctl_t h;
    odosim_hctl_config_t cfg = {99999U, ODOSIM_HCTL_CONV_1100, false};
    ck_assert(!odosim_hctl_init(&h, &cfg, 0.0, 0.0));
    ck_assert(!odosim_hctl_advance(&h, 1.0, 1.0)); /* a failed init stays harmless */
    cfg.f_clk_hz = 2000001U;
    ck_assert(!odosim_hctl_init(&h, &cfg, 0.0, 0.0));
    cfg.f_clk_hz = 1000000U;
    cfg.convention = (odosim_hctl_conv_t)7;
    ck_assert(!odosim_hctl_init(&h, &cfg, 0.0, 0.0));
    ck_assert(!odosim_hctl_init(&h, NULL, 0.0, 0.0));
    cfg.convention = ODOSIM_HCTL_CONV_1100;
    ck_assert(!odosim_hctl_init(&h, &cfg, NAN, 0.0));

    h = make(ODOSIM_HCTL_CONV_1100, 1000000U, false, 0.5);
    ck_assert(odosim_hctl_advance(&h, 1.0, 20.5));
    ck_assert(!odosim_hctl_advance(&h, 0.5, 30.5)); /* time backwards */
    ck_assert(!odosim_hctl_advance(&h, 2.0, NAN));
    ck_assert(!odosim_hctl_advance(&h, INFINITY, 1.0));
    ck_assert(!odosim_hctl_advance(&h, 2.0, 1e300));
    ck_assert_uint_eq(4U, odosim_hctl_diag(&h)->bad_inputs);
    ck_assert_uint_eq(20U, odosim_hctl_read_position(&h));
    ck_assert_uint_eq(0U, odosim_hctl_read(&h, 0x07U));
    ck_assert(!odosim_hctl_write(&h, ODOSIM_HCTL_REG_ACT_POS_LSB, 1U));
    ck_assert_uint_eq(2U, odosim_hctl_diag(&h)->bad_registers);
    /* A jump (same time, new phase) is legal: its states arrive at once; two on is skipped. */
    ck_assert(odosim_hctl_advance(&h, 1.0, 22.5));
    ck_assert(odosim_hctl_advance(&h, 1.1, 22.5));
    ck_assert_uint_eq(20U, odosim_hctl_read_position(&h));
    ck_assert_uint_eq(1U, odosim_hctl_skipped(&h));
}
END_TEST

int main(void)
{
    Suite *s = suite_create("hctl1100");
    TCase *tc = tcase_create("core");
    tcase_set_timeout(tc, 60);
    tcase_add_test(tc, counts_four_per_line_up_when_b_leads_a);
    tcase_add_test(tc, position_wraps_at_24_bits_both_ways);
    tcase_add_test(tc, fast_path_and_per_edge_path_count_identically);
    tcase_add_test(tc, counts_are_lost_above_the_filter_limit);
    tcase_add_test(tc, short_glitches_are_filtered_out);
    tcase_add_test(tc, torn_read_when_upper_bytes_are_read_before_r14h);
    tcase_add_test(tc, writing_r13h_clears_the_position);
    tcase_add_test(tc, presets_load_only_in_idle_mode);
    tcase_add_test(tc, index_pulses_leave_the_position_alone);
    tcase_add_test(tc, bad_inputs_are_refused_and_counted);
    suite_add_tcase(s, tc);
    return ts_run_suite(s);
}
