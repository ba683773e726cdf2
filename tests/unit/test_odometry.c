/// Per-truck odometry (000 Eqs. 2.1-2.6, 6.28, 6.33-6.35, App. B) on the fixed-point core.
/// Doubles appear only as test references.
#include <math.h>
#include <stdint.h>
#include <stdio.h>

#include "odo/odo_odometry.h"
#include "test_support.h"
#include "unity.h"

void setUp(void) {}
void tearDown(void) {}

#define Q30(x)              ((int32_t)llround((x)*1073741824.0))
#define MM_Q32(v)           ((double)(v) / 4294967296.0)
#define TURNS_Q64_TO_RAD(v) ((double)(int64_t)(v) / 18446744073709551616.0 * 2.0 * M_PI)

static odo_truck_params_t labmate(void)
{
    odo_params_t p;
    odo_params_defaults(&p);
    return p.truck[0];
}

static odo_model_t model_of(const odo_truck_params_t *tp, uint8_t bits, uint8_t form)
{
    odo_model_t m;
    TEST_ASSERT_EQUAL(ODO_MODEL_OK, odo_model_init(&m, tp, bits, form, 40000U, 3000U));
    return m;
}

/// A truck at the origin, heading +x, whose first reading (left, right) sets the counter baseline.
static odo_truck_t truck_at_origin(const odo_model_t *m, uint32_t left, uint32_t right, uint8_t bits)
{
    odo_truck_t t;
    const odo_pose_t origin = {0, 0, 0U};
    odo_truck_reset(&t, &origin);
    odo_step_t st;
    odo_truck_step(&t, m, left, right, bits, 1U, &st);
    TEST_ASSERT_FALSE(st.jump);
    return t;
}

static double cm_mm(const odo_truck_params_t *tp)
{
    return M_PI * (tp->wheel_diameter_nm * 1e-6 / (tp->es_q30 / 1073741824.0)) / (tp->counts_per_rev_milli * 1e-3);
}

static void multipliers_follow_eqs_2_1_6_33_6_34_and_6_28(void)
{
    /* 000 Eq. 6.35: DU = c * cm * N; Eq. 6.33/6.34: cL = 2/(Ed+1), cR = 2/(1/Ed+1); Eq. 6.28. */
    odo_truck_params_t tp = labmate();
    tp.ed_q30 = Q30(1.0042);
    tp.eb_q30 = Q30(0.9871);
    tp.es_q30 = Q30(1.0123);
    const odo_model_t m = model_of(&tp, 24U, ODO_HEADING_MIDPOINT);
    const double ed = tp.ed_q30 / 1073741824.0, eb = tp.eb_q30 / 1073741824.0;
    const double kl = 2.0 / (ed + 1.0) * cm_mm(&tp), kr = 2.0 / (1.0 / ed + 1.0) * cm_mm(&tp);
    const double b_eff = eb * 340.0;
    /* within half an LSB of the Q40 format (plus the reference's own rounding) */
    const double half_lsb = 0.5 / 1099511627776.0 + 1e-15;
    TEST_ASSERT_DOUBLE_WITHIN(half_lsb, kl, (double)m.dist_mm_q40[0] / 1099511627776.0);
    TEST_ASSERT_DOUBLE_WITHIN(half_lsb, kr, (double)m.dist_mm_q40[1] / 1099511627776.0);
    TEST_ASSERT_DOUBLE_WITHIN(1e-9, ed, (double)m.dist_mm_q40[1] / (double)m.dist_mm_q40[0]);
    const double tl = kl / (2.0 * M_PI * b_eff), tr = kr / (2.0 * M_PI * b_eff);
    TEST_ASSERT_DOUBLE_WITHIN(1e-12 * tl, tl, (double)m.turn_q64[0] / 18446744073709551616.0);
    TEST_ASSERT_DOUBLE_WITHIN(1e-12 * tr, tr, (double)m.turn_q64[1] / 18446744073709551616.0);
    /* max counts: 3 m/s for 40 ms over the smaller k, plus one */
    TEST_ASSERT_UINT32_WITHIN(1U, (uint32_t)ceil(120.0 / kl) + 1U, m.max_counts);
}

static void count_delta_handles_every_wrap_of_16_24_32_bit_counters(void)
{
    TEST_ASSERT_EQUAL_INT32(2, odo_count_delta(0xFFFFU, 0x0001U, 16U));
    TEST_ASSERT_EQUAL_INT32(-2, odo_count_delta(0x0001U, 0xFFFFU, 16U));
    TEST_ASSERT_EQUAL_INT32(32767, odo_count_delta(0U, 0x7FFFU, 16U));
    TEST_ASSERT_EQUAL_INT32(-32768, odo_count_delta(0U, 0x8000U, 16U));
    TEST_ASSERT_EQUAL_INT32(5, odo_count_delta(0xFFFFFEU, 0x000003U, 24U));
    TEST_ASSERT_EQUAL_INT32(-8388608, odo_count_delta(0U, 0x800000U, 24U));
    TEST_ASSERT_EQUAL_INT32(1, odo_count_delta(0xFFFFFFFFU, 0U, 32U));
    TEST_ASSERT_EQUAL_INT32(INT32_MIN, odo_count_delta(0U, 0x80000000U, 32U));
    TEST_ASSERT_EQUAL_INT32(INT32_MAX, odo_count_delta(0U, 0x7FFFFFFFU, 32U));
    /* bits above the counter width are ignored (a 16-bit value carried in a 24-bit field) */
    TEST_ASSERT_EQUAL_INT32(3, odo_count_delta(0xAB0FFFFU, 0x0002U, 16U));
    ts_rng_t rng;
    ts_rng_seed(&rng, 24U);
    const uint8_t widths[] = {16U, 24U, 32U};
    for (int n = 0; n < 100000; ++n) {
        const uint8_t bits = widths[n % 3];
        const int64_t half = (int64_t)1 << (bits - 1U);
        const int64_t start = ts_rng_range(&rng, 0, 2 * half - 1);
        const int64_t delta = ts_rng_range(&rng, -half, half - 1);
        TEST_ASSERT_EQUAL_INT32(
            (int32_t)delta, odo_count_delta(ts_wrap_counter(start, bits), ts_wrap_counter(start + delta, bits), bits));
    }
}

