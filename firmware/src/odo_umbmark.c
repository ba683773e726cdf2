/// UMBmark statistics and calibration, 000_12e7709aa9cd375a.txt Eqs. 3.1-3.6 and 6.19-6.34
/// ("000" below). See odo/odo_umbmark.h for units, sign conventions and how the loose spots of the
/// text are resolved.
#include "odo/odo_umbmark.h"

#include "odo/odo_fx.h"

#define Q30_ONE          ((int64_t)1 << 30)
/* 2^64 / (2 pi): BAM per radian in Q32 (the constant odo_odometry.c uses; checked there). */
#define BAM_PER_RAD_Q32  2935890503282001226ULL
/* Parameter block ratio range, as odo_params.c checks it (0.8 truncated to Q30, 1.25 exact). */
#define RATIO_MIN_Q30    ((int64_t)(((int64_t)4 << 30) / 5))
#define RATIO_MAX_Q30    ((int64_t)(((int64_t)5 << 30) / 4))
/* A Type A or B angle beyond 45 deg is not a small systematic error: refuse it. */
#define ANGLE_LIMIT_BAM  ((int64_t)1 << 29)
#define WHEELBASE_MIN_NM 50000000U
#define WHEELBASE_MAX_NM 3000000000U

static uint64_t abs_s64(int64_t v) { return v < 0 ? (uint64_t)0 - (uint64_t)v : (uint64_t)v; }

/// round(sqrt(v)) for any uint64: bitwise, 32 iterations.
static uint64_t isqrt_round_u64(uint64_t v)
{
    uint64_t rem = v;
    uint64_t root = 0U;
    uint64_t bit = (uint64_t)1U << 62;
    while (bit > rem) {
        bit >>= 2;
    }
    while (bit != 0U) {
        if (rem >= root + bit) {
            rem -= root + bit;
            root = (root >> 1) + bit;
        } else {
            root >>= 1;
        }
        bit >>= 2;
    }
    /* floor root; round up iff v - root^2 > root (i.e. v >= (root + 1/2)^2 rounded). */
    return rem > root ? root + 1U : root;
}

/// Rounded signed division (half away from zero); den != 0, |num| and |den| below 2^62.
static int64_t div_round_s64(int64_t num, int64_t den)
{
    if (den < 0) {
        num = -num;
        den = -den;
    }
    const int64_t half = den / 2;
    return num >= 0 ? (num + half) / den : -((-num + half) / den);
}

