/// Bump geometry: a rigid wheel of radius R rolling over a thin obstacle of height h (a cable, a
/// crack edge, a floor-roughness grain), and what it does to odometry.
///
/// Two models, selectable per scenario (effects catalog, parameter `model`):
///
///   exact   The wheel pivots about the obstacle's edge C (it cannot roll into the corner), so its
///           centre O swings on a circle of radius R about C from the contact angle
///           psi0 = acos(1 - h/R) up to vertical, and down again on the far side. The wheel turns
///           by the angle swept, so the encoder reports D_meas = R * psi0 per flank while the centre
///           advances only D_hor = sqrt(2Rh - h^2) (004_997ef9ec5c850202.txt Eq. 2, which is exact).
///           dD = 2 * (R * acos(1 - h/R) - sqrt(2Rh - h^2)).
///   paper   004_997ef9ec5c850202.txt Eqs. 1-3: D_meas ~= sqrt(D_hor^2 + h^2), the chord O-O'
///           instead of the arc. Physically that is a wheel rolling up a straight ramp from O to O',
///           which is how the profile below models it (constant excess per mm of rotation).
///
/// For R 75, h 10 mm: paper dD 2.63 mm (004 Table I), exact dD 3.51 mm. With b 340 mm those give
/// dtheta 0.44 deg and 0.59 deg (Eq. 4); the exact value matches the ~0.6 deg per bump the paper
/// itself observed (004 s. 6.1, DESIGN.md s. 7).
///
/// Profile: the world needs to know how the heading error builds up while the wheel is on the
/// bump (004 s. 4, Fig. 5 inset: the error grows over the few centimetres of the bump, it is not a
/// step). A bump is parametrised by the wheel's rotation since first contact, s in [0, 2 D_meas]
/// (arc length R * angle), or by the centre's horizontal progress u in [0, 2 D_hor]; the two are
/// monotonic functions of each other, and excess(s) = s - u(s) rises from 0 to dD. A bump of
/// finite top width adds a flat plateau with no excess, so a thin bump is the general case.
///
/// Pure functions, no state, reentrant, constant time.
#ifndef SIM_BUMP_H
#define SIM_BUMP_H

#include <stdbool.h>

typedef enum {
    SIM_BUMP_PAPER = 0, ///< 004 Eq. 3 chord approximation (reproduces Table I)
    SIM_BUMP_EXACT = 1  ///< rigid wheel pivoting about the step edge
} sim_bump_model_t;

/// Geometry of one bump under one wheel. All lengths in mm, per flank unless stated.
typedef struct {
    sim_bump_model_t model;
    double radius_mm; ///< R, the wheel's true rolling radius
    double height_mm; ///< h
    double d_hor_mm;  ///< centre's horizontal advance per flank, 004 Eq. 2 (both models)
    double d_meas_mm; ///< rotation (arc length) per flank: paper Eq. 3 chord, exact R * psi0
    double dd_mm;     ///< linear error over the whole bump, 004 Eq. 1: 2 (D_meas - D_hor)
    double psi0_rad;  ///< contact angle acos(1 - h/R) (exact model; also stored for paper)
} sim_bump_geom_t;

/// Fill *g for a wheel of radius R over a bump of height h. h == 0 gives a null bump (all zero).
/// Returns false (and leaves *g zeroed) iff g is NULL, R <= 0, h < 0, h >= R, a value is not
/// finite, or the model is unknown.
bool sim_bump_geom(double radius_mm, double height_mm, sim_bump_model_t model, sim_bump_geom_t *g);

/// Orientation error after the bump, 004 Eq. 4: asin(dD / b). NaN iff b <= 0 or |dD| > b.
double sim_bump_dtheta_rad(double dd_mm, double wheelbase_mm);

/// Lateral error after travelling `distance_mm` straight past the bump, 004 Eq. 5: D * dD / b.
double sim_bump_elat_mm(double dd_mm, double wheelbase_mm, double distance_mm);

/// Rotation (arc length) the wheel turns over the whole bump: 2 * D_meas.
double sim_bump_span_rot_mm(const sim_bump_geom_t *g);

/// Horizontal distance the centre covers over the whole bump: 2 * D_hor.
double sim_bump_span_hor_mm(const sim_bump_geom_t *g);

/// Horizontal progress of the centre after the wheel has turned by arc `s_mm` since first contact.
/// s is clamped to [0, span_rot]; beyond the bump the caller adds plain rolling itself.
double sim_bump_hor_of_rot(const sim_bump_geom_t *g, double s_mm);

/// Inverse of sim_bump_hor_of_rot: rotation needed for horizontal progress `u_mm` (clamped to
/// [0, span_hor]). Used for passive wheels (the trailer), which are pushed horizontally.
double sim_bump_rot_of_hor(const sim_bump_geom_t *g, double u_mm);

/// Excess rotation so far, s - u(s): rises monotonically from 0 to dd_mm.
double sim_bump_excess_mm(const sim_bump_geom_t *g, double s_mm);

/// Lift of the wheel centre above the floor at horizontal progress u (0 at both ends, h on top).
double sim_bump_lift_mm(const sim_bump_geom_t *g, double u_mm);

/// "paper" / "exact"; NULL for an unknown value.
const char *sim_bump_model_name(sim_bump_model_t m);

/// Parse "paper" / "exact". Returns false iff the name is neither (or NULL).
bool sim_bump_model_parse(const char *name, sim_bump_model_t *out);

#endif