static void straight_line_keeps_heading_and_lateral_position_exact(void)
{
    const odo_truck_params_t tp = labmate();
    const odo_model_t m = model_of(&tp, 24U, ODO_HEADING_MIDPOINT);
    uint32_t c = 0xFFF000U; /* starts close to the 24-bit wrap */
    odo_truck_t t = truck_at_origin(&m, c, c, 24U);
    odo_step_t st;
    for (int i = 0; i < 5000; ++i) {
        c = (c + 661U) & 0xFFFFFFU;
        odo_truck_step(&t, &m, c, c, 24U, 1U, &st);
        TEST_ASSERT_FALSE(st.jump);
    }
    TEST_ASSERT_EQUAL_UINT64(0U, t.pose.heading_q64);
    TEST_ASSERT_EQUAL_INT64(0, t.pose.y_mm_q32);
    TEST_ASSERT_DOUBLE_WITHIN(1e-6, 5000.0 * 661.0 * cm_mm(&tp), MM_Q32(t.pose.x_mm_q32));
}

static void on_the_spot_turn_changes_heading_not_position(void)
{
    const odo_truck_params_t tp = labmate();
    const odo_model_t m = model_of(&tp, 24U, ODO_HEADING_MIDPOINT);
    odo_truck_t t = truck_at_origin(&m, 0U, 0U, 24U);
    odo_step_t st;
    int64_t n = 0;
    for (int i = 1; i <= 250; ++i) { /* 250 ticks of +-300 counts */
        n += 300;
        odo_truck_step(&t, &m, ts_wrap_counter(-n, 24U), ts_wrap_counter(n, 24U), 24U, 1U, &st);
    }
    const double want = 2.0 * (double)n * cm_mm(&tp) / 340.0; /* Eq. 2.4 summed */
    const double got = TURNS_Q64_TO_RAD(t.pose.heading_q64);
    TEST_ASSERT_DOUBLE_WITHIN(1e-9, remainder(want, 2.0 * M_PI), got);
    TEST_ASSERT_DOUBLE_WITHIN(1e-6, 0.0, MM_Q32(t.pose.x_mm_q32));
    TEST_ASSERT_DOUBLE_WITHIN(1e-6, 0.0, MM_Q32(t.pose.y_mm_q32));
}

/// Drive a quarter of a constant-curvature arc; return the end-point error against the exact arc.
static double arc_end_error_mm(uint8_t form)
{
    const odo_truck_params_t tp = labmate();
    const odo_model_t m = model_of(&tp, 32U, form);
    const int32_t dl = 1500, dr = 1800; /* counts per tick */
    const double k = cm_mm(&tp), b = 340.0;
    const double dth = (dr - dl) * k / b, u = 0.5 * (dl + dr) * k;
    const int ticks = (int)floor((M_PI / 2.0) / dth);
    odo_truck_t t = truck_at_origin(&m, 0U, 0U, 32U);
    odo_step_t st;
    for (int i = 1; i <= ticks; ++i) {
        odo_truck_step(&t, &m, (uint32_t)(i * dl), (uint32_t)(i * dr), 32U, 1U, &st);
    }
    const double r = u / dth, th = ticks * dth; /* exact circle through the origin, heading +x */
    return hypot(MM_Q32(t.pose.x_mm_q32) - r * sin(th), MM_Q32(t.pose.y_mm_q32) - r * (1.0 - cos(th)));
}

static void midpoint_form_is_far_more_accurate_than_eq_2_6_on_arcs(void)
{
    /* Eq. 2.6 advances along the new heading: an error of order U*dtheta/2 per tick that adds up;
     * the midpoint form is exact in direction and only shortens each chord by dtheta^2/24. */
    const double mid = arc_end_error_mm(ODO_HEADING_MIDPOINT);
    const double paper = arc_end_error_mm(ODO_HEADING_PAPER);
    TEST_ASSERT_TRUE_MESSAGE(mid < 0.05, "midpoint error on a quarter arc");
    TEST_ASSERT_TRUE_MESSAGE(paper > 5.0, "Eq. 2.6 form should show its first-order error");
    TEST_ASSERT_TRUE(paper > 100.0 * mid);
}

