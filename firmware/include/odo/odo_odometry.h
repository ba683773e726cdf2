/// Per-truck dead reckoning from raw, wrapping wheel counters (000 Eqs. 2.1-2.6), with the UMBmark
/// per-wheel correction factors cL, cR (000 Eqs. 6.33-6.35), the effective wheelbase (Eq. 6.28) and
/// the scale correction (App. B) folded into two per-wheel multipliers when parameters load.
///
/// Representations: position in mm Q32 (int64), heading in turns Q64 (uint64, wraps), per-wheel
/// distance per count in mm Q40, per-wheel heading per count in turns Q64. One tick costs two
/// 64x64 multiplies for the heading, two for distance and two 64x32 for position; no loops and no
/// division (a step over a gap adds a few multiplies for the chord).
///
/// Tyre scrub (effect `scrub` of the effects catalog; parameter scrub_q30 per truck): real robots
/// show a larger effective wheelbase on arcs than on spot turns (the OptiOdom runs: Eb ~1.0065
/// on spot turns, ~1.0123 on circles of 0.37 m radius). This extends 000 Eq. 2.4 (with b_eff of
/// Eq. 2.8) by a factor on the heading change only. Per tick, with dL, dR the accepted deltas
/// (forward positive):
///   v = |dL| + |dR|;  m = 2 min(|dL|, |dR|) if dL, dR have the same strict sign, else 0
///   dtheta = dtheta(000 Eq. 2.4, with Ed, Eb, Es) * (1 - k m / v)      (v == 0: no motion)
/// m / v = 1 - s, where s = |dR - dL| / v is the spin fraction (1 on a spot turn, 0 straight,
/// b / 2R on an arc of radius R). So Eb keeps its meaning on spot turns (what UMBmark measures)
/// and the effective wheelbase on an arc is b Eb / (1 - k (1 - s)); k > 0 lengthens it. The
/// centre displacement (Eq. 2.3) is unchanged. k in Q30, |k| <= 1/4; k == 0 skips the term and
/// gives bit for bit the plain Eq. 2.4. Cost when k != 0 and both wheels move the same way: two
/// 64x32 modular multiplies for k dtheta, one odo_frac_q32 (two 32-bit divisions) and one 64x32
/// multiply (x86-64: about 130 instructions per truck on an arc tick, a few on a spot turn;
/// `odo-bench --json` prints scrub_step_instructions). Error: m / v is rounded to Q32 (within
/// 2^-33, no ties) and then multiplies k dtheta, so the heading error per tick is below
/// |k dtheta| 2^-33 (about 3e-11 rad per radian turned at |k| = 1/4) plus half a Q64 LSB per
/// count from the rounded k-scaled multipliers (1.7e-19 turns per count).
///
/// Accuracy (tests/host/test_odometry_reference.c and odo-bench): against a double-precision
/// reference fed the same counts, after 1 km of mixed driving the pose differs by <= 0.1 mm and
/// <= 1e-6 rad.
#ifndef ODO_ODOMETRY_H
#define ODO_ODOMETRY_H

#include <stdbool.h>
#include <stdint.h>

#include "odo/odo_params.h"
#include "odo/odo_types.h"

