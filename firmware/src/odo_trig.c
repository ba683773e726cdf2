/// Sine, cosine and two-argument arctangent on binary angles (odo_fx.h), integer only.
///
/// Method
///   sin/cos  The top three BAM bits pick an octant; the 29-bit remainder r (mirrored in odd
///            octants) is x = r pi/2^31 in [0, pi/4]. Its top 5 bits pick node i of
///            odo_sin_table_q31 (sin and cos of i pi/128, Q31), the rest is d < pi/128 rad in Q32,
///            and the angle-sum identities give sin x = S_i cos d + C_i sin d and
///            cos x = C_i cos d - S_i sin d with 1 - cos d = d^2/2 - d^4/24 and sin d = d - d^3/6
///            (A&S 4.3.65, 4.3.66 truncated), each product one UMULL; the octant then picks which
///            of the two answers and its sign. The body is odo_sincos_q30_inline (odo_fx.h).
///   atan2    The magnitudes fold the vector into the first octant, 0 <= n <= d, scaled to
///            d <= 2^30 with the ratio kept. One 32-bit division (odo_frac_q32: two UDIVs, no
///            64-bit division) gives t = n/d in Q32, or u = (d-n)/(d+n) when t > tan(pi/8), so
///            that the Gregory series (A&S 4.4.42, to u^21, coefficients 1/(2k+1) in Q32) only
///            sees |t| <= tan(pi/8) = 0.4142. Radians become BAM through 2^32/pi, and the octant
///            is unfolded exactly (pi/4 is 2^29 BAM).
///
/// Error budget (absolute, on the real value; Q31 LSB = 4.66e-10, Q32 LSB = 2.33e-10). Bracketed:
/// the maxima that odo-bench (`sincos_max_abs_err`, `atan2_max_abs_err_rad`) and
/// tests/unit/test_trig.c measure over 10^6 random inputs plus the edge sets.
///   sin/cos  series truncation   d^4/720 and d^5/120 at d = pi/128              < 8e-11
///            table entries       0.5 Q31 LSB each, times |cos d| + |sin d|      2.4e-10
///            d rounded to Q32    0.5 LSB, slope <= 1                           1.2e-10
///            1 - cos d, sin d    two truncating products each, 1 Q32 LSB each  < 9.4e-10
///            the two products    truncated (1 Q31 LSB) and rounded (0.5)       7.0e-10
///            output to Q30       0.5 Q30 LSB                                    4.7e-10
///            bound                                                             < 2.5e-9  [1.7e-9]
///   atan2    series truncation   u^23/23 at u = 0.4143                        < 7e-11
///            operands rounded    0.5 each with d >= 2^29: angle moves         < 1.4e-9
///            ratio to Q32        0.5 LSB, slope <= 1                          1.2e-10
///            Horner, truncating  < 1 LSB per step damped by u^2 <= 0.172      < 3.3e-10
///            radians to BAM      half a BAM plus the constant                 8.0e-10
///            bound                                                            < 2.8e-9  [1.8e-9]
///
/// Cost on a Cortex-M4 (arm-none-eabi-gcc -O2, `odo-bench-target --profile`): odo_sincos_q30
/// about 58 instructions for the pair, odo_sin_q30/odo_cos_q30 the same plus the call;
/// odo_atan2_bam about 140 plus about 55 in odo_frac_q32 (two UDIVs). One 260-byte table, no
/// state, no library calls, reentrant.

#include "odo/odo_fx.h"

/// One octant of a turn in BAM (pi/4), and the mask of the remainder inside an octant.
#define OCTANT_BAM ((uint32_t)1U << 29)

/// round(pi * 2^30). A remainder r of BAM in an octant is r * (pi/4) / 2^29 rad, which in Q32 is
/// r * 2 pi = r * PI_Q30 / 2^29; r <= 2^29 keeps the product below 2^61.
#define PI_Q30 3373259426U

/// round(2^32 / pi): rad_q32 * 2^32/pi / 2^33 = rad / (2 pi) * 2^32 = BAM.
#define INV_PI_Q32 1367130551U

/// round(tan(pi/8) * 2^31) = round((sqrt(2) - 1) * 2^31). Any value near it works: both branches
/// of the fold are exact identities, this only caps |u| of the series at 0.4143.
#define TAN_PI_8_Q31 889516852U

/// round(2^32 / d) for an integer d >= 2, computed by the compiler: the series coefficients 1/k!
/// (d = k!, at most 12! = 479001600) and 1/(2k+1).
#define RECIP_Q32(d) ((uint32_t)((((uint64_t)1U << 32) + (uint64_t)(d) / 2U) / (uint64_t)(d)))

/// floor(a * b / 2^32): one UMULL, the high word.
static inline uint32_t mulhi(uint32_t a, uint32_t b) { return (uint32_t)(((uint64_t)a * b) >> 32); }

/// round(a * b / 2^32), half up: UMULL and a carry.
static inline uint32_t mulhi_round(uint32_t a, uint32_t b)
{
    return (uint32_t)(((uint64_t)a * b + 0x80000000ULL) >> 32);
}

