/// Wide-integer helpers of odo_fx.h: exact products, rounded quotients, rounding shifts, checked
/// against a portable 128-bit reference written here (32-bit limbs, long division), so the same
/// checks run on the Cortex-M4 (tests/target) as on the host; where the compiler has __int128, the
/// reference itself is checked against it on every input.
#include <stdbool.h>
#include <stdint.h>

#include "odo/odo_fx.h"
#include "test_support.h"
#include "unity.h"

void setUp(void) {}
void tearDown(void) {}

static ts_rng_t rng;

/// A random value whose magnitude spans every bit length, so carries in every column are hit.
static uint64_t spread_u64(void)
{
    const unsigned bits = (unsigned)(ts_rng_u64(&rng) % 65U);
    if (bits == 0U) {
        return 0U;
    }
    const uint64_t v = ts_rng_u64(&rng);
    return bits == 64U ? v : (v & ((1ULL << bits) - 1U)) | (1ULL << (bits - 1U));
}

/// Reference 128-bit unsigned integer: the test's own arithmetic, independent of odo_fx.c.
typedef struct {
    uint64_t hi;
    uint64_t lo;
} ref_u128_t;

#define REF_M32 0xFFFFFFFFULL

/// Schoolbook product of 32-bit limbs; every partial sum fits in 64 bits.
static ref_u128_t ref_mul(uint64_t a, uint64_t b)
{
    const uint64_t a0 = a & REF_M32, a1 = a >> 32, b0 = b & REF_M32, b1 = b >> 32;
    const uint64_t p00 = a0 * b0, p01 = a0 * b1, p10 = a1 * b0, p11 = a1 * b1;
    const uint64_t mid = (p00 >> 32) + (p01 & REF_M32) + (p10 & REF_M32);
    const ref_u128_t r = {p11 + (p01 >> 32) + (p10 >> 32) + (mid >> 32), (mid << 32) | (p00 & REF_M32)};
    return r;
}

static ref_u128_t ref_add_u64(ref_u128_t a, uint64_t b)
{
    const ref_u128_t r = {a.hi + ((a.lo + b) < a.lo ? 1U : 0U), a.lo + b};
    return r;
}

/// a >> n for 0 < n < 64.
static ref_u128_t ref_shr_u128(ref_u128_t a, unsigned n)
{
    const ref_u128_t r = {a.hi >> n, (a.lo >> n) | (a.hi << (64U - n))};
    return r;
}

/// Restoring long division, one bit per step: q = n / d, *rem = n % d (d != 0).
static ref_u128_t ref_divmod(ref_u128_t n, uint64_t d, uint64_t *rem)
{
    ref_u128_t q = {0U, 0U};
    uint64_t r = 0U;
    for (int bit = 127; bit >= 0; --bit) {
        const uint64_t in = bit >= 64 ? (n.hi >> (bit - 64)) & 1U : (n.lo >> bit) & 1U;
        const bool carry = (r >> 63) != 0U; /* the shifted remainder has 65 bits */
        r = (r << 1) | in;
        if (carry || r >= d) {
            r -= d;
            if (bit >= 64) {
                q.hi |= 1ULL << (bit - 64);
            } else {
                q.lo |= 1ULL << bit;
            }
        }
    }
    *rem = r;
    return q;
}

#ifdef __SIZEOF_INT128__
static void assert_ref_is(unsigned __int128 want, ref_u128_t got)
{
    TEST_ASSERT_EQUAL_HEX64((uint64_t)(want >> 64), got.hi);
    TEST_ASSERT_EQUAL_HEX64((uint64_t)want, got.lo);
}
#endif

/// The exact product by the reference, with the host's __int128 (where it has one) as a check of
/// the reference.
static ref_u128_t checked_mul(uint64_t a, uint64_t b)
{
    const ref_u128_t p = ref_mul(a, b);
#ifdef __SIZEOF_INT128__
    assert_ref_is((unsigned __int128)a * b, p);
#endif
    return p;
}

