/// Robot description JSON reader and conversion to odo_params_t; see robot.h for the schema.
#include "odo_robot.h"
#include "odo_err.h"

#include "odo/odo_odometry.h"

#include <errno.h>
#include <jansson.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#define TWO30 1073741824.0

const char *sim_vehicle_name(sim_vehicle_t v)
{
    switch (v) {
    case SIM_VEHICLE_LABMATE: return "labmate";
    case SIM_VEHICLE_CLAPPER: return "clapper";
    case SIM_VEHICLE_SET: return "set";
    }
    return NULL;
}

bool sim_vehicle_parse(const char *name, sim_vehicle_t *out)
{
    for (int v = 0; v <= (int)SIM_VEHICLE_SET; ++v) {
        if (name != NULL && strcmp(name, sim_vehicle_name((sim_vehicle_t)v)) == 0) {
            *out = (sim_vehicle_t)v;
            return true;
        }
    }
    return false;
}

double sim_robot_counts_per_rev(const sim_truck_desc_t *t) { return 4.0 * t->encoder_lines * t->gear_ratio; }

/* A TRC LabMate truck (000 s. 4.1, 004 Table I): Dn 150 mm, b 340 mm; 500 lines x 4 x 19.5:1 =
 * 39000 counts per wheel turn, the firmware's documented default (odo_params_defaults). */
static void labmate_truck(sim_truck_desc_t *t)
{
    memset(t, 0, sizeof *t);
    t->wheel_diameter_mm = 150.0;
    t->wheelbase_mm = 340.0;
    t->encoder_lines = 500U;
    t->gear_ratio = 19.5;
    t->counter_bits = 24U;
    t->decoder = SIM_DECODER_HCTL1100;
    t->cal_ed = t->cal_eb = t->cal_es = 1.0;
    t->cal_scrub = 0.0;
}

/* The papers give no trailer dimensions; these are assumed (README "where the papers are loose"):
 * 100 mm passive wheels 300 mm apart with 1000-line encoders on the axle (4000 counts/turn). */
static void trailer_truck(sim_truck_desc_t *t)
{
    labmate_truck(t);
    t->wheel_diameter_mm = 100.0;
    t->wheelbase_mm = 300.0;
    t->encoder_lines = 1000U;
    t->gear_ratio = 1.0;
}

int sim_robot_default(sim_vehicle_t v, sim_robot_t *r)
{
    if (sim_vehicle_name(v) == NULL || r == NULL) {
        return -1;
    }
    memset(r, 0, sizeof *r);
    r->vehicle = v;
    r->n_trucks = v == SIM_VEHICLE_LABMATE ? 1U : 2U;
    r->tick_ms = 40.0;
    r->heading_form = ODO_HEADING_MIDPOINT;
    r->ipec_mode = v == SIM_VEHICLE_LABMATE ? ODO_IPEC_OFF : ODO_IPEC_PAPER;
    r->max_wheel_speed_mm_s = 3000.0;
    labmate_truck(&r->truck[0]);
    if (v == SIM_VEHICLE_SET) {
        trailer_truck(&r->truck[1]);
    } else {
        labmate_truck(&r->truck[1]);
    }
    r->link.length_mm = 1000.0; /* 004 s. 2 */
    r->link.min_mm = 900.0;
    r->link.max_mm = 1100.0;
    r->link.rotary_bits = 10U; /* 004 s. 2: 2^-10 turn = 0.35 deg */
    r->link.linear_resolution_mm = 0.1;
    r->set.hitch_offset_mm = 300.0;
    r->set.trailer_length_mm = 500.0;
    return 0;
}

/* ---------------------------------------------------------------------------------------------
 * THE limits of the robot description, one row per numeric key: the C tools parse with them and
 * the Python package reads the same parse through libodosim (odosim_robot_describe), so no second
 * copy exists to drift. Truck ranges are the firmware's (odo_params.h) so a file that parses also
 * validates.
 * ------------------------------------------------------------------------------------------- */
