/// IPEC (002_97a419d21cabf785.txt Eqs. 9-16): link convention, corrections, re-anchoring, the
/// encoder trailer, the estimator, and the fault gating of linkage frames in the app step.
#include <math.h>
#include <string.h>

#include "odo/odo_app.h"
#include "odo/odo_can.h"
#include "odo/odo_fx.h"
#include "odo/odo_ipec.h"
#include "unity.h"

void setUp(void) {}
void tearDown(void) {}

#define Q32         4294967296.0
#define BAM_PER_DEG (4294967296.0 / 360.0)

static odo_pose_t pose_at(double x_mm, double y_mm, double theta_deg)
{
    odo_pose_t p;
    p.x_mm_q32 = (int64_t)llround(x_mm * Q32);
    p.y_mm_q32 = (int64_t)llround(y_mm * Q32);
    p.heading_q64 = (uint64_t)(int64_t)llround(theta_deg * BAM_PER_DEG) << 32;
    return p;
}

static double deg_of(uint32_t bam) { return (double)(int32_t)bam / BAM_PER_DEG; }
static double heading_deg(const odo_pose_t *p) { return deg_of(odo_heading_bam(p)); }
static double mm(int64_t q32) { return (double)q32 / Q32; }

static odo_params_t clapper_params(uint8_t mode)
{
    odo_params_t p;
    odo_params_defaults(&p);
    p.vehicle = (uint8_t)ODO_VEHICLE_CLAPPER;
    p.ipec_mode = mode;
    p.truck[1] = p.truck[0];
    return p;
}

/// 002 Eq. 10 read with atan2 from B to A is the reading for which Eq. 16 puts B l behind A.
static void eq10_from_b_to_a_makes_eq16_put_b_l_behind_a(void)
{
    const double cases[][4] = {{0, 0, 0, 0}, {100, -50, 135, 20}, {-3000, 700, -100, -15}, {5, 5, 179, 3}};
    for (unsigned i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        const double th = cases[i][2] * M_PI / 180.0;
        const odo_pose_t a = pose_at(cases[i][0], cases[i][1], cases[i][2]);
        const odo_pose_t b = pose_at(cases[i][0] - 1000.0 * cos(th), cases[i][1] - 1000.0 * sin(th), 0);
        const uint32_t tl = odo_ipec_link_heading_bam(&a, &b);
        TEST_ASSERT_FLOAT_WITHIN(1e-5, cases[i][2],
                                 deg_of(tl - (uint32_t)llround(0.0)) - (cases[i][2] > 180.0 ? 360.0 : 0.0));
        odo_pose_t b2 = a;
        odo_ipec_anchor(&a, tl, odo_ipec_nm_to_mm_q32(1000000000LL), &b2);
        TEST_ASSERT_FLOAT_WITHIN(1e-4, mm(b.x_mm_q32), mm(b2.x_mm_q32));
        TEST_ASSERT_FLOAT_WITHIN(1e-4, mm(b.y_mm_q32), mm(b2.y_mm_q32));
    }
}

/// 002 Eqs. 11-13: a dead-reckoning heading error of A (a bump) is corrected in the same tick to
/// theta_L + alpha_act; B is re-anchored l behind A along theta_L (Eq. 16) with the measured l.
static void paper_form_corrects_a_heading_error_within_the_tick(void)
{
    const odo_params_t p = clapper_params((uint8_t)ODO_IPEC_PAPER);
    odo_pose_t pose[2] = {pose_at(2000, 0, 0.6), pose_at(1000, 0, 0)};
    /* Truth: both trucks along the link (alpha = beta = 0); the encoders' code 0 is [0, 0.35) deg. */
    const int32_t half = (int32_t)(1UL << 21); /* half a 10-bit step */
    const odo_ipec_reading_t rd = {half, half, odo_ipec_nm_to_mm_q32(1000200000LL)};
    odo_ipec_result_t r;
    odo_ipec_step(&p, &rd, pose, 0, &r);
    TEST_ASSERT_FLOAT_WITHIN(1e-6, 0.0, deg_of(r.theta_l_bam));
    TEST_ASSERT_FLOAT_WITHIN(1e-5, -0.6 + deg_of((uint32_t)half), deg_of((uint32_t)r.dtheta_bam[0]));
    TEST_ASSERT_FLOAT_WITHIN(1e-5, deg_of((uint32_t)half), heading_deg(&pose[0]));
    TEST_ASSERT_FLOAT_WITHIN(1e-5, deg_of((uint32_t)half), heading_deg(&pose[1]));
    TEST_ASSERT_FLOAT_WITHIN(1e-4, 2000.0 - 1000.2, mm(pose[1].x_mm_q32)); /* measured l */
    TEST_ASSERT_FLOAT_WITHIN(1e-4, 0.0, mm(pose[1].y_mm_q32));
}

