/// Recorded runs for `odo-calib fit`: the folders odo-import writes (tools/python/odo_tools/importer.py)
/// read back into per-tick arrays.
///
/// A folder holds, per run, `run-<direction>-NN.log` (candump -l, the robot's WHEEL_COUNTS_A
/// frames, can/odometry.dbc), optionally `run-<direction>-NN.truth.csv` (a continuous truth track:
/// header `t_s,a_x_mm,a_y_mm,a_theta_deg`, times on the log's clock) and `returns.csv` (return
/// poses, 000 Eq. 3.1: used for runs without a track), plus `robot.json`, the description the
/// runs were recorded with (checked against the robot given to the fit).
///
/// Each log is replayed through the firmware's own tick assembler and step (tools/replay), so the
/// counts the fit sees are exactly those the firmware accepts (wrap, inversion, missing frames).
/// A run is named `<folder name>/<log stem>` (e.g. `square/run-cw-01`); the folder is its group
/// (one session of the recording rig).
///
/// Host C99; not reentrant across one fit_set_t; errors name the file and, where there is one, the
/// line.
#ifndef CALIB_FIT_DATA_H
#define CALIB_FIT_DATA_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "odo/odo_params.h"

#define FIT_MAX_RUNS   256U
#define FIT_MAX_GROUPS 32U

typedef struct {
    char name[192]; ///< "<group>/<log stem>"
    char log_path[4096];
    unsigned group;                  ///< index into fit_set_t.group_name
    size_t n;                        ///< ticks (tick 0 sets the counter baseline)
    double *t_s;                     ///< tick times from the log's first frame
    int32_t (*delta)[2];             ///< accepted count deltas per tick, forward positive, [left, right];
                                     ///< delta[0] = 0
    bool has_track;                  ///< truth track, interpolated to the tick times:
    double *tx_mm, *ty_mm, *tth_rad; ///< tracked point (x, y) and heading (unwrapped)
    bool has_return;                 ///< return pose from returns.csv (used when there is no track)
    double ret[3];                   ///< x_mm, y_mm, theta_rad of the end pose in the start frame
    bool fit, judge;                 ///< selected by --fit / --judge
} fit_run_t;

typedef struct {
    size_t n_runs;
    fit_run_t run[FIT_MAX_RUNS];
    size_t n_groups;
    char group_name[FIT_MAX_GROUPS][96];
    char group_dir[FIT_MAX_GROUPS][4096];
    uint64_t can_fd_skipped; ///< CAN FD lines the log reader counted and skipped
} fit_set_t;

/// Read every run of `dir` (a folder odo-import wrote) into `s`, replaying the logs with the
/// parameter block `p` (the robot's nominal block: only counter width, inversion and speed limit
/// matter for the counts). `robot_path` is the description given to the fit: a folder whose
/// robot.json describes another robot (geometry, counters, cycle) is refused. Returns 0, or -1
/// with "<file>[:<line>]: <why>" in err (bad log line, truth time going backwards, a truth track
/// that does not cover the log, missing runs, ...).
int fit_data_load_dir(fit_set_t *s, const char *dir, const char *robot_path, const odo_params_t *p, char *err,
                      size_t errlen);

/// Mark runs by shell globs on their names (fnmatch). `fit` NULL/empty: every run; `judge`
/// NULL/empty: every run not fitted. Returns 0, or -1 if a glob matches no run or nothing is
/// selected for fitting.
int fit_data_select(fit_set_t *s, const char *const *fit, size_t n_fit, const char *const *judge, size_t n_judge,
                    char *err, size_t errlen);

/// Replay the run's log through the firmware booted on `block` (the tick assembler and
/// odo_app_step, as odo-replay does) and write truck A's published pose per tick into x, y (mm,
/// run->n entries). Returns 0, or -1 with a message (the block does not boot, the log changed).
int fit_data_firmware_track(const fit_run_t *run, const odo_params_t *block, double *x, double *y, char *err,
                            size_t errlen);

/// Release the arrays of every run.
void fit_data_free(fit_set_t *s);

#endif
