#include "ratelimit.h"

#include <math.h>

int sim_rate_limit(const double *v, const double *lim, size_t n, double *out)
{
    if (v == NULL || lim == NULL || out == NULL) {
        return -1;
    }
    double cur = 0.0;
    for (size_t i = 0; i < n; ++i) {
        const double d = v[i] - cur;
        cur += d > lim[i] ? lim[i] : (d < -lim[i] ? -lim[i] : d);
        out[i] = cur;
    }
    return 0;
}

/* one step of the plane limiter (a friction circle): (cx, cy) towards (vx, vy) by at most lim */
static void follow(double vx, double vy, double lim, double *cx, double *cy)
{
    const double dx = vx - *cx, dy = vy - *cy, m = hypot(dx, dy);
    const double f = m > lim ? lim / m : 1.0;
    *cx += f * dx;
    *cy += f * dy;
}

int sim_rate_limit_2d(const double *vx, const double *vy, const double *lim, size_t n, double *ox, double *oy)
{
    if (vx == NULL || vy == NULL || lim == NULL || ox == NULL || oy == NULL) {
        return -1;
    }
    double cx = 0.0, cy = 0.0;
    for (size_t i = 0; i < n; ++i) {
        follow(vx[i], vy[i], lim[i], &cx, &cy);
        ox[i] = cx;
        oy[i] = cy;
    }
    return 0;
}

int sim_rate_limit_track(const double *pose, size_t n, const double *dt, double acc, double *out)
{
    if (pose == NULL || dt == NULL || out == NULL || pose == out) {
        return -1;
    }
    if (n == 0U) {
        return 0;
    }
    /* the operations numpy made in model.py skid_friction before (bit for bit, test_gap_speed):
     * each step's velocity, the friction circle's limiter on it (cx, cy), then each axis's
     * running sum of u dt started at its first term, with the start added to every sum */
    double cx = 0.0, cy = 0.0, sx = 0.0, sy = 0.0;
    out[0] = pose[0];
    out[1] = pose[1];
    out[2] = pose[2];
    for (size_t i = 0; i + 1U < n; ++i) {
        const double *a = pose + 3U * i, *b = a + 3U;
        follow((b[0] - a[0]) / dt[i], (b[1] - a[1]) / dt[i], acc * dt[i], &cx, &cy);
        sx = i == 0U ? cx * dt[i] : sx + cx * dt[i];
        sy = i == 0U ? cy * dt[i] : sy + cy * dt[i];
        double *o = out + 3U * (i + 1U);
        o[0] = sx + pose[0];
        o[1] = sy + pose[1];
        o[2] = b[2];
    }
    return 0;
}
