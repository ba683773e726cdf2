/// Unity tests of the CAN codec (firmware/include/odo/odo_can.h) against the contract in
/// can/odometry.dbc. The bit-exact cross-check with cantools lives in tests/python/test_can_dbc.py;
/// these tests pin the firmware-side rules: round trips, truncation, rejection and zeroing.
#include <stdint.h>
#include <string.h>

#include "odo/odo_can.h"
#include "test_support.h"
#include "unity.h"

#define N_RANDOM 2000

static ts_rng_t rng;

void setUp(void) { ts_rng_seed(&rng, 0x0D0CA17ULL); }
void tearDown(void) {}

/* ---- helpers ---- */

typedef union {
    odo_msg_wheel_counts_t wheel;
    odo_msg_link_rotary_t rotary;
    odo_msg_link_linear_t linear;
    odo_msg_pose_xy_t xy;
    odo_msg_pose_theta_t theta;
    odo_msg_ipec_corr_t ipec;
    odo_msg_status_t status;
} any_msg_t;

static const odo_can_msg_t all_msgs[ODO_CAN_MSG_COUNT] = {
    ODO_CAN_MSG_WHEEL_COUNTS_A, ODO_CAN_MSG_WHEEL_COUNTS_B, ODO_CAN_MSG_LINK_ROTARY, ODO_CAN_MSG_LINK_LINEAR,
    ODO_CAN_MSG_POSE_XY_A,      ODO_CAN_MSG_POSE_THETA_A,   ODO_CAN_MSG_POSE_XY_B,   ODO_CAN_MSG_POSE_THETA_B,
    ODO_CAN_MSG_IPEC_CORR,      ODO_CAN_MSG_STATUS,
};

static uint32_t rnd32(void) { return (uint32_t)ts_rng_u64(&rng); }
static uint8_t rnd8(void) { return (uint8_t)ts_rng_u64(&rng); }

/* Random content for a message (every field over its full C range). */
static void random_msg(odo_can_msg_t m, any_msg_t *a)
{
    memset(a, 0, sizeof *a);
    switch (m) {
    case ODO_CAN_MSG_WHEEL_COUNTS_A:
    case ODO_CAN_MSG_WHEEL_COUNTS_B:
        a->wheel.left_count = rnd32() & ODO_CAN_COUNT_MASK;
        a->wheel.right_count = rnd32() & ODO_CAN_COUNT_MASK;
        a->wheel.seq = rnd8();
        a->wheel.status = rnd8();
        break;
    case ODO_CAN_MSG_LINK_ROTARY:
        a->rotary.alpha_bam16 = (uint16_t)rnd32();
        a->rotary.beta_bam16 = (uint16_t)rnd32();
        a->rotary.seq = rnd8();
        a->rotary.status = rnd8();
        break;
    case ODO_CAN_MSG_LINK_LINEAR:
        a->linear.length_um = rnd32();
        a->linear.seq = rnd8();
        a->linear.status = rnd8();
        break;
    case ODO_CAN_MSG_POSE_XY_A:
    case ODO_CAN_MSG_POSE_XY_B:
        a->xy.x_10um = (int32_t)ts_rng_range(&rng, INT32_MIN, INT32_MAX);
        a->xy.y_10um = (int32_t)ts_rng_range(&rng, INT32_MIN, INT32_MAX);
        break;
    case ODO_CAN_MSG_POSE_THETA_A:
    case ODO_CAN_MSG_POSE_THETA_B:
        a->theta.theta_bam = rnd32();
        a->theta.seq = rnd8();
        a->theta.flags = rnd8();
        break;
    case ODO_CAN_MSG_IPEC_CORR:
        a->ipec.dtheta_a_bam = (int32_t)ts_rng_range(&rng, INT32_MIN, INT32_MAX);
        a->ipec.dtheta_b_bam = (int32_t)ts_rng_range(&rng, INT32_MIN, INT32_MAX);
        break;
    case ODO_CAN_MSG_STATUS:
        a->status.faults = rnd32();
        a->status.seq = rnd8();
        a->status.param_state = rnd8();
        a->status.rejected = (uint16_t)rnd32();
        break;
    case ODO_CAN_MSG_UNKNOWN:
    default: TEST_FAIL_MESSAGE("no such message"); break;
    }
}

