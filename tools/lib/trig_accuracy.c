#include "trig_accuracy.h"

#include <math.h>
#include <stddef.h>

#include "odo/odo_fx.h"

#define TWO_PI      6.283185307179586476925286766559
#define RAD_PER_BAM (TWO_PI / 4294967296.0)

/// splitmix64 (Steele, Lea, Flood 2014): the same generator as tests/support, kept local so that
/// tools/ does not depend on tests/.
static uint64_t splitmix64(uint64_t *state)
{
    uint64_t z = (*state += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

/// Uniform in [0, 1) with 53 random bits.
static double unit_uniform(uint64_t *state) { return (double)(splitmix64(state) >> 11) * (1.0 / 9007199254740992.0); }

static double max_d(double a, double b) { return a > b ? a : b; }

static double sincos_err(uint32_t a)
{
    const double th = (double)a * RAD_PER_BAM;
    const double es = fabs((double)odo_sin_q30(a) / 1073741824.0 - sin(th));
    const double ec = fabs((double)odo_cos_q30(a) / 1073741824.0 - cos(th));
    return max_d(es, ec);
}

static double atan2_err_rad(int64_t y, int64_t x)
{
    const double got = (double)odo_atan2_bam(y, x) * RAD_PER_BAM;
    return fabs(remainder(got - atan2((double)y, (double)x), TWO_PI));
}

/// One random vector, cycling through three shapes so every octant, every scale from 1 to 2^62,
/// extreme aspect ratios and the raw int64 range (INT64_MIN included) are sampled.
static void random_vector(uint64_t *state, uint32_t i, int64_t *y, int64_t *x)
{
    switch (i % 3U) {
    case 0: { // uniform direction, magnitude 2^e * [1, 2), e in [0, 62]
        const double th = TWO_PI * unit_uniform(state);
        const double r = ldexp(1.0 + 0.99 * unit_uniform(state), (int)(splitmix64(state) % 63U));
        *x = (int64_t)llround(r * cos(th));
        *y = (int64_t)llround(r * sin(th));
        break;
    }
    case 1: { // independent magnitudes in [2^e, 2^(e+1)), e in [0, 62], random signs
        const unsigned ex = (unsigned)(splitmix64(state) % 63U);
        const unsigned ey = (unsigned)(splitmix64(state) % 63U);
        const uint64_t bits = splitmix64(state);
        const int64_t mx = (int64_t)(((uint64_t)1U << ex) | (bits & (((uint64_t)1U << ex) - 1U)));
        const int64_t my = (int64_t)(((uint64_t)1U << ey) | (splitmix64(state) & (((uint64_t)1U << ey) - 1U)));
        *x = (bits >> 63) != 0U ? -mx : mx;
        *y = ((bits >> 62) & 1U) != 0U ? -my : my;
        break;
    }
    default:
        *x = (int64_t)splitmix64(state);
        *y = (int64_t)splitmix64(state);
        break;
    }
}

static double sincos_worst(uint64_t seed, uint32_t n)
{
    double worst = 0.0;
    for (uint32_t k = 0; k <= 8U; k++) {
        for (uint32_t off = 0; off <= 6U; off++) { // k * pi/4 + (-3 .. +3) BAM, wrapping
            worst = max_d(worst, sincos_err(k * ((uint32_t)1U << 29) + off - 3U));
        }
    }
    uint64_t state = seed;
    for (uint32_t i = 0; i < n; i++) {
        worst = max_d(worst, sincos_err((uint32_t)splitmix64(&state)));
    }
    return worst;
}

static double atan2_worst(uint64_t seed, uint32_t n)
{
    const int64_t g = (int64_t)1 << 62;
    static const int64_t edges[][2] = {
        {0, 0},
        {1, 0},
        {0, -1},
        {1, 1},
        {-1, -1},
        {-1, 0},
        {0, 1},
        {1, -1},
        {-1, 1},
        {INT64_MAX, INT64_MAX},
        {INT64_MIN, INT64_MIN},
        {INT64_MIN, INT64_MAX},
        {INT64_MAX, INT64_MIN},
        {INT64_MIN, 0},
        {0, INT64_MIN},
        {INT64_MAX, 0},
        {0, INT64_MAX},
        {INT64_MIN, INT64_MIN + 1},
        {INT64_MAX, INT64_MAX - 1},
        {INT64_MAX - 1, INT64_MAX},
        {1, INT64_MAX},
        {-1, INT64_MIN},
        {INT64_MAX, 1},
        {INT64_MIN, -1},
    };
    double worst = 0.0;
    for (size_t i = 0; i < sizeof edges / sizeof edges[0]; i++) {
        worst = max_d(worst, atan2_err_rad(edges[i][0], edges[i][1]));
    }
    for (int64_t k = -1; k <= 1; k += 2) { // y = x +- 1 at large x: the diagonal octant boundary
        worst = max_d(worst, atan2_err_rad(g + k, g));
        worst = max_d(worst, atan2_err_rad(g, g + k));
        worst = max_d(worst, atan2_err_rad(-(g + k), g));
    }
    uint64_t state = seed ^ 0xA7A2A7A2A7A2A7A2ULL; // independent of the sin/cos stream
    for (uint32_t i = 0; i < n; i++) {
        int64_t y = 0;
        int64_t x = 0;
        random_vector(&state, i, &y, &x);
        worst = max_d(worst, atan2_err_rad(y, x));
    }
    return worst;
}

void odo_trig_accuracy(uint64_t seed, uint32_t n, double *sincos_max_abs_err, double *atan2_max_abs_err_rad)
{
    if (sincos_max_abs_err != NULL) {
        *sincos_max_abs_err = sincos_worst(seed, n);
    }
    if (atan2_max_abs_err_rad != NULL) {
        *atan2_max_abs_err_rad = atan2_worst(seed, n);
    }
}
