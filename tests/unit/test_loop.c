/// The imperative shell (firmware/app/odo_loop.c) on the scripted HAL backend (hal/test): every
/// side effect of a tick goes through hal.h, so a test drives each one and checks what the
/// firmware read and what it put on the bus.
#include <stdint.h>
#include <string.h>

#include "hal_test.h"
#include "odo/odo_app.h"
#include "odo/odo_params.h"
#include "odo/odo_status.h"
#include "odo_loop.h"
#include "unity.h"

void setUp(void) {}
void tearDown(void) {}

static odo_app_t app;
static hal_ctx_t hal;
static odo_tick_input_t in;
static odo_tick_output_t out;

static void boot(uint8_t vehicle, uint8_t hal_trucks, bool hal_link)
{
    odo_params_t p;
    odo_params_defaults(&p);
    p.vehicle = vehicle;
    TEST_ASSERT_EQUAL(ODO_PARAMS_OK, odo_app_init_params(&app, &p));
    hal_test_init(&hal, hal_trucks, hal_link);
}

/// A tick reads the clock and each truck's counters once, steps, and publishes every output
/// frame, in order, through hal_can_send.
static void tick_reads_the_hal_once_and_publishes_every_frame(void)
{
    boot(ODO_VEHICLE_SINGLE, 1U, false);
    hal.now_us = 40000U;
    hal_test_set_wheel(&hal, 0U, 1000U, 1000U, 24U, 1U);
    odo_loop_tick(&app, &hal, &in, &out);
    TEST_ASSERT_EQUAL_UINT64(40000U, in.t_us);
    TEST_ASSERT_TRUE(in.wheel[0].present);
    TEST_ASSERT_EQUAL_UINT32(1000U, in.wheel[0].left_raw);
    TEST_ASSERT_TRUE(out.n_frames > 0U);
    TEST_ASSERT_EQUAL_UINT32(out.n_frames, hal.n_tx);
    for (uint8_t k = 0U; k < out.n_frames; ++k) {
        TEST_ASSERT_EQUAL_UINT32(out.frames[k].id, hal.tx[k].id);
        TEST_ASSERT_EQUAL_MEMORY(out.frames[k].data, hal.tx[k].data, 8);
    }
    TEST_ASSERT_EQUAL_UINT32(0U, app.tx_dropped);
    /* The sample is delivered once: the next tick finds it missing and says so. */
    hal.now_us = 80000U;
    odo_loop_tick(&app, &hal, &in, &out);
    TEST_ASSERT_FALSE(in.wheel[0].present);
    TEST_ASSERT_TRUE((out.faults & ODO_FAULT_WHEEL_MISSING_A) != 0U);
}

/// A HAL that cannot read a truck's counters or the linkage: the tick still runs, with those
/// inputs marked absent (missing faults), never with stale data.
static void unreadable_counters_and_linkage_are_absent_not_stale(void)
{
    boot(ODO_VEHICLE_CLAPPER, 1U, false); /* a clapper's second truck and link: no hardware */
    hal.now_us = 40000U;
    in.wheel[1].present = true; /* garbage from a previous tick must not survive */
    in.link.rotary_present = in.link.linear_present = true;
    hal_test_set_wheel(&hal, 0U, 0U, 0U, 24U, 1U);
    odo_loop_tick(&app, &hal, &in, &out);
    TEST_ASSERT_TRUE(in.wheel[0].present);
    TEST_ASSERT_FALSE(in.wheel[1].present);
    TEST_ASSERT_FALSE(in.link.rotary_present);
    TEST_ASSERT_FALSE(in.link.linear_present);
    TEST_ASSERT_TRUE((out.faults & ODO_FAULT_WHEEL_MISSING_B) != 0U);
    TEST_ASSERT_TRUE((out.faults & ODO_FAULT_LINK_MISSING) != 0U);
}

/// Frames the HAL refuses are counted in tx_dropped, never retried, and the count saturates.
static void refused_frames_are_counted_and_the_count_saturates(void)
{
    boot(ODO_VEHICLE_SINGLE, 1U, false);
    hal.refuse_tx = 2U;
    hal_test_set_wheel(&hal, 0U, 0U, 0U, 24U, 1U);
    odo_loop_tick(&app, &hal, &in, &out);
    TEST_ASSERT_EQUAL_UINT32(2U, app.tx_dropped);
    TEST_ASSERT_EQUAL_UINT32(out.n_frames - 2U, hal.n_tx);
    app.tx_dropped = UINT32_MAX - 1U;
    hal.refuse_tx = 5U;
    hal.n_tx = 0U;
    hal_test_set_wheel(&hal, 0U, 0U, 0U, 24U, 2U);
    odo_loop_tick(&app, &hal, &in, &out);
    TEST_ASSERT_EQUAL_UINT32(UINT32_MAX, app.tx_dropped);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(tick_reads_the_hal_once_and_publishes_every_frame);
    RUN_TEST(unreadable_counters_and_linkage_are_absent_not_stale);
    RUN_TEST(refused_frames_are_counted_and_the_count_saturates);
    return UNITY_END();
}