static uint8_t truck_of(odo_can_msg_t m)
{
    return (m == ODO_CAN_MSG_WHEEL_COUNTS_B || m == ODO_CAN_MSG_POSE_XY_B || m == ODO_CAN_MSG_POSE_THETA_B)
               ? ODO_TRUCK_B
               : ODO_TRUCK_A;
}

/* The A and B variants of a per-truck message share one unpacker: map B to A. */
static odo_can_msg_t family(odo_can_msg_t m)
{
    switch (m) {
    case ODO_CAN_MSG_WHEEL_COUNTS_B: return ODO_CAN_MSG_WHEEL_COUNTS_A;
    case ODO_CAN_MSG_POSE_XY_B: return ODO_CAN_MSG_POSE_XY_A;
    case ODO_CAN_MSG_POSE_THETA_B: return ODO_CAN_MSG_POSE_THETA_A;
    case ODO_CAN_MSG_UNKNOWN:
    case ODO_CAN_MSG_WHEEL_COUNTS_A:
    case ODO_CAN_MSG_LINK_ROTARY:
    case ODO_CAN_MSG_LINK_LINEAR:
    case ODO_CAN_MSG_POSE_XY_A:
    case ODO_CAN_MSG_POSE_THETA_A:
    case ODO_CAN_MSG_IPEC_CORR:
    case ODO_CAN_MSG_STATUS:
    default: return m;
    }
}

static void pack_any(odo_can_msg_t m, const any_msg_t *a, odo_can_frame_t *f)
{
    switch (m) {
    case ODO_CAN_MSG_WHEEL_COUNTS_A:
    case ODO_CAN_MSG_WHEEL_COUNTS_B: odo_can_pack_wheel_counts(truck_of(m), &a->wheel, f); break;
    case ODO_CAN_MSG_LINK_ROTARY: odo_can_pack_link_rotary(&a->rotary, f); break;
    case ODO_CAN_MSG_LINK_LINEAR: odo_can_pack_link_linear(&a->linear, f); break;
    case ODO_CAN_MSG_POSE_XY_A:
    case ODO_CAN_MSG_POSE_XY_B: odo_can_pack_pose_xy(truck_of(m), &a->xy, f); break;
    case ODO_CAN_MSG_POSE_THETA_A:
    case ODO_CAN_MSG_POSE_THETA_B: odo_can_pack_pose_theta(truck_of(m), &a->theta, f); break;
    case ODO_CAN_MSG_IPEC_CORR: odo_can_pack_ipec_corr(&a->ipec, f); break;
    case ODO_CAN_MSG_STATUS: odo_can_pack_status(&a->status, f); break;
    case ODO_CAN_MSG_UNKNOWN:
    default: TEST_FAIL_MESSAGE("no such message"); break;
    }
}

/* The unpacker responsible for message m (the A/B pair share one). */
static odo_can_result_t unpack_any(odo_can_msg_t m, const odo_can_frame_t *f, uint8_t *truck, any_msg_t *a)
{
    switch (m) {
    case ODO_CAN_MSG_WHEEL_COUNTS_A:
    case ODO_CAN_MSG_WHEEL_COUNTS_B: return odo_can_unpack_wheel_counts(f, truck, &a->wheel);
    case ODO_CAN_MSG_LINK_ROTARY: return odo_can_unpack_link_rotary(f, &a->rotary);
    case ODO_CAN_MSG_LINK_LINEAR: return odo_can_unpack_link_linear(f, &a->linear);
    case ODO_CAN_MSG_POSE_XY_A:
    case ODO_CAN_MSG_POSE_XY_B: return odo_can_unpack_pose_xy(f, truck, &a->xy);
    case ODO_CAN_MSG_POSE_THETA_A:
    case ODO_CAN_MSG_POSE_THETA_B: return odo_can_unpack_pose_theta(f, truck, &a->theta);
    case ODO_CAN_MSG_IPEC_CORR: return odo_can_unpack_ipec_corr(f, &a->ipec);
    case ODO_CAN_MSG_STATUS: return odo_can_unpack_status(f, &a->status);
    case ODO_CAN_MSG_UNKNOWN:
    default: TEST_FAIL_MESSAGE("no such message"); return ODO_CAN_ERR_ID;
    }
}

