/// IPEC, 002_97a419d21cabf785.txt Eqs. 9-16 (see odo_ipec.h for the conventions).
#include "odo/odo_ipec.h"

#include "odo/odo_fx.h"
#include "odo/odo_odometry.h"
#include "odo/odo_status.h"

/// 2^32 / 10^6 in Q18: nm -> mm Q32 (relative error 1.4e-10).
#define NM_TO_MM_Q32_K18 1125899907L

/// nm -> mm Q32 for |nm| < 2^43 (8.8e12 nm, far beyond any link or wheelbase): the inline
/// product, exact and without the saturation of odo_ipec_nm_to_mm_q32.
static inline int64_t nm_to_mm_q32(int64_t nm) { return odo_mul_s64_s32_rnd(nm, (int32_t)NM_TO_MM_Q32_K18, 18U); }

int64_t odo_ipec_nm_to_mm_q32(int64_t nm) { return odo_mul_s64_s32_shr(nm, (int32_t)NM_TO_MM_Q32_K18, 18U); }

void odo_ipec_init(odo_ipec_t *s) { memset(s, 0, sizeof *s); }

static uint32_t abs_diff_bam16(uint16_t a, uint16_t b)
{
    /* the shortest way round: the 16-bit difference read as signed, without the
     * implementation-defined conversion of a value above INT16_MAX */
    const uint16_t u = (uint16_t)(a - b);
    const int32_t d = u < 0x8000U ? (int32_t)u : (int32_t)u - 65536;
    return (uint32_t)(d < 0 ? -d : d) << 16;
}

/// Half a rotary step, in BAM.
static uint32_t half_step_bam(uint8_t rotary_bits) { return (uint32_t)1U << (31U - rotary_bits); }

static int32_t decode_angle(uint16_t code_bam16, int32_t bias_bam, uint8_t rotary_bits)
{
    /* Code k covers [k, k+1) steps: take the centre, then remove the zero offset. */
    return (int32_t)(((uint32_t)code_bam16 << 16) + half_step_bam(rotary_bits) - (uint32_t)bias_bam);
}

uint32_t odo_ipec_check(odo_ipec_t *s, const odo_params_t *p, const odo_link_input_t *in, odo_ipec_reading_t *rd)
{
    const odo_link_params_t *lp = &p->link;
    const bool clapper = p->vehicle == (uint8_t)ODO_VEHICLE_CLAPPER;
    if (s->age_ticks != UINT32_MAX) {
        s->age_ticks++;
    }
    const uint8_t need_rot =
        (uint8_t)(clapper ? (ODO_LINK_STATUS_ALPHA_VALID | ODO_LINK_STATUS_BETA_VALID) : ODO_LINK_STATUS_ALPHA_VALID);
    const bool rot_ok = in->rotary_present && (in->rotary_status & need_rot) == need_rot;
    const bool lin_ok = !clapper || (in->linear_present && (in->linear_status & ODO_LINK_STATUS_LENGTH_VALID) != 0U);
    if (!rot_ok || !lin_ok) {
        return ODO_FAULT_LINK_MISSING;
    }

    bool stale = false;
    uint32_t ticks = 1U; /* ticks since the reference reading */
    if (s->have_last) {
        const uint8_t dr = (uint8_t)(in->rotary_seq - s->last_rot_seq);
        const uint8_t dl = clapper ? (uint8_t)(in->linear_seq - s->last_lin_seq) : dr;
        if (dr == 0U || dl == 0U) {
            return ODO_FAULT_SEQ_DUP;
        }
        if (dr >= 128U || dl >= 128U) {
            return ODO_FAULT_LINK_STALE; /* out of order: older than a sample already used */
        }
        const uint32_t samples = dr > dl ? dr : dl;
        ticks = s->age_ticks > samples ? s->age_ticks : samples;
        stale = ticks > lp->stale_ticks;
    }

    /* The length first: out of range is never accepted, not even as a reference. */
    if (clapper && (in->length_um < lp->length_min_um || in->length_um > lp->length_max_um)) {
        return ODO_FAULT_LINK_RANGE;
    }
    if (s->have_last && !stale) {
        const uint64_t max_a = (uint64_t)lp->max_jump_bam * ticks;
        const uint64_t max_l = (uint64_t)lp->max_length_jump_um * ticks;
        const uint32_t dl_um =
            in->length_um > s->last_length_um ? in->length_um - s->last_length_um : s->last_length_um - in->length_um;
        if (abs_diff_bam16(in->alpha_bam16, s->last_alpha_bam16) > max_a ||
            (clapper && (abs_diff_bam16(in->beta_bam16, s->last_beta_bam16) > max_a || dl_um > max_l))) {
            return ODO_FAULT_LINK_JUMP;
        }
    }

    s->have_last = true;
    s->last_rot_seq = in->rotary_seq;
    s->last_lin_seq = in->linear_seq;
    s->last_alpha_bam16 = in->alpha_bam16;
    s->last_beta_bam16 = in->beta_bam16;
    s->last_length_um = in->length_um;
    s->age_ticks = 0U;
    if (stale) {
        return ODO_FAULT_LINK_STALE;
    }
    if (rd == NULL) {
        return 0U; /* checked only: IPEC is off */
    }

    rd->alpha_bam = decode_angle(in->alpha_bam16, lp->alpha_bias_bam, lp->rotary_bits);
    if (clapper) {
        rd->beta_bam = decode_angle(in->beta_bam16, lp->beta_bias_bam, lp->rotary_bits);
        /* 002 s. 5.2: constant bias plus an eccentric part that grows as the trucks rotate
         * relative to each other, ecc (1 - cos(alpha - beta)) (host_sim's model). 1 - cos spans
         * [0, 2]: 2^31 in Q30 at 180 deg, one past int32, so the factor is an int64; the product
         * with |ecc| <= 5e7 nm stays below 2^57. No eccentricity: no cosine. */
        int64_t ecc_nm = 0;
        if (lp->length_ecc_nm != 0) {
            const int64_t one_minus_cos_q30 =
                (int64_t)ODO_Q30_ONE - odo_cos_q30((uint32_t)rd->alpha_bam - (uint32_t)rd->beta_bam);
            ecc_nm = odo_mul_s64_s32_rnd(one_minus_cos_q30, lp->length_ecc_nm, 30U);
        }
        const int64_t l_nm = (int64_t)in->length_um * 1000 - lp->length_bias_nm - ecc_nm;
        rd->length_mm_q32 = nm_to_mm_q32(l_nm);
    } else {
        rd->beta_bam = 0;
        rd->length_mm_q32 = nm_to_mm_q32((int64_t)lp->length_nm);
    }
    return 0U;
}