/// round(a b / 2^shift) with ties away from zero, for |b| < 2^32 (an int32 or a uint32 value) and
/// any shift below 128. Returns true iff it fits int64; *out is the value, saturated when not.
static bool ref_round_shift(int64_t a, int64_t b, unsigned shift, int64_t *out)
{
    const uint64_t ma = a < 0 ? 0U - (uint64_t)a : (uint64_t)a;
    const uint64_t mb = b < 0 ? 0U - (uint64_t)b : (uint64_t)b;
    const bool neg = (a < 0) != (b < 0);
    ref_u128_t q = {0U, 0U};
    if (shift < 120U) { /* |a b| < 2^95: larger shifts round to 0 */
        ref_u128_t m = checked_mul(ma, mb);
        if (shift > 0U) { /* + 2^(shift-1), then >> shift */
            const unsigned h = shift - 1U;
            const ref_u128_t half = {h >= 64U ? 1ULL << (h - 64U) : 0U, h < 64U ? 1ULL << h : 0U};
            const uint64_t lo = m.lo + half.lo;
            m.hi = m.hi + half.hi + (lo < m.lo ? 1U : 0U);
            m.lo = lo;
            if (shift >= 64U) {
                m.lo = m.hi >> (shift - 64U);
                m.hi = 0U;
            } else {
                m = ref_shr_u128(m, shift);
            }
        }
        q = m;
    }
    const uint64_t limit = neg ? 1ULL << 63 : (uint64_t)INT64_MAX;
    if (q.hi != 0U || q.lo > limit) {
        *out = neg ? INT64_MIN : INT64_MAX;
        return false;
    }
    *out = neg ? (int64_t)(0U - q.lo) : (int64_t)q.lo;
    return true;
}

/// The saturated value of ref_round_shift.
static int64_t ref_sat(int64_t a, int64_t b, unsigned shift)
{
    int64_t v = 0;
    (void)ref_round_shift(a, b, shift, &v);
    return v;
}

static void mul_u64_is_the_exact_128_bit_product(void)
{
    const uint64_t edge[] = {0U, 1U, 0xFFFFFFFFU, 0x100000000ULL, UINT64_MAX, UINT64_MAX - 1U};
    for (unsigned i = 0; i < 6; ++i) {
        for (unsigned j = 0; j < 6; ++j) {
            const ref_u128_t p = checked_mul(edge[i], edge[j]);
            const odo_u128_t r = odo_mul_u64(edge[i], edge[j]);
            TEST_ASSERT_EQUAL_HEX64(p.hi, r.hi);
            TEST_ASSERT_EQUAL_HEX64(p.lo, r.lo);
        }
    }
    for (int n = 0; n < 200000; ++n) {
        const uint64_t a = spread_u64(), b = spread_u64();
        const ref_u128_t p = checked_mul(a, b);
        const odo_u128_t r = odo_mul_u64(a, b);
        TEST_ASSERT_EQUAL_HEX64(p.hi, r.hi);
        TEST_ASSERT_EQUAL_HEX64(p.lo, r.lo);
    }
}

static void muldiv_rounds_to_nearest_and_reports_overflow(void)
{
    uint64_t q = 0;
    TEST_ASSERT_TRUE(odo_muldiv_u64(7U, 1U, 2U, &q)); /* 3.5 -> 4 */
    TEST_ASSERT_EQUAL_UINT64(4U, q);
    TEST_ASSERT_TRUE(odo_muldiv_u64(5U, 1U, 4U, &q)); /* 1.25 -> 1 */
    TEST_ASSERT_EQUAL_UINT64(1U, q);
    TEST_ASSERT_TRUE(odo_muldiv_u64(UINT64_MAX, UINT64_MAX, UINT64_MAX, &q));
    TEST_ASSERT_EQUAL_UINT64(UINT64_MAX, q);
    q = 12345U;
    TEST_ASSERT_FALSE(odo_muldiv_u64(1U, 1U, 0U, &q));         /* division by zero */
    TEST_ASSERT_FALSE(odo_muldiv_u64(UINT64_MAX, 2U, 1U, &q)); /* quotient >= 2^64 */
    TEST_ASSERT_FALSE(odo_muldiv_u64(UINT64_MAX, 3U, 2U, &q)); /* rounds up past 2^64 - 1 */
    TEST_ASSERT_EQUAL_UINT64(12345U, q);                       /* untouched on failure */
    for (int n = 0; n < 100000; ++n) {
        const uint64_t a = spread_u64(), b = spread_u64(), d = spread_u64() | 1U;
        uint64_t rem = 0U;
        const ref_u128_t fl = ref_divmod(checked_mul(a, b), d, &rem);
#ifdef __SIZEOF_INT128__
        const unsigned __int128 p = (unsigned __int128)a * b;
        assert_ref_is(p / d, fl);
        TEST_ASSERT_EQUAL_HEX64((uint64_t)(p % d), rem);
#endif
        const ref_u128_t want = ref_add_u64(fl, rem >= d - rem ? 1U : 0U);
        const bool fits = want.hi == 0U;
        TEST_ASSERT_EQUAL(fits, odo_muldiv_u64(a, b, d, &q));
        if (fits) {
            TEST_ASSERT_EQUAL_HEX64(want.lo, q);
        }
    }
}