/// 002 Eqs. 14-15 generalised: the centre moves by b |sin(dtheta/2)| against the direction of
/// travel, whichever wheel lagged (sign of the correction) and whichever way the truck drove.
static void translational_correction_is_against_travel_for_either_wheel_and_sign(void)
{
    const uint32_t b_nm = 340000000U;
    const double d = 0.6, expect = 340.0 * sin(d / 2.0 * M_PI / 180.0);
    const int signs[2] = {-1, 1};
    for (unsigned i = 0; i < 2; ++i) {
        for (unsigned k = 0; k < 2; ++k) {
            odo_pose_t p = pose_at(0, 0, 30);
            const int32_t dth = (int32_t)llround(signs[i] * d * BAM_PER_DEG);
            const int64_t dist = signs[k] * ((int64_t)1 << 40); /* 1 mm forward or backward */
            odo_ipec_translate(&p, dth, dist, b_nm, NULL, NULL);
            const double along = mm(p.x_mm_q32) * cos(M_PI / 6) + mm(p.y_mm_q32) * sin(M_PI / 6);
            TEST_ASSERT_FLOAT_WITHIN(1e-3, -signs[k] * expect, along);
        }
    }
    odo_pose_t still = pose_at(1, 2, 3);
    odo_ipec_translate(&still, 100000, 0, b_nm, NULL, NULL); /* turning on the spot: no shift */
    TEST_ASSERT_EQUAL_INT64(pose_at(1, 2, 3).x_mm_q32, still.x_mm_q32);
}

/// 002 Eq. 14's chord b |sin(dtheta/2)| within 4e-9 b of the double value over corrections from
/// one BAM to half a turn either way (a small-angle series below 5.6 deg, the sine table above;
/// the bound adds the Q30 sin/cos of the shift's direction and the nm conversion): the length
/// of the shift is the chord.
static void translational_correction_chord_matches_the_sine_over_every_correction_size(void)
{
    const uint32_t b_nm = 1000000000U; /* 1 m: the shift in mm is 1000 |sin(dtheta/2)| */
    double worst = 0.0;
    for (uint32_t k = 0U; k < 4096U; ++k) {
        /* geometric sweep from 1 BAM to 2^31 - 1, both signs, the series' edge 2^27 included */
        const double t = (double)k / 4095.0;
        int64_t mag = llround(pow(2.0, 31.0 * t));
        mag = mag > INT32_MAX ? INT32_MAX : mag;
        const int32_t dth[3] = {(int32_t)mag, (int32_t)-mag, (int32_t)(((uint32_t)1U << 27) - 2U + (k & 3U))};
        for (unsigned j = 0U; j < 3U; ++j) {
            odo_pose_t p = pose_at(0, 0, 0);
            int64_t dx = 0, dy = 0;
            odo_ipec_translate(&p, dth[j], (int64_t)1 << 40, b_nm, &dx, &dy);
            const double half_rad = (double)(dth[j] / 2) * (2.0 * M_PI / 4294967296.0);
            const double err = fabs(hypot(mm(dx), mm(dy)) - 1000.0 * fabs(sin(half_rad))) / 1000.0;
            worst = err > worst ? err : worst;
        }
    }
    TEST_ASSERT_TRUE(worst < 4e-9);
}

