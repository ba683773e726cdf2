/// Robot description: what the firmware believes about its robot (nominal geometry, encoders,
/// linkage), read from JSON and convertible to the firmware's parameter block (odo_params_t).
/// The truth (effects) lives in the scenario, never here (DESIGN.md s. 4).
///
///   {
///     "vehicle": "labmate" | "clapper" | "set",
///     "description": "optional",
///     "tick_ms": 40,                                   optional, default 40 (002 s. 4.1)
///     "heading_form": "midpoint" | "paper",            optional, default midpoint (000 Eq. 2.6)
///     "ipec": "off" | "paper" | "estimator",           optional, default off (labmate) / paper
///     "max_wheel_speed_mm_s": 3000,                    optional
///     "trucks": {
///       "A": {"wheel_diameter_mm": 150, "wheelbase_mm": 340, "encoder_lines": 500,
///             "gear_ratio": 19.5, "counter_bits": 24, "decoder": "hctl1100",
///             "invert_left": false, "invert_right": false,
///             "calibration": {"ed": 1.0, "eb": 1.0, "es": 1.0,           optional (UMBmark result)
///                             "scrub": 0.0}},            optional, k of the tyre-scrub term, |k| <= 0.25
///       "B": {...}                                     clapper: rear truck; set: the trailer
///     },
///     "linkage": {"length_mm": 1000, "range_mm": [900, 1100], "rotary_bits": 10,
///                 "linear_resolution_mm": 0.1,
///                 "calibration": {"length_bias_mm": 0, "length_ecc_mm": 0,
///                                 "alpha_bias_deg": 0, "beta_bias_deg": 0}},   clapper only
///     "trailer": {"hitch_offset_mm": 300, "trailer_length_mm": 500, "rotary_bits": 10,
///                 "calibration": {"alpha_bias_deg": 0}}                         set only
///   }
///
/// Counts per wheel turn = 4 * encoder_lines * gear_ratio (4x quadrature decoding, 000 Eq. 2.1's
/// n * Ce). "decoder" names the count-direction convention of the HCTL emulator: "hctl1100" counts
/// up when channel B leads A, "hctl20xx" the opposite. The firmware has one counter width, so all
/// trucks must give the same counter_bits.
///
/// Every error names the file, the field and why. Host-only C99; reentrant; no globals.
#ifndef SIM_ROBOT_H
#define SIM_ROBOT_H

#include <stdbool.h>
#include <stddef.h>

#include "odo/odo_params.h"

typedef enum { SIM_VEHICLE_LABMATE = 0, SIM_VEHICLE_CLAPPER = 1, SIM_VEHICLE_SET = 2 } sim_vehicle_t;

/// Quadrature count direction (HCTL-1100: up when B leads A; HCTL-20xx family: up when A leads B).
typedef enum { SIM_DECODER_HCTL1100 = 0, SIM_DECODER_HCTL20XX = 1 } sim_decoder_t;

typedef struct {
    double wheel_diameter_mm; ///< nominal Dn
    double wheelbase_mm;      ///< nominal b
    unsigned encoder_lines;   ///< lines per motor (or wheel) revolution, Ce
    double gear_ratio;        ///< n, motor turns per wheel turn
    unsigned counter_bits;    ///< 8..32 (robot.c limits; the firmware decides what it runs)
    sim_decoder_t decoder;
    bool invert_left; ///< left counter counts down when the wheel rolls forward
    bool invert_right;
    double cal_ed, cal_eb, cal_es; ///< calibration block (1.0 when absent)
    double cal_scrub;              ///< k of the firmware's tyre-scrub term (0 when absent)
    bool has_calibration;
} sim_truck_desc_t;

typedef struct {
    sim_vehicle_t vehicle;
    unsigned n_trucks; ///< 1 (labmate) or 2
    char description[160];
    double tick_ms;
    unsigned heading_form; ///< odo_heading_form_t
    unsigned ipec_mode;    ///< odo_ipec_mode_t
    double max_wheel_speed_mm_s;
    sim_truck_desc_t truck[ODO_TRUCKS]; ///< [1] valid iff n_trucks == 2 (B: rear truck / trailer)
    /// Clapper linkage (length, range, encoders) or the set's trailer joint (rotary_bits only).
    struct {
        double length_mm;            ///< clapper nominal l (004 s. 2: 1 m)
        double min_mm, max_mm;       ///< physical range of l (mechanical stops)
        unsigned rotary_bits;        ///< absolute rotary encoders (004: 10 bit)
        double linear_resolution_mm; ///< linear encoder (004: 0.1 mm)
        double cal_length_bias_mm, cal_length_ecc_mm, cal_alpha_bias_deg, cal_beta_bias_deg;
    } link;
    struct {
        double hitch_offset_mm;   ///< robot centre to the joint, behind the robot
        double trailer_length_mm; ///< joint to the trailer axle centre
    } set;
} sim_robot_t;

/// One numeric key of the description and its inclusive range: THE limits (robot.c's table), used
/// by the parser and handed to Python through libodosim. Keys are dotted paths; "trucks.*." stands
/// for either truck.
typedef struct {
    const char *key;
    double lo, hi;
    const char *unit;
} sim_robot_limit_t;

/// The table and its length. Never fails; static storage.
const sim_robot_limit_t *sim_robot_limits(size_t *n);

/// Decoded counts per wheel turn: 4 * lines * gear.
double sim_robot_counts_per_rev(const sim_truck_desc_t *t);

/// The description of a stock vehicle (the same values as host_sim/robots/<name>.json). Returns 0,
/// or -1 for an unknown name.
int sim_robot_default(sim_vehicle_t v, sim_robot_t *r);

/// Parse a robot description file. Returns 0, or -1 with "<path>: <field>: <why>" in err.
int sim_robot_parse_file(const char *path, sim_robot_t *r, char *err, size_t errlen);

/// The same from a string; `origin` names it in messages.
int sim_robot_parse_string(const char *json, const char *origin, sim_robot_t *r, char *err, size_t errlen);

/// Convert to the firmware's parameter block (odo_params_defaults, then fill) and validate it with
/// odo_params_validate. Returns 0, or -1 with the offending field (firmware and JSON name) in err.
int sim_robot_to_params(const sim_robot_t *r, odo_params_t *p, char *err, size_t errlen);

/// "labmate" / "clapper" / "set".
const char *sim_vehicle_name(sim_vehicle_t v);

/// Parse a vehicle name. Returns false iff unknown.
bool sim_vehicle_parse(const char *name, sim_vehicle_t *out);

#endif
