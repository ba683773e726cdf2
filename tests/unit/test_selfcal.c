/// Self-calibration from IPEC's corrections (odo_selfcal.h, 004 s. 5.1). The tick data is
/// synthesised here from the wheel model of 000 Eqs. 2.7-2.8 with known true Ed and Eb, so the
/// expected values are the ones put in, not the estimator's output.
#include <math.h>
#include <string.h>

#include "odo/odo_selfcal.h"
#include "unity.h"

void setUp(void) {}
void tearDown(void) {}

#define TWO30       1073741824.0
#define BAM_PER_RAD (4294967296.0 / (2.0 * M_PI))

typedef struct {
    double ed_t, eb_t; ///< the truth
    double ed_f, eb_f; ///< what the firmware uses
    double b_mm;       ///< nominal wheelbase
} truck_t;

/// Wheel factors of 000 Eq. 2.7 solved for the wheels (mean scale 1): cL = 2/(Ed+1), cR = Ed cL.
static void factors(double ed, double *cl, double *cr)
{
    *cl = 2.0 / (ed + 1.0);
    *cr = ed * *cl;
}

/// One tick of true wheel travel (dl, dr mm): what the firmware dead-reckons and IPEC corrects.
static void tick(odo_selfcal_t *s, uint8_t idx, const truck_t *t, double dl, double dr)
{
    double cl_t, cr_t, cl_f, cr_f;
    factors(t->ed_t, &cl_t, &cr_t);
    factors(t->ed_f, &cl_f, &cr_f);
    /* Wheel travel true = c_t n; the firmware computes c_f n = c_f / c_t x true. */
    const double fl = dl * cl_f / cl_t, fr = dr * cr_f / cr_t;
    const double b_t = t->b_mm * t->eb_t, b_f = t->b_mm * t->eb_f;
    const double u_f = (fl + fr) / 2.0, turn_f = (fr - fl) / b_f, turn_t = (dr - dl) / b_t;
    const double corr = turn_t - turn_f; /* IPEC restores the true heading */
    const int64_t u_q40 = (int64_t)llround(u_f * 1099511627776.0);
    const int64_t t_q64 = (int64_t)llround(turn_f * BAM_PER_RAD) * 4294967296LL;
    odo_selfcal_add(s, idx, (uint32_t)llround(b_f * 1e6), 10U, u_q40, t_q64, (int32_t)llround(corr * BAM_PER_RAD));
}

static odo_params_t params_for(const truck_t *t)
{
    odo_params_t p;
    odo_params_defaults(&p);
    p.vehicle = (uint8_t)ODO_VEHICLE_CLAPPER;
    p.truck[1] = p.truck[0];
    for (int i = 0; i < 2; ++i) {
        p.truck[i].wheelbase_nm = (uint32_t)llround(t[i].b_mm * 1e6);
        p.truck[i].ed_q30 = (int32_t)llround(t[i].ed_f * TWO30);
        p.truck[i].eb_q30 = (int32_t)llround(t[i].eb_f * TWO30);
    }
    return p;
}

/// A UMBmark-like program per truck: 4 m straight forward, a 90 deg spin, 4 m backward, a -90 deg
/// spin, and a 90 deg arc of radius 500 mm; n times.
static void drive(odo_selfcal_t *s, const truck_t *t, int n)
{
    for (int rep = 0; rep < n; ++rep) {
        for (uint8_t i = 0; i < 2; ++i) {
            const double b = t[i].b_mm * t[i].eb_t;
            for (int k = 0; k < 250; ++k) {
                tick(s, i, &t[i], 16.0, 16.0);
            }
            for (int k = 0; k < 45; ++k) { /* 2 deg per tick on the spot */
                const double d = b / 2.0 * (2.0 * M_PI / 180.0);
                tick(s, i, &t[i], -d, d);
            }
            for (int k = 0; k < 250; ++k) {
                tick(s, i, &t[i], -16.0, -16.0);
            }
            for (int k = 0; k < 45; ++k) {
                const double d = b / 2.0 * (2.0 * M_PI / 180.0);
                tick(s, i, &t[i], d, -d);
            }
            for (int k = 0; k < 45; ++k) { /* arc: centre travel 500 mm x 2 deg per tick */
                const double a = 2.0 * M_PI / 180.0;
                tick(s, i, &t[i], (500.0 - b / 2.0) * a, (500.0 + b / 2.0) * a);
            }
        }
    }
}

static void recovers_ed_and_eb_of_both_trucks(void)
{
    const truck_t t[2] = {{0.9985, 0.99118, 1.0, 1.0, 340.0}, {1.002, 1.006, 1.0, 1.0, 340.0}};
    odo_selfcal_t s;
    odo_selfcal_init(&s);
    drive(&s, t, 4);
    const odo_params_t in = params_for(t);
    odo_params_t out;
    odo_selfcal_result_t r;
    TEST_ASSERT_TRUE(odo_selfcal_estimate(&s, &in, &out, &r));
    for (int i = 0; i < 2; ++i) {
        TEST_ASSERT_TRUE(r.have_ed[i] && r.have_eb[i]);
        /* First order in k (the header): |k| = 0.2 % leaves < 1e-5. */
        TEST_ASSERT_DOUBLE_WITHIN(2e-5, t[i].ed_t, out.truck[i].ed_q30 / TWO30);
        TEST_ASSERT_DOUBLE_WITHIN(2e-5, t[i].eb_t, out.truck[i].eb_q30 / TWO30);
        TEST_ASSERT_EQUAL_UINT32(in.truck[i].wheelbase_nm, out.truck[i].wheelbase_nm);
    }
}

