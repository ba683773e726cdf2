/// Replay benchmark for odo-bench (issue 6, performance): offline replay of a 1-hour clapper
/// simulator log (90,000 ticks, 360,000 sensor frames), against python-can's CanutilsLogReader
/// merely reading the same file.
#ifndef ODO_REPLAY_BENCH_H
#define ODO_REPLAY_BENCH_H

#include <stddef.h>

typedef struct {
    double ticks_per_s;             ///< full replay: parse + tick assembly + firmware step (the
                                    ///< firmware packs the output frames), IPEC off as the log was
                                    ///< simulated (odo-sim's default)
    double frames_per_s;            ///< the same, in input frames per second
    double with_output_ticks_per_s; ///< the same plus formatting the output frames as candump
                                    ///< lines (written to /dev/null), as odo-replay does minus its CSV
    double ipec_ticks_per_s;        ///< the same with IPEC on (paper mode: the full clapper step)
    double python_can_frames_per_s; ///< CanutilsLogReader iterating the file; < 0 if not measured
    double ratio;                   ///< frames_per_s / python_can_frames_per_s; < 0 if not measured
    double ipec_ratio;              ///< the same with IPEC on
    unsigned long ticks;            ///< ticks replayed (90,000)
    unsigned long frames;           ///< frames in the log
    char log_path[512];             ///< the cached log
} replay_bench_t;

/// Make (once; cached under the build tree) the 1-hour log and time both readers, best of `reps`.
/// `python` is the interpreter with python-can (NULL: the project's .venv; python-can is skipped,
/// ratio < 0, if it is not there). Returns 0, or -1 with a
/// message on stderr.
int replay_bench_run(int reps, const char *python, replay_bench_t *out);

#endif
