/// replay: the 40 ms loop of odo-replay, fed with received CAN frames (offline from a candump log,
/// live from a CAN_RAW socket). Frames are assembled into the odo_tick_input_t of their tick and
/// the firmware's pure step (odo_app_step) runs once per tick; the same code serves both modes, so
/// their outputs are identical for the same frames.
///
/// Tick clock. The first frame fixes the origin t0; frame time t belongs to tick
/// k = round((t - t0) / tick_us), i.e. tick k collects the frames stamped within half a period of
/// t0 + k * tick_us (the simulator stamps a tick's sensor frames with the tick's time, live frames
/// carry kernel jitter). Tick k's input time is t0 + k * tick_us. A frame of a later tick closes
/// every earlier tick (ticks without frames step with nothing present: the firmware flags the
/// missing sensors); the end of the log closes the last one; live mode also closes the open tick
/// at its deadline (replay_deadline_us) so outputs do not wait for the next frame.
///
/// Re-anchoring. Two things move the anchor (t0, tick 0) to (t, the tick the frame opens), so that
/// tick k's input time is t + (k - that tick) * tick_us from then on:
///   - a frame stamped more than REPLAY_CLOCK_STEP_TICKS periods before the previous frame: the
///     sender's clock stepped back. Its frames open new ticks instead of being folded into the
///     open one (a 2 s step would otherwise fold 50 ticks into one): the tick its sequence number
///     says (its sensor's previous sample's tick plus the step, 1..127, so a frame lost at the
///     step shifts nothing), or else the tick after the open one;
///   - a frame more than REPLAY_MAX_GAP_TICKS periods after the open tick: a long gap in the log.
///     It is reported (stats.gaps, stats.gap_us) and skipped: the frame opens the next tick, the
///     empty ticks in between are never stepped (a 10^5 s gap would be 2.5 M of them).
/// Either way no tick index is lost or repeated; the firmware sees its input time step back
/// (ODO_FAULT_TIME_BACKWARDS) or forward, and judges the wheel counters over that time
/// (odo_app_step: a gap too long for the counter width is flagged, not integrated).
///
/// Frames, in the order the firmware's receive path would see them:
///   error frame (ODO_CAN_FLAG_ERR)         -> ODO_FAULT_BUS_ERROR in the tick (bus-off counted apart)
///   not a consumed sensor frame (unknown ID, RTR, extended, our own output IDs)
///                                           -> ignored and counted (stats.ignored): a controller's
///                                              acceptance filter drops these, so does the kernel
///                                              filter in live mode
///   sensor frame with the wrong DLC         -> ODO_FAULT_CAN_BAD_DLC, dropped
///   timestamp up to REPLAY_CLOCK_STEP_TICKS periods before the previous frame's (reordered)
///                                           -> ODO_FAULT_TIME_BACKWARDS, the frame joins the open tick
///   timestamp further back (clock step)     -> ODO_FAULT_TIME_BACKWARDS, re-anchored (above),
///                                              stats.clock_steps
///   more than REPLAY_MAX_GAP_TICKS after the open tick -> re-anchored, stats.gaps
///   frame of an already closed tick (live)  -> joins the open tick (stats.late)
///   second frame of a sensor in one tick    -> newer sequence number (1..127 ahead) replaces the
///                                              sample (the firmware then sees the skip); otherwise
///                                              it is a duplicate/stale copy: ODO_FAULT_SEQ_DUP, dropped
#ifndef ODO_REPLAY_H
#define ODO_REPLAY_H

#include <stdbool.h>
#include <stdint.h>

#include "odo/odo_app.h"

