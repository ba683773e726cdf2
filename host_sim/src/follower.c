#include "follower.h"

#include <math.h>
#include <string.h>

/* Cross-track loop natural frequency (see steer()); critically damped. */
#define WN_RAD_S             1.0
#define MIN_STEER_SPEED_MM_S 50.0
#define LINE_DONE_MM         0.5
#define TURN_DONE_RAD        (0.01 * M_PI / 180.0)

static double wrap_pi(double a) { return remainder(a, 2.0 * M_PI); }

void sim_follower_init(sim_follower_t *f, const sim_program_t *prog, double wheelbase_mm, double dt_s)
{
    memset(f, 0, sizeof *f);
    f->prog = prog;
    f->wheelbase_mm = wheelbase_mm;
    f->dt_s = dt_s;
}

/// Next speed on a trapezoid: accelerate by a*dt, cruise, and brake so that the distance to go
/// is covered exactly (the last step commands just what is left).
static double ramp(double v_prev, double v_max, double a, double to_go, double dt)
{
    if (to_go <= 0.0) {
        return 0.0;
    }
    double v = fmin(fabs(v_prev) + a * dt, v_max);
    v = fmin(v, sqrt(2.0 * a * to_go));
    return fmin(v, to_go / dt);
}

static void wheels(const sim_follower_t *f, double v, double w, double out[2])
{
    out[0] = v - w * f->wheelbase_mm / 2.0;
    out[1] = v + w * f->wheelbase_mm / 2.0;
}

/// Turn rate that brings cross-track error e (left of the path, mm) and heading error to zero.
/// Forward, e' = v sin(e_theta) so e'' = v w; backward (facing away from the path direction)
/// e' = -v sin(e_theta) so e'' = -v w. In both cases w = -2 zeta wn e_theta - wn^2 e / |v| gives
/// e'' + 2 zeta wn e' + wn^2 e = 0 (critically damped, zeta = 1).
static double steer(double v, double cross_mm, double heading_err)
{
    return -2.0 * WN_RAD_S * heading_err - WN_RAD_S * WN_RAD_S * cross_mm / fmax(fabs(v), MIN_STEER_SPEED_MM_S);
}

/// Returns true while the segment is still running.
static bool step_line(sim_follower_t *f, const sim_segment_t *s, double x, double y, double th, double out[2])
{
    const double dx = s->x1_mm - s->x0_mm, dy = s->y1_mm - s->y0_mm, len = hypot(dx, dy);
    const double ux = dx / len, uy = dy / len;
    const double along = (x - s->x0_mm) * ux + (y - s->y0_mm) * uy;
    const double cross = -(x - s->x0_mm) * uy + (y - s->y0_mm) * ux; /* left of the line: + */
    const double to_go = len - along;
    const bool backward = s->speed_mm_s < 0.0;
    if (to_go <= LINE_DONE_MM) {
        return false;
    }
    const double speed = ramp(f->v_mm_s, fabs(s->speed_mm_s), s->accel_mm_s2, to_go, f->dt_s);
    const double v = backward ? -speed : speed;
    /* Driving backward the robot keeps facing away from the line's direction. */
    const double want = atan2(uy, ux) + (backward ? M_PI : 0.0);
    const double w = steer(v, cross, wrap_pi(th - want));
    f->v_mm_s = v;
    f->w_rad_s = w;
    wheels(f, v, w, out);
    return true;
}

static bool step_turn(sim_follower_t *f, const sim_segment_t *s, double th, double out[2])
{
    const double err = wrap_pi(s->heading_rad - th);
    if (fabs(err) <= TURN_DONE_RAD) {
        return false;
    }
    const double half_b = f->wheelbase_mm / 2.0;
    const double wheel = ramp(fabs(f->w_rad_s) * half_b, s->speed_mm_s, s->accel_mm_s2, fabs(err) * half_b, f->dt_s);
    const double w = copysign(wheel / half_b, err);
    f->v_mm_s = 0.0;
    f->w_rad_s = w;
    wheels(f, 0.0, w, out);
    return true;
}

static bool step_arc(sim_follower_t *f, const sim_segment_t *s, double x, double y, double th, double out[2])
{
    const double dir = s->sweep_rad >= 0.0 ? 1.0 : -1.0;
    const double a0 = atan2(s->y0_mm - s->cy_mm, s->x0_mm - s->cx_mm);
    const double a = atan2(y - s->cy_mm, x - s->cx_mm);
    /* Angle swept since the arc's start (arcs here sweep at most half a turn). */
    const double done = dir * wrap_pi(a - a0);
    const double to_go = (fabs(s->sweep_rad) - done) * s->radius_mm;
    if (to_go <= LINE_DONE_MM) {
        return false;
    }
    const double r = hypot(x - s->cx_mm, y - s->cy_mm);
    /* For a ccw arc the centre is on the left: being outside (r > R) is being right of the path. */
    const double cross = dir * (s->radius_mm - r);
    const double tangent = a + dir * M_PI / 2.0;
    /* Arcs flow into the next line: no braking, only the ramp up to cruise speed. */
    const double v = fmin(fabs(f->v_mm_s) + s->accel_mm_s2 * f->dt_s, s->speed_mm_s);
    const double w = dir * v / s->radius_mm + steer(v, cross, wrap_pi(th - tangent));
    f->v_mm_s = v;
    f->w_rad_s = w;
    wheels(f, v, w, out);
    return true;
}