/// The estimator: beyond half a rotary step the correction is immediate (bumps); within it only
/// 2^-ODO_IPEC_EST_PULL_SHIFT per tick. PAPER passes everything; OFF nothing.
static void estimator_keeps_bumps_immediate_and_filters_within_a_step(void)
{
    const int32_t h = (int32_t)(1UL << 21);
    TEST_ASSERT_EQUAL_INT32(12345, odo_ipec_gain((uint8_t)ODO_IPEC_PAPER, 12345, 10U));
    TEST_ASSERT_EQUAL_INT32(0, odo_ipec_gain((uint8_t)ODO_IPEC_OFF, 12345, 10U));
    TEST_ASSERT_EQUAL_INT32(h / (1 << ODO_IPEC_EST_PULL_SHIFT), odo_ipec_gain((uint8_t)ODO_IPEC_ESTIMATOR, h, 10U));
    const int32_t bump = (int32_t)llround(-0.6 * BAM_PER_DEG);
    TEST_ASSERT_EQUAL_INT32(bump + h - h / (1 << ODO_IPEC_EST_PULL_SHIFT),
                            odo_ipec_gain((uint8_t)ODO_IPEC_ESTIMATOR, bump, 10U));
}

/// The encoder trailer: turning the robot swings the bar about the trailer axle, so the joint
/// angle moves by d (1 + hitch/L); the correction divides that out and lands exactly. The axle
/// keeps its place, its heading becomes the bar's.
static void set_trailer_correction_accounts_for_the_hitch_lever(void)
{
    odo_params_t p = clapper_params((uint8_t)ODO_IPEC_PAPER);
    p.vehicle = (uint8_t)ODO_VEHICLE_SET;
    p.link.hitch_offset_nm = 300000000U;
    p.link.length_nm = 500000000U;
    /* Truth: robot heading -0.6 deg (bumped), hitch 300 mm behind, axle 500 mm behind the hitch
     * at its old place (0 deg bar): solve the true joint angle. */
    const double th = -0.6 * M_PI / 180.0;
    const double hx = 1000.0 - 300.0 * cos(th), hy = -300.0 * sin(th);
    const double ax = 1000.0 - 300.0 - 500.0, ay = 0.0;
    const double bar = atan2(hy - ay, hx - ax);
    const double alpha = (th - bar) * 180.0 / M_PI;
    odo_pose_t pose[2] = {pose_at(1000, 0, 0), pose_at(ax, ay, 0)};
    const odo_ipec_reading_t rd = {(int32_t)llround(alpha * BAM_PER_DEG), 0, odo_ipec_nm_to_mm_q32(500000000LL)};
    odo_ipec_result_t r;
    odo_ipec_step(&p, &rd, pose, 0, &r);
    TEST_ASSERT_FLOAT_WITHIN(2e-3, -0.6, heading_deg(&pose[0]));
    TEST_ASSERT_FLOAT_WITHIN(2e-3, bar * 180.0 / M_PI, heading_deg(&pose[1]));
    const double l = hypot(mm(pose[1].x_mm_q32) - hx, mm(pose[1].y_mm_q32) - hy);
    TEST_ASSERT_FLOAT_WITHIN(1e-2, 500.0, l);
}

/* ---------------------------------------------------------------------------------------------
 * Fault gating in the app step (002 s. 4 needs fresh, plausible linkage readings)
 * ------------------------------------------------------------------------------------------- */
static odo_app_t app;
static odo_tick_output_t out;

static void boot(uint8_t mode)
{
    const odo_params_t p = clapper_params(mode);
    TEST_ASSERT_EQUAL(ODO_PARAMS_OK, odo_app_init_params(&app, &p));
}