static void unequal_wheels_are_corrected_per_eq_6_35(void)
{
    /* A robot with a larger right wheel (Ed > 1) that counts equally on both wheels really turns
     * left; the calibrated model must say so, with the rate of Eq. 2.4 on the corrected distances. */
    odo_truck_params_t tp = labmate();
    tp.ed_q30 = Q30(1.01);
    const odo_model_t m = model_of(&tp, 24U, ODO_HEADING_MIDPOINT);
    odo_truck_t t = truck_at_origin(&m, 0U, 0U, 24U);
    odo_step_t st;
    odo_truck_step(&t, &m, 1000U, 1000U, 24U, 1U, &st);
    const double ed = tp.ed_q30 / 1073741824.0;
    const double want = 1000.0 * cm_mm(&tp) * (2.0 / (1.0 / ed + 1.0) - 2.0 / (ed + 1.0)) / 340.0;
    TEST_ASSERT_TRUE(st.dturn_q64 > 0);
    TEST_ASSERT_DOUBLE_WITHIN(1e-12, want, TURNS_Q64_TO_RAD(t.pose.heading_q64));
    /* Eq. 6.30: the mean wheel diameter is kept, so the centre moves exactly 1000 * cm. */
    TEST_ASSERT_DOUBLE_WITHIN(1e-9, 1000.0 * cm_mm(&tp), (double)st.dist_mm_q40 / 1099511627776.0);
}

static void implausible_counter_jump_is_flagged_not_integrated(void)
{
    const odo_truck_params_t tp = labmate();
    const odo_model_t m = model_of(&tp, 24U, ODO_HEADING_MIDPOINT);
    odo_truck_t t = truck_at_origin(&m, 100U, 100U, 24U);
    odo_step_t st;
    odo_truck_step(&t, &m, 100U + m.max_counts, 100U, 24U, 1U, &st); /* exactly at the limit: fine */
    TEST_ASSERT_FALSE(st.jump);
    const odo_pose_t before = t.pose;
    const uint32_t base = 100U + m.max_counts;
    odo_truck_step(&t, &m, base + m.max_counts + 1U, 100U, 24U, 1U, &st); /* one count too many */
    TEST_ASSERT_TRUE(st.jump);
    TEST_ASSERT_EQUAL_INT64(before.x_mm_q32, t.pose.x_mm_q32);
    TEST_ASSERT_EQUAL_UINT64(before.heading_q64, t.pose.heading_q64);
    /* the next tick integrates from the re-taken baseline */
    odo_truck_step(&t, &m, base + m.max_counts + 11U, 110U, 24U, 1U, &st);
    TEST_ASSERT_FALSE(st.jump);
    TEST_ASSERT_EQUAL_INT32(10, st.delta[0]);
    TEST_ASSERT_EQUAL_INT32(10, st.delta[1]);
}

static void inverted_encoders_count_forward(void)
{
    odo_truck_params_t tp = labmate();
    tp.flags = ODO_TRUCK_INVERT_LEFT;
    const odo_model_t m = model_of(&tp, 16U, ODO_HEADING_MIDPOINT);
    odo_truck_t t = truck_at_origin(&m, 5U, 5U, 16U);
    odo_step_t st;
    odo_truck_step(&t, &m, ts_wrap_counter(5 - 400, 16U), 405U, 16U, 1U, &st);
    TEST_ASSERT_EQUAL_INT32(400, st.delta[0]);
    TEST_ASSERT_EQUAL_INT32(400, st.delta[1]);
    TEST_ASSERT_EQUAL_INT64(0, st.dturn_q64);
}

static void parameters_that_cannot_be_represented_are_refused(void)
{
    odo_truck_params_t tp = labmate();
    odo_model_t m;
    /* 3 m/s at 40 ms needs ~9900 counts per tick: more than half a 16-bit counter? no; but with a
     * very fine encoder it is, and the modular delta would be ambiguous. */
    tp.counts_per_rev_milli = 4000000000U; /* 4e6 counts per turn */
    TEST_ASSERT_EQUAL(ODO_MODEL_ERR_RANGE, odo_model_init(&m, &tp, 16U, 0U, 40000U, 3000U));
    TEST_ASSERT_EQUAL(ODO_MODEL_OK, odo_model_init(&m, &tp, 32U, 0U, 40000U, 3000U));
    tp = labmate();
    tp.ed_q30 = 0;
    TEST_ASSERT_EQUAL(ODO_MODEL_ERR_RANGE, odo_model_init(&m, &tp, 24U, 0U, 40000U, 3000U));
}

/// Lost samples: the limit is max_counts per tick elapsed, as long as the counter width can tell
/// that many counts apart (max_counts * ticks < 2^(w-1)).
static void the_plausibility_limit_scales_with_the_ticks_elapsed(void)
{
    const odo_truck_params_t tp = labmate();
    const odo_model_t m = model_of(&tp, 24U, ODO_HEADING_MIDPOINT);
    odo_truck_t t = truck_at_origin(&m, 0U, 0U, 24U);
    odo_step_t st;
    const uint32_t three = 3U * m.max_counts;
    odo_truck_step(&t, &m, three, three, 24U, 3U, &st);
    TEST_ASSERT_FALSE(st.jump);
    TEST_ASSERT_EQUAL_INT32((int32_t)three, st.delta[0]);
    odo_truck_step(&t, &m, three + 2U * m.max_counts + 1U, three, 24U, 2U, &st); /* one too many */
    TEST_ASSERT_TRUE(st.jump);
    odo_truck_step(&t, &m, three + 2U * m.max_counts + 1U, three, 24U, 0U, &st); /* 0 counts as 1 */
    TEST_ASSERT_FALSE(st.jump);
    /* 24 bits tell 844 ticks at 9933 counts (2^23 / 9933 = 844.5); 845 are ambiguous */
    const uint32_t horizon = (uint32_t)((1UL << 23) / m.max_counts);
    odo_truck_step(&t, &m, 0U, 0U, 24U, horizon, &st);
    TEST_ASSERT_FALSE(st.jump);
    odo_truck_step(&t, &m, 0U, 0U, 24U, horizon + 1U, &st);
    TEST_ASSERT_TRUE(st.jump);
    odo_truck_step(&t, &m, 5U, 5U, 0U, 1U, &st); /* a reading of no bits tells nothing */
    TEST_ASSERT_TRUE(st.jump);
    TEST_ASSERT_EQUAL_INT32(0, odo_count_delta(7U, 9U, 0U));
    TEST_ASSERT_EQUAL_INT32(2, odo_count_delta(7U, 9U, 200U));
}

