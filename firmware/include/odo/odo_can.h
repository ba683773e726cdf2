/// CAN codec: the firmware's implementation of can/odometry.dbc, the single source of truth for
/// every frame. tests/python/test_can_dbc.py checks this codec against cantools' reading of the DBC
/// (names, identifiers, lengths, layouts and thousands of raw values both ways), so a change to
/// either side that is not made to the other fails CI.
///
/// Scope: classic CAN, 11-bit identifiers, every signal little-endian (Intel). One struct per
/// message whose fields hold the raw signal values (the integers on the wire, before DBC scaling),
/// with the unit in the field name. One pack and one unpack function per message.
///
/// Frame table (DLC 8 unless stated; every message is cyclic, 40 ms):
///
///   id     name            sender  signals (start|length, s = signed)
///   0x110  WHEEL_COUNTS_A  SENSOR  LeftCount 0|24, RightCount 24|24, Seq 48|8, Status 56|8
///   0x111  WHEEL_COUNTS_B  SENSOR  same as WHEEL_COUNTS_A, truck B
///   0x120  LINK_ROTARY     SENSOR  DLC 6: Alpha 0|16, Beta 16|16, Seq 32|8, Status 40|8
///   0x121  LINK_LINEAR     SENSOR  DLC 6: Length 0|32, Seq 32|8, Status 40|8
///   0x180  POSE_XY_A       ODO     X 0|32 s, Y 32|32 s
///   0x181  POSE_THETA_A    ODO     DLC 6: Theta 0|32, Seq 32|8, Flags 40|8
///   0x182  POSE_XY_B       ODO     same as POSE_XY_A, truck B
///   0x183  POSE_THETA_B    ODO     same as POSE_THETA_A, truck B
///   0x190  IPEC_CORR       ODO     DThetaA 0|32 s, DThetaB 32|32 s
///   0x1A0  STATUS          ODO     Faults 0|32, Seq 32|8, ParamState 40|8, Rejected 48|16
///
/// Acceptance rules of every unpacker, checked in this order:
///   1. flags: RTR, error and extended-identifier frames are not our data frames -> ODO_CAN_ERR_FLAGS;
///   2. identifier: not the message (or, for per-truck messages, either truck's) -> ODO_CAN_ERR_ID;
///   3. length: DLC differs from the DBC's (shorter or longer) -> ODO_CAN_ERR_DLC.
/// On any error the outputs are left untouched. Payload bytes beyond the DLC are never read.
/// Packers write every byte of the frame: id, dlc, flags = 0, the payload, and zeros beyond the DLC.
///
/// Cost and reentrancy: every function is pure (no state, no globals written), reentrant and
/// constant time: one 64-bit assemble/split of the payload and a shift and mask per signal.
/// odo_can_classify compares against at most ODO_CAN_MSG_COUNT identifiers.
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

/// Identifiers (11-bit, standard frames).
#define ODO_CAN_ID_WHEEL_COUNTS_A 0x110U
#define ODO_CAN_ID_WHEEL_COUNTS_B 0x111U
#define ODO_CAN_ID_LINK_ROTARY    0x120U
#define ODO_CAN_ID_LINK_LINEAR    0x121U
#define ODO_CAN_ID_POSE_XY_A      0x180U
#define ODO_CAN_ID_POSE_THETA_A   0x181U
#define ODO_CAN_ID_POSE_XY_B      0x182U
#define ODO_CAN_ID_POSE_THETA_B   0x183U
#define ODO_CAN_ID_IPEC_CORR      0x190U
#define ODO_CAN_ID_STATUS         0x1A0U

/// Data length codes, from the DBC.
#define ODO_CAN_DLC_WHEEL_COUNTS 8U
#define ODO_CAN_DLC_LINK_ROTARY  6U
#define ODO_CAN_DLC_LINK_LINEAR  6U
#define ODO_CAN_DLC_POSE_XY      8U
#define ODO_CAN_DLC_POSE_THETA   6U
#define ODO_CAN_DLC_IPEC_CORR    8U
#define ODO_CAN_DLC_STATUS       8U

/// Period of every message, from the DBC's GenMsgCycleTime.
#define ODO_CAN_CYCLE_TIME_US 40000UL

/// Largest raw value of a 24-bit wheel counter signal.
#define ODO_CAN_COUNT_MASK 0x00FFFFFFUL

/// Which message a frame is. ODO_CAN_MSG_UNKNOWN is 0; the known messages are 1..ODO_CAN_MSG_COUNT
/// in identifier order, so the value can index a table of ODO_CAN_MSG_COUNT + 1 entries.
typedef enum {
    ODO_CAN_MSG_UNKNOWN = 0,
    ODO_CAN_MSG_WHEEL_COUNTS_A,
    ODO_CAN_MSG_WHEEL_COUNTS_B,
    ODO_CAN_MSG_LINK_ROTARY,
    ODO_CAN_MSG_LINK_LINEAR,
    ODO_CAN_MSG_POSE_XY_A,
    ODO_CAN_MSG_POSE_THETA_A,
    ODO_CAN_MSG_POSE_XY_B,
    ODO_CAN_MSG_POSE_THETA_B,
    ODO_CAN_MSG_IPEC_CORR,
    ODO_CAN_MSG_STATUS
} odo_can_msg_t;

