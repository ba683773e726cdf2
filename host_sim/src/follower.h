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
    double wheelbase_mm; ///< nominal (what the navigation computer believes)
    double dt_s;         ///< control period: the firmware tick
    size_t seg;          ///< current segment
    double seg_time_s;   ///< time spent in it
    double v_mm_s;       ///< last commanded centre speed
    double w_rad_s;      ///< last commanded turn rate
    double max_wheel_mm_s;
} sim_follower_t;

void sim_follower_init(sim_follower_t *f, const sim_program_t *prog, double wheelbase_mm, double dt_s);

/// One control step from the estimated pose; writes wheel surface speeds [left, right] in mm/s.
/// Returns false once the program is finished (speeds are then zero).
bool sim_follower_step(sim_follower_t *f, double x_mm, double y_mm, double theta_rad, double wheel_mm_s[2]);

/// Clapper follower: the navigation computer driving both trucks of the clapper from the poses
/// the firmware publishes for A and B and the linkage encoders' readings.
///
/// Truck A drives the program exactly as sim_follower_step does. Truck B drives the same path l
/// behind A: on LINE/ARC segments it tracks the segment it is on itself (its own segment index,
/// advanced by its own estimated position) with its own cross-track and heading feedback, at A's
/// commanded speed plus k (l_meas - l_nom); the same sign works forward and backward, since both
/// trucks face the same way (driving backward, B leads and slows down when l is long). PAUSE:
/// both stand still. TURN (the program must come from sim_program_for_clapper): a rigid turn of
/// the vehicle about its midpoint. Differential-drive trucks cannot move sideways, so it takes
/// three phases: (0) both trucks turn on the spot until they stand perpendicular to the link as
/// the rotary encoders measure it (toward the turn); (1) both drive arcs of radius l/2 about the
/// link's midpoint, A forward and B backward, turning by the sweep together (one common ramped
/// speed, a term that keeps their heading changes equal, a loop that holds each truck's measured
/// angle to the link at 90 deg, and a tilt of B that holds l at nominal); (2) both turn on the
/// spot to the segment's new heading. The link's angles are used because with IPEC off each
/// truck's heading error is its own: after bumps under one truck the trucks no longer stand
/// along the link, and arcs planned from the estimates alone would stretch l into its stops.
typedef struct {
    double length_mm; ///< measured centre-to-centre l
    double alpha_rad; ///< measured theta_A - theta_L
    double beta_rad;  ///< measured theta_B - theta_L
} sim_link_meas_t;

typedef struct {
    sim_follower_t a; ///< truck A: the single-truck follower
    double wheelbase_b_mm;
    double l_nom_mm;
    size_t seg_b;   ///< truck B's own segment (LINE/ARC)
    int turn_phase; ///< 0 spin to the circle, 1 arc about the midpoint, 2 spin to the new heading
    bool phase_started;
    double spin_target_rad[2];
    double arc_th0_rad[2];    ///< headings at the start of the phase
    double w_turn_rad_s[2];   ///< last on-the-spot rates (A, B), phases 0 and 2
    double w_arc_rad_s;       ///< last common angular speed about the midpoint, phase 1
    double v_b_mm_s;          ///< last commanded speed of B
    unsigned spin_settled[2]; ///< ticks each truck's spin has been within SPIN_SETTLE_RAD
} sim_clapper_follower_t;

void sim_clapper_follower_init(sim_clapper_follower_t *f, const sim_program_t *prog, double wheelbase_a_mm,
                               double wheelbase_b_mm, double link_length_mm, double dt_s);

/// One control step from the estimated poses pose[truck] = {x_mm, y_mm, theta_rad} and the
/// linkage readings; writes wheel[truck][left, right] in mm/s. Returns false once the program is
/// finished (speeds are then zero).
bool sim_clapper_follower_step(sim_clapper_follower_t *f, const double pose[2][3], const sim_link_meas_t *link,
                               double wheel_mm_s[2][2]);

#endif