/// A step over several ticks of a constant-curvature arc (000 Eqs. 2.2-2.6 with the midpoint
/// heading) lands on the arc: its length is taken as the chord, U sinc(dtheta/2), not U, whose
/// overshoot grows with the cube of the gap. 6 ticks of a 0.5 m radius at 1 m/s: 2.3 mm.
static void a_multi_tick_step_follows_the_arc(void)
{
    const odo_truck_params_t tp = labmate();
    const odo_model_t m = model_of(&tp, 24U, ODO_HEADING_MIDPOINT);
    const double k = cm_mm(&tp), b = 340.0, r_mm = 500.0, v = 1000.0;
    const int32_t dl = (int32_t)llround(v * (1.0 - b / (2.0 * r_mm)) * 0.04 / k);
    const int32_t dr = (int32_t)llround(v * (1.0 + b / (2.0 * r_mm)) * 0.04 / k);
    odo_truck_t t = truck_at_origin(&m, 0U, 0U, 24U);
    odo_step_t st;
    odo_truck_step(&t, &m, (uint32_t)(6 * dl), (uint32_t)(6 * dr), 24U, 6U, &st);
    TEST_ASSERT_FALSE(st.jump);
    /* the exact arc through the same counts, in double precision */
    const double u = 6.0 * k * (dl + dr) / 2.0, th = 6.0 * k * (dr - dl) / b;
    const double chord = u * sin(th / 2.0) / (th / 2.0);
    TEST_ASSERT_DOUBLE_WITHIN(0.005, chord * cos(th / 2.0), MM_Q32(t.pose.x_mm_q32));
    TEST_ASSERT_DOUBLE_WITHIN(0.005, chord * sin(th / 2.0), MM_Q32(t.pose.y_mm_q32));
    TEST_ASSERT_TRUE(u - chord > 2.0); /* what the step would have overshot */
    TEST_ASSERT_DOUBLE_WITHIN(1e-9, th, TURNS_Q64_TO_RAD(t.pose.heading_q64));
    /* per tick (ticks == 1) the step stays U along the midpoint, as the double reference has it */
    odo_truck_t t1 = truck_at_origin(&m, 0U, 0U, 24U);
    odo_truck_step(&t1, &m, (uint32_t)dl, (uint32_t)dr, 24U, 1U, &st);
    const double u1 = k * (dl + dr) / 2.0, th1 = k * (dr - dl) / b;
    TEST_ASSERT_DOUBLE_WITHIN(1e-6, u1 * cos(th1 / 2.0), MM_Q32(t1.pose.x_mm_q32));
}

/// A step over a long gap is bounded by what int64 mm Q40 can sum: a coarse encoder (100 counts
/// per turn of a 477 mm wheel, 15 mm a count) with 32-bit counters can tell 100,000 ticks apart,
/// but 200,000 counts would be 3,000 km, 2^62.5 per wheel in Q40: flagged, never overflowed.
static void a_step_too_large_to_integrate_is_flagged(void)
{
    odo_truck_params_t tp = labmate();
    tp.wheel_diameter_nm = 477000000U;
    tp.counts_per_rev_milli = 100000U;
    const odo_model_t m = model_of(&tp, 32U, ODO_HEADING_MIDPOINT);
    TEST_ASSERT_TRUE(m.max_delta_counts >= m.max_counts);
    TEST_ASSERT_TRUE(m.max_delta_counts < 200000U);
    TEST_ASSERT_TRUE((uint64_t)m.max_counts * 100000U > 200000U);
    odo_truck_t t = truck_at_origin(&m, 0U, 0U, 32U);
    odo_step_t st;
    odo_truck_step(&t, &m, 200000U, 200000U, 32U, 100000U, &st);
    TEST_ASSERT_TRUE(st.jump);
    TEST_ASSERT_EQUAL_INT64(0, t.pose.x_mm_q32);
    odo_truck_step(&t, &m, 200000U + m.max_delta_counts, 200000U + m.max_delta_counts, 32U, 100000U, &st);
    TEST_ASSERT_FALSE(st.jump);
    TEST_ASSERT_DOUBLE_WITHIN(1e-6 * m.max_delta_counts * cm_mm(&tp), m.max_delta_counts * cm_mm(&tp),
                              MM_Q32(t.pose.x_mm_q32));
}