/// A tick of straight driving (both trucks 1000 counts per tick) with a good linkage sample.
static odo_tick_input_t good(uint8_t k)
{
    odo_tick_input_t in;
    memset(&in, 0, sizeof in);
    in.t_us = 40000ULL * k;
    for (unsigned t = 0; t < 2U; ++t) {
        in.wheel[t].present = true;
        in.wheel[t].bits = 24U;
        in.wheel[t].seq = k;
        in.wheel[t].left_raw = 1000U * k;
        in.wheel[t].right_raw = 1000U * k + (t == 0U ? 300U * k : 0U); /* A drifts left in DR */
    }
    in.link.rotary_present = in.link.linear_present = true;
    in.link.rotary_seq = in.link.linear_seq = k;
    in.link.rotary_status = ODO_LINK_STATUS_ALPHA_VALID | ODO_LINK_STATUS_BETA_VALID;
    in.link.linear_status = ODO_LINK_STATUS_LENGTH_VALID;
    in.link.length_um = 1000000U;
    return in;
}

static void run_good(uint8_t n)
{
    for (uint8_t k = 0U; k < n; ++k) {
        odo_tick_input_t in = good(k);
        odo_app_step(&app, &in, &out);
        TEST_ASSERT_EQUAL_UINT32(0U, out.faults);
    }
}

/// The tick is dead reckoning only: no correction, A still advances, the fault and the gate flag
/// are raised in STATUS and both POSE_THETA frames.
static void assert_gated(const odo_tick_input_t *in, uint32_t fault)
{
    const int64_t x0 = app.truck[0].pose.x_mm_q32;
    odo_app_step(&app, in, &out);
    TEST_ASSERT_NOT_EQUAL(0U, out.faults & fault);
    TEST_ASSERT_NOT_EQUAL(0U, out.faults & ODO_FAULT_IPEC_GATED);
    TEST_ASSERT_FALSE(out.ipec_applied);
    TEST_ASSERT_EQUAL_INT32(0, out.ipec_dtheta_bam[0]);
    TEST_ASSERT_TRUE(out.pose[0].x_mm_q32 > x0);
    odo_msg_pose_theta_t th;
    uint8_t truck = 0U;
    TEST_ASSERT_EQUAL(ODO_CAN_OK, odo_can_unpack_pose_theta(&out.frames[1], &truck, &th));
    TEST_ASSERT_NOT_EQUAL(0U, th.flags & ODO_POSE_FLAG_IPEC_GATED);
    odo_msg_status_t st;
    TEST_ASSERT_EQUAL(ODO_CAN_OK, odo_can_unpack_status(&out.frames[out.n_frames - 1U], &st));
    TEST_ASSERT_NOT_EQUAL(0U, st.faults & fault);
}

static void corrections_reach_the_ipec_corr_frame(void)
{
    boot((uint8_t)ODO_IPEC_PAPER);
    run_good(5U);
    TEST_ASSERT_TRUE(out.ipec_applied);
    TEST_ASSERT_NOT_EQUAL(0, out.ipec_dtheta_bam[0]); /* A's DR drift is taken out every tick */
    odo_msg_ipec_corr_t c;
    TEST_ASSERT_EQUAL(ODO_CAN_OK, odo_can_unpack_ipec_corr(&out.frames[4], &c));
    TEST_ASSERT_EQUAL_INT32(out.ipec_dtheta_bam[0], c.dtheta_a_bam);
    TEST_ASSERT_EQUAL_INT32(out.ipec_dtheta_bam[1], c.dtheta_b_bam);
    /* Heading stays at theta_L + the code centre, where without IPEC it drifts. */
    TEST_ASSERT_FLOAT_WITHIN(0.05, 360.0 / 2048.0, heading_deg(&out.pose[0])); /* + theta_L drift */
    boot((uint8_t)ODO_IPEC_OFF);
    run_good(5U);
    TEST_ASSERT_TRUE(heading_deg(&out.pose[0]) > 0.5);
    TEST_ASSERT_EQUAL_INT32(0, out.ipec_dtheta_bam[0]);
}