/* Pack, check the frame header and the zeroed tail, unpack, compare. */
static void check_round_trip(odo_can_msg_t m, const any_msg_t *in)
{
    odo_can_frame_t f;
    memset(&f, 0xA5, sizeof f);
    pack_any(m, in, &f);
    const odo_can_msg_info_t *info = odo_can_msg_info(m);
    TEST_ASSERT_NOT_NULL(info);
    TEST_ASSERT_EQUAL_HEX32(info->id, f.id);
    TEST_ASSERT_EQUAL_UINT8(info->dlc, f.dlc);
    TEST_ASSERT_EQUAL_HEX8(0U, f.flags);
    for (unsigned i = f.dlc; i < 8U; i++) {
        TEST_ASSERT_EQUAL_HEX8_MESSAGE(0U, f.data[i], "byte beyond the DLC not zeroed");
    }
    TEST_ASSERT_EQUAL_INT(m, odo_can_classify(&f));

    any_msg_t out;
    memset(&out, 0, sizeof out);
    uint8_t truck = 0xEEU;
    TEST_ASSERT_EQUAL_INT(ODO_CAN_OK, unpack_any(m, &f, &truck, &out));
    TEST_ASSERT_EQUAL_MEMORY(in, &out, sizeof out);
    if (m == ODO_CAN_MSG_WHEEL_COUNTS_A || m == ODO_CAN_MSG_WHEEL_COUNTS_B || m == ODO_CAN_MSG_POSE_XY_A ||
        m == ODO_CAN_MSG_POSE_XY_B || m == ODO_CAN_MSG_POSE_THETA_A || m == ODO_CAN_MSG_POSE_THETA_B) {
        TEST_ASSERT_EQUAL_UINT8(truck_of(m), truck);
    } else {
        TEST_ASSERT_EQUAL_HEX8_MESSAGE(0xEEU, truck, "single-truck unpacker wrote a truck index");
    }
}

static void check_random_round_trips(odo_can_msg_t m)
{
    any_msg_t a;
    for (int i = 0; i < N_RANDOM; i++) {
        random_msg(m, &a);
        check_round_trip(m, &a);
    }
}

/* Every field of a message set to one extreme: lo (all bits clear / most negative) or hi. */
static void extreme_msg(odo_can_msg_t m, int which, any_msg_t *a)
{
    const uint32_t u32 = which == 0 ? 0U : UINT32_MAX;
    const uint8_t u8 = which == 0 ? 0U : UINT8_MAX;
    const int32_t s32 = which == 0 ? INT32_MIN : which == 1 ? INT32_MAX : -1;
    memset(a, 0, sizeof *a);
    switch (m) {
    case ODO_CAN_MSG_WHEEL_COUNTS_A:
    case ODO_CAN_MSG_WHEEL_COUNTS_B:
        a->wheel.left_count = u32 & ODO_CAN_COUNT_MASK;
        a->wheel.right_count = u32 & ODO_CAN_COUNT_MASK;
        a->wheel.seq = a->wheel.status = u8;
        break;
    case ODO_CAN_MSG_LINK_ROTARY:
        a->rotary.alpha_bam16 = a->rotary.beta_bam16 = (uint16_t)u32;
        a->rotary.seq = a->rotary.status = u8;
        break;
    case ODO_CAN_MSG_LINK_LINEAR:
        a->linear.length_um = u32;
        a->linear.seq = a->linear.status = u8;
        break;
    case ODO_CAN_MSG_POSE_XY_A:
    case ODO_CAN_MSG_POSE_XY_B: a->xy.x_10um = a->xy.y_10um = s32; break;
    case ODO_CAN_MSG_POSE_THETA_A:
    case ODO_CAN_MSG_POSE_THETA_B:
        a->theta.theta_bam = u32;
        a->theta.seq = a->theta.flags = u8;
        break;
    case ODO_CAN_MSG_IPEC_CORR: a->ipec.dtheta_a_bam = a->ipec.dtheta_b_bam = s32; break;
    case ODO_CAN_MSG_STATUS:
        a->status.faults = u32;
        a->status.seq = a->status.param_state = u8;
        a->status.rejected = (uint16_t)u32;
        break;
    case ODO_CAN_MSG_UNKNOWN:
    default: TEST_FAIL_MESSAGE("no such message"); break;
    }
}

