/// Software in the loop: one run of an experiment. Every physics step (default 1 ms) the world
/// moves under the follower's wheel commands and the HCTL emulators see the wheels turn; every
/// firmware tick (40 ms) the firmware's own loop (odo_loop_tick on the sim HAL) reads the counters
/// through the emulated registers and publishes a pose, which the follower drives from.
/// Deterministic: same inputs and seed, same bits out.
#ifndef SIM_SIL_H
#define SIM_SIL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "effects.h"
#include "odo/odo_app.h"
#include "program.h"
#include "robot.h"
#include "summary.h"
#include "world.h"

typedef struct {
    const sim_robot_t *robot;       ///< what the firmware believes (nominal + calibration)
    const sim_scenario_t *scenario; ///< the truth's effects
    const char *experiment;         ///< sim_experiment_names
    int ccw;                        ///< direction of closed paths
    int bumps;                      ///< < 0: the experiment's default
    double bump_height_mm;
    int ipec;                   ///< firmware ipec_mode: 0 off, 1 paper (per tick), 2 estimator
    uint64_t seed;              ///< roughness etc. for this run
    unsigned run_index;         ///< 0-based within its direction
    double physics_dt_s;        ///< 0: SIM_WORLD_DEFAULT_DT_S
    const sim_hidden_t *hidden; ///< out-of-catalog truth (world.h); NULL: none (odo-gap blind)
} sim_run_config_t;

/// What the per-tick callback sees. Pointers are valid during the callback only.
typedef struct {
    double t_s;
    uint32_t tick;
    sim_pose_t truth[ODO_TRUCKS];
    sim_link_geom_t link;
    const odo_tick_input_t *input;   ///< what the firmware read from the HAL (the sensor frames)
    const odo_tick_output_t *output; ///< what it published
    const sim_bump_event_t *events;  ///< bump events that happened during this tick
    size_t n_events;
} sim_tick_t;

typedef void (*sim_tick_fn)(void *user, const sim_tick_t *tick);

/// Run one experiment run. Calls `on_tick` (may be NULL) after every firmware tick, fills *ret
/// with the return errors (000 Eq. 3.1; absolute = truth of truck A, calculated = the firmware's
/// last published pose of truck A). Returns 0, or -1 with a message in err (bad configuration,
/// a vehicle the experiment does not support yet, a run that does not finish in time).
int sim_run(const sim_run_config_t *cfg, sim_tick_fn on_tick, void *user, sim_return_t *ret, char *err, size_t errlen);

/// The seed of run `run` (0-based) of direction `ccw` for a base seed: odo-sim and libodosim
/// use it so a run is reproducible from either.
uint64_t sim_run_seed(uint64_t base, int ccw, unsigned run);

#endif