static const sim_robot_limit_t k_limits[] = {
    {"tick_ms", 1.0, 1000.0, "ms"},
    {"max_wheel_speed_mm_s", 100.0, 20000.0, "mm/s"},
    {"trucks.*.wheel_diameter_mm", 10.0, 2000.0, "mm"},
    {"trucks.*.wheelbase_mm", 50.0, 3000.0, "mm"},
    {"trucks.*.encoder_lines", 1.0, 1000000.0, "lines per turn"},
    {"trucks.*.gear_ratio", 0.01, 10000.0, "motor turns per wheel turn"},
    {"trucks.*.counter_bits", 8.0, 32.0, "bit"}, /* what real decoders have: HCTL 8/16/24, MCU timers 16/32 */
    {"trucks.*.calibration.ed", 0.8, 1.25, ""},
    {"trucks.*.calibration.eb", 0.8, 1.25, ""},
    {"trucks.*.calibration.es", 0.8, 1.25, ""},
    {"trucks.*.calibration.scrub", -0.25, 0.25, ""},
    {"linkage.length_mm", 100.0, 4000.0, "mm"},
    {"linkage.rotary_bits", 8.0, 16.0, "bit"},
    {"linkage.linear_resolution_mm", 0.001, 10.0, "mm"},
    {"linkage.calibration.length_bias_mm", -50.0, 50.0, "mm"},
    {"linkage.calibration.length_ecc_mm", -50.0, 50.0, "mm"},
    {"linkage.calibration.alpha_bias_deg", -10.0, 10.0, "deg"},
    {"linkage.calibration.beta_bias_deg", -10.0, 10.0, "deg"},
    {"trailer.hitch_offset_mm", 0.0, 4000.0, "mm"},
    {"trailer.trailer_length_mm", 100.0, 4000.0, "mm"},
    {"trailer.rotary_bits", 8.0, 16.0, "bit"},
    {"trailer.calibration.alpha_bias_deg", -10.0, 10.0, "deg"},
};

const sim_robot_limit_t *sim_robot_limits(size_t *n)
{
    *n = sizeof k_limits / sizeof k_limits[0];
    return k_limits;
}

/* The row of `key` ("trucks.A.x" matches "trucks.*.x"); a missing row is a programming error. */
static const sim_robot_limit_t *lim(const char *path, const char *key)
{
    char full[160];
    snprintf(full, sizeof full, "%s%s%s", path, path[0] ? "." : "", key);
    if (strncmp(full, "trucks.", 7) == 0 && full[7] != '\0' && full[8] == '.') {
        full[7] = '*';
    }
    for (size_t i = 0; i < sizeof k_limits / sizeof k_limits[0]; ++i) {
        if (strcmp(k_limits[i].key, full) == 0) {
            return &k_limits[i];
        }
    }
    static const sim_robot_limit_t none = {"", 0.0, -1.0, ""};
    return &none; /* empty range: every value fails, loudly, in the tests */
}

#define LO(path, key) lim(path, key)->lo
#define HI(path, key) lim(path, key)->hi

/* ---------------------------------------------------------------------------------------------
 * JSON helpers. Each names "<origin>: <field>: <why>".
 * ------------------------------------------------------------------------------------------- */
typedef struct {
    const char *origin;
    char *err;
    size_t errlen;
} ctx_t;

#if defined(__GNUC__)
__attribute__((format(printf, 3, 4)))
#endif
static int
fail(const ctx_t *c, const char *field, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    (void)odo_verrf_at(c->err, c->errlen, c->origin, field, fmt, ap);
    va_end(ap);
    return -1;
}

static const char *tname(const json_t *v)
{
    if (json_is_object(v))
        return "an object";
    if (json_is_array(v))
        return "an array";
    if (json_is_string(v))
        return "a string";
    if (json_is_number(v))
        return "a number";
    if (json_is_boolean(v))
        return "a boolean";
    return "null";
}

/* Reject keys not in the NULL-terminated list. */
static int only_keys(const ctx_t *c, const json_t *obj, const char *path, const char *const *keys)
{
    const char *key;
    json_t *v;
    json_object_foreach((json_t *)obj, key, v)
    {
        bool ok = false;
        for (const char *const *k = keys; *k != NULL; ++k) {
            ok = ok || strcmp(*k, key) == 0;
        }
        if (!ok) {
            char known[256] = "";
            size_t n = 0;
            for (const char *const *k = keys; *k != NULL && n < sizeof known; ++k) {
                int w = snprintf(known + n, sizeof known - n, "%s%s", k == keys ? "" : ", ", *k);
                n += w > 0 ? (size_t)w : 0U;
            }
            char f[160];
            snprintf(f, sizeof f, "%s%s%.60s", path, path[0] ? "." : "", key);
            return fail(c, f, "unknown key (known: %s)", known);
        }
    }
    return 0;
}