/* ---- round trips ---- */

static void test_every_message_round_trips_random_raw_values(void)
{
    for (unsigned i = 0; i < ODO_CAN_MSG_COUNT; i++) {
        check_random_round_trips(all_msgs[i]);
    }
}

static void test_every_message_round_trips_its_extremes(void)
{
    any_msg_t a;
    for (unsigned i = 0; i < ODO_CAN_MSG_COUNT; i++) {
        for (int which = 0; which < 3; which++) {
            extreme_msg(all_msgs[i], which, &a);
            check_round_trip(all_msgs[i], &a);
        }
    }
}

static void test_signed_signals_keep_int32_extremes_in_each_half(void)
{
    /* X and Y (and DThetaA/B) are independent: opposite extremes must not bleed into each other. */
    const int32_t v[] = {INT32_MIN, INT32_MIN + 1, -1, 0, 1, INT32_MAX - 1, INT32_MAX};
    for (unsigned i = 0; i < sizeof v / sizeof v[0]; i++) {
        for (unsigned j = 0; j < sizeof v / sizeof v[0]; j++) {
            any_msg_t a;
            memset(&a, 0, sizeof a);
            a.xy.x_10um = v[i];
            a.xy.y_10um = v[j];
            check_round_trip(ODO_CAN_MSG_POSE_XY_A, &a);
            check_round_trip(ODO_CAN_MSG_POSE_XY_B, &a);
            memset(&a, 0, sizeof a);
            a.ipec.dtheta_a_bam = v[i];
            a.ipec.dtheta_b_bam = v[j];
            check_round_trip(ODO_CAN_MSG_IPEC_CORR, &a);
        }
    }
}

/* ---- wire layout pinned to literal bytes (the DBC's start bits, Intel order) ---- */

static void test_pose_xy_int32_min_is_little_endian_twos_complement(void)
{
    odo_msg_pose_xy_t m = {INT32_MIN, 5};
    odo_can_frame_t f;
    odo_can_pack_pose_xy(ODO_TRUCK_A, &m, &f);
    const uint8_t want[8] = {0x00, 0x00, 0x00, 0x80, 0x05, 0x00, 0x00, 0x00};
    TEST_ASSERT_EQUAL_HEX32(0x180U, f.id);
    TEST_ASSERT_EQUAL_HEX8_ARRAY(want, f.data, 8);
}

static void test_wheel_counts_layout_matches_dbc_bytes(void)
{
    odo_msg_wheel_counts_t m = {0x123456U, 0xABCDEFU, 0x42U, 0x0FU};
    odo_can_frame_t f;
    odo_can_pack_wheel_counts(ODO_TRUCK_B, &m, &f);
    const uint8_t want[8] = {0x56, 0x34, 0x12, 0xEF, 0xCD, 0xAB, 0x42, 0x0F};
    TEST_ASSERT_EQUAL_HEX32(0x111U, f.id);
    TEST_ASSERT_EQUAL_UINT8(8U, f.dlc);
    TEST_ASSERT_EQUAL_HEX8_ARRAY(want, f.data, 8);
}