odo_umb_status_t odo_umb_stats(const odo_umb_return_t *cw, size_t n_cw, const odo_umb_return_t *ccw, size_t n_ccw,
                               odo_umb_stats_t *out)
{
    if (cw == NULL || ccw == NULL || out == NULL) {
        return ODO_UMB_ERR_ARG;
    }
    if (n_cw < 2U || n_ccw < 2U || n_cw > ODO_UMB_MAX_RUNS || n_ccw > ODO_UMB_MAX_RUNS) {
        return ODO_UMB_ERR_FEW_RUNS;
    }
    const odo_umb_return_t *const runs[2] = {cw, ccw};
    const size_t n[2] = {n_cw, n_ccw};
    odo_umb_stats_t s;
    memset(&s, 0, sizeof s);
    uint64_t abs_theta_sum = 0U;
    for (unsigned d = 0U; d < 2U; ++d) {
        int64_t sx = 0;
        int64_t sy = 0;
        int64_t st = 0;
        for (size_t i = 0U; i < n[d]; ++i) {
            const odo_umb_return_t *r = &runs[d][i];
            if (r->ex_um < -ODO_UMB_MAX_ERR_UM || r->ex_um > ODO_UMB_MAX_ERR_UM || r->ey_um < -ODO_UMB_MAX_ERR_UM ||
                r->ey_um > ODO_UMB_MAX_ERR_UM || r->etheta_udeg < -ODO_UMB_MAX_THETA_UDEG ||
                r->etheta_udeg > ODO_UMB_MAX_THETA_UDEG) {
                return ODO_UMB_ERR_INPUT;
            }
            sx += r->ex_um;
            sy += r->ey_um;
            st += r->etheta_udeg;
            abs_theta_sum += abs_s64(r->etheta_udeg);
        }
        s.n[d] = (uint16_t)n[d];
        /* 000 Eq. 3.2 */
        s.cg_x_um[d] = (int32_t)div_round_s64(sx, (int64_t)n[d]);
        s.cg_y_um[d] = (int32_t)div_round_s64(sy, (int64_t)n[d]);
        /* 000 Eq. 3.6 */
        s.theta_bias_udeg[d] = (int32_t)div_round_s64(st, (int64_t)n[d]);
        /* 000 Eq. 3.3: |cg| <= 2^25.5 um, squares fit easily. */
        const uint64_t r2 =
            (uint64_t)((int64_t)s.cg_x_um[d] * s.cg_x_um[d]) + (uint64_t)((int64_t)s.cg_y_um[d] * s.cg_y_um[d]);
        s.r_cg_um[d] = (uint32_t)isqrt_round_u64(r2);
    }
    /* 000 Eq. 3.4 */
    s.emax_syst_um = s.r_cg_um[0] > s.r_cg_um[1] ? s.r_cg_um[0] : s.r_cg_um[1];

    /* Pooled spread about each cluster's own (rounded) cg. Deviations are < 2^26 um, so each
     * square is < 2^52 and the sum over <= 512 runs, two components each, stays below 2^62.
     * Using the rounded cg adds at most n * 0.5 um^2, far below the micrometre of the result. */
    uint64_t ss = 0U;
    for (unsigned d = 0U; d < 2U; ++d) {
        for (size_t i = 0U; i < n[d]; ++i) {
            const int64_t dx = (int64_t)runs[d][i].ex_um - s.cg_x_um[d];
            const int64_t dy = (int64_t)runs[d][i].ey_um - s.cg_y_um[d];
            ss += (uint64_t)(dx * dx) + (uint64_t)(dy * dy);
        }
    }
    const uint64_t n_all = (uint64_t)n_cw + (uint64_t)n_ccw;
    const uint64_t var = (ss + (n_all - 2U) / 2U) / (n_all - 2U);
    s.sigma_um = (uint32_t)isqrt_round_u64(var);
    /* SEM^2 = sigma^2 / (n_all / 2) = 2 var / n_all. */
    s.sem_um = (uint32_t)isqrt_round_u64((2U * var + n_all / 2U) / n_all);
    s.avg_abs_theta_udeg = (uint32_t)((abs_theta_sum + n_all / 2U) / n_all);
    /* 000 s. 6.3: below 3 SEM a second compensation is unlikely to help. */
    s.second_pass_advised = (uint64_t)s.emax_syst_um > 3U * (uint64_t)s.sem_um;
    *out = s;
    return ODO_UMB_OK;
}

/// An angle in radians given as delta_um / (-4 L_um) (000 Eqs. 6.22, 6.26), as a BAM. |delta| is
/// below 2^27 um and 4 L below 2^29 um, so the 128-bit mul-div cannot fail; the result is
/// saturated to +-ANGLE_LIMIT_BAM (*over set).
static int32_t angle_over_minus_4l(int64_t delta_um, uint32_t side_um, bool *over)
{
    uint64_t q = 0U;
    (void)odo_muldiv_u64(abs_s64(delta_um), BAM_PER_RAD_Q32, ((uint64_t)side_um * 4U) << 32, &q);
    if (q > (uint64_t)ANGLE_LIMIT_BAM) {
        *over = true;
        q = (uint64_t)ANGLE_LIMIT_BAM;
    }
    return delta_um > 0 ? -(int32_t)q : (int32_t)q;
}

static uint32_t abs_diff_s32(int32_t a, int32_t b) { return (uint32_t)abs_s64((int64_t)a - b); }

/// (a + b) / 2 rounded half away from zero, without overflow.
static int32_t mean_s32(int32_t a, int32_t b) { return (int32_t)div_round_s64((int64_t)a + b, 2); }

static bool ratio_ok(int64_t q30) { return q30 >= RATIO_MIN_Q30 && q30 <= RATIO_MAX_Q30; }

/// a * b / 2^30 rounded, for two positive Q30 ratios in range.
static int64_t mul_q30(int64_t a, int64_t b)
{
    uint64_t q = 0U;
    (void)odo_muldiv_u64((uint64_t)a, (uint64_t)b, (uint64_t)Q30_ONE, &q);
    return (int64_t)q;
}

