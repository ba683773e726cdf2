/// The boot self-test of the Cortex-M4 image, as portable C: a short synthetic run through
/// odo_app_init/odo_app_step (the same entry points every other target calls) whose result the
/// image publishes in RAM (odo_board_selftest) and a host program (tests/target/selftest_host.c)
/// computes from the same parameter block, so tests/target can compare the two field by field.
#ifndef ODO_SELFTEST_H
#define ODO_SELFTEST_H

#include <stddef.h>
#include <stdint.h>

#include "odo/odo_app.h"

#ifdef __cplusplus
extern "C" {
#endif

/// Result of the boot self-test. Layout (little-endian, 40 bytes) is read by
/// tests/target/run_target_test.py from the image's RAM: keep the two in step.
typedef struct {
    uint32_t params_status; ///< odo_params_status_t of odo_app_init on the parameter block (0: OK)
    uint32_t steps;         ///< synthetic ticks run through odo_app_step
    uint32_t faults_or;     ///< OR of the ODO_FAULT_* bits every step raised
    uint32_t frames;        ///< output frames produced in total
    int64_t x_mm_q32;       ///< final pose of truck A (odo_pose_t units)
    int64_t y_mm_q32;
    uint32_t heading_bam; ///< top 32 bits of the final heading_q64 of truck A
    uint32_t done;        ///< ODO_BOARD_SELFTEST_DONE when the above are complete
} odo_board_selftest_t;

#define ODO_BOARD_SELFTEST_DONE 0x600DF00DU

/// Boot *app on block[0..len) (odo_app_init: defaults and a fault flag if the block is bad), run
/// ODO_SELFTEST_TICKS synthetic ticks of truck A (straight, left and right turns, a stop, and a
/// 24-bit counter wrap) and fill *r. *app is left booted on the block with the synthetic run in
/// its state: the caller re-initialises it before real use. *in and *out are scratch (static on
/// the target, so the stack holds only call frames). Constant time; no side effects elsewhere.
void odo_selftest_run(odo_app_t *app, odo_tick_input_t *in, odo_tick_output_t *out, const uint8_t *block, size_t len,
                      odo_board_selftest_t *r);

#ifdef __cplusplus
}
#endif
#endif
