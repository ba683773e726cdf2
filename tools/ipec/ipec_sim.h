/// odo-ipec's shared helpers: the data root, loading robots and scenarios, one SIL run, angle units.
/// Used by every odo-ipec command (odo-ipec.c, ipec_goals.c, ipec_selfcal.c); uses nothing of theirs.
#ifndef IPEC_SIM_H
#define IPEC_SIM_H

#include <stdint.h>

#include "odo/odo_odometry.h"
#include "odosim/odosim_sil.h"

/// The data root: $ODO_SOURCE_DIR, the checkout, or PREFIX/share/odometry (hostlib/odo_data_dir.h).
const char *ipec_src_dir(void);

/// Robot (default host_sim/robots/<vehicle>.json) and scenario (NULL: *sc's effects cleared; sc
/// comes from odosim_scenario_new). 0 or -1 (printed).
int ipec_load(const char *vehicle, const char *robot_path, const char *scenario_path, sim_robot_t *robot,
              odosim_scenario_t *sc);

/// One run, seeded as odo-sim seeds run `run` of direction ccw. ipec: 0 off, 1 paper, 2 estimator.
int ipec_run(const sim_robot_t *robot, const odosim_scenario_t *sc, const char *experiment, int ccw, int bumps,
             int ipec, uint64_t seed, unsigned run, odosim_tick_fn fn, void *user, odosim_return_t *ret);

double ipec_bam_deg(int64_t bam);
double ipec_est_theta_deg(const odo_pose_t *p);

#endif