/// Beyond ODO_POSE_LIMIT_MM_Q32 the pose is held (int64 overflowed 2^31 mm out before).
static void a_pose_beyond_the_limit_is_held(void)
{
    const odo_truck_params_t tp = labmate();
    const odo_model_t m = model_of(&tp, 24U, ODO_HEADING_MIDPOINT);
    odo_truck_t t;
    const odo_pose_t far = {INT64_MAX - 5, INT64_MIN + 5, 0U};
    odo_truck_reset(&t, &far);
    odo_step_t st;
    odo_truck_step(&t, &m, 0U, 0U, 24U, 1U, &st);
    odo_truck_step(&t, &m, 9000U, 9000U, 24U, 1U, &st);
    TEST_ASSERT_TRUE(st.range);
    TEST_ASSERT_FALSE(st.jump);
    TEST_ASSERT_EQUAL_INT64(INT64_MAX - 5, t.pose.x_mm_q32);
    TEST_ASSERT_FALSE(odo_pose_in_range(&t.pose));
    const odo_pose_t edge = {ODO_POSE_LIMIT_MM_Q32 - 1, -(ODO_POSE_LIMIT_MM_Q32 - 1), 0U};
    TEST_ASSERT_TRUE(odo_pose_in_range(&edge));
    const odo_pose_t low = {-ODO_POSE_LIMIT_MM_Q32, -ODO_POSE_LIMIT_MM_Q32, 0U}; /* [-L, L) */
    TEST_ASSERT_TRUE(odo_pose_in_range(&low));
    const odo_pose_t out_y = {0, -ODO_POSE_LIMIT_MM_Q32 - 1, 0U};
    TEST_ASSERT_FALSE(odo_pose_in_range(&out_y));
    const odo_pose_t out_x = {ODO_POSE_LIMIT_MM_Q32, 0, 0U};
    TEST_ASSERT_FALSE(odo_pose_in_range(&out_x));
    const odo_pose_t far_y = {0, INT64_MAX, 0U};
    TEST_ASSERT_FALSE(odo_pose_in_range(&far_y));
}

/* ---------------------------------------------------------------------------------------------
 * Tyre scrub (odo_odometry.h): dtheta = dtheta(Eq. 2.4) * (1 - k m / v).
 * ------------------------------------------------------------------------------------------- */

/// Run the same count stream through two models and return both trucks.
static void drive_pair(const odo_model_t *a, const odo_model_t *b, const int32_t (*d)[2], int n, uint8_t bits,
                       odo_truck_t *ta, odo_truck_t *tb)
{
    *ta = truck_at_origin(a, 0U, 0U, bits);
    *tb = truck_at_origin(b, 0U, 0U, bits);
    int64_t c[2] = {0, 0};
    odo_step_t st;
    for (int i = 0; i < n; ++i) {
        c[0] += d[i][0];
        c[1] += d[i][1];
        odo_truck_step(ta, a, ts_wrap_counter(c[0], bits), ts_wrap_counter(c[1], bits), bits, 1U, &st);
        TEST_ASSERT_FALSE(st.jump);
        odo_truck_step(tb, b, ts_wrap_counter(c[0], bits), ts_wrap_counter(c[1], bits), bits, 1U, &st);
        TEST_ASSERT_FALSE(st.jump);
    }
}

/// 000 Eq. 2.4 / Eq. 2.8, extended: on a spot turn (wheels opposite, s = 1) or a pivot on one wheel
/// m = 0, so Eb alone is the wheelbase there (what UMBmark measures) and k changes nothing, bit for
/// bit.
static void spot_turn_is_unchanged_by_scrub(void)
{
    odo_truck_params_t tp = labmate(), tk = labmate();
    tp.eb_q30 = tk.eb_q30 = Q30(1.0065);
    static const int32_t ks_q30[] = {Q30(0.2), Q30(-0.2), Q30(0.0095), (int32_t)(1 << 28), -(int32_t)(1 << 28)};
    int32_t d[300][2];
    for (int i = 0; i < 300; ++i) {
        const int32_t n = 1 + (i * 37) % 600;
        d[i][0] = (i % 3 == 2) ? 0 : ((i & 1) ? -n : n); /* spot turns both ways, pivots */
        d[i][1] = (i % 3 == 2) ? n : -d[i][0];
    }
    for (size_t k = 0; k < sizeof ks_q30 / sizeof ks_q30[0]; ++k) {
        tk.scrub_q30 = ks_q30[k];
        const odo_model_t m0 = model_of(&tp, 24U, ODO_HEADING_MIDPOINT), mk = model_of(&tk, 24U, ODO_HEADING_MIDPOINT);
        odo_truck_t a, b;
        drive_pair(&m0, &mk, (const int32_t(*)[2])d, 300, 24U, &a, &b);
        TEST_ASSERT_EQUAL_UINT64(a.pose.heading_q64, b.pose.heading_q64);
        TEST_ASSERT_EQUAL_INT64(a.pose.x_mm_q32, b.pose.x_mm_q32);
        TEST_ASSERT_EQUAL_INT64(a.pose.y_mm_q32, b.pose.y_mm_q32);
    }
    /* a spot turn's heading is Eq. 2.4 over b Eb, computed here in double */
    tk.scrub_q30 = Q30(0.2);
    const odo_model_t mk = model_of(&tk, 24U, ODO_HEADING_MIDPOINT);
    odo_truck_t t = truck_at_origin(&mk, 0U, 0U, 24U);
    odo_step_t st;
    odo_truck_step(&t, &mk, ts_wrap_counter(-500, 24U), 500U, 24U, 1U, &st);
    TEST_ASSERT_DOUBLE_WITHIN(1e-12, 1000.0 * cm_mm(&tk) / (340.0 * (tk.eb_q30 / 1073741824.0)),
                              TURNS_Q64_TO_RAD(t.pose.heading_q64));
}