static void mul_s64_s32_shr_is_exact_through_96_bits(void)
{
    /* Products far beyond 64 bits whose shifted result fits. */
    TEST_ASSERT_EQUAL_INT64(INT64_MAX, odo_mul_s64_s32_shr(INT64_MAX, 1 << 30, 30U));
    TEST_ASSERT_EQUAL_INT64(INT64_MIN, odo_mul_s64_s32_shr(INT64_MIN, 1 << 30, 30U));
    TEST_ASSERT_EQUAL_INT64(-3, odo_mul_s64_s32_shr(-5, 1, 1U)); /* -2.5 rounds away from zero */
    TEST_ASSERT_EQUAL_INT64(3, odo_mul_s64_s32_shr(5, 1, 1U));
    TEST_ASSERT_EQUAL_INT64(-2, odo_mul_s64_s32_shr(-9, 1, 2U)); /* -2.25 -> -2 */
    const int64_t ea[] = {INT64_MIN, INT64_MIN + 1, -1, 0, 1, INT64_MAX};
    const int32_t eb[] = {INT32_MIN, -1, 0, 1, INT32_MAX, 1 << 30};
    for (int n = 0; n < 300000; ++n) {
        const int64_t a = n < 36 ? ea[n / 6] : (int64_t)spread_u64();
        const int32_t b = n < 36 ? eb[n % 6] : (int32_t)(uint32_t)ts_rng_u64(&rng);
        const unsigned shift = 30U + (unsigned)(ts_rng_u64(&rng) % 33U); /* 30..62 */
        /* |a b| rounded half away from zero, then the sign: the magnitude is below 2^95. */
        const uint64_t ma = a < 0 ? 0U - (uint64_t)a : (uint64_t)a;
        const uint64_t mb = b < 0 ? 0U - (uint64_t)(int64_t)b : (uint64_t)b;
        const bool neg = (a < 0) != (b < 0);
        const ref_u128_t mag = ref_shr_u128(ref_add_u64(checked_mul(ma, mb), 1ULL << (shift - 1U)), shift);
#ifdef __SIZEOF_INT128__
        const __int128 p = (__int128)a * b;
        const __int128 half = (__int128)1 << (shift - 1U);
        const __int128 w128 = p >= 0 ? (p + half) >> shift : -((-p + half) >> shift);
        assert_ref_is((unsigned __int128)(w128 >= 0 ? w128 : -w128), mag);
#endif
        const uint64_t limit = neg ? 1ULL << 63 : (uint64_t)INT64_MAX;
        if (mag.hi != 0U || mag.lo > limit) {
            continue; /* outside the documented domain */
        }
        const int64_t want = neg ? (int64_t)(0U - mag.lo) : (int64_t)mag.lo;
        TEST_ASSERT_EQUAL_INT64(want, odo_mul_s64_s32_shr(a, b, shift));
    }
}

