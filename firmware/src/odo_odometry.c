/// Per-truck dead reckoning, 000_12e7709aa9cd375a.txt Eqs. 2.1-2.6 with the UMBmark corrections
/// (Eqs. 6.28, 6.33-6.35) and the scale correction of App. B. See odo_odometry.h.
#include "odo/odo_odometry.h"

#include "odo/odo_fx.h"

/* pi * 2^60 and 2^64 / (2 pi), rounded to nearest (computed with 60-digit decimal arithmetic;
 * tests/unit/test_odometry.c checks them against libm). */
#define PI_Q60      3622009729038561421ULL
#define INV_2PI_Q64 2935890503282001226ULL

#define Q30_ONE_U     ((uint64_t)1U << 30)
#define SCRUB_MAX_Q30 ((int32_t)ODO_SCRUB_MAX_Q30)
#define NM_PER_MM     1000000U

/* Heading bookkeeping reads a per-tick heading change as a signed fraction of a turn, which is
 * unambiguous only below half a turn: keep each wheel's worst case below a quarter. */
#define TURN_LIMIT_Q64 ((uint64_t)1U << 62)
/* Distance per tick per wheel stays below 2^61 mm Q40 (about 2 km) so sums cannot overflow. */
#define DIST_LIMIT_Q40 ((uint64_t)1U << 61)

/// Round a Q60 value to Q40.
static uint64_t q60_to_q40(uint64_t v) { return (v >> 20) + ((v >> 19) & 1U); }