static void test_six_byte_messages_layout_matches_dbc_bytes(void)
{
    odo_can_frame_t f;
    odo_msg_link_rotary_t r = {0x1234U, 0xFEDCU, 7U, 3U};
    odo_can_pack_link_rotary(&r, &f);
    const uint8_t want_r[8] = {0x34, 0x12, 0xDC, 0xFE, 0x07, 0x03, 0x00, 0x00};
    TEST_ASSERT_EQUAL_UINT8(6U, f.dlc);
    TEST_ASSERT_EQUAL_HEX8_ARRAY(want_r, f.data, 8);

    odo_msg_link_linear_t l = {1000000U, 9U, ODO_LINK_STATUS_LENGTH_VALID};
    odo_can_pack_link_linear(&l, &f);
    const uint8_t want_l[8] = {0x40, 0x42, 0x0F, 0x00, 0x09, 0x04, 0x00, 0x00};
    TEST_ASSERT_EQUAL_HEX8_ARRAY(want_l, f.data, 8);

    odo_msg_pose_theta_t t = {0x40000000UL, 0xFFU, 0x81U};
    odo_can_pack_pose_theta(ODO_TRUCK_B, &t, &f);
    const uint8_t want_t[8] = {0x00, 0x00, 0x00, 0x40, 0xFF, 0x81, 0x00, 0x00};
    TEST_ASSERT_EQUAL_HEX32(0x183U, f.id);
    TEST_ASSERT_EQUAL_HEX8_ARRAY(want_t, f.data, 8);
}

static void test_status_layout_matches_dbc_bytes(void)
{
    odo_msg_status_t m = {0x00020021UL, 0x10U, 5U, 0xBEEFU};
    odo_can_frame_t f;
    odo_can_pack_status(&m, &f);
    const uint8_t want[8] = {0x21, 0x00, 0x02, 0x00, 0x10, 0x05, 0xEF, 0xBE};
    TEST_ASSERT_EQUAL_HEX32(0x1A0U, f.id);
    TEST_ASSERT_EQUAL_HEX8_ARRAY(want, f.data, 8);
}

/* ---- truncation and truck selection ---- */

static void test_wheel_counts_send_only_the_low_24_bits(void)
{
    for (int i = 0; i < N_RANDOM; i++) {
        odo_msg_wheel_counts_t m = {rnd32() | 0x01000000UL, rnd32(), rnd8(), rnd8()};
        odo_can_frame_t f;
        odo_can_pack_wheel_counts(ODO_TRUCK_A, &m, &f);
        odo_msg_wheel_counts_t out;
        uint8_t truck = 0xEEU;
        TEST_ASSERT_EQUAL_INT(ODO_CAN_OK, odo_can_unpack_wheel_counts(&f, &truck, &out));
        TEST_ASSERT_EQUAL_UINT8(ODO_TRUCK_A, truck);
        TEST_ASSERT_EQUAL_HEX32(m.left_count & ODO_CAN_COUNT_MASK, out.left_count);
        TEST_ASSERT_EQUAL_HEX32(m.right_count & ODO_CAN_COUNT_MASK, out.right_count);
        /* the high byte of the counts must not leak into the neighbouring signals */
        TEST_ASSERT_EQUAL_UINT8(m.seq, out.seq);
        TEST_ASSERT_EQUAL_UINT8(m.status, out.status);
    }
    /* a 16-bit decoder's counter, zero-extended, wraps at 2^16 like the decoder does */
    odo_msg_wheel_counts_t m = {0xFFFFU, 0x0000U, 0U, 0U};
    odo_can_frame_t f;
    odo_can_pack_wheel_counts(ODO_TRUCK_A, &m, &f);
    const uint8_t want[8] = {0xFF, 0xFF, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00};
    TEST_ASSERT_EQUAL_HEX8_ARRAY(want, f.data, 8);
}

