/// The boot self-test (odo_selftest.h). Portable C99: built into the image and, unchanged, into
/// the host program that the target test compares against.
#include "odo_selftest.h"

#include <string.h>

/// Wheel-count deltas of the synthetic run (truck A): straight, a left then a right turn, a stop.
/// Small enough for any valid parameter block's speed limit at a 40 ms tick.
static const int16_t k_synthetic_deltas[][2] = {
    {100, 100}, {100, 100}, {90, 110}, {90, 110}, {110, 90}, {110, 90}, {0, 0}, {100, 100},
};

#define ODO_SELFTEST_TICKS (sizeof k_synthetic_deltas / sizeof k_synthetic_deltas[0])

/// Counters start just below the 24-bit wrap, so the run also crosses a counter wrap.
#define ODO_SELFTEST_START_RAW 0x00FFFF80U
#define ODO_SELFTEST_BITS      24U
#define ODO_SELFTEST_TICK_US   40000U

void odo_selftest_run(odo_app_t *app, odo_tick_input_t *in, odo_tick_output_t *out, const uint8_t *block, size_t len,
                      odo_board_selftest_t *r)
{
    memset(r, 0, sizeof *r);
    r->params_status = (uint32_t)odo_app_init(app, block, len);

    const uint32_t mask = (1U << ODO_SELFTEST_BITS) - 1U;
    uint32_t left_raw = ODO_SELFTEST_START_RAW;
    uint32_t right_raw = ODO_SELFTEST_START_RAW;
    for (uint32_t i = 0U; i < ODO_SELFTEST_TICKS; ++i) {
        const uint32_t dl = (uint32_t)(int32_t)k_synthetic_deltas[i][0];
        const uint32_t dr = (uint32_t)(int32_t)k_synthetic_deltas[i][1];
        left_raw = (uint32_t)(left_raw + dl) & mask;
        right_raw = (uint32_t)(right_raw + dr) & mask;

        memset(in, 0, sizeof *in);
        in->t_us = (uint64_t)(i + 1U) * ODO_SELFTEST_TICK_US;
        in->wheel[ODO_TRUCK_A].present = true;
        in->wheel[ODO_TRUCK_A].bits = ODO_SELFTEST_BITS;
        in->wheel[ODO_TRUCK_A].seq = (uint8_t)i;
        in->wheel[ODO_TRUCK_A].left_raw = left_raw;
        in->wheel[ODO_TRUCK_A].right_raw = right_raw;

        odo_app_step(app, in, out);

        r->steps++;
        r->faults_or |= out->faults;
        r->frames += out->n_frames;
    }
    r->x_mm_q32 = out->pose[ODO_TRUCK_A].x_mm_q32;
    r->y_mm_q32 = out->pose[ODO_TRUCK_A].y_mm_q32;
    r->heading_bam = (uint32_t)(out->pose[ODO_TRUCK_A].heading_q64 >> 32);
    r->done = ODO_BOARD_SELFTEST_DONE;
}
