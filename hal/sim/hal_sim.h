/// hal_sim: the simulator's HAL backend. The firmware's wheel counters come out of HCTL-1100-style
/// decoder emulators (host_sim/src/hctl1100.h), read only through the chip's byte-wise register
/// protocol, so firmware that works here reads the real chip the same way. The linkage encoders
/// are quantised like the real absolute encoders; transmitted frames are captured for the
/// simulator to log. No threads, no I/O, no heap, no randomness: identical calls give identical
/// reads (issue 3 item 7).
///
/// Each physics step the simulator calls hal_sim_set_wheel_phase for every wheel, and before each
/// firmware tick hal_sim_set_link and hal_sim_set_time_us; after the tick it drains the captured
/// frames with hal_sim_take_tx.
///
/// Threading: a context is used from one thread.
#ifndef HAL_SIM_H
#define HAL_SIM_H

#include <stdbool.h>
#include <stdint.h>

#include "hal.h"
#include "hctl1100.h"

#define HAL_SIM_MAX_TX 64U ///< capture ring size; the simulator drains it every tick
#define HAL_SIM_MAX_RX 16U ///< frames the simulator can queue for hal_can_recv

#define HAL_SIM_ROTARY_BITS_MIN 1U
#define HAL_SIM_ROTARY_BITS_MAX 16U

typedef struct {
    uint32_t f_clk_hz;             ///< decoder CLK, ODOSIM_HCTL_F_CLK_MIN_HZ..MAX_HZ
    odosim_hctl_conv_t convention; ///< counting convention of the decoders
    bool force_per_edge;           ///< decoders never take their fast path (tests)
    uint8_t rotary_bits;           ///< absolute rotary linkage encoders, 1..16 bits/turn
    uint32_t linear_resolution_um; ///< linear linkage encoder step, >= 1 um
} hal_sim_config_t;

/// Faults of the simulator's own inputs; counters only increase (saturating).
typedef struct {
    uint32_t bad_wheel_inputs; ///< set_wheel_phase rejected (bad truck/wheel, time back, NaN)
    uint32_t bad_link_inputs;  ///< link readings out of range or NaN (reported invalid instead)
    uint32_t bad_times;        ///< set_time_us tried to go backwards (ignored)
    uint32_t tx_overflows;     ///< hal_can_send refused because the capture ring was full
    uint32_t rx_overflows;     ///< hal_sim_push_rx refused because the queue was full
} hal_sim_faults_t;

struct hal_ctx {
    hal_sim_config_t cfg;
    uint8_t trucks;                       ///< trucks with counters (1 or 2)
    bool has_link;                        ///< the vehicle has linkage encoders
    uint64_t now_us;                      ///< what hal_time_us returns
    odosim_hctl_t dec[ODO_TRUCKS][2];     ///< [truck][ODO_LEFT/ODO_RIGHT]
    uint8_t wheel_seq[ODO_TRUCKS];        ///< seq of the next wheel sample
    uint32_t skipped_seen[ODO_TRUCKS][2]; ///< decoder skipped count at the last read
    odo_link_input_t link;                ///< latest quantised linkage reading
    odo_can_frame_t tx[HAL_SIM_MAX_TX];   ///< capture ring
    uint64_t tx_t_us[HAL_SIM_MAX_TX];
    uint32_t tx_head, tx_count;
    odo_can_frame_t rx[HAL_SIM_MAX_RX]; ///< queue for hal_can_recv
    uint64_t rx_t_us[HAL_SIM_MAX_RX];
    uint32_t rx_head, rx_count;
    hal_sim_faults_t faults;
};

/// Reset to a backend with `trucks` (1 or 2) counter pairs and optional linkage encoders; every
/// decoder starts at t = 0 s, phase 0, position 0. Returns false iff ctx or cfg is NULL, trucks is
/// not 1 or 2, or a config value is out of range (then *ctx is zeroed and reads return false).
bool hal_sim_init(hal_ctx_t *ctx, uint8_t trucks, bool has_link, const hal_sim_config_t *cfg);

/// Move one wheel's encoder to `phase_counts` (quadrature states, 4 per line; the sign of motion
/// that counts up depends on cfg.convention) at time t_s, at constant velocity since the last call
/// (odosim_hctl_advance). Returns false iff truck/wheel is invalid or the emulator rejects the
/// input (time backwards, NaN); counted in faults.bad_wheel_inputs. O(1) on the fast path.
bool hal_sim_set_wheel_phase(hal_ctx_t *ctx, uint8_t truck, uint8_t wheel, double t_s, double phase_counts);

/// Present a new linkage reading for the next hal_link_read. Angles in radians (any value; taken
/// modulo one turn), quantised like an n-bit absolute encoder: code = floor(turns * 2^n), reported
/// as bam16 = code << (16 - n). length_mm is quantised down to cfg.linear_resolution_um and given
/// in um. `valid` is a set of ODO_LINK_STATUS_* bits; a NaN/infinite angle or a length outside
/// 0..UINT32_MAX um clears its bit and counts faults.bad_link_inputs. Sequence numbers advance by
/// one per call (rotary and linear). Returns false iff the backend has no linkage encoders.
bool hal_sim_set_link(hal_ctx_t *ctx, double alpha_rad, double beta_rad, double length_mm, uint8_t valid);

/// Set the clock hal_time_us returns. Going backwards is ignored (faults.bad_times).
void hal_sim_set_time_us(hal_ctx_t *ctx, uint64_t t_us);

/// Take the oldest captured transmit frame and the hal_time_us at which it was sent. Returns false
/// iff none is waiting. O(1).
bool hal_sim_take_tx(hal_ctx_t *ctx, odo_can_frame_t *frame, uint64_t *t_us);

/// Queue a frame for hal_can_recv. Returns false iff the queue is full (faults.rx_overflows).
bool hal_sim_push_rx(hal_ctx_t *ctx, const odo_can_frame_t *frame, uint64_t t_us);

/// The decoder emulator of one wheel (diagnostics, INDEX pulses, idle/preset); NULL iff truck or
/// wheel is out of range. Reading its position directly bypasses what hal_wheel_read models.
odosim_hctl_t *hal_sim_decoder(hal_ctx_t *ctx, uint8_t truck, uint8_t wheel);

/// Quantise an angle like an n-bit absolute encoder and report it as a 16-bit binary angle
/// (see hal_sim_set_link). Returns false iff bits is outside 1..16 or the angle is not finite.
bool hal_sim_quantise_angle(double angle_rad, uint8_t bits, uint16_t *out_bam16);

#endif