static void field(char *buf, size_t cap, const char *path, const char *key)
{
    snprintf(buf, cap, "%.100s%s%.50s", path, path[0] ? "." : "", key);
}

/* Optional number in [lo, hi]; keeps *out if absent unless `required`. */
static int get_num(const ctx_t *c, const json_t *obj, const char *path, const char *key, bool required, double lo,
                   double hi, double *out)
{
    char f[160];
    field(f, sizeof f, path, key);
    const json_t *v = json_object_get(obj, key);
    if (v == NULL) {
        return required ? fail(c, f, "missing (a number in [%g, %g])", lo, hi) : 0;
    }
    if (!json_is_number(v)) {
        return fail(c, f, "expected a number, got %s", tname(v));
    }
    const double x = json_number_value(v);
    if (!isfinite(x) || x < lo || x > hi) {
        return fail(c, f, "%g is out of range [%g, %g]", x, lo, hi);
    }
    *out = x;
    return 0;
}

static int get_uint(const ctx_t *c, const json_t *obj, const char *path, const char *key, bool required, unsigned lo,
                    unsigned hi, unsigned *out)
{
    char f[160];
    field(f, sizeof f, path, key);
    const json_t *v = json_object_get(obj, key);
    if (v == NULL) {
        return required ? fail(c, f, "missing (an integer in [%u, %u])", lo, hi) : 0;
    }
    if (!json_is_integer(v)) {
        return fail(c, f, "expected an integer, got %s", json_is_real(v) ? "a fraction" : tname(v));
    }
    const json_int_t x = json_integer_value(v);
    if (x < (json_int_t)lo || x > (json_int_t)hi) {
        return fail(c, f, "%lld is out of range [%u, %u]", (long long)x, lo, hi);
    }
    *out = (unsigned)x;
    return 0;
}

static int get_bool(const ctx_t *c, const json_t *obj, const char *path, const char *key, bool *out)
{
    char f[160];
    field(f, sizeof f, path, key);
    const json_t *v = json_object_get(obj, key);
    if (v == NULL) {
        return 0;
    }
    if (!json_is_boolean(v)) {
        return fail(c, f, "expected true or false, got %s", tname(v));
    }
    *out = json_is_true(v);
    return 0;
}

/* Optional string among `choices` (NULL-terminated); *out receives its index. */
static int get_choice(const ctx_t *c, const json_t *obj, const char *path, const char *key, bool required,
                      const char *const *choices, unsigned *out)
{
    char f[160];
    field(f, sizeof f, path, key);
    const json_t *v = json_object_get(obj, key);
    if (v == NULL) {
        return required ? fail(c, f, "missing") : 0;
    }
    char known[160] = "";
    size_t n = 0;
    for (unsigned i = 0; choices[i] != NULL; ++i) {
        if (json_is_string(v) && strcmp(json_string_value(v), choices[i]) == 0) {
            *out = i;
            return 0;
        }
        int w = snprintf(known + n, sizeof known - n, "%s\"%s\"", i ? ", " : "", choices[i]);
        n += (w > 0 && (size_t)w < sizeof known - n) ? (size_t)w : 0U;
    }
    if (json_is_string(v)) {
        return fail(c, f, "\"%s\" is not one of %s", json_string_value(v), known);
    }
    return fail(c, f, "expected one of %s, got %s", known, tname(v));
}

static int get_obj(const ctx_t *c, const json_t *parent, const char *path, const char *key, bool required,
                   const json_t **out)
{
    char f[160];
    field(f, sizeof f, path, key);
    const json_t *v = json_object_get(parent, key);
    *out = NULL;
    if (v == NULL) {
        return required ? fail(c, f, "missing (an object)") : 0;
    }
    if (!json_is_object(v)) {
        return fail(c, f, "expected an object, got %s", tname(v));
    }
    *out = v;
    return 0;
}

