/// The 40 ms application step: parameter boot rule, fault flags, output frames.
#include <string.h>

#include "odo/odo_app.h"
#include "odo/odo_can.h"
#include "test_support.h"
#include "unity.h"

void setUp(void) {}
void tearDown(void) {}

static odo_app_t app;
static odo_tick_output_t out;

static odo_tick_input_t tick(uint64_t t_us, uint32_t left, uint32_t right, uint8_t seq)
{
    odo_tick_input_t in;
    memset(&in, 0, sizeof in);
    in.t_us = t_us;
    in.wheel[0].present = true;
    in.wheel[0].bits = 24U;
    in.wheel[0].seq = seq;
    in.wheel[0].left_raw = left;
    in.wheel[0].right_raw = right;
    in.wheel[1] = in.wheel[0];
    return in;
}

static odo_msg_status_t status_frame(void)
{
    odo_msg_status_t st;
    TEST_ASSERT_EQUAL(ODO_CAN_OK, odo_can_unpack_status(&out.frames[out.n_frames - 1U], &st));
    return st;
}

static void boots_on_defaults_and_flags_it_when_the_block_is_bad(void)
{
    uint8_t block[ODO_PARAMS_SIZE];
    odo_params_t p;
    odo_params_defaults(&p);
    p.truck[0].wheelbase_nm = 337000000U;
    TEST_ASSERT_EQUAL(ODO_PARAMS_SIZE, odo_params_encode(&p, block, sizeof block));
    TEST_ASSERT_EQUAL(ODO_PARAMS_OK, odo_app_init(&app, block, sizeof block));
    TEST_ASSERT_EQUAL_UINT32(337000000U, app.params.truck[0].wheelbase_nm);
    odo_tick_input_t in = tick(0U, 0U, 0U, 0U);
    odo_app_step(&app, &in, &out);
    TEST_ASSERT_EQUAL_UINT32(0U, out.faults & ODO_FAULT_PARAMS_DEFAULTED);

    block[40] ^= 0x01U; /* one flipped bit: CRC */
    TEST_ASSERT_EQUAL(ODO_PARAMS_ERR_CRC, odo_app_init(&app, block, sizeof block));
    TEST_ASSERT_EQUAL_UINT32(340000000U, app.params.truck[0].wheelbase_nm); /* defaults */
    for (uint8_t i = 0U; i < 3U; ++i) {
        in = tick(40000U * i, 10U * i, 10U * i, i);
        odo_app_step(&app, &in, &out);
        TEST_ASSERT_NOT_EQUAL(0U, out.faults & ODO_FAULT_PARAMS_DEFAULTED);
        TEST_ASSERT_EQUAL_UINT8(ODO_PARAMS_ERR_CRC, status_frame().param_state);
    }
    TEST_ASSERT_EQUAL(ODO_PARAMS_ERR_ARG, odo_app_init(&app, NULL, 0U));
}

static void single_truck_publishes_pose_and_status_frames(void)
{
    TEST_ASSERT_EQUAL(ODO_PARAMS_ERR_ARG, odo_app_init(&app, NULL, 0U));
    odo_params_t p;
    odo_params_defaults(&p);
    TEST_ASSERT_EQUAL(ODO_PARAMS_OK, odo_app_init_params(&app, &p));
    odo_tick_input_t in = tick(0U, 0U, 0U, 7U);
    odo_app_step(&app, &in, &out);
    in = tick(40000U, 8000U, 8000U, 8U);
    odo_app_step(&app, &in, &out);
    TEST_ASSERT_EQUAL_UINT8(3U, out.n_frames);
    TEST_ASSERT_EQUAL_HEX32(ODO_CAN_ID_POSE_XY_A, out.frames[0].id);
    TEST_ASSERT_EQUAL_HEX32(ODO_CAN_ID_POSE_THETA_A, out.frames[1].id);
    TEST_ASSERT_EQUAL_HEX32(ODO_CAN_ID_STATUS, out.frames[2].id);
    uint8_t truck = 9U;
    odo_msg_pose_xy_t xy;
    TEST_ASSERT_EQUAL(ODO_CAN_OK, odo_can_unpack_pose_xy(&out.frames[0], &truck, &xy));
    TEST_ASSERT_EQUAL_UINT8(0U, truck);
    /* 8000 counts of 150 mm * pi / 39000 = 96.664 mm -> 9666 units of 10 um */
    TEST_ASSERT_INT32_WITHIN(1, 9666, xy.x_10um);
    TEST_ASSERT_EQUAL_INT32(0, xy.y_10um);
    odo_msg_status_t st = status_frame();
    TEST_ASSERT_EQUAL_UINT32(0U, st.faults);
    TEST_ASSERT_EQUAL_UINT8(1U, st.seq); /* second output */
}

