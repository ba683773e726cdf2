/// The 40 ms application step: parameter boot rule, fault flags, output frames.
#include <math.h>
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

/* -------------------------------------------------------------------------------------------
 * Faults at speed and silent limits (issue 16): each of these failed on the code before it.
 * ------------------------------------------------------------------------------------------- */

#define K_MM         (3.14159265358979323846 * 150.0 / 39000.0) /* the default labmate: mm per count */
#define MM_OF_Q32(v) ((double)(v) / 4294967296.0)

static void boot_defaults(uint8_t counter_bits)
{
    odo_params_t p;
    odo_params_defaults(&p);
    p.counter_bits = counter_bits;
    TEST_ASSERT_EQUAL(ODO_PARAMS_OK, odo_app_init_params(&app, &p));
}

/// Straight driving at v mm/s; the samples whose index is in `lost` never arrive. Returns x (mm).
static double drive_straight(uint8_t bits, double v_mm_s, uint32_t ticks, const uint32_t *lost, size_t n_lost,
                             uint32_t *faults_or)
{
    boot_defaults(bits);
    const double per_tick = v_mm_s * 0.04 / K_MM;
    *faults_or = 0U;
    size_t next = 0U;
    for (uint32_t k = 0U; k < ticks; ++k) {
        const uint32_t c = ts_wrap_counter((int64_t)llround(per_tick * k), bits);
        odo_tick_input_t in = tick(40000ULL * k, c, c, (uint8_t)k);
        in.wheel[0].bits = bits;
        if (next < n_lost && lost[next] == k) {
            in.wheel[0].present = false;
            next++;
        }
        odo_app_step(&app, &in, &out);
        *faults_or |= out.faults;
    }
    return MM_OF_Q32(app.truck[0].pose.x_mm_q32);
}

/// Counters are cumulative (000 Eq. 2.3 sums counts), so a sample after lost ones carries their
/// motion: the plausibility limit scales with the ticks elapsed. At 2.5 m/s a two-tick delta is
/// above the one-tick limit of 3 m/s, and the old guard threw every such sample away.
static void lost_samples_at_speed_lose_no_travel(void)
{
    static const uint32_t lost[] = {10, 20, 21, 30, 31, 32, 40, 41, 42, 43, 60, 61, 62, 63, 64, 65, 66, 67};
    uint32_t f_clean, f_lossy;
    const double clean = drive_straight(24U, 2500.0, 100U, NULL, 0U, &f_clean);
    const double lossy = drive_straight(24U, 2500.0, 100U, lost, sizeof lost / sizeof lost[0], &f_lossy);
    TEST_ASSERT_EQUAL_UINT32(0U, f_clean);
    TEST_ASSERT_NOT_EQUAL(0U, f_lossy & ODO_FAULT_SEQ_GAP);
    TEST_ASSERT_EQUAL_UINT32(0U, f_lossy & ODO_FAULT_COUNTER_JUMP_A);
    TEST_ASSERT_DOUBLE_WITHIN(K_MM, 99.0 * 100.0, clean); /* 99 ticks of 100 mm */
    TEST_ASSERT_DOUBLE_WITHIN(1e-6, clean, lossy);
}