static int parse_truck(const ctx_t *c, const json_t *o, const char *path, sim_truck_desc_t *t)
{
    static const char *const keys[] = {
        "wheel_diameter_mm", "wheelbase_mm", "encoder_lines", "gear_ratio",  "counter_bits",
        "decoder",           "invert_left",  "invert_right",  "calibration", NULL};
    static const char *const decoders[] = {"hctl1100", "hctl20xx", NULL};
    static const char *const cal_keys[] = {"ed", "eb", "es", "scrub", NULL};
    unsigned dec = (unsigned)t->decoder;
    if (only_keys(c, o, path, keys) != 0 ||
        get_num(c, o, path, "wheel_diameter_mm", true, LO(path, "wheel_diameter_mm"), HI(path, "wheel_diameter_mm"),
                &t->wheel_diameter_mm) != 0 ||
        get_num(c, o, path, "wheelbase_mm", true, LO(path, "wheelbase_mm"), HI(path, "wheelbase_mm"),
                &t->wheelbase_mm) != 0 ||
        get_uint(c, o, path, "encoder_lines", true, (unsigned)LO(path, "encoder_lines"),
                 (unsigned)HI(path, "encoder_lines"), &t->encoder_lines) != 0 ||
        get_num(c, o, path, "gear_ratio", true, LO(path, "gear_ratio"), HI(path, "gear_ratio"), &t->gear_ratio) != 0 ||
        get_uint(c, o, path, "counter_bits", false, (unsigned)LO(path, "counter_bits"),
                 (unsigned)HI(path, "counter_bits"), &t->counter_bits) != 0 ||
        get_choice(c, o, path, "decoder", false, decoders, &dec) != 0 ||
        get_bool(c, o, path, "invert_left", &t->invert_left) != 0 ||
        get_bool(c, o, path, "invert_right", &t->invert_right) != 0) {
        return -1;
    }
    t->decoder = (sim_decoder_t)dec;
    char f[160];
    const double cpr = sim_robot_counts_per_rev(t);
    if (cpr < 100.0 || cpr > 4.0e6) {
        field(f, sizeof f, path, "encoder_lines");
        return fail(c, f, "4 * encoder_lines * gear_ratio = %g counts per wheel turn, outside [100, 4e6]", cpr);
    }
    const json_t *cal = NULL;
    if (get_obj(c, o, path, "calibration", false, &cal) != 0) {
        return -1;
    }
    if (cal != NULL) {
        field(f, sizeof f, path, "calibration");
        if (only_keys(c, cal, f, cal_keys) != 0 ||
            get_num(c, cal, f, "ed", false, LO(f, "ed"), HI(f, "ed"), &t->cal_ed) != 0 ||
            get_num(c, cal, f, "eb", false, LO(f, "eb"), HI(f, "eb"), &t->cal_eb) != 0 ||
            get_num(c, cal, f, "es", false, LO(f, "es"), HI(f, "es"), &t->cal_es) != 0 ||
            /* k of the firmware's tyre-scrub term (odo_odometry.h): |k| <= 0.25, as the block */
            get_num(c, cal, f, "scrub", false, LO(f, "scrub"), HI(f, "scrub"), &t->cal_scrub) != 0) {
            return -1;
        }
        t->has_calibration = true;
    }
    return 0;
}

