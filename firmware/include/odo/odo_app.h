/// The 40 ms application step: one pure function over a tick input and the application state.
/// host_sim, odo-replay (offline and live), the vcan test and the Cortex-M image all call
/// odo_app_step; only firmware/app/odo_loop.c touches the HAL around it.
///
/// Per tick: sequence/fault bookkeeping -> per-truck odometry (odo_odometry.h) -> linkage checks
/// and, with ipec_mode on, the IPEC correction (odo_ipec.h) within the same tick -> output frames
/// (pose per truck, IPEC corrections, status) packed with the DBC codec (odo_can.h).
///
/// IPEC gating: the correction runs only when both trucks' wheel samples were integrated and the
/// linkage sample passed odo_ipec_check; otherwise that tick is dead reckoning only, the check's
/// fault bit and ODO_FAULT_IPEC_GATED are raised in STATUS, and both POSE_THETA frames carry
/// ODO_POSE_FLAG_IPEC_GATED. The linkage is checked (and its faults reported) with IPEC off too.
#ifndef ODO_APP_H
#define ODO_APP_H

#include <stddef.h>
#include <stdint.h>

#include "odo/odo_ipec.h"
#include "odo/odo_odometry.h"
#include "odo/odo_params.h"
#include "odo/odo_status.h"
#include "odo/odo_types.h"

#ifdef __cplusplus
extern "C" {
#endif

/// Most frames one step publishes: pose XY+theta for two trucks, IPEC corrections, status.
#define ODO_APP_MAX_FRAMES 6U

/// Flags byte of the POSE_THETA frames: what happened to that truck's pose this tick.
// A table whose multi-line trailing comments clang-format 14 would turn into backslash
// continuations (tests/python/test_can_dbc.py reads it): kept as written.
// clang-format off
#define ODO_POSE_FLAG_MISSING    0x01U ///< no wheel sample: pose held
#define ODO_POSE_FLAG_JUMP       0x02U ///< implausible or ambiguous counter reading: pose held,
                                       ///< baseline re-taken
#define ODO_POSE_FLAG_IPEC       0x04U ///< an IPEC heading correction was applied
#define ODO_POSE_FLAG_IPEC_GATED 0x08U ///< IPEC is on but was skipped this tick (see faults)
#define ODO_POSE_FLAG_RANGE      0x10U ///< position beyond ODO_POSE_LIMIT_MM_Q32: pose held
#define ODO_POSE_FLAG_XY_SATURATED 0x20U ///< POSE_XY carries a saturated x or y (beyond 21.47 km)
// clang-format on

/// Application state. Plain data, caller-allocated (static on the target); no pointers inside,
/// so it can be copied to checkpoint a run.
typedef struct {
    odo_params_t params;
    odo_params_status_t params_status; ///< result of the boot-time load (OK or why defaulted)
    odo_model_t model[ODO_TRUCKS];
    odo_truck_t truck[ODO_TRUCKS];
    odo_ipec_t ipec; ///< linkage bookkeeping (two-truck vehicles)
    uint8_t trucks;  ///< 1 (single) or 2 (clapper, set)
    uint8_t out_seq; ///< sequence number of the output frames
    bool seen_seq[ODO_TRUCKS];
    uint8_t last_seq[ODO_TRUCKS];
    uint64_t last_wheel_t_us[ODO_TRUCKS]; ///< t_us of the truck's last wheel sample
    bool have_time;
    uint64_t last_t_us;
    uint32_t ticks;              ///< steps run since init (wraps after 2^32)
    uint32_t tx_dropped;         ///< output frames the HAL could not queue (odo_loop)
    odo_fault_counters_t faults; ///< occurrences per fault bit, saturating
} odo_app_t;

/// What one step produced.
typedef struct {
    odo_pose_t pose[ODO_TRUCKS];
    int32_t ipec_dtheta_bam[ODO_TRUCKS]; ///< correction applied this tick (0 when off/gated)
    int32_t ipec_innov_bam[ODO_TRUCKS];  ///< measured minus expected link angle (002 Eq. 12)
                                         ///< before the estimator; 0 when off/gated
    bool ipec_applied;                   ///< the IPEC computation ran this tick
    int64_t dist_mm_q40[ODO_TRUCKS];     ///< dead-reckoning displacement U_i (0: none)
    int64_t dturn_q64[ODO_TRUCKS];       ///< dead-reckoning heading change, signed turns Q64
    uint32_t faults;                     ///< ODO_FAULT_* bits raised this tick
    uint8_t n_frames;
    odo_can_frame_t frames[ODO_APP_MAX_FRAMES]; ///< to publish, in order
} odo_tick_output_t;

/// Boot: load the parameter block (odo_params_load: defaults on any failure), precompute the
/// models, reset both trucks to the origin heading +x. Returns the load status; on anything but
/// ODO_PARAMS_OK every later step raises ODO_FAULT_PARAMS_DEFAULTED. `block` may be NULL (len 0)
/// to boot on defaults deliberately (still flagged).
odo_params_status_t odo_app_init(odo_app_t *app, const uint8_t *block, size_t len);

/// Same as odo_app_init, from already-decoded parameters (host tools). Returns ODO_PARAMS_ERR_RANGE
/// and boots on defaults if they fail validation or the model precomputation.
odo_params_status_t odo_app_init_params(odo_app_t *app, const odo_params_t *p);

/// One application step. Pure: reads *in and *app, writes *app and *out. Constant time. Every
/// input is valid; what is wrong with it is reported in out->faults (ODO_FAULT_*), never asserted.
///
/// Lost samples lose no distance: a truck's wheel sample is integrated over the ticks elapsed
/// since its previous one (odo_truck_step's `ticks`), counted by the sample's sequence number
/// (8 bits) or, once in->t_us says 128 ticks or more have passed (the sequence number wraps at
/// 256), by in->t_us (one 32-bit division, only then). A repeated sequence number counts as one
/// tick, an older one (out of order) as its distance back. Time going backwards raises
/// ODO_FAULT_TIME_BACKWARDS and the sequence number alone decides.
///
/// Range: a truck whose position is beyond ODO_POSE_LIMIT_MM_Q32 is held and flagged
/// (ODO_FAULT_POSE_RANGE, ODO_POSE_FLAG_RANGE) and IPEC is gated; a position beyond POSE_XY's
/// +-21.47 km is published saturated and flagged (ODO_FAULT_POSE_XY_SATURATED,
/// ODO_POSE_FLAG_XY_SATURATED) while the pose itself goes on.
void odo_app_step(odo_app_t *app, const odo_tick_input_t *in, odo_tick_output_t *out);

#ifdef __cplusplus
}
#endif
#endif