bool odo_umb_correction_factors(int32_t ed_q30, int32_t *cl_q30, int32_t *cr_q30)
{
    if (ed_q30 <= 0 || cl_q30 == NULL || cr_q30 == NULL) {
        return false;
    }
    const uint64_t den = (uint64_t)ed_q30 + (uint64_t)Q30_ONE;
    uint64_t cl = 0U;
    uint64_t cr = 0U;
    /* 000 Eq. 6.33: cL = 2 / (Ed + 1); Eq. 6.34: cR = 2 / (1/Ed + 1) = 2 Ed / (Ed + 1). Both < 2. */
    (void)odo_muldiv_u64((uint64_t)Q30_ONE * 2U, (uint64_t)Q30_ONE, den, &cl);
    (void)odo_muldiv_u64((uint64_t)ed_q30 * 2U, (uint64_t)Q30_ONE, den, &cr);
    *cl_q30 = (int32_t)cl;
    *cr_q30 = (int32_t)cr;
    return true;
}

odo_umb_status_t odo_umb_calibrate(const odo_umb_stats_t *s, uint32_t side_um, uint32_t wheelbase_nm, int32_t ed_q30,
                                   int32_t eb_q30, odo_umb_calib_t *out)
{
    if (s == NULL || out == NULL) {
        return ODO_UMB_ERR_ARG;
    }
    if (side_um < ODO_UMB_MIN_SIDE_UM || side_um > ODO_UMB_MAX_SIDE_UM) {
        return ODO_UMB_ERR_SIDE;
    }
    if (wheelbase_nm < WHEELBASE_MIN_NM || wheelbase_nm > WHEELBASE_MAX_NM || !ratio_ok(ed_q30) || !ratio_ok(eb_q30)) {
        return ODO_UMB_ERR_GEOMETRY;
    }
    odo_umb_calib_t c;
    memset(&c, 0, sizeof c);
    const int64_t xcw = s->cg_x_um[ODO_UMB_CW];
    const int64_t xccw = s->cg_x_um[ODO_UMB_CCW];
    const int64_t ycw = s->cg_y_um[ODO_UMB_CW];
    const int64_t yccw = s->cg_y_um[ODO_UMB_CCW];
    bool over = false;
    /* 000 Eqs. 6.21-6.22: beta from x and from y; Eqs. 6.25-6.26: alpha likewise. */
    c.beta_x_bam = angle_over_minus_4l(xcw - xccw, side_um, &over);
    c.beta_y_bam = angle_over_minus_4l(ycw + yccw, side_um, &over);
    c.alpha_x_bam = angle_over_minus_4l(xcw + xccw, side_um, &over);
    c.alpha_y_bam = angle_over_minus_4l(ycw - yccw, side_um, &over);
    c.alpha_bam = mean_s32(c.alpha_x_bam, c.alpha_y_bam);
    c.beta_bam = mean_s32(c.beta_x_bam, c.beta_y_bam);
    c.alpha_disagree_bam = abs_diff_s32(c.alpha_x_bam, c.alpha_y_bam);
    c.beta_disagree_bam = abs_diff_s32(c.beta_x_bam, c.beta_y_bam);

    /* 000 Eq. 6.23: R = (L/2) / sin(beta/2). */
    const int32_t sin_half_q30 = odo_sin_q30((uint32_t)(c.beta_bam / 2));
    if (sin_half_q30 != 0) {
        c.radius_um = div_round_s64((int64_t)side_um * (Q30_ONE / 2), sin_half_q30);
    }
    if (over) {
        *out = c;
        return ODO_UMB_ERR_RESULT;
    }

    /* 000 Eq. 6.29: Eb = 90 deg / (90 deg - alpha); 90 deg is 2^30 BAM, so Eb_q30 = 2^60 / (2^30 -
     * alpha). |alpha| <= 45 deg keeps the divisor in [2^29, 3 * 2^29]. */
    uint64_t eb_meas = 0U;
    (void)odo_muldiv_u64((uint64_t)Q30_ONE, (uint64_t)Q30_ONE, (uint64_t)(Q30_ONE - c.alpha_bam), &eb_meas);
    const int64_t eb_new = mul_q30(eb_q30, (int64_t)eb_meas);
    /* 000 Eq. 6.28: b_actual = b_nominal * Eb (the block keeps b_nominal and carries Eb). */
    uint64_t b_actual_nm = 0U;
    (void)odo_muldiv_u64(wheelbase_nm, (uint64_t)eb_new, (uint64_t)Q30_ONE, &b_actual_nm);

    /* 000 Eqs. 6.23-6.24 with R substituted: Ed = (L + b sin(beta/2)) / (L - b sin(beta/2)), b the
     * wheelbase the robot actually has (in um). L 2^30 < 2^57 and b sin < 2^52: no overflow, and
     * with b <= 3.75 m, L >= 100 mm and |beta| <= 45 deg the denominator stays positive unless
     * the geometry is absurd (checked). */
    const int64_t b_um = (int64_t)((b_actual_nm + 500U) / 1000U);
    const int64_t l_q30 = (int64_t)side_um * Q30_ONE;
    const int64_t bs = b_um * sin_half_q30;
    const int64_t num = l_q30 + bs;
    const int64_t den = l_q30 - bs;
    uint64_t ed_meas = 0U;
    if (num <= 0 || den <= 0 || !odo_muldiv_u64((uint64_t)num, (uint64_t)Q30_ONE, (uint64_t)den, &ed_meas) ||
        ed_meas > (uint64_t)INT32_MAX || eb_meas > (uint64_t)INT32_MAX) {
        *out = c;
        return ODO_UMB_ERR_RESULT;
    }
    c.ed_meas_q30 = (int32_t)ed_meas;
    c.eb_meas_q30 = (int32_t)eb_meas;
    const int64_t ed_new = mul_q30(ed_q30, (int64_t)ed_meas);
    if (!ratio_ok(ed_new) || !ratio_ok(eb_new)) {
        *out = c;
        return ODO_UMB_ERR_RESULT;
    }
    c.ed_q30 = (int32_t)ed_new;
    c.eb_q30 = (int32_t)eb_new;
    c.b_actual_nm = (uint32_t)b_actual_nm;
    (void)odo_umb_correction_factors(c.ed_q30, &c.cl_q30, &c.cr_q30);
    *out = c;
    return ODO_UMB_OK;
}

