/// Fixed-point arithmetic for the odometry core: wide multiplies, rounding shifts, binary angles
/// and trigonometry. Integer only, no tables larger than a few words, no state: every function is
/// pure, reentrant and constant time unless its entry says otherwise.
///
/// Conventions
///   - BAM: binary angle, uint32, 2^32 per turn; wraps for free. 1 BAM = 8.38e-8 deg = 1.46e-9 rad.
///   - Q30: signed, 1.0 == 2^30 (sin/cos outputs span [-2^30, +2^30]).
///   - Rounding is to nearest, ties away from zero, unless stated.
///
/// Error bounds (measured against libm by tests/unit/test_trig.c over >= 10^6 random inputs plus
/// every octant boundary; odo-bench prints the figures):
///   - odo_sin_q30 / odo_cos_q30: |error| <= 2e-8 (absolute, on the real value)
///   - odo_atan2_bam:             |error| <= 1e-7 rad
#ifndef ODO_FX_H
#define ODO_FX_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define ODO_Q30_ONE ((int32_t)1 << 30)

/// Binary angle constants.
#define ODO_BAM_QUARTER 0x40000000UL ///< 90 deg
#define ODO_BAM_HALF    0x80000000UL ///< 180 deg

/// Unsigned 128-bit value, for the wide intermediates of parameter precomputation.
typedef struct {
    uint64_t hi;
    uint64_t lo;
} odo_u128_t;

/// Full 64x64 -> 128-bit unsigned product. Constant time (four 32x32 multiplies).
odo_u128_t odo_mul_u64(uint64_t a, uint64_t b);

/// round(n / d) for a 128-bit numerator. Returns false (and leaves *q untouched) iff d == 0 or the
/// quotient does not fit in 64 bits. Bit-serial: 128 iterations, used only when parameters load.
bool odo_div_u128(odo_u128_t n, uint64_t d, uint64_t *q);

/// round(a * b / d) with a 128-bit intermediate. Returns false iff d == 0 or the result overflows
/// 64 bits. Same cost as odo_div_u128.
bool odo_muldiv_u64(uint64_t a, uint64_t b, uint64_t d, uint64_t *out);

/// round(a * b / 2^shift), ties away from zero, computed exactly through a 96-bit product. Every
/// input is valid: any shift (0 is the plain product; 96 and above give 0, since |a * b| <= 2^94),
/// and a result beyond int64 saturates to INT64_MIN / INT64_MAX. Three 32x32 multiplies.
int64_t odo_mul_s64_s32_shr(int64_t a, int32_t b, unsigned shift);

/// round(a * b / 2^shift) for an unsigned 32-bit b, as odo_mul_s64_s32_shr: exact through a
/// 96-bit product, ties away from zero, every shift valid (96 and above give 0), saturating
/// beyond int64. Three 32x32 multiplies.
int64_t odo_mul_s64_u32_shr(int64_t a, uint32_t b, unsigned shift);

/// The fraction n / d in Q32: round(n * 2^32 / d) for n < d, which is at most 2^32 - 1, so it
/// always fits; saturates to UINT32_MAX when n >= d (d == 0 included). Exact rounding (ties
/// cannot occur: d < 2^32 has at most 31 factors of two). Two 32/32 divisions after
/// normalising d (Knuth's algorithm D with 16-bit digits, as Hacker's Delight's divlu), so no
/// 64-bit division: constant time apart from at most two corrections per digit.
uint32_t odo_frac_q32(uint32_t n, uint32_t d);

/// round(v / 2^shift), ties away from zero (an arithmetic right shift with rounding to nearest).
/// Every input is valid: shift 0 returns v; shift 64 and above return 0, except -1 for INT64_MIN
/// at exactly 64 (|v| / 2^64 = 1/2). Never overflows.
int64_t odo_shr_round_s64(int64_t v, unsigned shift);

/// sin and cos of a binary angle, Q30. Constant time: octant fold, a 65-entry table and a short
/// series on the remainder (Cortex-M4: about 58 instructions, one or both).
int32_t odo_sin_q30(uint32_t angle_bam);
int32_t odo_cos_q30(uint32_t angle_bam);
void odo_sincos_q30(uint32_t angle_bam, int32_t *sin_q30, int32_t *cos_q30);