/// A 16-bit counter at the 3 m/s limit (9933 counts a tick) can tell a reading 3 ticks after the
/// previous one (29,799 counts < 2^15) but not 4 (39,732): then the reading is ambiguous whatever
/// it says, so it is flagged and not integrated, even when it looks small.
static void a_gap_the_counter_width_cannot_tell_is_flagged_not_integrated(void)
{
    static const uint32_t lost2[] = {10, 11};
    uint32_t f;
    const double clean = drive_straight(16U, 2000.0, 30U, NULL, 0U, &f);
    TEST_ASSERT_DOUBLE_WITHIN(1e-6, clean, drive_straight(16U, 2000.0, 30U, lost2, 2U, &f));
    TEST_ASSERT_EQUAL_UINT32(0U, f & ODO_FAULT_COUNTER_JUMP_A);

    boot_defaults(16U);
    odo_tick_input_t in = tick(0U, 100U, 100U, 0U);
    in.wheel[0].bits = 16U;
    odo_app_step(&app, &in, &out);
    in = tick(4U * 40000U, 200U, 200U, 4U); /* 3 samples lost: 100 counts moved, or 65,636? */
    in.wheel[0].bits = 16U;
    odo_app_step(&app, &in, &out);
    TEST_ASSERT_NOT_EQUAL(0U, out.faults & ODO_FAULT_COUNTER_JUMP_A);
    TEST_ASSERT_EQUAL_INT64(0, app.truck[0].pose.x_mm_q32);
    in = tick(5U * 40000U, 300U, 300U, 5U); /* from the re-taken baseline */
    in.wheel[0].bits = 16U;
    odo_app_step(&app, &in, &out);
    TEST_ASSERT_EQUAL_UINT32(0U, out.faults);
    TEST_ASSERT_DOUBLE_WITHIN(1e-6, 100.0 * K_MM, MM_OF_Q32(app.truck[0].pose.x_mm_q32));
}

/// The sequence number wraps at 256, so from 128 ticks on the clock counts the gap: 12 s at
/// 0.5 m/s (300 ticks, sequence step 44) is within what 24 bits can tell (300 x 9933 < 2^23) and
/// is integrated; 36 s (900 ticks) is not, whatever the reading.
static void gaps_beyond_the_sequence_wrap_are_counted_by_the_clock(void)
{
    boot_defaults(24U);
    odo_tick_input_t in = tick(0U, 0U, 0U, 0U);
    odo_app_step(&app, &in, &out);
    const uint32_t moved = (uint32_t)llround(6000.0 / K_MM); /* 6 m */
    in = tick(300U * 40000U, moved, moved, (uint8_t)300U);
    odo_app_step(&app, &in, &out);
    TEST_ASSERT_NOT_EQUAL(0U, out.faults & ODO_FAULT_SEQ_GAP);
    TEST_ASSERT_EQUAL_UINT32(0U, out.faults & ODO_FAULT_COUNTER_JUMP_A);
    TEST_ASSERT_DOUBLE_WITHIN(K_MM, 6000.0, MM_OF_Q32(app.truck[0].pose.x_mm_q32));

    in = tick(1200U * 40000U, moved + 5000U, moved + 5000U, (uint8_t)1200U); /* 900 ticks later */
    odo_app_step(&app, &in, &out);
    TEST_ASSERT_NOT_EQUAL(0U, out.faults & ODO_FAULT_COUNTER_JUMP_A);
    TEST_ASSERT_DOUBLE_WITHIN(K_MM, 6000.0, MM_OF_Q32(app.truck[0].pose.x_mm_q32));
}

/// CAN frames carry 24 bits of count (can/odometry.dbc). With counter_bits 32 and a wheel that may
/// turn more than 2^23 counts in a tick (4e6 counts per turn of a 10 mm wheel at 3 m/s: 15.3 M),
/// a 24-bit delta is ambiguous: +9 M read as -7.8 M was integrated backwards. It is flagged now.
/// Within the frame's range (the labmate) 32-bit counters fed 24-bit frames wrap at 2^24.
static void counts_in_24_bit_frames_are_judged_by_the_frame_width(void)
{
    odo_params_t p;
    odo_params_defaults(&p);
    p.counter_bits = 32U;
    p.truck[0].wheel_diameter_nm = 10000000U;
    p.truck[0].counts_per_rev_milli = 4000000000U;
    TEST_ASSERT_EQUAL(ODO_PARAMS_OK, odo_app_init_params(&app, &p));
    TEST_ASSERT_TRUE(app.model[0].max_counts > (1UL << 23));
    odo_tick_input_t in = tick(0U, 0U, 0U, 0U);
    odo_app_step(&app, &in, &out);
    in = tick(40000U, 9000000U, 9000000U, 1U); /* 9 M counts forward: 70.7 mm */
    odo_app_step(&app, &in, &out);
    TEST_ASSERT_NOT_EQUAL(0U, out.faults & ODO_FAULT_COUNTER_JUMP_A);
    TEST_ASSERT_TRUE(app.truck[0].pose.x_mm_q32 >= 0); /* never backwards */

    boot_defaults(32U);
    in = tick(0U, 0x00FFFFF0U, 0x00FFFFF0U, 0U);
    odo_app_step(&app, &in, &out);
    in = tick(40000U, 0x00000010U, 0x00000010U, 1U); /* across the frame's 2^24 wrap: +32 */
    odo_app_step(&app, &in, &out);
    TEST_ASSERT_EQUAL_UINT32(0U, out.faults);
    TEST_ASSERT_DOUBLE_WITHIN(1e-6, 32.0 * K_MM, MM_OF_Q32(app.truck[0].pose.x_mm_q32));
}

