/// Internal Position Error Correction (IPEC): every tick, two trucks joined by a compliant linkage
/// (clapper) or a robot towing an encoder trailer (set) compare the linkage angles they expect from
/// dead reckoning with the angles the linkage encoders measure, and correct their headings within
/// that tick (002_97a419d21cabf785.txt section 4, Eqs. 9-16; 004_997ef9ec5c850202.txt sections 3-5).
///
/// Scope: pure functions over a caller-allocated state; integer only, no allocation, no loops that
/// depend on data. One odo_ipec_step costs one atan2, a handful of sin/cos and 64-bit multiplies.
/// Not reentrant per instance; instances are independent.
///
/// Conventions that resolve the papers' looseness (002 papers README):
///   - Eq. 10 is read with atan2 *from B to A*: theta_L = atan2(y_A - y_B, x_A - x_B). With that
///     reading Eq. 16 (x_B = x_A - l cos theta_L) places B at distance l behind A, as it must.
///     The simulator's truth uses the same convention (host_sim/src/world.h).
///   - Eqs. 14-15 are written for a bump under the right wheel. Generalised: the wheel whose encoder
///     over-reported is the one that lagged (002 s. 4.2), so the corrective rotation is about the
///     *other* wheel's contact point. For forward travel a negative (clockwise) correction means the
///     right wheel lagged, a positive one the left; for backward travel the reverse. In every case
///     the centre moves by b |sin(dtheta/2)| *against the direction of travel*, along
///     theta + dtheta/2 (the exact chord of the rotation; Eq. 15 uses theta, the same to first
///     order). No translational correction while the truck turns on the spot (U = 0).
///   - An n-bit absolute rotary encoder's code k covers [k, k+1) steps (as the simulated encoder
///     board and the CAN contract: code << (16 - n)); the firmware takes the centre of that
///     interval, then subtracts the calibrated zero offset (alpha/beta_bias_bam).
///   - The `set` (one joint encoder, fixed trailer length) is the same computation with the hitch
///     point H = A - hitch_offset (cos theta_A, sin theta_A) in place of A's centre for the link,
///     the trailer bar as the link (its length fixed, link.length_nm) and alpha = the joint angle.
///     Two differences: turning the robot by d swings the bar too (the hitch is behind the centre),
///     so the joint angle moves by d (1 + hitch cos(alpha) / L) and the correction divides that
///     sensitivity out; and the trailer axle cannot slide sideways, so it keeps its place, the bar
///     pivots about it to the corrected hitch, the trailer heading becomes the bar's (beta = 0)
///     and Eq. 16 only restores the bar length.
///
/// Two forms of the heading correction (odo_ipec_mode_t):
///   - PAPER: Eqs. 12-13 as printed: theta' = theta + (alpha_act - alpha_exp), i.e. each truck's
///     heading becomes theta_L + alpha_act. Its error is bounded by the rotary resolution
///     (10 bit: 0.35 deg, +-0.18 deg about the code centre).
///   - ESTIMATOR: the growth-rate argument (004 s. 3.3) applied to quantisation. A fast-growing
///     error (a bump) pushes the expected angle out of the measured code's interval: the part
///     outside is corrected in the same tick (immediate response). Inside the interval dead
///     reckoning is more precise than the encoder over a few ticks, so the residual is only pulled
///     toward the code centre slowly (gain 2^-ODO_IPEC_EST_PULL_SHIFT per tick); every code edge
///     the motion crosses then pins the angle to the edge, which gets below the resolution.
#ifndef ODO_IPEC_H
#define ODO_IPEC_H

#include <stdbool.h>
#include <stdint.h>

#include "odo/odo_params.h"
#include "odo/odo_types.h"

