/// See calib_core.h.
#include "calib_core.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define Q30 1073741824.0

int calib_umbmark(const returns_t *r, double side_mm, const odo_params_t *in_force, calib_method_t method,
                  calib_result_t *out, char *err, size_t errlen)
{
    memset(out, 0, sizeof *out);
    out->method = method;
    if (!(side_mm > 0.0) || !isfinite(side_mm)) {
        snprintf(err, errlen, "the side length must be a positive number of mm, not %g", side_mm);
        return -1;
    }
    if (side_mm * 1000.0 < ODO_UMB_MIN_SIDE_UM || side_mm * 1000.0 > ODO_UMB_MAX_SIDE_UM) {
        snprintf(err, errlen, "side %g mm: %s", side_mm, odo_umb_status_str(ODO_UMB_ERR_SIDE));
        return -1;
    }
    for (int d = 0; d < 2; ++d) {
        if (r->n[d] < 2) {
            snprintf(err, errlen,
                     "%zu %s run%s: UMBmark needs at least 2 runs in each direction (000 s. 3.5 "
                     "asks for 5)",
                     r->n[d], d ? "ccw" : "cw", r->n[d] == 1 ? "" : "s");
            return -1;
        }
    }
    static odo_umb_return_t u[2][RETURNS_MAX_RUNS];
    if (returns_to_umb(r, u, err, errlen) != 0) {
        return -1;
    }
    odo_umb_status_t s = odo_umb_stats(u[0], r->n[0], u[1], r->n[1], &out->st);
    if (s != ODO_UMB_OK) {
        snprintf(err, errlen, "statistics: %s", odo_umb_status_str(s));
        return -1;
    }
    const odo_truck_params_t *tp = &in_force->truck[0];
    out->ed_in_force = tp->ed_q30 / Q30;
    out->eb_in_force = tp->eb_q30 / Q30;
    const uint32_t side_um = (uint32_t)lround(side_mm * 1000.0);
    s = odo_umb_calibrate(&out->st, side_um, tp->wheelbase_nm, tp->ed_q30, tp->eb_q30, &out->paper);
    if (s != ODO_UMB_OK) {
        snprintf(err, errlen, "paper method: %s (alpha %.3f deg, beta %.3f deg)", odo_umb_status_str(s),
                 out->paper.alpha_bam * (180.0 / 2147483648.0), out->paper.beta_bam * (180.0 / 2147483648.0));
        return -1;
    }
    const double b_nom = tp->wheelbase_nm / 1e6;
    if (method == CALIB_PAPER) {
        out->ed_q30 = out->paper.ed_q30;
        out->eb_q30 = out->paper.eb_q30;
    } else {
        const umb_setup_t su = {side_um / 1000.0, b_nom, out->ed_in_force, out->eb_in_force};
        const double cg[2][2] = {{out->st.cg_x_um[0] / 1000.0, out->st.cg_y_um[0] / 1000.0},
                                 {out->st.cg_x_um[1] / 1000.0, out->st.cg_y_um[1] / 1000.0}};
        if (umb_exact_fit(&su, cg, out->paper.ed_q30 / Q30, (double)out->paper.b_actual_nm / 1e6, &out->fit, err,
                          errlen > UINT32_MAX ? UINT32_MAX : (unsigned)errlen) != 0) {
            return -1;
        }
        const double ed = out->fit.ed * Q30, eb = out->fit.b_mm / b_nom * Q30;
        const double lo = (double)(((int64_t)4 << 30) / 5), hi = 1.25 * Q30;
        if (!(ed >= lo && ed <= hi && eb >= lo && eb <= hi)) {
            snprintf(err, errlen, "exact method: Ed %.6f or Eb %.6f outside the parameter block's [0.8, 1.25]",
                     out->fit.ed, out->fit.b_mm / b_nom);
            return -1;
        }
        out->ed_q30 = (int32_t)llround(ed);
        out->eb_q30 = (int32_t)llround(eb);
    }
    (void)odo_umb_correction_factors(out->ed_q30, &out->cl_q30, &out->cr_q30);
    out->b_actual_mm = b_nom * (out->eb_q30 / Q30);
    return 0;
}

void calib_apply(const odo_params_t *in_force, const calib_result_t *c, odo_params_t *out)
{
    *out = *in_force;
    out->truck[0].ed_q30 = c->ed_q30;
    out->truck[0].eb_q30 = c->eb_q30;
}
