/// Sine, cosine and two-argument arctangent on binary angles (odo_fx.h), integer only.
///
/// Method
///   sin/cos  The top three BAM bits pick an octant; the 29-bit remainder (mirrored in odd
///            octants) becomes x in [0, pi/4] in Q31. sin x and cos x are the Taylor series
///            (Abramowitz & Stegun 4.3.65, 4.3.66) to x^11 and x^12 in Horner form with exact
///            integer denominators; the octant then picks which of the two answers and its sign.
///   atan2    The magnitudes fold the vector into the first octant, 0 <= n <= d. One division
///            gives t = n/d, or u = (d-n)/(d+n) when t > tan(pi/8), so that the Gregory series
///            (A&S 4.4.42, to u^21) only sees |t| <= tan(pi/8) = 0.4142. Radians become BAM through
///            2^32/pi, and the octant is unfolded exactly (pi/4 is 2^29 BAM).
///
/// Error budget (absolute, on the real value; LSB = 2^-31 = 4.66e-10). Bracketed: the maxima that
/// tests/unit/test_trig.c measures over 2^20 random inputs per function plus the edge sets
/// (a sweep of every 13th BAM, and 10^8 random vectors, gave the same figures).
///   sin/cos  series truncation   x^13/13! resp. x^14/14! at x = pi/4        < 7.0e-12
///            x rounded to Q31    0.5 LSB, slope <= 1                          2.3e-10
///            Horner roundings    <= 0.75 LSB per step, earlier steps damped  < 6.1e-10
///                                by x^2/k(k+1) <= 0.1; final multiply 0.5 LSB
///            output to Q30       0.5 Q30 LSB = 1 LSB                          4.7e-10
///            bound                                                            < 1.4e-9  [1.0e-9]
///   atan2    series truncation   u^23/23 at u = 0.4143                        < 7e-11
///            operands rounded    0.5 each with |(d, n)| >= 2^31: angle moves < 3.3e-10
///            ratio to Q31        0.5 LSB, slope <= 1                          2.3e-10
///            Horner and coeffs   0.5 LSB per step damped by u^2 <= 0.172,     < 4.7e-10
///                                times u <= 0.414, plus the final 0.5 LSB
///            radians to BAM      half a BAM                                   7.3e-10
///            bound                                                            < 1.9e-9  [1.4e-9]
///
/// Cost on a Cortex-M4 (arm-none-eabi-gcc -O2): sin or cos alone about 16 multiply instructions,
/// the constant divisions included, and no library calls; sincos about 30; atan2 about 15 plus one
/// __aeabi_uldivmod. About 1.6 kB of code, no tables, no state, reentrant.

#include "odo/odo_fx.h"

/// Q31 in unsigned form: 1.0 == 2^31 fits a uint32, so cos(0) and atan's leading 1 are exact.
#define Q31_ONE ((uint32_t)1U << 31)

/// One octant of a turn in BAM (pi/4), and the mask of the remainder inside an octant.
#define OCTANT_BAM  ((uint32_t)1U << 29)
#define OCTANT_MASK (OCTANT_BAM - 1U)

/// round(pi * 2^30). A remainder r of BAM in an octant is r * (pi/4) / 2^29 rad, which in Q31 is
/// exactly r * pi; r <= 2^29 keeps r * PI_Q30 below 2^61. The constant's own rounding (0.13)
/// costs < 0.07 LSB at r = 2^29.
#define PI_Q30 3373259426U

/// round(2^32 / pi). rad_q31 * 2^32/pi / 2^32 = rad/(2 pi) * 2^32 = BAM.
#define INV_PI_Q32 1367130551U

/// round(tan(pi/8) * 2^31) = round((sqrt(2) - 1) * 2^31). Any value near it works: both branches
/// of the fold are exact identities, this only caps |u| of the series at 0.4143.
#define TAN_PI_8_Q31 889516852U

/// round(2^31 / d): the series coefficients 1/(2k+1), computed by the compiler from the integer.
#define RECIP_Q31(d) ((uint32_t)((Q31_ONE + (uint32_t)(d) / 2U) / (uint32_t)(d)))

/// round(a * b / 2^31) for a, b in [0, 2^31] (Q31); the result stays in [0, 2^31].
static inline uint32_t mul_q31(uint32_t a, uint32_t b)
{
    return (uint32_t)(((uint64_t)a * b + ((uint64_t)1U << 30)) >> 31);
}

/// One Horner step of a Taylor series with alternating signs: 1 - x^2 * p / d, where d is the
/// integer k(k+1) that links consecutive factorials (x^(k+1)/(k+1)! = x^(k-1)/(k-1)! * x^2/k(k+1)).
/// x2 * p / d < 1 for every step used here, so the subtraction cannot wrap. d is a literal at
/// every call, so after inlining the division is a multiply-high.
static inline uint32_t horner_step(uint32_t x2_q31, uint32_t p_q31, uint32_t d)
{
    return Q31_ONE - (mul_q31(x2_q31, p_q31) + d / 2U) / d;
}