/// An arc of radius R (same-sign wheels, s = b / 2R) turns by Eq. 2.4's angle times
/// 1 - k m / v, m = 2 min(|dL|, |dR|), v = |dL| + |dR|, computed here from the integer counts; the
/// distance is unchanged. Forward and backward, left and right, k of either sign; and the
/// effective wheelbase is b Eb / (1 - k (1 - s)).
static void arc_of_known_radius_gets_the_predicted_factor(void)
{
    static const struct {
        int32_t dl, dr;
        double k;
    } arcs[] = {
        {1000, 1459, 0.0095},                        /* R ~ 0.43 m at b 340 mm, OptiOdom's k */
        {1459, 1000, 0.0095},                        /* the other side */
        {-1000, -1459, 0.0095},                      /* backwards */
        {700, 2100, 0.2},                            /* tight: s = 0.5 */
        {2100, 700, -0.2},      {1500, 1501, -0.25}, /* almost straight: s ~ 3e-4 */
        {1, 600, 0.25},                              /* almost a pivot */
    };
    for (size_t i = 0; i < sizeof arcs / sizeof arcs[0]; ++i) {
        odo_truck_params_t tp = labmate(), tk = labmate();
        tp.eb_q30 = tk.eb_q30 = Q30(1.0065);
        tk.scrub_q30 = Q30(arcs[i].k);
        const odo_model_t m0 = model_of(&tp, 32U, ODO_HEADING_MIDPOINT), mk = model_of(&tk, 32U, ODO_HEADING_MIDPOINT);
        odo_step_t s0, sk;
        odo_truck_t a = truck_at_origin(&m0, 0U, 0U, 32U), b = truck_at_origin(&mk, 0U, 0U, 32U);
        odo_truck_step(&a, &m0, (uint32_t)arcs[i].dl, (uint32_t)arcs[i].dr, 32U, 1U, &s0);
        odo_truck_step(&b, &mk, (uint32_t)arcs[i].dl, (uint32_t)arcs[i].dr, 32U, 1U, &sk);
        const double al = fabs((double)arcs[i].dl), ar = fabs((double)arcs[i].dr);
        const double g = 1.0 - (tk.scrub_q30 / 1073741824.0) * 2.0 * fmin(al, ar) / (al + ar);
        char msg[64];
        snprintf(msg, sizeof msg, "arc %u", (unsigned)i);
        /* the factor, on the firmware's own Eq. 2.4 angle: within 2^-33 relative (m / v in Q32)
         * plus half an LSB per count (k times the per-count multipliers, rounded) */
        TEST_ASSERT_DOUBLE_WITHIN_MESSAGE(fabs(g * (double)s0.dturn_q64) * 2e-10 + (al + ar), g * (double)s0.dturn_q64,
                                          (double)sk.dturn_q64, msg);
        TEST_ASSERT_EQUAL_INT64_MESSAGE(s0.dist_mm_q40, sk.dist_mm_q40, msg);
        /* against the effective wheelbase of the header, in double from the parameters */
        const double s = fabs(ar - al) / (al + ar);
        const double b_arc = 340.0 * (tk.eb_q30 / 1073741824.0) / (1.0 - (tk.scrub_q30 / 1073741824.0) * (1.0 - s));
        const double want = (arcs[i].dr - arcs[i].dl) * cm_mm(&tk) / b_arc;
        TEST_ASSERT_DOUBLE_WITHIN_MESSAGE(fabs(want) * 5e-11 + 1e-15, want, TURNS_Q64_TO_RAD(b.pose.heading_q64), msg);
    }
    /* equal wheels with Ed != 1 (m / v = 1): the factor is exactly 1 - k */
    odo_truck_params_t tp = labmate(), tk = labmate();
    tp.ed_q30 = tk.ed_q30 = Q30(1.01);
    tk.scrub_q30 = Q30(0.125);
    const odo_model_t m0 = model_of(&tp, 24U, ODO_HEADING_MIDPOINT), mk = model_of(&tk, 24U, ODO_HEADING_MIDPOINT);
    odo_truck_t a = truck_at_origin(&m0, 0U, 0U, 24U), b = truck_at_origin(&mk, 0U, 0U, 24U);
    odo_step_t s0, sk;
    odo_truck_step(&a, &m0, 1000U, 1000U, 24U, 1U, &s0);
    odo_truck_step(&b, &mk, 1000U, 1000U, 24U, 1U, &sk);
    TEST_ASSERT_TRUE(s0.dturn_q64 > 0);
    /* k dtheta comes from k-scaled per-count multipliers, each rounded to half a Q64 LSB: 2000
     * counts give at most 1000 LSB (5e-17 rad) */
    TEST_ASSERT_INT64_WITHIN(1000, s0.dturn_q64 - s0.dturn_q64 / 8, sk.dturn_q64);
}

