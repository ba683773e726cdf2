#include "program.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "odo/odo_types.h"

const char *const sim_experiment_names[] = {"umbmark", "umbmark-ext", "straight-36m", "rect-7x4", NULL};

static sim_segment_t *add(sim_program_t *p, sim_seg_kind_t kind)
{
    sim_segment_t *s = &p->seg[p->n_seg++];
    memset(s, 0, sizeof *s);
    s->kind = kind;
    return s;
}

static void line(sim_program_t *p, double x0, double y0, double x1, double y1, double v, double a)
{
    sim_segment_t *s = add(p, SIM_SEG_LINE);
    s->x0_mm = x0;
    s->y0_mm = y0;
    s->x1_mm = x1;
    s->y1_mm = y1;
    s->speed_mm_s = v;
    s->accel_mm_s2 = a;
    p->path_mm += hypot(x1 - x0, y1 - y0);
}

static void turn(sim_program_t *p, double heading, double wheel_speed, double a)
{
    sim_segment_t *s = add(p, SIM_SEG_TURN);
    s->heading_rad = heading;
    s->speed_mm_s = wheel_speed;
    s->accel_mm_s2 = a;
}

static void pause_for(sim_program_t *p, double seconds) { add(p, SIM_SEG_PAUSE)->pause_s = seconds; }

static void arc(sim_program_t *p, double cx, double cy, double r, double from_angle, double sweep, double v, double a)
{
    sim_segment_t *s = add(p, SIM_SEG_ARC);
    s->cx_mm = cx;
    s->cy_mm = cy;
    s->radius_mm = r;
    s->x0_mm = cx + r * cos(from_angle);
    s->y0_mm = cy + r * sin(from_angle);
    s->sweep_rad = sweep;
    s->speed_mm_s = v;
    s->accel_mm_s2 = a;
    p->path_mm += fabs(sweep) * r;
}

/// 000 s. 3.5 / 6.3: 4 m legs at 0.2 m/s, full stop, 90 deg on the spot with wheel speeds of
/// about 0.2 m/s, four turns (the fourth brings the robot back to its start heading).
static void umbmark(sim_program_t *p)
{
    const double side = 4000.0, v = 200.0, a = 200.0, dir = p->ccw ? 1.0 : -1.0;
    double x = 0.0, y = 0.0, heading = 0.0;
    for (int leg = 0; leg < 4; ++leg) {
        const double nx = x + side * cos(heading), ny = y + side * sin(heading);
        line(p, x, y, round(nx), round(ny), v, a);
        x = round(nx);
        y = round(ny);
        pause_for(p, 1.0);
        heading += dir * M_PI / 2.0;
        turn(p, heading, v, a);
        pause_for(p, 1.0);
    }
}

/// Bumps evenly on [from, from + length) of the path: at the middle of N equal parts.
static int spread_bumps(sim_program_t *p, int n, double from, double length, uint8_t side, double h)
{
    if (n < 0 || (size_t)n > SIM_PROGRAM_MAX_BUMPS) {
        return -1;
    }
    for (int k = 0; k < n; ++k) {
        sim_bump_t *b = &p->bump[p->n_bumps++];
        b->at_path_mm = from + length * (k + 0.5) / n;
        b->side = side;
        b->height_mm = h;
    }
    return 0;
}

