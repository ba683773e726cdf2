/// CAN codec: the firmware's implementation of can/odometry.dbc, the single source of truth for
/// every frame. The identifiers, lengths, message structs and pack/unpack functions are generated
/// from the DBC (odo/odo_can_dbc.h and src/odo_can_dbc.c, by tools/python/odo_tools/cangen.py;
/// tests/python/test_can_dbc.py regenerates them and fails on any difference), and the same test
/// checks the codec against cantools' reading of the DBC with thousands of raw values both ways.
///
/// Scope: classic CAN, 11-bit identifiers, every signal little-endian (Intel). One struct per
/// message whose fields hold the raw signal values (the integers on the wire, before DBC scaling),
/// with the unit in the field name (the DBC's CField attribute). Signals that are bits of one
/// value (the fault, flag and status bits) share one field, at their bit offset in it. The A and B
/// variants of a per-truck message share one struct and take the truck as an argument.
///
/// Acceptance rules of every unpacker, checked in this order:
///   1. flags: RTR, error and extended-identifier frames are not our data frames -> ODO_CAN_ERR_FLAGS;
///   2. identifier: not the message (or, for per-truck messages, either truck's) -> ODO_CAN_ERR_ID;
///   3. length: DLC differs from the DBC's (shorter or longer) -> ODO_CAN_ERR_DLC.
/// On any error the outputs are left untouched. Payload bytes beyond the DLC are never read.
/// Packers write every byte of the frame: id, dlc, flags = 0, the payload, and zeros beyond the DLC
/// and in bits no signal covers.
///
/// Cost and reentrancy: pack and unpack are static inline functions of byte stores and loads with
/// constant shifts (a POSE_XY frame: about 15 Cortex-M4 instructions), pure, reentrant and
/// constant time. odo_can_classify is one switch on the identifier.
///
/// Pointers must not be NULL; that is the caller's invariant, not external input, and is not checked.
#ifndef ODO_CAN_H
#define ODO_CAN_H

#include <stdbool.h>
#include <stdint.h>

#include "odo/odo_types.h"

#ifdef __cplusplus
extern "C" {
#endif

/// Result of an unpacker. Map to faults as: ERR_FLAGS with ODO_CAN_FLAG_ERR -> ODO_FAULT_BUS_ERROR,
/// ERR_ID -> ODO_FAULT_CAN_UNKNOWN_ID, ERR_DLC -> ODO_FAULT_CAN_BAD_DLC.
typedef enum {
    ODO_CAN_OK = 0,   ///< decoded; outputs written
    ODO_CAN_ERR_ID,   ///< identifier is not this message's
    ODO_CAN_ERR_DLC,  ///< right identifier, wrong length: a sender on another protocol version
    ODO_CAN_ERR_FLAGS ///< RTR, error or extended-identifier frame: not one of our data frames
} odo_can_result_t;

/// The frame flags that make a frame not one of this protocol's data frames.
#define ODO_CAN_FLAGS_NOT_OURS (ODO_CAN_FLAG_EXT | ODO_CAN_FLAG_RTR | ODO_CAN_FLAG_ERR)

#ifdef __cplusplus
}
#endif

#include "odo/odo_can_dbc.h" /* generated from can/odometry.dbc */

#ifdef __cplusplus
extern "C" {
#endif

/// Largest raw value of a wheel counter signal (the DBC's LeftCount/RightCount width).
#define ODO_CAN_COUNT_MASK ((1UL << ODO_CAN_BITS_WHEEL_COUNTS_LEFT_COUNT) - 1UL)

/// Layout of one signal as the DBC's SG_ line has it. All signals are little-endian integers with
/// start_bit + bit_len <= 8 * dlc of their message.
typedef struct {
    const char *name;  ///< DBC signal name, e.g. "LeftCount"
    uint8_t start_bit; ///< DBC start bit: position of the least significant bit, 0..63
    uint8_t bit_len;   ///< 1..32
    bool is_signed;    ///< two's complement
} odo_can_signal_info_t;

/// Layout of one message, for tools and tests (the codec itself uses the generated constants).
typedef struct {
    const char *name;  ///< DBC message name, e.g. "POSE_XY_A"
    uint32_t id;       ///< 11-bit identifier
    uint8_t dlc;       ///< exact data length
    uint8_t n_signals; ///< entries in signals[], in DBC order
    const odo_can_signal_info_t *signals;
} odo_can_msg_info_t;

/// Which known message a frame is, by identifier. Returns ODO_CAN_MSG_UNKNOWN iff the frame has
/// any of the ODO_CAN_FLAG_EXT/RTR/ERR flags or an identifier not in the DBC; otherwise the
/// matching unpacker fails only with ODO_CAN_ERR_DLC (or succeeds). Does not look at the DLC.
/// One switch on the identifier.
odo_can_msg_t odo_can_classify(const odo_can_frame_t *f);

/// Exact DLC of a message: 6 or 8. Returns 0 iff m is ODO_CAN_MSG_UNKNOWN or out of range.
uint8_t odo_can_expected_dlc(odo_can_msg_t m);

/// Layout of a message (name, id, dlc, signals in DBC order), for tools and tests. Returns NULL
/// iff m is ODO_CAN_MSG_UNKNOWN or out of range. The table is const and lives for the program.
const odo_can_msg_info_t *odo_can_msg_info(odo_can_msg_t m);

/// Pack message m from its raw signal values in DBC signal order (raw[i] is signal i of
/// odo_can_msg_info(m), taken modulo 2^length) through the typed odo_can_pack_* function. For
/// tools that drive the codec by signal name (odo-canvec, the cantools cross-check). Returns
/// false (and writes nothing) iff m is not a known message.
bool odo_can_pack_signals(odo_can_msg_t m, const int64_t *raw, odo_can_frame_t *f);

/// Unpack *f as message m through the typed odo_can_unpack_* function and write its raw signal
/// values in DBC signal order (signed signals sign-extended) into raw[0..n_signals). A frame of
/// the other truck of a per-truck message is ODO_CAN_ERR_ID here. raw is untouched on error.
odo_can_result_t odo_can_unpack_signals(odo_can_msg_t m, const odo_can_frame_t *f, int64_t *raw);

/// Frames between two sequence numbers, modulo 256: (uint8_t)(seq - prev_seq). 1 is the next
/// sample, 0 a duplicate (or exactly 256 lost), n > 1 means n - 1 samples were lost.
static inline uint8_t odo_can_seq_delta(uint8_t prev_seq, uint8_t seq) { return (uint8_t)(seq - prev_seq); }

#ifdef __cplusplus
}
#endif
#endif
