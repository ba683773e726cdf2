/// HCTL-1100-style quadrature decoder emulator: the part of the HP/Avago HCTL-1100 "General Purpose
/// Motion Control IC" that the odometry reads (encoder interface, digital filter, 4x quadrature
/// decoder, 24-bit actual position counter and its byte-wise read protocol). Section names below
/// are those of the HCTL-1100 data sheet; behaviour the data sheet leaves open is resolved here and
/// marked "model".
///
/// Scope: host C (double allowed), one instance per encoder, no heap, no global state, no
/// randomness: the same calls give the same register values on every run (issue 3 item 7).
/// Not modelled: the motor-control side (position/velocity loops, PWM, commutator), the command
/// position registers' control use, the 8-bit multiplexed bus timing.
///
/// Input model. The encoder's mechanical phase is a real number of quadrature states ("counts";
/// 4 states per line). odosim_hctl_advance() moves it from the last (t, phase) to a new one at
/// constant velocity. The channel levels are a function of the state s = floor(phase) mod 4:
///
///     s      0  1  2  3
///     CHA    1  1  0  0      (A high for phase mod 4 in [0, 2))
///     CHB    1  0  0  1      (B high for phase mod 4 in [-1, 1))
///
/// so with rising phase B changes one state before A does: "B leads A". The HCTL-1100 counts up
/// when B leads A ("Quadrature Decoder"), so with the default convention rising phase counts up;
/// ODOSIM_HCTL_CONV_20XX selects the HCTL-20xx family's opposite convention.
///
/// Filter model ("Digital Filter"). CHA and CHB are sampled on rising CLK edges t_k = k / f_CLK
/// (k = 0 at t = 0 s); a level change at time tau is first seen by edge k0 = ceil(tau * f_CLK) (an
/// edge at exactly tau sees the new level). The data sheet requires an input to be stable for three
/// consecutive rising CLK edges before the decoder sees it; the model applies this to the two
/// inputs together: a new CHA/CHB state reaches the decoder at edge k0 + 2 iff it was still present
/// at that edge (three equal samples), otherwise it is rejected. So input edges closer than three
/// clock periods are lost, and above about f_CLK/3 state changes per second counts go missing
/// (the limit issue 3 states; a per-channel filter would pass twice that rate).
///
/// Decoder model ("Quadrature Decoder"). When the filtered state changes, one state forward or
/// back counts +-1 (4x decoding). A jump by two states (both channels changed at once, because the
/// state between was rejected) is a skipped (illegal) state: the counter is left alone and
/// odosim_hctl_diag_t.skipped_states is incremented (model: the chip has no such counter; the
/// emulator keeps one so that the simulator can report it as decoder status). A jump by three
/// states looks like one step the other way and counts wrongly, as on the chip.
///
/// Cost. odosim_hctl_advance() is event driven: it visits each input state change in the interval
/// and each filter settle edge. When state changes are more than ODOSIM_HCTL_FAST_PERIODS clock
/// periods apart and nothing from earlier is still in the filter, every change must pass the filter
/// and be counted, so a run of such changes is added arithmetically (fast path); a call then costs
/// O(1) however many counts it spans. The two paths give identical results
/// (test_hctl1100: fast_path_and_per_edge_path_count_identically).
///
/// Threading: an instance is used from one thread; distinct instances are independent.
#ifndef HCTL1100_H
#define HCTL1100_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/// Register addresses ("Register Description"; the actual position is 24-bit two's complement).
#define ODOSIM_HCTL_REG_CMD_POS_MSB 0x0CU ///< R0CH: command position MSB, used here as preset MSB
#define ODOSIM_HCTL_REG_CMD_POS_MID 0x0DU ///< R0DH: command position middle byte / preset middle
#define ODOSIM_HCTL_REG_CMD_POS_LSB 0x0EU ///< R0EH: command position LSB / preset LSB (loads)
#define ODOSIM_HCTL_REG_ACT_POS_MSB 0x12U ///< R12H: actual position bits 23..16
#define ODOSIM_HCTL_REG_ACT_POS_MID 0x13U ///< R13H: actual position bits 15..8; write: clear
#define ODOSIM_HCTL_REG_ACT_POS_LSB 0x14U ///< R14H: actual position bits 7..0; read: latch

