/// UMBmark: statistics of the bi-directional square test and the calibration that follows from it
/// (000_12e7709aa9cd375a.txt, "000" below: s. 3 and s. 6), in integer arithmetic, so the same code
/// serves the host CLI (`odo-calib umbmark`) and a future on-robot self-calibration (000 s. 7.3).
///
/// Scope: pure functions, no state, no heap, no I/O; reentrant. Every routine loops at most once
/// over its runs (O(n)), plus a constant number of 128-bit mul-divs (odo_fx.h) and integer square
/// roots (64 iterations each).
///
/// Units (names carry them): return errors in micrometres (`_um`) and micro-degrees (`_udeg`);
/// angles in signed binary angle (`_bam`, 2^31 == 180 deg, 1 BAM = 8.4e-8 deg); ratios in Q30
/// (`_q30`, 1.0 == 2^30, the parameter block's format); lengths in um or nm as named.
///
/// Sign conventions (000 s. 3.1 and Eqs. 6.3-6.18; checked against host_sim in tests/python):
///   - return error e = absolute - calculated (000 Eq. 3.1); cw turns right; start heading +x.
///   - alpha: under-rotation in each nominal 90 deg on-the-spot turn (Type A, caused by Eb);
///     alpha > 0 iff the true wheelbase is larger than the firmware believes (Eq. 6.28).
///   - beta: heading gained on each straight leg (Type B, caused by Ed); beta > 0 iff the robot
///     curves left (ccw) on a commanded straight line, i.e. iff DR > DL (Eq. 6.24).
///
/// Where 000 is loose, this module decides (and says so):
///   - Eqs. 6.22a/b and 6.26a/b give beta and alpha twice, from x and from y; the result uses
///     their mean (it uses all four centre-of-gravity coordinates) and reports the x-y
///     disagreement, which grows with the size of the errors (the small-angle model breaks down).
///   - Eq. 6.24 is evaluated as Ed = (L + b sin(beta/2)) / (L - b sin(beta/2)) (Eq. 6.23 substituted,
///     so beta = 0 needs no special case) with b the actual wheelbase of Eq. 6.28.
///   - Eq. 3.5 is lost in the plain-text transcription; the text around it defines it as the mean
///     absolute orientation error of the extended runs after removing each direction's systematic
///     bias (Eq. 3.6, the mean over the plain UMBmark runs of that direction). This module takes the
///     mean over all extended runs of both directions (n = 2 x runs per direction).
///   - SEM (000 s. 6.3) = sigma / sqrt(n), sigma pooled over both clusters about their own centres
///     (2 degrees of freedom lost), n the mean number of runs per direction; the same statistic
///     host_sim's summary.json reports.
#ifndef ODO_UMBMARK_H
#define ODO_UMBMARK_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/// Most runs accepted per direction (keeps every sum of squares inside 63 bits).
#define ODO_UMB_MAX_RUNS       256U
/// Largest accepted |return error| component: 2^25 um = 33.554 m.
#define ODO_UMB_MAX_ERR_UM     ((int32_t)1 << 25)
/// Largest accepted |orientation error|: 180 deg.
#define ODO_UMB_MAX_THETA_UDEG 180000000
/// Side length L of the square: [100 mm, 100 m].
#define ODO_UMB_MIN_SIDE_UM    100000U
#define ODO_UMB_MAX_SIDE_UM    100000000U

/// Direction index of the arrays below.
#define ODO_UMB_CW  0U
#define ODO_UMB_CCW 1U

typedef enum {
    ODO_UMB_OK = 0,
    ODO_UMB_ERR_ARG,      ///< NULL pointer
    ODO_UMB_ERR_FEW_RUNS, ///< a direction with fewer than 2 runs, or more than ODO_UMB_MAX_RUNS
    ODO_UMB_ERR_INPUT,    ///< a return error outside +-ODO_UMB_MAX_ERR_UM / +-180 deg
    ODO_UMB_ERR_SIDE,     ///< side length outside [ODO_UMB_MIN_SIDE_UM, ODO_UMB_MAX_SIDE_UM]
    ODO_UMB_ERR_GEOMETRY, ///< wheelbase or current calibration outside the parameter block's range
    ODO_UMB_ERR_RESULT    ///< the corrected Ed or Eb would leave the parameter block's [0.8, 1.25]
} odo_umb_status_t;

/// One run's return error (000 Eq. 3.1).
typedef struct {
    int32_t ex_um;       ///< x_abs - x_calc
    int32_t ey_um;       ///< y_abs - y_calc
    int32_t etheta_udeg; ///< theta_abs - theta_calc, wrapped to [-180, 180] deg
} odo_umb_return_t;