odo_model_status_t odo_model_init(odo_model_t *m, const odo_truck_params_t *tp, uint8_t counter_bits,
                                  uint8_t heading_form, uint32_t tick_us, uint32_t max_wheel_speed_mm_s)
{
    const uint64_t ed = (uint64_t)(uint32_t)tp->ed_q30;
    const uint64_t eb = (uint64_t)(uint32_t)tp->eb_q30;
    const uint64_t es = (uint64_t)(uint32_t)tp->es_q30;
    if (tp->ed_q30 <= 0 || tp->eb_q30 <= 0 || tp->es_q30 <= 0 || tp->wheelbase_nm == 0U ||
        tp->counts_per_rev_milli == 0U || counter_bits < ODO_COUNTER_BITS_MIN || counter_bits > ODO_COUNTER_BITS_MAX ||
        tp->scrub_q30 < -SCRUB_MAX_Q30 || tp->scrub_q30 > SCRUB_MAX_Q30) {
        return ODO_MODEL_ERR_RANGE;
    }

    /* cm, mm per count, in Q60: pi * Dn / counts = pi * Dn_nm / (1000 * counts_milli) (Eq. 2.1). */
    uint64_t cm_q60;
    if (!odo_muldiv_u64(tp->wheel_diameter_nm, PI_Q60, 1000ULL * tp->counts_per_rev_milli, &cm_q60)) {
        return ODO_MODEL_ERR_RANGE;
    }
    /* Dn* = Dn / Es (App. B, Eq. B.1; see the header on B.2). */
    if (!odo_muldiv_u64(cm_q60, Q30_ONE_U, es, &cm_q60)) {
        return ODO_MODEL_ERR_RANGE;
    }

    odo_model_t mm;
    /* cL = 2 / (Ed + 1), cR = 2 Ed / (Ed + 1) (Eqs. 6.33, 6.34), applied as in Eq. 6.35. */
    const uint64_t num[2] = {2U * Q30_ONE_U, 2U * ed};
    uint64_t k_q60[2];
    for (unsigned w = 0U; w < 2U; ++w) {
        if (!odo_muldiv_u64(cm_q60, num[w], ed + Q30_ONE_U, &k_q60[w])) {
            return ODO_MODEL_ERR_RANGE;
        }
        mm.dist_mm_q40[w] = (int64_t)q60_to_q40(k_q60[w]);
        if (mm.dist_mm_q40[w] <= 0) {
            return ODO_MODEL_ERR_RANGE; /* below 2^-40 mm per count: not a real encoder */
        }
        /* Heading per count: k / (2 pi Eb b) in turns Q64 (Eqs. 2.4, 6.28).
         * k / b_mm in Q64 first (k_q60 * 1e6 * 2^4 / b_nm), then / Eb, then * 1/(2 pi). */
        uint64_t k_over_b_q64;
        if (!odo_muldiv_u64(k_q60[w], (uint64_t)NM_PER_MM << 4, tp->wheelbase_nm, &k_over_b_q64) ||
            !odo_muldiv_u64(k_over_b_q64, Q30_ONE_U, eb, &k_over_b_q64)) {
            return ODO_MODEL_ERR_RANGE;
        }
        const odo_u128_t t = odo_mul_u64(k_over_b_q64, INV_2PI_Q64);
        mm.turn_q64[w] = t.hi + (t.lo >> 63);
    }

    /* Largest believable count change per tick: the faster wheel at max speed, plus one count.
     * counts = (v * tick) / k = d_um * 2^40 / (1000 * k_q40), using the smaller k. */
    /* ceil(v * tick / 1000) in um, v * 1000 a + v b with tick = 1000 a + b: 32-bit divisions
     * only (v <= 20000 mm/s keeps v b + 999 below 2^32). */
    if (max_wheel_speed_mm_s > 4000000U) {
        return ODO_MODEL_ERR_RANGE;
    }
    const uint64_t d_um =
        (uint64_t)max_wheel_speed_mm_s * (tick_us / 1000U) + (max_wheel_speed_mm_s * (tick_us % 1000U) + 999U) / 1000U;
    const uint64_t k_min = (uint64_t)(mm.dist_mm_q40[0] < mm.dist_mm_q40[1] ? mm.dist_mm_q40[0] : mm.dist_mm_q40[1]);
    uint64_t max_counts;
    if (!odo_muldiv_u64(d_um, (uint64_t)1U << 40, 1000U * k_min, &max_counts)) {
        return ODO_MODEL_ERR_RANGE;
    }
    max_counts += 1U;
    /* The modular delta of a w-bit counter is unambiguous only below 2^(w-1). */
    const uint64_t half_range = (uint64_t)1U << (counter_bits - 1U);
    if (max_counts >= half_range) {
        return ODO_MODEL_ERR_RANGE;
    }
    for (unsigned w = 0U; w < 2U; ++w) {
        const odo_u128_t dist = odo_mul_u64((uint64_t)mm.dist_mm_q40[w], max_counts);
        const odo_u128_t turn = odo_mul_u64(mm.turn_q64[w], max_counts);
        if (dist.hi != 0U || dist.lo >= DIST_LIMIT_Q40 || turn.hi != 0U || turn.lo >= TURN_LIMIT_Q64) {
            return ODO_MODEL_ERR_RANGE;
        }
    }
    /* k * turn per count for the scrub term. turn * max_counts < 2^62 (checked above) and
     * |k| <= 1/4, so k * turn * |delta| stays below 2^60 for every one-tick delta (over a gap the
     * products are taken modulo 2^64, as Eq. 2.4's are). */
    for (unsigned w = 0U; w < 2U; ++w) {
        mm.scrub_turn_q64[w] = (uint64_t)odo_mul_s64_s32_shr((int64_t)mm.turn_q64[w], tp->scrub_q30, 30U);
    }
    mm.scrub_q30 = tp->scrub_q30;
    /* The largest delta one step can integrate (a gap of many ticks): k * |d| < 2^61 on both
     * wheels, so their sum cannot overflow. At least max_counts, by the check above. */
    uint64_t max_delta = (uint64_t)INT32_MAX;
    for (unsigned w = 0U; w < 2U; ++w) {
        /* floor((2^61 - 1) / k) through the shared 128-bit division (no 64-bit division in the
         * image): round, then step back if the rounding went up. */
        const uint64_t k = (uint64_t)mm.dist_mm_q40[w];
        uint64_t q;
        if (!odo_muldiv_u64(DIST_LIMIT_Q40 - 1U, 1U, k, &q)) {
            return ODO_MODEL_ERR_RANGE;
        }
        q -= (q * k > DIST_LIMIT_Q40 - 1U) ? 1U : 0U;
        max_delta = q < max_delta ? q : max_delta;
    }
    mm.max_counts = (uint32_t)max_counts;
    mm.max_delta_counts = (uint32_t)max_delta;
    mm.counter_bits = counter_bits;
    mm.invert = tp->flags;
    mm.heading_form = heading_form;
    *m = mm;
    return ODO_MODEL_OK;
}

