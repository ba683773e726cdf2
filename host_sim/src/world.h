/// The world: true planar kinematics of each truck at a fixed physics step (default 1 ms, set by
/// the caller, independent of the firmware's 40 ms tick), with the scenario's effects applied.
/// It produces what the sensors see (each wheel's encoder phase, the linkage geometry with encoder
/// biases) and the ground truth (poses, bump events). The HCTL emulator, the HAL and the firmware
/// sit downstream of it; the path follower upstream (it commands wheel speeds).
///
/// Frame: x forward at the start, y left, theta counter-clockwise; start at the origin heading +x.
///
/// Wheels. A command is a wheel *surface speed as the controller believes it* (mm/s, forward
/// positive): the motor turns the wheel at omega = v_cmd / R_nominal. The wheel's true radius
/// (nominal with Ed, Es and tyre compression; Ed keeps the mean diameter, 000 Eqs. 6.30-6.32; Es
/// gives a mean diameter of Dn/Es, 000 App. B) turns that into a surface arc, slip changes how much
/// of it reaches the floor, and bumps/roughness (bump.h profiles) take away horizontal progress
/// while the encoder still counts the whole rotation. The truck then moves by the two horizontal
/// wheel advances over the true wheelbase Eb * b (000 Eqs. 2.3-2.5, integrated exactly along the
/// arc of each step), plus the lateral skid of fast turns.
///
/// Vehicles. labmate: truck A only. clapper: A and B both driven by their own commands; the
/// compliant linkage is force-free within its range [min, max] of l; a step that would leave it is
/// clamped (both trucks pulled/pushed equally along the link; the wheels slide, the encoders do not
/// count it) and counted. set: B is a passive two-wheel trailer: it ignores its command and follows
/// the hitch point, hitch_offset behind A's centre, with its axle trailer_length behind the hitch
/// and no sideways motion of the axle (standard trailer kinematics); its wheels' encoders count
/// the rotation their horizontal travel (plus any bump) needs.
///
/// Linkage (002_97a419d21cabf785.txt Eqs. 10, 11, 16). theta_L is the link orientation from B to
/// A: theta_L = atan2(y_A - y_B, x_A - x_B), the atan2 reading of Eq. 10 for which Eq. 16
/// (x_B = x_A - l cos theta_L, y_B = y_A - l sin theta_L) holds. alpha = theta_A - theta_L,
/// beta = theta_B - theta_L (Eq. 11), wrapped to (-pi, pi]. For a set, the "link" is the trailer
/// bar (axle to hitch), so theta_L is the trailer heading, alpha the joint angle and beta 0.
///
/// Determinism: a seeded splitmix64 stream per wheel lives in the struct (no globals); identical
/// inputs and seed give bit-identical state. No allocation; the struct is plain data (~36 KiB):
/// declare it static or on the heap if the stack is small. Not thread-safe per instance;
/// instances are independent.
#ifndef SIM_WORLD_H
#define SIM_WORLD_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "bump.h"
#include "effects.h"
#include "odo_robot.h"

#define SIM_WORLD_DEFAULT_DT_S 0.001 ///< 1 ms physics step
#define SIM_WORLD_MAX_DT_S     0.1   ///< larger steps are refused
#define SIM_WORLD_MAX_PENDING  64    ///< discrete bumps waiting under one wheel
#define SIM_WORLD_MAX_ACTIVE   16    ///< bumps under one wheel at the same time
#define SIM_WORLD_MAX_EVENTS   512   ///< bump events kept (later ones are counted, not kept)

typedef struct {
    double x_mm, y_mm; ///< truck centre (set trailer: axle centre)
    double theta_rad;  ///< heading, unwrapped (ccw positive)
} sim_pose_t;

/// A discrete bump reached by a wheel (roughness grains are not logged).
typedef struct {
    double t_s;           ///< simulation time of first contact
    uint8_t truck, wheel; ///< ODO_TRUCK_*, ODO_LEFT / ODO_RIGHT
    double x_mm, y_mm;    ///< wheel contact point at first contact
    double height_mm;
    double at_distance_mm; ///< the wheel's travel when it was reached
} sim_bump_event_t;

/// True linkage geometry.
typedef struct {
    double theta_l_rad; ///< link orientation, from B to A
    double alpha_rad;   ///< theta_A - theta_L, (-pi, pi]
    double beta_rad;    ///< theta_B - theta_L, (-pi, pi] (set: 0)
    double length_mm;   ///< centre-to-centre l (set: trailer_length)
} sim_link_geom_t;

