/// Soak and frame-loss figures of the firmware's receive path (issue 16, "faults at speed" and
/// item 6): a seeded drive of a labmate is sent as the WHEEL_COUNTS_A frames its decoder board
/// would put on the bus, and replayed twice through odo-replay's tick assembler and the firmware's
/// own odo_app_step (tools/replay/replay.h): once as sent, once through a faulty bus (lost,
/// duplicated and reordered frames, error-frame bursts, the sender's clock stepping back). The
/// figures are the faulty run's pose against the clean run's, tick by tick.
///
/// The drive is computed in double precision by this file (independent of the firmware): wheel
/// speeds per segment, counts accumulated by tools/lib/odo_synth (24-bit cumulative counters, Seq
/// +1 per 40 ms tick). The robot is the parameter block's default labmate (3 m/s wheel limit).
///
/// Host-only C; allocates the two replays (a few hundred kB). Deterministic for a given config.
#ifndef ODO_SOAK_H
#define ODO_SOAK_H

#include <stdbool.h>
#include <stdint.h>

#include "odo/odo_status.h"

typedef struct {
    uint64_t ticks; ///< ticks driven (24 h at 40 ms: 2,160,000)
    uint64_t seed;
    double v_max_mm_s;     ///< fastest wheel speed of the random program (<= 3000, the limit)
    double straight_mm_s;  ///< != 0: drive straight ahead at this speed instead of the program
    double drop;           ///< probability that a sensor frame is lost
    double dup;            ///< ... that it is sent twice
    double reorder;        ///< ... that it is swapped with the next tick's frame
    uint64_t burst_every;  ///< mean ticks between error-frame bursts (0: none); a burst also
                           ///< destroys that tick's sensor frame
    unsigned burst_frames; ///< error frames per burst (the last one of the bus-off class)
    int64_t clock_step_us; ///< the sender's clock steps by this at the middle tick (0: none)
} soak_config_t;

typedef struct {
    uint64_t ticks_clean, ticks_faulty;  ///< steps each replay ran
    uint64_t frames_sent, frames_faulty; ///< sensor frames of the drive, frames on the faulty bus
    uint64_t dropped, duplicated, reordered, bursts, error_frames;
    uint64_t clock_steps, gaps;            ///< re-anchorings the faulty replay did
    uint64_t fault_ticks[ODO_FAULT_COUNT]; ///< faulty run: ticks that raised each ODO_FAULT_* bit
    double path_m;                         ///< clean run: path length of the centre (sum |U|)
    double end_pos_err_mm;                 ///< faulty vs clean pose at the last tick
    double end_heading_err_deg;
    double max_pos_err_mm;                  ///< worst over the ticks the faulty run integrated a
                                            ///< sample (its pose caught up): accumulated error
    double max_lag_mm;                      ///< worst over every tick (a held pose lags)
    double end_x_clean_mm, end_x_faulty_mm; ///< straight drives: travel along x
    double wall_s;                          ///< wall-clock time of both replays and the drive
} soak_result_t;

/// The soak: 2,160,000 ticks (24 h), program up to 3 m/s, 20 % lost, 5 % duplicated, 2 %
/// reordered, a burst of 20 error frames every 15,000 ticks (10 min) on average, and a 2 s clock
/// step back at the middle.
void soak_defaults(soak_config_t *c);

/// Called now and then with the ticks driven so far.
typedef void (*soak_progress_fn)(void *user, uint64_t done, uint64_t total);

/// Run one soak. Returns 0 with *r filled, or -1 if memory runs out or the firmware refuses the
/// parameters (never on any config: rates outside [0, 1] act as 0 or 1). The first and last 16
/// ticks carry no faults (the random program stands still there), so both runs take the same
/// baseline and end on the same tick with every count delivered.
int soak_run(const soak_config_t *c, soak_result_t *r, soak_progress_fn progress, void *user);

#endif