static int parse_root(const ctx_t *c, const json_t *root, sim_robot_t *r)
{
    static const char *const keys[] = {
        "vehicle", "description", "tick_ms", "heading_form", "ipec", "max_wheel_speed_mm_s", "trucks",
        "linkage", "trailer",     NULL};
    static const char *const vehicles[] = {"labmate", "clapper", "set", NULL};
    static const char *const forms[] = {"midpoint", "paper", NULL};
    static const char *const ipec[] = {"off", "paper", "estimator", NULL};
    if (!json_is_object(root)) {
        return fail(c, NULL, "a robot description is a JSON object, got %s", tname(root));
    }
    if (only_keys(c, root, "", keys) != 0) {
        return -1;
    }
    unsigned veh = 0;
    if (get_choice(c, root, "", "vehicle", true, vehicles, &veh) != 0) {
        return -1;
    }
    sim_robot_default((sim_vehicle_t)veh, r);
    const json_t *d = json_object_get(root, "description");
    if (d != NULL) {
        if (!json_is_string(d)) {
            return fail(c, "description", "expected a string, got %s", tname(d));
        }
        snprintf(r->description, sizeof r->description, "%s", json_string_value(d));
    }
    if (get_num(c, root, "", "tick_ms", false, LO("", "tick_ms"), HI("", "tick_ms"), &r->tick_ms) != 0 ||
        get_choice(c, root, "", "heading_form", false, forms, &r->heading_form) != 0 ||
        get_choice(c, root, "", "ipec", false, ipec, &r->ipec_mode) != 0 ||
        get_num(c, root, "", "max_wheel_speed_mm_s", false, LO("", "max_wheel_speed_mm_s"),
                HI("", "max_wheel_speed_mm_s"), &r->max_wheel_speed_mm_s) != 0) {
        return -1;
    }
    if (fabs(r->tick_ms * 1000.0 - round(r->tick_ms * 1000.0)) > 1e-6) {
        return fail(c, "tick_ms", "%g ms is not a whole number of microseconds", r->tick_ms);
    }
    const json_t *trucks = NULL, *ta = NULL, *tb = NULL;
    if (get_obj(c, root, "", "trucks", true, &trucks) != 0) {
        return -1;
    }
    static const char *const truck_keys_1[] = {"A", NULL};
    static const char *const truck_keys_2[] = {"A", "B", NULL};
    if (only_keys(c, trucks, "trucks", r->n_trucks == 1U ? truck_keys_1 : truck_keys_2) != 0 ||
        get_obj(c, trucks, "trucks", "A", true, &ta) != 0 || parse_truck(c, ta, "trucks.A", &r->truck[0]) != 0) {
        return -1;
    }
    if (r->n_trucks == 2U) {
        if (get_obj(c, trucks, "trucks", "B", true, &tb) != 0 || parse_truck(c, tb, "trucks.B", &r->truck[1]) != 0) {
            return -1;
        }
        if (r->truck[1].counter_bits != r->truck[0].counter_bits) {
            return fail(c, "trucks.B.counter_bits",
                        "%u differs from trucks.A (%u): the firmware has one "
                        "counter width",
                        r->truck[1].counter_bits, r->truck[0].counter_bits);
        }
    }
    const json_t *link = json_object_get(root, "linkage"), *trailer = json_object_get(root, "trailer");
    if (link != NULL && r->vehicle != SIM_VEHICLE_CLAPPER) {
        return fail(c, "linkage", "only a clapper has a linkage (vehicle is %s)", sim_vehicle_name(r->vehicle));
    }
    if (trailer != NULL && r->vehicle != SIM_VEHICLE_SET) {
        return fail(c, "trailer", "only a set has a trailer (vehicle is %s)", sim_vehicle_name(r->vehicle));
    }
    if (r->vehicle == SIM_VEHICLE_CLAPPER) {
        static const char *const lk[] = {"length_mm",   "range_mm", "rotary_bits", "linear_resolution_mm",
                                         "calibration", NULL};
        static const char *const ck[] = {"length_bias_mm", "length_ecc_mm", "alpha_bias_deg", "beta_bias_deg", NULL};
        const json_t *cal = NULL;
        if (get_obj(c, root, "", "linkage", true, &link) != 0 || only_keys(c, link, "linkage", lk) != 0 ||
            get_num(c, link, "linkage", "length_mm", true, LO("linkage", "length_mm"), HI("linkage", "length_mm"),
                    &r->link.length_mm) != 0 ||
            get_uint(c, link, "linkage", "rotary_bits", false, (unsigned)LO("linkage", "rotary_bits"),
                     (unsigned)HI("linkage", "rotary_bits"), &r->link.rotary_bits) != 0 ||
            get_num(c, link, "linkage", "linear_resolution_mm", false, LO("linkage", "linear_resolution_mm"),
                    HI("linkage", "linear_resolution_mm"), &r->link.linear_resolution_mm) != 0 ||
            get_obj(c, link, "linkage", "calibration", false, &cal) != 0) {
            return -1;
        }
        r->link.min_mm = r->link.length_mm - 100.0;
        r->link.max_mm = r->link.length_mm + 100.0;
        const json_t *range = json_object_get(link, "range_mm");
        if (range != NULL) {
            if (!json_is_array(range) || json_array_size(range) != 2U || !json_is_number(json_array_get(range, 0)) ||
                !json_is_number(json_array_get(range, 1))) {
                return fail(c, "linkage.range_mm", "expected [min, max] in mm");
            }
            r->link.min_mm = json_number_value(json_array_get(range, 0));
            r->link.max_mm = json_number_value(json_array_get(range, 1));
            if (!(r->link.min_mm >= 1.0 && r->link.min_mm < r->link.length_mm && r->link.length_mm < r->link.max_mm &&
                  r->link.max_mm <= 20000.0)) {
                return fail(c, "linkage.range_mm", "[%g, %g] must satisfy 1 <= min < length_mm (%g) < max <= 20000",
                            r->link.min_mm, r->link.max_mm, r->link.length_mm);
            }
        }
        if (cal != NULL &&
            (only_keys(c, cal, "linkage.calibration", ck) != 0 ||
             get_num(c, cal, "linkage.calibration", "length_bias_mm", false,
                     LO("linkage.calibration", "length_bias_mm"), HI("linkage.calibration", "length_bias_mm"),
                     &r->link.cal_length_bias_mm) != 0 ||
             get_num(c, cal, "linkage.calibration", "length_ecc_mm", false, LO("linkage.calibration", "length_ecc_mm"),
                     HI("linkage.calibration", "length_ecc_mm"), &r->link.cal_length_ecc_mm) != 0 ||
             get_num(c, cal, "linkage.calibration", "alpha_bias_deg", false,
                     LO("linkage.calibration", "alpha_bias_deg"), HI("linkage.calibration", "alpha_bias_deg"),
                     &r->link.cal_alpha_bias_deg) != 0 ||
             get_num(c, cal, "linkage.calibration", "beta_bias_deg", false, LO("linkage.calibration", "beta_bias_deg"),
                     HI("linkage.calibration", "beta_bias_deg"), &r->link.cal_beta_bias_deg) != 0)) {
            return -1;
        }
    }
    if (r->vehicle == SIM_VEHICLE_SET) {
        static const char *const tk[] = {"hitch_offset_mm", "trailer_length_mm", "rotary_bits", "calibration", NULL};
        static const char *const ck[] = {"alpha_bias_deg", NULL};
        const json_t *cal = NULL;
        if (get_obj(c, root, "", "trailer", true, &trailer) != 0 || only_keys(c, trailer, "trailer", tk) != 0 ||
            get_num(c, trailer, "trailer", "hitch_offset_mm", true, LO("trailer", "hitch_offset_mm"),
                    HI("trailer", "hitch_offset_mm"), &r->set.hitch_offset_mm) != 0 ||
            get_num(c, trailer, "trailer", "trailer_length_mm", true, LO("trailer", "trailer_length_mm"),
                    HI("trailer", "trailer_length_mm"), &r->set.trailer_length_mm) != 0 ||
            get_uint(c, trailer, "trailer", "rotary_bits", false, (unsigned)LO("trailer", "rotary_bits"),
                     (unsigned)HI("trailer", "rotary_bits"), &r->link.rotary_bits) != 0 ||
            get_obj(c, trailer, "trailer", "calibration", false, &cal) != 0) {
            return -1;
        }
        if (cal != NULL && (only_keys(c, cal, "trailer.calibration", ck) != 0 ||
                            get_num(c, cal, "trailer.calibration", "alpha_bias_deg", false,
                                    LO("trailer.calibration", "alpha_bias_deg"),
                                    HI("trailer.calibration", "alpha_bias_deg"), &r->link.cal_alpha_bias_deg) != 0)) {
            return -1;
        }
    }
    return 0;
}

