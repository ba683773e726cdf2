/// Synthetic wheel-count streams: random mixed driving (straights, arcs, on-the-spot turns, stops,
/// both directions) or scripted segments, as per-tick count deltas of an ideal robot. Used by the
/// property test, odo-bench and the foundation demo. Deterministic for a given seed.
#ifndef ODO_SYNTH_H
#define ODO_SYNTH_H

#include <stdint.h>

#include "odo/odo_params.h"

typedef struct {
    uint64_t rng;
    double k_mm; ///< nominal distance per count
    double b_mm; ///< nominal wheelbase
    double tick_s;
    double acc[2];      ///< fractional counts carried to the next tick
    double rate[2];     ///< counts per tick of the current segment, [left, right]
    uint32_t remaining; ///< ticks left in the current segment
    double distance_mm; ///< centre-point path length so far (|U| summed)
} odo_synth_t;

void odo_synth_init(odo_synth_t *s, uint64_t seed, const odo_truck_params_t *tp, uint32_t tick_us);

/// Script the next `ticks` ticks with constant wheel speeds (mm/s). Random segments resume after.
void odo_synth_segment(odo_synth_t *s, double v_left_mm_s, double v_right_mm_s, uint32_t ticks);

/// Next tick's count deltas (forward positive). Picks a new random segment when one ends.
void odo_synth_next(odo_synth_t *s, int32_t *d_left, int32_t *d_right);

#endif
