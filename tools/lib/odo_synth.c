#include "odo_synth.h"

#include <math.h>

static uint64_t next_u64(uint64_t *state)
{
    uint64_t z = (*state += 0x9E3779B97F4A7C15ULL); /* splitmix64 */
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

static double uniform(uint64_t *state, double lo, double hi)
{
    return lo + (hi - lo) * ((double)(next_u64(state) >> 11) * (1.0 / 9007199254740992.0));
}

static double signed_mag(uint64_t *state, double lo, double hi)
{
    const double v = uniform(state, lo, hi);
    return (next_u64(state) & 1U) ? -v : v;
}

void odo_synth_init(odo_synth_t *s, uint64_t seed, const odo_truck_params_t *tp, uint32_t tick_us)
{
    s->rng = seed;
    s->k_mm = 3.14159265358979323846 * (tp->wheel_diameter_nm * 1e-6) / (tp->counts_per_rev_milli * 1e-3);
    s->b_mm = tp->wheelbase_nm * 1e-6;
    s->tick_s = tick_us * 1e-6;
    s->acc[0] = s->acc[1] = 0.0;
    s->rate[0] = s->rate[1] = 0.0;
    s->remaining = 0U;
    s->distance_mm = 0.0;
}

void odo_synth_segment(odo_synth_t *s, double v_left_mm_s, double v_right_mm_s, uint32_t ticks)
{
    s->rate[0] = v_left_mm_s * s->tick_s / s->k_mm;
    s->rate[1] = v_right_mm_s * s->tick_s / s->k_mm;
    s->remaining = ticks;
}

/// A random segment of 0.5-8 s: straight, arc, on-the-spot turn or stop, either direction.
static void random_segment(odo_synth_t *s)
{
    double vl, vr;
    const uint64_t kind = next_u64(&s->rng) % 8U;
    if (kind < 3U) { /* straight */
        vl = vr = signed_mag(&s->rng, 50.0, 1500.0);
    } else if (kind < 6U) { /* arc of radius 0.3-20 m, either side */
        const double v = signed_mag(&s->rng, 100.0, 1200.0);
        const double r = signed_mag(&s->rng, 300.0, 20000.0);
        vl = v * (1.0 - s->b_mm / (2.0 * r));
        vr = v * (1.0 + s->b_mm / (2.0 * r));
    } else if (kind < 7U) { /* turn on the spot */
        vr = signed_mag(&s->rng, 50.0, 600.0);
        vl = -vr;
    } else {
        vl = vr = 0.0;
    }
    odo_synth_segment(s, vl, vr, (uint32_t)(uniform(&s->rng, 0.5, 8.0) / s->tick_s));
}

void odo_synth_next(odo_synth_t *s, int32_t *d_left, int32_t *d_right)
{
    while (s->remaining == 0U) {
        random_segment(s);
    }
    s->remaining--;
    int32_t d[2];
    for (int w = 0; w < 2; ++w) {
        s->acc[w] += s->rate[w];
        const double whole = floor(s->acc[w]);
        s->acc[w] -= whole;
        d[w] = (int32_t)whole;
    }
    *d_left = d[0];
    *d_right = d[1];
    s->distance_mm += fabs(0.5 * (d[0] + d[1]) * s->k_mm);
}
