/// Path follower: the navigation computer's stand-in. Every firmware tick it reads the pose the
/// firmware published (not the truth) and commands wheel speeds that drive the programmed path,
/// so dead-reckoning errors turn into real path errors as on a robot.
///
/// LINE: trapezoidal speed on the estimated distance to go, steering that brings cross-track
/// error and heading error to zero (critically damped, 1 rad/s). TURN: on-the-spot turn to an
/// absolute heading, ramped, landing within a count. ARC: constant curvature plus the same
/// feedback. PAUSE: stand still. Deterministic; no allocation.
#ifndef SIM_FOLLOWER_H
#define SIM_FOLLOWER_H

#include <stdbool.h>

#include "program.h"

typedef struct {
    const sim_program_t *prog;
    double   wheelbase_mm;  ///< nominal (what the navigation computer believes)
    double   dt_s;          ///< control period: the firmware tick
    size_t   seg;           ///< current segment
    double   seg_time_s;    ///< time spent in it
    double   v_mm_s;        ///< last commanded centre speed
    double   w_rad_s;       ///< last commanded turn rate
    double   max_wheel_mm_s;
} sim_follower_t;

void sim_follower_init(sim_follower_t *f, const sim_program_t *prog, double wheelbase_mm, double dt_s);

/// One control step from the estimated pose; writes wheel surface speeds [left, right] in mm/s.
/// Returns false once the program is finished (speeds are then zero).
bool sim_follower_step(sim_follower_t *f, double x_mm, double y_mm, double theta_rad,
                       double wheel_mm_s[2]);

#endif
