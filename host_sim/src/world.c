/// True kinematics with effects; see world.h for the model and its conventions.
#include "world.h"
#include "odo_err.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* ---------------------------------------------------------------------------------------------
 * Seeded randomness: splitmix64, one stream per wheel so each wheel's roughness is independent of
 * what the others do (and of how many trucks the vehicle has).
 * ------------------------------------------------------------------------------------------- */
static uint64_t splitmix64(uint64_t *s)
{
    uint64_t z = (*s += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

static double uniform01(uint64_t *s) { return (double)(splitmix64(s) >> 11) * (1.0 / 9007199254740992.0); }

static double wrap_pi(double a)
{
    a = fmod(a, 2.0 * M_PI);
    if (a > M_PI) {
        a -= 2.0 * M_PI;
    } else if (a <= -M_PI) {
        a += 2.0 * M_PI;
    }
    return a;
}

static bool eff_on(const sim_world_t *w, sim_effect_id_t id, unsigned t)
{
    return sim_scenario_enabled_on(&w->sc, id, t);
}

static double eff_p(const sim_world_t *w, sim_effect_id_t id, unsigned t, size_t k) { return w->sc.eff[id][t].p[k]; }

static unsigned n_trucks(const sim_world_t *w) { return w->robot.n_trucks; }

static bool driven(const sim_world_t *w, unsigned t)
{
    return t == ODO_TRUCK_A || w->robot.vehicle == SIM_VEHICLE_CLAPPER;
}

/* ---------------------------------------------------------------------------------------------
 * Set-up
 * ------------------------------------------------------------------------------------------- */
static int truck_radii(sim_world_t *w, unsigned t, char *err, size_t errlen)
{
    const sim_truck_desc_t *d = &w->robot.truck[t];
    sim_truck_state_t *ts = &w->truck[t];
    ts->r_nominal_mm = 0.5 * d->wheel_diameter_mm;
    ts->counts_per_rev = sim_robot_counts_per_rev(d);
    ts->b_true_mm = d->wheelbase_mm * (eff_on(w, SIM_EFFECT_EB, t) ? eff_p(w, SIM_EFFECT_EB, t, SIM_P_EB_VALUE) : 1.0);
    /* 000 App. B: Es = L_calc/L_actual, so the true mean diameter is Dn / Es. */
    const double d_mean =
        d->wheel_diameter_mm / (eff_on(w, SIM_EFFECT_ES, t) ? eff_p(w, SIM_EFFECT_ES, t, SIM_P_ES_VALUE) : 1.0);
    /* 000 Eqs. 6.30-6.32: Ed = DR/DL with the mean kept: DL = 2 Da/(Ed + 1), DR = 2 Da/(1/Ed + 1). */
    const double ed = eff_on(w, SIM_EFFECT_ED, t) ? eff_p(w, SIM_EFFECT_ED, t, SIM_P_ED_VALUE) : 1.0;
    double r[2] = {d_mean / (ed + 1.0), d_mean / (1.0 / ed + 1.0)};
    if (eff_on(w, SIM_EFFECT_TIRE_COMPRESSION, t)) {
        const double k = eff_p(w, SIM_EFFECT_TIRE_COMPRESSION, t, SIM_P_TIRE_K);
        const double m = eff_p(w, SIM_EFFECT_TIRE_COMPRESSION, t, SIM_P_TIRE_LOAD);
        const double off = eff_p(w, SIM_EFFECT_TIRE_COMPRESSION, t, SIM_P_TIRE_OFFSET);
        const double b = d->wheelbase_mm;
        if (fabs(off) >= 0.5 * b) {
            return odo_errf(err, errlen,
                            "tire_compression.lateral_offset_mm: |%g| must be below half the "
                            "wheelbase of truck %c (%g mm)",
                            off, (char)('A' + t), 0.5 * b);
        }
        /* Static lever rule: the load sits `off` left of the centre. */
        r[ODO_LEFT] -= k * m * (0.5 * b + off) / b;
        r[ODO_RIGHT] -= k * m * (0.5 * b - off) / b;
    }
    for (unsigned wh = 0; wh < 2U; ++wh) {
        if (!(r[wh] > 1.0)) {
            return odo_errf(err, errlen, "truck %c %s wheel: the effects leave a radius of %g mm", (char)('A' + t),
                            wh == ODO_LEFT ? "left" : "right", r[wh]);
        }
        ts->wheel[wh].radius_mm = r[wh];
    }
    ts->bump_model = (sim_bump_model_t)(int)eff_p(w, SIM_EFFECT_BUMPS, t, SIM_P_BUMPS_MODEL);
    ts->rough_model = (sim_bump_model_t)(int)eff_p(w, SIM_EFFECT_ROUGHNESS, t, SIM_P_ROUGH_MODEL);
    return 0;
}

static double rough_gap(sim_world_t *w, unsigned t, sim_wheel_state_t *ws)
{
    const double spacing = eff_p(w, SIM_EFFECT_ROUGHNESS, t, SIM_P_ROUGH_SPACING);
    const double jitter = eff_p(w, SIM_EFFECT_ROUGHNESS, t, SIM_P_ROUGH_JITTER);
    return spacing * (1.0 + jitter * (2.0 * uniform01(&ws->rng) - 1.0));
}

int sim_world_init(sim_world_t *w, const sim_robot_t *robot, const sim_scenario_t *sc, uint64_t seed, char *err,
                   size_t errlen)
{
    if (w == NULL || robot == NULL || sc == NULL) {
        return odo_errf(err, errlen, "sim_world_init: NULL argument");
    }
    memset(w, 0, sizeof *w);
    w->robot = *robot;
    w->sc = *sc;
    w->seed = seed;
    if (w->robot.n_trucks < 1U || w->robot.n_trucks > ODO_TRUCKS) {
        return odo_errf(err, errlen, "sim_world_init: robot has %u trucks", w->robot.n_trucks);
    }
    for (unsigned t = 0; t < n_trucks(w); ++t) {
        if (truck_radii(w, t, err, errlen) != 0) {
            return -1;
        }
        for (unsigned wh = 0; wh < 2U; ++wh) {
            sim_wheel_state_t *ws = &w->truck[t].wheel[wh];
            uint64_t s = seed ^ (0xD1B54A32D192ED03ULL * (uint64_t)(1U + 2U * t + wh));
            ws->rng = splitmix64(&s);
            if (eff_on(w, SIM_EFFECT_ROUGHNESS, t)) {
                /* First grain at a random phase of the spacing. */
                ws->next_rough_mm = eff_p(w, SIM_EFFECT_ROUGHNESS, t, SIM_P_ROUGH_SPACING) * uniform01(&ws->rng);
            }
        }
    }
    for (size_t i = 0; i < sc->n_bumps; ++i) {
        const sim_scenario_bump_t *b = &sc->bump[i];
        if (b->truck >= n_trucks(w)) {
            return odo_errf(err, errlen, "scenario bump %zu is under truck B, but a %s has one truck", i,
                            sim_vehicle_name(w->robot.vehicle));
        }
        if (!eff_on(w, SIM_EFFECT_BUMPS, b->truck)) {
            continue;
        }
        if (sim_world_add_bump(w, b->truck, b->wheel, b->distance_mm, b->height_mm) != 0) {
            return odo_errf(err, errlen,
                            "scenario bump %zu (height %g mm at %g mm) does not fit under truck %c's wheel", i,
                            b->height_mm, b->distance_mm, (char)('A' + b->truck));
        }
    }
    sim_world_place(w, 0.0, 0.0, 0.0);
    return 0;
}

void sim_world_place(sim_world_t *w, double x_mm, double y_mm, double theta_rad)
{
    w->truck[0].pose = (sim_pose_t){x_mm, y_mm, theta_rad};
    const double c = cos(theta_rad), s = sin(theta_rad);
    if (w->robot.vehicle == SIM_VEHICLE_CLAPPER) {
        const double l = w->robot.link.length_mm;
        w->truck[1].pose = (sim_pose_t){x_mm - l * c, y_mm - l * s, theta_rad};
    } else if (w->robot.vehicle == SIM_VEHICLE_SET) {
        const double back = w->robot.set.hitch_offset_mm + w->robot.set.trailer_length_mm;
        w->truck[1].pose = (sim_pose_t){x_mm - back * c, y_mm - back * s, theta_rad};
    }
}

int sim_world_add_bump(sim_world_t *w, unsigned truck, unsigned wheel, double at_distance_mm, double height_mm)
{
    if (w == NULL || truck >= n_trucks(w) || wheel > 1U || !isfinite(at_distance_mm) || !isfinite(height_mm) ||
        height_mm < 0.0 || height_mm >= w->truck[truck].wheel[wheel].radius_mm) {
        return -1;
    }
    sim_wheel_state_t *ws = &w->truck[truck].wheel[wheel];
    if (ws->n_pending >= SIM_WORLD_MAX_PENDING) {
        w->bumps_dropped++;
        return -1;
    }
    size_t i = ws->n_pending;
    while (i > 0 && ws->pending[i - 1].at_mm > at_distance_mm) { /* keep ascending; stable for ties */
        ws->pending[i] = ws->pending[i - 1];
        --i;
    }
    ws->pending[i].at_mm = at_distance_mm;
    ws->pending[i].height_mm = height_mm;
    ws->n_pending++;
    return 0;
}

/* ---------------------------------------------------------------------------------------------
 * Bumps under a wheel
 * ------------------------------------------------------------------------------------------- */
static void activate(sim_world_t *w, sim_wheel_state_t *ws, sim_bump_model_t model, double height_mm)
{
    if (ws->n_active >= SIM_WORLD_MAX_ACTIVE) {
        w->bumps_dropped++;
        return;
    }
    sim_active_bump_t *a = &ws->active[ws->n_active];
    if (!sim_bump_geom(ws->radius_mm, height_mm, model, &a->g) || a->g.d_meas_mm <= 0.0) {
        return; /* null bump (h == 0): nothing to do */
    }
    a->progress_mm = 0.0;
    ws->n_active++;
}

/* Driven wheel: the floor-contact arc `arc` (magnitude) is given; returns the horizontal progress
 * (magnitude). Each active bump takes away its excess over the part of the arc spent on it
 * (bump.h profile); overlapping grains add up, which is exact for one and fine for tiny ones. */
static double driven_progress(sim_wheel_state_t *ws, double arc)
{
    double excess = 0.0;
    size_t keep = 0;
    for (size_t i = 0; i < ws->n_active; ++i) {
        sim_active_bump_t *a = &ws->active[i];
        const double s0 = a->progress_mm, s1 = s0 + arc;
        excess += sim_bump_excess_mm(&a->g, s1) - sim_bump_excess_mm(&a->g, s0);
        a->progress_mm = s1;
        if (s1 < sim_bump_span_rot_mm(&a->g)) {
            ws->active[keep++] = *a;
        }
    }
    ws->n_active = keep;
    const double hor = arc - excess;
    return hor > 0.0 ? hor : 0.0;
}

/* Passive wheel: the horizontal progress `hor` (magnitude) is imposed; returns the rotation arc. */
static double passive_rotation(sim_wheel_state_t *ws, double hor)
{
    double extra = 0.0;
    size_t keep = 0;
    for (size_t i = 0; i < ws->n_active; ++i) {
        sim_active_bump_t *a = &ws->active[i];
        const double span = sim_bump_span_hor_mm(&a->g);
        const double u0 = a->progress_mm, u1 = u0 + hor, u1c = u1 < span ? u1 : span;
        extra += (sim_bump_rot_of_hor(&a->g, u1c) - sim_bump_rot_of_hor(&a->g, u0)) - (u1c - u0);
        a->progress_mm = u1;
        if (u1 < span) {
            ws->active[keep++] = *a;
        }
    }
    ws->n_active = keep;
    return hor + extra;
}

/* Contact point of a wheel. */
static void wheel_point(const sim_truck_state_t *ts, unsigned wh, double *x, double *y)
{
    const double half = (wh == ODO_LEFT ? 0.5 : -0.5) * ts->b_true_mm;
    *x = ts->pose.x_mm - half * sin(ts->pose.theta_rad);
    *y = ts->pose.y_mm + half * cos(ts->pose.theta_rad);
}

/* Advance the odometer and start every bump it has now reached (after the pose update, so events
 * carry the wheel's position). */
static void reach_bumps(sim_world_t *w, unsigned t, unsigned wh, double hor)
{
    sim_truck_state_t *ts = &w->truck[t];
    sim_wheel_state_t *ws = &ts->wheel[wh];
    ws->odometer_mm += hor;
    size_t done = 0;
    while (done < ws->n_pending && ws->pending[done].at_mm <= ws->odometer_mm) {
        activate(w, ws, ts->bump_model, ws->pending[done].height_mm);
        if (w->n_events < SIM_WORLD_MAX_EVENTS) {
            sim_bump_event_t *e = &w->events[w->n_events++];
            e->t_s = w->t_s;
            e->truck = (uint8_t)t;
            e->wheel = (uint8_t)wh;
            wheel_point(ts, wh, &e->x_mm, &e->y_mm);
            e->height_mm = ws->pending[done].height_mm;
            e->at_distance_mm = ws->odometer_mm;
        } else {
            w->events_dropped++;
        }
        ++done;
    }
    if (done > 0) {
        memmove(&ws->pending[0], &ws->pending[done], (ws->n_pending - done) * sizeof ws->pending[0]);
        ws->n_pending -= done;
    }
    if (eff_on(w, SIM_EFFECT_ROUGHNESS, t)) {
        const double hmax = eff_p(w, SIM_EFFECT_ROUGHNESS, t, SIM_P_ROUGH_MAX_HEIGHT);
        while (ws->next_rough_mm <= ws->odometer_mm) {
            activate(w, ws, ts->rough_model, hmax * uniform01(&ws->rng));
            ws->next_rough_mm += rough_gap(w, t, ws);
        }
    }
}

/* ---------------------------------------------------------------------------------------------
 * Kinematics
 * ------------------------------------------------------------------------------------------- */
/* Move a truck by horizontal wheel advances (signed) along the exact arc of constant curvature
 * (000 Eqs. 2.3-2.5 with the chord of the arc instead of Eq. 2.6's tangent), plus a sideways
 * displacement `lateral` (body y); the heading change is scaled by `turn_factor` (scrub_factor). */
static void move_truck(sim_truck_state_t *ts, double du_l, double du_r, double lateral, double turn_factor)
{
    const double d = 0.5 * (du_l + du_r);
    const double dth = turn_factor * (du_r - du_l) / ts->b_true_mm;
    const double half = 0.5 * dth;
    const double chord = fabs(half) > 1e-9 ? d * sin(half) / half : d;
    const double mid = ts->pose.theta_rad + half;
    ts->pose.x_mm += chord * cos(mid) - lateral * sin(mid);
    ts->pose.y_mm += chord * sin(mid) + lateral * cos(mid);
    ts->pose.theta_rad += dth;
}

static double slip_factor(const sim_world_t *w, unsigned t, double cmd, double prev, double dt)
{
    if (!eff_on(w, SIM_EFFECT_SLIP, t)) {
        return 1.0;
    }
    const double a = fabs(cmd - prev) / dt * 1e-3; /* m/s^2 */
    const double k = eff_p(w, SIM_EFFECT_SLIP, t, SIM_P_SLIP_K);
    const double a0 = eff_p(w, SIM_EFFECT_SLIP, t, SIM_P_SLIP_A0);
    const double cap = eff_p(w, SIM_EFFECT_SLIP, t, SIM_P_SLIP_MAX);
    double s = k * (a > a0 ? a - a0 : 0.0);
    s = s < cap ? s : cap;
    /* Speeding up, the wheel spins: floor = (1 - s) * surface. Slowing down, it drags: surface =
     * (1 - s) * floor. */
    return fabs(cmd) >= fabs(prev) ? 1.0 - s : 1.0 / (1.0 - s);
}

int sim_world_set_hidden(sim_world_t *w, const sim_hidden_t *h, char *err, size_t errlen)
{
    if (w == NULL || h == NULL) {
        return odo_errf(err, errlen, "sim_world_set_hidden: NULL argument");
    }
    const double v[5] = {h->motor_tau_s, fabs(h->diam_var_amp), h->diam_var_period_s, fabs(h->diam_drift_per_s),
                         h->backlash_rad};
    for (size_t i = 0; i < 5; ++i) {
        if (!isfinite(v[i]) || v[i] < 0.0) {
            return odo_errf(err, errlen, "hidden effect %zu: %g is not a finite non-negative value", i, v[i]);
        }
    }
    if (fabs(h->diam_var_amp) >= 0.5 || (h->diam_var_amp != 0.0 && !(h->diam_var_period_s > 0.0))) {
        return odo_errf(err, errlen, "hidden diameter variation: |amp| < 0.5 and a positive period needed");
    }
    w->hidden = *h;
    return 0;
}

/* Hidden time-varying diameter: the factor on the true radius at time t. */
static double hidden_radius_factor(const sim_world_t *w)
{
    double f = 1.0;
    if (w->hidden.diam_var_amp != 0.0) {
        f += w->hidden.diam_var_amp * sin(2.0 * M_PI * w->t_s / w->hidden.diam_var_period_s);
    }
    if (w->hidden.diam_drift_per_s != 0.0) {
        f += w->hidden.diam_drift_per_s * w->t_s;
    }
    return f > 0.1 ? f : 0.1;
}

/* Hidden backlash: the motor's rotation dphi moves through the gear play first; returns the
 * wheel's rotation. play_rad starts at 0 (teeth against the backward flank), so even the first
 * forward move takes up the play, as a real gearbox at rest might. */
static double hidden_backlash(const sim_world_t *w, sim_wheel_state_t *ws, double dphi)
{
    const double bl = w->hidden.backlash_rad;
    if (!(bl > 0.0)) {
        return dphi;
    }
    double p = ws->play_rad + dphi, rot = 0.0;
    if (p > bl) {
        rot = p - bl;
        p = bl;
    } else if (p < 0.0) {
        rot = p;
        p = 0.0;
    }
    ws->play_rad = p;
    return rot;
}

/* Tyre scrub (catalog `scrub`): the heading change of the Ed/Eb/Es model times g = 1 - k m / v,
 * v = |dL| + |dR|, m = 2 min(|dL|, |dR|) when both wheels roll one way (else 0). m / v = 1 - s with
 * s = |dR - dL| / v the spin fraction: 1 on the spot (g = 1, Eb alone), b / (2R) on an arc of
 * radius R (effective wheelbase b Eb / (1 - k (1 - s))), 0 straight. Taken from the floor advances
 * of each physics step; the firmware's correction takes it from each tick's counts (the same
 * ratio wherever the wheel speeds hold over a tick). */
static double scrub_factor(const sim_world_t *w, unsigned t, double du_l, double du_r)
{
    if (!eff_on(w, SIM_EFFECT_SCRUB, t)) {
        return 1.0;
    }
    const double v = fabs(du_l) + fabs(du_r);
    if (!(v > 0.0) || !((du_l > 0.0 && du_r > 0.0) || (du_l < 0.0 && du_r < 0.0))) {
        return 1.0;
    }
    const double m = 2.0 * fmin(fabs(du_l), fabs(du_r));
    return 1.0 - eff_p(w, SIM_EFFECT_SCRUB, t, SIM_P_SCRUB_K) * m / v;
}

static void step_driven(sim_world_t *w, unsigned t, double dt, const double cmd_in[2])
{
    sim_truck_state_t *ts = &w->truck[t];
    double du[2], cmd[2] = {cmd_in[0], cmd_in[1]};
    const double rf = hidden_radius_factor(w);
    for (unsigned wh = 0; wh < 2U; ++wh) {
        sim_wheel_state_t *ws = &ts->wheel[wh];
        if (w->hidden.motor_tau_s > 0.0) { /* hidden controller dynamics: the wheel lags */
            ws->v_motor_mm_s += (cmd[wh] - ws->v_motor_mm_s) * (1.0 - exp(-dt / w->hidden.motor_tau_s));
            cmd[wh] = ws->v_motor_mm_s;
        }
        const double dphi = cmd[wh] / ts->r_nominal_mm * dt; /* the motor follows the command */
        ws->phase_rad += dphi;
        const double wrot = hidden_backlash(w, ws, dphi);
        const double arc = wrot * ws->radius_mm * rf * slip_factor(w, t, cmd[wh], ws->cmd_prev_mm_s, dt);
        ws->cmd_prev_mm_s = cmd[wh];
        const double hor = driven_progress(ws, fabs(arc));
        du[wh] = arc < 0.0 ? -hor : hor;
    }
    double lateral = 0.0;
    const double g = scrub_factor(w, t, du[0], du[1]);
    if (eff_on(w, SIM_EFFECT_SKID, t)) {
        const double v = 0.5 * (du[0] + du[1]) / dt;                /* mm/s */
        const double om = g * (du[1] - du[0]) / ts->b_true_mm / dt; /* rad/s */
        const double ac = v * om * 1e-3;                            /* m/s^2, + centre on the left */
        const double a0 = eff_p(w, SIM_EFFECT_SKID, t, SIM_P_SKID_A0);
        if (fabs(ac) > a0) {
            const double vlat = eff_p(w, SIM_EFFECT_SKID, t, SIM_P_SKID_K) * (fabs(ac) - a0) * 1e3; /* mm/s */
            lateral = (ac > 0.0 ? -vlat : vlat) * dt; /* outward, away from the centre */
        }
    }
    move_truck(ts, du[0], du[1], lateral, g);
    for (unsigned wh = 0; wh < 2U; ++wh) {
        reach_bumps(w, t, wh, fabs(du[wh]));
    }
}

/* Passive trailer of a set: the hitch H is hitch_offset behind A's centre; the axle T is L behind
 * H along the trailer heading phi and cannot move sideways, so dphi/dt = (dH/dt . n(phi)) / L with
 * n(phi) = (-sin phi, cos phi). Solved per step at the midpoint heading (two fixed-point passes),
 * then T is put back exactly L behind H so the bar length never drifts. */
static void step_trailer(sim_world_t *w, const sim_pose_t *a0)
{
    sim_truck_state_t *tr = &w->truck[1];
    const sim_pose_t *a1 = &w->truck[0].pose;
    const double hoff = w->robot.set.hitch_offset_mm, L = w->robot.set.trailer_length_mm;
    const double hx0 = a0->x_mm - hoff * cos(a0->theta_rad), hy0 = a0->y_mm - hoff * sin(a0->theta_rad);
    const double hx1 = a1->x_mm - hoff * cos(a1->theta_rad), hy1 = a1->y_mm - hoff * sin(a1->theta_rad);
    const double dhx = hx1 - hx0, dhy = hy1 - hy0;
    const double phi0 = tr->pose.theta_rad;
    double dphi = 0.0;
    for (int it = 0; it < 3; ++it) {
        const double pm = phi0 + 0.5 * dphi;
        dphi = (-dhx * sin(pm) + dhy * cos(pm)) / L;
    }
    const double phi1 = phi0 + dphi, pm = phi0 + 0.5 * dphi;
    const double tx1 = hx1 - L * cos(phi1), ty1 = hy1 - L * sin(phi1);
    const double ds = (tx1 - tr->pose.x_mm) * cos(pm) + (ty1 - tr->pose.y_mm) * sin(pm);
    tr->pose = (sim_pose_t){tx1, ty1, phi1};
    const double du[2] = {ds - 0.5 * dphi * tr->b_true_mm, ds + 0.5 * dphi * tr->b_true_mm};
    for (unsigned wh = 0; wh < 2U; ++wh) {
        sim_wheel_state_t *ws = &tr->wheel[wh];
        const double rot = passive_rotation(ws, fabs(du[wh]));
        ws->phase_rad += (du[wh] < 0.0 ? -rot : rot) / ws->radius_mm;
        reach_bumps(w, 1U, wh, fabs(du[wh]));
    }
}

bool sim_link_push(double dx, double dy, double lo_mm, double hi_mm, double ux0, double uy0, double *px, double *py)
{
    const double l = hypot(dx, dy);
    *px = 0.0;
    *py = 0.0;
    if (l >= lo_mm && l <= hi_mm) {
        return false;
    }
    const double half = 0.5 * ((l < lo_mm ? lo_mm : hi_mm) - l);
    *px = half * (l > 0.0 ? dx / l : ux0);
    *py = half * (l > 0.0 ? dy / l : uy0);
    return true;
}

long sim_link_clamp_track(const double *rel, size_t n, double lo_mm, double hi_mm, const unsigned char *gate,
                          double *push)
{
    if (rel == NULL || push == NULL || !isfinite(lo_mm) || !isfinite(hi_mm) || lo_mm > hi_mm) {
        return -1;
    }
    long acted = 0;
    double ox = 0.0, oy = 0.0; /* A's cumulative move; the link vector moves by twice it */
    for (size_t i = 0; i < n; ++i) {
        double px, py;
        if (i > 0U && (gate == NULL || gate[i] != 0U) &&
            sim_link_push(rel[2U * i] + 2.0 * ox, rel[2U * i + 1U] + 2.0 * oy, lo_mm, hi_mm, 1.0, 0.0, &px, &py)) {
            ox += px;
            oy += py;
            acted++;
        }
        push[2U * i] = ox;
        push[2U * i + 1U] = oy;
    }
    return acted;
}

/* Clapper: keep l within its mechanical range by moving both trucks equally along the link. */
static void clamp_link(sim_world_t *w)
{
    sim_pose_t *a = &w->truck[0].pose, *b = &w->truck[1].pose;
    double px, py;
    w->clamped_last = sim_link_push(a->x_mm - b->x_mm, a->y_mm - b->y_mm, w->robot.link.min_mm, w->robot.link.max_mm,
                                    cos(a->theta_rad), sin(a->theta_rad), &px, &py);
    if (!w->clamped_last) {
        return;
    }
    a->x_mm += px;
    a->y_mm += py;
    b->x_mm -= px;
    b->y_mm -= py;
    w->link_clamps++;
}

int sim_world_step(sim_world_t *w, double dt_s, const double wheel_speed_cmd_mm_s[2][2])
{
    if (w == NULL || wheel_speed_cmd_mm_s == NULL || !(dt_s > 0.0) || dt_s > SIM_WORLD_MAX_DT_S) {
        return -1;
    }
    for (unsigned t = 0; t < ODO_TRUCKS; ++t) {
        for (unsigned wh = 0; wh < 2U; ++wh) {
            if (!isfinite(wheel_speed_cmd_mm_s[t][wh])) {
                return -1;
            }
        }
    }
    const sim_pose_t a0 = w->truck[0].pose;
    for (unsigned t = 0; t < n_trucks(w); ++t) {
        if (driven(w, t)) {
            step_driven(w, t, dt_s, wheel_speed_cmd_mm_s[t]);
        }
    }
    if (w->robot.vehicle == SIM_VEHICLE_SET) {
        step_trailer(w, &a0);
    } else if (w->robot.vehicle == SIM_VEHICLE_CLAPPER) {
        clamp_link(w);
    }
    w->t_s += dt_s;
    return 0;
}

/* ---------------------------------------------------------------------------------------------
 * Accessors
 * ------------------------------------------------------------------------------------------- */
sim_pose_t sim_world_pose(const sim_world_t *w, unsigned truck)
{
    sim_pose_t none = {0.0, 0.0, 0.0};
    return truck < n_trucks(w) ? w->truck[truck].pose : none;
}

double sim_world_encoder_phase_counts(const sim_world_t *w, unsigned truck, unsigned wheel)
{
    if (truck >= n_trucks(w) || wheel > 1U) {
        return 0.0;
    }
    return w->truck[truck].wheel[wheel].phase_rad * w->truck[truck].counts_per_rev / (2.0 * M_PI);
}

double sim_world_wheel_travel_mm(const sim_world_t *w, unsigned truck, unsigned wheel)
{
    return (truck < n_trucks(w) && wheel <= 1U) ? w->truck[truck].wheel[wheel].odometer_mm : 0.0;
}

double sim_world_wheel_radius_mm(const sim_world_t *w, unsigned truck, unsigned wheel)
{
    return (truck < n_trucks(w) && wheel <= 1U) ? w->truck[truck].wheel[wheel].radius_mm : 0.0;
}

sim_link_geom_t sim_world_link_true(const sim_world_t *w)
{
    sim_link_geom_t g = {0.0, 0.0, 0.0, 0.0};
    const sim_pose_t *a = &w->truck[0].pose, *b = &w->truck[1].pose;
    if (w->robot.vehicle == SIM_VEHICLE_CLAPPER) {
        /* 002 Eq. 10 read with atan2 from B to A, so that Eq. 16 holds. */
        g.theta_l_rad = atan2(a->y_mm - b->y_mm, a->x_mm - b->x_mm);
        g.length_mm = hypot(a->x_mm - b->x_mm, a->y_mm - b->y_mm);
        g.alpha_rad = wrap_pi(a->theta_rad - g.theta_l_rad); /* 002 Eq. 11a */
        g.beta_rad = wrap_pi(b->theta_rad - g.theta_l_rad);  /* 002 Eq. 11b */
    } else if (w->robot.vehicle == SIM_VEHICLE_SET) {
        g.theta_l_rad = wrap_pi(b->theta_rad);
        g.length_mm = w->robot.set.trailer_length_mm;
        g.alpha_rad = wrap_pi(a->theta_rad - b->theta_rad);
    }
    return g;
}

static uint16_t quantise_bam16(double angle_rad, unsigned bits)
{
    const double steps = ldexp(1.0, (int)bits);
    double turns = angle_rad / (2.0 * M_PI);
    turns -= floor(turns);
    const uint32_t code = (uint32_t)llround(turns * steps) & ((1U << bits) - 1U);
    return (uint16_t)(code << (16U - bits));
}

sim_link_reading_t sim_world_link_measured(const sim_world_t *w)
{
    const sim_link_geom_t g = sim_world_link_true(w);
    sim_link_reading_t r;
    memset(&r, 0, sizeof r);
    if (w->robot.vehicle == SIM_VEHICLE_LABMATE) {
        return r;
    }
    r.alpha_rad = g.alpha_rad;
    r.beta_rad = g.beta_rad;
    r.length_mm = g.length_mm;
    if (eff_on(w, SIM_EFFECT_ROTARY_BIAS, 0U)) {
        r.alpha_rad += eff_p(w, SIM_EFFECT_ROTARY_BIAS, 0U, SIM_P_ROTARY_ALPHA) * M_PI / 180.0;
        if (w->robot.vehicle == SIM_VEHICLE_CLAPPER) {
            r.beta_rad += eff_p(w, SIM_EFFECT_ROTARY_BIAS, 0U, SIM_P_ROTARY_BETA) * M_PI / 180.0;
        }
    }
    if (eff_on(w, SIM_EFFECT_LINK_BIAS, 0U) && w->robot.vehicle == SIM_VEHICLE_CLAPPER) {
        r.length_mm += eff_p(w, SIM_EFFECT_LINK_BIAS, 0U, SIM_P_LINK_CONST) +
                       eff_p(w, SIM_EFFECT_LINK_BIAS, 0U, SIM_P_LINK_ECC) * (1.0 - cos(g.alpha_rad - g.beta_rad));
    }
    const unsigned bits =
        w->robot.link.rotary_bits >= 1U && w->robot.link.rotary_bits <= 16U ? w->robot.link.rotary_bits : 16U;
    r.alpha_bam16 = quantise_bam16(r.alpha_rad, bits);
    r.beta_bam16 = quantise_bam16(r.beta_rad, bits);
    const double res = w->robot.link.linear_resolution_mm > 0.0 ? w->robot.link.linear_resolution_mm : 0.001;
    const double q = round(r.length_mm / res) * res * 1000.0;
    r.length_um = q > 0.0 ? (uint32_t)llround(q) : 0U;
    return r;
}

const sim_bump_event_t *sim_world_bump_events(const sim_world_t *w, size_t *n)
{
    if (n != NULL) {
        *n = w->n_events;
    }
    return w->events;
}

double sim_world_count_loss_f_clk_hz(const sim_world_t *w, unsigned truck)
{
    if (truck >= n_trucks(w) || !eff_on(w, SIM_EFFECT_COUNT_LOSS, truck)) {
        return 0.0;
    }
    return eff_p(w, SIM_EFFECT_COUNT_LOSS, truck, SIM_P_COUNT_LOSS_F_CLK);
}

double sim_world_time_s(const sim_world_t *w) { return w->t_s; }

unsigned long sim_world_link_clamps(const sim_world_t *w) { return w->link_clamps; }