/// UMBmark statistics (000 Eqs. 3.2-3.4, s. 3.4 sigma, s. 6.3 SEM), index ODO_UMB_CW / _CCW.
typedef struct {
    uint16_t n[2];      ///< runs per direction
    int32_t cg_x_um[2]; ///< centre of gravity (Eq. 3.2), rounded to 1 um
    int32_t cg_y_um[2];
    uint32_t r_cg_um[2];         ///< |cg| (Eq. 3.3)
    uint32_t emax_syst_um;       ///< max(r_cg cw, r_cg ccw) (Eq. 3.4)
    uint32_t sigma_um;           ///< pooled standard deviation about each cluster's own cg
    uint32_t sem_um;             ///< sigma / sqrt(runs per direction)
    int32_t theta_bias_udeg[2];  ///< mean orientation error per direction (Eq. 3.6)
    uint32_t avg_abs_theta_udeg; ///< mean |etheta| over all runs (004 Eq. 17)
    bool second_pass_advised;    ///< Emax,syst > 3 SEM (000 s. 6.3 rule of thumb)
} odo_umb_stats_t;

/// Compute the statistics of n_cw + n_ccw runs. Returns ODO_UMB_OK with *out filled, or an error
/// with *out untouched: ERR_ARG (NULL), ERR_FEW_RUNS (a direction with < 2 or > ODO_UMB_MAX_RUNS
/// runs), ERR_INPUT (a component out of range). O(n_cw + n_ccw).
odo_umb_status_t odo_umb_stats(const odo_umb_return_t *cw, size_t n_cw, const odo_umb_return_t *ccw, size_t n_ccw,
                               odo_umb_stats_t *out);

/// The paper's calibration (000 s. 6.1-6.2) from the statistics, for a firmware that ran the test
/// with the calibration (ed_q30, eb_q30) already in its parameter block (1.0 for an uncalibrated
/// robot); "a compensated robot can be treated as a new uncompensated robot" (000 s. 6.3), so the
/// measured ratios multiply the current ones.
typedef struct {
    int32_t alpha_x_bam, alpha_y_bam; ///< Eq. 6.26a (from x) and 6.26b (from y)
    int32_t beta_x_bam, beta_y_bam;   ///< Eq. 6.22a, 6.22b
    int32_t alpha_bam, beta_bam;      ///< the means used
    uint32_t alpha_disagree_bam;      ///< |alpha_x - alpha_y|
    uint32_t beta_disagree_bam;       ///< |beta_x - beta_y|
    int64_t radius_um;                ///< signed R of the leg's arc (Eq. 6.23); 0 iff beta == 0
    int32_t ed_meas_q30;              ///< Ed measured relative to the current calibration (Eq. 6.24)
    int32_t eb_meas_q30;              ///< Eb relative to the current calibration (Eq. 6.29)
    int32_t ed_q30;                   ///< new block value: current ed x ed_meas
    int32_t eb_q30;                   ///< new block value: current eb x eb_meas
    uint32_t b_actual_nm;             ///< nominal wheelbase x new eb (Eq. 6.28)
    int32_t cl_q30, cr_q30;           ///< correction factors of the new Ed (Eqs. 6.33, 6.34)
} odo_umb_calib_t;

/// Paper method. side_um: L; wheelbase_nm: the nominal b of the parameter block (wheelbase_nm,
/// [50 mm, 3 m]); ed_q30/eb_q30: the calibration in force during the test ([0.8, 1.25]).
/// Returns ODO_UMB_OK with *out filled, or ERR_ARG, ERR_SIDE, ERR_GEOMETRY, ERR_RESULT (the result
/// would not fit the parameter block; *out is then filled anyway, except ed/eb/cl/cr/b_actual,
/// so a tool can say how far off it is). Constant time.
odo_umb_status_t odo_umb_calibrate(const odo_umb_stats_t *s, uint32_t side_um, uint32_t wheelbase_nm, int32_t ed_q30,
                                   int32_t eb_q30, odo_umb_calib_t *out);

/// cL = 2 / (Ed + 1) and cR = 2 / (1/Ed + 1) in Q30 (000 Eqs. 6.33, 6.34); the mean wheel diameter
/// stays Da (Eq. 6.30). Returns false (outputs untouched) iff ed_q30 <= 0 or a pointer is NULL.
bool odo_umb_correction_factors(int32_t ed_q30, int32_t *cl_q30, int32_t *cr_q30);

/// Extended UMBmark (000 s. 3.4): mean absolute bias-free orientation error of the extended runs
/// (Eq. 3.5), each run's error taken relative to its direction's systematic bias from the plain
/// UMBmark (Eq. 3.6: theta_bias_udeg of odo_umb_stats). Returns ODO_UMB_OK with *out_udeg, or
/// ERR_ARG, ERR_FEW_RUNS (no run at all, or more than ODO_UMB_MAX_RUNS per direction), ERR_INPUT.
odo_umb_status_t odo_umb_nonsys_theta(const odo_umb_return_t *cw, size_t n_cw, const odo_umb_return_t *ccw,
                                      size_t n_ccw, const int32_t theta_bias_udeg[2], uint32_t *out_udeg);

/// Static English text for a status.
const char *odo_umb_status_str(odo_umb_status_t s);

#ifdef __cplusplus
}
#endif
#endif