uint32_t odo_ipec_link_heading_bam(const odo_pose_t *a, const odo_pose_t *b)
{
    return odo_atan2_bam(a->y_mm_q32 - b->y_mm_q32, a->x_mm_q32 - b->x_mm_q32);
}

/// Heading as BAM, rounded (odo_heading_bam, inline).
static inline uint32_t heading_bam(const odo_pose_t *p) { return (uint32_t)((p->heading_q64 + 0x80000000ULL) >> 32); }

/// Eq. 16's placement: *b at l (|l| < 2^61 mm Q32 / 2^30... any link: below 2^47) from *a against
/// theta; two inline 64x32 products.
static inline void anchor(const odo_pose_t *a, uint32_t theta_l_bam, int64_t length_mm_q32, odo_pose_t *b)
{
    int32_t s, c;
    odo_sincos_q30(theta_l_bam, &s, &c);
    b->x_mm_q32 = a->x_mm_q32 - odo_mul_s64_s32_rnd(length_mm_q32, c, 30U);
    b->y_mm_q32 = a->y_mm_q32 - odo_mul_s64_s32_rnd(length_mm_q32, s, 30U);
}

static inline void hitch(const odo_pose_t *a, uint32_t hitch_offset_nm, odo_pose_t *h)
{
    anchor(a, heading_bam(a), nm_to_mm_q32((int64_t)hitch_offset_nm), h);
    h->heading_q64 = a->heading_q64;
}

void odo_ipec_hitch(const odo_pose_t *a, uint32_t hitch_offset_nm, odo_pose_t *h) { hitch(a, hitch_offset_nm, h); }

void odo_ipec_anchor(const odo_pose_t *a, uint32_t theta_l_bam, int64_t length_mm_q32, odo_pose_t *b)
{
    anchor(a, theta_l_bam, length_mm_q32, b);
}

