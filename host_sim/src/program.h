/// Experiment programs: the paths of the papers' experiments as segments a path follower drives,
/// plus where the experiment puts its bumps. Pure data; no simulation here.
///   umbmark       4 x 4 m square, stop and turn on the spot at every corner, fourth turn included,
///                 0.2 m/s (000 section 3.5, 6.3)
///   umbmark-ext   the same with N (default 10) bumps under the inside wheel, evenly on leg 1
///                 (000 section 3.4)
///   straight-36m  18 m out, stop, 18 m back driving backward, bumps under the right wheels of
///                 both trucks on the return leg (004 section 6.1)
///   rect-7x4      7 x 4 m rectangle with smooth 90 deg turns at ~0.5 m/s, not stopping at the
///                 corners, bumps under one side (004 section 6.2)
/// Frame: start at the origin heading +x; ccw turns left; cw turns right.
#ifndef SIM_PROGRAM_H
#define SIM_PROGRAM_H

#include <stddef.h>
#include <stdint.h>

#define SIM_PROGRAM_MAX_SEGMENTS 32
#define SIM_PROGRAM_MAX_BUMPS    64

typedef enum { SIM_SEG_LINE, SIM_SEG_TURN, SIM_SEG_ARC, SIM_SEG_PAUSE } sim_seg_kind_t;

typedef struct {
    sim_seg_kind_t kind;
    double x0_mm, y0_mm; ///< LINE/ARC start (ARC: a point on the circle)
    double x1_mm, y1_mm; ///< LINE end
    double cx_mm, cy_mm; ///< ARC centre
    double radius_mm;    ///< ARC radius
    double sweep_rad;    ///< ARC signed sweep (ccw positive)
    double heading_rad;  ///< TURN: target heading (absolute, nominal frame)
                         ///< clapper TURN (sim_program_for_clapper): x0/y0 truck A before,
                         ///< x1/y1 after, cx/cy the pivot (the vehicle's midpoint), radius_mm
                         ///< l/2, sweep_rad the signed turn angle
    double speed_mm_s;   ///< LINE/ARC cruise speed (negative: drive backward); TURN wheel speed
    double accel_mm_s2;  ///< ramp rate
    double pause_s;      ///< PAUSE duration
} sim_segment_t;

/// A bump on the floor, placed by distance along the path travelled by a wheel.
typedef struct {
    double at_path_mm; ///< distance of the bump along the programmed path
    uint8_t side;      ///< ODO_LEFT or ODO_RIGHT wheel track
    double height_mm;
} sim_bump_t;

typedef struct {
    char name[32];
    int ccw; ///< 1 ccw, 0 cw
    sim_segment_t seg[SIM_PROGRAM_MAX_SEGMENTS];
    size_t n_seg;
    sim_bump_t bump[SIM_PROGRAM_MAX_BUMPS];
    size_t n_bumps;
    double path_mm; ///< total programmed path length (lines and arcs)
} sim_program_t;

/// Names of the experiments, NULL-terminated, for --help and validation.
extern const char *const sim_experiment_names[];

/// Build the program of `experiment` for one run. `bumps` < 0 means the experiment's default
/// (umbmark-ext 10, straight-36m 10, rect-7x4 10, umbmark 0). `run_index` alternates the bump side
/// of rect-7x4 (half the runs right, half left). Returns 0, or -1 with a message in err for an
/// unknown experiment or more bumps than fit.
int sim_program_build(const char *experiment, int ccw, int bumps, double bump_height_mm, unsigned run_index,
                      sim_program_t *out, char *err, size_t errlen);

/// Adapt a built program to the clapper (two trucks l apart, A in front): every TURN becomes a
/// rigid turn of the whole vehicle about its midpoint, l/2 behind truck A (see follower.h), so A
/// does not end the turn where it started it; the LINE/ARC segments that follow are moved by the
/// same offset (direction, length and speed kept) so that A starts each of them where the turn
/// left it. For umbmark this makes the midpoint, not truck A, drive the 4 x 4 m square, and A is
/// back at the origin heading +x after the fourth turn. Paths without TURNs (straight-36m,
/// rect-7x4) are unchanged. Bumps keep their path distances. Returns 0, or -1 for l <= 0.
int sim_program_for_clapper(sim_program_t *p, double link_length_mm);

#endif