static void clapper_publishes_both_trucks_and_ipec_frame(void)
{
    odo_params_t p;
    odo_params_defaults(&p);
    p.vehicle = ODO_VEHICLE_CLAPPER;
    TEST_ASSERT_EQUAL(ODO_PARAMS_OK, odo_app_init_params(&app, &p));
    /* truck B starts one link length (1 m) behind A, so Eq. 16 holds from the start */
    TEST_ASSERT_EQUAL_INT64(-(int64_t)1000 * 4294967296LL, app.truck[1].pose.x_mm_q32);
    odo_tick_input_t in = tick(0U, 0U, 0U, 0U);
    odo_app_step(&app, &in, &out);
    TEST_ASSERT_EQUAL_UINT8(6U, out.n_frames);
    TEST_ASSERT_EQUAL_HEX32(ODO_CAN_ID_POSE_XY_B, out.frames[2].id);
    TEST_ASSERT_EQUAL_HEX32(ODO_CAN_ID_POSE_THETA_B, out.frames[3].id);
    TEST_ASSERT_EQUAL_HEX32(ODO_CAN_ID_IPEC_CORR, out.frames[4].id);
}

static void missing_duplicated_and_lost_frames_are_flagged(void)
{
    odo_params_t p;
    odo_params_defaults(&p);
    TEST_ASSERT_EQUAL(ODO_PARAMS_OK, odo_app_init_params(&app, &p));
    odo_tick_input_t in = tick(0U, 0U, 0U, 1U);
    odo_app_step(&app, &in, &out);
    in.wheel[0].present = false;
    in.t_us = 40000U;
    odo_app_step(&app, &in, &out);
    TEST_ASSERT_NOT_EQUAL(0U, out.faults & ODO_FAULT_WHEEL_MISSING_A);
    odo_msg_pose_theta_t th;
    uint8_t truck;
    TEST_ASSERT_EQUAL(ODO_CAN_OK, odo_can_unpack_pose_theta(&out.frames[1], &truck, &th));
    TEST_ASSERT_EQUAL_HEX8(ODO_POSE_FLAG_MISSING, th.flags);

    in = tick(80000U, 100U, 100U, 1U); /* same seq again: duplicate */
    odo_app_step(&app, &in, &out);
    TEST_ASSERT_NOT_EQUAL(0U, out.faults & ODO_FAULT_SEQ_DUP);
    in = tick(120000U, 300U, 300U, 4U); /* 2 and 3 lost */
    odo_app_step(&app, &in, &out);
    TEST_ASSERT_NOT_EQUAL(0U, out.faults & ODO_FAULT_SEQ_GAP);
    /* counters are cumulative: nothing was lost from the distance */
    TEST_ASSERT_INT64_WITHIN(1 << 20, (int64_t)(300.0 * 3.14159265358979 * 150.0 / 39000.0 * 4294967296.0),
                             app.truck[0].pose.x_mm_q32);
    in = tick(160000U, 310U, 310U, 5U);
    odo_app_step(&app, &in, &out);
    TEST_ASSERT_EQUAL_UINT32(0U, out.faults);
    TEST_ASSERT_EQUAL_UINT32(1U, app.faults.count[5]); /* one SEQ_GAP occurrence */
    TEST_ASSERT_EQUAL_UINT32(1U, app.faults.count[6]); /* one SEQ_DUP occurrence */
}

static void impossible_jumps_decoder_errors_and_time_reversal_are_flagged(void)
{
    odo_params_t p;
    odo_params_defaults(&p);
    TEST_ASSERT_EQUAL(ODO_PARAMS_OK, odo_app_init_params(&app, &p));
    odo_tick_input_t in = tick(1000000U, 0U, 0U, 0U);
    odo_app_step(&app, &in, &out);
    in = tick(1040000U, 0x400000U, 0U, 1U); /* 4.2 M counts in 40 ms */
    odo_app_step(&app, &in, &out);
    TEST_ASSERT_NOT_EQUAL(0U, out.faults & ODO_FAULT_COUNTER_JUMP_A);
    TEST_ASSERT_EQUAL_INT64(0, app.truck[0].pose.x_mm_q32);
    in = tick(1000000U, 0x400000U, 0U, 2U); /* earlier than the last tick */
    in.wheel[0].status = ODO_WHEEL_STATUS_RIGHT_SKIPPED;
    in.rx_faults = ODO_FAULT_CAN_BAD_DLC;
    odo_app_step(&app, &in, &out);
    TEST_ASSERT_NOT_EQUAL(0U, out.faults & ODO_FAULT_TIME_BACKWARDS);
    TEST_ASSERT_NOT_EQUAL(0U, out.faults & ODO_FAULT_DECODER_A);
    TEST_ASSERT_NOT_EQUAL(0U, out.faults & ODO_FAULT_CAN_BAD_DLC);
    TEST_ASSERT_EQUAL_UINT16(1U, status_frame().rejected);
}