/// The modular delta of a w-bit counter, w in [1, 32]: the low w bits of cur - prev read as a
/// w-bit two's complement number (xor-subtract sign extension). Branch-free.
static inline int32_t delta_bits(uint32_t prev, uint32_t cur, unsigned w)
{
    const uint32_t mask = UINT32_MAX >> (32U - w);
    const uint32_t sign = (uint32_t)0x80000000U >> (32U - w);
    return odo_as_s32((((cur - prev) & mask) ^ sign) - sign);
}

/// |v| as unsigned; exact for INT32_MIN.
static inline uint32_t mag32(int32_t v) { return v < 0 ? 0U - (uint32_t)v : (uint32_t)v; }

/// v in [-L, L) iff v + L (modulo 2^64) is below 2L = 2^62: one OR tests both coordinates.
static inline bool in_range(const odo_pose_t *p)
{
    const uint64_t lim = (uint64_t)ODO_POSE_LIMIT_MM_Q32;
    return ((((uint64_t)p->x_mm_q32 + lim) | ((uint64_t)p->y_mm_q32 + lim)) >> 62) == 0U;
}

/// The direction of 000 Eq. 2.5's step as a BAM: the new heading (Eq. 2.6, PAPER) or the
/// midpoint, the old heading plus floor(dturn / 2), which is exact in direction for a
/// constant-curvature arc (second-order accurate).
static inline uint32_t step_direction_bam(const odo_pose_t *p, int64_t dturn_q64, uint8_t heading_form)
{
    const int64_t part = (heading_form == (uint8_t)ODO_HEADING_PAPER) ? dturn_q64 : odo_floor_shr_s64(dturn_q64, 1U);
    return (uint32_t)((p->heading_q64 + (uint64_t)part + 0x80000000ULL) >> 32);
}

/// 000 Eqs. 2.5, 2.6 given the direction's sin and cos: two inline 64x32 products (Q40 mm x Q30 ->
/// Q32 mm; |dist| < 2^62 keeps each below 2^54), then the heading turns by dturn.
static inline void move(odo_pose_t *p, int64_t dist_mm_q40, int64_t dturn_q64, int32_t s, int32_t c)
{
    p->x_mm_q32 += odo_mul_s64_s32_rnd(dist_mm_q40, c, 38U);
    p->y_mm_q32 += odo_mul_s64_s32_rnd(dist_mm_q40, s, 38U);
    p->heading_q64 += (uint64_t)dturn_q64;
}