static void a_missing_linkage_frame_gates_the_tick(void)
{
    boot((uint8_t)ODO_IPEC_PAPER);
    run_good(3U);
    odo_tick_input_t in = good(3U);
    in.link.linear_present = false;
    assert_gated(&in, ODO_FAULT_LINK_MISSING);
    in = good(4U);
    in.link.rotary_status = ODO_LINK_STATUS_ALPHA_VALID; /* beta not valid */
    assert_gated(&in, ODO_FAULT_LINK_MISSING);
    in = good(5U);
    odo_app_step(&app, &in, &out);
    TEST_ASSERT_EQUAL_UINT32(0U, out.faults); /* back within stale_ticks: corrected again */
    TEST_ASSERT_TRUE(out.ipec_applied);
}

static void a_stale_linkage_reading_gates_the_tick(void)
{
    boot((uint8_t)ODO_IPEC_PAPER);
    run_good(3U);
    for (uint8_t k = 3U; k < 3U + 4U; ++k) { /* four ticks without a link sample: > stale_ticks */
        odo_tick_input_t in = good(k);
        in.link.rotary_present = in.link.linear_present = false;
        odo_app_step(&app, &in, &out);
    }
    odo_tick_input_t in = good(7U);
    assert_gated(&in, ODO_FAULT_LINK_STALE);
    in = good(8U);
    odo_app_step(&app, &in, &out);
    TEST_ASSERT_EQUAL_UINT32(0U, out.faults);
}

static void an_out_of_range_length_gates_the_tick(void)
{
    boot((uint8_t)ODO_IPEC_PAPER);
    run_good(3U);
    odo_tick_input_t in = good(3U);
    in.link.length_um = 1200000U; /* beyond the 1100 mm stop */
    assert_gated(&in, ODO_FAULT_LINK_RANGE);
}

static void an_impossible_jump_gates_the_tick(void)
{
    boot((uint8_t)ODO_IPEC_PAPER);
    run_good(3U);
    odo_tick_input_t in = good(3U);
    in.link.alpha_bam16 = (uint16_t)(65536.0 * 20.0 / 360.0); /* 20 deg in 40 ms */
    assert_gated(&in, ODO_FAULT_LINK_JUMP);
    in = good(4U);
    in.link.length_um = 1050000U; /* 50 mm in 40 ms */
    assert_gated(&in, ODO_FAULT_LINK_JUMP);
    in = good(5U); /* the glitch did not become the reference */
    odo_app_step(&app, &in, &out);
    TEST_ASSERT_EQUAL_UINT32(0U, out.faults);
}

static void out_of_order_and_duplicated_linkage_frames_gate_the_tick(void)
{
    boot((uint8_t)ODO_IPEC_PAPER);
    run_good(5U);
    odo_tick_input_t in = good(5U);
    in.link.rotary_seq = in.link.linear_seq = 4U; /* the previous sample again */
    assert_gated(&in, ODO_FAULT_SEQ_DUP);
    in = good(6U);
    in.link.rotary_seq = in.link.linear_seq = 2U; /* older than one already used */
    assert_gated(&in, ODO_FAULT_LINK_STALE);
    in = good(7U);
    in.link.linear_seq = 4U; /* rotary fresh, linear a repeat */
    assert_gated(&in, ODO_FAULT_SEQ_DUP);
}