/// k == 0 is the firmware before the term, bit for bit: the heading change is exactly Eq. 2.4's
/// modular sum of the model's own multipliers, on every kind of tick, including arcs.
static void zero_scrub_is_bit_identical_to_plain_eq_2_4(void)
{
    ts_rng_t rng;
    ts_rng_seed(&rng, 0x5C4ABULL);
    odo_truck_params_t tp = labmate();
    tp.ed_q30 = Q30(1.0031);
    tp.eb_q30 = Q30(0.9917);
    tp.scrub_q30 = 0;
    const odo_model_t m = model_of(&tp, 24U, ODO_HEADING_MIDPOINT);
    odo_truck_t t = truck_at_origin(&m, 0U, 0U, 24U);
    int64_t c[2] = {0, 0};
    for (int i = 0; i < 20000; ++i) {
        int32_t d[2];
        for (int w = 0; w < 2; ++w) {
            d[w] = (int32_t)ts_rng_range(&rng, -(int64_t)m.max_counts, (int64_t)m.max_counts);
            c[w] += d[w];
        }
        odo_pose_t before = t.pose;
        odo_step_t st;
        odo_truck_step(&t, &m, ts_wrap_counter(c[0], 24U), ts_wrap_counter(c[1], 24U), 24U, 1U, &st);
        const uint64_t want = m.turn_q64[1] * (uint64_t)(int64_t)d[1] - m.turn_q64[0] * (uint64_t)(int64_t)d[0];
        TEST_ASSERT_EQUAL_UINT64(want, (uint64_t)st.dturn_q64);
        TEST_ASSERT_EQUAL_UINT64(before.heading_q64 + want, t.pose.heading_q64);
    }
}

/// The firmware's scrub term against the double reference's formula over many random ticks: the
/// relative error of the factor stays below 2^-32 (m / v in Q32, then k dtheta).
static void scrub_factor_error_is_below_2e_minus_32_on_random_ticks(void)
{
    ts_rng_t rng;
    ts_rng_seed(&rng, 0xFAC7ULL);
    odo_truck_params_t tp = labmate(), tk = labmate();
    tk.scrub_q30 = -(int32_t)(1 << 28);                              /* the largest |k| */
    tp.counts_per_rev_milli = tk.counts_per_rev_milli = 4000000000U; /* big deltas: up to ~1e6 */
    const odo_model_t m0 = model_of(&tp, 32U, ODO_HEADING_MIDPOINT), mk = model_of(&tk, 32U, ODO_HEADING_MIDPOINT);
    double worst = 0.0;
    for (int i = 0; i < 100000; ++i) {
        const int32_t sign = (i & 1) ? 1 : -1;
        const int32_t dl = sign * (int32_t)ts_rng_range(&rng, 1, (int64_t)m0.max_counts);
        const int32_t dr = sign * (int32_t)ts_rng_range(&rng, 1, (int64_t)m0.max_counts);
        odo_truck_t a = truck_at_origin(&m0, 0U, 0U, 32U), b = truck_at_origin(&mk, 0U, 0U, 32U);
        odo_step_t s0, sk;
        odo_truck_step(&a, &m0, (uint32_t)dl, (uint32_t)dr, 32U, 1U, &s0);
        odo_truck_step(&b, &mk, (uint32_t)dl, (uint32_t)dr, 32U, 1U, &sk);
        if (s0.dturn_q64 == 0) {
            continue;
        }
        const long double al = fabsl((long double)dl), ar = fabsl((long double)dr);
        const long double g = 1.0L + 0.25L * 2.0L * fminl(al, ar) / (al + ar);
        const long double want = g * (long double)s0.dturn_q64;
        const double err = (double)(fabsl((long double)sk.dturn_q64 - want) / fabsl(want));
        worst = fmax(worst, err);
    }
    TEST_ASSERT_TRUE_MESSAGE(worst < ldexp(1.0, -32), "relative error of the scrub factor");
}

/* ---------------------------------------------------------------------------------------------
 * Counter widths 8..32 (odo_params_t.counter_bits).
 * ------------------------------------------------------------------------------------------- */

/// Every (prev, cur) pair of an 8-bit counter, and random ones of 12 and the other widths: the
/// delta is the shortest way round, so wraps both ways are exact.
static void count_delta_handles_8_and_12_bit_counters(void)
{
    for (uint32_t prev = 0; prev < 256U; ++prev) {
        for (uint32_t cur = 0; cur < 256U; ++cur) {
            int32_t want = (int32_t)((cur - prev) & 0xFFU);
            if (want >= 128) {
                want -= 256;
            }
            TEST_ASSERT_EQUAL_INT32(want, odo_count_delta(prev, cur, 8U));
        }
    }
    TEST_ASSERT_EQUAL_INT32(3, odo_count_delta(0xFFEU, 0x001U, 12U));
    TEST_ASSERT_EQUAL_INT32(-3, odo_count_delta(0x001U, 0xFFEU, 12U));
    TEST_ASSERT_EQUAL_INT32(-2048, odo_count_delta(0U, 0x800U, 12U));
    TEST_ASSERT_EQUAL_INT32(2047, odo_count_delta(0U, 0x7FFU, 12U));
    ts_rng_t rng;
    ts_rng_seed(&rng, 12U);
    for (int n = 0; n < 100000; ++n) {
        const uint8_t bits = (uint8_t)ts_rng_range(&rng, 8, 32);
        const int64_t half = (int64_t)1 << (bits - 1U);
        const int64_t start = ts_rng_range(&rng, 0, 2 * half - 1);
        const int64_t delta = ts_rng_range(&rng, -half, half - 1);
        TEST_ASSERT_EQUAL_INT32(
            (int32_t)delta, odo_count_delta(ts_wrap_counter(start, bits), ts_wrap_counter(start + delta, bits), bits));
    }
}

