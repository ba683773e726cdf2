/// The board's receive path: CAN frames taken from the controller are sorted into the next tick's
/// sensor samples or rejected with a fault bit and a counter. Pure: no registers, no HAL.
///
/// A frame is, in this order:
///   - an error frame (ODO_CAN_FLAG_ERR)            -> ODO_FAULT_BUS_ERROR, counted
///   - extended or remote, an identifier the DBC does not define, or one this board does not
///     consume (outputs, WHEEL_COUNTS of a truck with local counters)
///                                                   -> ODO_FAULT_CAN_UNKNOWN_ID, counted
///   - a consumed identifier whose DLC field differs from the DBC's (DLC 9..15 included)
///                                                   -> ODO_FAULT_CAN_BAD_DLC, counted
///   - otherwise unpacked (odo/odo_can.h) into the tick's sample; a later frame of the same sensor
///     in the same tick replaces it (the firmware then sees its sequence skip).
/// A rejected frame never reaches odo_app_step: its bytes are not read.
#ifndef ODO_BOARD_RX_H
#define ODO_BOARD_RX_H

#include <stdbool.h>
#include <stdint.h>

#include "odo/odo_types.h"

#ifdef __cplusplus
extern "C" {
#endif

/// Counters since boot; they only increase (saturating).
typedef struct {
    uint32_t frames;       ///< frames taken from the controller
    uint32_t accepted;     ///< unpacked into a sample
    uint32_t bad_dlc;      ///< consumed identifier, wrong DLC
    uint32_t unknown_id;   ///< not consumed here (see above)
    uint32_t error_frames; ///< error frames and bus-off observations
    uint32_t overruns;     ///< receive FIFO overflows seen (frames lost in hardware)
} odo_board_rx_counts_t;

typedef struct {
    bool can_wheels[ODO_TRUCKS];         ///< truck's counters arrive as WHEEL_COUNTS
    odo_wheel_input_t wheel[ODO_TRUCKS]; ///< present: a frame arrived this tick
    odo_link_input_t link;               ///< *_present: a frame arrived this tick
    uint32_t faults;                     ///< ODO_FAULT_* bits of this tick's frames
    odo_board_rx_counts_t count;
} odo_board_rx_t;

/// Empty receive state; can_wheels[i] says whether truck i's counters come over CAN.
void odo_board_rx_init(odo_board_rx_t *rx, bool can_wheel_a, bool can_wheel_b);

/// Sort one frame (raw_dlc: the DLC field as received, 0..15). Constant time.
void odo_board_rx_frame(odo_board_rx_t *rx, const odo_can_frame_t *f, uint8_t raw_dlc);

/// Count events reported by the controller rather than by a frame (ODO_FAULT_BUS_ERROR for
/// bus-off; a FIFO overrun only counts: the lost frames show as sequence gaps).
void odo_board_rx_bus_off(odo_board_rx_t *rx);
void odo_board_rx_overrun(odo_board_rx_t *rx);

/// Hand the tick's samples and fault bits to the step and start the next tick empty.
void odo_board_rx_take(odo_board_rx_t *rx, odo_wheel_input_t wheel[ODO_TRUCKS], odo_link_input_t *link,
                       uint32_t *faults);

#ifdef __cplusplus
}
#endif
#endif