/// A sample that says it carries 0 bits reached 1 << -1 (undefined) in the counter delta. It
/// carries no information: flagged, not integrated.
static void a_sample_of_zero_bits_is_refused(void)
{
    boot_defaults(24U);
    odo_tick_input_t in = tick(0U, 0U, 0U, 0U);
    odo_app_step(&app, &in, &out);
    in = tick(40000U, 500U, 500U, 1U);
    in.wheel[0].bits = 0U;
    odo_app_step(&app, &in, &out);
    TEST_ASSERT_NOT_EQUAL(0U, out.faults & ODO_FAULT_COUNTER_JUMP_A);
    TEST_ASSERT_EQUAL_INT64(0, app.truck[0].pose.x_mm_q32);
}

static uint8_t pose_flags_of_a(void)
{
    odo_msg_pose_theta_t th;
    uint8_t truck = 9U;
    TEST_ASSERT_EQUAL(ODO_CAN_OK, odo_can_unpack_pose_theta(&out.frames[1], &truck, &th));
    return th.flags;
}

/// Position is int64 mm Q32: it overflowed (undefined) 2^31 mm from the origin. The odometry now
/// holds a pose beyond ODO_POSE_LIMIT_MM_Q32 (2^29 mm) and says so every tick, before anything
/// can overflow.
static void a_pose_beyond_the_integrable_range_is_held_and_flagged(void)
{
    boot_defaults(24U);
    odo_tick_input_t in = tick(0U, 0U, 0U, 0U);
    odo_app_step(&app, &in, &out);
    app.truck[0].pose.x_mm_q32 = INT64_MAX - 1000; /* one more forward step would overflow */
    in = tick(40000U, 8000U, 8000U, 1U);
    odo_app_step(&app, &in, &out);
    TEST_ASSERT_NOT_EQUAL(0U, out.faults & ODO_FAULT_POSE_RANGE);
    TEST_ASSERT_NOT_EQUAL(0U, pose_flags_of_a() & ODO_POSE_FLAG_RANGE);
    TEST_ASSERT_EQUAL_INT64(INT64_MAX - 1000, app.truck[0].pose.x_mm_q32);

    /* just inside the limit a step still integrates; the tick that crosses it raises the flag */
    app.truck[0].pose.x_mm_q32 = ODO_POSE_LIMIT_MM_Q32 - ((int64_t)50 << 32); /* 50 mm short */
    in = tick(80000U, 16000U, 16000U, 2U);                                    /* 96.7 mm */
    odo_app_step(&app, &in, &out);
    TEST_ASSERT_TRUE(app.truck[0].pose.x_mm_q32 > ODO_POSE_LIMIT_MM_Q32);
    TEST_ASSERT_NOT_EQUAL(0U, out.faults & ODO_FAULT_POSE_RANGE);
    const int64_t held = app.truck[0].pose.x_mm_q32;
    in = tick(120000U, 24000U, 24000U, 3U);
    odo_app_step(&app, &in, &out);
    TEST_ASSERT_EQUAL_INT64(held, app.truck[0].pose.x_mm_q32);
    TEST_ASSERT_EQUAL_UINT32(3U, app.faults.count[18]); /* every tick beyond the limit */
}