/// The position counter's width and mask.
#define ODOSIM_HCTL_POS_BITS 24U
#define ODOSIM_HCTL_POS_MASK 0xFFFFFFUL

/// Valid CLK range of the emulator (the HCTL-1100 runs at 100 kHz..2 MHz; "Recommended Operating Conditions").
#define ODOSIM_HCTL_F_CLK_MIN_HZ 100000UL
#define ODOSIM_HCTL_F_CLK_MAX_HZ 2000000UL

/// The fast path is taken when successive state changes are more than this many CLK periods apart
/// (the filter needs three; one more keeps rounding of edge times far from the boundary).
#define ODOSIM_HCTL_FAST_PERIODS 4.0

/// Input limits of odosim_hctl_advance (keep edge indices and floor(phase) exact in int64/double).
#define ODOSIM_HCTL_T_MAX_S          1.0e9
#define ODOSIM_HCTL_PHASE_MAX_COUNTS 4.0e15

/// Counting convention.
typedef enum {
    ODOSIM_HCTL_CONV_1100 = 0, ///< HCTL-1100: counts up when CHB leads CHA (rising phase counts up)
    ODOSIM_HCTL_CONV_20XX = 1, ///< HCTL-20xx: counts up when CHA leads CHB (rising phase counts down)
} odosim_hctl_conv_t;

typedef struct {
    uint32_t f_clk_hz; ///< ODOSIM_HCTL_F_CLK_MIN_HZ..ODOSIM_HCTL_F_CLK_MAX_HZ
    odosim_hctl_conv_t convention;
    bool force_per_edge; ///< never take the fast path (tests, diagnosis)
} odosim_hctl_config_t;

/// Counters that only increase (they saturate at UINT32_MAX / UINT64_MAX).
typedef struct {
    uint32_t skipped_states;   ///< illegal transitions seen by the decoder (counter unchanged)
    uint32_t index_pulses;     ///< INDEX pulses (they never touch the position counter)
    uint32_t ignored_writes;   ///< preset writes outside idle mode
    uint32_t bad_registers;    ///< reads/writes of registers the emulator does not model
    uint32_t bad_inputs;       ///< advance() calls rejected (time backwards, NaN, infinity)
    uint64_t changes_fast;     ///< input state changes counted arithmetically by the fast path
    uint64_t changes_per_edge; ///< input state changes processed one by one
} odosim_hctl_diag_t;

/// One emulated decoder. A plain struct so that it can be embedded without a heap; the fields are
/// private to hctl1100.c (read them through the functions below).
typedef struct {
    odosim_hctl_config_t cfg;
    double f_clk;        ///< cfg.f_clk_hz as double
    double t_s;          ///< time of the last advance
    double phase_counts; ///< phase at t_s
    int64_t raw_state;   ///< floor(phase): the unfiltered input state
    uint8_t filt_ab;     ///< filtered levels seen by the decoder: CHA << 1 | CHB
    int64_t pend_edge;   ///< CLK edge at which the raw state passes the filter,
                         ///< or INT64_MAX when it equals the filtered state
    uint32_t position;   ///< 24-bit actual position counter (upper byte zero)
    bool latched;        ///< an R14H read latched R12H/R13H and R12H was not read yet
    uint8_t latch_msb;
    uint8_t latch_mid;
    bool idle; ///< idle mode: presets load
    uint8_t preset_msb;
    uint8_t preset_mid;
    odosim_hctl_diag_t diag;
} odosim_hctl_t;