/// Number of known messages (ODO_CAN_MSG_UNKNOWN excluded).
#define ODO_CAN_MSG_COUNT 10U

/// Result of an unpacker. Map to faults as: ERR_FLAGS with ODO_CAN_FLAG_ERR -> ODO_FAULT_BUS_ERROR,
/// ERR_ID -> ODO_FAULT_CAN_UNKNOWN_ID, ERR_DLC -> ODO_FAULT_CAN_BAD_DLC.
typedef enum {
    ODO_CAN_OK = 0,   ///< decoded; outputs written
    ODO_CAN_ERR_ID,   ///< identifier is not this message's
    ODO_CAN_ERR_DLC,  ///< right identifier, wrong length: a sender on another protocol version
    ODO_CAN_ERR_FLAGS ///< RTR, error or extended-identifier frame: not one of our data frames
} odo_can_result_t;

/// Layout of one signal as the codec uses it; mirrors the DBC's SG_ line. All signals are
/// little-endian integers with start_bit + bit_len <= 8 * dlc of their message.
typedef struct {
    const char *name;  ///< DBC signal name, e.g. "LeftCount"
    uint8_t start_bit; ///< DBC start bit: position of the least significant bit, 0..63
    uint8_t bit_len;   ///< 1..32
    bool is_signed;    ///< two's complement
} odo_can_signal_info_t;

/// Layout of one message; the table behind every pack/unpack function.
typedef struct {
    const char *name;  ///< DBC message name, e.g. "POSE_XY_A"
    uint32_t id;       ///< 11-bit identifier
    uint8_t dlc;       ///< exact data length
    uint8_t n_signals; ///< entries in signals[], in DBC order
    const odo_can_signal_info_t *signals;
} odo_can_msg_info_t;

/// WHEEL_COUNTS_A / WHEEL_COUNTS_B: one sample of a truck's two wheel decoders.
typedef struct {
    uint32_t left_count;  ///< LeftCount: decoder position, counts; low 24 bits on the wire
    uint32_t right_count; ///< RightCount: decoder position, counts; low 24 bits on the wire
    uint8_t seq;          ///< Seq: sample sequence number, wraps at 256
    uint8_t status;       ///< Status: ODO_WHEEL_STATUS_* bits
} odo_msg_wheel_counts_t;

/// LINK_ROTARY: one sample of the linkage rotary encoders.
typedef struct {
    uint16_t alpha_bam16; ///< Alpha: 2^16 per turn; an n-bit encoder code shifted left by 16 - n
    uint16_t beta_bam16;  ///< Beta: 2^16 per turn (clapper only)
    uint8_t seq;          ///< Seq: sample sequence number, wraps at 256
    uint8_t status;       ///< Status: ODO_LINK_STATUS_ALPHA_VALID | ODO_LINK_STATUS_BETA_VALID
} odo_msg_link_rotary_t;

/// LINK_LINEAR: one sample of the linkage linear encoder.
typedef struct {
    uint32_t length_um; ///< Length: centre-to-centre link length, micrometres
    uint8_t seq;        ///< Seq: sample sequence number, wraps at 256
    uint8_t status;     ///< Status: ODO_LINK_STATUS_LENGTH_VALID
} odo_msg_link_linear_t;

/// POSE_XY_A / POSE_XY_B: position of a truck in the odometry frame.
typedef struct {
    int32_t x_10um; ///< X: 10 micrometres per LSB (+-21.47 km)
    int32_t y_10um; ///< Y: 10 micrometres per LSB
} odo_msg_pose_xy_t;

/// POSE_THETA_A / POSE_THETA_B: heading of a truck.
typedef struct {
    uint32_t theta_bam; ///< Theta: binary angle, 2^32 per turn, ccw from +x
    uint8_t seq;        ///< Seq: output sequence number of the tick, wraps at 256
    uint8_t flags;      ///< Flags: pose qualifier bits, defined by the application (odo_app.h)
} odo_msg_pose_theta_t;

/// IPEC_CORR: heading corrections applied this tick (002 Eqs. 9-16).
typedef struct {
    int32_t dtheta_a_bam; ///< DThetaA: signed binary angle, 2^32 per turn, ccw positive
    int32_t dtheta_b_bam; ///< DThetaB: signed binary angle, 2^32 per turn, ccw positive
} odo_msg_ipec_corr_t;

/// STATUS: firmware status of the tick.
typedef struct {
    uint32_t faults;     ///< Faults: ODO_FAULT_* bits raised this tick
    uint8_t seq;         ///< Seq: output sequence number of the tick, wraps at 256
    uint8_t param_state; ///< ParamState: odo_params_status_t of the boot-time load (0 = OK)
    uint16_t rejected;   ///< Rejected: frames rejected since boot, saturating at 65535
} odo_msg_status_t;

