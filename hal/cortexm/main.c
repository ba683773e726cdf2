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

volatile odo_board_selftest_t odo_board_selftest;

// The whole application state is static: no heap, and the stack holds only call frames.
static odo_app_t s_app;
static odo_tick_input_t s_in;
static odo_tick_output_t s_out;

int main(void)
{
    odo_board_selftest_t r;
    odo_selftest_run(&s_app, &s_in, &s_out, odo_param_block, sizeof odo_param_block, &r);
    odo_board_selftest = r;

    // HAL loop: the 40 ms firmware/app loop over the cortexm HAL backend goes here.
    for (;;) {
        __asm__ volatile("wfi");
    }
}
