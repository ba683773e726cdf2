/// The HAL-driven tick (firmware/app/odo_loop.c) on the scripted test backend: reads counters
/// through the HAL, publishes through the HAL, and never loses a tick when sends are refused.
#include <check.h>

#include <string.h>

#include "check_support.h"
#include "hal_test.h"
#include "odo/odo_can.h"
#include "odo_loop.h"

static odo_app_t app;
static hal_ctx_t hal;
static odo_tick_output_t out;
static odo_tick_input_t loop_in;

static void boot(uint8_t vehicle)
{
    odo_params_t p;
    odo_params_defaults(&p);
    p.vehicle = vehicle;
    ck_assert_int_eq(ODO_PARAMS_OK, odo_app_init_params(&app, &p));
    hal_test_init(&hal, vehicle == ODO_VEHICLE_SINGLE ? 1U : 2U, vehicle != ODO_VEHICLE_SINGLE);
}

START_TEST(loop_reads_counters_through_the_hal_and_publishes_frames)
{
    boot(ODO_VEHICLE_SINGLE);
    hal_test_set_wheel(&hal, 0U, 0xFFFFF0U, 0xFFFFF0U, 24U, 0U);
    odo_loop_tick(&app, &hal, &loop_in, &out);
    hal.now_us = 40000U;
    hal_test_set_wheel(&hal, 0U, 0x000010U, 0x000010U, 24U, 1U); /* across the 24-bit wrap */
    odo_loop_tick(&app, &hal, &loop_in, &out);
    ck_assert_uint_eq(6U, hal.n_tx); /* 2 ticks x (pose xy, pose theta, status) */
    odo_msg_pose_xy_t xy;
    uint8_t truck;
    ck_assert_int_eq(ODO_CAN_OK, odo_can_unpack_pose_xy(&hal.tx[3], &truck, &xy));
    ck_assert_int_gt(xy.x_10um, 0); /* 32 counts forward, not 16 M backward */
    ck_assert_int_lt(xy.x_10um, 50);
}
END_TEST

START_TEST(absent_sample_is_reported_as_missing)
{
    boot(ODO_VEHICLE_SINGLE);
    odo_loop_tick(&app, &hal, &loop_in, &out); /* nothing set */
    ck_assert(out.faults & ODO_FAULT_WHEEL_MISSING_A);
}
END_TEST

START_TEST(refused_sends_are_counted_and_the_tick_is_not_lost)
{
    boot(ODO_VEHICLE_CLAPPER);
    hal.refuse_tx = 4U; /* like ENOBUFS on a busy bus */
    hal_test_set_wheel(&hal, 0U, 0U, 0U, 24U, 0U);
    hal_test_set_wheel(&hal, 1U, 0U, 0U, 24U, 0U);
    odo_loop_tick(&app, &hal, &loop_in, &out);
    ck_assert_uint_eq(4U, app.tx_dropped);
    ck_assert_uint_eq(2U, hal.n_tx);
    ck_assert_uint_eq(1U, app.ticks);
    hal_test_set_wheel(&hal, 0U, 50U, 50U, 24U, 1U);
    hal_test_set_wheel(&hal, 1U, 50U, 50U, 24U, 1U);
    odo_loop_tick(&app, &hal, &loop_in, &out);
    ck_assert_uint_eq(8U, hal.n_tx);
    ck_assert_uint_eq(2U, app.ticks);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("hal_loop");
    TCase *tc = tcase_create("core");
    tcase_add_test(tc, loop_reads_counters_through_the_hal_and_publishes_frames);
    tcase_add_test(tc, absent_sample_is_reported_as_missing);
    tcase_add_test(tc, refused_sends_are_counted_and_the_tick_is_not_lost);
    suite_add_tcase(s, tc);
    return ts_run_suite(s);
}