/// Which known message a frame is, by identifier. Returns ODO_CAN_MSG_UNKNOWN iff the frame has
/// any of the ODO_CAN_FLAG_EXT/RTR/ERR flags or an identifier not in the table; otherwise the
/// matching unpacker fails only with ODO_CAN_ERR_DLC (or succeeds). Does not look at the DLC.
/// At most ODO_CAN_MSG_COUNT comparisons.
odo_can_msg_t odo_can_classify(const odo_can_frame_t *f);

/// Exact DLC of a message: 6 or 8. Returns 0 iff m is ODO_CAN_MSG_UNKNOWN or out of range.
uint8_t odo_can_expected_dlc(odo_can_msg_t m);

/// Layout of a message (name, id, dlc, signals in DBC order), for tools and tests. Returns NULL
/// iff m is ODO_CAN_MSG_UNKNOWN or out of range. The table is const and lives for the program.
const odo_can_msg_info_t *odo_can_msg_info(odo_can_msg_t m);

/// Frames between two sequence numbers, modulo 256: (uint8_t)(seq - prev_seq). 1 is the next
/// sample, 0 a duplicate (or exactly 256 lost), n > 1 means n - 1 samples were lost.
uint8_t odo_can_seq_delta(uint8_t prev_seq, uint8_t seq);

/// WHEEL_COUNTS: truck ODO_TRUCK_A -> 0x110, ODO_TRUCK_B -> 0x111 (any other value is a caller
/// bug and is sent as truck B). Counts keep only their low 24 bits (ODO_CAN_COUNT_MASK).
void odo_can_pack_wheel_counts(uint8_t truck, const odo_msg_wheel_counts_t *m, odo_can_frame_t *f);

/// Decode 0x110 or 0x111; *truck receives ODO_TRUCK_A or ODO_TRUCK_B. Counts come back in
/// [0, ODO_CAN_COUNT_MASK]. ERR_ID for any other identifier. *truck and *m untouched on error.
odo_can_result_t odo_can_unpack_wheel_counts(const odo_can_frame_t *f, uint8_t *truck, odo_msg_wheel_counts_t *m);

/// LINK_ROTARY (0x120, DLC 6).
void odo_can_pack_link_rotary(const odo_msg_link_rotary_t *m, odo_can_frame_t *f);

/// Decode 0x120. *m untouched on error.
odo_can_result_t odo_can_unpack_link_rotary(const odo_can_frame_t *f, odo_msg_link_rotary_t *m);

/// LINK_LINEAR (0x121, DLC 6).
void odo_can_pack_link_linear(const odo_msg_link_linear_t *m, odo_can_frame_t *f);

/// Decode 0x121. *m untouched on error.
odo_can_result_t odo_can_unpack_link_linear(const odo_can_frame_t *f, odo_msg_link_linear_t *m);

/// POSE_XY: truck ODO_TRUCK_A -> 0x180, ODO_TRUCK_B -> 0x182 (any other value is sent as B).
/// Every int32 value, INT32_MIN included, is representable.
void odo_can_pack_pose_xy(uint8_t truck, const odo_msg_pose_xy_t *m, odo_can_frame_t *f);

/// Decode 0x180 or 0x182; *truck receives ODO_TRUCK_A or ODO_TRUCK_B. *truck and *m untouched on
/// error.
odo_can_result_t odo_can_unpack_pose_xy(const odo_can_frame_t *f, uint8_t *truck, odo_msg_pose_xy_t *m);

/// POSE_THETA: truck ODO_TRUCK_A -> 0x181, ODO_TRUCK_B -> 0x183 (any other value is sent as B).
void odo_can_pack_pose_theta(uint8_t truck, const odo_msg_pose_theta_t *m, odo_can_frame_t *f);

/// Decode 0x181 or 0x183; *truck receives ODO_TRUCK_A or ODO_TRUCK_B. *truck and *m untouched on
/// error.
odo_can_result_t odo_can_unpack_pose_theta(const odo_can_frame_t *f, uint8_t *truck, odo_msg_pose_theta_t *m);

/// IPEC_CORR (0x190).
void odo_can_pack_ipec_corr(const odo_msg_ipec_corr_t *m, odo_can_frame_t *f);

/// Decode 0x190. *m untouched on error.
odo_can_result_t odo_can_unpack_ipec_corr(const odo_can_frame_t *f, odo_msg_ipec_corr_t *m);

/// STATUS (0x1A0).
void odo_can_pack_status(const odo_msg_status_t *m, odo_can_frame_t *f);

/// Decode 0x1A0. *m untouched on error.
odo_can_result_t odo_can_unpack_status(const odo_can_frame_t *f, odo_msg_status_t *m);

#ifdef __cplusplus
}
#endif
#endif
