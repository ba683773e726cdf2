/// The effects catalog (DESIGN.md s. 5): every truth effect the simulator can switch on, with one
/// name, one parameter set and one doc line each. It is THE source of truth shared by the
/// simulator (scenario JSON, world) and the diagnosis tools (which fit the same parameters as
/// hypotheses): `sim_effects_write_json` prints it for them, `sim_effects_write_markdown` for docs.
///
/// A scenario (what is true about the robot and floor; host_sim only, diagnosis never reads it):
///
///   {
///     "description": "optional free text",
///     "seed": 1,                          optional unsigned integer; default 1
///     "bump_model": "exact",              optional default `model` for bumps and roughness
///     "effects": {
///       "ed":   {"value": 0.9985},         one object: applies to every truck
///       "eb":   [{"truck": "A", "value": 0.991}, {"truck": "B", "value": 1.0}],  per truck
///       "es":   {"value": 1.002, "enabled": false},   kept in the file, switched off
///       "bumps": {"height_mm": 10, "model": "paper",
///                 "at": [{"truck": "A", "wheel": "right", "distance_mm": 1200}]}
///     }
///   }
///
/// Effect objects hold the effect's parameters (missing ones take the catalog default) plus
/// "enabled" (bool, default true) and, for truck-scoped effects, "truck": "A" | "B" | "both"
/// (default "both"). `bumps` also takes "at", a list of discrete bumps (truck, wheel "left"/"right",
/// distance_mm along that wheel's true travel, optional height_mm). Anything else (an unknown
/// effect or key, a wrong type, a value outside the catalog range, a truck given twice) is an
/// error naming the file, the effect and the parameter.
///
/// Host-only C99; no globals beyond the constant catalog; no allocation except jansson's while
/// parsing. All functions are reentrant.
#ifndef SIM_EFFECTS_H
#define SIM_EFFECTS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "bump.h"
#include "odo/odo_types.h"

typedef enum {
    SIM_EFFECT_ED = 0,           ///< unequal wheel diameters, Ed = DR/DL
    SIM_EFFECT_EB,               ///< wheelbase error, Eb = b_actual/b_nominal
    SIM_EFFECT_ES,               ///< scale error, Es = L_calc/L_actual
    SIM_EFFECT_BUMPS,            ///< discrete bumps (rigid wheel over a step)
    SIM_EFFECT_ROUGHNESS,        ///< floor roughness: small random bumps every ~2 cm per wheel
    SIM_EFFECT_SLIP,             ///< longitudinal slip under acceleration
    SIM_EFFECT_SKID,             ///< lateral skid in fast turns
    SIM_EFFECT_COUNT_LOSS,       ///< decoder count loss above ~f_CLK/3 (HCTL emulator)
    SIM_EFFECT_ROTARY_BIAS,      ///< linkage rotary encoder zero offsets
    SIM_EFFECT_LINK_BIAS,        ///< link-length bias, constant plus eccentric
    SIM_EFFECT_TIRE_COMPRESSION, ///< load-dependent rolling radius
    SIM_EFFECT_SCRUB,            ///< turn-radius-dependent wheelbase (tyre scrub)
    SIM_EFFECT_COUNT
} sim_effect_id_t;

#define SIM_EFFECT_MAX_PARAMS 4

typedef enum {
    SIM_PARAM_NUMBER = 0, ///< a JSON number within [min, max]
    SIM_PARAM_ENUM = 1    ///< a JSON string, one of `choices` ("a|b"); stored as its index
} sim_param_kind_t;

typedef enum {
    SIM_SCOPE_TRUCK = 0,  ///< set per truck ("truck": "A" | "B" | "both")
    SIM_SCOPE_VEHICLE = 1 ///< one setting for the vehicle (linkage effects)
} sim_effect_scope_t;