#ifdef __cplusplus
extern "C" {
#endif

/// Per-truck multipliers, precomputed by odo_model_init from one odo_truck_params_t.
typedef struct {
    int64_t dist_mm_q40[2];     ///< distance per count, [ODO_LEFT, ODO_RIGHT]: cL/R * cm (Eq. 6.35)
    uint64_t turn_q64[2];       ///< heading change per count: dist / (2 pi b_eff) (Eq. 2.4), turns Q64
    uint64_t scrub_turn_q64[2]; ///< k * turn_q64[w], two's complement (the scrub term's k dtheta)
    int32_t scrub_q30;          ///< k of the scrub term (odo_truck_params_t); 0: term skipped
    uint32_t max_counts;        ///< largest believable |delta| per tick (from max_wheel_speed_mm_s)
    uint32_t max_delta_counts;  ///< largest |delta| one step can integrate (k |delta| < 2^61 mm Q40
                                ///< on both wheels; >= max_counts), for steps over a gap
    uint8_t counter_bits;       ///< decoder counter width, ODO_COUNTER_BITS_MIN..ODO_COUNTER_BITS_MAX
    uint8_t invert;             ///< ODO_TRUCK_INVERT_* flags
    uint8_t heading_form;       ///< odo_heading_form_t
} odo_model_t;

/// A truck's dead-reckoning state.
typedef struct {
    odo_pose_t pose;
    uint32_t last_raw[2]; ///< last accepted raw counter values
    bool primed;          ///< last_raw holds a reading (the first reading only sets the baseline)
} odo_truck_t;

/// What one odometry step did.
typedef struct {
    int64_t dist_mm_q40; ///< centre-point displacement U_i (000 Eq. 2.3), mm Q40
    int64_t dturn_q64;   ///< heading change dtheta_i (000 Eq. 2.4), signed turns Q64
    int32_t delta[2];    ///< accepted count deltas, forward positive
    bool jump;           ///< implausible or ambiguous reading (see odo_truck_step): nothing
                         ///< integrated, baseline re-taken
    bool range;          ///< the pose is beyond ODO_POSE_LIMIT_MM_Q32 (odo_pose_in_range false);
                         ///< if it already was, nothing was integrated (pose held)
} odo_step_t;

typedef enum {
    ODO_MODEL_OK = 0,
    ODO_MODEL_ERR_RANGE, ///< the parameters give multipliers that do not fit the number formats
} odo_model_status_t;

/// Counter widths a wheel decoder may have (odo_params_t.counter_bits; real decoders: 8 to 32).
#define ODO_COUNTER_BITS_MIN 8U
#define ODO_COUNTER_BITS_MAX 32U

/// Precompute the multipliers for one truck (integer 128-bit arithmetic; a few microseconds).
///   cm     = pi * (Dn / Es) / counts_per_rev              (000 Eq. 2.1 with App. B: Dn* = Dn/Es)
///   cL, cR = 2 / (Ed + 1), 2 / (1/Ed + 1)                  (000 Eqs. 6.33, 6.34)
///   b_eff  = Eb * b_nominal                               (000 Eq. 6.28 via Eq. 2.8)
///   k turn = k * turn per count                           (the scrub term above)
/// Note on App. B: Eq. B.1 defines Es = L_calc/L_actual, so the diameter that makes L_calc equal
/// L_actual is Dn/Es; the transcription's "Dn* = Es Dn" (B.2) contradicts B.1 and is not used.
/// Returns ODO_MODEL_ERR_RANGE (and leaves *m untouched) if counter_bits is outside [8, 32], |k|
/// exceeds 1/4, a multiplier would overflow its format, max_counts * distance exceeds 2^61 mm
/// Q40, or max_counts reaches half the counter range (the modular delta would be ambiguous: an
/// 8-bit counter allows at most 127 counts per tick); params must already pass odo_params_validate.
odo_model_status_t odo_model_init(odo_model_t *m, const odo_truck_params_t *tp, uint8_t counter_bits,
                                  uint8_t heading_form, uint32_t tick_us, uint32_t max_wheel_speed_mm_s);

/// Signed difference cur - prev of two raw counter readings modulo 2^bits, interpreted in
/// [-2^(bits-1), 2^(bits-1)). Handles every wrap of any counter width. bits above 32 count as
/// 32; bits 0 returns 0 (no information). Constant time.
int32_t odo_count_delta(uint32_t prev, uint32_t cur, uint8_t bits);

/// The odometry integrates from x and y in [-L, L), L = 2^61 mm Q32 = 2^29 mm (536.87 km). One
/// step moves a pose by less than 2^54 mm Q32, so positions stay below 2^62 in magnitude and every
/// difference of two positions (IPEC's link vector) fits int64. Beyond, odo_truck_step holds it.
#define ODO_POSE_LIMIT_MM_Q32 ((int64_t)1 << 61)

/// True iff x and y are both in [-ODO_POSE_LIMIT_MM_Q32, ODO_POSE_LIMIT_MM_Q32). Constant time.
bool odo_pose_in_range(const odo_pose_t *p);

/// Reset a truck to a pose; the next reading sets the counter baseline.
void odo_truck_reset(odo_truck_t *t, const odo_pose_t *pose);

/// One dead-reckoning step from raw counter readings (000 Eqs. 2.2-2.6, with the scrub term).
///   bits   the width the readings carry (a CAN frame carries 24); deltas are taken modulo 2^w,
///          w = min(bits, the model's counter_bits).
///   ticks  ticks elapsed since the previous reading (1: consecutive samples; 0 counts as 1).
///          Counters are cumulative, so a reading after lost samples carries their motion, and
///          the plausibility limit is max_counts * ticks.
/// The first reading after odo_truck_reset only sets the baseline. out->jump is set, the pose is
/// not changed and the baseline is re-taken when
///   - |delta| > max_counts * ticks on either wheel (faster than max_wheel_speed_mm_s), or
///     |delta| > max_delta_counts (a step too large to integrate), or
///   - max_counts * ticks >= 2^(w-1): the wheel could have moved half the counter's range since
///     the previous reading, so the modular delta is ambiguous whatever it reads (a gap too long
///     for the counter width, or a w too narrow for one tick at the speed limit), or w == 0.
/// out->range is set when the pose is beyond ODO_POSE_LIMIT_MM_Q32 after the step; a pose that was
/// beyond it already is held (not integrated, baseline re-taken). A jump leaves out->range false.
/// Over several ticks (ticks > 1) with the midpoint heading form, the position moves by the chord
/// of the constant-curvature arc, U sin(dtheta/2) / (dtheta/2), along the midpoint heading: the
/// arc's end, where U alone would overshoot by a part growing with the cube of the gap. Per tick
/// it moves by U, as 000 Eq. 2.5 and the double reference have it. A heading change above half a
/// turn in one step (a spin at speed over a long gap) is kept exactly modulo a turn (the scrub
/// term, from two turns on), but its midpoint direction is then taken the short way round.
/// Never fails otherwise. Constant time: no loop over the gap.
void odo_truck_step(odo_truck_t *t, const odo_model_t *m, uint32_t left_raw, uint32_t right_raw, uint8_t bits,
                    uint32_t ticks, odo_step_t *out);

/// The tyre-scrub part of one tick's heading change, k dtheta m / v in signed turns Q64 (the term
/// above; odo_truck_step subtracts it when k != 0), for accepted deltas (|d| <= max_delta_counts).
/// 0 unless both wheels moved the same strict way. Constant time: two 32-bit divisions at most.
/// A function of its own so the k == 0 path of odo_truck_step carries none of its code.
int64_t odo_scrub_dturn(const odo_model_t *m, int32_t d_left, int32_t d_right);

/// Advance a pose by a centre displacement and heading change (000 Eqs. 2.5, 2.6), with the
/// midpoint or the paper's heading form. Shared by odometry and IPEC re-integration.
void odo_pose_advance(odo_pose_t *p, int64_t dist_mm_q40, int64_t dturn_q64, uint8_t heading_form);

/// sin(x) / x in Q30 for x = dturn_q64 / 2 (signed turns Q64, below half a turn): 1 - x^2/6 +
/// x^4/120 - x^6/5040, within 3e-5 up to |x| = pi/2. Multiplies only. The chord factor of a step
/// over several ticks (odo_truck_step); not on the per-tick path.
int32_t odo_sinc_half_q30(int64_t dturn_q64);

/// What odo_truck_tick did, as bits of its result (the same meaning as odo_step_t's fields).
#define ODO_STEP_JUMP  0x1U ///< implausible or ambiguous reading: nothing integrated, baseline re-taken
#define ODO_STEP_RANGE 0x2U ///< the pose is beyond ODO_POSE_LIMIT_MM_Q32

/// odo_truck_step in the form the 40 ms step uses (odo_app.c): the sample as the tick input has it
/// (w->present is not looked at), the result as ODO_STEP_* bits, the displacement U (mm Q40) and
/// heading change (signed turns Q64) written to motion[0] and motion[1] (0 when nothing was
/// integrated). The same body as odo_truck_step, bit for bit, without the result struct to fill
/// and copy. Constant time.
uint32_t odo_truck_tick(odo_truck_t *t, const odo_model_t *m, const odo_wheel_input_t *w, uint32_t ticks,
                        int64_t motion[2]);

/// Conversions for output: heading as BAM (rounded), position in units of 10 um (rounded half
/// up, saturating to int32: +-21.47 km, the POSE_XY frame's range; *saturated, if not NULL, is set
/// true when it saturated and left alone otherwise).
uint32_t odo_heading_bam(const odo_pose_t *p);
int32_t odo_mm_q32_to_10um(int64_t v_mm_q32, bool *saturated);

/// mm Q32 to units of 10 um, rounded half up, not saturated: floor(v * 100 / 2^32 + 1/2), exact
/// for every int64 (the result is below 2^38 in magnitude). With v = hi 2^32 + lo: hi * 100 plus
/// floor((lo * 100 + 2^31) / 2^32), the latter from lo's two 16-bit halves in 32-bit arithmetic
/// (two MULs; a 64-bit product by the constant 100 is expanded by gcc into a dozen shifts and
/// adds). About 11 instructions. The step saturates the result itself (odo_app.c);
/// odo_mm_q32_to_10um above is the same plus the clamp.
static inline int64_t odo_mm_q32_to_10um_wide(int64_t v_mm_q32)
{
    const uint32_t lo = (uint32_t)((uint64_t)v_mm_q32 & 0xFFFFFFFFU);
    const uint32_t hi = (uint32_t)((uint64_t)v_mm_q32 >> 32);
    const int32_t shi = hi <= (uint32_t)INT32_MAX ? (int32_t)hi : -(int32_t)(~hi) - 1;
    /* lo * 100 = a 2^16 + b with a, b < 2^23; floor((a 2^16 + b + 2^31) / 2^32) nests exactly. */
    const uint32_t a = (lo >> 16) * 100U, b = (lo & 0xFFFFU) * 100U;
    return (int64_t)shi * 100 + (int64_t)((a + ((b + 0x80000000U) >> 16)) >> 16);
}

#ifdef __cplusplus
}
#endif
#endif
