/// Return-error statistics of a set of runs: UMBmark centres of gravity and Emax,syst
/// (000 Eqs. 3.1-3.4), the spread (standard deviation and standard error of the mean, 000 s. 6.3)
/// and the average absolute orientation error (004 Eq. 17). Host-side double precision.
#ifndef SIM_SUMMARY_H
#define SIM_SUMMARY_H

#include <stddef.h>

typedef struct {
    unsigned run;                                ///< run number within its direction, from 1
    int ccw;                                     ///< 1 ccw, 0 cw
    double x_abs_mm, y_abs_mm, theta_abs_deg;    ///< true (measured) return pose
    double x_calc_mm, y_calc_mm, theta_calc_deg; ///< what the firmware computed
    double ex_mm, ey_mm, etheta_deg;             ///< 000 Eq. 3.1: absolute - calculated
    double t_end_s;                              ///< simulated duration of the run
} sim_return_t;

typedef struct {
    size_t n_cw, n_ccw;
    double cg_cw_mm[2], cg_ccw_mm[2]; ///< 000 Eq. 3.2
    double r_cw_mm, r_ccw_mm;         ///< 000 Eq. 3.3
    double emax_syst_mm;              ///< 000 Eq. 3.4: max(r_cw, r_ccw) over the directions run
    double sigma_mm;                  ///< pooled std deviation of positions about their cluster cg
    double sem_mm;                    ///< sigma / sqrt(runs per direction) (000 s. 6.3)
    double avg_abs_theta_err_deg;     ///< 004 Eq. 17 over all runs
} sim_summary_t;

/// Fill `e*` of a return from its absolute and calculated poses (000 Eq. 3.1; theta wrapped to
/// [-180, 180)).
void sim_return_errors(sim_return_t *r);

/// Statistics of n runs. Clusters with no run have cg 0 and do not enter Emax,syst.
void sim_summarise(const sim_return_t *runs, size_t n, sim_summary_t *out);

#endif
