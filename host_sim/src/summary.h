/// Return-error statistics of a set of runs: UMBmark centres of gravity and Emax,syst
/// (000 Eqs. 3.1-3.4), the spread (standard deviation and standard error of the mean, 000 s. 6.3)
/// and the average absolute orientation error (004 Eq. 17). Host-side double precision.
#ifndef SIM_SUMMARY_H
#define SIM_SUMMARY_H

#include <stddef.h>

#include "odosim/odosim_sil.h"

/// The public shapes (host_sim/include/odosim/odosim_sil.h) are the runner's own.
typedef odosim_return_t sim_return_t;
typedef odosim_summary_t sim_summary_t;

/// Fill `e*` of a return from its absolute and calculated poses (000 Eq. 3.1; theta wrapped to
/// [-180, 180)).
void sim_return_errors(sim_return_t *r);

/// Statistics of n runs. Clusters with no run have cg 0 and do not enter Emax,syst.
void sim_summarise(const sim_return_t *runs, size_t n, sim_summary_t *out);

#endif