#ifdef __cplusplus
extern "C" {
#endif

/// Width of the counters in WHEEL_COUNTS frames (odo_can.h).
#define REPLAY_WIRE_COUNTER_BITS 24U

/// A frame stamped more than this many tick periods before the previous one means the clock
/// stepped back (re-anchor); up to it, the frame was merely reordered (joins the open tick).
#define REPLAY_CLOCK_STEP_TICKS 2U

/// More empty ticks than this between the open tick and a frame is a gap in the log: skipped
/// (re-anchor) rather than stepped through. 128 ticks (5.12 s at 40 ms), the span the 8-bit
/// sequence numbers can count.
#define REPLAY_MAX_GAP_TICKS 128U

/// Counters only increase.
typedef struct {
    uint64_t frames;         ///< frames pushed
    uint64_t sensor_frames;  ///< accepted into a tick input
    uint64_t ticks;          ///< steps run
    uint64_t ignored;        ///< not consumed (unknown ID, RTR, extended, output frames)
    uint64_t bad_dlc;        ///< consumed ID with the wrong length
    uint64_t error_frames;   ///< error frames
    uint64_t bus_off;        ///< error frames of the bus-off class
    uint64_t time_backwards; ///< frames stamped before the previous frame
    uint64_t late;           ///< frames of a tick already closed (live jitter)
    uint64_t dup_dropped;    ///< duplicate/stale sensor frames dropped within a tick
    uint64_t clock_steps;    ///< backward clock steps re-anchored (also in time_backwards)
    uint64_t gaps;           ///< gaps longer than REPLAY_MAX_GAP_TICKS skipped
    uint64_t gap_us;         ///< time skipped over those gaps (saturating)
    uint64_t longest_gap_us; ///< the longest of them
    uint64_t last_gap_us;    ///< the latest of them
} replay_stats_t;

struct replay;

/// Called after every step with the tick's index (0 = the origin tick), its input and output
/// (in->t_us: the tick's time on the log's clock, see re-anchoring).
typedef void (*replay_tick_fn)(void *user, struct replay *r, uint64_t tick, const odo_tick_input_t *in,
                               const odo_tick_output_t *out);

typedef struct replay {
    odo_app_t app;
    uint32_t tick_us;
    bool have_origin;
    uint64_t origin_us; ///< t0: the first frame's time (tick 0)
    uint64_t anchor_us; ///< time of tick anchor_tick (t0 and 0 until re-anchored)
    uint64_t anchor_tick;
    uint64_t cur; ///< index of the open tick
    bool pending; ///< the open tick has received a frame
    bool have_last;
    uint64_t last_t_us;   ///< timestamp of the previous frame
    bool seq_known[4];    ///< per sensor (WHEEL_COUNTS_A, _B, LINK_ROTARY, _LINEAR):
    uint8_t seq_last[4];  ///< the last sample taken, and the tick it went to
    uint64_t seq_tick[4]; ///< (re-anchoring after a clock step goes by them)
    odo_tick_input_t in;  ///< the open tick's input being assembled
    odo_tick_output_t out;
    replay_stats_t stats;
    replay_tick_fn fn;
    void *user;
} replay_t;

/// Boot the firmware app like the target and the simulator do, from the encoded parameter block
/// of `p` (odo_params_encode + odo_app_init), and reset the tick clock. Returns the parameter
/// status (anything but ODO_PARAMS_OK: the app runs on defaults and flags it).
odo_params_status_t replay_init(replay_t *r, const odo_params_t *p, replay_tick_fn fn, void *user);

/// Feed one received frame stamped t_us (any value). Steps every tick this frame closes first:
/// at most REPLAY_MAX_GAP_TICKS + 1 steps. O(1) plus the steps run.
void replay_push(replay_t *r, const odo_can_frame_t *f, uint64_t t_us);

/// Live mode: the time at which the open tick must be closed (its last frame may be stamped up to
/// half a period after the tick time; `margin_us` allows for delivery). False iff no tick is open
/// with a frame in it.
bool replay_deadline_us(const replay_t *r, uint64_t margin_us, uint64_t *deadline_us);

/// Step the open tick now (if it has any frame) and open the next one. Live mode calls it at the
/// deadline; replay_finish at the end of input.
void replay_close_tick(replay_t *r);

/// End of input: close the open tick if it holds any frame.
void replay_finish(replay_t *r);

#ifdef __cplusplus
}
#endif
#endif
