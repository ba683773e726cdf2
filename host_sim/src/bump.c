/// Bump geometry and profile; see bump.h for the models and their derivation.
#include "bump.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

bool sim_bump_geom(double radius_mm, double height_mm, sim_bump_model_t model, sim_bump_geom_t *g)
{
    if (g == NULL) {
        return false;
    }
    memset(g, 0, sizeof *g);
    if (!isfinite(radius_mm) || !isfinite(height_mm) || radius_mm <= 0.0 || height_mm < 0.0 || height_mm >= radius_mm ||
        (model != SIM_BUMP_PAPER && model != SIM_BUMP_EXACT)) {
        return false;
    }
    g->model = model;
    g->radius_mm = radius_mm;
    g->height_mm = height_mm;
    if (height_mm == 0.0) {
        return true;
    }
    const double r = radius_mm, h = height_mm;
    g->d_hor_mm = sqrt(2.0 * r * h - h * h); /* 004_997ef9ec5c850202.txt Eq. 2 */
    g->psi0_rad = acos(1.0 - h / r);         /* contact angle: cos psi0 = (R - h) / R */
    if (model == SIM_BUMP_PAPER) {
        g->d_meas_mm = sqrt(g->d_hor_mm * g->d_hor_mm + h * h); /* 004 Eq. 3 (chord O-O') */
    } else {
        g->d_meas_mm = r * g->psi0_rad; /* arc swept about the edge: wheel rotation */
    }
    g->dd_mm = 2.0 * (g->d_meas_mm - g->d_hor_mm); /* 004 Eq. 1: up and down */
    return true;
}

double sim_bump_dtheta_rad(double dd_mm, double wheelbase_mm)
{
    if (!(wheelbase_mm > 0.0) || fabs(dd_mm) > wheelbase_mm) {
        return NAN;
    }
    return asin(dd_mm / wheelbase_mm); /* 004 Eq. 4 */
}

double sim_bump_elat_mm(double dd_mm, double wheelbase_mm, double distance_mm)
{
    return distance_mm * dd_mm / wheelbase_mm; /* 004 Eq. 5 */
}

double sim_bump_span_rot_mm(const sim_bump_geom_t *g) { return 2.0 * g->d_meas_mm; }

double sim_bump_span_hor_mm(const sim_bump_geom_t *g) { return 2.0 * g->d_hor_mm; }

static double clamp(double v, double lo, double hi) { return v < lo ? lo : (v > hi ? hi : v); }

/* Climb flank only (s in [0, D_meas]); the descent mirrors it about the top. */
static double climb_hor_of_rot(const sim_bump_geom_t *g, double s)
{
    if (g->model == SIM_BUMP_PAPER) {
        return s * (g->d_hor_mm / g->d_meas_mm); /* straight ramp O-O' */
    }
    /* Centre at angle psi from vertical about the edge: u = D_hor - R sin(psi), psi = psi0 - s/R. */
    return g->d_hor_mm - g->radius_mm * sin(g->psi0_rad - s / g->radius_mm);
}

static double climb_rot_of_hor(const sim_bump_geom_t *g, double u)
{
    if (g->model == SIM_BUMP_PAPER) {
        return u * (g->d_meas_mm / g->d_hor_mm);
    }
    const double sin_psi = clamp((g->d_hor_mm - u) / g->radius_mm, 0.0, 1.0);
    return g->radius_mm * (g->psi0_rad - asin(sin_psi));
}

double sim_bump_hor_of_rot(const sim_bump_geom_t *g, double s_mm)
{
    if (g->d_meas_mm <= 0.0) {
        return 0.0;
    }
    const double dm = g->d_meas_mm;
    const double s = clamp(s_mm, 0.0, 2.0 * dm);
    if (s <= dm) {
        return climb_hor_of_rot(g, s);
    }
    return 2.0 * g->d_hor_mm - climb_hor_of_rot(g, 2.0 * dm - s);
}

double sim_bump_rot_of_hor(const sim_bump_geom_t *g, double u_mm)
{
    if (g->d_hor_mm <= 0.0) {
        return 0.0;
    }
    const double dh = g->d_hor_mm;
    const double u = clamp(u_mm, 0.0, 2.0 * dh);
    if (u <= dh) {
        return climb_rot_of_hor(g, u);
    }
    return 2.0 * g->d_meas_mm - climb_rot_of_hor(g, 2.0 * dh - u);
}

double sim_bump_excess_mm(const sim_bump_geom_t *g, double s_mm)
{
    const double s = clamp(s_mm, 0.0, sim_bump_span_rot_mm(g));
    return s - sim_bump_hor_of_rot(g, s);
}

double sim_bump_lift_mm(const sim_bump_geom_t *g, double u_mm)
{
    if (g->d_hor_mm <= 0.0) {
        return 0.0;
    }
    const double dh = g->d_hor_mm;
    double u = clamp(u_mm, 0.0, 2.0 * dh);
    if (u > dh) {
        u = 2.0 * dh - u;
    }
    if (g->model == SIM_BUMP_PAPER) {
        return g->height_mm * u / dh;
    }
    const double x = dh - u; /* horizontal distance of the centre from the edge */
    return sqrt(g->radius_mm * g->radius_mm - x * x) - (g->radius_mm - g->height_mm);
}

const char *sim_bump_model_name(sim_bump_model_t m)
{
    switch (m) {
    case SIM_BUMP_PAPER: return "paper";
    case SIM_BUMP_EXACT: return "exact";
    }
    return NULL;
}

bool sim_bump_model_parse(const char *name, sim_bump_model_t *out)
{
    if (name == NULL) {
        return false;
    }
    if (strcmp(name, "paper") == 0) {
        *out = SIM_BUMP_PAPER;
        return true;
    }
    if (strcmp(name, "exact") == 0) {
        *out = SIM_BUMP_EXACT;
        return true;
    }
    return false;
}
