/// Property test (issue: foundation, item 9): the fixed-point odometry against a double-precision
/// reference of 000 Eqs. 2.1-2.6 fed identical counts, over random mixed paths of 1 km each
/// (straights, arcs, on-the-spot turns, stops, both directions), with 16, 24 and 32-bit counters
/// crossing their wrap, both heading forms, and random UMBmark calibrations.
/// Requirement (DESIGN.md s. 3): <= 0.1 mm and <= 1e-6 rad after 1 km, also with the tyre-scrub
/// term on (odo_odometry.h; k = +-0.01 and +-0.2, and the OptiOdom robot's +0.0095) and with the
/// narrow counters real decoders have (8, 12 bits).
#include <check.h>

#include <math.h>
#include <stdio.h>

#include "check_support.h"
#include "odo/odo_params.h"
#include "odo_refcheck.h"
#include "test_support.h"

static odo_truck_params_t random_truck(ts_rng_t *rng)
{
    odo_params_t p;
    odo_params_defaults(&p);
    odo_truck_params_t tp = p.truck[0];
    tp.wheel_diameter_nm = (uint32_t)ts_rng_range(rng, 60000000, 300000000);
    tp.counts_per_rev_milli = (uint32_t)ts_rng_range(rng, 2000000, 200000000);
    tp.wheelbase_nm = (uint32_t)ts_rng_range(rng, 150000000, 900000000);
    tp.ed_q30 = (int32_t)llround(ts_rng_uniform(rng, 0.99, 1.01) * 1073741824.0);
    tp.eb_q30 = (int32_t)llround(ts_rng_uniform(rng, 0.95, 1.05) * 1073741824.0);
    tp.es_q30 = (int32_t)llround(ts_rng_uniform(rng, 0.98, 1.02) * 1073741824.0);
    return tp;
}

START_TEST(fixed_point_pose_matches_double_reference_after_1km)
{
    const uint8_t widths[] = {16U, 24U, 32U};
    ts_rng_t rng;
    ts_rng_seed(&rng, 2026U);
    double worst_pos = 0.0, worst_head = 0.0;
    uint32_t total_wraps = 0U;
    for (int run = 0; run < 12; ++run) {
        const uint8_t bits = widths[run % 3];
        const uint8_t form = (uint8_t)((run / 3) % 2);
        odo_truck_params_t tp = random_truck(&rng);
        if (bits == 16U) {
            tp.counts_per_rev_milli = 8000000U; /* keep 3 m/s within half a 16-bit range */
        }
        odo_refcheck_t r;
        ck_assert_int_eq(0, odo_refcheck_run(ts_rng_u64(&rng), bits, form, &tp, &tp, 1.0e6, &r));
        ck_assert(r.distance_mm >= 1.0e6);
        total_wraps += r.wraps;
        if (r.pos_err_mm > worst_pos) {
            worst_pos = r.pos_err_mm;
        }
        if (r.heading_err_rad > worst_head) {
            worst_head = r.heading_err_rad;
        }
        ck_assert_msg(r.pos_err_mm <= 0.1, "run %d (%u-bit, form %u): %.3g mm", run, bits, form, r.pos_err_mm);
        ck_assert_msg(r.heading_err_rad <= 1e-6, "run %d: %.3g rad", run, r.heading_err_rad);
    }
    ck_assert_msg(total_wraps > 12U, "the paths must cross counter wraps (%u)", total_wraps);
    printf("fixed vs double after 1 km: worst position %.3g mm, worst heading %.3g rad, %u wraps\n", worst_pos,
           worst_head, total_wraps);
}
END_TEST

/// Worst of `runs` 1 km runs of random trucks with scrub k (Q30), counters `bits` wide, both heading
/// forms; asserts the requirement on each.
static void scrub_runs(ts_rng_t *rng, int32_t k_q30, uint8_t bits, uint32_t counts_milli, int runs, double *worst_pos,
                       double *worst_head, uint32_t *wraps)
{
    for (int run = 0; run < runs; ++run) {
        odo_truck_params_t tp = random_truck(rng);
        tp.scrub_q30 = k_q30;
        if (counts_milli != 0U) {
            tp.counts_per_rev_milli = counts_milli; /* coarse enough for the counter width */
        }
        const uint8_t form = (uint8_t)(run % 2);
        odo_refcheck_t r;
        ck_assert_int_eq(0, odo_refcheck_run(ts_rng_u64(rng), bits, form, &tp, &tp, 1.0e6, &r));
        ck_assert(r.distance_mm >= 1.0e6);
        *wraps += r.wraps;
        *worst_pos = fmax(*worst_pos, r.pos_err_mm);
        *worst_head = fmax(*worst_head, r.heading_err_rad);
        ck_assert_msg(r.pos_err_mm <= 0.1, "k %d, %u-bit, form %u: %.3g mm", k_q30, bits, form, r.pos_err_mm);
        ck_assert_msg(r.heading_err_rad <= 1e-6, "k %d, %u-bit, form %u: %.3g rad", k_q30, bits, form,
                      r.heading_err_rad);
    }
}

