#include "follower.h"

#include <math.h>
#include <string.h>

/* Cross-track loop: e'' = v * w, with w = -2 z wn e_theta - wn^2 e / v gives
 * e'' + 2 z wn e' + wn^2 e = 0; critically damped at wn = 1 rad/s. */
#define WN_RAD_S 1.0
#define MIN_STEER_SPEED_MM_S 50.0
#define LINE_DONE_MM 0.5
#define TURN_DONE_RAD (0.01 * M_PI / 180.0)

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

static double steer(double v, double cross_mm, double heading_err)
{
    double vs = fabs(v) < MIN_STEER_SPEED_MM_S ? copysign(MIN_STEER_SPEED_MM_S, v == 0.0 ? 1.0 : v) : v;
    return -2.0 * WN_RAD_S * heading_err - WN_RAD_S * WN_RAD_S * cross_mm / vs;
}

/// Returns true while the segment is still running.
static bool step_line(sim_follower_t *f, const sim_segment_t *s, double x, double y, double th,
                      double out[2])
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
    const double wheel = ramp(fabs(f->w_rad_s) * half_b, s->speed_mm_s, s->accel_mm_s2,
                              fabs(err) * half_b, f->dt_s);
    const double w = copysign(wheel / half_b, err);
    f->v_mm_s = 0.0;
    f->w_rad_s = w;
    wheels(f, 0.0, w, out);
    return true;
}

static bool step_arc(sim_follower_t *f, const sim_segment_t *s, double x, double y, double th,
                     double out[2])
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

bool sim_follower_step(sim_follower_t *f, double x_mm, double y_mm, double theta_rad, double wheel_mm_s[2])
{
    wheel_mm_s[0] = wheel_mm_s[1] = 0.0;
    while (f->seg < f->prog->n_seg) {
        const sim_segment_t *s = &f->prog->seg[f->seg];
        bool running = false;
        switch (s->kind) {
        case SIM_SEG_LINE: running = step_line(f, s, x_mm, y_mm, theta_rad, wheel_mm_s); break;
        case SIM_SEG_TURN: running = step_turn(f, s, theta_rad, wheel_mm_s); break;
        case SIM_SEG_ARC: running = step_arc(f, s, x_mm, y_mm, theta_rad, wheel_mm_s); break;
        case SIM_SEG_PAUSE:
            running = f->seg_time_s < s->pause_s;
            f->v_mm_s = f->w_rad_s = 0.0;
            break;
        }
        if (running) {
            f->seg_time_s += f->dt_s;
            return true;
        }
        /* Flowing segments (arc <-> line) keep their speed; stops and turns restart from rest. */
        const bool flowing = s->kind == SIM_SEG_ARC ||
                             (f->seg + 1 < f->prog->n_seg && f->prog->seg[f->seg + 1].kind == SIM_SEG_ARC);
        if (!flowing) {
            f->v_mm_s = f->w_rad_s = 0.0;
        }
        f->seg++;
        f->seg_time_s = 0.0;
    }
    return false;
}