static void test_truck_index_selects_identifier(void)
{
    odo_can_frame_t f;
    odo_msg_wheel_counts_t w = {0};
    odo_msg_pose_xy_t xy = {0};
    odo_msg_pose_theta_t th = {0};
    odo_can_pack_wheel_counts(ODO_TRUCK_A, &w, &f);
    TEST_ASSERT_EQUAL_HEX32(ODO_CAN_ID_WHEEL_COUNTS_A, f.id);
    odo_can_pack_wheel_counts(ODO_TRUCK_B, &w, &f);
    TEST_ASSERT_EQUAL_HEX32(ODO_CAN_ID_WHEEL_COUNTS_B, f.id);
    odo_can_pack_pose_xy(ODO_TRUCK_A, &xy, &f);
    TEST_ASSERT_EQUAL_HEX32(ODO_CAN_ID_POSE_XY_A, f.id);
    odo_can_pack_pose_xy(ODO_TRUCK_B, &xy, &f);
    TEST_ASSERT_EQUAL_HEX32(ODO_CAN_ID_POSE_XY_B, f.id);
    odo_can_pack_pose_theta(ODO_TRUCK_A, &th, &f);
    TEST_ASSERT_EQUAL_HEX32(ODO_CAN_ID_POSE_THETA_A, f.id);
    odo_can_pack_pose_theta(ODO_TRUCK_B, &th, &f);
    TEST_ASSERT_EQUAL_HEX32(ODO_CAN_ID_POSE_THETA_B, f.id);
    /* documented fallback for a caller bug: anything but A is sent as B */
    odo_can_pack_pose_xy(7U, &xy, &f);
    TEST_ASSERT_EQUAL_HEX32(ODO_CAN_ID_POSE_XY_B, f.id);
}

/* ---- rejection: the output is never touched ---- */

/* Run the unpacker for message m on f with sentinel-filled outputs; expect `want` and, unless OK,
   untouched outputs. */
static void expect_unpack(odo_can_msg_t m, const odo_can_frame_t *f, odo_can_result_t want)
{
    any_msg_t out, before;
    memset(&out, 0x5A, sizeof out);
    memcpy(&before, &out, sizeof out);
    uint8_t truck = 0xEEU;
    TEST_ASSERT_EQUAL_INT(want, unpack_any(m, f, &truck, &out));
    if (want != ODO_CAN_OK) {
        TEST_ASSERT_EQUAL_MEMORY_MESSAGE(&before, &out, sizeof out, "output written on error");
        TEST_ASSERT_EQUAL_HEX8_MESSAGE(0xEEU, truck, "truck written on error");
    }
}

static void test_wrong_dlc_is_rejected_for_every_message_and_output_untouched(void)
{
    for (unsigned i = 0; i < ODO_CAN_MSG_COUNT; i++) {
        odo_can_msg_t m = all_msgs[i];
        any_msg_t a;
        random_msg(m, &a);
        odo_can_frame_t f;
        pack_any(m, &a, &f);
        const uint8_t right = odo_can_expected_dlc(m);
        TEST_ASSERT_EQUAL_UINT8(f.dlc, right);
        for (uint8_t dlc = 0U; dlc <= 15U; dlc++) {
            f.dlc = dlc;
            expect_unpack(m, &f, dlc == right ? ODO_CAN_OK : ODO_CAN_ERR_DLC);
            /* classify is by identifier only: a bad length is still this message */
            TEST_ASSERT_EQUAL_INT(m, odo_can_classify(&f));
        }
    }
}

static void test_unknown_identifiers_are_rejected_by_every_unpacker(void)
{
    const uint32_t ids[] = {0x000U, 0x10FU, 0x112U, 0x122U,          0x184U,      0x191U,
                            0x1A1U, 0x7FFU, 0x800U, 0x110U | 0x800U, 0x1FFFFFFFUL};
    for (unsigned k = 0; k < sizeof ids / sizeof ids[0]; k++) {
        odo_can_frame_t f;
        memset(&f, 0, sizeof f);
        f.id = ids[k];
        f.dlc = 8U;
        TEST_ASSERT_EQUAL_INT(ODO_CAN_MSG_UNKNOWN, odo_can_classify(&f));
        for (unsigned i = 0; i < ODO_CAN_MSG_COUNT; i++) {
            f.dlc = odo_can_expected_dlc(all_msgs[i]);
            expect_unpack(all_msgs[i], &f, ODO_CAN_ERR_ID);
        }
    }
}