/// The one body of odo_truck_step and odo_truck_tick (see odo_truck_step for the contract). A step
/// of one tick stays in 32-bit arithmetic up to the products of 000 Eqs. 2.2-2.4: two 64x32 each
/// for distance and heading. Writes *dist, *dturn and d[] (0 when nothing was integrated) and
/// returns ODO_STEP_* bits.
static inline uint32_t step(odo_truck_t *t, const odo_model_t *m, uint32_t left_raw, uint32_t right_raw, uint8_t bits,
                            uint32_t ticks, int64_t *dist_out, int64_t *dturn_out, int32_t d_out[2])
{
    const uint8_t w_bits = bits < m->counter_bits ? bits : m->counter_bits;
    *dist_out = 0;
    *dturn_out = 0;
    d_out[0] = 0;
    d_out[1] = 0;
    const uint32_t prev_l = t->last_raw[0], prev_r = t->last_raw[1];
    t->last_raw[0] = left_raw;
    t->last_raw[1] = right_raw;
    if (!t->primed) {
        t->primed = true;
        return 0U;
    }
    if (w_bits == 0U) {
        return ODO_STEP_JUMP; /* a reading of no bits tells nothing */
    }
    /* The wheel may travel max_counts per tick elapsed. A modular delta of a w-bit reading is
     * unambiguous only below 2^(w-1): if the wheel could have gone that far since the previous
     * reading, the reading cannot be trusted whatever it says. One tick stays in 32 bits. */
    const uint32_t half_range = (uint32_t)1U << (w_bits - 1U);
    uint32_t limit = m->max_counts;
    bool jump;
    if (ticks <= 1U) {
        jump = limit >= half_range;
    } else {
        const uint64_t reach = (uint64_t)limit * ticks; /* 32x32 -> 64: cannot overflow */
        jump = reach >= half_range;
        limit = reach < m->max_delta_counts ? (uint32_t)reach : m->max_delta_counts;
    }
    int32_t d_l = delta_bits(prev_l, left_raw, w_bits);
    int32_t d_r = delta_bits(prev_r, right_raw, w_bits);
    if (jump || mag32(d_l) > limit || mag32(d_r) > limit) {
        return ODO_STEP_JUMP; /* physically impossible or ambiguous: do not integrate garbage */
    }
    if (!in_range(&t->pose)) {
        return ODO_STEP_RANGE; /* one more step could leave int64: hold the pose */
    }
    /* |d| <= limit < 2^31 here, so negation is safe. */
    if ((m->invert & ODO_TRUCK_INVERT_LEFT) != 0U) {
        d_l = -d_l;
    }
    if ((m->invert & ODO_TRUCK_INVERT_RIGHT) != 0U) {
        d_r = -d_r;
    }
    /* Eqs. 2.2/6.35 and 2.3: |d| <= max_delta_counts, so |k d| < 2^61 and the sum fits; its
     * half is rounded half up. */
    const int64_t dist = odo_floor_shr_s64(m->dist_mm_q40[0] * d_l + m->dist_mm_q40[1] * d_r + 1, 1U);
    /* Eq. 2.4 in turns: modular arithmetic on uint64 is exact whatever the size of d; read as a
     * signed change it is below a quarter turn per tick elapsed (checked at init). */
    int64_t dturn = odo_as_s64(m->turn_q64[1] * (uint64_t)(int64_t)d_r - m->turn_q64[0] * (uint64_t)(int64_t)d_l);
    if (m->scrub_q30 != 0) {
        /* g = 1 - k m / v, |k m / v| <= 1/4; modulo a turn, as a gap's dturn may be near half a
         * turn already. */
        dturn = odo_as_s64((uint64_t)dturn - (uint64_t)odo_scrub_dturn(m, d_l, d_r));
    }
    /* Over several ticks the midpoint form's step (the arc length U along the chord's direction)
     * overshoots by U (1 - sinc(dtheta/2)), an error that grows with the cube of the gap: take the
     * chord of the constant-curvature arc instead (only on this rare path; per tick the paper's
     * U stays, as the double reference has it). */
    const int64_t along = (ticks > 1U && m->heading_form == (uint8_t)ODO_HEADING_MIDPOINT)
                              ? odo_mul_s64_s32_shr(dist, odo_sinc_half_q30(dturn), 30U)
                              : dist;
    const uint64_t sc = odo_sincos_pair_q30(step_direction_bam(&t->pose, dturn, m->heading_form));
    move(&t->pose, along, dturn, odo_sincos_sin_q30(sc), odo_sincos_cos_q30(sc));
    *dist_out = dist;
    *dturn_out = dturn;
    d_out[0] = d_l;
    d_out[1] = d_r;
    return in_range(&t->pose) ? 0U : ODO_STEP_RANGE; /* held from the next step on */
}

int32_t odo_count_delta(uint32_t prev, uint32_t cur, uint8_t bits)
{
    if (bits == 0U) {
        return 0; /* no bits, no information */
    }
    return delta_bits(prev, cur, bits > 32U ? 32U : bits);
}