int sim_program_build(const char *experiment, int ccw, int bumps, double bump_height_mm, unsigned run_index,
                      sim_program_t *out, char *err, size_t errlen)
{
    memset(out, 0, sizeof *out);
    out->ccw = ccw ? 1 : 0;
    snprintf(out->name, sizeof out->name, "%s", experiment);
    int rc = 0;
    if (strcmp(experiment, "umbmark") == 0) {
        umbmark(out);
        rc = spread_bumps(out, bumps < 0 ? 0 : bumps, 0.0, 4000.0, (uint8_t)(out->ccw ? ODO_LEFT : ODO_RIGHT),
                          bump_height_mm);
    } else if (strcmp(experiment, "umbmark-ext") == 0) {
        /* 000 s. 3.4: the bumps go under the wheel facing the inside of the square, on leg 1. */
        umbmark(out);
        rc = spread_bumps(out, bumps < 0 ? 10 : bumps, 0.0, 4000.0, (uint8_t)(out->ccw ? ODO_LEFT : ODO_RIGHT),
                          bump_height_mm);
    } else if (strcmp(experiment, "straight-36m") == 0) {
        /* 004 s. 6.1: out 18 m, stop, back 18 m driving backward; bumps under the right wheels on
         * the return leg only. Direction has no meaning here. */
        line(out, 0.0, 0.0, 18000.0, 0.0, 450.0, 300.0);
        pause_for(out, 2.0);
        line(out, 18000.0, 0.0, 0.0, 0.0, -450.0, 300.0);
        rc = spread_bumps(out, bumps < 0 ? 10 : bumps, 18000.0, 18000.0, ODO_RIGHT, bump_height_mm);
    } else if (strcmp(experiment, "rect-7x4") == 0) {
        /* 004 s. 6.2: pass by the corners of a 7 x 4 m rectangle with smooth 90 deg turns
         * (radius 0.5 m here), ~0.5 m/s, no stops; 10 bumps, right side on even runs, left on odd. */
        const double w = 7000.0, hgt = 4000.0, r = 500.0, v = 480.0, a = 300.0;
        const double s = out->ccw ? 1.0 : -1.0; /* y grows to the left (ccw) or right (cw) */
        line(out, 0.0, 0.0, w - r, 0.0, v, a);
        arc(out, w - r, s * r, r, -s * M_PI / 2.0, s * M_PI / 2.0, v, a);
        line(out, w, s * r, w, s * (hgt - r), v, a);
        arc(out, w - r, s * (hgt - r), r, 0.0, s * M_PI / 2.0, v, a);
        line(out, w - r, s * hgt, r, s * hgt, v, a);
        arc(out, r, s * (hgt - r), r, s * M_PI / 2.0, s * M_PI / 2.0, v, a);
        line(out, 0.0, s * (hgt - r), 0.0, s * r, v, a);
        arc(out, r, s * r, r, M_PI, s * M_PI / 2.0, v, a);
        line(out, r, 0.0, r + 1.0, 0.0, v, a); /* settle on the home heading */
        rc = spread_bumps(out, bumps < 0 ? 10 : bumps, 0.0, out->path_mm, (run_index % 2U) == 0U ? ODO_RIGHT : ODO_LEFT,
                          bump_height_mm);
    } else {
        snprintf(err, errlen, "unknown experiment '%s' (one of: umbmark, umbmark-ext, straight-36m, rect-7x4)",
                 experiment);
        return -1;
    }
    if (rc != 0) {
        snprintf(err, errlen, "%d bumps do not fit (at most %d)", bumps, SIM_PROGRAM_MAX_BUMPS);
        return -1;
    }
    return 0;
}

int sim_program_for_clapper(sim_program_t *p, double link_length_mm)
{
    if (!(link_length_mm > 0.0)) {
        return -1;
    }
    const double half = link_length_mm / 2.0;
    double x = 0.0, y = 0.0, heading = 0.0; /* nominal pose of truck A */
    double ox = 0.0, oy = 0.0;              /* offset the rigid turns so far put on A's path */
    for (size_t i = 0; i < p->n_seg; ++i) {
        sim_segment_t *s = &p->seg[i];
        switch (s->kind) {
        case SIM_SEG_LINE: {
            s->x0_mm += ox;
            s->y0_mm += oy;
            s->x1_mm += ox;
            s->y1_mm += oy;
            x = s->x1_mm;
            y = s->y1_mm;
            const double dx = s->x1_mm - s->x0_mm, dy = s->y1_mm - s->y0_mm;
            heading = atan2(dy, dx) + (s->speed_mm_s < 0.0 ? M_PI : 0.0);
            break;
        }
        case SIM_SEG_ARC: {
            s->x0_mm += ox;
            s->y0_mm += oy;
            s->cx_mm += ox;
            s->cy_mm += oy;
            const double a1 = atan2(s->y0_mm - s->cy_mm, s->x0_mm - s->cx_mm) + s->sweep_rad;
            x = s->cx_mm + s->radius_mm * cos(a1);
            y = s->cy_mm + s->radius_mm * sin(a1);
            heading += s->sweep_rad;
            break;
        }
        case SIM_SEG_TURN: {
            const double sweep = remainder(s->heading_rad - heading, 2.0 * M_PI);
            s->x0_mm = x;
            s->y0_mm = y;
            s->cx_mm = x - half * cos(heading);
            s->cy_mm = y - half * sin(heading);
            s->radius_mm = half;
            s->sweep_rad = sweep;
            heading = s->heading_rad;
            s->x1_mm = s->cx_mm + half * cos(heading);
            s->y1_mm = s->cy_mm + half * sin(heading);
            ox += s->x1_mm - x;
            oy += s->y1_mm - y;
            x = s->x1_mm;
            y = s->y1_mm;
            break;
        }
        case SIM_SEG_PAUSE: break;
        }
    }
    return 0;
}