static void a_calibrated_firmware_estimates_no_change(void)
{
    /* Start from a firmware already carrying the truth: the estimate must stay put, and an
     * estimate from a partly calibrated one must land on the truth too (Ed_f, Eb_f != 1). */
    const truck_t t[2] = {{0.9985, 0.99118, 0.9985, 0.99118, 340.0}, {1.002, 1.006, 1.001, 1.0, 340.0}};
    odo_selfcal_t s;
    odo_selfcal_init(&s);
    drive(&s, t, 2);
    const odo_params_t in = params_for(t);
    odo_params_t out;
    TEST_ASSERT_TRUE(odo_selfcal_estimate(&s, &in, &out, NULL));
    TEST_ASSERT_DOUBLE_WITHIN(2e-6, 0.9985, out.truck[0].ed_q30 / TWO30);
    TEST_ASSERT_DOUBLE_WITHIN(2e-6, 0.99118, out.truck[0].eb_q30 / TWO30);
    TEST_ASSERT_DOUBLE_WITHIN(2e-5, 1.002, out.truck[1].ed_q30 / TWO30);
    TEST_ASSERT_DOUBLE_WITHIN(2e-5, 1.006, out.truck[1].eb_q30 / TWO30);
}

static void bumps_and_the_quantisation_limit_cycle_are_left_out(void)
{
    const truck_t t[2] = {{0.9985, 0.99118, 1.0, 1.0, 340.0}, {0.9985, 0.99118, 1.0, 1.0, 340.0}};
    odo_selfcal_t s, ref;
    odo_selfcal_init(&s);
    drive(&s, t, 2);
    ref = s;
    /* A bump: 0.8 deg in one straight tick (more than two 10-bit steps). */
    odo_selfcal_add(&s, 0, 340000000U, 10U, 16LL << 40, 0, (int32_t)llround(0.8 / 360.0 * 4294967296.0));
    /* The limit cycle: a stopped truck dithering by half a step, the correction undoing it. */
    const int64_t half = (int64_t)1 << 21;
    for (int k = 0; k < 100; ++k) {
        const int64_t tt = (k % 2) ? half : -half;
        odo_selfcal_add(&s, 0, 340000000U, 10U, 0, tt * 4294967296LL, (int32_t)-tt);
    }
    TEST_ASSERT_EQUAL_MEMORY(&ref.truck[0].straight_corr, &s.truck[0].straight_corr, sizeof(int64_t));
    TEST_ASSERT_EQUAL_INT64(ref.truck[0].turn_corr, s.truck[0].turn_corr);
    TEST_ASSERT_EQUAL_INT64(ref.truck[0].turn_bam, s.truck[0].turn_bam);
    TEST_ASSERT_EQUAL_UINT32(ref.truck[0].skipped_ticks + 101U, s.truck[0].skipped_ticks);
}

static void too_little_data_estimates_nothing(void)
{
    const truck_t t[2] = {{0.9985, 0.99118, 1.0, 1.0, 340.0}, {0.9985, 0.99118, 1.0, 1.0, 340.0}};
    odo_selfcal_t s;
    odo_selfcal_init(&s);
    for (int k = 0; k < 100; ++k) { /* 1.6 m straight, no turning */
        tick(&s, 0, &t[0], 16.0, 16.0);
    }
    const odo_params_t in = params_for(t);
    odo_params_t out;
    odo_selfcal_result_t r;
    TEST_ASSERT_FALSE(odo_selfcal_estimate(&s, &in, &out, &r));
    TEST_ASSERT_FALSE(r.have_ed[0] || r.have_eb[0] || r.have_ed[1] || r.have_eb[1]);
    TEST_ASSERT_EQUAL_MEMORY(&in, &out, sizeof in);
    /* An out-of-range truck index is ignored, not a crash. */
    odo_selfcal_add(&s, 7U, 340000000U, 10U, 1, 1, 1);
}

static void an_absurd_correction_rate_is_clamped_and_stays_valid(void)
{
    const truck_t t[2] = {{1.0, 0.99118, 1.0, 1.0, 340.0}, {1.0, 1.0, 1.0, 1.0, 340.0}};
    odo_selfcal_t s;
    odo_selfcal_init(&s);
    for (int k = 0; k < 300; ++k) { /* a "straight" that IPEC turns 0.6 deg per 16 mm: a fault */
        odo_selfcal_add(&s, 0, 340000000U, 10U, 16LL << 40, 0, (int32_t)llround(-0.6 / 360.0 * 4294967296.0));
    }
    const odo_params_t in = params_for(t);
    odo_params_t out;
    odo_selfcal_result_t r;
    (void)odo_selfcal_estimate(&s, &in, &out, &r);
    TEST_ASSERT_EQUAL_INT32(1 << 27, r.k_q30[0] < 0 ? -r.k_q30[0] : r.k_q30[0]);
    TEST_ASSERT_EQUAL_INT(ODO_PARAMS_OK, odo_params_validate(&out, NULL, NULL));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(recovers_ed_and_eb_of_both_trucks);
    RUN_TEST(a_calibrated_firmware_estimates_no_change);
    RUN_TEST(bumps_and_the_quantisation_limit_cycle_are_left_out);
    RUN_TEST(too_little_data_estimates_nothing);
    RUN_TEST(an_absurd_correction_rate_is_clamped_and_stays_valid);
    return UNITY_END();
}