#ifdef __cplusplus
extern "C" {
#endif

/// ESTIMATOR: per-tick gain of the pull toward the code centre, as a right shift (6: 1/64).
#ifndef ODO_IPEC_EST_PULL_SHIFT
#define ODO_IPEC_EST_PULL_SHIFT 6U
#endif

/// Link readings that passed the checks of odo_ipec_check, in the units IPEC uses.
typedef struct {
    int32_t alpha_bam;     ///< alpha_act: truck A (set: robot) relative to the link, code centre - bias
    int32_t beta_bam;      ///< beta_act: truck B relative to the link (set: 0)
    int64_t length_mm_q32; ///< l: measured minus bias (clapper) or the fixed trailer length (set)
} odo_ipec_reading_t;

/// Per-instance state: the last accepted link reading (jump and sequence checks) and its age.
typedef struct {
    bool have_last; ///< a reading has been accepted since init
    uint8_t last_rot_seq;
    uint8_t last_lin_seq;
    uint16_t last_alpha_bam16;
    uint16_t last_beta_bam16;
    uint32_t last_length_um;
    uint32_t age_ticks; ///< ticks since the last accepted reading (saturating)
} odo_ipec_t;

/// What one correction did.
typedef struct {
    int32_t dtheta_bam[2];   ///< heading correction applied to A and B this tick (002 Eq. 12)
    int32_t innov_bam[2];    ///< alpha_act - alpha_exp, beta_act - beta_exp before any filtering
    uint32_t theta_l_bam;    ///< link orientation from B to A (Eq. 10), before re-anchoring
    int64_t shift_mm_q32[2]; ///< translational correction of A (Eq. 15 generalised), x and y
} odo_ipec_result_t;

/// Reset the link bookkeeping (the next reading is accepted without a jump check).
void odo_ipec_init(odo_ipec_t *s);

/// Check this tick's linkage sample for a vehicle (ODO_VEHICLE_CLAPPER: rotary alpha+beta and the
/// linear encoder; ODO_VEHICLE_SET: rotary alpha only) and decode it into *rd. Returns the
/// ODO_FAULT_* bits found; 0 means *rd is valid and IPEC may use it. Never asserts on the input.
///   ODO_FAULT_LINK_MISSING  a needed frame did not arrive, or its valid bit is clear
///   ODO_FAULT_SEQ_DUP       the same sample again (sequence number repeated)
///   ODO_FAULT_LINK_STALE    an older sample than one already used (sequence went backwards:
///                           out of order), or the last accepted reading is more than
///                           lp->stale_ticks ticks (or samples, by sequence) old, so this one
///                           cannot be checked for a jump: it is taken as the new reference but
///                           not used this tick
///   ODO_FAULT_LINK_RANGE    l outside [length_min_um, length_max_um] (clapper)
///   ODO_FAULT_LINK_JUMP     alpha or beta changed by more than max_jump_bam, or l by more than
///                           max_length_jump_um, per tick since the reference (not accepted as
///                           the reference either, so a single glitch does not poison the next)
/// Call once per tick whether or not IPEC is on (the ages count ticks). Constant time.
uint32_t odo_ipec_check(odo_ipec_t *s, const odo_params_t *p, const odo_link_input_t *in, odo_ipec_reading_t *rd);

/// Eq. 10 with the B-to-A convention: direction of (x_A - x_B, y_A - y_B) as a BAM.
uint32_t odo_ipec_link_heading_bam(const odo_pose_t *a, const odo_pose_t *b);

/// Set: the hitch point H, hitch_offset_nm behind A's centre along A's heading.
void odo_ipec_hitch(const odo_pose_t *a, uint32_t hitch_offset_nm, odo_pose_t *h);

/// Eqs. 14-15 generalised (see the banner): move *p by b |sin(dtheta/2)| against the direction of
/// travel (sign of dist_mm_q40) along heading + dtheta/2, where heading is p's heading *before*
/// the correction. dist 0 or dtheta 0: no change. Writes the shift to dx/dy (may be NULL).
/// wheelbase_nm is the effective wheelbase b. Constant time.
void odo_ipec_translate(odo_pose_t *p, int32_t dtheta_bam, int64_t dist_mm_q40, uint32_t wheelbase_nm,
                        int64_t *dx_mm_q32, int64_t *dy_mm_q32);

/// Eq. 16: place *b (position only) at distance l from *a against theta_L.
void odo_ipec_anchor(const odo_pose_t *a, uint32_t theta_l_bam, int64_t length_mm_q32, odo_pose_t *b);

/// The heading correction of one truck from its innovation e = angle_act - angle_exp (BAM):
/// PAPER returns e; ESTIMATOR returns the part of e outside +-half a rotary step plus
/// 2^-ODO_IPEC_EST_PULL_SHIFT of the part inside (see the banner); OFF returns 0.
int32_t odo_ipec_gain(uint8_t ipec_mode, int32_t innov_bam, uint8_t rotary_bits);

/// One IPEC correction (002 Eqs. 10-16) on poses already advanced by this tick's dead reckoning
/// (Eq. 9, odo_truck_step): pose[0] = A, pose[1] = B (set: the trailer axle). dist_mm_q40 is A's
/// centre displacement this tick (for the translational correction's direction). Corrects both
/// headings, A's position (Eq. 15, only the part of the correction beyond half a rotary step, so
/// quantisation dither does not walk the position), and re-anchors B (Eq. 16). Constant time.
void odo_ipec_step(const odo_params_t *p, const odo_ipec_reading_t *rd, odo_pose_t pose[2], int64_t dist_mm_q40,
                   odo_ipec_result_t *out);

/// nm -> mm Q32 (exact to 2e-10 relative; saturates beyond +-2.1e15 nm, where mm Q32 leaves int64).
int64_t odo_ipec_nm_to_mm_q32(int64_t nm);

#ifdef __cplusplus
}
#endif
#endif
