/// One UMBmark calibration from return errors: the statistics and the paper's answer from the
/// firmware module (odo/odo_umbmark.h), and the exact fit (umb_exact.h) started from it.
/// Shared by `odo-calib umbmark` and `odo-calib acceptance`. Host C; reentrant.
#ifndef CALIB_CORE_H
#define CALIB_CORE_H

#include <stdbool.h>
#include <stddef.h>

#include "odo/odo_params.h"
#include "odo/odo_umbmark.h"
#include "returns_csv.h"
#include "umb_exact.h"

typedef enum { CALIB_PAPER = 0, CALIB_EXACT = 1 } calib_method_t;

typedef struct {
    calib_method_t method;
    odo_umb_stats_t st;
    odo_umb_calib_t paper;  ///< always computed (the start of the exact fit)
    umb_fit_t fit;          ///< method exact only
    int32_t ed_q30, eb_q30; ///< the new parameter block values of the chosen method
    int32_t cl_q30, cr_q30;
    double b_actual_mm;
    double ed_in_force, eb_in_force;
} calib_result_t;

/// Calibrate truck A of `in_force` (the parameter block the robot ran the test with) from the
/// return errors. side_mm: L. Returns 0, or -1 with a message in err (too few runs, a side <= 0,
/// a result outside the parameter block's range, a fit that fails).
int calib_umbmark(const returns_t *r, double side_mm, const odo_params_t *in_force, calib_method_t method,
                  calib_result_t *out, char *err, size_t errlen);

/// in_force with truck A's ed/eb replaced by the result.
void calib_apply(const odo_params_t *in_force, const calib_result_t *c, odo_params_t *out);

#endif
