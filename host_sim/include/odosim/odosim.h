/// libodosim: the simulator as a library, for tools that re-simulate many candidate effect
/// settings in memory (the sim-to-real diagnosis) without touching the disk. Every run is the same
/// software-in-the-loop run odo-sim makes (same seeds, same bits), but its per-tick results land
/// in caller-provided arrays instead of files.
///
/// C ABI, plain types only, so Python can call it through ctypes. Thread safety: a setup may be
/// shared by concurrent odosim_run calls (it is only read); everything else is per call.
/// Errors: functions return 0 / non-NULL on success, and -1 / NULL with a message in err.
/// C programs built in this tree that need more (a per-tick callback with the firmware's own
/// tick input and output, scenarios built in memory) use odosim_sil.h beside this header.
#ifndef ODOSIM_H
#define ODOSIM_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define ODOSIM_API_VERSION 1

/// A robot (what the firmware believes) plus a scenario (the truth's effects).
typedef struct odosim_setup odosim_setup_t;

/// One row per firmware tick (40 ms).
typedef struct {
    double t_s;
    double truth[2][3];    ///< per truck: x_mm, y_mm, theta_rad (unwrapped), true
    double est[2][3];      ///< per truck: the firmware's published pose (theta in [-pi, pi))
    double link[3];        ///< true alpha_rad, beta_rad, l_mm (clapper/set; 0 for a labmate)
    uint32_t counts[2][2]; ///< raw counter values the firmware read, [truck][left, right]
    uint32_t faults;       ///< ODO_FAULT_* bits of the tick
    uint32_t bump_events;  ///< discrete bumps first touched during this tick
} odosim_tick_row_t;

typedef struct {
    double x_abs_mm, y_abs_mm, theta_abs_deg;    ///< true return pose of truck A
    double x_calc_mm, y_calc_mm, theta_calc_deg; ///< the firmware's
    double ex_mm, ey_mm, etheta_deg;             ///< 000 Eq. 3.1
    double t_end_s;
    size_t n_ticks; ///< ticks run (rows beyond capacity not stored)
} odosim_result_t;

/// ODOSIM_API_VERSION of the loaded library.
int odosim_api_version(void);

/// Read a robot description and a scenario from files (host_sim/robots, host_sim/scenarios).
odosim_setup_t *odosim_setup_load(const char *robot_path, const char *scenario_path, char *err, size_t errlen);

/// The same from JSON text.
odosim_setup_t *odosim_setup_parse(const char *robot_json, const char *scenario_json, char *err, size_t errlen);

/// Switch an effect on and set one of its parameters (NULL param: just enable); truck_mask bit 0
/// is truck A, bit 1 truck B. For sweeping candidates without files.
int odosim_setup_set(odosim_setup_t *s, const char *effect, const char *param, unsigned truck_mask, double value,
                     char *err, size_t errlen);

/// Switch every effect off again (keeps the robot).
void odosim_setup_clear(odosim_setup_t *s);

void odosim_setup_free(odosim_setup_t *s);

/// The seed odo-sim gives run `run` (0-based) of direction `ccw` for a base seed, so a library
/// run reproduces a CLI run exactly.
uint64_t odosim_run_seed(uint64_t base_seed, int ccw, unsigned run);

/// One run of an experiment ("umbmark", "umbmark-ext", "straight-36m", "rect-7x4"); bumps < 0 for
/// the experiment's default; ipec 0 off, 1 paper form, 2 estimator (else -1). Writes up to
/// `capacity` rows (rows may be NULL). Returns 0.
int odosim_run(const odosim_setup_t *s, const char *experiment, int ccw, int bumps, int ipec, uint64_t seed,
               unsigned run_index, odosim_tick_row_t *rows, size_t capacity, odosim_result_t *result, char *err,
               size_t errlen);

/// Options of odosim_run_ex. Zero-initialise, then set what you need: zero hidden fields are off,
/// physics_dt_s 0 is 1 ms, bump_height_mm 0 is 10 mm.
typedef struct {
    const char *experiment; ///< as odosim_run
    int ccw;
    int bumps;             ///< < 0: the experiment's default
    double bump_height_mm; ///< height of the experiment's bumps (0: 10 mm)
    int ipec;
    uint64_t seed;
    unsigned run_index;
    double physics_dt_s; ///< 0: 1 ms
    /* Hidden (out-of-catalog) truth, host_sim/src/world.h sim_hidden_t; not in any scenario. */
    double motor_tau_s;       ///< wheel speed lags its command (controller dynamics)
    double diam_var_amp;      ///< D(t) = D (1 + amp sin(2 pi t / T) + drift t)
    double diam_var_period_s; ///< T
    double diam_drift_per_s;  ///< drift
    double backlash_rad;      ///< gear backlash at the wheel
} odosim_run_opts_t;

/// One row per firmware tick with what the sensors put on the bus (for writing "real" logs).
typedef struct {
    double t_s;
    uint64_t t_us;         ///< sample time the firmware read (the frames' timestamp)
    double truth[2][3];    ///< per truck: x_mm, y_mm, theta_rad (unwrapped), true
    double link_true[3];   ///< true alpha_rad, beta_rad, l_mm
    uint32_t counts[2][2]; ///< raw counter values, [truck][left, right]
    uint8_t wheel_seq[2], wheel_status[2], wheel_present[2];
    uint8_t rotary_present, linear_present, rotary_status, linear_status;
    uint8_t rotary_seq, linear_seq;
    uint16_t alpha_bam16, beta_bam16; ///< linkage encoders as read (bias, quantisation applied)
    uint32_t length_um;
    uint32_t n_events; ///< bump events first touched during this tick
} odosim_tick_row_ex_t;

