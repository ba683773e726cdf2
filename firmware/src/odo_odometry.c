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
    const uint64_t d_um = ((uint64_t)max_wheel_speed_mm_s * tick_us + 999U) / 1000U;
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
        const uint64_t q = (DIST_LIMIT_Q40 - 1U) / (uint64_t)mm.dist_mm_q40[w];
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

int32_t odo_count_delta(uint32_t prev, uint32_t cur, uint8_t bits)
{
    if ((unsigned)bits - 1U >= 31U) { /* 0, or 32 and above */
        if (bits == 0U) {
            return 0; /* no bits, no information */
        }
        const uint32_t d = cur - prev;
        return d >= 0x80000000UL ? (int32_t)((int64_t)d - ((int64_t)1 << 32)) : (int32_t)d;
    }
    const uint32_t mask = ((uint32_t)1U << bits) - 1U;
    const uint32_t d = (cur - prev) & mask;
    return d >= ((uint32_t)1U << (bits - 1U)) ? (int32_t)((int64_t)d - ((int64_t)1 << bits)) : (int32_t)d;
}

void odo_truck_reset(odo_truck_t *t, const odo_pose_t *pose)
{
    t->pose = *pose;
    t->last_raw[0] = 0U;
    t->last_raw[1] = 0U;
    t->primed = false;
}

/// Reinterpret a uint64 as two's complement int64 without implementation-defined conversion.
static int64_t as_signed(uint64_t u) { return u <= (uint64_t)INT64_MAX ? (int64_t)u : -(int64_t)(~u) - 1; }

/// |v| as unsigned; exact for INT32_MIN.
static uint32_t mag32(int32_t v) { return v < 0 ? 0U - (uint32_t)v : (uint32_t)v; }

/// v in [-L, L) iff v + L (modulo 2^64) is below 2L = 2^62: one OR tests both coordinates.
static bool in_range(const odo_pose_t *p)
{
    const uint64_t lim = (uint64_t)ODO_POSE_LIMIT_MM_Q32;
    return ((((uint64_t)p->x_mm_q32 + lim) | ((uint64_t)p->y_mm_q32 + lim)) >> 62) == 0U;
}

bool odo_pose_in_range(const odo_pose_t *p) { return in_range(p); }

/// sin(x) / x in Q30 for x = dtheta / 2, dtheta = dturn_q64 signed turns (below half a turn):
/// 1 - x^2/6 + x^4/120 - x^6/5040 in Horner form, within 3e-5 up to |x| = pi/2. Multiplies only
/// (Q30 reciprocals of 42, 20 and 6), every product below 2^62.
static int32_t sinc_half_q30(int64_t dturn_q64)
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
        as_signed(m->scrub_turn_q64[1] * (uint64_t)(int64_t)d[1] - m->scrub_turn_q64[0] * (uint64_t)(int64_t)d[0]);
    if (mv == v) {
        return k_dturn; /* equal wheels: m / v = 1 (does not fit Q32) */
    }
    return odo_mul_s64_u32_shr(k_dturn, odo_frac_q32(mv, v), 32U);
}