static void test_each_unpacker_takes_only_its_own_identifiers(void)
{
    for (unsigned i = 0; i < ODO_CAN_MSG_COUNT; i++) {
        any_msg_t a;
        random_msg(all_msgs[i], &a);
        odo_can_frame_t f;
        pack_any(all_msgs[i], &a, &f);
        for (unsigned j = 0; j < ODO_CAN_MSG_COUNT; j++) {
            const bool shared = family(all_msgs[i]) == family(all_msgs[j]);
            expect_unpack(all_msgs[j], &f, shared ? ODO_CAN_OK : ODO_CAN_ERR_ID);
        }
    }
}

static void test_rtr_error_and_extended_frames_are_not_our_data_frames(void)
{
    const uint8_t flags[] = {ODO_CAN_FLAG_RTR, ODO_CAN_FLAG_ERR, ODO_CAN_FLAG_EXT, ODO_CAN_FLAG_EXT | ODO_CAN_FLAG_RTR};
    for (unsigned i = 0; i < ODO_CAN_MSG_COUNT; i++) {
        any_msg_t a;
        random_msg(all_msgs[i], &a);
        odo_can_frame_t f;
        pack_any(all_msgs[i], &a, &f);
        for (unsigned k = 0; k < sizeof flags / sizeof flags[0]; k++) {
            odo_can_frame_t g = f;
            g.flags = flags[k];
            TEST_ASSERT_EQUAL_INT(ODO_CAN_MSG_UNKNOWN, odo_can_classify(&g));
            expect_unpack(all_msgs[i], &g, ODO_CAN_ERR_FLAGS);
            /* flags are checked first: an RTR frame usually has no data and any DLC */
            g.dlc = 0U;
            expect_unpack(all_msgs[i], &g, ODO_CAN_ERR_FLAGS);
        }
    }
}

/* ---- bytes beyond the DLC ---- */

static void test_packers_zero_bytes_beyond_the_dlc(void)
{
    /* check_round_trip pre-fills the frame with 0xA5 and checks the tail; all-ones values put
       as many set bits next to the boundary as possible */
    any_msg_t a;
    for (unsigned i = 0; i < ODO_CAN_MSG_COUNT; i++) {
        extreme_msg(all_msgs[i], 1, &a);
        check_round_trip(all_msgs[i], &a);
    }
}

static void test_unpackers_ignore_garbage_beyond_the_dlc(void)
{
    for (unsigned i = 0; i < ODO_CAN_MSG_COUNT; i++) {
        any_msg_t a;
        random_msg(all_msgs[i], &a);
        odo_can_frame_t f;
        pack_any(all_msgs[i], &a, &f);
        for (unsigned b = f.dlc; b < 8U; b++) {
            f.data[b] = 0xFFU;
        }
        any_msg_t out;
        memset(&out, 0, sizeof out);
        uint8_t truck;
        TEST_ASSERT_EQUAL_INT(ODO_CAN_OK, unpack_any(all_msgs[i], &f, &truck, &out));
        TEST_ASSERT_EQUAL_MEMORY(&a, &out, sizeof out);
    }
}

/* ---- tables, classification, sequence numbers ---- */