/// |sin(h)| in Q30 for a BAM h. A correction is mostly a few rotary steps, so below 2^26 BAM
/// (5.6 deg, x < 0.099 rad) the series x - x^3/6 + x^5/120 in Q32 is used (truncation x^7/5040
/// < 2e-11, three truncating products < 7e-10, output rounding half a Q30 LSB: below 1.2e-9 in
/// all, tests/unit/test_ipec.c sweeps it); larger angles take odo_sin_q30. About 15 Cortex-M4
/// instructions instead of 45.
static int32_t abs_sin_half_q30(int32_t h_bam)
{
    const uint32_t m = h_bam < 0 ? 0U - (uint32_t)h_bam : (uint32_t)h_bam;
    if (m >= ((uint32_t)1U << 26)) {
        const int32_t s = odo_sin_q30(m);
        return s < 0 ? -s : s; /* m = 2^31 (INT32_MIN) gives sin(pi) = 0 */
    }
    /* x = m 2 pi / 2^32 rad in Q32 is m * 2 pi: m * round(pi 2^30) / 2^29, below 2^29 */
    const uint32_t x = (uint32_t)(((uint64_t)m * 3373259426U + ((uint64_t)1U << 28)) >> 29);
    const uint32_t x2 = odo_mulhi_round_u32(x, x);
    const uint32_t x3 = odo_mulhi_u32(x, x2);
    const uint32_t sx = x - odo_mulhi_u32(x3, 715827883U)                  /* 2^32 / 6 */
                        + odo_mulhi_u32(odo_mulhi_u32(x3, x2), 35791394U); /* 2^32 / 120 */
    return (int32_t)((sx + 2U) >> 2);
}

void odo_ipec_translate(odo_pose_t *p, int32_t dtheta_bam, int64_t dist_mm_q40, uint32_t wheelbase_nm,
                        int64_t *dx_mm_q32, int64_t *dy_mm_q32)
{
    int64_t dx = 0, dy = 0;
    if (dist_mm_q40 != 0 && dtheta_bam != 0) {
        const int32_t half = dtheta_bam / 2;
        const int32_t sh = abs_sin_half_q30(half);
        /* Chord of the rotation about the non-lagging wheel: b |sin(dtheta/2)| (002 Eq. 14);
         * b <= 3.75 m is below 2^44 mm Q32, so every product below stays far inside int64. */
        int64_t chord = odo_mul_s64_s32_rnd(nm_to_mm_q32((int64_t)wheelbase_nm), sh, 30U);
        if (dist_mm_q40 > 0) {
            chord = -chord; /* against the direction of travel */
        }
        int32_t s, c;
        odo_sincos_q30(heading_bam(p) + (uint32_t)half, &s, &c);
        dx = odo_mul_s64_s32_rnd(chord, c, 30U);
        dy = odo_mul_s64_s32_rnd(chord, s, 30U);
        p->x_mm_q32 += dx;
        p->y_mm_q32 += dy;
    }
    if (dx_mm_q32 != NULL) {
        *dx_mm_q32 = dx;
    }
    if (dy_mm_q32 != NULL) {
        *dy_mm_q32 = dy;
    }
}

static int32_t clamp_s32(int32_t v, int32_t lim) { return v > lim ? lim : (v < -lim ? -lim : v); }

int32_t odo_ipec_gain(uint8_t ipec_mode, int32_t innov_bam, uint8_t rotary_bits)
{
    if (ipec_mode == (uint8_t)ODO_IPEC_PAPER) {
        return innov_bam;
    }
    if (ipec_mode != (uint8_t)ODO_IPEC_ESTIMATOR) {
        return 0;
    }
    const int32_t h = (int32_t)half_step_bam(rotary_bits);
    const int32_t inside = clamp_s32(innov_bam, h);
    /* inside / 2^shift rounded half away from zero, as odo_shr_round_s64 does, in 32 bits
     * (|inside| <= 2^30): the same value without the call and the 64-bit arithmetic. */
    const uint32_t mag = inside < 0 ? 0U - (uint32_t)inside : (uint32_t)inside;
    const int32_t pull = (int32_t)((mag + ((uint32_t)1U << (ODO_IPEC_EST_PULL_SHIFT - 1U))) >> ODO_IPEC_EST_PULL_SHIFT);
    return (innov_bam - inside) + (inside < 0 ? -pull : pull);
}

static uint64_t turns_q64(int32_t bam) { return (uint64_t)((int64_t)bam * 4294967296LL); }

/// Set: the correction divided by the joint's sensitivity, d L / den for den in [L/4, L + hitch]
/// (both below 2^33 nm): L / den as a Q30 factor from 32-bit divisions only (no 64-bit division
/// per tick), then one product. den >= L/4 keeps the factor at most 4, and |d| < 2^31, so the
/// result is clamped to int32 explicitly rather than converted with implementation-defined
/// narrowing. Relative error of the factor: 2^-30 from its rounding plus 2^-31 from bringing
/// L and den below 2^32.
static int32_t divide_sensitivity(int32_t d_bam, int64_t len_nm, int64_t den_nm)
{
    uint64_t l = (uint64_t)len_nm, q = (uint64_t)den_nm;
    while ((q >> 32) != 0U) { /* at most twice: both are below 2^34 */
        l = (l + 1U) >> 1;
        q = (q + 1U) >> 1;
    }
    const uint32_t l32 = (uint32_t)l, q32 = (uint32_t)q;
    const uint32_t whole = l32 / q32; /* 0..4 */
    const uint32_t frac = odo_frac_q32(l32 - whole * q32, q32);
    /* factor in Q30: whole 2^30 + frac / 4 (rounded), at most 4 2^30 + 2^30 */
    const int64_t factor_q30 = ((int64_t)whole << 30) + (int64_t)((frac + 2U) >> 2);
    const int64_t r = odo_floor_shr_s64((int64_t)d_bam * factor_q30 + ((int64_t)1 << 29), 30U);
    return r > INT32_MAX ? INT32_MAX : (r < INT32_MIN ? INT32_MIN : (int32_t)r);
}