void odo_truck_step(odo_truck_t *t, const odo_model_t *m, uint32_t left_raw, uint32_t right_raw, uint8_t bits,
                    uint32_t ticks, odo_step_t *out)
{
    const uint32_t raw[2] = {left_raw, right_raw};
    const uint8_t w_bits = bits < m->counter_bits ? bits : m->counter_bits;
    out->dist_mm_q40 = 0;
    out->dturn_q64 = 0;
    out->delta[0] = 0;
    out->delta[1] = 0;
    out->jump = false;
    out->range = false;
    if (!t->primed) {
        t->last_raw[0] = raw[0];
        t->last_raw[1] = raw[1];
        t->primed = true;
        return;
    }

    /* The wheel may travel max_counts per tick elapsed. A modular delta of a w-bit reading is
     * unambiguous only below 2^(w-1): if the wheel could have gone that far since the previous
     * reading, the reading cannot be trusted whatever it says (32x32 -> 64: cannot overflow). */
    uint64_t reach = m->max_counts; /* counts the wheel could have turned since the last reading */
    if (ticks > 1U) {
        reach *= ticks;
    }
    out->jump = w_bits == 0U || reach >= ((uint64_t)1U << (w_bits - 1U));
    const uint32_t limit = reach < m->max_delta_counts ? (uint32_t)reach : m->max_delta_counts;
    int32_t d[2];
    for (unsigned w = 0U; w < 2U; ++w) {
        d[w] = odo_count_delta(t->last_raw[w], raw[w], w_bits);
        if (mag32(d[w]) > limit) {
            out->jump = true; /* physically impossible: do not integrate garbage */
        }
    }
    t->last_raw[0] = raw[0];
    t->last_raw[1] = raw[1];
    if (out->jump) {
        return;
    }
    if (!in_range(&t->pose)) {
        out->range = true; /* one more step could leave int64: hold the pose */
        return;
    }
    /* |d| <= limit < 2^31 here, so negation is safe. */
    if ((m->invert & ODO_TRUCK_INVERT_LEFT) != 0U) {
        d[0] = -d[0];
    }
    if ((m->invert & ODO_TRUCK_INVERT_RIGHT) != 0U) {
        d[1] = -d[1];
    }

    /* Eqs. 2.2/6.35 and 2.3: |d| <= max_delta_counts, so |k * d| < 2^61 and the sum fits. */
    const int64_t s_l = m->dist_mm_q40[0] * d[0];
    const int64_t s_r = m->dist_mm_q40[1] * d[1];
    const int64_t dist = odo_shr_round_s64(s_l + s_r, 1U);
    /* Eq. 2.4 in turns: modular arithmetic on uint64 is exact whatever the size of d; read as a
     * signed change it is below a quarter turn per tick elapsed (checked at init). */
    const uint64_t dturn_u = m->turn_q64[1] * (uint64_t)(int64_t)d[1] - m->turn_q64[0] * (uint64_t)(int64_t)d[0];
    int64_t dturn = as_signed(dturn_u);
    if (m->scrub_q30 != 0) {
        /* g = 1 - k m / v, |k m / v| <= 1/4; modulo a turn, as a gap's dturn may be near half a
         * turn already. */
        dturn = as_signed((uint64_t)dturn - (uint64_t)odo_scrub_dturn(m, d[0], d[1]));
    }

    /* Over several ticks the midpoint form's step (the arc length U along the chord's direction)
     * overshoots by U (1 - sinc(dtheta/2)), an error that grows with the cube of the gap: take the
     * chord of the constant-curvature arc instead (only on this rare path; per tick the paper's
     * U stays, as the double reference has it). */
    const int64_t step = (ticks > 1U && m->heading_form == (uint8_t)ODO_HEADING_MIDPOINT)
                             ? odo_mul_s64_s32_shr(dist, sinc_half_q30(dturn), 30U)
                             : dist;
    odo_pose_advance(&t->pose, step, dturn, m->heading_form);
    out->range = !in_range(&t->pose); /* held from the next step on */
    out->dist_mm_q40 = dist;
    out->dturn_q64 = dturn;
    out->delta[0] = d[0];
    out->delta[1] = d[1];
}

void odo_pose_advance(odo_pose_t *p, int64_t dist_mm_q40, int64_t dturn_q64, uint8_t heading_form)
{
    const uint64_t h_new = p->heading_q64 + (uint64_t)dturn_q64;
    /* Eq. 2.6 advances along the new heading; the midpoint form along theta_{i-1} + dtheta/2,
     * which is exact in direction for a constant-curvature arc (second-order accurate). */
    const uint64_t h_dir =
        (heading_form == (uint8_t)ODO_HEADING_PAPER) ? h_new : p->heading_q64 + (uint64_t)(dturn_q64 / 2);
    int32_t s, c;
    odo_sincos_q30((uint32_t)((h_dir + 0x80000000ULL) >> 32), &s, &c);
    /* Q40 mm * Q30 -> Q32 mm: shift by 38. */
    p->x_mm_q32 += odo_mul_s64_s32_shr(dist_mm_q40, c, 38U);
    p->y_mm_q32 += odo_mul_s64_s32_shr(dist_mm_q40, s, 38U);
    p->heading_q64 = h_new;
}

uint32_t odo_heading_bam(const odo_pose_t *p) { return (uint32_t)((p->heading_q64 + 0x80000000ULL) >> 32); }

int32_t odo_mm_q32_to_10um(int64_t v_mm_q32, bool *saturated)
{
    const int64_t v = odo_mul_s64_s32_shr(v_mm_q32, 100, 32U);
    if (v > INT32_MAX || v < INT32_MIN) {
        if (saturated != NULL) {
            *saturated = true;
        }
        return v > 0 ? INT32_MAX : INT32_MIN;
    }
    return (int32_t)v;
}