typedef struct {
    const char *name; ///< JSON key
    const char *unit; ///< "1" for dimensionless ratios
    sim_param_kind_t kind;
    double def; ///< default (enum: index into choices)
    double min; ///< inclusive range (enum: 0 .. n_choices - 1)
    double max;
    const char *choices; ///< enum only: "paper|exact"; NULL for numbers
    const char *doc;     ///< one line
} sim_param_def_t;

/// The evidence a diagnosis can have about a robot (DESIGN.md s. 6): a continuous truth track, the
/// UMBmark return poses only, or nothing but the linkage encoders of a clapper or a set.
typedef enum {
    SIM_EVIDENCE_TRUTH = 0,
    SIM_EVIDENCE_RETURNS,
    SIM_EVIDENCE_LINKAGE,
    SIM_EVIDENCE_COUNT
} sim_evidence_mode_t;

/// How well one evidence mode sees an effect.
typedef enum {
    SIM_SEEN_NO = 0,   ///< not identifiable: never a hypothesis in that mode (`why` says why)
    SIM_SEEN_WEAK = 1, ///< fitted as a hypothesis, but too faint to be named reliably (not scored)
    SIM_SEEN_YES = 2   ///< a hypothesis the mode identifies
} sim_seen_t;

typedef struct {
    sim_seen_t seen;
    const char *why; ///< one line for SIM_SEEN_NO / SIM_SEEN_WEAK; NULL for SIM_SEEN_YES
} sim_evidence_t;

/// Vehicles an effect exists on (bit mask of sim_vehicle_t values, robot.h).
#define SIM_VEHICLES_ALL   0x7U
#define SIM_VEHICLE_BIT(v) (1U << (unsigned)(v))

typedef struct {
    sim_effect_id_t id;
    const char *name; ///< JSON key in "effects"
    sim_effect_scope_t scope;
    const char *ref; ///< paper reference, e.g. "000 Eq. 2.7"
    const char *doc; ///< one line
    size_t n_params;
    sim_param_def_t params[SIM_EFFECT_MAX_PARAMS];
    unsigned vehicles;                           ///< SIM_VEHICLE_BIT mask
    sim_evidence_t evidence[SIM_EVIDENCE_COUNT]; ///< what each evidence mode sees of it
} sim_effect_def_t;

/// The catalog, indexed by sim_effect_id_t; *n (if not NULL) receives SIM_EFFECT_COUNT.
const sim_effect_def_t *sim_effects_catalog(size_t *n);

/// Catalog entry by JSON name; NULL iff unknown.
const sim_effect_def_t *sim_effect_find(const char *name);

/// Index of a parameter of an effect by name; -1 iff unknown.
int sim_effect_param_index(const sim_effect_def_t *e, const char *param);

/// Print the catalog as JSON ({"effects": [{name, scope, ref, doc, params: [...], vehicles:
/// ["labmate", ...], evidence: {"truth": {"seen": "yes|weak|no", "why": ...}, ...}}, ...]}) or as a
/// Markdown table (name | parameters | units | defaults | doc). Return 0, or -1 on a write error.
int sim_effects_write_json(FILE *out);
int sim_effects_write_markdown(FILE *out);

/* ---------------------------------------------------------------------------------------------
 * Scenario
 * ------------------------------------------------------------------------------------------- */

#define SIM_SCENARIO_MAX_BUMPS 64

/// One effect's setting on one truck. Parameters always hold valid values (defaults when the file
/// does not give them), so readers never need the catalog to interpret a disabled effect.
typedef struct {
    bool enabled;
    double p[SIM_EFFECT_MAX_PARAMS]; ///< in catalog order; enums as their index
} sim_effect_setting_t;

/// A discrete bump listed in the scenario ("bumps" -> "at").
typedef struct {
    uint8_t truck;      ///< ODO_TRUCK_A / ODO_TRUCK_B
    uint8_t wheel;      ///< ODO_LEFT / ODO_RIGHT
    double distance_mm; ///< along that wheel's cumulative true travel
    double height_mm;   ///< from the entry, else the effect's height_mm
} sim_scenario_bump_t;

