/// The exact UMBmark calibration (issue 4, item 2): fit the true wheel-diameter ratio Ed and the
/// true (effective) wheelbase b to the measured cw and ccw centres of gravity by simulating the
/// 4-leg square without 000_12e7709aa9cd375a.txt's small-angle approximations (Eqs. 6.1-6.2).
///
/// Forward model (the kinematics of host_sim/src/world.c without noise): the robot's controller
/// drives the square the firmware believes in: four straight legs of L and four on-the-spot turns
/// of 90 deg (fourth turn included, 000 s. 3.5). The firmware believes each wheel travels
/// counts * pi * Dn * c / CPR with the calibration in force (c = cL, cR of its ed, Eqs. 6.33-6.35);
/// the true travel uses the true diameters DL = 2 Dn/(Ed + 1), DR = 2 Dn Ed/(Ed + 1), the mean
/// diameter kept (Eq. 6.30). Each segment's true motion is an exact circular arc over the true
/// wheelbase b (Eq. 2.4 without small angles). The return error is the true end pose (the firmware
/// believes it is home, 000 Eq. 3.1).
///
/// What a closed square cannot identify: the scale error Es (all legs scale alike; measure it
/// with a tape, 000 App. B) and anything about a second truck. Ed and b are identifiable from the
/// four cg coordinates unless the Jacobian is singular, which the fit reports.
///
/// Host C, double precision; reentrant; no allocation.
#ifndef CALIB_UMB_EXACT_H
#define CALIB_UMB_EXACT_H

#include <stdbool.h>

/// What the firmware believed while the test ran.
typedef struct {
    double side_mm;      ///< L
    double b_nominal_mm; ///< wheelbase_nm of the parameter block
    double ed_fw;        ///< ed of the block in force (1.0 uncalibrated)
    double eb_fw;        ///< eb of the block in force
} umb_setup_t;

/// Return error (x, y mm; theta rad, wrapped) of one noise-free run for a true Ed and b.
void umb_exact_forward(const umb_setup_t *s, double ed_true, double b_true_mm, int ccw, double out[3]);

typedef struct {
    double ed;             ///< fitted true DR/DL (= the block's new ed)
    double b_mm;           ///< fitted true effective wheelbase (block eb = b_mm / b_nominal)
    double residual_mm;    ///< rms misfit of the four cg coordinates at the solution
    double sv_min, sv_max; ///< singular values of the scaled Jacobian (identifiability)
    bool identifiable;     ///< sv_min / sv_max above 1e-9 and both singular values non-zero
    bool converged;
    int iterations;
} umb_fit_t;

/// Levenberg-Marquardt fit of (Ed, b) to cg[dir][x, y] (dir 0 cw, 1 ccw; mm), starting at
/// (ed0, b0_mm) (the paper method's answer). Returns 0, or -1 (message in err) if the start is not
/// finite or positive or the fit leaves the physical range (Ed in [0.5, 2], b in [0.2, 5] x
/// nominal).
int umb_exact_fit(const umb_setup_t *s, const double cg[2][2], double ed0, double b0_mm, umb_fit_t *out, char *err,
                  unsigned errlen);

#endif
