/// Reader of the UMBmark return-error contract (host_sim/README.md, DESIGN.md s. 4; 000 Eq. 3.1):
///
///   run,direction,x_abs_mm,y_abs_mm,theta_abs_deg,x_calc_mm,y_calc_mm,theta_calc_deg
///   1,cw,228.572,200.071,-6.3801,-0.001,-0.120,-0.0020
///
/// The header must be exactly that line. direction is cw or ccw (a straight experiment's "fwd"
/// is refused: UMBmark needs the square). Every number must be finite, positions within
/// +-RETURNS_MAX_ABS_MM and headings within +-RETURNS_MAX_ABS_DEG (beyond, the difference of two
/// of them loses the micrometre / micro-degree the calibration works in); blank lines and lines
/// starting with '#' are skipped. Errors name the file and line: "returns.csv:7: field 4
/// (y_abs_mm): 'nan' is not a finite number".
#ifndef CALIB_RETURNS_CSV_H
#define CALIB_RETURNS_CSV_H

#include <stddef.h>

#include "odo/odo_umbmark.h"

#define RETURNS_MAX_RUNS    ODO_UMB_MAX_RUNS
#define RETURNS_MAX_ABS_MM  1e9 ///< |x|, |y| (1000 km): doubles keep 1e-7 mm there
#define RETURNS_MAX_ABS_DEG 1e6 ///< |theta| (2778 turns): doubles keep 1e-10 deg there

typedef struct {
    size_t n[2];                       ///< cw, ccw
    double ex_mm[2][RETURNS_MAX_RUNS]; ///< 000 Eq. 3.1: absolute - calculated
    double ey_mm[2][RETURNS_MAX_RUNS];
    double etheta_deg[2][RETURNS_MAX_RUNS]; ///< wrapped to [-180, 180]
    unsigned run[2][RETURNS_MAX_RUNS];
} returns_t;

/// Read a returns.csv. Returns 0, or -1 with "<path>:<line>: <why>" in err. Does not require
/// runs in both directions (the caller decides; odo_umb_stats refuses fewer than 2).
int returns_read(const char *path, returns_t *r, char *err, size_t errlen);

/// Convert to the firmware module's integer form (um, udeg, rounded). Returns 0, or -1 with a
/// message if a value is outside odo_umbmark.h's input range.
int returns_to_umb(const returns_t *r, odo_umb_return_t out[2][RETURNS_MAX_RUNS], char *err, size_t errlen);

#endif
