/// Double-precision reference odometry (000 Eqs. 2.1-2.6, 6.28, 6.33-6.35, App. B, and the
/// tyre-scrub factor on Eq. 2.4 of odo_odometry.h), written straight from the equations with no
/// fixed-point tricks. The firmware is checked against it; never the reverse.
#ifndef ODO_REF_H
#define ODO_REF_H

#include <stdint.h>

#include "odo/odo_params.h"

typedef struct {
    double x_mm, y_mm, theta_rad; ///< pose; theta unwrapped
    double k_mm[2];               ///< distance per count, cL/R * cm
    double b_eff_mm;              ///< Eb * b
    double scrub;                 ///< k: dtheta *= 1 - k m / v (odo_odometry.h)
    int paper_form;               ///< 1: advance along the new heading (Eq. 2.6); 0: midpoint
} odo_ref_t;

/// Set up from truck parameters; pose at (x0, y0, theta0).
void odo_ref_init(odo_ref_t *r, const odo_truck_params_t *tp, uint8_t heading_form, double x0_mm, double y0_mm,
                  double theta0_rad);

/// One step from signed count deltas (forward positive).
void odo_ref_step(odo_ref_t *r, int32_t d_left, int32_t d_right);

/// Q30 ratio to double.
double odo_ref_q30(int32_t v);

#endif
