/// Self-calibration from IPEC's corrective actions (see odo_selfcal.h; 004 s. 5.1).
#include "odo/odo_selfcal.h"

#include "odo/odo_fx.h"

/// pi / 2 in Q30: radians per BAM x 2^30 is pi / 2^31 x 2^30 = pi / 2.
#define PI_2_Q30 1686629713L
/// mm Q40 -> um: x 1000 / 2^40.
#define Q40_MM   40U

void odo_selfcal_init(odo_selfcal_t *s) { memset(s, 0, sizeof *s); }

static int64_t abs64(int64_t v) { return v < 0 ? -v : v; }

void odo_selfcal_add(odo_selfcal_t *s, uint8_t truck, uint32_t wheelbase_nm, uint8_t rotary_bits, int64_t dist_mm_q40,
                     int64_t dturn_q64, int32_t dtheta_bam)
{
    if (truck >= ODO_TRUCKS) {
        return;
    }
    odo_selfcal_truck_t *t = &s->truck[truck];
    const int64_t step = (int64_t)1 << (32U - (rotary_bits == 0U || rotary_bits > 16U ? 10U : rotary_bits));
    if (dtheta_bam == 0 && dist_mm_q40 == 0 && dturn_q64 == 0) {
        return; /* standing still (or no IPEC): nothing to learn */
    }
    if (abs64((int64_t)dtheta_bam) > step * (int64_t)ODO_SELFCAL_MAX_STEPS) {
        t->skipped_ticks++;
        return;
    }
    /* |U| <= ~2^47 mm Q40 per tick in practice (a few m); um = U * 1000 / 2^40 fits easily. */
    const int64_t u_um = odo_mul_s64_s32_shr(dist_mm_q40, 1000, Q40_MM);
    /* T as a BAM: the turn in Q64 turns, top 32 bits (a tick turns far less than half a turn). */
    const int64_t t_bam = (int64_t)(int32_t)(uint32_t)((uint64_t)dturn_q64 >> 32);
    /* Differential wheel travel b |T| / 2 in um: |T| 2 pi / 2^32 b_um / 2 = |T| b_um pi / 2^32. */
    const int64_t b_um = (int64_t)(wheelbase_nm / 1000U);
    const int64_t diff_um = odo_mul_s64_s32_shr(abs64(t_bam) * b_um, PI_2_Q30, 30U + 31U);
    const int64_t au = abs64(u_um);
    if (diff_um * 32 < au) {
        if (au == 0) {
            return;
        }
        t->straight_um += au;
        t->straight_corr += u_um > 0 ? dtheta_bam : -(int64_t)dtheta_bam;
        t->straight_ticks++;
    } else if (diff_um * 4 >= au && abs64(t_bam) >= step) {
        const bool pos = t_bam > 0;
        t->turn_bam += abs64(t_bam);
        t->turn_corr += pos ? dtheta_bam : -(int64_t)dtheta_bam;
        t->turn_u_um += pos ? u_um : -u_um;
        t->turn_ticks++;
    } else {
        t->skipped_ticks++;
    }
}

/// num / den in Q30 for |num / den| < 2 (den > 0), without overflow: both are scaled down
/// together until num fits 32 bits (estimate time only, not per tick).
static int64_t ratio_q30(int64_t num, int64_t den)
{
    while (abs64(num) >= ((int64_t)1 << 32)) {
        num /= 2;
        den /= 2;
    }
    if (den <= 0) {
        return 0;
    }
    return (num * ((int64_t)1 << 30)) / den;
}

static int32_t clamp_q30(int64_t v, int64_t lim) { return (int32_t)(v > lim ? lim : (v < -lim ? -lim : v)); }

/// f / (1 + x), Q30 in and out (|x| <= 1/8).
static int32_t div_one_plus(int32_t f_q30, int32_t x_q30)
{
    return (int32_t)(((int64_t)f_q30 * ((int64_t)1 << 30)) / (((int64_t)1 << 30) + x_q30));
}

bool odo_selfcal_estimate(const odo_selfcal_t *s, const odo_params_t *in, odo_params_t *out, odo_selfcal_result_t *r)
{
    odo_selfcal_result_t res;
    memset(&res, 0, sizeof res);
    odo_params_t p = *in;
    bool any = false;
    const int64_t lim = (int64_t)1 << 27; /* |k|, |c| <= 12.5 %: beyond, the data is not systematic */
    for (uint8_t i = 0U; i < ODO_TRUCKS; ++i) {
        const odo_selfcal_truck_t *t = &s->truck[i];
        odo_truck_params_t *tp = &p.truck[i];
        /* The firmware's effective wheelbase b_f = b_n Eb_f, in um. */
        const int64_t bf_um = (int64_t)((((uint64_t)tp->wheelbase_nm / 1000U) * (uint64_t)(uint32_t)tp->eb_q30) >> 30);
        int64_t a_q16 = 0; /* a = C per um of straight travel, BAM Q16 */
        if (t->straight_um >= ODO_SELFCAL_MIN_STRAIGHT_UM) {
            /* k = -b_f sum(sgn U C) / sum|U|, C in radians = BAM pi / 2^31:
             * k_q30 = -sum(C) b_um (pi / 2) / sum|U|_um. */
            /* |C| sums beyond 16 turns are not calibration data; the clamp keeps the products in range. */
            const int64_t c = t->straight_corr > ((int64_t)1 << 36)
                                  ? ((int64_t)1 << 36)
                                  : (t->straight_corr < -((int64_t)1 << 36) ? -((int64_t)1 << 36) : t->straight_corr);
            const int64_t num = odo_mul_s64_s32_shr(c * bf_um, PI_2_Q30, 30U);
            res.k_q30[i] = clamp_q30(-(num / t->straight_um), lim);
            res.corr_per_m_bam[i] = (int32_t)((c * 1000000) / t->straight_um);
            a_q16 = (c * 65536) / t->straight_um;
            tp->ed_q30 = div_one_plus(tp->ed_q30, res.k_q30[i]);
            res.have_ed[i] = true;
        }
        if (t->turn_bam >= ODO_SELFCAL_MIN_TURN_BAM) {
            /* The Ed part of the turning ticks' corrections: a sum(sgn T U). */
            const int64_t ed_part = odo_mul_s64_s32_shr(t->turn_u_um, clamp_q30(a_q16, INT32_MAX), 16U);
            const int64_t c = t->turn_corr - ed_part;
            res.c_q30[i] = clamp_q30(ratio_q30(c, t->turn_bam), lim);
            res.corr_per_turn_bam[i] = (int32_t)ratio_q30(c, t->turn_bam >> 2); /* x 2^32 / turn_bam */
            tp->eb_q30 = div_one_plus(tp->eb_q30, res.c_q30[i]);
            res.have_eb[i] = true;
        }
        any = any || res.have_ed[i] || res.have_eb[i];
    }
    if (r != NULL) {
        *r = res;
    }
    if (!any || odo_params_validate(&p, NULL, NULL) != ODO_PARAMS_OK) {
        *out = *in;
        return false;
    }
    *out = p;
    return true;
}