START_TEST(fixed_point_pose_matches_double_reference_with_scrub_after_1km)
{
    static const double ks[] = {0.01, -0.01, 0.2, -0.2, 0.0095, 0.25, -0.25};
    ts_rng_t rng;
    ts_rng_seed(&rng, 2027U);
    double worst_pos = 0.0, worst_head = 0.0;
    uint32_t wraps = 0U;
    for (size_t i = 0; i < sizeof ks / sizeof ks[0]; ++i) {
        const int32_t k = (int32_t)llround(ks[i] * 1073741824.0);
        scrub_runs(&rng, k, i % 2 ? 32U : 24U, 0U, 2, &worst_pos, &worst_head, &wraps);
    }
    printf("fixed vs double after 1 km with scrub k in [-0.25, 0.25]: worst position %.3g mm, worst heading "
           "%.3g rad\n",
           worst_pos, worst_head);
}
END_TEST

START_TEST(fixed_point_pose_matches_double_reference_with_8_and_12_bit_counters)
{
    /* 3 m/s for 40 ms is 120 mm: at most 127 counts for 8 bits, 2047 for 12. */
    ts_rng_t rng;
    ts_rng_seed(&rng, 12U);
    double worst_pos = 0.0, worst_head = 0.0;
    uint32_t wraps = 0U;
    scrub_runs(&rng, 0, 8U, 60000U, 2, &worst_pos, &worst_head, &wraps);
    scrub_runs(&rng, (int32_t)llround(0.0095 * 1073741824.0), 12U, 2000000U, 2, &worst_pos, &worst_head, &wraps);
    ck_assert_msg(wraps > 1000U, "narrow counters must wrap often (%u)", wraps);
    printf("fixed vs double after 1 km, 8/12-bit counters: worst position %.3g mm, worst heading %.3g rad, "
           "%u wraps\n",
           worst_pos, worst_head, wraps);
}
END_TEST

START_TEST(comparison_detects_a_scrub_mismatch)
{
    /* The reference must see the term: a k that differs by 1e-4 (or is missing) drifts past the
     * heading bar over 1 km of the same counts. */
    odo_params_t p;
    odo_params_defaults(&p);
    odo_truck_params_t fw = p.truck[0], ref = p.truck[0];
    fw.scrub_q30 = (int32_t)llround(0.0095 * 1073741824.0);
    ref.scrub_q30 = fw.scrub_q30 + 107374; /* +1e-4 */
    odo_refcheck_t r;
    ck_assert_int_eq(0, odo_refcheck_run(7U, 24U, 0U, &fw, &ref, 1.0e6, &r));
    ck_assert_msg(r.heading_err_rad > 1e-6 || r.max_pos_err_mm > 0.1, "mismatch went unseen: %.3g rad, %.3g mm",
                  r.heading_err_rad, r.max_pos_err_mm);
    ref.scrub_q30 = 0;
    ck_assert_int_eq(0, odo_refcheck_run(7U, 24U, 0U, &fw, &ref, 1.0e6, &r));
    ck_assert_msg(r.max_pos_err_mm > 0.1, "a missing term went unseen: %.3g mm", r.max_pos_err_mm);
}
END_TEST

START_TEST(comparison_detects_a_1e6_calibration_mismatch)
{
    /* The check must be able to fail: a reference whose Ed differs by 1e-6 drifts well past
     * the 0.1 mm bar over 1 km of the same counts. */
    odo_params_t p;
    odo_params_defaults(&p);
    odo_truck_params_t ref = p.truck[0];
    ref.ed_q30 += 1074; /* +1e-6 */
    odo_refcheck_t r;
    ck_assert_int_eq(0, odo_refcheck_run(7U, 24U, 0U, &p.truck[0], &ref, 1.0e6, &r));
    ck_assert_msg(r.max_pos_err_mm > 0.1, "mismatch went unseen: %.3g mm", r.max_pos_err_mm);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("odometry_reference");
    TCase *tc = tcase_create("core");
    tcase_set_timeout(tc, 300);
    tcase_add_test(tc, fixed_point_pose_matches_double_reference_after_1km);
    tcase_add_test(tc, comparison_detects_a_1e6_calibration_mismatch);
    tcase_add_test(tc, fixed_point_pose_matches_double_reference_with_scrub_after_1km);
    tcase_add_test(tc, fixed_point_pose_matches_double_reference_with_8_and_12_bit_counters);
    tcase_add_test(tc, comparison_detects_a_scrub_mismatch);
    suite_add_tcase(s, tc);
    return ts_run_suite(s);
}