static void step_is_deterministic_for_identical_inputs(void)
{
    odo_params_t p;
    odo_params_defaults(&p);
    p.vehicle = ODO_VEHICLE_CLAPPER;
    static odo_app_t a, b;
    static odo_tick_output_t oa, ob;
    TEST_ASSERT_EQUAL(ODO_PARAMS_OK, odo_app_init_params(&a, &p));
    TEST_ASSERT_EQUAL(ODO_PARAMS_OK, odo_app_init_params(&b, &p));
    ts_rng_t rng;
    ts_rng_seed(&rng, 99U);
    int64_t c[2][2] = {{0, 0}, {0, 0}};
    for (uint32_t i = 0U; i < 2000U; ++i) {
        odo_tick_input_t in;
        memset(&in, 0, sizeof in);
        in.t_us = 40000ULL * i;
        for (int t = 0; t < 2; ++t) {
            c[t][0] += ts_rng_range(&rng, -900, 900);
            c[t][1] += ts_rng_range(&rng, -900, 900);
            in.wheel[t].present = true;
            in.wheel[t].bits = 24U;
            in.wheel[t].seq = (uint8_t)i;
            in.wheel[t].left_raw = ts_wrap_counter(c[t][0], 24U);
            in.wheel[t].right_raw = ts_wrap_counter(c[t][1], 24U);
        }
        odo_app_step(&a, &in, &oa);
        odo_app_step(&b, &in, &ob);
        TEST_ASSERT_EQUAL_MEMORY(oa.frames, ob.frames, sizeof oa.frames);
    }
    TEST_ASSERT_EQUAL_MEMORY(&a.truck, &b.truck, sizeof a.truck);
}

/// A 12-bit decoder behind 24-bit CAN frames (the OptiOdom robot's width): the app takes deltas
/// modulo 2^12, so driving forward and back across the counter's wrap many times loses nothing,
/// and no wrap looks like a counter jump; a block carrying that width boots.
static void twelve_bit_counters_wrap_both_ways_through_the_app(void)
{
    odo_params_t p;
    odo_params_defaults(&p);
    p.counter_bits = 12U;
    p.truck[0].counts_per_rev_milli = p.truck[1].counts_per_rev_milli = 2000000U; /* 2000 counts/turn */
    TEST_ASSERT_EQUAL(ODO_PARAMS_OK, odo_app_init_params(&app, &p));
    int64_t c = 4096 - 300; /* just below the wrap */
    uint8_t seq = 0U;
    odo_tick_input_t in = tick(0U, ts_wrap_counter(c, 12U), ts_wrap_counter(c, 12U), seq);
    odo_app_step(&app, &in, &out);
    for (int k = 1; k <= 200; ++k) { /* forward 200 x 450 counts: 22 wraps */
        c += 450;
        ++seq;
        in = tick(40000U * (uint64_t)k, ts_wrap_counter(c, 12U), ts_wrap_counter(c, 12U), seq);
        odo_app_step(&app, &in, &out);
        TEST_ASSERT_EQUAL_UINT32(0U, out.faults & (ODO_FAULT_COUNTER_JUMP_A | ODO_FAULT_COUNTER_JUMP_B));
    }
    /* 90000 counts of pi * 150 mm / 2000 */
    TEST_ASSERT_DOUBLE_WITHIN(1e-3, 90000.0 * 3.14159265358979 * 150.0 / 2000.0,
                              (double)app.truck[0].pose.x_mm_q32 / 4294967296.0);
    for (int k = 201; k <= 400; ++k) { /* and back */
        c -= 450;
        ++seq;
        in = tick(40000U * (uint64_t)k, ts_wrap_counter(c, 12U), ts_wrap_counter(c, 12U), seq);
        odo_app_step(&app, &in, &out);
        TEST_ASSERT_EQUAL_UINT32(0U, out.faults & (ODO_FAULT_COUNTER_JUMP_A | ODO_FAULT_COUNTER_JUMP_B));
    }
    TEST_ASSERT_INT64_WITHIN(4, 0, app.truck[0].pose.x_mm_q32);

    uint8_t block[ODO_PARAMS_SIZE];
    TEST_ASSERT_EQUAL(ODO_PARAMS_SIZE, odo_params_encode(&p, block, sizeof block));
    TEST_ASSERT_EQUAL(ODO_PARAMS_OK, odo_app_init(&app, block, sizeof block));
    TEST_ASSERT_EQUAL_UINT8(12U, app.params.counter_bits);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(boots_on_defaults_and_flags_it_when_the_block_is_bad);
    RUN_TEST(single_truck_publishes_pose_and_status_frames);
    RUN_TEST(clapper_publishes_both_trucks_and_ipec_frame);
    RUN_TEST(missing_duplicated_and_lost_frames_are_flagged);
    RUN_TEST(impossible_jumps_decoder_errors_and_time_reversal_are_flagged);
    RUN_TEST(step_is_deterministic_for_identical_inputs);
    RUN_TEST(twelve_bit_counters_wrap_both_ways_through_the_app);
    return UNITY_END();
}