/// The link check runs every tick on a two-truck vehicle, IPEC on or off. Rotary readings exactly
/// 180 deg apart make 1 - cos(alpha - beta) = 2, one past int32 in Q30 (it overflowed there, undefined
/// behaviour from two CAN frames); the eccentric bias (002 s. 5.2) is then twice length_ecc_nm.
static void rotary_readings_180_deg_apart_give_twice_the_eccentric_bias(void)
{
    odo_params_t p = clapper_params((uint8_t)ODO_IPEC_OFF);
    p.link.length_ecc_nm = 3000000;   /* 3 mm */
    p.link.length_bias_nm = -1000000; /* -1 mm */
    p.link.length_min_um = 1000U;
    p.link.length_max_um = 20000000U;
    const uint16_t half_step = (uint16_t)(1U << (16U - p.link.rotary_bits - 1U));
    const uint16_t codes[][2] = {{0x0000U, 0x8000U}, {0x8000U, 0x0000U}, {0x4000U, 0xC000U}, {0x1230U, 0x1230U}};
    for (unsigned i = 0; i < sizeof codes / sizeof codes[0]; ++i) {
        odo_ipec_t s;
        odo_ipec_init(&s);
        odo_link_input_t in;
        memset(&in, 0, sizeof in);
        in.rotary_present = in.linear_present = true;
        in.rotary_status = ODO_LINK_STATUS_ALPHA_VALID | ODO_LINK_STATUS_BETA_VALID;
        in.linear_status = ODO_LINK_STATUS_LENGTH_VALID;
        in.alpha_bam16 = (uint16_t)(codes[i][0] - half_step); /* decoded at the code centre */
        in.beta_bam16 = (uint16_t)(codes[i][1] - half_step);
        in.length_um = 1000000U;
        odo_ipec_reading_t rd;
        TEST_ASSERT_EQUAL_UINT32(0U, odo_ipec_check(&s, &p, &in, &rd));
        const double rel = 2.0 * M_PI * ((double)(int16_t)(uint16_t)(codes[i][0] - codes[i][1]) / 65536.0);
        const double want_mm = 1000.0 + 1.0 - 3.0 * (1.0 - cos(rel));
        TEST_ASSERT_DOUBLE_WITHIN(1e-6, want_mm, mm(rd.length_mm_q32));
    }
    /* and through the app with IPEC off, as the reproducer's two frames reach it */
    TEST_ASSERT_EQUAL(ODO_PARAMS_OK, odo_app_init_params(&app, &p));
    odo_tick_input_t in = good(0U);
    in.link.alpha_bam16 = 0x0000U;
    in.link.beta_bam16 = 0x8000U;
    odo_app_step(&app, &in, &out);
    TEST_ASSERT_EQUAL_UINT32(0U, out.faults);
}

static void a_missing_wheel_sample_gates_ipec_too(void)
{
    boot((uint8_t)ODO_IPEC_PAPER);
    run_good(3U);
    odo_tick_input_t in = good(3U);
    in.wheel[1].present = false;
    odo_app_step(&app, &in, &out);
    TEST_ASSERT_NOT_EQUAL(0U, out.faults & ODO_FAULT_IPEC_GATED);
    TEST_ASSERT_FALSE(out.ipec_applied);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(eq10_from_b_to_a_makes_eq16_put_b_l_behind_a);
    RUN_TEST(paper_form_corrects_a_heading_error_within_the_tick);
    RUN_TEST(translational_correction_is_against_travel_for_either_wheel_and_sign);
    RUN_TEST(translational_correction_chord_matches_the_sine_over_every_correction_size);
    RUN_TEST(estimator_keeps_bumps_immediate_and_filters_within_a_step);
    RUN_TEST(set_trailer_correction_accounts_for_the_hitch_lever);
    RUN_TEST(corrections_reach_the_ipec_corr_frame);
    RUN_TEST(a_missing_linkage_frame_gates_the_tick);
    RUN_TEST(a_stale_linkage_reading_gates_the_tick);
    RUN_TEST(an_out_of_range_length_gates_the_tick);
    RUN_TEST(an_impossible_jump_gates_the_tick);
    RUN_TEST(out_of_order_and_duplicated_linkage_frames_gate_the_tick);
    RUN_TEST(a_missing_wheel_sample_gates_ipec_too);
    RUN_TEST(rotary_readings_180_deg_apart_give_twice_the_eccentric_bias);
    return UNITY_END();
}