static void mul_s64_u32_shr_is_exact_through_96_bits(void)
{
    TEST_ASSERT_EQUAL_INT64(INT64_MIN, odo_mul_s64_u32_shr(INT64_MIN, 1U << 31, 31U));
    TEST_ASSERT_EQUAL_INT64(-3, odo_mul_s64_u32_shr(-5, 1U, 1U)); /* -2.5 rounds away from zero */
    TEST_ASSERT_EQUAL_INT64(3, odo_mul_s64_u32_shr(5, 1U, 1U));
    TEST_ASSERT_EQUAL_INT64(INT64_MAX / 2 + 1, odo_mul_s64_u32_shr(INT64_MAX, 0x80000000U, 32U)); /* 2^62 - 0.5 */
    const int64_t ea[] = {INT64_MIN, INT64_MIN + 1, -1, 0, 1, INT64_MAX};
    const uint32_t eb[] = {0U, 1U, 0x7FFFFFFFU, 0x80000000U, 0xFFFFFFFEU, UINT32_MAX};
    for (int n = 0; n < 300000; ++n) {
        const int64_t a = n < 36 ? ea[n / 6] : (int64_t)spread_u64();
        const uint32_t b = n < 36 ? eb[n % 6] : (uint32_t)ts_rng_u64(&rng);
        const unsigned shift = 1U + (unsigned)(ts_rng_u64(&rng) % 62U); /* 1..62 */
        int64_t want = 0;
        const bool fits = ref_round_shift(a, (int64_t)b, shift, &want);
#ifdef __SIZEOF_INT128__
        const __int128 p = (__int128)a * b;
        const __int128 half = (__int128)1 << (shift - 1U);
        const __int128 w128 = p >= 0 ? (p + half) >> shift : -((-p + half) >> shift);
        TEST_ASSERT_EQUAL(w128 <= INT64_MAX && w128 >= INT64_MIN, fits);
        if (fits) {
            TEST_ASSERT_EQUAL_INT64((int64_t)w128, want);
        }
#endif
        if (!fits) {
            continue; /* outside the documented domain */
        }
        TEST_ASSERT_EQUAL_INT64(want, odo_mul_s64_u32_shr(a, b, shift));
    }
}

/// round(n 2^32 / d), computed here with a 64-bit division the firmware does not use.
static uint32_t frac_reference(uint32_t n, uint32_t d)
{
    const uint64_t num = (uint64_t)n << 32;
    const uint64_t q = num / d, r = num % d;
    return (uint32_t)(q + (2U * r >= d ? 1U : 0U));
}

/// The fraction n/d in Q32 from two 32-bit divisions equals the 64-bit division's rounded result
/// everywhere: every n < d for small d, both ends of every normalisation shift (d = 2^j and
/// 2^(j+1) - 1), n = d - 1 (the largest result), and random pairs across all bit lengths; n >= d
/// saturates.
static void frac_q32_is_the_correctly_rounded_fraction(void)
{
    for (uint32_t d = 1U; d <= 300U; ++d) {
        for (uint32_t n = 0U; n < d; ++n) {
            TEST_ASSERT_EQUAL_HEX32(frac_reference(n, d), odo_frac_q32(n, d));
        }
    }
    for (unsigned j = 0U; j < 32U; ++j) {
        const uint32_t ds[2] = {1U << j, j == 31U ? UINT32_MAX : (2U << j) - 1U};
        for (int k = 0; k < 2; ++k) {
            const uint32_t d = ds[k];
            const uint32_t ns[5] = {0U, d > 1U ? 1U : 0U, d / 2U, d > 1U ? d - 2U : 0U, d - 1U};
            for (int i = 0; i < 5; ++i) {
                TEST_ASSERT_EQUAL_HEX32(frac_reference(ns[i], d), odo_frac_q32(ns[i], d));
            }
        }
    }
    TEST_ASSERT_EQUAL_HEX32(0xFFFFFFFFU, odo_frac_q32(UINT32_MAX - 1U, UINT32_MAX));
    TEST_ASSERT_EQUAL_HEX32(0x80000000U, odo_frac_q32(1U, 2U));
    TEST_ASSERT_EQUAL_HEX32(0x55555555U, odo_frac_q32(1U, 3U));
    TEST_ASSERT_EQUAL_HEX32(0xAAAAAAABU, odo_frac_q32(2U, 3U)); /* .666... rounds up */
    for (int n = 0; n < 1000000; ++n) {
        uint32_t d = (uint32_t)spread_u64();
        d = d == 0U ? 1U : d;
        const uint32_t nn = (uint32_t)(ts_rng_u64(&rng) % d);
        TEST_ASSERT_EQUAL_HEX32(frac_reference(nn, d), odo_frac_q32(nn, d));
    }
    TEST_ASSERT_EQUAL_HEX32(UINT32_MAX, odo_frac_q32(5U, 5U));
    TEST_ASSERT_EQUAL_HEX32(UINT32_MAX, odo_frac_q32(6U, 5U));
    TEST_ASSERT_EQUAL_HEX32(UINT32_MAX, odo_frac_q32(0U, 0U));
}