/// What the linkage encoders report: truth plus rotary_bias / link_bias, then quantised to the
/// encoders' resolution (rounded: code k covers k +- half a step), in the firmware's units.
typedef struct {
    double alpha_rad, beta_rad; ///< biased, before quantisation
    double length_mm;           ///< biased, before quantisation (set: trailer_length)
    uint16_t alpha_bam16;       ///< quantised to rotary_bits, as 2^16 per turn
    uint16_t beta_bam16;
    uint32_t length_um; ///< quantised to linear_resolution_mm
} sim_link_reading_t;

typedef struct {
    sim_bump_geom_t g;
    double progress_mm; ///< rotation arc (driven wheel) or horizontal (passive) so far
} sim_active_bump_t;

/// Hidden effects: truth the effects catalog deliberately does not list, so the diagnosis has no
/// hypothesis for them (the blind check's out-of-catalog cases), plus the controller dynamics that
/// make a "real" run higher fidelity than the diagnosis model. Never read from a scenario file;
/// set only through sim_world_set_hidden (libodosim: odosim_run_ex). All zero = off, and then the
/// world is bit-identical to a world without this struct. Driven wheels only.
typedef struct {
    double motor_tau_s;       ///< first-order lag of each wheel's speed behind its command (s)
    double diam_var_amp;      ///< time-varying wheel diameter: D(t) = D (1 + amp sin(2 pi t / T))
    double diam_var_period_s; ///< T of the above (s); both wheels of a truck in phase
    double diam_drift_per_s;  ///< and/or a linear drift D(t) = D (1 + drift t) (tyre warming)
    double backlash_rad;      ///< gear backlash at the wheel: after a reversal the motor (and its
                              ///< encoder) turns this much before the wheel follows
} sim_hidden_t;

typedef struct {
    double radius_mm;     ///< true rolling radius
    double phase_rad;     ///< cumulative rotation angle, forward positive
    double odometer_mm;   ///< cumulative |horizontal travel| of the contact point
    double cmd_prev_mm_s; ///< last command (slip)
    double v_motor_mm_s;  ///< hidden motor lag: the wheel's actual surface speed command
    double play_rad;      ///< hidden backlash: position in the gear play, [0, backlash]
    size_t n_pending;
    struct {
        double at_mm, height_mm;
    } pending[SIM_WORLD_MAX_PENDING]; ///< ascending at_mm
    size_t n_active;
    sim_active_bump_t active[SIM_WORLD_MAX_ACTIVE];
    double next_rough_mm; ///< odometer reading of the next roughness grain
    uint64_t rng;         ///< splitmix64 state of this wheel's roughness stream
} sim_wheel_state_t;

typedef struct {
    sim_pose_t pose;
    double b_true_mm;             ///< Eb * nominal
    double r_nominal_mm;          ///< what the controller believes
    double counts_per_rev;        ///< decoded counts per wheel turn
    sim_bump_model_t bump_model;  ///< discrete bumps on this truck
    sim_bump_model_t rough_model; ///< roughness grains on this truck
    sim_wheel_state_t wheel[2];
} sim_truck_state_t;

/// Treat as opaque; use the functions below.
typedef struct {
    sim_robot_t robot;
    sim_scenario_t sc;
    uint64_t seed;
    double t_s;
    sim_truck_state_t truck[ODO_TRUCKS];
    sim_hidden_t hidden;          ///< out-of-catalog truth (all zero: off)
    unsigned long link_clamps;    ///< steps in which the clapper linkage hit a stop
    bool clamped_last;            ///< the last step did
    unsigned long bumps_dropped;  ///< bumps lost to full queues (should stay 0)
    unsigned long events_dropped; ///< events beyond SIM_WORLD_MAX_EVENTS
    size_t n_events;
    sim_bump_event_t events[SIM_WORLD_MAX_EVENTS];
} sim_world_t;

/// Set up the world at rest: truck A at the origin heading +x, B (clapper) l behind it, or the
/// trailer (set) straight behind. Applies the scenario (copied): true radii, wheelbases, the
/// scenario's "at" bumps (if the bumps effect is enabled on that truck) and the roughness streams
/// seeded from `seed` (the caller decides between the scenario's seed and a --seed override).
/// Returns 0, or -1 with a message for a NULL argument, a tyre load offset beyond b/2, a radius that
/// compression makes non-positive, or a scenario bump the vehicle cannot take.
int sim_world_init(sim_world_t *w, const sim_robot_t *robot, const sim_scenario_t *sc, uint64_t seed, char *err,
                   size_t errlen);

