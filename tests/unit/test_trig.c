/// Accuracy and symmetry of the binary-angle trigonometry in firmware/src/odo_trig.c, measured
/// against libm in double precision. The bounds asserted here are the product requirements of
/// odo_fx.h (sin/cos <= 2e-8, atan2 <= 1e-7 rad); the measured maxima are printed so regressions
/// toward the bound show up long before they fail.
#include <math.h>
#include <stdint.h>
#include <stdio.h>

#include "odo/odo_fx.h"
#include "test_support.h"
#include "unity.h"

#define SINCOS_BOUND    2e-8
#define ATAN2_BOUND_RAD 1e-7
#define RANDOM_INPUTS   (1UL << 20) // >= 10^6 per function
#define TWO_PI          6.283185307179586476925286766559
#define RAD_PER_BAM     (TWO_PI / 4294967296.0)

void setUp(void) {}
void tearDown(void) {}

static double bam_to_rad(uint32_t a) { return (double)a * RAD_PER_BAM; }
static double q30_to_double(int32_t v) { return (double)v / 1073741824.0; }

/// Difference of two angles wrapped into [-pi, pi], so 2 pi - eps and 0 are eps apart.
static double angle_diff_rad(double a, double b) { return remainder(a - b, TWO_PI); }

static double sin_err(uint32_t a) { return fabs(q30_to_double(odo_sin_q30(a)) - sin(bam_to_rad(a))); }

static double cos_err(uint32_t a) { return fabs(q30_to_double(odo_cos_q30(a)) - cos(bam_to_rad(a))); }

static double atan2_err_rad(int64_t y, int64_t x)
{
    return fabs(angle_diff_rad(bam_to_rad(odo_atan2_bam(y, x)), atan2((double)y, (double)x)));
}

static double max_d(double a, double b) { return a > b ? a : b; }

static void report(const char *what, double max_err, unsigned long n)
{
    char msg[128];
    snprintf(msg, sizeof msg, "%s: max abs error %.3e over %lu inputs", what, max_err, n);
    TEST_MESSAGE(msg);
}

/// The table plus A&S 4.3.65/4.3.66's short series on the remainder, folded to [0, pi/4], meets
/// 2e-8 everywhere on the circle. Uniform random BAMs sample every octant and every remainder bit.
static void test_sin_cos_within_2e8_over_a_million_random_angles(void)
{
    ts_rng_t rng;
    ts_rng_seed(&rng, 0x5EED0001ULL);
    double worst_sin = 0.0;
    double worst_cos = 0.0;
    for (unsigned long i = 0; i < RANDOM_INPUTS; i++) {
        const uint32_t a = (uint32_t)ts_rng_u64(&rng);
        worst_sin = max_d(worst_sin, sin_err(a));
        worst_cos = max_d(worst_cos, cos_err(a));
    }
    report("sin", worst_sin, RANDOM_INPUTS);
    report("cos", worst_cos, RANDOM_INPUTS);
    TEST_ASSERT_LESS_OR_EQUAL_DOUBLE(SINCOS_BOUND, worst_sin);
    TEST_ASSERT_LESS_OR_EQUAL_DOUBLE(SINCOS_BOUND, worst_cos);
}

/// The node table behind sin/cos (odo_sin_table_q31): entry i is round(sin(i pi / 128) 2^31) for
/// i = 0..64, computed here with libm (each entry is at least 0.005 LSB from a rounding tie, far
/// beyond libm's error), and entry 64 is exactly 1.0.
static void test_sin_table_entries_are_the_rounded_sines(void)
{
    TEST_ASSERT_EQUAL_UINT32(65U, ODO_SIN_TABLE_SIZE);
    for (uint32_t i = 0U; i < ODO_SIN_TABLE_SIZE; i++) {
        const double want = floor(sin((double)i * (TWO_PI / 256.0)) * 2147483648.0 + 0.5);
        TEST_ASSERT_EQUAL_UINT32((uint32_t)want, odo_sin_table_q31[i]);
    }
    TEST_ASSERT_EQUAL_UINT32(1UL << 31, odo_sin_table_q31[64]);
}