odo_umb_status_t odo_umb_nonsys_theta(const odo_umb_return_t *cw, size_t n_cw, const odo_umb_return_t *ccw,
                                      size_t n_ccw, const int32_t theta_bias_udeg[2], uint32_t *out_udeg)
{
    if (cw == NULL || ccw == NULL || theta_bias_udeg == NULL || out_udeg == NULL) {
        return ODO_UMB_ERR_ARG;
    }
    if (n_cw + n_ccw == 0U || n_cw > ODO_UMB_MAX_RUNS || n_ccw > ODO_UMB_MAX_RUNS) {
        return ODO_UMB_ERR_FEW_RUNS;
    }
    const odo_umb_return_t *const runs[2] = {cw, ccw};
    const size_t n[2] = {n_cw, n_ccw};
    uint64_t sum = 0U;
    for (unsigned d = 0U; d < 2U; ++d) {
        if (theta_bias_udeg[d] < -ODO_UMB_MAX_THETA_UDEG || theta_bias_udeg[d] > ODO_UMB_MAX_THETA_UDEG) {
            return ODO_UMB_ERR_INPUT;
        }
        for (size_t i = 0U; i < n[d]; ++i) {
            const int32_t e = runs[d][i].etheta_udeg;
            if (e < -ODO_UMB_MAX_THETA_UDEG || e > ODO_UMB_MAX_THETA_UDEG) {
                return ODO_UMB_ERR_INPUT;
            }
            /* 000 Eq. 3.5: |etheta_i - bias_dir|, wrapped into [-180, 180] deg. */
            int64_t dv = (int64_t)e - theta_bias_udeg[d];
            if (dv > ODO_UMB_MAX_THETA_UDEG) {
                dv -= 2 * (int64_t)ODO_UMB_MAX_THETA_UDEG;
            } else if (dv < -ODO_UMB_MAX_THETA_UDEG) {
                dv += 2 * (int64_t)ODO_UMB_MAX_THETA_UDEG;
            }
            sum += abs_s64(dv);
        }
    }
    const uint64_t n_all = (uint64_t)n_cw + (uint64_t)n_ccw;
    *out_udeg = (uint32_t)((sum + n_all / 2U) / n_all);
    return ODO_UMB_OK;
}

const char *odo_umb_status_str(odo_umb_status_t s)
{
    switch (s) {
    case ODO_UMB_OK: return "ok";
    case ODO_UMB_ERR_ARG: return "NULL argument";
    case ODO_UMB_ERR_FEW_RUNS: return "each direction needs at least 2 runs (at most 256)";
    case ODO_UMB_ERR_INPUT: return "a return error is out of range (|e| <= 33.5 m, |etheta| <= 180 deg)";
    case ODO_UMB_ERR_SIDE: return "side length must be in [100 mm, 100 m]";
    case ODO_UMB_ERR_GEOMETRY: return "wheelbase or current calibration outside the parameter block's range";
    case ODO_UMB_ERR_RESULT: return "the correction would leave the parameter block's range [0.8, 1.25]";
    }
    return "unknown status";
}
