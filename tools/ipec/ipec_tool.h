/// Shared helpers of odo-ipec (tools/ipec): loading robots and scenarios, one SIL run.
#ifndef IPEC_TOOL_H
#define IPEC_TOOL_H

#include "odo_out.h"
#include <stdbool.h>
#include <stdint.h>

#include "effects.h"
#include "odo/odo_odometry.h"
#include "robot.h"
#include "sil.h"
#include "summary.h"

/// The data root: $ODO_SOURCE_DIR, the checkout, or PREFIX/share/odometry (tools/lib/data_dir.h).
const char *ipec_src_dir(void);

/// Robot (default host_sim/robots/<vehicle>.json) and scenario (NULL: no effects). 0 or -1 (printed).
int ipec_load(const char *vehicle, const char *robot_path, const char *scenario_path, sim_robot_t *robot,
              sim_scenario_t *sc);

/// One run, seeded as odo-sim seeds run `run` of direction ccw. ipec: 0 off, 1 paper, 2 estimator.
int ipec_run(const sim_robot_t *robot, const sim_scenario_t *sc, const char *experiment, int ccw, int bumps, int ipec,
             uint64_t seed, unsigned run, sim_tick_fn fn, void *user, sim_return_t *ret);

double ipec_bam_deg(int64_t bam);
double ipec_est_theta_deg(const odo_pose_t *p);

int ipec_cmd_goals(int argc, char **argv);

/// The robot's calibration fields (Ed, Eb, Es per truck; link biases) from a parameter block.
void ipec_apply_params(sim_robot_t *r, const odo_params_t *p);
/// Write a parameter block as JSON (params_json.h) into the output begun with odo_out_file_begin
/// and commit it (hostlib/odo_out.h); p NULL aborts it. 0 or -1 (message on stderr).
int ipec_write_params(odo_out_file_t *o, const odo_params_t *p);

/// 004 s. 5.1: Ed and Eb of both trucks from IPEC's corrections (odo_selfcal.h) over `runs` cw and
/// `runs` ccw runs of `exp`, then the same runs again with the estimate (the "after" figures).
typedef struct {
    odo_params_t params; ///< the robot's block with the estimated Ed, Eb
    double ed[ODO_TRUCKS], eb[ODO_TRUCKS];
    bool have_ed[ODO_TRUCKS], have_eb[ODO_TRUCKS];
    double straight_m[ODO_TRUCKS], turn_deg[ODO_TRUCKS];
    double corr_deg_per_m[ODO_TRUCKS], corr_deg_per_turn[ODO_TRUCKS];
    double one_sided_before_deg[ODO_TRUCKS], one_sided_after_deg[ODO_TRUCKS]; ///< systematic part
    double abs_before_deg[ODO_TRUCKS], abs_after_deg[ODO_TRUCKS];             ///< sum |correction|
} ipec_selfcal_t;
int ipec_selfcal(const sim_robot_t *robot, const sim_scenario_t *sc, const char *exp, unsigned runs, int ipec,
                 uint64_t seed, ipec_selfcal_t *out);

/// 004 s. 5.2: rotary-encoder and link-length biases in a calibration bay: an external reference
/// (the simulator's truth) gives the true alpha, beta and l while the clapper drives one UMBmark
/// square each way; the biases are the mean code-centre minus true angle over the ticks whose
/// code just changed (the spins sweep the codes), and the mean measured minus true length
/// (tools/ipec/README.md). Before/after: the far-mark error of a straight 18 m run and the UMBmark
/// return headings.
typedef struct {
    odo_params_t params;
    double alpha_bias_deg, beta_bias_deg, length_bias_mm;
    double rotary_before[2], rotary_after[2]; ///< far mark: etheta deg, ey / 100 mm
    double link_before[2], link_after[2];     ///< UMBmark return etheta deg, cw and ccw
    unsigned sweep_ticks[2];                  ///< code changes averaged, alpha and beta
} ipec_selfcal_link_t;
int ipec_selfcal_link(const sim_robot_t *robot, const sim_scenario_t *sc, const odo_params_t *start,
                      ipec_selfcal_link_t *out);

/// `odo-ipec selfcal` (link = 0) and `odo-ipec selfcal-link` (link = 1).
int ipec_cmd_selfcal(int argc, char **argv, int link);

#endif