/// POSE_XY carries +-21.47 km (int32 of 10 um); beyond it the frame saturated with no word. The
/// frame still saturates, and STATUS and POSE_THETA say so; the pose itself goes on.
static void a_pose_beyond_the_pose_xy_frame_is_flagged(void)
{
    boot_defaults(24U);
    odo_tick_input_t in = tick(0U, 0U, 0U, 0U);
    odo_app_step(&app, &in, &out);
    TEST_ASSERT_EQUAL_UINT32(0U, out.faults);
    app.truck[0].pose.x_mm_q32 = (int64_t)21474836 << 32; /* 21,474.836 km: still fits */
    app.truck[0].pose.y_mm_q32 = -((int64_t)21474836 << 32);
    in = tick(40000U, 0U, 0U, 1U);
    odo_app_step(&app, &in, &out);
    TEST_ASSERT_EQUAL_UINT32(0U, out.faults);
    in = tick(80000U, 1000U, 1000U, 2U); /* 12 mm further */
    odo_app_step(&app, &in, &out);
    TEST_ASSERT_NOT_EQUAL(0U, out.faults & ODO_FAULT_POSE_XY_SATURATED);
    TEST_ASSERT_NOT_EQUAL(0U, pose_flags_of_a() & ODO_POSE_FLAG_XY_SATURATED);
    odo_msg_pose_xy_t xy;
    uint8_t truck = 9U;
    TEST_ASSERT_EQUAL(ODO_CAN_OK, odo_can_unpack_pose_xy(&out.frames[0], &truck, &xy));
    TEST_ASSERT_EQUAL_INT32(INT32_MAX, xy.x_10um);
    TEST_ASSERT_EQUAL_INT32(-2147483600, xy.y_10um); /* y still fits */
    TEST_ASSERT_DOUBLE_WITHIN(1e-3, 21474836.0 + 1000.0 * K_MM, MM_OF_Q32(app.truck[0].pose.x_mm_q32));
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

/// A single truck boots on a narrow counter that only its own record fits: the unused record B
/// (the defaults, a labmate whose 3 m/s in 40 ms is ~9900 counts) is not a model the app runs.
/// The same record B on a clapper, which does run it, is refused.
static void unused_truck_record_does_not_stop_a_single_truck_from_booting(void)
{
    odo_params_t p;
    odo_params_defaults(&p);
    p.counter_bits = 12U;
    p.tick_us = 50000U; /* OptiOdom: D 84 mm, 2796.8 counts/turn */
    p.truck[0].wheel_diameter_nm = 84000000U;
    p.truck[0].counts_per_rev_milli = 2796800U;
    p.truck[0].wheelbase_nm = 200000000U;
    TEST_ASSERT_EQUAL(ODO_PARAMS_OK, odo_app_init_params(&app, &p));
    TEST_ASSERT_EQUAL_UINT8(12U, app.params.counter_bits);
    p.vehicle = (uint8_t)ODO_VEHICLE_CLAPPER;
    TEST_ASSERT_EQUAL(ODO_PARAMS_ERR_RANGE, odo_app_init_params(&app, &p));
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
    RUN_TEST(lost_samples_at_speed_lose_no_travel);
    RUN_TEST(a_gap_the_counter_width_cannot_tell_is_flagged_not_integrated);
    RUN_TEST(gaps_beyond_the_sequence_wrap_are_counted_by_the_clock);
    RUN_TEST(counts_in_24_bit_frames_are_judged_by_the_frame_width);
    RUN_TEST(a_sample_of_zero_bits_is_refused);
    RUN_TEST(a_pose_beyond_the_integrable_range_is_held_and_flagged);
    RUN_TEST(a_pose_beyond_the_pose_xy_frame_is_flagged);
    RUN_TEST(twelve_bit_counters_wrap_both_ways_through_the_app);
    RUN_TEST(unused_truck_record_does_not_stop_a_single_truck_from_booting);
    return UNITY_END();
}