void odo_ipec_step(const odo_params_t *p, const odo_ipec_reading_t *rd, odo_pose_t pose[2], int64_t dist_mm_q40,
                   odo_ipec_result_t *out)
{
    const bool set = p->vehicle == (uint8_t)ODO_VEHICLE_SET;
    odo_pose_t front = pose[0];
    if (set) {
        hitch(&pose[0], p->link.hitch_offset_nm, &front);
    }
    /* Eq. 10 (B to A), Eq. 11 (expected), Eq. 12 (innovation), all modulo a turn. */
    const uint32_t theta_l = odo_ipec_link_heading_bam(&front, &pose[1]);
    const uint32_t alpha_exp = heading_bam(&pose[0]) - theta_l;
    const uint32_t beta_exp = heading_bam(&pose[1]) - theta_l;
    out->theta_l_bam = theta_l;
    out->innov_bam[0] = odo_as_s32((uint32_t)rd->alpha_bam - alpha_exp);
    out->innov_bam[1] = odo_as_s32((uint32_t)rd->beta_bam - beta_exp);
    out->dtheta_bam[0] = odo_ipec_gain(p->ipec_mode, out->innov_bam[0], p->link.rotary_bits);
    out->dtheta_bam[1] = 0;
    if (set) {
        /* The hitch sits behind the robot's centre, so turning the robot by d also swings the bar
         * by d hitch cos(alpha) / L the other way: alpha moves by d (1 + hitch cos(alpha) / L).
         * Divide that sensitivity out (|alpha| < 90 deg keeps it above 1). */
        const int64_t len_nm = (int64_t)p->link.length_nm;
        int64_t den =
            len_nm + odo_mul_s64_s32_rnd((int64_t)p->link.hitch_offset_nm, odo_cos_q30((uint32_t)rd->alpha_bam), 30U);
        den = den < len_nm / 4 ? len_nm / 4 : den;
        out->dtheta_bam[0] = divide_sensitivity(out->dtheta_bam[0], len_nm, den);
    } else {
        out->dtheta_bam[1] = odo_ipec_gain(p->ipec_mode, out->innov_bam[1], p->link.rotary_bits);
    }

    /* Eqs. 14-15 for A, on the part of the correction that quantisation cannot explain. */
    const int32_t h = (int32_t)half_step_bam(p->link.rotary_bits);
    const int32_t fast = out->dtheta_bam[0] - clamp_s32(out->dtheta_bam[0], h);
    const uint64_t b_nm = ((uint64_t)p->truck[0].wheelbase_nm * (uint64_t)(uint32_t)p->truck[0].eb_q30) >> 30;
    odo_ipec_translate(&pose[0], fast, dist_mm_q40, (uint32_t)b_nm, &out->shift_mm_q32[0], &out->shift_mm_q32[1]);

    /* Eq. 13. */
    pose[0].heading_q64 += turns_q64(out->dtheta_bam[0]);

    if (set) {
        /* The trailer axle cannot slide sideways: it keeps its place, the bar pivots about it to
         * the corrected hitch, the trailer's heading is the bar's (beta = 0) and the axle sits the
         * fixed trailer length behind the hitch (Eq. 16 along the new bar). */
        hitch(&pose[0], p->link.hitch_offset_nm, &front);
        const uint32_t bar = odo_ipec_link_heading_bam(&front, &pose[1]);
        out->dtheta_bam[1] = odo_as_s32(bar - heading_bam(&pose[1]));
        pose[1].heading_q64 += turns_q64(out->dtheta_bam[1]);
        anchor(&front, bar, rd->length_mm_q32, &pose[1]);
    } else {
        /* Eq. 13 for B, then Eq. 16: B re-anchored l behind A along theta_L. */
        pose[1].heading_q64 += turns_q64(out->dtheta_bam[1]);
        anchor(&pose[0], theta_l, rd->length_mm_q32, &pose[1]);
    }
}