static void shr_round_is_symmetric_and_safe_at_the_extremes(void)
{
    TEST_ASSERT_EQUAL_INT64(2, odo_shr_round_s64(3, 1U));   /* 1.5 -> 2 */
    TEST_ASSERT_EQUAL_INT64(-2, odo_shr_round_s64(-3, 1U)); /* -1.5 -> -2 */
    TEST_ASSERT_EQUAL_INT64(-1, odo_shr_round_s64(-5, 2U)); /* -1.25 -> -1 */
    TEST_ASSERT_EQUAL_INT64(INT64_MIN / 4, odo_shr_round_s64(INT64_MIN, 2U));
    TEST_ASSERT_EQUAL_INT64(INT64_MAX / 4 + 1, odo_shr_round_s64(INT64_MAX, 2U));
}

#ifdef __SIZEOF_INT128__
/// round(p / 2^shift) ties away from zero, saturated to int64: the contract of both functions, in
/// the host's __int128, as a check of the portable ref_round_shift.
static int64_t ref_shr(__int128 p, unsigned shift)
{
    __int128 q;
    if (shift >= 120U) {
        q = 0; /* every product here is below 2^95 */
    } else {
        const __int128 mag = p < 0 ? -p : p;
        const __int128 half = shift == 0U ? 0 : (__int128)1 << (shift - 1U);
        q = (mag + half) >> shift;
        q = p < 0 ? -q : q;
    }
    if (q > INT64_MAX) {
        return INT64_MAX;
    }
    if (q < INT64_MIN) {
        return INT64_MIN;
    }
    return (int64_t)q;
}
#endif