void odo_truck_reset(odo_truck_t *t, const odo_pose_t *pose)
{
    t->pose = *pose;
    t->last_raw[0] = 0U;
    t->last_raw[1] = 0U;
    t->primed = false;
}

bool odo_pose_in_range(const odo_pose_t *p) { return in_range(p); }

int32_t odo_sinc_half_q30(int64_t dturn_q64)
{
    /* x in rad Q30 = pi * dturn / 2^64 * 2^30 = dturn * (pi * 2^29) / 2^63; |x| < pi/2 */
    const int64_t x = odo_mul_s64_s32_shr(dturn_q64, 1686629713, 63U);
    const int64_t x2 = (x * x) >> 30;                         /* x^2 in Q30, < 2.65e9 */
    int64_t p = ODO_Q30_ONE - ((x2 * 25565282) >> 30);        /* 1 - x^2/42 */
    p = ODO_Q30_ONE - ((((x2 * p) >> 30) * 53687091) >> 30);  /* 1 - x^2/20 (...) */
    p = ODO_Q30_ONE - ((((x2 * p) >> 30) * 178956971) >> 30); /* 1 - x^2/6 (...) */
    return (int32_t)p;
}

int64_t odo_scrub_dturn(const odo_model_t *m, int32_t d_left, int32_t d_right)
{
    const int32_t d[2] = {d_left, d_right};
    if ((int64_t)d[0] * d[1] <= 0) {
        return 0; /* a spot turn, a pivot on one wheel or a stop: m = 0 */
    }
    const uint32_t a = mag32(d[0]), b = mag32(d[1]);
    const uint32_t v = a + b;                 /* < 2^32: |d| <= max_delta_counts < 2^31 */
    const uint32_t mv = 2U * (a < b ? a : b); /* <= v */
    /* k * dtheta from the k-scaled multipliers, with the same exact modular sum as Eq. 2.4. */
    const int64_t k_dturn =
        odo_as_s64(m->scrub_turn_q64[1] * (uint64_t)(int64_t)d[1] - m->scrub_turn_q64[0] * (uint64_t)(int64_t)d[0]);
    if (mv == v) {
        return k_dturn; /* equal wheels: m / v = 1 (does not fit Q32) */
    }
    return odo_mul_s64_u32_shr(k_dturn, odo_frac_q32(mv, v), 32U);
}

uint32_t odo_truck_tick(odo_truck_t *t, const odo_model_t *m, const odo_wheel_input_t *w, uint32_t ticks,
                        int64_t motion[2])
{
    int32_t d[2];
    return step(t, m, w->left_raw, w->right_raw, w->bits, ticks, &motion[0], &motion[1], d);
}

void odo_truck_step(odo_truck_t *t, const odo_model_t *m, uint32_t left_raw, uint32_t right_raw, uint8_t bits,
                    uint32_t ticks, odo_step_t *out)
{
    const uint32_t r = step(t, m, left_raw, right_raw, bits, ticks, &out->dist_mm_q40, &out->dturn_q64, out->delta);
    out->jump = (r & ODO_STEP_JUMP) != 0U;
    out->range = (r & ODO_STEP_RANGE) != 0U;
}

void odo_pose_advance(odo_pose_t *p, int64_t dist_mm_q40, int64_t dturn_q64, uint8_t heading_form)
{
    int32_t s, c;
    odo_sincos_q30(step_direction_bam(p, dturn_q64, heading_form), &s, &c);
    move(p, dist_mm_q40, dturn_q64, s, c);
}

uint32_t odo_heading_bam(const odo_pose_t *p) { return (uint32_t)((p->heading_q64 + 0x80000000ULL) >> 32); }

int32_t odo_mm_q32_to_10um(int64_t v_mm_q32, bool *saturated)
{
    const int64_t v = odo_mm_q32_to_10um_wide(v_mm_q32);
    if (v > INT32_MAX || v < INT32_MIN) {
        if (saturated != NULL) {
            *saturated = true;
        }
        return v > 0 ? INT32_MAX : INT32_MIN;
    }
    return (int32_t)v;
}
