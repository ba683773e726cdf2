/// Fixed-point firmware odometry against the double-precision reference, fed identical counts.
/// Shared by the property test (tests/host/test_odometry_reference.c) and odo-bench, so the
/// benchmark prints exactly what the test asserts.
#ifndef ODO_REFCHECK_H
#define ODO_REFCHECK_H

#include <stdint.h>

#include "odo/odo_params.h"

typedef struct {
    double pos_err_mm;      ///< |firmware - reference| position at the end
    double heading_err_rad; ///< |firmware - reference| heading at the end, wrapped to [0, pi]
    double max_pos_err_mm;  ///< largest position difference seen along the way
    double distance_mm;     ///< path length driven
    uint32_t ticks;
    uint32_t wraps; ///< counter wraparounds crossed (both wheels)
} odo_refcheck_t;

/// Drive random mixed paths (odo_synth) for `distance_mm`, with counters of `bits` width
/// starting just below a wrap, through odo_truck_step (firmware) and odo_ref_step (reference).
/// `model_params` feeds the firmware, `ref_params` the reference (equal for a fair comparison;
/// tests pass different ones to show the check is sensitive). Returns 0, or -1 if the firmware
/// refused the parameters.
int odo_refcheck_run(uint64_t seed, uint8_t bits, uint8_t heading_form, const odo_truck_params_t *model_params,
                     const odo_truck_params_t *ref_params, double distance_mm, odo_refcheck_t *out);

#endif