static void test_layout_table_is_consistent(void)
{
    const uint32_t ids[ODO_CAN_MSG_COUNT] = {
        ODO_CAN_ID_WHEEL_COUNTS_A, ODO_CAN_ID_WHEEL_COUNTS_B, ODO_CAN_ID_LINK_ROTARY, ODO_CAN_ID_LINK_LINEAR,
        ODO_CAN_ID_POSE_XY_A,      ODO_CAN_ID_POSE_THETA_A,   ODO_CAN_ID_POSE_XY_B,   ODO_CAN_ID_POSE_THETA_B,
        ODO_CAN_ID_IPEC_CORR,      ODO_CAN_ID_STATUS};
    TEST_ASSERT_NULL(odo_can_msg_info(ODO_CAN_MSG_UNKNOWN));
    TEST_ASSERT_NULL(odo_can_msg_info((odo_can_msg_t)(ODO_CAN_MSG_COUNT + 1U)));
    TEST_ASSERT_EQUAL_UINT8(0U, odo_can_expected_dlc(ODO_CAN_MSG_UNKNOWN));
    TEST_ASSERT_EQUAL_UINT8(0U, odo_can_expected_dlc((odo_can_msg_t)(ODO_CAN_MSG_COUNT + 1U)));
    for (unsigned i = 0; i < ODO_CAN_MSG_COUNT; i++) {
        const odo_can_msg_info_t *info = odo_can_msg_info(all_msgs[i]);
        TEST_ASSERT_NOT_NULL(info);
        TEST_ASSERT_NOT_NULL(info->name);
        TEST_ASSERT_EQUAL_HEX32(ids[i], info->id);
        TEST_ASSERT_LESS_OR_EQUAL_HEX32(0x7FFU, info->id);
        TEST_ASSERT_EQUAL_UINT8(info->dlc, odo_can_expected_dlc(all_msgs[i]));
        TEST_ASSERT_TRUE(info->dlc == 6U || info->dlc == 8U);
        uint64_t used = 0U;
        for (unsigned s = 0; s < info->n_signals; s++) {
            const odo_can_signal_info_t *sig = &info->signals[s];
            TEST_ASSERT_NOT_NULL(sig->name);
            TEST_ASSERT_TRUE(sig->bit_len >= 1U && sig->bit_len <= 32U);
            TEST_ASSERT_TRUE_MESSAGE(sig->start_bit + sig->bit_len <= 8U * info->dlc, "signal beyond the DLC");
            const uint64_t bits = ((UINT64_C(1) << sig->bit_len) - 1U) << sig->start_bit;
            TEST_ASSERT_EQUAL_HEX64_MESSAGE(0U, used & bits, "signals overlap");
            used |= bits;
        }
        /* identifiers are unique */
        for (unsigned j = 0; j < i; j++) {
            TEST_ASSERT_NOT_EQUAL(odo_can_msg_info(all_msgs[j])->id, info->id);
        }
    }
}

static void test_seq_delta_wraps_at_256(void)
{
    TEST_ASSERT_EQUAL_UINT8(1U, odo_can_seq_delta(255U, 0U));
    TEST_ASSERT_EQUAL_UINT8(1U, odo_can_seq_delta(41U, 42U));
    TEST_ASSERT_EQUAL_UINT8(0U, odo_can_seq_delta(42U, 42U)); /* duplicate */
    TEST_ASSERT_EQUAL_UINT8(3U, odo_can_seq_delta(254U, 1U)); /* two samples lost */
    TEST_ASSERT_EQUAL_UINT8(255U, odo_can_seq_delta(1U, 0U));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_every_message_round_trips_random_raw_values);
    RUN_TEST(test_every_message_round_trips_its_extremes);
    RUN_TEST(test_signed_signals_keep_int32_extremes_in_each_half);
    RUN_TEST(test_pose_xy_int32_min_is_little_endian_twos_complement);
    RUN_TEST(test_wheel_counts_layout_matches_dbc_bytes);
    RUN_TEST(test_six_byte_messages_layout_matches_dbc_bytes);
    RUN_TEST(test_status_layout_matches_dbc_bytes);
    RUN_TEST(test_wheel_counts_send_only_the_low_24_bits);
    RUN_TEST(test_truck_index_selects_identifier);
    RUN_TEST(test_wrong_dlc_is_rejected_for_every_message_and_output_untouched);
    RUN_TEST(test_unknown_identifiers_are_rejected_by_every_unpacker);
    RUN_TEST(test_each_unpacker_takes_only_its_own_identifiers);
    RUN_TEST(test_rtr_error_and_extended_frames_are_not_our_data_frames);
    RUN_TEST(test_packers_zero_bytes_beyond_the_dlc);
    RUN_TEST(test_unpackers_ignore_garbage_beyond_the_dlc);
    RUN_TEST(test_layout_table_is_consistent);
    RUN_TEST(test_seq_delta_wraps_at_256);
    return UNITY_END();
}