/// Step the program from the estimated pose. Returns 0 once finished, 1 while running, and, when
/// `yield_turns`, 2 on reaching a TURN segment without stepping it (the clapper turns its own way).
static int follow(sim_follower_t *f, double x_mm, double y_mm, double theta_rad, double wheel_mm_s[2], bool yield_turns)
{
    wheel_mm_s[0] = wheel_mm_s[1] = 0.0;
    while (f->seg < f->prog->n_seg) {
        const sim_segment_t *s = &f->prog->seg[f->seg];
        bool running = false;
        switch (s->kind) {
        case SIM_SEG_LINE: running = step_line(f, s, x_mm, y_mm, theta_rad, wheel_mm_s); break;
        case SIM_SEG_TURN:
            if (yield_turns) {
                return 2;
            }
            running = step_turn(f, s, theta_rad, wheel_mm_s);
            break;
        case SIM_SEG_ARC: running = step_arc(f, s, x_mm, y_mm, theta_rad, wheel_mm_s); break;
        case SIM_SEG_PAUSE:
            running = f->seg_time_s < s->pause_s;
            f->v_mm_s = f->w_rad_s = 0.0;
            break;
        }
        if (running) {
            f->seg_time_s += f->dt_s;
            return 1;
        }
        /* Flowing segments (arc <-> line) keep their speed; stops and turns restart from rest. */
        const bool flowing =
            s->kind == SIM_SEG_ARC || (f->seg + 1 < f->prog->n_seg && f->prog->seg[f->seg + 1].kind == SIM_SEG_ARC);
        if (!flowing) {
            f->v_mm_s = f->w_rad_s = 0.0;
        }
        f->seg++;
        f->seg_time_s = 0.0;
    }
    return 0;
}

bool sim_follower_step(sim_follower_t *f, double x_mm, double y_mm, double theta_rad, double wheel_mm_s[2])
{
    return follow(f, x_mm, y_mm, theta_rad, wheel_mm_s, false) != 0;
}

/* ---------------------------------------------------------------------------------------------
 * Clapper: truck B follows A's path l behind; rigid turns about the midpoint
 * ------------------------------------------------------------------------------------------- */
#define LINK_K_PER_S       8.0                  /* l loop: v_B = v_A + k (l_meas - l_nom) */
#define LINK_MAX_CORR_MM_S 400.0                /* cap on that correction */
#define SYNC_K_PER_S       2.0                  /* rigid turn: keeps both trucks' progress equal */
#define REL_K_PER_S        3.0                  /* rigid turn: holds each truck perpendicular to the link */
#define SPIN_SETTLE_RAD    (0.8 * M_PI / 180.0) /* a spin within this of its target ... */
#define SPIN_SETTLE_TICKS  25U                  /* ... for this many ticks is done */
#define TILT_MAX_RAD       0.35                 /* rigid turn: B's largest tilt for the l loop */

/// Cross-track steering valid in both driving directions: for a truck moving at signed speed v
/// with heading error eh (against its wanted heading) and cross-track error e (left of the path's
/// direction of travel), e' = |v| eh and e'' = |v| w, so w = -2 wn eh - wn^2 e / |v| is critically
/// damped forward and backward.
static void wheels_b(double wheelbase_mm, double v, double w, double out[2])
{
    out[0] = v - w * wheelbase_mm / 2.0;
    out[1] = v + w * wheelbase_mm / 2.0;
}

