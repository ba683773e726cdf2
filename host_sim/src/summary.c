#include "summary.h"

#include <math.h>
#include <string.h>

void sim_return_errors(sim_return_t *r)
{
    r->ex_mm = r->x_abs_mm - r->x_calc_mm;
    r->ey_mm = r->y_abs_mm - r->y_calc_mm;
    r->etheta_deg = remainder(r->theta_abs_deg - r->theta_calc_deg, 360.0);
}

void sim_summarise(const sim_return_t *runs, size_t n, sim_summary_t *out)
{
    memset(out, 0, sizeof *out);
    double sum[2][2] = {{0, 0}, {0, 0}};
    size_t cnt[2] = {0, 0};
    for (size_t i = 0; i < n; ++i) {
        const int d = runs[i].ccw ? 1 : 0;
        sum[d][0] += runs[i].ex_mm;
        sum[d][1] += runs[i].ey_mm;
        cnt[d]++;
        out->avg_abs_theta_err_deg += fabs(runs[i].etheta_deg);
    }
    out->n_cw = cnt[0];
    out->n_ccw = cnt[1];
    double cg[2][2] = {{0, 0}, {0, 0}};
    for (int d = 0; d < 2; ++d) {
        if (cnt[d] > 0) {
            cg[d][0] = sum[d][0] / (double)cnt[d];
            cg[d][1] = sum[d][1] / (double)cnt[d];
        }
    }
    memcpy(out->cg_cw_mm, cg[0], sizeof out->cg_cw_mm);
    memcpy(out->cg_ccw_mm, cg[1], sizeof out->cg_ccw_mm);
    out->r_cw_mm = hypot(cg[0][0], cg[0][1]);
    out->r_ccw_mm = hypot(cg[1][0], cg[1][1]);
    out->emax_syst_mm = fmax(cnt[0] ? out->r_cw_mm : 0.0, cnt[1] ? out->r_ccw_mm : 0.0);
    /* Spread about each cluster's own centre, pooled with one degree of freedom lost per
     * cluster; SEM over the runs of one direction, as in 000 s. 6.3 (n = 5). */
    double ss = 0.0;
    for (size_t i = 0; i < n; ++i) {
        const int d = runs[i].ccw ? 1 : 0;
        ss += pow(runs[i].ex_mm - cg[d][0], 2) + pow(runs[i].ey_mm - cg[d][1], 2);
    }
    const size_t clusters = (size_t)(cnt[0] > 0) + (size_t)(cnt[1] > 0);
    if (n > clusters) {
        out->sigma_mm = sqrt(ss / (double)(n - clusters));
        const double per_dir = (double)n / (double)clusters;
        out->sem_mm = out->sigma_mm / sqrt(per_dir);
    }
    if (n > 0) {
        out->avg_abs_theta_err_deg /= (double)n;
    }
}