/// A discrete bump event (first contact).
typedef struct {
    double t_s, x_mm, y_mm, height_mm, at_distance_mm;
    uint32_t truck, wheel; ///< 0 A / 1 B; 0 left / 1 right
} odosim_event_t;

/// odosim_run with options (hidden effects, physics step) and sensor-level rows; events (may be
/// NULL) receives up to ev_capacity bump events, *n_events (may be NULL) their total. Returns 0,
/// or -1 with a message (also for bad hidden values).
int odosim_run_ex(const odosim_setup_t *s, const odosim_run_opts_t *opts, odosim_tick_row_ex_t *rows, size_t capacity,
                  odosim_event_t *events, size_t ev_capacity, size_t *n_events, odosim_result_t *result, char *err,
                  size_t errlen);

/// The effects catalog as a JSON document (malloc'd; release with odosim_free), or NULL.
char *odosim_effects_json(void);

/// sizeof of one of this header's structs, by its type name ("odosim_tick_row_ex_t",
/// "odosim_event_t", "odosim_result_t", "odosim_run_opts_t", "odosim_tick_row_t"); 0 iff the name
/// is unknown. Bindings in other languages (tools/python/odo_tools/gap/simlib.py) check their
/// layouts against it, so a field added here fails a test instead of corrupting memory.
size_t odosim_sizeof(const char *type_name);

void odosim_free(void *p);

/* ---------------------------------------------------------------------------------------------
 * The robot-description contract and the firmware's step, for tools that must not re-implement
 * either (host_sim/run/odosim_robot.c).
 * ------------------------------------------------------------------------------------------- */

/// Parse and validate a robot description with THE validator (hostlib/odo_robot.c's limits table
/// and odo_params_validate) and return what it means as compact JSON (malloc'd; odosim_free):
/// {"vehicle", "tick_ms", "heading_form", "max_wheel_speed_mm_s", "trucks": [{"wheel_diameter_mm",
/// "wheelbase_mm", "encoder_lines", "gear_ratio", "counter_bits", "invert_left", "invert_right",
/// "ed", "eb", "es"}, ...], "linkage" (clapper) / "trailer" (set)}. NULL with "<path>: <field>:
/// <why>" in err on any error.
char *odosim_robot_describe(const char *robot_path, char *err, size_t errlen);

/// The limits table as JSON [{"key", "lo", "hi", "unit"}, ...] (malloc'd; odosim_free), or NULL.
char *odosim_robot_limits_json(void);

/// Run the firmware's application step (odo_app_step, booted on the robot's block) over raw
/// counter readings of truck A, raw[2 i] left, raw[2 i + 1] right (as the decoder holds them, low
/// counter_bits bits), one per tick; pose[3 i .. 3 i + 2] receives x_mm, y_mm and the heading in
/// rad (unwrapped). Tick 0 sets the counter baseline. Returns 0, or -1 with a message.
int odosim_firmware_track(const char *robot_path, const uint32_t *raw, size_t n, double *pose, char *err,
                          size_t errlen);

/// The clapper's linkage stop (host_sim/src/world.c sim_link_clamp_track) replayed over a recorded
/// motion, for the diagnosis's model: rel[2 i], rel[2 i + 1] is truck A - truck B (mm) at tick i
/// as the wheels alone move them, gate[i] (NULL: always) whether the stop may act at tick i;
/// push[2 i], push[2 i + 1] receives A's cumulative move (B's is its negative). Returns the
/// number of ticks the stop acted, or -1 on NULL arrays or a range that is not finite and ordered.
long odosim_link_clamp(const double *rel, size_t n, double lo_mm, double hi_mm, const unsigned char *gate,
                       double *push);

/// The rate limiter of the diagnosis's traction-slip laws (host_sim/src/ratelimit.h):
/// out[i] = out[i-1] + clamp(v[i] - out[i-1], -lim[i], lim[i]) from 0. 0, or -1 on a NULL array.
int odosim_rate_limit(const double *v, const double *lim, size_t n, double *out);

/// Its plane form (a friction circle, sim_rate_limit_2d): the vector (ox, oy) follows (vx, vy)
/// by at most lim[i] per step, from (0, 0). 0, or -1 on a NULL array. (The diagnosis calls the
/// track form below since; kept, as `make bench-gap REF=<rev>` loads older packages beside
/// this library.)
int odosim_rate_limit_2d(const double *vx, const double *vy, const double *lim, size_t n, double *ox, double *oy);

/// The plane limiter on a pose track (sim_rate_limit_track; the friction circle's skid): out's
/// x, y follow pose's (n, 3) rows with a velocity that changes by at most acc dt[i] per step,
/// out's theta is pose's. 0, or -1 on a NULL or aliased array.
int odosim_rate_limit_track(const double *pose, size_t n, const double *dt, double acc, double *out);

#ifdef __cplusplus
}
#endif
#endif