/// Angle of the vector (x, y) as a BAM in [0, 2^32): atan2(y, x) mapped so that +x is 0 and +y is
/// ODO_BAM_QUARTER. Any int64 inputs are valid, INT64_MIN included; (0, 0) returns 0. Constant time
/// apart from odo_frac_q32's corrections: two 32/32 divisions, no 64-bit division (Cortex-M4:
/// about 200 instructions with odo_frac_q32's).
uint32_t odo_atan2_bam(int64_t y, int64_t x);

/* ---------------------------------------------------------------------------------------------
 * Inline helpers for the 40 ms step. Each states the input ranges it is exact for; the callers'
 * ranges come from the model and parameter checks. Outside them the generic functions above apply.
 * ------------------------------------------------------------------------------------------- */

/// The int32 whose two's-complement bits are u (u mod 2^32 read as signed), without the
/// implementation-defined conversion of a value above INT32_MAX. A plain move when inlined.
static inline int32_t odo_as_s32(uint32_t u) { return u <= (uint32_t)INT32_MAX ? (int32_t)u : -(int32_t)(~u) - 1; }

/// The int64 whose two's-complement bits are u, as odo_as_s32.
static inline int64_t odo_as_s64(uint64_t u) { return u <= (uint64_t)INT64_MAX ? (int64_t)u : -(int64_t)(~u) - 1; }

/// floor(v / 2^s) for s in [0, 63]: an arithmetic right shift written without shifting a negative
/// value (implementation-defined in C99): a negative v is ~(~v >> s), with ~v >= 0. Every int64
/// is valid. Compilers fold it into the plain arithmetic shift (three Cortex-M4 instructions).
static inline int64_t odo_floor_shr_s64(int64_t v, unsigned s) { return v < 0 ? ~(~v >> s) : v >> s; }

/// floor(v / 2^s) for s in [0, 31], as odo_floor_shr_s64 for int32 (one ASR).
static inline int32_t odo_floor_shr_s32(int32_t v, unsigned s) { return v < 0 ? ~(~v >> s) : v >> s; }

/// floor(a * b / 2^s + 1/2) (round half up), exact through the 96-bit product, for s in [1, 63],
/// |a| < 2^63 - 2^31 and every b; for s < 32 the caller also keeps |a * b| below 2^(61 + s) so
/// the result fits. a is split as h 2^32 + l with l in [-2^31, 2^31), so both partial products
/// are signed 32x32 -> 64 multiplies: with a constant s >= 32 it is one SMULL, one SMLAL and a
/// shift (11 Cortex-M4 instructions). The step's workhorse (positions, link geometry), where
/// odo_mul_s64_s32_shr's variable shift and saturation are not needed.
static inline int64_t odo_mul_s64_s32_rnd(int64_t a, int32_t b, unsigned s)
{
    const int32_t l = odo_as_s32((uint32_t)((uint64_t)a & 0xFFFFFFFFU));
    const int32_t h = odo_as_s32((uint32_t)(((uint64_t)a - (uint64_t)(int64_t)l) >> 32));
    if (s >= 32U) {
        /* a b + half = h b 2^32 + (l b + half). Below 2^32, l b + half cannot change
         * floor(. / 2^s) for s >= 32: only its high word counts (|l b| <= 2^62). The half is
         * 2^31 in the low product for s == 32, 2^(s - 33) in the high word otherwise. */
        const int64_t low = (int64_t)l * b + (s == 32U ? (int64_t)0x80000000 : 0);
        const int32_t mid = odo_as_s32((uint32_t)((uint64_t)low >> 32)); /* floor(low / 2^32) */
        const int64_t top = (int64_t)h * b + mid + (s == 32U ? 0 : (int64_t)((uint64_t)1U << (s - 33U)));
        return s == 32U ? top : odo_floor_shr_s64(top, s - 32U);
    }
    const int64_t low = (int64_t)l * b + (int64_t)((uint64_t)1U << (s - 1U));
    return (int64_t)h * b * ((int64_t)1 << (32U - s)) + odo_floor_shr_s64(low, s);
}

/// floor(a * b / 2^32) for unsigned a, b: the high word of one UMULL.
static inline uint32_t odo_mulhi_u32(uint32_t a, uint32_t b) { return (uint32_t)(((uint64_t)a * b) >> 32); }

