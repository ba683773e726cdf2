/// Cortex-M4 image entry: boot the application on the parameter block in flash, run a short
/// synthetic self-test through the same odo_app_step every other target calls, publish the result
/// in odo_board_selftest, then idle.
///
/// There is no HAL backend for this board yet (hardware and qemu come in a later issue). When it
/// lands, the synthetic loop below is replaced by the 40 ms loop of firmware/app (hal_wheel_read,
/// hal_link_read -> odo_app_step -> hal_can_send) at the place marked "HAL loop".
#include <stdint.h>
#include <string.h>

#include "odo/odo_app.h"
#include "odo_board.h"

/// Wheel-count deltas of the synthetic run (truck A): straight, a left then a right turn, a stop.
/// Small enough for any valid parameter block's speed limit at a 40 ms tick.
static const int16_t k_synthetic_deltas[][2] = {
    {100, 100}, {100, 100}, {90, 110}, {90, 110}, {110, 90}, {110, 90}, {0, 0}, {100, 100},
};

#define ODO_BOARD_SYNTHETIC_TICKS (sizeof k_synthetic_deltas / sizeof k_synthetic_deltas[0])

/// Counters start just below the 24-bit wrap, so the run also crosses a counter wrap.
#define ODO_BOARD_SYNTHETIC_START_RAW 0x00FFFF80UL
#define ODO_BOARD_SYNTHETIC_BITS      24U
#define ODO_BOARD_TICK_US             40000U

volatile odo_board_selftest_t odo_board_selftest;

// The whole application state is static: no heap, and the stack holds only call frames.
static odo_app_t s_app;
static odo_tick_input_t s_in;
static odo_tick_output_t s_out;

int main(void)
{
    odo_board_selftest_t r;
    memset(&r, 0, sizeof r);

    r.params_status = (uint32_t)odo_app_init(&s_app, odo_param_block, sizeof odo_param_block);

    uint32_t mask = (1UL << ODO_BOARD_SYNTHETIC_BITS) - 1UL;
    uint32_t left_raw = ODO_BOARD_SYNTHETIC_START_RAW;
    uint32_t right_raw = ODO_BOARD_SYNTHETIC_START_RAW;
    for (uint32_t i = 0U; i < ODO_BOARD_SYNTHETIC_TICKS; ++i) {
        left_raw = (left_raw + (uint32_t)(int32_t)k_synthetic_deltas[i][0]) & mask;
        right_raw = (right_raw + (uint32_t)(int32_t)k_synthetic_deltas[i][1]) & mask;

        memset(&s_in, 0, sizeof s_in);
        s_in.t_us = (uint64_t)(i + 1U) * ODO_BOARD_TICK_US;
        s_in.wheel[ODO_TRUCK_A].present = true;
        s_in.wheel[ODO_TRUCK_A].bits = ODO_BOARD_SYNTHETIC_BITS;
        s_in.wheel[ODO_TRUCK_A].seq = (uint8_t)i;
        s_in.wheel[ODO_TRUCK_A].left_raw = left_raw;
        s_in.wheel[ODO_TRUCK_A].right_raw = right_raw;

        odo_app_step(&s_app, &s_in, &s_out);

        r.steps++;
        r.faults_or |= s_out.faults;
        r.frames += s_out.n_frames;
    }
    r.x_mm_q32 = s_out.pose[ODO_TRUCK_A].x_mm_q32;
    r.y_mm_q32 = s_out.pose[ODO_TRUCK_A].y_mm_q32;
    r.heading_bam = (uint32_t)(s_out.pose[ODO_TRUCK_A].heading_q64 >> 32);
    r.done = ODO_BOARD_SELFTEST_DONE;
    odo_board_selftest = r;

    // HAL loop: the 40 ms firmware/app loop over the cortexm HAL backend goes here.
    for (;;) {
        __asm__ volatile("wfi");
    }
}
