/// Cortex-M4 image entry: the boot self-test (odo_selftest.h, published in odo_board_selftest),
/// then the board (odo_board_port.h: clocks, counters, CAN, tick timer, watchdog), then the 40 ms
/// loop: wait for the tick, odo_board_tick (read, odo_app_step, publish), forever.
#include <stdint.h>
#include <string.h>

#include "odo/odo_app.h"
#include "odo_board.h"

volatile odo_board_selftest_t odo_board_selftest;
volatile odo_board_status_t odo_board_status;

// The whole application state is static: no heap, and the stack holds only call frames.
static odo_app_t s_app;
static odo_tick_input_t s_in;
static odo_tick_output_t s_out;
static hal_ctx_t s_hal;

int main(void)
{
    odo_board_selftest_t r;
    odo_selftest_run(&s_app, &s_in, &s_out, odo_param_block, sizeof odo_param_block, &r);
    odo_board_selftest = r;

    odo_board_init(&s_hal, &odo_board_config);
    odo_board_status = s_hal.status; // what came up, before the first tick (tests/target reads it)
    (void)odo_app_init(&s_app, odo_param_block, sizeof odo_param_block);
    for (;;) {
        if (!odo_board_wait_tick(&s_hal)) {
            // No tick timer: nothing can run on time. Stop here; the watchdog (if it started)
            // resets the part.
            for (;;) {
                __asm__ volatile("wfi");
            }
        }
        odo_board_tick(&s_hal, &s_app, &s_in, &s_out);
        odo_board_status = s_hal.status;
    }
}