/// Truck on a LINE/ARC segment at signed speed v: its turn rate (*w) and how much of the segment
/// is left (*to_go, may be negative once past the end).
static void track_segment(const sim_segment_t *s, double x, double y, double th, double v, double *w, double *to_go)
{
    const bool backward = s->speed_mm_s < 0.0;
    if (s->kind == SIM_SEG_LINE) {
        const double dx = s->x1_mm - s->x0_mm, dy = s->y1_mm - s->y0_mm, len = hypot(dx, dy);
        const double ux = dx / len, uy = dy / len;
        const double along = (x - s->x0_mm) * ux + (y - s->y0_mm) * uy;
        const double cross = -(x - s->x0_mm) * uy + (y - s->y0_mm) * ux;
        const double want = atan2(uy, ux) + (backward ? M_PI : 0.0);
        *to_go = len - along;
        *w = steer(v, cross, wrap_pi(th - want));
    } else {
        const double dir = s->sweep_rad >= 0.0 ? 1.0 : -1.0;
        const double a0 = atan2(s->y0_mm - s->cy_mm, s->x0_mm - s->cx_mm);
        const double a = atan2(y - s->cy_mm, x - s->cx_mm);
        const double r = hypot(x - s->cx_mm, y - s->cy_mm);
        const double want = a + dir * M_PI / 2.0 + (backward ? M_PI : 0.0);
        *to_go = (fabs(s->sweep_rad) - dir * wrap_pi(a - a0)) * s->radius_mm;
        *w = dir * fabs(v) / s->radius_mm + steer(v, dir * (s->radius_mm - r), wrap_pi(th - want));
    }
}

void sim_clapper_follower_init(sim_clapper_follower_t *f, const sim_program_t *prog, double wheelbase_a_mm,
                               double wheelbase_b_mm, double link_length_mm, double dt_s)
{
    memset(f, 0, sizeof *f);
    sim_follower_init(&f->a, prog, wheelbase_a_mm, dt_s);
    f->wheelbase_b_mm = wheelbase_b_mm;
    f->l_nom_mm = link_length_mm;
}

/// On-the-spot turn of one truck to an absolute heading (as step_turn); false once there.
static bool spin(sim_clapper_follower_t *f, unsigned t, const sim_segment_t *s, double target, double th, double out[2])
{
    const double err = wrap_pi(target - th);
    out[0] = out[1] = 0.0;
    /* With IPEC's per-tick form the published heading is theta_L plus the rotary code's centre,
     * so it cannot settle finer than a rotary step: a spin that has been within SPIN_SETTLE_RAD
     * for SPIN_SETTLE_TICKS ticks is done too (otherwise the truck would chase the code forever). */
    f->spin_settled[t] = fabs(err) <= SPIN_SETTLE_RAD ? f->spin_settled[t] + 1U : 0U;
    if (fabs(err) <= TURN_DONE_RAD || f->spin_settled[t] > SPIN_SETTLE_TICKS) {
        f->w_turn_rad_s[t] = 0.0;
        return false;
    }
    const double b = t == 0U ? f->a.wheelbase_mm : f->wheelbase_b_mm, half_b = b / 2.0;
    const double wheel =
        ramp(fabs(f->w_turn_rad_s[t]) * half_b, s->speed_mm_s, s->accel_mm_s2, fabs(err) * half_b, f->a.dt_s);
    f->w_turn_rad_s[t] = copysign(wheel / half_b, err);
    wheels_b(b, 0.0, f->w_turn_rad_s[t], out);
    return true;
}

/// Phase 1 of a rigid turn: both trucks, perpendicular to the link, drive arcs of radius l/2
/// about its midpoint, A forward and B backward, turning by the sweep together. Progress is each
/// truck's heading change (equal to the link's rotation while a truck stays perpendicular to it);
/// one common ramped speed, a term that keeps the two progresses equal, a loop that holds each
/// truck's measured angle to the link at 90 deg, and B's tilt that brings l back to nominal.
/// False once the mean sweep is done.
static bool arc_about_midpoint(sim_clapper_follower_t *f, const sim_segment_t *s, const double pose[2][3],
                               const sim_link_meas_t *link, double out[2][2])
{
    const double sg = s->sweep_rad >= 0.0 ? 1.0 : -1.0, R = s->radius_mm;
    double done[2];
    for (unsigned t = 0; t < 2U; ++t) {
        done[t] = sg * wrap_pi(pose[t][2] - f->arc_th0_rad[t]);
    }
    const double mean = 0.5 * (done[0] + done[1]);
    const double to_go = (fabs(s->sweep_rad) - mean) * R;
    out[0][0] = out[0][1] = out[1][0] = out[1][1] = 0.0;
    if (to_go <= LINE_DONE_MM) {
        f->w_arc_rad_s = 0.0;
        return false;
    }
    const double v = ramp(f->w_arc_rad_s * R, s->speed_mm_s, s->accel_mm_s2, to_go, f->a.dt_s);
    f->w_arc_rad_s = v / R;
    const double r_true = link->length_mm > 0.0 ? link->length_mm / 2.0 : R;
    /* B tilts toward A (l long) or away (l short) by psi: radial speed v sin(psi). */
    const double psi = sg * fmax(-TILT_MAX_RAD, fmin(TILT_MAX_RAD, LINK_K_PER_S * (link->length_mm - f->l_nom_mm) /
                                                                       fmax(v, MIN_STEER_SPEED_MM_S)));
    for (unsigned t = 0; t < 2U; ++t) {
        const double vt = fmax(0.0, v + SYNC_K_PER_S * (mean - done[t]) * R);
        const double vs = t == 0U ? vt : -vt; /* A drives forward along the circle, B backward */
        const double rel = t == 0U ? link->alpha_rad : link->beta_rad;
        const double rel_want = sg * M_PI / 2.0 + (t == 0U ? 0.0 : psi);
        const double w = sg * vt / r_true - REL_K_PER_S * wrap_pi(rel - rel_want);
        wheels_b(t == 0U ? f->a.wheelbase_mm : f->wheelbase_b_mm, vs, w, out[t]);
    }
    return true;
}