/// Power-on reset ("Operating Modes": Reset): position 0, no latch pending, not idle, filter settled on the input
/// state of phase0_counts at time t0_s. Returns false iff cfg is NULL, f_clk_hz is out of range,
/// the convention is unknown, or t0_s/phase0_counts are not finite; *h is then zeroed and every
/// other call on it misbehaves harmlessly (returns zeros and counts bad inputs). O(1).
bool odosim_hctl_init(odosim_hctl_t *h, const odosim_hctl_config_t *cfg, double t0_s, double phase0_counts);

/// Move the encoder from the last (t, phase) to (t_end_s, phase_end_counts) at constant velocity
/// and clock every CLK edge strictly before t_end_s through the filter and the decoder (an edge at
/// exactly t_end_s is clocked by the next call). t_end_s == last t with a different phase is a
/// jump: all its state changes happen at that instant. Valid inputs: |t_end_s| <= ODOSIM_HCTL_T_MAX_S,
/// |phase_end_counts| <= ODOSIM_HCTL_PHASE_MAX_COUNTS, t_end_s not earlier than the last time.
/// Returns false iff an input is outside that (or NaN), or the instance failed init; the state is
/// then unchanged and diag.bad_inputs incremented. Cost: O(1) on the fast path; otherwise O(state changes spanned).
bool odosim_hctl_advance(odosim_hctl_t *h, double t_end_s, double phase_end_counts);

/// Host read of one register ("Actual Position Registers R12H-R14H", model):
///  - R14H returns the live LSB and latches the live MSB and middle byte;
///  - R13H returns the latched middle byte if a latch is pending, else the live one;
///  - R12H returns the latched MSB if a latch is pending (and releases the latch), else the live one.
/// So the consistent order is R14H, R13H, R12H; any other order while the counter moves can tear.
/// Other registers read 0x00 and count diag.bad_registers. O(1).
uint8_t odosim_hctl_read(odosim_hctl_t *h, uint8_t reg);

/// Host write of one register. Returns true iff the write had an effect:
///  - R13H (any value) clears the actual position counter and any pending latch, in every mode
///    ("Actual Position Registers R12H-R14H");
///  - R0CH/R0DH/R0EH in idle mode stage the preset MSB/middle/LSB; the R0EH write loads all three
///    into the actual position counter ("Idle mode / Preset", model); outside idle mode they are
///    ignored and count diag.ignored_writes;
///  - anything else is ignored and counts diag.bad_registers. O(1).
bool odosim_hctl_write(odosim_hctl_t *h, uint8_t reg, uint8_t value);

/// Enter (true) or leave (false) idle mode ("Idle mode / Preset"). Decoding goes on in every mode.
void odosim_hctl_set_idle(odosim_hctl_t *h, bool idle);

/// One pulse on the INDEX input. The HCTL-1100 uses INDEX only for commutator alignment ("Commutator";
/// INDEX in "Pin Description"); the actual position counter is not touched. Counts diag.index_pulses. O(1).
void odosim_hctl_index(odosim_hctl_t *h);

/// The actual position read the correct way: R14H, then R13H, then R12H through odosim_hctl_read.
/// Returns the 24-bit two's-complement value in the low 24 bits (upper byte zero). O(1).
uint32_t odosim_hctl_read_position(odosim_hctl_t *h);

/// The encoder's CHA/CHB levels at a phase (table above) as CHA << 1 | CHB; for tests and plots.
/// Returns 0 for a phase outside +-ODOSIM_HCTL_PHASE_MAX_COUNTS or NaN. O(1).
uint8_t odosim_hctl_input_ab(double phase_counts);

/// Sign-extend a 24-bit two's-complement position to int32 (0x800000 -> -8388608).
int32_t odosim_hctl_to_signed(uint32_t position24);

/// Illegal transitions seen so far (diag.skipped_states). O(1).
uint32_t odosim_hctl_skipped(const odosim_hctl_t *h);

/// All diagnostic counters. O(1).
const odosim_hctl_diag_t *odosim_hctl_diag(const odosim_hctl_t *h);

#ifdef __cplusplus
}
#endif
#endif