static int parse_loaded(json_t *root, const json_error_t *jerr, const ctx_t *c, sim_robot_t *r)
{
    if (root == NULL) {
        return fail(c, NULL, "malformed JSON at line %d column %d: %s", jerr->line, jerr->column, jerr->text);
    }
    const int rc = parse_root(c, root, r);
    json_decref(root);
    return rc;
}

int sim_robot_parse_string(const char *json, const char *origin, sim_robot_t *r, char *err, size_t errlen)
{
    const ctx_t c = {origin != NULL ? origin : "<string>", err, errlen};
    if (json == NULL || r == NULL) {
        return fail(&c, NULL, "no input");
    }
    json_error_t jerr;
    return parse_loaded(json_loads(json, JSON_REJECT_DUPLICATES, &jerr), &jerr, &c, r);
}

int sim_robot_parse_file(const char *path, sim_robot_t *r, char *err, size_t errlen)
{
    const ctx_t c = {path != NULL ? path : "<robot>", err, errlen};
    if (path == NULL || r == NULL) {
        return fail(&c, NULL, "no file given");
    }
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        return fail(&c, NULL, "cannot open robot description: %s", strerror(errno));
    }
    json_error_t jerr;
    json_t *root = json_loadf(f, JSON_REJECT_DUPLICATES, &jerr);
    fclose(f);
    return parse_loaded(root, &jerr, &c, r);
}

/* ---------------------------------------------------------------------------------------------
 * Conversion to the parameter block. Saturating casts: a value out of range (from a description
 * built in code) must reach odo_params_validate as an out-of-range field, not as undefined
 * behaviour in the cast.
 * ------------------------------------------------------------------------------------------- */
static uint32_t sat_u32(double v)
{
    if (!(v > 0.0)) {
        return 0U;
    }
    return v >= 4294967295.0 ? UINT32_MAX : (uint32_t)llround(v);
}

