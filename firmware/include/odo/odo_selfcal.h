/// Self-calibration from IPEC's corrective actions (004_997ef9ec5c850202.txt s. 5.1): on a smooth
/// floor the corrections IPEC applies are the dead-reckoning heading errors the systematic errors
/// cause, so a steady one-sided correction on straight legs reveals Ed (000 Eq. 2.7) and one
/// proportional to the turning reveals Eb (000 Eq. 2.8).
///
/// Model, per truck and per tick (U = centre displacement, T = dead-reckoned heading change,
/// C = IPEC heading correction, all signed; b_f = the firmware's effective wheelbase b_n Eb_f):
///   - Ed: driving straight, the firmware's wheel factors turn a true straight into
///     d = U (cR/cR_t - cL/cL_t) / b_f = U k / b_f with k = Ed_f / Ed_t - 1 (to first order in k,
///     the second-order term is k^2 / 2 < 1e-5 for |k| < 0.5 %), and IPEC corrects C = -d. So
///     k = -b_f (sum sgn(U) C) / (sum |U|) over straight ticks, and Ed_t = Ed_f / (1 + k).
///   - Eb: a dead-reckoned turn T_f = (dR - dL) / b_f of a true turn (dR - dL) / b_t leaves
///     C = T_f (b_f / b_t - 1), so with c = (sum sgn(T) (C - a U)) / (sum |T|) over turning ticks
///     (a U: the Ed part of the correction, a = the straight ticks' C per U), Eb_t = Eb_f / (1 + c).
///     Any error in the mean wheel scale is absorbed into Eb, as in UMBmark (000 s. 6.3).
/// Tick classes: straight when the wheels' differential travel b |T| / 2 is below |U| / 32;
/// turning when it is at least |U| / 4 (spins, and arcs of radius <= 2 b) and the tick turns by
/// at least one rotary step; otherwise (steering wiggles, wide arcs, and the quantisation limit
/// cycle: a truck that has stopped turning dithers across a code edge by half a step per tick,
/// the firmware heading is pinned to alternating code centres and every such tick would show
/// sgn(T) C = +|T|) the tick is left out. A tick whose correction exceeds
/// ODO_SELFCAL_MAX_STEPS rotary steps is a non-systematic event (a bump: 004 s. 4.2) and is left
/// out too, as are ticks without an IPEC correction (gated, off).
///
/// The corrections are quantised by the rotary encoders (paper form: the heading is pinned to the
/// code centre), so one straight leg or one corner is attributed to within about one step; many
/// legs and corners average that out (tools/ipec/README.md gives the measured tolerance).
///
/// Integer only, no allocation; odo_selfcal_add is constant time. Not reentrant per instance.
#ifndef ODO_SELFCAL_H
#define ODO_SELFCAL_H

#include <stdbool.h>
#include <stdint.h>

#include "odo/odo_params.h"
#include "odo/odo_types.h"

#ifdef __cplusplus
extern "C" {
#endif

/// Corrections larger than this many rotary steps in one tick are non-systematic (left out).
#ifndef ODO_SELFCAL_MAX_STEPS
#define ODO_SELFCAL_MAX_STEPS 2U
#endif

/// Least straight travel (um) and least turning (BAM) before Ed / Eb are estimated.
#define ODO_SELFCAL_MIN_STRAIGHT_UM 2000000LL    /* 2 m */
#define ODO_SELFCAL_MIN_TURN_BAM    1073741824LL /* 90 deg */

/// One truck's sums (see the banner).
typedef struct {
    int64_t straight_um;   ///< sum |U| over straight ticks
    int64_t straight_corr; ///< sum sgn(U) C over straight ticks (BAM)
    int64_t turn_bam;      ///< sum |T| over turning ticks (BAM)
    int64_t turn_corr;     ///< sum sgn(T) C over turning ticks (BAM)
    int64_t turn_u_um;     ///< sum sgn(T) U over turning ticks
    uint32_t straight_ticks;
    uint32_t turn_ticks;
    uint32_t skipped_ticks; ///< left out: in between, too large a correction
} odo_selfcal_truck_t;

typedef struct {
    odo_selfcal_truck_t truck[ODO_TRUCKS];
} odo_selfcal_t;

/// What an estimate found, per truck.
typedef struct {
    bool have_ed[ODO_TRUCKS];              ///< enough straight travel: ed_q30 updated
    bool have_eb[ODO_TRUCKS];              ///< enough turning: eb_q30 updated
    int32_t k_q30[ODO_TRUCKS];             ///< Ed_f / Ed_t - 1
    int32_t c_q30[ODO_TRUCKS];             ///< b_f / b_t - 1
    int32_t corr_per_m_bam[ODO_TRUCKS];    ///< straight: sum sgn(U) C per metre of travel
    int32_t corr_per_turn_bam[ODO_TRUCKS]; ///< turning: sum sgn(T) (C - a U) per full turn
} odo_selfcal_result_t;

void odo_selfcal_init(odo_selfcal_t *s);

/// One truck's tick: dist_mm_q40 = U, dturn_q64 = T (odo_tick_output_t), dtheta_bam = C.
/// wheelbase_nm: the firmware's effective wheelbase (b_n Eb_f); rotary_bits: the link encoders'.
void odo_selfcal_add(odo_selfcal_t *s, uint8_t truck, uint32_t wheelbase_nm, uint8_t rotary_bits, int64_t dist_mm_q40,
                     int64_t dturn_q64, int32_t dtheta_bam);

/// Estimate Ed and Eb of every truck that has enough data and write them into *out (a copy of
/// *in otherwise; in and out may alias). Returns true if at least one value was estimated and
/// *out passes odo_params_validate; false leaves *out = *in.
bool odo_selfcal_estimate(const odo_selfcal_t *s, const odo_params_t *in, odo_params_t *out, odo_selfcal_result_t *r);

#ifdef __cplusplus
}
#endif
#endif