/// The octant fold: every boundary k * pi/4 (k = 0..8, so 0 and UINT32_MAX are both hit) and
/// +-1..3 BAM around it, where the fold switches between mirrored and direct remainders and
/// between the sin and cos polynomials.
static void test_sin_cos_within_2e8_at_and_around_every_octant_boundary(void)
{
    double worst = 0.0;
    unsigned long n = 0;
    for (uint32_t k = 0; k <= 8U; k++) {
        for (int32_t off = -3; off <= 3; off++) {
            const uint32_t a = (uint32_t)(k * ((uint32_t)1U << 29) + (uint32_t)off);
            worst = max_d(worst, max_d(sin_err(a), cos_err(a)));
            n++;
        }
    }
    worst = max_d(worst, max_d(sin_err(UINT32_MAX), cos_err(UINT32_MAX)));
    report("sin/cos at octant boundaries", worst, n + 1U);
    TEST_ASSERT_LESS_OR_EQUAL_DOUBLE(SINCOS_BOUND, worst);
}

/// On the axes the fold lands on x = 0, where both polynomials are exact: sin and cos are exactly
/// 0 and +-1.0 (Q30), with no spurious -0 or off-by-one LSB.
static void test_sin_cos_are_exact_on_the_axes(void)
{
    const int32_t one = ODO_Q30_ONE;
    TEST_ASSERT_EQUAL_INT32(0, odo_sin_q30(0U));
    TEST_ASSERT_EQUAL_INT32(one, odo_cos_q30(0U));
    TEST_ASSERT_EQUAL_INT32(one, odo_sin_q30((uint32_t)ODO_BAM_QUARTER));
    TEST_ASSERT_EQUAL_INT32(0, odo_cos_q30((uint32_t)ODO_BAM_QUARTER));
    TEST_ASSERT_EQUAL_INT32(0, odo_sin_q30((uint32_t)ODO_BAM_HALF));
    TEST_ASSERT_EQUAL_INT32(-one, odo_cos_q30((uint32_t)ODO_BAM_HALF));
    TEST_ASSERT_EQUAL_INT32(-one, odo_sin_q30(3U * (uint32_t)ODO_BAM_QUARTER));
    TEST_ASSERT_EQUAL_INT32(0, odo_cos_q30(3U * (uint32_t)ODO_BAM_QUARTER));
}

/// The fold is symmetric: sin(-a) == -sin(a), cos(-a) == cos(a), sin(pi - a) == sin(a) and
/// cos(a) == sin(a + pi/2) hold bit for bit, and odo_sincos_q30 returns exactly the pair that
/// odo_sin_q30 and odo_cos_q30 return separately.
static void test_sin_cos_symmetries_hold_bit_for_bit(void)
{
    ts_rng_t rng;
    ts_rng_seed(&rng, 0x5EED0002ULL);
    for (unsigned long i = 0; i < (1UL << 16); i++) {
        const uint32_t a = (uint32_t)ts_rng_u64(&rng);
        const int32_t s = odo_sin_q30(a);
        const int32_t c = odo_cos_q30(a);
        int32_t s2 = 0;
        int32_t c2 = 0;
        odo_sincos_q30(a, &s2, &c2);
        TEST_ASSERT_EQUAL_INT32(s, s2);
        TEST_ASSERT_EQUAL_INT32(c, c2);
        TEST_ASSERT_EQUAL_INT32(-s, odo_sin_q30(0U - a));
        TEST_ASSERT_EQUAL_INT32(c, odo_cos_q30(0U - a));
        TEST_ASSERT_EQUAL_INT32(s, odo_sin_q30((uint32_t)ODO_BAM_HALF - a));
        TEST_ASSERT_EQUAL_INT32(c, odo_sin_q30(a + (uint32_t)ODO_BAM_QUARTER));
    }
}