/// sin x for x in [0, pi/4] (Q31 in and out):
/// x (1 - x^2/(2*3) (1 - x^2/(4*5) (1 - x^2/(6*7) (1 - x^2/(8*9) (1 - x^2/(10*11)))))).
static uint32_t sin_poly_q31(uint32_t x_q31)
{
    const uint32_t x2 = mul_q31(x_q31, x_q31);
    uint32_t p = Q31_ONE;
    p = horner_step(x2, p, 10U * 11U);
    p = horner_step(x2, p, 8U * 9U);
    p = horner_step(x2, p, 6U * 7U);
    p = horner_step(x2, p, 4U * 5U);
    p = horner_step(x2, p, 2U * 3U);
    return mul_q31(x_q31, p);
}

/// cos x for x in [0, pi/4] (Q31 in and out):
/// 1 - x^2/(1*2) (1 - x^2/(3*4) (1 - x^2/(5*6) (1 - x^2/(7*8) (1 - x^2/(9*10)
///   (1 - x^2/(11*12)))))).
static uint32_t cos_poly_q31(uint32_t x_q31)
{
    const uint32_t x2 = mul_q31(x_q31, x_q31);
    uint32_t p = Q31_ONE;
    p = horner_step(x2, p, 11U * 12U);
    p = horner_step(x2, p, 9U * 10U);
    p = horner_step(x2, p, 7U * 8U);
    p = horner_step(x2, p, 5U * 6U);
    p = horner_step(x2, p, 3U * 4U);
    return horner_step(x2, p, 1U * 2U);
}

/// Splits a BAM into its octant (0..7) and the distance x in [0, pi/4] (Q31) from the nearest
/// axis-or-diagonal that makes the octant's identity a plain sin/cos of x. Even octants measure
/// from their start (theta = o pi/4 + x); odd octants from their end (theta = (o+1) pi/4 - x),
/// so r == 0 in an odd octant gives x = pi/4, the same point reached from the other side.
static uint32_t fold_octant_q31(uint32_t angle_bam, uint32_t *octant)
{
    const uint32_t oct = angle_bam >> 29;
    uint32_t r = angle_bam & OCTANT_MASK;
    if ((oct & 1U) != 0U) {
        r = OCTANT_BAM - r;
    }
    *octant = oct;
    return (uint32_t)(((uint64_t)r * PI_Q30 + ((uint64_t)1U << 29)) >> 30);
}

/// With theta written as above, sin theta is +-cos x in octants 1, 2, 5, 6 (theta within pi/4 of
/// +-pi/2) and +-sin x elsewhere; it is negative in octants 4..7. cos theta takes the other
/// polynomial and is negative in octants 2..5. Hence cos(a) == sin(a + quarter) bit for bit.
static bool octant_swaps(uint32_t oct) { return ((oct + 1U) & 2U) != 0U; }
static bool octant_sin_negative(uint32_t oct) { return oct >= 4U; }
static bool octant_cos_negative(uint32_t oct) { return ((oct + 2U) & 4U) != 0U; }

/// Q31 magnitude in [0, 2^31] to signed Q30, rounding the magnitude half away from zero.
static int32_t signed_q30(uint32_t mag_q31, bool negative)
{
    const int32_t v = (int32_t)((mag_q31 + 1U) >> 1);
    return negative ? -v : v;
}

int32_t odo_sin_q30(uint32_t angle_bam)
{
    uint32_t oct;
    const uint32_t x = fold_octant_q31(angle_bam, &oct);
    const uint32_t mag = octant_swaps(oct) ? cos_poly_q31(x) : sin_poly_q31(x);
    return signed_q30(mag, octant_sin_negative(oct));
}

int32_t odo_cos_q30(uint32_t angle_bam)
{
    // cos a = sin(a + pi/2); BAM addition wraps exactly, so no extra rounding.
    return odo_sin_q30((uint32_t)(angle_bam + (uint32_t)ODO_BAM_QUARTER));
}

void odo_sincos_q30(uint32_t angle_bam, int32_t *sin_q30, int32_t *cos_q30)
{
    uint32_t oct;
    const uint32_t x = fold_octant_q31(angle_bam, &oct);
    const uint32_t s = sin_poly_q31(x);
    const uint32_t c = cos_poly_q31(x);
    const bool swap = octant_swaps(oct);
    *sin_q30 = signed_q30(swap ? c : s, octant_sin_negative(oct));
    *cos_q30 = signed_q30(swap ? s : c, octant_cos_negative(oct));
}