/// A robot with 8- or 12-bit decoders drives forward and then back across many counter wraps:
/// the distance is the counts times cm, and it comes back to the origin exactly.
static void narrow_counters_wrap_both_ways_without_losing_counts(void)
{
    static const struct {
        uint8_t bits;
        uint32_t counts_milli; /* coarse enough that 3 m/s stays below half the counter range */
        int32_t per_tick;
    } cases[] = {{8U, 100000U, 25}, {12U, 2000000U, 500}, {12U, 2000000U, 17}, {9U, 200000U, 50}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        odo_truck_params_t tp = labmate();
        tp.counts_per_rev_milli = cases[i].counts_milli;
        const uint8_t bits = cases[i].bits;
        const odo_model_t m = model_of(&tp, bits, ODO_HEADING_MIDPOINT);
        TEST_ASSERT_TRUE(m.max_counts < (1U << (bits - 1U)));
        const uint32_t start = (1U << bits) - 7U; /* just below the wrap */
        odo_truck_t t = truck_at_origin(&m, start, start, bits);
        odo_step_t st;
        int64_t c = start;
        int wraps = 0;
        for (int k = 0; k < 400; ++k) { /* forward: up through the wrap, many times */
            c += cases[i].per_tick;
            odo_truck_step(&t, &m, ts_wrap_counter(c, bits), ts_wrap_counter(c, bits), bits, 1U, &st);
            TEST_ASSERT_FALSE(st.jump);
            TEST_ASSERT_EQUAL_INT32(cases[i].per_tick, st.delta[0]);
            wraps += (ts_wrap_counter(c, bits) < ts_wrap_counter(c - cases[i].per_tick, bits)) ? 1 : 0;
        }
        TEST_ASSERT_TRUE(wraps >= 2);
        TEST_ASSERT_DOUBLE_WITHIN(1e-6, 400.0 * cases[i].per_tick * cm_mm(&tp), MM_Q32(t.pose.x_mm_q32));
        for (int k = 0; k < 400; ++k) { /* and back down through it */
            c -= cases[i].per_tick;
            odo_truck_step(&t, &m, ts_wrap_counter(c, bits), ts_wrap_counter(c, bits), bits, 1U, &st);
            TEST_ASSERT_FALSE(st.jump);
            TEST_ASSERT_EQUAL_INT32(-cases[i].per_tick, st.delta[1]);
        }
        TEST_ASSERT_INT64_WITHIN(2, 0, t.pose.x_mm_q32);
        TEST_ASSERT_EQUAL_UINT64(0U, t.pose.heading_q64);
    }
    /* model widths: 8..32 only */
    odo_truck_params_t tp = labmate();
    tp.counts_per_rev_milli = 100000U;
    odo_model_t m;
    TEST_ASSERT_EQUAL(ODO_MODEL_ERR_RANGE, odo_model_init(&m, &tp, 7U, 0U, 40000U, 3000U));
    TEST_ASSERT_EQUAL(ODO_MODEL_OK, odo_model_init(&m, &tp, 8U, 0U, 40000U, 3000U));
    TEST_ASSERT_EQUAL(ODO_MODEL_ERR_RANGE, odo_model_init(&m, &tp, 33U, 0U, 40000U, 3000U));
    /* the default 39000-count labmate moves ~9900 counts per tick at 3 m/s: too many for 12 bits */
    tp = labmate();
    TEST_ASSERT_EQUAL(ODO_MODEL_ERR_RANGE, odo_model_init(&m, &tp, 12U, 0U, 40000U, 3000U));
    tp.scrub_q30 = (int32_t)(1 << 28) + 1; /* |k| > 1/4 */
    TEST_ASSERT_EQUAL(ODO_MODEL_ERR_RANGE, odo_model_init(&m, &tp, 24U, 0U, 40000U, 3000U));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(multipliers_follow_eqs_2_1_6_33_6_34_and_6_28);
    RUN_TEST(count_delta_handles_every_wrap_of_16_24_32_bit_counters);
    RUN_TEST(straight_line_keeps_heading_and_lateral_position_exact);
    RUN_TEST(on_the_spot_turn_changes_heading_not_position);
    RUN_TEST(midpoint_form_is_far_more_accurate_than_eq_2_6_on_arcs);
    RUN_TEST(unequal_wheels_are_corrected_per_eq_6_35);
    RUN_TEST(implausible_counter_jump_is_flagged_not_integrated);
    RUN_TEST(inverted_encoders_count_forward);
    RUN_TEST(parameters_that_cannot_be_represented_are_refused);
    RUN_TEST(the_plausibility_limit_scales_with_the_ticks_elapsed);
    RUN_TEST(a_multi_tick_step_follows_the_arc);
    RUN_TEST(a_step_too_large_to_integrate_is_flagged);
    RUN_TEST(a_pose_beyond_the_limit_is_held);
    RUN_TEST(spot_turn_is_unchanged_by_scrub);
    RUN_TEST(arc_of_known_radius_gets_the_predicted_factor);
    RUN_TEST(zero_scrub_is_bit_identical_to_plain_eq_2_4);
    RUN_TEST(scrub_factor_error_is_below_2e_minus_32_on_random_ticks);
    RUN_TEST(count_delta_handles_8_and_12_bit_counters);
    RUN_TEST(narrow_counters_wrap_both_ways_without_losing_counts);
    return UNITY_END();
}
