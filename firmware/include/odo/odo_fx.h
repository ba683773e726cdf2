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

/// sin and cos of a binary angle, Q30. Constant time (octant fold + short polynomial).
int32_t odo_sin_q30(uint32_t angle_bam);
int32_t odo_cos_q30(uint32_t angle_bam);
void odo_sincos_q30(uint32_t angle_bam, int32_t *sin_q30, int32_t *cos_q30);

/// Angle of the vector (x, y) as a BAM in [0, 2^32): atan2(y, x) mapped so that +x is 0 and +y is
/// ODO_BAM_QUARTER. Any int64 inputs are valid, INT64_MIN included; (0, 0) returns 0. Constant time
/// apart from one 64/64 division.
uint32_t odo_atan2_bam(int64_t y, int64_t x);

#ifdef __cplusplus
}
#endif
#endif