/// Switch the hidden (out-of-catalog) effects on; call after sim_world_init, before stepping.
/// Returns 0, or -1 with a message for a negative or non-finite value, |amp| or |drift t| that
/// would make a radius non-positive, or a zero period with a non-zero amplitude.
int sim_world_set_hidden(sim_world_t *w, const sim_hidden_t *h, char *err, size_t errlen);

/// Place the vehicle rigidly at a pose (truck A), the other truck straight behind. Keeps time,
/// encoder phases, odometers and bumps.
void sim_world_place(sim_world_t *w, double x_mm, double y_mm, double theta_rad);

/// Advance by dt_s (0 < dt <= SIM_WORLD_MAX_DT_S) under wheel_speed_cmd_mm_s[truck][wheel] (see the
/// banner: nominal surface speeds; truck B of a set and of a labmate ignore theirs). Returns 0, or
/// -1 (state untouched) for a bad dt, a NULL or non-finite command. Constant time per step apart
/// from the bumps under each wheel.
int sim_world_step(sim_world_t *w, double dt_s, const double wheel_speed_cmd_mm_s[2][2]);

/// Put a bump under a wheel, reached when that wheel's true travel (sim_world_wheel_travel_mm)
/// reaches at_distance_mm. Works whether or not the scenario enables "bumps" (experiments place
/// their own); the profile model is the scenario's bumps model for that truck. Returns 0, or -1 for
/// a bad truck/wheel, h outside [0, R), a non-finite distance or a full queue.
int sim_world_add_bump(sim_world_t *w, unsigned truck, unsigned wheel, double at_distance_mm, double height_mm);

/// True pose of a truck (B of a labmate: all zero).
sim_pose_t sim_world_pose(const sim_world_t *w, unsigned truck);

/// Encoder phase in counts: rotation angle * counts_per_rev / 2pi, forward positive, unwrapped,
/// before any decoder inversion or count loss (the HCTL emulator's input).
double sim_world_encoder_phase_counts(const sim_world_t *w, unsigned truck, unsigned wheel);

/// Cumulative |horizontal travel| of a wheel's contact point (what bump positions refer to).
double sim_world_wheel_travel_mm(const sim_world_t *w, unsigned truck, unsigned wheel);

/// True rolling radius of a wheel (effects applied).
double sim_world_wheel_radius_mm(const sim_world_t *w, unsigned truck, unsigned wheel);

/// True linkage geometry (clapper) or trailer joint (set); all zero for a labmate.
sim_link_geom_t sim_world_link_true(const sim_world_t *w);

/// Linkage encoder readings with rotary_bias / link_bias applied and quantised.
sim_link_reading_t sim_world_link_measured(const sim_world_t *w);

/// Bump events so far, in order; *n receives the count (<= SIM_WORLD_MAX_EVENTS).
const sim_bump_event_t *sim_world_bump_events(const sim_world_t *w, size_t *n);

/// Decoder clock for the HCTL emulator's count loss on a truck, or 0 when count_loss is off.
double sim_world_count_loss_f_clk_hz(const sim_world_t *w, unsigned truck);

/// Simulation time in seconds.
double sim_world_time_s(const sim_world_t *w);

/// Steps in which the clapper linkage hit a stop.
unsigned long sim_world_link_clamps(const sim_world_t *w);

/// The clapper's stop: the move of truck A (B moves by its negative) that brings the link vector
/// A - B = (dx, dy) back to the nearer end of [lo_mm, hi_mm], along the link, or along (ux0, uy0)
/// where A and B coincide. False with a zero move when the length lies within the range.
bool sim_link_push(double dx, double dy, double lo_mm, double hi_mm, double ux0, double uy0, double *px, double *py);

/// The same stop replayed over a whole recorded motion (the diagnosis's model, gap/model.py, asks
/// for it once per fit step): rel[2 i], rel[2 i + 1] is A - B at tick i as the wheels alone would
/// move it, gate[i] (NULL: always) whether the stop may act at tick i, and push[2 i], push[2 i + 1]
/// receives A's cumulative move from the stops up to tick i. Tick 0 is taken as it is. Returns the
/// number of ticks a stop acted, or -1 on NULL arrays or a range that is not finite and ordered.
long sim_link_clamp_track(const double *rel, size_t n, double lo_mm, double hi_mm, const unsigned char *gate,
                          double *push);

#endif
