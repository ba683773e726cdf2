#include "odo_refcheck.h"

#include <math.h>

#include "odo/odo_odometry.h"
#include "odo_ref.h"
#include "odo_synth.h"

static double wrap_pi(double a) { return fabs(remainder(a, 2.0 * M_PI)); }

int odo_refcheck_run(uint64_t seed, uint8_t bits, uint8_t heading_form, const odo_truck_params_t *model_params,
                     const odo_truck_params_t *ref_params, double distance_mm, odo_refcheck_t *out)
{
    odo_model_t m;
    if (odo_model_init(&m, model_params, bits, heading_form, 40000U, 3000U) != ODO_MODEL_OK) {
        return -1;
    }
    odo_truck_t t;
    const odo_pose_t origin = {0, 0, 0U};
    odo_truck_reset(&t, &origin);
    odo_ref_t r;
    odo_ref_init(&r, ref_params, heading_form, 0.0, 0.0, 0.0);
    odo_synth_t s;
    odo_synth_init(&s, seed, model_params, 40000U);

    const uint64_t mask = bits >= 32U ? 0xFFFFFFFFULL : ((1ULL << bits) - 1U);
    int64_t count[2] = {(int64_t)mask - 5000, (int64_t)mask - 12345}; /* wrap early */
    odo_step_t st;
    odo_truck_step(&t, &m, (uint32_t)((uint64_t)count[0] & mask), (uint32_t)((uint64_t)count[1] & mask), bits, 1U, &st);
    out->max_pos_err_mm = 0.0;
    out->ticks = 0U;
    out->wraps = 0U;
    while (s.distance_mm < distance_mm) {
        int32_t d[2];
        odo_synth_next(&s, &d[0], &d[1]);
        for (int w = 0; w < 2; ++w) {
            const int64_t before = count[w];
            count[w] += d[w];
            if ((((uint64_t)before) & ~mask) != (((uint64_t)count[w]) & ~mask)) {
                out->wraps++;
            }
        }
        odo_truck_step(&t, &m, (uint32_t)((uint64_t)count[0] & mask), (uint32_t)((uint64_t)count[1] & mask), bits, 1U,
                       &st);
        odo_ref_step(&r, d[0], d[1]);
        out->ticks++;
        const double ex = (double)t.pose.x_mm_q32 / 4294967296.0 - r.x_mm;
        const double ey = (double)t.pose.y_mm_q32 / 4294967296.0 - r.y_mm;
        const double e = hypot(ex, ey);
        if (e > out->max_pos_err_mm) {
            out->max_pos_err_mm = e;
        }
        out->pos_err_mm = e;
    }
    const double heading = (double)t.pose.heading_q64 / 18446744073709551616.0 * 2.0 * M_PI;
    out->heading_err_rad = wrap_pi(heading - r.theta_rad);
    out->distance_mm = s.distance_mm;
    return 0;
}