typedef struct {
    uint64_t seed;                                          ///< "seed" (default 1); the CLI's --seed overrides it
    bool has_seed;                                          ///< the file gave a seed
    sim_effect_setting_t eff[SIM_EFFECT_COUNT][ODO_TRUCKS]; ///< vehicle-scoped: both entries equal
    size_t n_bumps;
    sim_scenario_bump_t bump[SIM_SCENARIO_MAX_BUMPS];
    char description[160];
} sim_scenario_t;

/// No effect enabled, every parameter at its default, seed 1. Never fails.
void sim_scenario_none(sim_scenario_t *sc);

/// Parse a scenario file (starting from sim_scenario_none). Returns 0, or -1 with a message
/// "<path>: <where>: <why>" in err (missing file, malformed JSON with line/column, schema error).
/// *sc is unspecified after a failure.
int sim_scenario_parse_file(const char *path, sim_scenario_t *sc, char *err, size_t errlen);

/// The same from a NUL-terminated string; `origin` names it in messages (e.g. "<inline>").
int sim_scenario_parse_string(const char *json, const char *origin, sim_scenario_t *sc, char *err, size_t errlen);

/// Switch an effect on for the trucks in `truck_mask` (bit 0 A, bit 1 B; vehicle-scoped effects
/// ignore the mask) and set one parameter (NULL: just enable, keeping current values). For tools
/// that sweep effect settings without files. Returns 0, or -1 with a message for an unknown effect
/// or parameter or an out-of-range value.
int sim_scenario_set(sim_scenario_t *sc, const char *effect, const char *param, unsigned truck_mask, double value,
                     char *err, size_t errlen);

/// Whether an effect is enabled on any truck.
bool sim_scenario_enabled(const sim_scenario_t *sc, sim_effect_id_t id);

/// Whether an effect is enabled on one truck.
bool sim_scenario_enabled_on(const sim_scenario_t *sc, sim_effect_id_t id, unsigned truck);

/// For each effect (indexed by sim_effect_id_t), whether it is enabled on any truck.
void sim_scenario_enabled_list(const sim_scenario_t *sc, bool out[SIM_EFFECT_COUNT]);

/// A parameter value (default if the file did not give it); NaN for a bad index.
double sim_scenario_param(const sim_scenario_t *sc, sim_effect_id_t id, unsigned truck, size_t param);

/// A parameter value by names; NaN iff the effect or parameter is unknown.
double sim_scenario_param_named(const sim_scenario_t *sc, const char *effect, const char *param, unsigned truck);

/* Parameter indices, in catalog order, for the world's hot path. */
enum { SIM_P_ED_VALUE = 0 };
enum { SIM_P_EB_VALUE = 0 };
enum { SIM_P_ES_VALUE = 0 };
enum { SIM_P_BUMPS_HEIGHT = 0, SIM_P_BUMPS_MODEL = 1 };
enum { SIM_P_ROUGH_MAX_HEIGHT = 0, SIM_P_ROUGH_SPACING = 1, SIM_P_ROUGH_JITTER = 2, SIM_P_ROUGH_MODEL = 3 };
enum { SIM_P_SLIP_K = 0, SIM_P_SLIP_A0 = 1, SIM_P_SLIP_MAX = 2 };
enum { SIM_P_SKID_K = 0, SIM_P_SKID_A0 = 1 };
enum { SIM_P_COUNT_LOSS_F_CLK = 0 };
enum { SIM_P_ROTARY_ALPHA = 0, SIM_P_ROTARY_BETA = 1 };
enum { SIM_P_LINK_CONST = 0, SIM_P_LINK_ECC = 1 };
enum { SIM_P_TIRE_K = 0, SIM_P_TIRE_LOAD = 1, SIM_P_TIRE_OFFSET = 2 };
enum { SIM_P_SCRUB_K = 0 };

#endif
