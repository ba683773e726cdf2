/// Plain data types shared by the firmware core, the HAL and the host tools.
///
/// Units are in the names: _bam (binary angle, 2^32 per turn, uint32 wraps for free), _bam16
/// (2^16 per turn), _q64 (turns as a fraction of 2^64), _q32/_q40 (fixed point with that many
/// fraction bits), _um, _nm, _us, _counts. No function here; no allocation anywhere.
#ifndef ODO_TYPES_H
#define ODO_TYPES_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/// Trucks: A is the front (or only) truck; B is the rear truck of a clapper, or the encoder trailer
/// of a `set` vehicle.
#define ODO_TRUCK_A 0U
#define ODO_TRUCK_B 1U
#define ODO_TRUCKS  2U

/// Wheels of a truck.
#define ODO_LEFT  0U
#define ODO_RIGHT 1U

/// One classic CAN frame (11-bit or 29-bit identifier, 0..8 data bytes).
typedef struct {
    uint32_t id;     ///< identifier without flag bits: <= 0x7FF standard, <= 0x1FFFFFFF extended
    uint8_t dlc;     ///< 0..8
    uint8_t flags;   ///< ODO_CAN_FLAG_*
    uint8_t data[8]; ///< bytes beyond dlc are zero
} odo_can_frame_t;

#define ODO_CAN_FLAG_EXT 0x01U ///< 29-bit identifier
#define ODO_CAN_FLAG_RTR 0x02U ///< remote request: no data
#define ODO_CAN_FLAG_ERR 0x04U ///< error frame reported by the controller/kernel

/// One sample of a truck's two wheel-encoder counters, as the decoder (or the sensor frame) gives it.
typedef struct {
    bool present;      ///< a sample for this tick arrived; false: nothing arrived
    uint8_t bits;      ///< valid low bits in left/right_raw, 8 to 32 (a CAN frame: 24);
                       ///< above 32 counts as 32, 0 makes the sample unusable (flagged)
    uint8_t seq;       ///< sender's sample sequence number, +1 per tick (wraps at 256): a skip
                       ///< says how many ticks the counters moved over
    uint8_t status;    ///< sender's status bits, ODO_WHEEL_STATUS_*
    uint32_t left_raw; ///< raw counter value, only the low `bits` bits are meaningful
    uint32_t right_raw;
} odo_wheel_input_t;

#define ODO_WHEEL_STATUS_LEFT_SKIPPED  0x01U ///< decoder saw an illegal quadrature transition
#define ODO_WHEEL_STATUS_RIGHT_SKIPPED 0x02U
#define ODO_WHEEL_STATUS_LEFT_FAULT    0x04U ///< decoder/reader fault on that channel
#define ODO_WHEEL_STATUS_RIGHT_FAULT   0x08U

/// One sample of the linkage encoders (clapper: two rotary + one linear; set: one rotary).
typedef struct {
    bool rotary_present; ///< a rotary frame arrived this tick
    uint8_t rotary_seq;
    uint8_t rotary_status; ///< ODO_LINK_STATUS_*
    uint16_t alpha_bam16;  ///< truck A relative to the link (clapper) or joint angle (set)
    uint16_t beta_bam16;   ///< truck B relative to the link (clapper only)
    bool linear_present;   ///< a linear-encoder frame arrived this tick
    uint8_t linear_seq;
    uint8_t linear_status;
    uint32_t length_um; ///< measured centre-to-centre link length
} odo_link_input_t;

#define ODO_LINK_STATUS_ALPHA_VALID  0x01U
#define ODO_LINK_STATUS_BETA_VALID   0x02U
#define ODO_LINK_STATUS_LENGTH_VALID 0x04U

/// Everything the 40 ms application step consumes. Filled by a HAL backend (direct counter reads)
/// or assembled from received sensor frames; the two give identical inputs for the same data.
typedef struct {
    uint64_t t_us;      ///< monotonic time of the sample
    uint32_t rx_faults; ///< ODO_FAULT_* bits seen while assembling this input
                        ///< (bad DLC, unknown ID, bus error); 0 for direct reads
    odo_wheel_input_t wheel[ODO_TRUCKS];
    odo_link_input_t link;
} odo_tick_input_t;

/// A pose in the odometry frame: start at the origin heading +x; ccw positive.
typedef struct {
    int64_t x_mm_q32; ///< mm, 32 fraction bits (resolution 2.3e-10 mm); the odometry integrates
                      ///< within +-536.87 km (ODO_POSE_LIMIT_MM_Q32, odo_odometry.h)
    int64_t y_mm_q32;
    uint64_t heading_q64; ///< turns as a fraction of 2^64; the top 32 bits are the BAM heading
} odo_pose_t;

#ifdef __cplusplus
}
#endif
#endif
