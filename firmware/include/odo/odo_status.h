/// Fault flags. One bit per cause; the status frame carries the bits raised in the last tick,
/// and odo_fault_counters_t counts every occurrence (counters only ever increase, saturating).
#ifndef ODO_STATUS_H
#define ODO_STATUS_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

// A table whose multi-line trailing comments clang-format 14 would turn into backslash
// continuations (tests/python/test_can_dbc.py reads it): kept as written.
// clang-format off
#define ODO_FAULT_PARAMS_DEFAULTED  (1UL << 0)  ///< parameter block rejected at boot; defaults in use
#define ODO_FAULT_COUNTER_JUMP_A    (1UL << 1)  ///< a wheel count delta above the physical limit for
                                                ///< the ticks elapsed, or a gap too long for the
                                                ///< counter width to tell (truck A): not integrated
#define ODO_FAULT_COUNTER_JUMP_B    (1UL << 2)
#define ODO_FAULT_WHEEL_MISSING_A   (1UL << 3)  ///< no wheel-counter sample this tick (truck A)
#define ODO_FAULT_WHEEL_MISSING_B   (1UL << 4)
#define ODO_FAULT_SEQ_GAP           (1UL << 5)  ///< a sensor sequence number skipped (frames lost)
#define ODO_FAULT_SEQ_DUP           (1UL << 6)  ///< a sensor sequence number repeated (duplicate frame)
#define ODO_FAULT_DECODER_A         (1UL << 7)  ///< the decoder reported skipped states or a fault (truck A)
#define ODO_FAULT_DECODER_B         (1UL << 8)
#define ODO_FAULT_LINK_MISSING      (1UL << 9)  ///< linkage frame(s) missing this tick
#define ODO_FAULT_LINK_STALE        (1UL << 10) ///< linkage data older than the allowed age
#define ODO_FAULT_LINK_RANGE        (1UL << 11) ///< linkage reading out of its physical range
#define ODO_FAULT_LINK_JUMP         (1UL << 12) ///< linkage reading jumped more than physically possible
#define ODO_FAULT_IPEC_GATED        (1UL << 13) ///< IPEC correction skipped this tick (dead reckoning only)
#define ODO_FAULT_CAN_BAD_DLC       (1UL << 14) ///< a known frame arrived with the wrong length
#define ODO_FAULT_CAN_UNKNOWN_ID    (1UL << 15) ///< a frame with an identifier we do not consume
#define ODO_FAULT_BUS_ERROR         (1UL << 16) ///< error frame / bus-off reported by the HAL
#define ODO_FAULT_TIME_BACKWARDS    (1UL << 17) ///< an input timestamp older than the previous one
#define ODO_FAULT_POSE_RANGE        (1UL << 18) ///< a truck's x or y beyond +-2^29 mm (536.87 km,
                                                ///< ODO_POSE_LIMIT_MM_Q32): its pose is held
#define ODO_FAULT_POSE_XY_SATURATED (1UL << 19) ///< a truck's x or y beyond POSE_XY's +-21.47 km:
                                                ///< the frame carries the saturated value
// clang-format on

#define ODO_FAULT_COUNT 20U

/// Occurrence counters, one per fault bit, saturating at UINT32_MAX.
typedef struct {
    uint32_t count[ODO_FAULT_COUNT];
} odo_fault_counters_t;

#ifdef __cplusplus
}
#endif
#endif
