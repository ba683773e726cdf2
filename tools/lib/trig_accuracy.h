/// Accuracy of the firmware trigonometry (odo_sin_q30, odo_cos_q30, odo_atan2_bam) against libm in
/// double precision, for odo-bench. The same measurement as tests/unit/test_trig.c, which asserts
/// the bounds; this one only reports the figures. Host-only.
#ifndef TRIG_ACCURACY_H
#define TRIG_ACCURACY_H

#include <stdint.h>

/// Maximum absolute errors over n random inputs per function plus a fixed edge set (every octant
/// boundary +-3 BAM for sin/cos; axes, diagonals, INT64_MIN/INT64_MAX mixes, unit vectors and
/// y = x +- 1 at large x for atan2).
///
/// seed                   splitmix64 seed; the same seed gives the same figures on every host.
/// n                      random inputs per function; 0 measures the edge set only.
/// sincos_max_abs_err     out: max |odo_sin_q30/2^30 - sin| and |odo_cos_q30/2^30 - cos| together,
///                        unitless. May be NULL to skip sin/cos.
/// atan2_max_abs_err_rad  out: max |odo_atan2_bam - atan2| in radians, the difference wrapped into
///                        [-pi, pi]. May be NULL to skip atan2.
///
/// Cost: about 3n libm calls for each measured family. Pure apart from the outputs; reentrant.
void odo_trig_accuracy(uint64_t seed, uint32_t n, double *sincos_max_abs_err, double *atan2_max_abs_err_rad);

#endif