/// sin^2 + cos^2 = 1 within 2 * sqrt(2) times the per-function error, so a rotation built from
/// odo_sincos_q30 keeps vector lengths to a few parts in 10^9.
static void test_sin_squared_plus_cos_squared_is_one(void)
{
    ts_rng_t rng;
    ts_rng_seed(&rng, 0x5EED0003ULL);
    double worst = 0.0;
    for (unsigned long i = 0; i < (1UL << 18); i++) {
        const uint32_t a = (uint32_t)ts_rng_u64(&rng);
        int32_t s = 0;
        int32_t c = 0;
        odo_sincos_q30(a, &s, &c);
        const double sd = q30_to_double(s);
        const double cd = q30_to_double(c);
        worst = max_d(worst, fabs(sd * sd + cd * cd - 1.0));
    }
    report("|sin^2 + cos^2 - 1|", worst, 1UL << 18);
    TEST_ASSERT_LESS_OR_EQUAL_DOUBLE(2.83 * SINCOS_BOUND, worst);
}

/// (cos, sin) of k pi/16 for k = 0..7 in Q30, as integers: the atan2 inputs below are built from
/// these and integer arithmetic only, so they are bit-identical on every platform (libm's sin/cos
/// differ in the last bit between glibc and newlib, and tests/target compares host and Cortex-M4
/// output byte for byte).
static const int64_t k_dir_q30[8][2] = {
    {1073741824, 0},        {1053110176, 209476638}, {992008094, 410903207}, {892783698, 596538995},
    {759250125, 759250125}, {596538995, 892783698},  {410903207, 992008094}, {209476638, 1053110176},
};

/// round(p * 2^(e - 50)) with the rounding half away from zero, for |p| < 2^51 and 0 <= e <= 62.
static int64_t scale_pow2(int64_t p, int e)
{
    const uint64_t mag = p < 0 ? (uint64_t)(-p) : (uint64_t)p;
    const uint64_t r = e >= 50 ? mag << (e - 50) : (mag + (1ULL << (49 - e))) >> (50 - e);
    return p < 0 ? -(int64_t)r : (int64_t)r;
}

/// One random vector for atan2. Three shapes in turn, so that every octant, every scale from 1
/// to 2^62, near-axis directions and the raw int64 range (INT64_MIN included) are all sampled.
static void random_vector(ts_rng_t *rng, unsigned long i, int64_t *y, int64_t *x)
{
    switch (i % 3U) {
    case 0: { // polar: any direction, magnitude 2^e * [1, 1.99), e in [0, 62]
        /* One of 32 fixed directions k pi/16 (a table entry turned by k/8 quarter turns), turned
         * by a random d in [-pi/32, pi/32] with cos d ~ 1 - d^2/2, sin d ~ d - d^3/6 (Q30): the
         * direction only has to be spread evenly, not exact; |(c, s)| = 1 within 1e-5. */
        const int64_t k = ts_rng_range(rng, 0, 31);
        int64_t c = k_dir_q30[k % 8][0];
        int64_t s = k_dir_q30[k % 8][1];
        for (int64_t q = 0; q < k / 8; ++q) {
            const int64_t t = c;
            c = -s;
            s = t;
        }
        const int64_t d = ts_rng_range(rng, -105414357, 105414357); // pi/32 in Q30
        const int64_t d2 = d * d / ODO_Q30_ONE;
        const int64_t cd = ODO_Q30_ONE - d2 / 2;
        const int64_t sd = d - d2 * d / ODO_Q30_ONE / 6;
        const int64_t cx = (c * cd - s * sd) / ODO_Q30_ONE;
        const int64_t sy = (s * cd + c * sd) / ODO_Q30_ONE;
        const int64_t m_q20 = ts_rng_range(rng, 1 << 20, 2086666); // [1, 1.99) in Q20
        const int e = (int)ts_rng_range(rng, 0, 62);
        *x = scale_pow2(cx * m_q20, e);
        *y = scale_pow2(sy * m_q20, e);
        break;
    }
    case 1: { // independent magnitudes 2^e..2^(e+1)-1, e in [0, 62]: steep and flat vectors
        const int ex = (int)ts_rng_range(rng, 0, 62);
        const int ey = (int)ts_rng_range(rng, 0, 62);
        const uint64_t lx = ts_rng_u64(rng) & (((uint64_t)1U << ex) - 1U);
        const uint64_t ly = ts_rng_u64(rng) & (((uint64_t)1U << ey) - 1U);
        const int64_t mx = (int64_t)(((uint64_t)1U << ex) | lx);
        const int64_t my = (int64_t)(((uint64_t)1U << ey) | ly);
        *x = (ts_rng_u64(rng) & 1U) != 0U ? -mx : mx;
        *y = (ts_rng_u64(rng) & 1U) != 0U ? -my : my;
        break;
    }
    default: // the raw int64 range
        *x = (int64_t)ts_rng_u64(rng);
        *y = (int64_t)ts_rng_u64(rng);
        break;
    }
}

