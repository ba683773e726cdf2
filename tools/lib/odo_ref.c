#include "odo_ref.h"

#include <math.h>
#include <stdlib.h>

double odo_ref_q30(int32_t v) { return (double)v / (double)(1L << 30); }

void odo_ref_init(odo_ref_t *r, const odo_truck_params_t *tp, uint8_t heading_form, double x0_mm, double y0_mm,
                  double theta0_rad)
{
    const double ed = odo_ref_q30(tp->ed_q30), eb = odo_ref_q30(tp->eb_q30), es = odo_ref_q30(tp->es_q30);
    const double dn_mm = tp->wheel_diameter_nm * 1e-6 / es; /* App. B: Dn* = Dn / Es */
    const double counts = tp->counts_per_rev_milli * 1e-3;
    const double cm = M_PI * dn_mm / counts;    /* Eq. 2.1 */
    r->k_mm[0] = 2.0 / (ed + 1.0) * cm;         /* Eqs. 6.33, 6.35 */
    r->k_mm[1] = 2.0 / (1.0 / ed + 1.0) * cm;   /* Eqs. 6.34, 6.35 */
    r->b_eff_mm = eb * tp->wheelbase_nm * 1e-6; /* Eqs. 2.8, 6.28 */
    r->scrub = odo_ref_q30(tp->scrub_q30);      /* odo_odometry.h */
    r->paper_form = heading_form == ODO_HEADING_PAPER;
    r->x_mm = x0_mm;
    r->y_mm = y0_mm;
    r->theta_rad = theta0_rad;
}

void odo_ref_step(odo_ref_t *r, int32_t d_left, int32_t d_right)
{
    const double s_l = r->k_mm[0] * d_left, s_r = r->k_mm[1] * d_right; /* Eq. 2.2 */
    const double u = 0.5 * (s_r + s_l);                                 /* Eq. 2.3 */
    double dth = (s_r - s_l) / r->b_eff_mm;                             /* Eq. 2.4 */
    /* Tyre scrub: m = 2 min(|dL|, |dR|) when both wheels turn the same way, v = |dL| + |dR|. */
    const long long al = llabs((long long)d_left), ar = llabs((long long)d_right);
    if (((d_left > 0 && d_right > 0) || (d_left < 0 && d_right < 0))) {
        const double m = 2.0 * (double)(al < ar ? al : ar), v = (double)(al + ar);
        dth *= 1.0 - r->scrub * m / v;
    }
    const double dir = r->paper_form ? r->theta_rad + dth : r->theta_rad + 0.5 * dth;
    r->x_mm += u * cos(dir); /* Eq. 2.6 */
    r->y_mm += u * sin(dir);
    r->theta_rad += dth; /* Eq. 2.5 */
}