static int32_t sat_i32(double v)
{
    if (v != v) {
        return 0;
    }
    if (v >= 2147483647.0) {
        return INT32_MAX;
    }
    return v <= -2147483648.0 ? INT32_MIN : (int32_t)llround(v);
}

static int32_t deg_to_bam(double deg) { return sat_i32(deg / 360.0 * 4294967296.0); }

/* JSON name of a parameter-block field, for messages. */
static const char *json_field(const sim_robot_t *r, odo_param_field_t f)
{
    switch (f) {
    case ODO_PF_VEHICLE: return "vehicle";
    case ODO_PF_COUNTER_BITS: return "counter_bits";
    case ODO_PF_HEADING_FORM: return "heading_form";
    case ODO_PF_IPEC_MODE: return "ipec";
    case ODO_PF_TICK_US: return "tick_ms";
    case ODO_PF_MAX_WHEEL_SPEED: return "max_wheel_speed_mm_s";
    case ODO_PF_WHEEL_DIAMETER: return "wheel_diameter_mm";
    case ODO_PF_COUNTS_PER_REV: return "encoder_lines/gear_ratio";
    case ODO_PF_WHEELBASE: return "wheelbase_mm";
    case ODO_PF_ED: return "calibration.ed";
    case ODO_PF_EB: return "calibration.eb";
    case ODO_PF_ES: return "calibration.es";
    case ODO_PF_SCRUB: return "calibration.scrub";
    case ODO_PF_TRUCK_FLAGS: return "invert_left/invert_right";
    case ODO_PF_LINK_LENGTH: return r->vehicle == SIM_VEHICLE_SET ? "trailer.trailer_length_mm" : "linkage.length_mm";
    case ODO_PF_HITCH_OFFSET: return "trailer.hitch_offset_mm";
    case ODO_PF_LENGTH_BIAS: return "linkage.calibration.length_bias_mm";
    case ODO_PF_LENGTH_ECC: return "linkage.calibration.length_ecc_mm";
    case ODO_PF_ALPHA_BIAS: return "calibration.alpha_bias_deg";
    case ODO_PF_BETA_BIAS: return "linkage.calibration.beta_bias_deg";
    case ODO_PF_ROTARY_BITS: return "rotary_bits";
    case ODO_PF_STALE_TICKS: return "(stale_ticks)";
    case ODO_PF_MAX_JUMP: return "(max_jump)";
    case ODO_PF_MAX_LENGTH_JUMP: return "(max_length_jump)";
    case ODO_PF_LENGTH_MIN:
    case ODO_PF_LENGTH_MAX:
    case ODO_PF_LENGTH_RANGE: return "linkage.range_mm";
    case ODO_PF_NONE:
    case ODO_PF_RESERVED: break;
    }
    return "(reserved)";
}