/// A&S 4.4.42 on |u| <= tan(pi/8) after the octant fold: atan2 meets 1e-7 rad for every direction
/// and every magnitude from 1 to 2^63.
static void test_atan2_within_1e7_rad_over_a_million_random_vectors(void)
{
    ts_rng_t rng;
    ts_rng_seed(&rng, 0x5EED0004ULL);
    double worst = 0.0;
    for (unsigned long i = 0; i < RANDOM_INPUTS; i++) {
        int64_t y = 0;
        int64_t x = 0;
        random_vector(&rng, i, &y, &x);
        worst = max_d(worst, atan2_err_rad(y, x));
    }
    report("atan2 (rad)", worst, RANDOM_INPUTS);
    TEST_ASSERT_LESS_OR_EQUAL_DOUBLE(ATAN2_BOUND_RAD, worst);
}

/// Axes and diagonals are exact multiples of pi/4 in BAM at every scale, INT64_MIN and INT64_MAX
/// included (|INT64_MIN| = 2^63 has no int64 form; the magnitudes are taken unsigned).
static void test_atan2_is_exact_on_axes_and_diagonals(void)
{
    const int64_t mags[] = {
        1, 2, 3, 1000, INT32_MAX, (int64_t)1 << 32, (int64_t)1 << 62, INT64_MAX,
    };
    const uint32_t eighth = (uint32_t)1U << 29;
    for (size_t i = 0; i < sizeof mags / sizeof mags[0]; i++) {
        const int64_t m = mags[i];
        TEST_ASSERT_EQUAL_HEX32(0U, odo_atan2_bam(0, m));
        TEST_ASSERT_EQUAL_HEX32(1U * eighth, odo_atan2_bam(m, m));
        TEST_ASSERT_EQUAL_HEX32(2U * eighth, odo_atan2_bam(m, 0));
        TEST_ASSERT_EQUAL_HEX32(3U * eighth, odo_atan2_bam(m, -m));
        TEST_ASSERT_EQUAL_HEX32(4U * eighth, odo_atan2_bam(0, -m));
        TEST_ASSERT_EQUAL_HEX32(5U * eighth, odo_atan2_bam(-m, -m));
        TEST_ASSERT_EQUAL_HEX32(6U * eighth, odo_atan2_bam(-m, 0));
        TEST_ASSERT_EQUAL_HEX32(7U * eighth, odo_atan2_bam(-m, m));
    }
    TEST_ASSERT_EQUAL_HEX32(4U * eighth, odo_atan2_bam(0, INT64_MIN));
    TEST_ASSERT_EQUAL_HEX32(6U * eighth, odo_atan2_bam(INT64_MIN, 0));
    TEST_ASSERT_EQUAL_HEX32(5U * eighth, odo_atan2_bam(INT64_MIN, INT64_MIN));
}

/// odo_fx.h: (0, 0) has no direction and returns 0 rather than failing.
static void test_atan2_of_the_zero_vector_is_zero(void) { TEST_ASSERT_EQUAL_HEX32(0U, odo_atan2_bam(0, 0)); }

