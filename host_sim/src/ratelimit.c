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

int sim_rate_limit_2d(const double *vx, const double *vy, const double *lim, size_t n, double *ox, double *oy)
{
    if (vx == NULL || vy == NULL || lim == NULL || ox == NULL || oy == NULL) {
        return -1;
    }
    double cx = 0.0, cy = 0.0;
    for (size_t i = 0; i < n; ++i) {
        const double dx = vx[i] - cx, dy = vy[i] - cy, m = hypot(dx, dy);
        const double f = m > lim[i] ? lim[i] / m : 1.0;
        cx += f * dx;
        cy += f * dy;
        ox[i] = cx;
        oy[i] = cy;
    }
    return 0;
}
