/// `odo-calib fit`: calibrate the odometry model from any driven path with truth (a motion-capture
/// track or return poses), in the spirit of OptiOdom's generic approach (Sousa et al. 2022, J.
/// Intell. Robot. Syst. 105:39; ../shared/data/optiodom/README.md), not only UMBmark squares.
///
/// Model: the double-precision reference of the firmware's odometry (tools/lib/odo_ref.c: 000
/// Eqs. 2.1-2.6, 6.28, 6.33-6.35, App. B) with the turn-radius-dependent wheelbase (effects
/// catalog `scrub`): per tick, with accepted count deltas dL, dR (forward positive),
/// v = |dL| + |dR|, m = 2 min(|dL|, |dR|) if dL, dR have the same strict sign else 0, the heading
/// change is the Ed/Eb/Es one times (1 - k m / v). k = 0 on spot turns' terms (m = 0), so Eb is
/// the spot-turn wheelbase ratio UMBmark measures and an arc of radius R sees b Eb / (1 - k (1 - s)),
/// s = b / (2R).
///
/// Nuisance per folder (one session of the recording rig), fitted beside the model and never
/// written to the block: the tracked point's offset from the axle centre (lever arm lx, ly in the
/// robot frame, mm) and the truth heading's offset from the robot's heading (phi). Without the
/// lever arm, spot turns swing the marker on a circle the model cannot explain and corrupt Eb.
///
/// Residuals: every tick of every fitted track (tracked point x, y in mm; heading times the nominal
/// wheelbase, so 1 rad weighs like b mm); a run with only a return pose contributes its return
/// error (x, y, heading x b), weighted by sqrt(ticks) so it counts like a track of its length.
/// Solver: GSL's trust-region Levenberg-Marquardt (gsl_multifit_nlinear) with finite-difference
/// Jacobians. Closed paths alone do not show the scale (Es): it is fitted only when a fitted run
/// has a track.
///
/// Host C99 + GSL; not reentrant (one fit at a time per fit_set_t).
#ifndef CALIB_FIT_MODEL_H
#define CALIB_FIT_MODEL_H

#include <stdbool.h>
#include <stddef.h>

#include "fit_data.h"
#include "odo/odo_params.h"

/// The model's parameters (what the block carries).
typedef struct {
    double ed, eb, es; ///< 000 Eqs. 2.7, 2.8, B.1
    double k;          ///< scrub: turn-radius-dependent wheelbase, |k| <= FIT_SCRUB_MAX
} fit_params_t;

#define FIT_SCRUB_MAX 0.25

/// The recording rig of one folder (nuisance).
typedef struct {
    double lx_mm, ly_mm; ///< tracked point in the robot frame, from the axle centre
    double phi_rad;      ///< truth heading minus robot heading
    bool fitted;         ///< false: the folder had no fitted track (zeros used)
} fit_rig_t;

/// Which parameters are free (the rest keep the starting block's values).
typedef struct {
    bool ed, eb, es, k;
} fit_free_t;

typedef struct {
    fit_params_t p;  ///< fitted model
    fit_params_t sd; ///< formal standard errors (residuals scaled; optimistic:
                     ///< track residuals are correlated along time)
    fit_rig_t rig[FIT_MAX_GROUPS];
    double rms_mm; ///< RMS of the fitted residuals
    size_t n_residuals;
    int iterations;
    bool converged;
    bool es_free, k_free; ///< as actually fitted (Es needs a track)
} fit_result_t;

/// One run's return error (000 Eq. 3.1 sign: computed minus true; axle centre, start frame).
typedef struct {
    double ex_mm, ey_mm, eth_deg, pos_mm;
} fit_return_err_t;

/// Integrate the model over one run from (x0, y0, th0); writes n poses (x, y, th may be NULL).
/// `base`: the block's truck A geometry (diameter, counts, wheelbase); `heading_form` as the block.
void fit_integrate(const fit_run_t *run, const odo_truck_params_t *base, unsigned heading_form, const fit_params_t *p,
                   double x0, double y0, double th0, double *x, double *y, double *th);

/// Fit the free parameters on the runs marked `fit`, starting from `start`. Returns 0, or -1 with a
/// message (solver failure, parameters out of the block's ranges).
int fit_run_fit(const fit_set_t *s, const odo_truck_params_t *base, unsigned heading_form, const fit_params_t *start,
                fit_free_t free_, fit_result_t *out, char *err, size_t errlen);

/// The return error of a run under parameters p, the truth taken to the axle centre with `rig`.
void fit_return_error(const fit_run_t *run, const odo_truck_params_t *base, unsigned heading_form,
                      const fit_params_t *p, const fit_rig_t *rig, fit_return_err_t *e);

/// Parameters as a block's truck (Q30, rounded: ed, eb, es and scrub).
void fit_params_to_truck(const fit_params_t *p, odo_truck_params_t *t);

/// The block's truck as parameters.
void fit_params_from_truck(const odo_truck_params_t *t, fit_params_t *p);

#endif
