/// The simulator's C API for the C programs of this tree (odo-sim, odo-calib acceptance, odo-ipec,
/// odo-bench, the replay benchmark): a software-in-the-loop run with a callback after every
/// firmware tick that sees the truth and the firmware's own tick input and output, scenarios built
/// in memory, and the UMBmark statistics of a set of runs. Everything a tool needs from host_sim
/// is here or in odosim.h; host_sim/src and host_sim/run stay private (tests/lint/layers.py).
///
/// Unlike odosim.h (plain types for ctypes, installed with libodosim.so), this header speaks the
/// firmware's types (odo/odo_app.h) and hostlib's robot description (odo_robot.h: sim_robot_t,
/// its parser and its parameter block), so it serves programs built in this tree and is not
/// installed. Host C99; no globals; a scenario may be shared by concurrent runs (only read).
/// Errors: 0 on success, -1 with a message in err (NUL-terminated, at most errlen bytes).
#ifndef ODOSIM_SIL_H
#define ODOSIM_SIL_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "odo/odo_app.h"
#include "odo_robot.h"
#include "odosim/odosim.h"

#ifdef __cplusplus
extern "C" {
#endif

/// Most discrete bumps an experiment can be asked for (odo-sim --bumps, odo-ipec --bumps).
#define ODOSIM_MAX_BUMPS 64

/// The truth's effects: which catalog effects are on, their parameters, and the seed of the
/// roughness streams (host_sim/README.md, "Scenario"). Opaque; heap-allocated.
typedef struct odosim_scenario odosim_scenario_t;

/// A scenario with no effect on, every parameter at its default, seed 1; NULL when out of memory.
odosim_scenario_t *odosim_scenario_new(void);

/// Replace *sc by the scenario in a JSON file (host_sim/scenarios). On error *sc is unchanged.
int odosim_scenario_load(odosim_scenario_t *sc, const char *path, char *err, size_t errlen);

/// Switch an effect on and set one parameter (NULL param: only switch it on); truck_mask bit 0 is
/// truck A, bit 1 truck B. Unknown names and out-of-range values are refused.
int odosim_scenario_set(odosim_scenario_t *sc, const char *effect, const char *param, unsigned truck_mask, double value,
                        char *err, size_t errlen);

/// Every effect off and every parameter at its default again; the seed is kept.
void odosim_scenario_clear(odosim_scenario_t *sc);

/// The scenario's seed ("seed" of the file, default 1), and setting it.
uint64_t odosim_scenario_seed(const odosim_scenario_t *sc);
void odosim_scenario_set_seed(odosim_scenario_t *sc, uint64_t seed);

/// Release a scenario; NULL is a no-op.
void odosim_scenario_free(odosim_scenario_t *sc);

/// A true pose: truck centre (set trailer: axle centre) and the unwrapped heading, ccw positive.
typedef struct {
    double x_mm, y_mm;
    double theta_rad;
} odosim_pose_t;

/// The true linkage geometry (002 Eq. 11): theta_L from B to A, alpha = theta_A - theta_L,
/// beta = theta_B - theta_L, both in (-pi, pi] (set: beta 0), centre-to-centre l (set: the bar).
typedef struct {
    double theta_l_rad, alpha_rad, beta_rad, length_mm;
} odosim_link_geom_t;

/// One run of an experiment.
typedef struct {
    const sim_robot_t *robot;          ///< what the firmware believes (nominal + calibration)
    const odosim_scenario_t *scenario; ///< the truth's effects
    const char *experiment;            ///< "umbmark", "umbmark-ext", "straight-36m", "rect-7x4"
    int ccw;                           ///< direction of closed paths: 1 ccw, 0 cw
    int bumps;                         ///< discrete bumps, 0..ODOSIM_MAX_BUMPS; < 0: the experiment's default
    double bump_height_mm;             ///< height of each discrete bump (the papers' cables: 10)
    int ipec;                          ///< firmware ipec_mode: 0 off, 1 paper (per tick), 2 estimator
    uint64_t seed;                     ///< roughness etc. of this run (odosim_run_seed)
    unsigned run_index;                ///< 0-based within its direction
    double physics_dt_s;               ///< 0: 1 ms
} odosim_sil_config_t;

/// What the per-tick callback sees. Pointers are valid during the callback only.
typedef struct {
    double t_s;    ///< simulation time of the tick
    uint32_t tick; ///< firmware tick number, from 0
    odosim_pose_t truth[ODO_TRUCKS];
    odosim_link_geom_t link;
    const odo_tick_input_t *input;   ///< what the firmware read from the HAL (the sensor frames)
    const odo_tick_output_t *output; ///< what it published
    const odosim_event_t *events;    ///< discrete bumps first touched during this tick
    size_t n_events;
} odosim_tick_t;

typedef void (*odosim_tick_fn)(void *user, const odosim_tick_t *tick);

/// The return errors of one run (000 Eq. 3.1; absolute = truth of truck A, calculated = the
/// firmware's last published pose of truck A).
typedef struct {
    unsigned run;                                ///< run number within its direction, from 1
    int ccw;                                     ///< 1 ccw, 0 cw
    double x_abs_mm, y_abs_mm, theta_abs_deg;    ///< true (measured) return pose
    double x_calc_mm, y_calc_mm, theta_calc_deg; ///< what the firmware computed
    double ex_mm, ey_mm, etheta_deg;             ///< 000 Eq. 3.1: absolute - calculated
    double t_end_s;                              ///< simulated duration of the run
} odosim_return_t;

/// Statistics of a set of runs.
typedef struct {
    size_t n_cw, n_ccw;
    double cg_cw_mm[2], cg_ccw_mm[2]; ///< 000 Eq. 3.2
    double r_cw_mm, r_ccw_mm;         ///< 000 Eq. 3.3
    double emax_syst_mm;              ///< 000 Eq. 3.4: max(r_cw, r_ccw) over the directions run
    double sigma_mm;                  ///< pooled std deviation of positions about their cluster cg
    double sem_mm;                    ///< sigma / sqrt(runs per direction) (000 s. 6.3)
    double avg_abs_theta_err_deg;     ///< 004 Eq. 17 over all runs
} odosim_summary_t;

/// Run one experiment run: the world at the physics step under the path follower, the firmware's
/// own 40 ms loop on the sim HAL; `on_tick` (may be NULL) after every firmware tick. Deterministic:
/// same inputs, same bits. Fills *ret. Returns -1 for a bad configuration, a vehicle the experiment
/// does not support, or a run that does not finish in time. Cost: the run's length / physics step.
int odosim_sil_run(const odosim_sil_config_t *cfg, odosim_tick_fn on_tick, void *user, odosim_return_t *ret, char *err,
                   size_t errlen);

/// UMBmark statistics of n runs (000 Eqs. 3.2-3.4, 004 Eq. 17). Clusters with no run have cg 0 and
/// do not enter Emax,syst. O(n).
void odosim_summarise(const odosim_return_t *runs, size_t n, odosim_summary_t *out);

/// The experiments odosim_sil_run knows, NULL-terminated; static storage.
const char *const *odosim_experiment_names(void);

/// The effects catalog as JSON (what the diagnosis reads) or as the Markdown table of
/// host_sim/README.md. Returns 0, or -1 if the stream reported an error.
int odosim_effects_write_json(FILE *out);
int odosim_effects_write_markdown(FILE *out);

#ifdef __cplusplus
}
#endif
#endif