int sim_robot_to_params(const sim_robot_t *r, odo_params_t *p, char *err, size_t errlen)
{
    const ctx_t c = {"robot", err, errlen};
    if (r == NULL || p == NULL) {
        return fail(&c, NULL, "no robot");
    }
    odo_params_defaults(p);
    switch (r->vehicle) {
    case SIM_VEHICLE_LABMATE: p->vehicle = (uint8_t)ODO_VEHICLE_SINGLE; break;
    case SIM_VEHICLE_CLAPPER: p->vehicle = (uint8_t)ODO_VEHICLE_CLAPPER; break;
    case SIM_VEHICLE_SET: p->vehicle = (uint8_t)ODO_VEHICLE_SET; break;
    }
    p->counter_bits = (uint8_t)r->truck[0].counter_bits;
    p->heading_form = (uint8_t)r->heading_form;
    p->ipec_mode = (uint8_t)r->ipec_mode;
    p->tick_us = sat_u32(r->tick_ms * 1000.0);
    p->max_wheel_speed_mm_s = sat_u32(r->max_wheel_speed_mm_s);
    for (unsigned t = 0; t < r->n_trucks && t < ODO_TRUCKS; ++t) {
        const sim_truck_desc_t *d = &r->truck[t];
        odo_truck_params_t *tp = &p->truck[t];
        tp->wheel_diameter_nm = sat_u32(d->wheel_diameter_mm * 1e6);
        tp->counts_per_rev_milli = sat_u32(sim_robot_counts_per_rev(d) * 1000.0);
        tp->wheelbase_nm = sat_u32(d->wheelbase_mm * 1e6);
        tp->ed_q30 = sat_i32(d->cal_ed * TWO30);
        tp->eb_q30 = sat_i32(d->cal_eb * TWO30);
        tp->es_q30 = sat_i32(d->cal_es * TWO30);
        tp->scrub_q30 = sat_i32(d->cal_scrub * TWO30);
        tp->flags =
            (uint8_t)((d->invert_left ? ODO_TRUCK_INVERT_LEFT : 0U) | (d->invert_right ? ODO_TRUCK_INVERT_RIGHT : 0U));
    }
    if (r->vehicle == SIM_VEHICLE_CLAPPER) {
        p->link.length_nm = sat_u32(r->link.length_mm * 1e6);
        p->link.length_min_um = sat_u32(r->link.min_mm * 1e3);
        p->link.length_max_um = sat_u32(r->link.max_mm * 1e3);
        p->link.length_bias_nm = sat_i32(r->link.cal_length_bias_mm * 1e6);
        p->link.length_ecc_nm = sat_i32(r->link.cal_length_ecc_mm * 1e6);
        p->link.beta_bias_bam = deg_to_bam(r->link.cal_beta_bias_deg);
    } else if (r->vehicle == SIM_VEHICLE_SET) {
        p->link.length_nm = sat_u32(r->set.trailer_length_mm * 1e6);
        p->link.hitch_offset_nm = sat_u32(r->set.hitch_offset_mm * 1e6);
        /* No linear encoder on a set; keep a sane physical range around the fixed bar length. */
        p->link.length_min_um = sat_u32((r->set.trailer_length_mm - 50.0) * 1e3);
        p->link.length_max_um = sat_u32((r->set.trailer_length_mm + 50.0) * 1e3);
    }
    p->link.alpha_bias_bam = deg_to_bam(r->link.cal_alpha_bias_deg);
    p->link.rotary_bits = (uint8_t)r->link.rotary_bits;

    odo_param_field_t bad = ODO_PF_NONE;
    uint8_t bad_truck = 0U;
    if (odo_params_validate(p, &bad, &bad_truck) != ODO_PARAMS_OK) {
        const bool truck_field = odo_params_field_is_truck(bad);
        char f[160];
        snprintf(f, sizeof f, "%s%s%s", truck_field ? "trucks." : "",
                 truck_field ? (bad_truck == 0U ? "A." : "B.") : "", json_field(r, bad));
        return fail(&c, f, "rejected by odo_params_validate (parameter block field %d out of range)", (int)bad);
    }
    /* A block that validates must also boot: the firmware's per-truck multipliers must fit, and a
     * counter must not wrap within one tick at the top wheel speed (odo_model_init). */
    for (unsigned t = 0; t < r->n_trucks && t < ODO_TRUCKS; ++t) {
        odo_model_t m;
        if (odo_model_init(&m, &p->truck[t], p->counter_bits, p->heading_form, p->tick_us, p->max_wheel_speed_mm_s) !=
            ODO_MODEL_OK) {
            const sim_truck_desc_t *d = &r->truck[t];
            const double per_tick = r->max_wheel_speed_mm_s * r->tick_ms * 1e-3 /
                                    (M_PI * d->wheel_diameter_mm / sim_robot_counts_per_rev(d));
            char f[64];
            if (per_tick + 1.0 >= ldexp(1.0, (int)d->counter_bits - 1)) {
                snprintf(f, sizeof f, "trucks.%c.counter_bits", t == 0U ? 'A' : 'B');
                return fail(&c, f,
                            "%u-bit counters wrap within one %g ms tick at max_wheel_speed_mm_s %g "
                            "(%.0f counts per tick; the firmware needs fewer than %.0f)",
                            d->counter_bits, r->tick_ms, r->max_wheel_speed_mm_s, per_tick,
                            ldexp(1.0, (int)d->counter_bits - 1));
            }
            const double turns = 2.0 * r->max_wheel_speed_mm_s * r->tick_ms * 1e-3 / d->wheelbase_mm / (2.0 * M_PI);
            snprintf(f, sizeof f, "trucks.%c", t == 0U ? 'A' : 'B');
            return fail(&c, f,
                        "geometry beyond the firmware's fixed-point formats (odo_model_init): at "
                        "max_wheel_speed_mm_s %g a %g ms tick may turn %.3g turns with wheelbase_mm %g",
                        r->max_wheel_speed_mm_s, r->tick_ms, turns, d->wheelbase_mm);
        }
    }
    return 0;
}
