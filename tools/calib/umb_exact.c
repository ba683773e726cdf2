/// The exact UMBmark fit. See umb_exact.h.
#include "umb_exact.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/// Advance a pose by one exact circular arc of length ds turning by dth.
static void arc(double pose[3], double ds, double dth)
{
    const double chord = fabs(dth) < 1e-12 ? ds : 2.0 * (ds / dth) * sin(dth / 2.0);
    pose[0] += chord * cos(pose[2] + dth / 2.0);
    pose[1] += chord * sin(pose[2] + dth / 2.0);
    pose[2] += dth;
}

void umb_exact_forward(const umb_setup_t *s, double ed_true, double b_true_mm, int ccw, double out[3])
{
    /* 000 Eqs. 6.31-6.34: true and believed diameters relative to the same mean. */
    const double gl = (2.0 / (ed_true + 1.0)) / (2.0 / (s->ed_fw + 1.0));
    const double gr = (2.0 * ed_true / (ed_true + 1.0)) / (2.0 * s->ed_fw / (s->ed_fw + 1.0));
    const double b_believed = s->b_nominal_mm * s->eb_fw;
    const double phi = ccw ? M_PI / 2.0 : -M_PI / 2.0;
    double pose[3] = {0.0, 0.0, 0.0};
    for (int leg = 0; leg < 4; ++leg) {
        /* Straight leg as believed: both wheels L. */
        const double l_l = gl * s->side_mm, l_r = gr * s->side_mm;
        arc(pose, (l_l + l_r) / 2.0, (l_r - l_l) / b_true_mm);
        /* On-the-spot turn as believed: wheels +-phi b_believed / 2. */
        const double t_r = gr * phi * b_believed / 2.0, t_l = -gl * phi * b_believed / 2.0;
        arc(pose, (t_l + t_r) / 2.0, (t_r - t_l) / b_true_mm);
    }
    out[0] = pose[0];
    out[1] = pose[1];
    out[2] = remainder(pose[2], 2.0 * M_PI);
}

static void residuals(const umb_setup_t *s, const double cg[2][2], double ed, double b, double r[4])
{
    for (int d = 0; d < 2; ++d) {
        double e[3];
        umb_exact_forward(s, ed, b, d, e);
        r[2 * d] = e[0] - cg[d][0];
        r[2 * d + 1] = e[1] - cg[d][1];
    }
}

static double sumsq(const double r[4]) { return r[0] * r[0] + r[1] * r[1] + r[2] * r[2] + r[3] * r[3]; }

int umb_exact_fit(const umb_setup_t *s, const double cg[2][2], double ed0, double b0_mm, umb_fit_t *out, char *err,
                  unsigned errlen)
{
    memset(out, 0, sizeof *out);
    if (!isfinite(ed0) || !isfinite(b0_mm) || ed0 <= 0.0 || b0_mm <= 0.0 || !(s->side_mm > 0.0) ||
        !(s->b_nominal_mm > 0.0)) {
        snprintf(err, errlen, "exact fit: start point or geometry not finite and positive");
        return -1;
    }
    double p[2] = {ed0, b0_mm};
    const double hstep[2] = {1e-7, 1e-4 * s->b_nominal_mm / 340.0};
    double r[4];
    residuals(s, cg, p[0], p[1], r);
    double cost = sumsq(r);
    double lambda = 1e-3;
    double jac[4][2];
    int it;
    for (it = 0; it < 200; ++it) {
        for (int k = 0; k < 2; ++k) {
            double pp[2] = {p[0], p[1]}, pm[2] = {p[0], p[1]}, rp[4], rm[4];
            pp[k] += hstep[k];
            pm[k] -= hstep[k];
            residuals(s, cg, pp[0], pp[1], rp);
            residuals(s, cg, pm[0], pm[1], rm);
            for (int i = 0; i < 4; ++i) {
                jac[i][k] = (rp[i] - rm[i]) / (2.0 * hstep[k]);
            }
        }
        double a[2][2] = {{0, 0}, {0, 0}}, g[2] = {0, 0};
        for (int i = 0; i < 4; ++i) {
            for (int k = 0; k < 2; ++k) {
                g[k] += jac[i][k] * r[i];
                for (int m = 0; m < 2; ++m) {
                    a[k][m] += jac[i][k] * jac[i][m];
                }
            }
        }
        bool stepped = false;
        double dp[2] = {0, 0};
        for (int tries = 0; tries < 30 && !stepped; ++tries) {
            const double m00 = a[0][0] * (1.0 + lambda), m11 = a[1][1] * (1.0 + lambda), m01 = a[0][1];
            const double det = m00 * m11 - m01 * m01;
            if (!(fabs(det) > 0.0)) {
                lambda *= 10.0;
                continue;
            }
            dp[0] = -(m11 * g[0] - m01 * g[1]) / det;
            dp[1] = -(-m01 * g[0] + m00 * g[1]) / det;
            double rn[4];
            residuals(s, cg, p[0] + dp[0], p[1] + dp[1], rn);
            const double cn = sumsq(rn);
            if (cn <= cost) {
                p[0] += dp[0];
                p[1] += dp[1];
                memcpy(r, rn, sizeof r);
                cost = cn;
                lambda = fmax(lambda / 10.0, 1e-12);
                stepped = true;
            } else {
                lambda *= 10.0;
            }
        }
        if (!(p[0] >= 0.5 && p[0] <= 2.0 && p[1] >= 0.2 * s->b_nominal_mm && p[1] <= 5.0 * s->b_nominal_mm)) {
            snprintf(err, errlen,
                     "exact fit left the physical range (Ed %.6g, b %.6g mm): the return "
                     "errors are not those of a differential drive with Ed and b errors",
                     p[0], p[1]);
            return -1;
        }
        if (!stepped || (fabs(dp[0]) < 1e-13 && fabs(dp[1]) < 1e-10)) {
            out->converged = true;
            break;
        }
    }
    /* Identifiability: singular values of the column-normalised Jacobian at the solution. */
    double n0 = 0, n1 = 0, c01 = 0;
    for (int i = 0; i < 4; ++i) {
        n0 += jac[i][0] * jac[i][0];
        n1 += jac[i][1] * jac[i][1];
        c01 += jac[i][0] * jac[i][1];
    }
    if (n0 > 0.0 && n1 > 0.0) {
        const double c = c01 / sqrt(n0 * n1); /* cosine between the columns */
        out->sv_max = sqrt(1.0 + fabs(c));
        out->sv_min = sqrt(fmax(0.0, 1.0 - fabs(c)));
    }
    out->identifiable = out->sv_max > 0.0 && out->sv_min / out->sv_max > 1e-6;
    out->ed = p[0];
    out->b_mm = p[1];
    out->residual_mm = sqrt(cost / 4.0);
    out->iterations = it + 1;
    return 0;
}
