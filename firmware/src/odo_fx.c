/// Wide integer helpers of odo_fx.h (the trigonometry lives in odo_trig.c).
/// Written with 32x32->64 partial products only, so the same code is exact on a Cortex-M4
/// (UMULL) and on a 64-bit host, and never relies on a compiler's __int128.
#include "odo/odo_fx.h"

#define LO32(v) ((v)&0xFFFFFFFFULL)

odo_u128_t odo_mul_u64(uint64_t a, uint64_t b)
{
    const uint64_t a0 = LO32(a), a1 = a >> 32;
    const uint64_t b0 = LO32(b), b1 = b >> 32;
    const uint64_t p00 = a0 * b0, p01 = a0 * b1, p10 = a1 * b0, p11 = a1 * b1;
    /* Middle column: at most 3 * (2^32 - 1) < 2^34, so it cannot overflow. */
    const uint64_t mid = (p00 >> 32) + LO32(p01) + LO32(p10);
    odo_u128_t r;
    r.lo = (mid << 32) | LO32(p00);
    r.hi = p11 + (p01 >> 32) + (p10 >> 32) + (mid >> 32);
    return r;
}

bool odo_div_u128(odo_u128_t n, uint64_t d, uint64_t *q)
{
    if (d == 0U || n.hi >= d) {
        return false; /* division by zero, or a quotient of 2^64 or more */
    }
    /* Restoring division, one quotient bit per iteration. The running remainder is below d,
     * so after a shift it needs 65 bits: the bit shifted out is kept in `carry`. */
    uint64_t r = n.hi;
    uint64_t quo = 0U;
    for (int i = 63; i >= 0; --i) {
        const uint64_t carry = r >> 63;
        r = (r << 1) | ((n.lo >> (unsigned)i) & 1U);
        quo <<= 1;
        if (carry != 0U || r >= d) {
            r -= d;
            quo |= 1U;
        }
    }
    if (r >= d - r) { /* remainder >= d/2: round half up */
        if (quo == UINT64_MAX) {
            return false;
        }
        ++quo;
    }
    *q = quo;
    return true;
}

bool odo_muldiv_u64(uint64_t a, uint64_t b, uint64_t d, uint64_t *out)
{
    return odo_div_u128(odo_mul_u64(a, b), d, out);
}

/// Magnitude of a signed value as unsigned; exact for INT64_MIN.
static uint64_t mag_s64(int64_t v) { return v < 0 ? (uint64_t)0U - (uint64_t)v : (uint64_t)v; }

/// Apply a sign to a magnitude known to fit (mag <= 2^63, and 2^63 only when negative).
static int64_t apply_sign(uint64_t mag, bool negative)
{
    if (!negative) {
        return (int64_t)mag;
    }
    return (mag == 0U) ? 0 : -(int64_t)(mag - 1U) - 1;
}

/// Apply a sign to a magnitude of 64 + `over` bits, saturating to INT64_MIN/INT64_MAX beyond
/// int64. The common case (over == 0, mag < 2^63) costs one test.
static int64_t apply_sign_sat(uint64_t over, uint64_t mag, bool negative)
{
    if ((over | (mag >> 63)) != 0U) {
        return negative ? INT64_MIN : INT64_MAX; /* -2^63 itself lands on INT64_MIN exactly */
    }
    return negative ? -(int64_t)mag : (int64_t)mag;
}

/// round(p / 2^shift) of a 96-bit magnitude p = (hi : lo), ties away from zero, with the sign
/// applied and saturated to int64 (the shared tail of the two mul-shifts below).
static int64_t shr96_round_sat(uint64_t hi, uint64_t lo, unsigned shift, bool negative)
{
    /* Add half a unit of the result, then shift the 96-bit value. Whatever stays in `hi` after
     * the shift is beyond 64 bits: saturate. */
    if (shift - 1U < 63U) { /* 1..63, every caller in the firmware */
        const uint64_t lo2 = lo + ((uint64_t)1U << (shift - 1U));
        hi += (lo2 < lo) ? 1U : 0U;
        return apply_sign_sat(hi >> shift, (lo2 >> shift) | (hi << (64U - shift)), negative);
    }
    if (shift == 0U) {
        return apply_sign_sat(hi, lo, negative);
    }
    if (shift < 96U) {
        /* The half unit sits in hi (or is lo's top bit); lo's other bits cannot carry into the
         * result: floor((H + f) / 2^s) == floor(H / 2^s) for an integer H and 0 <= f < 1. */
        const unsigned s = shift - 64U;
        return apply_sign_sat(0U, (s == 0U) ? hi + (lo >> 63) : (hi + ((uint64_t)1U << (s - 1U))) >> s, negative);
    }
    return 0; /* p < 2^95: below half a unit */
}