/// round(sin(i pi / 128) 2^31) for i = 0..64: sin and cos at the 33 nodes of an octant (cos of
/// node i is entry 64 - i), Q31 in uint32 so that 1.0 (entry 64) is exact. Computed with 60-digit
/// decimal arithmetic (every value is at least 0.005 LSB from a rounding tie);
/// tests/unit/test_trig.c checks each entry against libm.
const uint32_t odo_sin_table_q31[ODO_SIN_TABLE_SIZE] = {
    0U,          52701887U,   105372028U,  157978697U,  210490206U,  262874923U,  315101295U,  367137861U,  418953276U,
    470516330U,  521795963U,  572761285U,  623381598U,  673626408U,  723465451U,  772868706U,  821806413U,  870249095U,
    918167572U,  965532978U,  1012316784U, 1058490808U, 1104027237U, 1148898640U, 1193077991U, 1236538675U, 1279254516U,
    1321199781U, 1362349204U, 1402678000U, 1442161874U, 1480777044U, 1518500250U, 1555308768U, 1591180426U, 1626093616U,
    1660027308U, 1692961062U, 1724875040U, 1755750017U, 1785567396U, 1814309216U, 1841958164U, 1868497586U, 1893911494U,
    1918184581U, 1941302225U, 1963250501U, 1984016189U, 2003586779U, 2021950484U, 2039096241U, 2055013723U, 2069693342U,
    2083126254U, 2095304370U, 2106220352U, 2115867626U, 2124240380U, 2131333572U, 2137142927U, 2141664948U, 2144896910U,
    2146836866U, 2147483648U,
};

void odo_sincos_q30(uint32_t angle_bam, int32_t *sin_q30, int32_t *cos_q30)
{
    odo_sincos_q30_inline(angle_bam, sin_q30, cos_q30);
}

uint64_t odo_sincos_pair_q30(uint32_t angle_bam)
{
    int32_t s, c;
    odo_sincos_q30_inline(angle_bam, &s, &c);
    return (uint64_t)(uint32_t)s | ((uint64_t)(uint32_t)c << 32);
}

int32_t odo_sin_q30(uint32_t angle_bam)
{
    int32_t s, c;
    odo_sincos_q30(angle_bam, &s, &c);
    return s;
}

int32_t odo_cos_q30(uint32_t angle_bam)
{
    int32_t s, c;
    odo_sincos_q30(angle_bam, &s, &c);
    return c;
}

/// atan u for u in [0, 0.4143] (Q32 in, radians Q32 out): u - u^3/3 + ... + u^21/21, as
/// u - u (u^2 (1/3 - u^2 (1/5 - ... u^2 (1/19 - u^2/21)))). Every bracket is positive because
/// u^2 < 1 and 1/(2k+3) < 1/(2k+1), so the whole evaluation stays unsigned.
static uint32_t atan_poly_q32(uint32_t u)
{
    const uint32_t u2 = mulhi_round(u, u);
    uint32_t p = RECIP_Q32(21U);
    p = RECIP_Q32(19U) - mulhi(u2, p);
    p = RECIP_Q32(17U) - mulhi(u2, p);
    p = RECIP_Q32(15U) - mulhi(u2, p);
    p = RECIP_Q32(13U) - mulhi(u2, p);
    p = RECIP_Q32(11U) - mulhi(u2, p);
    p = RECIP_Q32(9U) - mulhi(u2, p);
    p = RECIP_Q32(7U) - mulhi(u2, p);
    p = RECIP_Q32(5U) - mulhi(u2, p);
    p = RECIP_Q32(3U) - mulhi(u2, p);
    return u - mulhi_round(u, mulhi_round(u2, p));
}

/// max(0, bit_length(v) - 30): the right shift that brings v to at most 2^30. Five fixed steps
/// on the high word, then the low word's top bits.
static unsigned excess_bits_over_30(uint64_t v)
{
    uint32_t h = (uint32_t)(v >> 30);
    unsigned n = 0U;
    if ((v >> 62) != 0U) {
        return 33U + (unsigned)(v >> 63);
    }
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

/// v / 2^s rounded half up, s in [0, 34]; v <= 2^63 so the bias cannot overflow.
static uint64_t shr_round_u64(uint64_t v, unsigned s) { return s == 0U ? v : (v + ((uint64_t)1U << (s - 1U))) >> s; }

uint32_t odo_atan2_bam(int64_t y, int64_t x)
{
    // Magnitudes in uint64: |INT64_MIN| = 2^63 has no int64 form but is exact here.
    const uint64_t ux = x < 0 ? 0U - (uint64_t)x : (uint64_t)x;
    const uint64_t uy = y < 0 ? 0U - (uint64_t)y : (uint64_t)y;

    // First octant: angle phi = atan(n/d) in [0, pi/4]; "steep" vectors are mirrored about
    // the diagonal (phi' = pi/2 - phi).
    const bool steep = uy > ux;
    uint64_t n64 = steep ? ux : uy;
    uint64_t d64 = steep ? uy : ux;
    if (d64 == 0U) {
        return 0U;
    }

    // A common rounding shift keeps the ratio while bringing d to at most 2^30, so d + n fits
    // 32 bits. Once shifted d >= 2^29, so the direction moves by < 1.4e-9 rad.
    const unsigned s = excess_bits_over_30(d64);
    const uint32_t n = (uint32_t)shr_round_u64(n64, s);
    const uint32_t d = (uint32_t)shr_round_u64(d64, s);

    // Past tan(pi/8) use tan(pi/4 - phi) = (1 - t)/(1 + t) = (d - n)/(d + n), which is then
    // below tan(pi/8) too. Choosing the operands first keeps it to one division.
    const bool reflect = ((uint64_t)n << 31) > (uint64_t)d * TAN_PI_8_Q31;
    const uint32_t ratio_q32 = reflect ? odo_frac_q32(d - n, d + n) : odo_frac_q32(n, d);
    const uint32_t atan_q32 = atan_poly_q32(ratio_q32);
    const uint32_t atan_bam = (uint32_t)(((uint64_t)atan_q32 * INV_PI_Q32 + ((uint64_t)1U << 32)) >> 33);
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
