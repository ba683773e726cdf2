/// Property test (issue: foundation, item 9): the fixed-point odometry against a double-precision
/// reference of 000 Eqs. 2.1-2.6 fed identical counts, over random mixed paths of 1 km each
/// (straights, arcs, on-the-spot turns, stops, both directions), with 16, 24 and 32-bit counters
/// crossing their wrap, both heading forms, and random UMBmark calibrations.
/// Requirement (DESIGN.md s. 3): <= 0.1 mm and <= 1e-6 rad after 1 km.
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
    printf("fixed vs double after 1 km: worst position %.3g mm, worst heading %.3g rad, %u wraps\n",
           worst_pos, worst_head, total_wraps);
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
    suite_add_tcase(s, tc);
    return ts_run_suite(s);
}