/// odo_fx.h: every shift is valid, 0 and 64-127 included, and a result beyond int64 saturates
/// (shift 0 used to read 1 << -1, undefined behaviour under UBSan), for both mul-shifts.
static void shifts_are_defined_for_every_shift_and_saturate(void)
{
    TEST_ASSERT_EQUAL_INT64(-15, odo_mul_s64_s32_shr(5, -3, 0U));
    TEST_ASSERT_EQUAL_INT64(INT64_MAX, odo_mul_s64_s32_shr(INT64_MAX, 2, 0U));
    TEST_ASSERT_EQUAL_INT64(INT64_MIN, odo_mul_s64_s32_shr(INT64_MIN, 1, 0U));
    TEST_ASSERT_EQUAL_INT64(INT64_MAX, odo_mul_s64_s32_shr(INT64_MIN, -1, 0U)); /* 2^63 saturates */
    TEST_ASSERT_EQUAL_INT64(1, odo_mul_s64_s32_shr(INT64_MIN, INT32_MIN, 95U)); /* exactly 1/2 */
    TEST_ASSERT_EQUAL_INT64(0, odo_mul_s64_s32_shr(INT64_MIN, INT32_MIN, 96U));
    TEST_ASSERT_EQUAL_INT64(0, odo_mul_s64_s32_shr(INT64_MAX, INT32_MAX, 200U));
    TEST_ASSERT_EQUAL_INT64(INT64_MAX, odo_mul_s64_u32_shr(INT64_MAX, UINT32_MAX, 0U));
    TEST_ASSERT_EQUAL_INT64(-7, odo_mul_s64_u32_shr(-7, 1U, 0U));
    TEST_ASSERT_EQUAL_INT64(-1, odo_mul_s64_u32_shr(INT64_MIN, UINT32_MAX, 95U)); /* -(1 - 2^-32) */
    TEST_ASSERT_EQUAL_INT64(0, odo_mul_s64_u32_shr(INT64_MIN, UINT32_MAX, 96U));  /* below 1/2 */
    TEST_ASSERT_EQUAL_INT64(-7, odo_shr_round_s64(-7, 0U));
    TEST_ASSERT_EQUAL_INT64(-1, odo_shr_round_s64(INT64_MIN, 63U));
    TEST_ASSERT_EQUAL_INT64(-1, odo_shr_round_s64(INT64_MIN, 64U));
    TEST_ASSERT_EQUAL_INT64(0, odo_shr_round_s64(INT64_MAX, 64U));
    TEST_ASSERT_EQUAL_INT64(0, odo_shr_round_s64(INT64_MIN, 65U));
    TEST_ASSERT_EQUAL_INT64(0, odo_shr_round_s64(INT64_MIN, UINT32_MAX));
    const int64_t ea[] = {
        0, 1, -1, 3, -3, INT64_MAX, INT64_MIN, INT64_MAX - 1, INT64_MIN + 1, (int64_t)1 << 62, -((int64_t)1 << 62)};
    const int32_t eb[] = {0, 1, -1, 2, -2, INT32_MAX, INT32_MIN, 1 << 30, -(1 << 30)};
    for (unsigned shift = 0U; shift < 128U; ++shift) {
        for (unsigned i = 0U; i < sizeof ea / sizeof ea[0]; ++i) {
            TEST_ASSERT_EQUAL_INT64(ref_sat(ea[i], 1, shift), odo_shr_round_s64(ea[i], shift));
            for (unsigned j = 0U; j < sizeof eb / sizeof eb[0]; ++j) {
                TEST_ASSERT_EQUAL_INT64(ref_sat(ea[i], eb[j], shift), odo_mul_s64_s32_shr(ea[i], eb[j], shift));
                const uint32_t ub = (uint32_t)eb[j];
                TEST_ASSERT_EQUAL_INT64(ref_sat(ea[i], (int64_t)ub, shift), odo_mul_s64_u32_shr(ea[i], ub, shift));
#ifdef __SIZEOF_INT128__
                TEST_ASSERT_EQUAL_INT64(ref_shr((__int128)ea[i] * eb[j], shift), ref_sat(ea[i], eb[j], shift));
                TEST_ASSERT_EQUAL_INT64(ref_shr((__int128)ea[i] * ub, shift), ref_sat(ea[i], (int64_t)ub, shift));
#endif
            }
        }
        for (int n = 0; n < 2000; ++n) {
            const int64_t a = (int64_t)spread_u64();
            const uint32_t u = (uint32_t)spread_u64();
            const int32_t b = (int32_t)u;
            TEST_ASSERT_EQUAL_INT64(ref_sat(a, 1, shift), odo_shr_round_s64(a, shift));
            TEST_ASSERT_EQUAL_INT64(ref_sat(a, b, shift), odo_mul_s64_s32_shr(a, b, shift));
            TEST_ASSERT_EQUAL_INT64(ref_sat(a, (int64_t)u, shift), odo_mul_s64_u32_shr(a, u, shift));
#ifdef __SIZEOF_INT128__
            TEST_ASSERT_EQUAL_INT64(ref_shr((__int128)a * b, shift), ref_sat(a, b, shift));
            TEST_ASSERT_EQUAL_INT64(ref_shr((__int128)a * u, shift), ref_sat(a, (int64_t)u, shift));
#endif
        }
    }
}

int main(void)
{
    ts_rng_seed(&rng, 0x0D0F00D5EEDULL);
    UNITY_BEGIN();
    RUN_TEST(mul_u64_is_the_exact_128_bit_product);
    RUN_TEST(muldiv_rounds_to_nearest_and_reports_overflow);
    RUN_TEST(mul_s64_s32_shr_is_exact_through_96_bits);
    RUN_TEST(shr_round_is_symmetric_and_safe_at_the_extremes);
    RUN_TEST(shifts_are_defined_for_every_shift_and_saturate);
    RUN_TEST(mul_s64_u32_shr_is_exact_through_96_bits);
    RUN_TEST(frac_q32_is_the_correctly_rounded_fraction);
    return UNITY_END();
}