int64_t odo_mul_s64_s32_shr(int64_t a, int32_t b, unsigned shift)
{
    const uint64_t ua = mag_s64(a);
    const uint64_t ub = (uint64_t)mag_s64((int64_t)b); /* < 2^32 */
    /* 96-bit product |a| * |b| = (hi : lo), at most 2^63 * 2^31 = 2^94. */
    const uint64_t p_lo = LO32(ua) * ub;
    const uint64_t p_hi = (ua >> 32) * ub;
    const uint64_t lo = p_lo + (p_hi << 32);
    return shr96_round_sat((p_hi >> 32) + (lo < p_lo ? 1U : 0U), lo, shift, (a < 0) != (b < 0));
}

int64_t odo_mul_s64_u32_shr(int64_t a, uint32_t b, unsigned shift)
{
    const uint64_t ua = mag_s64(a);
    const uint64_t ub = b;
    /* 96-bit product |a| * b = (hi : lo), below 2^95. */
    const uint64_t p_lo = LO32(ua) * ub;
    const uint64_t p_hi = (ua >> 32) * ub;
    const uint64_t lo = p_lo + (p_hi << 32);
    return shr96_round_sat((p_hi >> 32) + (lo < p_lo ? 1U : 0U), lo, shift, a < 0 && b != 0U);
}

/// Leading zero bits of a non-zero value; portable C (five steps), so no compiler builtin.
static unsigned clz32(uint32_t x)
{
    unsigned n = 0U;
    if ((x & 0xFFFF0000UL) == 0U) {
        n += 16U;
        x <<= 16;
    }
    if ((x & 0xFF000000UL) == 0U) {
        n += 8U;
        x <<= 8;
    }
    if ((x & 0xF0000000UL) == 0U) {
        n += 4U;
        x <<= 4;
    }
    if ((x & 0xC0000000UL) == 0U) {
        n += 2U;
        x <<= 2;
    }
    return ((x & 0x80000000UL) == 0U) ? n + 1U : n;
}

/// One 16-bit quotient digit of (u * 2^16) / vn for u < vn, vn normalised (top bit set): the
/// estimate u / vn1 is at most 2 too large and corrected with the next divisor digit vn0
/// (Knuth, TAOCP vol. 2, 4.3.1, algorithm D, step D3). *rem gets the remainder, in [0, vn).
static uint32_t div_digit(uint32_t u, uint32_t vn, uint32_t *rem)
{
    const uint32_t vn1 = vn >> 16, vn0 = vn & 0xFFFFU;
    uint32_t q = u / vn1;
    uint32_t rhat = u - q * vn1;
    while (q > 0xFFFFU || q * vn0 > (rhat << 16)) {
        q--;
        rhat += vn1;
        if (rhat > 0xFFFFU) {
            break;
        }
    }
    /* u * 2^16 - q * vn is the true remainder, in [0, vn): exact modulo 2^32. */
    *rem = (u << 16) - q * vn;
    return q;
}

uint32_t odo_frac_q32(uint32_t n, uint32_t d)
{
    if (n >= d) {
        return UINT32_MAX; /* also d == 0 */
    }
    /* Scale both so d's top bit is set: the quotient is unchanged, n << s < d << s fits. */
    const unsigned s = clz32(d);
    const uint32_t vn = d << s;
    uint32_t r1, r0;
    const uint32_t q1 = div_digit(n << s, vn, &r1);
    const uint32_t q0 = div_digit(r1, vn, &r0);
    const uint32_t q = (q1 << 16) | q0;
    /* Round half up on the remainder: r0 / vn >= 1/2. q + 1 cannot wrap: n < d gives
     * n * 2^32 / d <= 2^32 - 2^32 / d < 2^32 - 1. */
    return (r0 >= vn - r0) ? q + 1U : q;
}

int64_t odo_shr_round_s64(int64_t v, unsigned shift)
{
    if (shift == 0U) {
        return v;
    }
    const uint64_t mag = mag_s64(v);
    if (shift >= 64U) {
        /* |v| / 2^64 <= 1/2, exactly 1/2 only for INT64_MIN (which rounds away to -1). */
        return (shift == 64U && mag == ((uint64_t)1U << 63)) ? -1 : 0;
    }
    const uint64_t half = (uint64_t)1U << (shift - 1U);
    /* mag + half cannot wrap: mag <= 2^63 and half <= 2^62. */
    return apply_sign((mag + half) >> shift, v < 0);
}