/// The awkward inputs: INT64_MIN/INT64_MAX mixed, unit-sized vectors, near-axis vectors of
/// extreme aspect, y = x +- 1 at large x (the diagonal octant boundary, where the rounding shift
/// sees equal operands), and both sides of the tan(pi/8) branch switch of the fold.
static void test_atan2_within_1e7_rad_on_edge_vectors(void)
{
    const int64_t big = INT64_MAX;
    const int64_t big2 = (int64_t)1 << 62;
    const int64_t edges[][2] = {
        {INT64_MIN, INT64_MAX},
        {INT64_MAX, INT64_MIN},
        {INT64_MIN, -INT64_MAX},
        {-INT64_MAX, INT64_MIN},
        {INT64_MAX, INT64_MAX - 1},
        {INT64_MIN, INT64_MIN + 1},
        {INT64_MIN + 1, INT64_MIN},
        {1, 0},
        {0, -1},
        {1, 1},
        {-1, -1},
        {-1, 0},
        {0, 1},
        {1, -1},
        {-1, 1},
        {1, 2},
        {2, 1},
        {1, 3},
        {3, -1},
        {-2, -5},
        {1, INT64_MAX},
        {-1, INT64_MAX},
        {1, INT64_MIN},
        {-1, INT64_MIN},
        {INT64_MAX, 1},
        {INT64_MIN, 1},
        {INT64_MAX, -1},
        {INT64_MIN, -1},
        {big2 + 1, big2},
        {big2 - 1, big2},
        {big2, big2 + 1},
        {big2, big2 - 1},
        {-(big2 + 1), big2},
        {big2 - 1, -big2},
        {big - 1, big},
        {big, big - 1},
        {((int64_t)1 << 33) + 1, (int64_t)1 << 33},
        {((int64_t)1 << 31) - 1, (int64_t)1 << 31},
    };
    double worst = 0.0;
    unsigned long n = 0;
    for (size_t i = 0; i < sizeof edges / sizeof edges[0]; i++) {
        worst = max_d(worst, atan2_err_rad(edges[i][0], edges[i][1]));
        n++;
    }
    // Around y = x tan(pi/8) at several scales: the fold switches between t and (1-t)/(1+t).
    const double tan_pi_8 = 0.41421356237309504880;
    for (int e = 3; e <= 62; e += 7) {
        const int64_t x = (int64_t)1 << e;
        const int64_t y0 = (int64_t)llround(ldexp(tan_pi_8, e));
        for (int64_t k = -3; k <= 3; k++) {
            worst = max_d(worst, atan2_err_rad(y0 + k, x));
            worst = max_d(worst, atan2_err_rad(-(y0 + k), -x));
            worst = max_d(worst, atan2_err_rad(x, y0 + k));
            n += 3U;
        }
    }
    report("atan2 edges (rad)", worst, n);
    TEST_ASSERT_LESS_OR_EQUAL_DOUBLE(ATAN2_BOUND_RAD, worst);
}

/// atan2 undoes sincos: the direction of (cos a, sin a) in Q30 comes back to a within the sin/cos
/// requirement (measured: about one BAM), which bounds the combined error of both halves.
static void test_atan2_recovers_the_angle_of_sincos(void)
{
    ts_rng_t rng;
    ts_rng_seed(&rng, 0x5EED0005ULL);
    double worst = 0.0;
    for (unsigned long i = 0; i < (1UL << 18); i++) {
        const uint32_t a = (uint32_t)ts_rng_u64(&rng);
        int32_t s = 0;
        int32_t c = 0;
        odo_sincos_q30(a, &s, &c);
        const uint32_t back = odo_atan2_bam(s, c);
        worst = max_d(worst, fabs((double)(int32_t)(back - a)) * RAD_PER_BAM);
    }
    report("atan2(sincos(a)) - a (rad)", worst, 1UL << 18);
    TEST_ASSERT_LESS_OR_EQUAL_DOUBLE(SINCOS_BOUND, worst);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_sin_table_entries_are_the_rounded_sines);
    RUN_TEST(test_sin_cos_within_2e8_over_a_million_random_angles);
    RUN_TEST(test_sin_cos_within_2e8_at_and_around_every_octant_boundary);
    RUN_TEST(test_sin_cos_are_exact_on_the_axes);
    RUN_TEST(test_sin_cos_symmetries_hold_bit_for_bit);
    RUN_TEST(test_sin_squared_plus_cos_squared_is_one);
    RUN_TEST(test_atan2_within_1e7_rad_over_a_million_random_vectors);
    RUN_TEST(test_atan2_is_exact_on_axes_and_diagonals);
    RUN_TEST(test_atan2_of_the_zero_vector_is_zero);
    RUN_TEST(test_atan2_within_1e7_rad_on_edge_vectors);
    RUN_TEST(test_atan2_recovers_the_angle_of_sincos);
    return UNITY_END();
}
