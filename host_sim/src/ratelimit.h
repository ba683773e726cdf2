/// Rate limiters over a whole sequence, for the diagnosis's traction-slip and friction-skid laws
/// (tools/python/odo_tools/gap/model.py slip_traction, slip_motor, skid_friction), which run them
/// once per fit step over every tick of every run: sequential, so a loop in C, not in Python.
#ifndef SIM_RATELIMIT_H
#define SIM_RATELIMIT_H

#include <stddef.h>

/// out[i] = out[i-1] + clamp(v[i] - out[i-1], -lim[i], lim[i]) from out[-1] = 0 (the floor
/// speed that follows the wheel's v by at most lim per step). out may alias neither input.
/// 0, or -1 on a NULL array.
int sim_rate_limit(const double *v, const double *lim, size_t n, double *out);

/// The same for a plane vector (a friction circle): (ox, oy)[i] = (ox, oy)[i-1] + d min(1,
/// lim[i] / |d|), d = (vx, vy)[i] - (ox, oy)[i-1], from (0, 0). 0, or -1 on a NULL array.
int sim_rate_limit_2d(const double *vx, const double *vy, const double *lim, size_t n, double *ox, double *oy);

/// Its form on a track (model.py skid_friction, the friction circle): pose and out are
/// (n, 3) x, y, theta rows, dt the n - 1 steps (s). The wanted velocity of step i is pose's
/// (row i+1 - row i) / dt[i]; the followed one changes by at most acc dt[i] (acc in the track's
/// unit per s^2), from rest; out's x, y are pose's start plus the followed velocity's running
/// sum, out's theta pose's. out may not alias pose. 0, or -1 on a NULL or aliased array.
int sim_rate_limit_track(const double *pose, size_t n, const double *dt, double acc, double *out);

#endif