/// round(a * b / 2^32), half up: one UMULL (or UMLAL) and the carry.
static inline uint32_t odo_mulhi_round_u32(uint32_t a, uint32_t b)
{
    return (uint32_t)(((uint64_t)a * b + 0x80000000ULL) >> 32);
}

/// sin and cos in one return value, for callers that want them in registers: the low 32 bits
/// are sin, the high 32 bits cos, each the two's-complement Q30 of odo_sincos_q30 (bit for bit the
/// same values). Unpack with odo_sincos_sin_q30 / odo_sincos_cos_q30.
uint64_t odo_sincos_pair_q30(uint32_t angle_bam);
static inline int32_t odo_sincos_sin_q30(uint64_t pair) { return odo_as_s32((uint32_t)(pair & 0xFFFFFFFFU)); }
static inline int32_t odo_sincos_cos_q30(uint64_t pair) { return odo_as_s32((uint32_t)(pair >> 32)); }

/// The table behind odo_sincos_q30: round(sin(i pi / 128) 2^31) for i = 0..64 (260 bytes of
/// flash), exposed so tests can check every entry against libm.
#define ODO_SIN_TABLE_SIZE 65U
extern const uint32_t odo_sin_table_q31[ODO_SIN_TABLE_SIZE];

/// odo_sincos_q30, inline for the step (odo_sincos_q30 is this function compiled once).
///
/// The top three BAM bits pick an octant; the 29-bit remainder r (mirrored in odd octants, so
/// r == 0 there means x = pi/4, the point reached from the other side) gives x = r (pi/4) / 2^29
/// in [0, pi/4]. Node i = r / 2^24 of odo_sin_table_q31 and the rest d = (r mod 2^24) (pi/4) /
/// 2^29 < pi/128 rad give
///   sin(x_i + d) = S_i cos d + C_i sin d,  cos(x_i + d) = C_i cos d - S_i sin d   (Q31),
/// with 1 - cos d = d^2/2 - d^4/24 and sin d = d - d^3/6 (the next terms are below 4e-14 and
/// 7e-11); x <= pi/4 keeps both in [0, 2^31]. The octant then picks which is sin and which cos
/// of the angle and their signs: sin is +-cos x in octants 1, 2, 5, 6 and negative in octants 4..7;
/// cos takes the other and is negative in octants 2..5, so cos(a) == sin(a + quarter) bit for bit.
/// Each magnitude is rounded half up to Q30. Error below 2.5e-9 (budget in src/odo_trig.c;
/// measured 1.7e-9, tests/unit/test_trig.c and odo-bench).
static inline void odo_sincos_q30_inline(uint32_t angle_bam, int32_t *sin_q30, int32_t *cos_q30)
{
    const uint32_t oct = angle_bam >> 29;
    uint32_t r = angle_bam & 0x1FFFFFFFU;
    if ((oct & 1U) != 0U) {
        r = 0x20000000U - r;
    }
    /* d in rad Q32: (r mod 2^24) * 2 pi = (r mod 2^24) * round(pi 2^30) / 2^29 */
    const uint32_t i = r >> 24;
    const uint32_t d = (uint32_t)(((uint64_t)(r & 0xFFFFFFU) * 3373259426U + ((uint64_t)1U << 28)) >> 29);
    const uint32_t d2 = odo_mulhi_round_u32(d, d);                                   /* d^2 < 6.1e-4 */
    const uint32_t u = (d2 >> 1) - odo_mulhi_u32(odo_mulhi_u32(d2, d2), 178956971U); /* 1 - cos d */
    const uint32_t sd = d - odo_mulhi_u32(d, odo_mulhi_u32(d2, 715827883U));         /* sin d */
    const uint32_t si = odo_sin_table_q31[i], ci = odo_sin_table_q31[64U - i];
    const uint32_t s = si - odo_mulhi_u32(si, u) + odo_mulhi_round_u32(ci, sd);
    const uint32_t c = ci - odo_mulhi_u32(ci, u) - odo_mulhi_round_u32(si, sd);
    const bool swap = ((oct + 1U) & 2U) != 0U;
    const int32_t sv = (int32_t)(((swap ? c : s) + 1U) >> 1);
    const int32_t cv = (int32_t)(((swap ? s : c) + 1U) >> 1);
    *sin_q30 = oct >= 4U ? -sv : sv;
    *cos_q30 = ((oct + 2U) & 4U) != 0U ? -cv : cv;
}

#ifdef __cplusplus
}
#endif
#endif