/// atan u for u in [0, 0.4143] (Q31 in, radians Q31 out):
/// u (1 - u^2 (1/3 - u^2 (1/5 - ... u^2 (1/19 - u^2/21)))). Every bracket is positive because
/// u^2 < 1 and 1/(2k+3) < 1/(2k+1), so the whole evaluation stays unsigned.
static uint32_t atan_poly_q31(uint32_t u_q31)
{
    const uint32_t u2 = mul_q31(u_q31, u_q31);
    uint32_t p = RECIP_Q31(21);
    p = RECIP_Q31(19) - mul_q31(u2, p);
    p = RECIP_Q31(17) - mul_q31(u2, p);
    p = RECIP_Q31(15) - mul_q31(u2, p);
    p = RECIP_Q31(13) - mul_q31(u2, p);
    p = RECIP_Q31(11) - mul_q31(u2, p);
    p = RECIP_Q31(9) - mul_q31(u2, p);
    p = RECIP_Q31(7) - mul_q31(u2, p);
    p = RECIP_Q31(5) - mul_q31(u2, p);
    p = RECIP_Q31(3) - mul_q31(u2, p);
    p = Q31_ONE - mul_q31(u2, p);
    return mul_q31(u_q31, p);
}

/// Radians in [0, pi/8] (Q31) to BAM, rounded to nearest.
static uint32_t rad_q31_to_bam(uint32_t rad_q31)
{
    return (uint32_t)(((uint64_t)rad_q31 * INV_PI_Q32 + ((uint64_t)1U << 31)) >> 32);
}

/// max(0, bit_length(v) - 32): the right shift that brings v below 2^32. Five fixed steps.
static unsigned excess_bits_over_32(uint64_t v)
{
    uint32_t h = (uint32_t)(v >> 32);
    unsigned n = 0U;
    if (h >= ((uint32_t)1U << 16)) {
        h >>= 16;
        n += 16U;
    }
    if (h >= ((uint32_t)1U << 8)) {
        h >>= 8;
        n += 8U;
    }
    if (h >= ((uint32_t)1U << 4)) {
        h >>= 4;
        n += 4U;
    }
    if (h >= ((uint32_t)1U << 2)) {
        h >>= 2;
        n += 2U;
    }
    if (h >= ((uint32_t)1U << 1)) {
        h >>= 1;
        n += 1U;
    }
    return n + (unsigned)h;
}

/// v / 2^s rounded to nearest, s in [0, 32]; v <= 2^63 so the bias cannot overflow.
static uint64_t shr_round_u64(uint64_t v, unsigned s) { return s == 0U ? v : (v + ((uint64_t)1U << (s - 1U))) >> s; }

uint32_t odo_atan2_bam(int64_t y, int64_t x)
{
    // Magnitudes in uint64: |INT64_MIN| = 2^63 has no int64 form but is exact here.
    const uint64_t ux = x < 0 ? 0U - (uint64_t)x : (uint64_t)x;
    const uint64_t uy = y < 0 ? 0U - (uint64_t)y : (uint64_t)y;

    // First octant: angle phi = atan(n/d) in [0, pi/4]; "steep" vectors are mirrored about
    // the diagonal (phi' = pi/2 - phi).
    const bool steep = uy > ux;
    uint64_t n = steep ? ux : uy;
    uint64_t d = steep ? uy : ux;
    if (d == 0U) {
        return 0U;
    }

    // A common rounding shift keeps the ratio while bringing d to at most 2^32, so n << 31 and
    // (d - n) << 31 fit 64 bits. Once shifted d >= 2^31, so the ratio moves by < 2^-31.
    const unsigned s = excess_bits_over_32(d);
    n = shr_round_u64(n, s);
    d = shr_round_u64(d, s);

    // Past tan(pi/8) use tan(pi/4 - phi) = (1 - t)/(1 + t) = (d - n)/(d + n), which is then
    // below tan(pi/8) too. Choosing the operands first keeps it to one division.
    const bool reflect = n * Q31_ONE > d * TAN_PI_8_Q31;
    const uint64_t num = reflect ? (d - n) * Q31_ONE : n * Q31_ONE;
    const uint64_t den = reflect ? d + n : d;
    const uint32_t ratio_q31 = (uint32_t)((num + den / 2U) / den);
    const uint32_t atan_bam = rad_q31_to_bam(atan_poly_q31(ratio_q31));
    const uint32_t phi_bam = reflect ? OCTANT_BAM - atan_bam : atan_bam;

    // Unfold: octant -> quadrant I -> quadrant by the signs. BAM arithmetic wraps mod 2 pi.
    uint32_t angle_bam = steep ? (uint32_t)ODO_BAM_QUARTER - phi_bam : phi_bam;
    if (x < 0) {
        angle_bam = (uint32_t)ODO_BAM_HALF - angle_bam;
    }
    if (y < 0) {
        angle_bam = 0U - angle_bam;
    }
    return angle_bam;
}