/// The rigid turn about the midpoint (see follower.h); false once finished.
static bool rigid_turn(sim_clapper_follower_t *f, const sim_segment_t *s, const double pose[2][3],
                       const sim_link_meas_t *link, double out[2][2])
{
    const double sg = s->sweep_rad >= 0.0 ? 1.0 : -1.0;
    while (f->turn_phase < 3) {
        if (!f->phase_started) {
            f->phase_started = true;
            f->spin_settled[0] = f->spin_settled[1] = 0U;
            for (unsigned t = 0; t < 2U; ++t) {
                const double rel = t == 0U ? link->alpha_rad : link->beta_rad;
                /* Phase 0 aims each truck perpendicular to the link as measured (its centre does
                 * not move while it spins, so neither does the link); phase 2 at the new heading. */
                f->spin_target_rad[t] =
                    f->turn_phase == 0 ? pose[t][2] + wrap_pi(sg * M_PI / 2.0 - rel) : s->heading_rad;
                f->arc_th0_rad[t] = pose[t][2];
            }
        }
        if (f->turn_phase == 1) {
            if (arc_about_midpoint(f, s, pose, link, out)) {
                return true;
            }
        } else {
            const bool a = spin(f, 0U, s, f->spin_target_rad[0], pose[0][2], out[0]);
            const bool b = spin(f, 1U, s, f->spin_target_rad[1], pose[1][2], out[1]);
            if (a || b) {
                return true;
            }
        }
        f->turn_phase++;
        f->phase_started = false;
    }
    return false;
}

bool sim_clapper_follower_step(sim_clapper_follower_t *f, const double pose[2][3], const sim_link_meas_t *link,
                               double wheel_mm_s[2][2])
{
    const sim_program_t *p = f->a.prog;
    wheel_mm_s[1][0] = wheel_mm_s[1][1] = 0.0;
    int rc;
    while ((rc = follow(&f->a, pose[0][0], pose[0][1], pose[0][2], wheel_mm_s[0], true)) == 2) {
        const sim_segment_t *s = &p->seg[f->a.seg];
        if (rigid_turn(f, s, pose, link, wheel_mm_s)) {
            f->a.seg_time_s += f->a.dt_s;
            return true;
        }
        f->turn_phase = 0;
        f->phase_started = false;
        f->a.v_mm_s = f->a.w_rad_s = 0.0;
        f->a.seg++;
        f->a.seg_time_s = 0.0;
    }
    if (rc == 0) {
        f->v_b_mm_s = 0.0;
        return false;
    }
    const sim_segment_t *sa = &p->seg[f->a.seg];
    if (sa->kind != SIM_SEG_LINE && sa->kind != SIM_SEG_ARC) { /* PAUSE: both stand still */
        f->seg_b = f->a.seg;
        f->v_b_mm_s = 0.0;
        return true;
    }
    if (f->seg_b >= p->n_seg || (p->seg[f->seg_b].kind != SIM_SEG_LINE && p->seg[f->seg_b].kind != SIM_SEG_ARC)) {
        f->seg_b = f->a.seg;
    }
    /* B's speed: A's, plus what brings the measured l back to nominal (the same sign serves both
     * directions: both trucks face the same way, so v_A - v_B is the rate at which l grows). */
    const double corr =
        fmax(-LINK_MAX_CORR_MM_S, fmin(LINK_MAX_CORR_MM_S, LINK_K_PER_S * (link->length_mm - f->l_nom_mm)));
    const double v_b = f->a.v_mm_s + corr;
    double w_b = 0.0, to_go = 0.0;
    for (;;) {
        track_segment(&p->seg[f->seg_b], pose[1][0], pose[1][1], pose[1][2], v_b, &w_b, &to_go);
        const size_t next = f->seg_b + 1;
        if (to_go > LINE_DONE_MM || next >= p->n_seg ||
            (p->seg[next].kind != SIM_SEG_LINE && p->seg[next].kind != SIM_SEG_ARC)) {
            break;
        }
        f->seg_b = next; /* B passed the end of its segment: on to the next flowing one */
    }
    f->v_b_mm_s = v_b;
    wheels_b(f->wheelbase_b_mm, v_b, w_b, wheel_mm_s[1]);
    return true;
}
