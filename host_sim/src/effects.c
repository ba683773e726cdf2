/// The effects catalog and the scenario JSON reader; see effects.h for the schema.
#include "effects.h"
#include "odo_err.h"

#include "odo_robot.h"

#include <errno.h>
#include <jansson.h>
#include <math.h>
#include <string.h>

#define ENUM_BUMP_MODEL "paper|exact"

#define YES                \
    {                      \
        SIM_SEEN_YES, NULL \
    }
#define NO(why)          \
    {                    \
        SIM_SEEN_NO, why \
    }
#define WEAK(why)          \
    {                      \
        SIM_SEEN_WEAK, why \
    }
#define TWO_TRUCKS (SIM_VEHICLE_BIT(SIM_VEHICLE_CLAPPER) | SIM_VEHICLE_BIT(SIM_VEHICLE_SET))
#define TIRE_ALIAS                                                                                  \
    "kinematically an Ed plus an Es (off-centre load and mean load): aliased with the pair ed+es, " \
    "reported through them"
#define FLOOR_IN_LINKAGE                                                                           \
    WEAK("the linkage sees a floor effect only through the difference of the two trucks: fitted, " \
         "not named reliably")

/* Sizes are typical of the papers; ranges are what the world can simulate sensibly (and, for the
 * calibration ratios, what the firmware's parameter block accepts: [0.8, 1.25], odo_params.h). */
static const sim_effect_def_t catalog[SIM_EFFECT_COUNT] = {
    [SIM_EFFECT_ED] = {SIM_EFFECT_ED,
                       "ed",
                       SIM_SCOPE_TRUCK,
                       "000 Eqs. 2.7, 6.30-6.32",
                       "Unequal wheel diameters: Ed = DR/DL with the mean diameter kept (000 Eq. 6.30); a straight "
                       "command curves toward the smaller wheel",
                       1,
                       {{"value", "1", SIM_PARAM_NUMBER, 1.0, 0.8, 1.25, NULL, "Ed = DR/DL (true diameters)"}},
                       .vehicles = SIM_VEHICLES_ALL,
                       .evidence = {YES, YES, YES}},
    [SIM_EFFECT_EB] = {SIM_EFFECT_EB,
                       "eb",
                       SIM_SCOPE_TRUCK,
                       "000 Eq. 2.8",
                       "Wheelbase error: true b = Eb * nominal b; on-the-spot turns come out 1/Eb of the commanded "
                       "angle",
                       1,
                       {{"value", "1", SIM_PARAM_NUMBER, 1.0, 0.8, 1.25, NULL, "Eb = b_actual/b_nominal"}},
                       .vehicles = SIM_VEHICLES_ALL,
                       .evidence = {YES, YES, YES}},
    [SIM_EFFECT_ES] = {SIM_EFFECT_ES,
                       "es",
                       SIM_SCOPE_TRUCK,
                       "000 App. B, Eq. B.1",
                       "Scale error: Es = L_calc/L_actual, i.e. the true mean wheel diameter is Dn/Es",
                       1,
                       {{"value", "1", SIM_PARAM_NUMBER, 1.0, 0.8, 1.25, NULL, "Es = L_calc/L_actual"}},
                       .vehicles = SIM_VEHICLES_ALL,
                       .evidence = {YES, NO("closed paths do not fix the overall scale (Es)"), YES}},
    [SIM_EFFECT_BUMPS] = {SIM_EFFECT_BUMPS,
                          "bumps",
                          SIM_SCOPE_TRUCK,
                          "004 Eqs. 1-5, Table I",
                          "Discrete bumps: a rigid wheel over a thin step of height h turns more than it advances "
                          "(dD per bump); positions from the experiment or the scenario's \"at\" list",
                          2,
                          {{"height_mm", "mm", SIM_PARAM_NUMBER, 10.0, 0.0, 50.0, NULL, "step height h"},
                           {"model", "-", SIM_PARAM_ENUM, (double)SIM_BUMP_EXACT, 0.0, 1.0, ENUM_BUMP_MODEL,
                            "paper: 004 Eq. 3 chord (Table I); exact: pivot about the edge"}},
                          .vehicles = SIM_VEHICLES_ALL,
                          .evidence = {YES, NO("return errors carry no positions of discrete events"),
                                       NO("not located from linkage readings alone (tested in truth mode)")}},
    [SIM_EFFECT_ROUGHNESS] =
        {SIM_EFFECT_ROUGHNESS,
         "roughness",
         SIM_SCOPE_TRUCK,
         "000 s. 4.6.2",
         "Floor roughness: every ~spacing of its own travel each wheel meets a bump of random height "
         "in [0, max] (independent per wheel, seeded)",
         4,
         {{"max_height_mm", "mm", SIM_PARAM_NUMBER, 1.0, 0.0, 10.0, NULL, "heights uniform in [0, max]"},
          {"spacing_mm", "mm", SIM_PARAM_NUMBER, 20.0, 2.0, 1000.0, NULL, "mean distance between bumps"},
          {"jitter", "1", SIM_PARAM_NUMBER, 0.5, 0.0, 0.95, NULL, "gap = spacing * (1 + jitter * U(-1, 1))"},
          {"model", "-", SIM_PARAM_ENUM, (double)SIM_BUMP_EXACT, 0.0, 1.0, ENUM_BUMP_MODEL,
           "bump model of each grain"}},
         .vehicles = SIM_VEHICLES_ALL,
         .evidence = {YES, YES, FLOOR_IN_LINKAGE}},
    [SIM_EFFECT_SLIP] = {SIM_EFFECT_SLIP,
                         "slip",
                         SIM_SCOPE_TRUCK,
                         "000 s. 2 (over-acceleration)",
                         "Longitudinal slip under acceleration: slip fraction = k * max(0, abs(a) - a0), capped; the "
                         "wheel spins (speeding up) or drags (slowing down) relative to the floor",
                         3,
                         {{"k_per_m_s2", "1/(m/s^2)", SIM_PARAM_NUMBER, 0.02, 0.0, 1.0, NULL,
                           "slip fraction per m/s^2"},
                          {"a0_m_s2", "m/s^2", SIM_PARAM_NUMBER, 0.5, 0.0, 20.0, NULL, "acceleration without slip"},
                          {"max_fraction", "1", SIM_PARAM_NUMBER, 0.2, 0.0, 0.9, NULL, "cap on the slip fraction"}},
                         .vehicles = SIM_VEHICLES_ALL,
                         .evidence = {YES, YES, FLOOR_IN_LINKAGE}},
    [SIM_EFFECT_SKID] =
        {SIM_EFFECT_SKID,
         "skid",
         SIM_SCOPE_TRUCK,
         "000 s. 2 (fast turning)",
         "Lateral skid in fast turns: outward sideways speed = k * max(0, abs(v * omega) - a0); the "
         "encoders do not see it",
         2,
         {{"k_s", "s", SIM_PARAM_NUMBER, 0.02, 0.0, 1.0, NULL, "lateral speed per m/s^2 of excess"},
          {"a0_m_s2", "m/s^2", SIM_PARAM_NUMBER, 0.3, 0.0, 20.0, NULL, "centripetal threshold"}},
         .vehicles = SIM_VEHICLES_ALL,
         .evidence =
             {YES,
              NO("a corner's outward skid turns no heading, and around a closed path the corners' displacements cancel: k = 0.3 s moves these return poses by ~1 mm (tests/python/test_gap_evidence.py)"),
              FLOOR_IN_LINKAGE}},
    [SIM_EFFECT_COUNT_LOSS] =
        {SIM_EFFECT_COUNT_LOSS,
         "count_loss",
         SIM_SCOPE_TRUCK,
         "HCTL-1100 data sheet (input filter)",
         "Encoder count loss: the decoder's 3-clock input filter drops quadrature states faster "
         "than about f_CLK/3 (applied by the HCTL emulator)",
         1,
         {{"f_clk_hz", "Hz", SIM_PARAM_NUMBER, 1.0e6, 1.0e5, 2.0e6, NULL, "decoder clock"}},
         .vehicles = SIM_VEHICLES_ALL,
         .evidence = {YES, NO("a loss on the fast legs scales them like an Es, which closed paths do not fix"),
                      NO("both trucks drive at one speed and lose alike: the linkage sees no difference")}},
    [SIM_EFFECT_ROTARY_BIAS] = {SIM_EFFECT_ROTARY_BIAS,
                                "rotary_bias",
                                SIM_SCOPE_VEHICLE,
                                "002 s. 5.2",
                                "Linkage rotary encoder zero offsets: measured alpha/beta = true + bias (clapper; set: "
                                "alpha is the joint encoder)",
                                2,
                                {{"alpha_deg", "deg", SIM_PARAM_NUMBER, 0.0, -10.0, 10.0, NULL, "truck A encoder bias"},
                                 {"beta_deg", "deg", SIM_PARAM_NUMBER, 0.0, -10.0, 10.0, NULL, "truck B encoder bias"}},
                                .vehicles = TWO_TRUCKS,
                                .evidence = {YES, NO("needs linkage readings"), YES}},
    [SIM_EFFECT_LINK_BIAS] = {SIM_EFFECT_LINK_BIAS,
                              "link_bias",
                              SIM_SCOPE_VEHICLE,
                              "002 s. 5.2",
                              "Link-length bias: measured l = true l + const + ecc * (1 - cos(alpha - beta)) (clapper)",
                              2,
                              {{"const_mm", "mm", SIM_PARAM_NUMBER, 0.0, -50.0, 50.0, NULL, "constant bias"},
                               {"ecc_mm", "mm", SIM_PARAM_NUMBER, 0.0, -50.0, 50.0, NULL, "eccentric bias amplitude"}},
                              .vehicles = SIM_VEHICLE_BIT(SIM_VEHICLE_CLAPPER),
                              .evidence = {YES, NO("needs linkage readings"), YES}},
    [SIM_EFFECT_TIRE_COMPRESSION] =
        {SIM_EFFECT_TIRE_COMPRESSION,
         "tire_compression",
         SIM_SCOPE_TRUCK,
         "000 s. 2.2 a, 004 s. 3.2 a",
         "Load-dependent tyre radius: each radius shrinks by k * its wheel load; an off-centre load "
         "acts like an Ed, the mean like an Es",
         3,
         {{"k_mm_per_kg", "mm/kg", SIM_PARAM_NUMBER, 0.002, 0.0, 0.1, NULL, "radius loss per kg"},
          {"load_kg", "kg", SIM_PARAM_NUMBER, 100.0, 0.0, 2000.0, NULL, "load carried by the truck"},
          {"lateral_offset_mm", "mm", SIM_PARAM_NUMBER, 0.0, -500.0, 500.0, NULL,
           "centre of mass left (+) of the centre; must stay within b/2"}},
         .vehicles = SIM_VEHICLES_ALL,
         .evidence = {NO(TIRE_ALIAS), NO(TIRE_ALIAS), NO(TIRE_ALIAS)}},
    [SIM_EFFECT_SCRUB] =
        {SIM_EFFECT_SCRUB,
         "scrub",
         SIM_SCOPE_TRUCK,
         "000 s. 2.2 b (contact area, not point)",
         "Turn-radius-dependent wheelbase (tyre scrub): the heading change of the Ed/Eb/Es model times "
         "g = 1 - k m/v, v = |dL| + |dR|, m = 2 min(|dL|, |dR|) when both wheels roll one way (else 0): "
         "Eb on spot turns, b Eb / (1 - k (1 - b/(2R))) on an arc of radius R",
         1,
         {{"k", "1", SIM_PARAM_NUMBER, 0.0, -0.25, 0.25, NULL, "scrub coefficient"}},
         .vehicles = SIM_VEHICLES_ALL,
         .evidence = {YES, YES, WEAK("seen only through the trucks' heading difference on arcs")}},
};

const sim_effect_def_t *sim_effects_catalog(size_t *n)
{
    if (n != NULL) {
        *n = SIM_EFFECT_COUNT;
    }
    return catalog;
}

const sim_effect_def_t *sim_effect_find(const char *name)
{
    if (name == NULL) {
        return NULL;
    }
    for (size_t i = 0; i < SIM_EFFECT_COUNT; ++i) {
        if (strcmp(catalog[i].name, name) == 0) {
            return &catalog[i];
        }
    }
    return NULL;
}

int sim_effect_param_index(const sim_effect_def_t *e, const char *param)
{
    if (e == NULL || param == NULL) {
        return -1;
    }
    for (size_t i = 0; i < e->n_params; ++i) {
        if (strcmp(e->params[i].name, param) == 0) {
            return (int)i;
        }
    }
    return -1;
}

/* Index of `s` in a "a|b|c" choice list; -1 iff absent. */
static int choice_index(const char *choices, const char *s)
{
    const size_t n = strlen(s);
    int idx = 0;
    for (const char *p = choices; p != NULL; ++idx) {
        const char *bar = strchr(p, '|');
        const size_t len = bar != NULL ? (size_t)(bar - p) : strlen(p);
        if (len == n && strncmp(p, s, n) == 0) {
            return idx;
        }
        p = bar != NULL ? bar + 1 : NULL;
    }
    return -1;
}

/* The idx-th choice, copied into buf. */
static const char *choice_name(const char *choices, int idx, char *buf, size_t cap)
{
    const char *p = choices;
    for (int i = 0; i < idx && p != NULL; ++i) {
        p = strchr(p, '|');
        p = p != NULL ? p + 1 : NULL;
    }
    if (p == NULL) {
        snprintf(buf, cap, "?");
        return buf;
    }
    const char *bar = strchr(p, '|');
    const int len = bar != NULL ? (int)(bar - p) : (int)strlen(p);
    snprintf(buf, cap, "%.*s", len, p);
    return buf;
}

/* ---------------------------------------------------------------------------------------------
 * Catalog printers
 * ------------------------------------------------------------------------------------------- */
int sim_effects_write_json(FILE *out)
{
    json_t *root = json_object(), *arr = json_array();
    json_object_set_new(root, "effects", arr);
    for (size_t i = 0; i < SIM_EFFECT_COUNT; ++i) {
        const sim_effect_def_t *e = &catalog[i];
        json_t *je = json_object(), *jp = json_array();
        json_object_set_new(je, "name", json_string(e->name));
        json_object_set_new(je, "scope", json_string(e->scope == SIM_SCOPE_TRUCK ? "truck" : "vehicle"));
        json_object_set_new(je, "ref", json_string(e->ref));
        json_object_set_new(je, "doc", json_string(e->doc));
        for (size_t k = 0; k < e->n_params; ++k) {
            const sim_param_def_t *p = &e->params[k];
            json_t *o = json_object();
            json_object_set_new(o, "name", json_string(p->name));
            json_object_set_new(o, "unit", json_string(p->unit));
            if (p->kind == SIM_PARAM_ENUM) {
                char buf[32];
                json_t *ch = json_array();
                for (int c = 0; c <= (int)p->max; ++c) {
                    json_array_append_new(ch, json_string(choice_name(p->choices, c, buf, sizeof buf)));
                }
                json_object_set_new(o, "type", json_string("enum"));
                json_object_set_new(o, "choices", ch);
                json_object_set_new(o, "default", json_string(choice_name(p->choices, (int)p->def, buf, sizeof buf)));
            } else {
                json_object_set_new(o, "type", json_string("number"));
                json_object_set_new(o, "default", json_real(p->def));
                json_object_set_new(o, "min", json_real(p->min));
                json_object_set_new(o, "max", json_real(p->max));
            }
            json_object_set_new(o, "doc", json_string(p->doc));
            json_array_append_new(jp, o);
        }
        json_object_set_new(je, "params", jp);
        json_t *jv = json_array();
        for (unsigned v = 0; v < 3U; ++v) {
            if (e->vehicles & SIM_VEHICLE_BIT(v)) {
                json_array_append_new(jv, json_string(sim_vehicle_name((sim_vehicle_t)v)));
            }
        }
        json_object_set_new(je, "vehicles", jv);
        static const char *const mode_name[SIM_EVIDENCE_COUNT] = {"truth", "returns", "linkage"};
        static const char *const seen_name[3] = {"no", "weak", "yes"};
        json_t *jev = json_object();
        for (unsigned m = 0; m < (unsigned)SIM_EVIDENCE_COUNT; ++m) {
            json_t *o = json_object();
            json_object_set_new(o, "seen", json_string(seen_name[e->evidence[m].seen]));
            json_object_set_new(o, "why", e->evidence[m].why != NULL ? json_string(e->evidence[m].why) : json_null());
            json_object_set_new(jev, mode_name[m], o);
        }
        json_object_set_new(je, "evidence", jev);
        json_array_append_new(arr, je);
    }
    const int rc = json_dumpf(root, out, JSON_INDENT(2) | JSON_PRESERVE_ORDER);
    json_decref(root);
    if (rc != 0 || fputc('\n', out) == EOF) {
        return -1;
    }
    return ferror(out) ? -1 : 0;
}

/* Markdown cell text: a '|' would end the cell. */
static void md_cell(FILE *out, const char *s)
{
    for (; *s != '\0'; ++s) {
        if (*s == '|') {
            fputc('\\', out);
        }
        fputc(*s, out);
    }
}

int sim_effects_write_markdown(FILE *out)
{
    fprintf(out, "| effect | scope | parameter | unit | default | range | doc |\n");
    fprintf(out, "|---|---|---|---|---|---|---|\n");
    for (size_t i = 0; i < SIM_EFFECT_COUNT; ++i) {
        const sim_effect_def_t *e = &catalog[i];
        for (size_t k = 0; k < e->n_params; ++k) {
            const sim_param_def_t *p = &e->params[k];
            char def[32], range[64];
            if (p->kind == SIM_PARAM_ENUM) {
                choice_name(p->choices, (int)p->def, def, sizeof def);
                snprintf(range, sizeof range, "%s", p->choices);
                for (char *c = range; *c != '\0'; ++c) {
                    if (*c == '|') {
                        *c = '/';
                    }
                }
            } else {
                snprintf(def, sizeof def, "%g", p->def);
                snprintf(range, sizeof range, "[%g, %g]", p->min, p->max);
            }
            fprintf(out, "| %s | %s | `%s` | %s | %s | %s | ", k == 0 ? e->name : "",
                    k == 0 ? (e->scope == SIM_SCOPE_TRUCK ? "truck" : "vehicle") : "", p->name, p->unit, def, range);
            md_cell(out, k == 0 ? e->doc : p->doc);
            if (k == 0) {
                fputs(" (", out);
                md_cell(out, p->doc);
                fputc(')', out);
            }
            fputs(" |\n", out);
        }
    }
    return ferror(out) ? -1 : 0;
}

/* ---------------------------------------------------------------------------------------------
 * Scenario
 * ------------------------------------------------------------------------------------------- */
void sim_scenario_none(sim_scenario_t *sc)
{
    memset(sc, 0, sizeof *sc);
    sc->seed = 1U;
    for (size_t i = 0; i < SIM_EFFECT_COUNT; ++i) {
        for (unsigned t = 0; t < ODO_TRUCKS; ++t) {
            for (size_t k = 0; k < catalog[i].n_params; ++k) {
                sc->eff[i][t].p[k] = catalog[i].params[k].def;
            }
        }
    }
}

static const char *json_type_name(const json_t *v)
{
    switch (json_typeof(v)) {
    case JSON_OBJECT: return "an object";
    case JSON_ARRAY: return "an array";
    case JSON_STRING: return "a string";
    case JSON_INTEGER:
    case JSON_REAL: return "a number";
    case JSON_TRUE:
    case JSON_FALSE: return "a boolean";
    case JSON_NULL: return "null";
    }
    return "?";
}

static void known_params(const sim_effect_def_t *e, char *buf, size_t cap)
{
    size_t n = 0;
    buf[0] = '\0';
    for (size_t k = 0; k < e->n_params && n < cap; ++k) {
        int w = snprintf(buf + n, cap - n, "%s%s", k ? ", " : "", e->params[k].name);
        n += w > 0 ? (size_t)w : 0U;
    }
}

static void known_effects(char *buf, size_t cap)
{
    size_t n = 0;
    buf[0] = '\0';
    for (size_t i = 0; i < SIM_EFFECT_COUNT && n < cap; ++i) {
        int w = snprintf(buf + n, cap - n, "%s%s", i ? ", " : "", catalog[i].name);
        n += w > 0 ? (size_t)w : 0U;
    }
}

/* Check and store one parameter value (number or enum string). */
static int param_from_json(const sim_param_def_t *p, const json_t *v, double *out, const char *origin,
                           const char *where, char *err, size_t errlen)
{
    if (p->kind == SIM_PARAM_ENUM) {
        if (!json_is_string(v)) {
            return odo_errf_at(err, errlen, origin, where, "expected a string (%s), got %s", p->choices,
                               json_type_name(v));
        }
        const int idx = choice_index(p->choices, json_string_value(v));
        if (idx < 0) {
            return odo_errf_at(err, errlen, origin, where, "\"%s\" is not one of %s", json_string_value(v), p->choices);
        }
        *out = (double)idx;
        return 0;
    }
    if (!json_is_number(v)) {
        return odo_errf_at(err, errlen, origin, where, "expected a number (%s), got %s", p->unit, json_type_name(v));
    }
    const double x = json_number_value(v);
    if (!isfinite(x) || x < p->min || x > p->max) {
        return odo_errf_at(err, errlen, origin, where, "%g is out of range [%g, %g] %s", x, p->min, p->max, p->unit);
    }
    *out = x;
    return 0;
}

static int parse_truck(const json_t *v, bool allow_both, unsigned *mask, const char *origin, const char *where,
                       char *err, size_t errlen)
{
    const char *s = json_is_string(v) ? json_string_value(v) : NULL;
    if (s != NULL && strcmp(s, "A") == 0) {
        *mask = 1U;
    } else if (s != NULL && strcmp(s, "B") == 0) {
        *mask = 2U;
    } else if (allow_both && s != NULL && strcmp(s, "both") == 0) {
        *mask = 3U;
    } else {
        return odo_errf_at(err, errlen, origin, where, "expected \"A\", \"B\"%s, got %s%s%s",
                           allow_both ? " or \"both\"" : "", s ? "\"" : json_type_name(v), s ? s : "", s ? "\"" : "");
    }
    return 0;
}

static int parse_bump_list(const json_t *at, const char *prefix, double default_height, sim_scenario_t *sc,
                           const char *origin, char *err, size_t errlen)
{
    char where[160];
    snprintf(where, sizeof where, "%.140s.at", prefix);
    if (!json_is_array(at)) {
        return odo_errf_at(err, errlen, origin, where, "expected an array of {truck, wheel, distance_mm}, got %s",
                           json_type_name(at));
    }
    static const sim_param_def_t dist = {"distance_mm", "mm", SIM_PARAM_NUMBER, 0.0, 0.0, 1.0e7, NULL, ""};
    static const sim_param_def_t height = {"height_mm", "mm", SIM_PARAM_NUMBER, 10.0, 0.0, 50.0, NULL, ""};
    size_t i;
    json_t *item;
    json_array_foreach(at, i, item)
    {
        snprintf(where, sizeof where, "%.130s.at[%zu]", prefix, i);
        if (!json_is_object(item)) {
            return odo_errf_at(err, errlen, origin, where, "expected an object, got %s", json_type_name(item));
        }
        if (sc->n_bumps >= SIM_SCENARIO_MAX_BUMPS) {
            return odo_errf_at(err, errlen, origin, where, "more than %d bumps", SIM_SCENARIO_MAX_BUMPS);
        }
        sim_scenario_bump_t b = {0, 0, -1.0, default_height};
        bool have_truck = false, have_wheel = false;
        const char *key;
        json_t *v;
        json_object_foreach(item, key, v)
        {
            char w2[200];
            snprintf(w2, sizeof w2, "%.150s.%.40s", where, key);
            if (strcmp(key, "truck") == 0) {
                unsigned m = 0;
                if (parse_truck(v, false, &m, origin, w2, err, errlen) != 0) {
                    return -1;
                }
                b.truck = (uint8_t)(m == 1U ? ODO_TRUCK_A : ODO_TRUCK_B);
                have_truck = true;
            } else if (strcmp(key, "wheel") == 0) {
                const char *s = json_is_string(v) ? json_string_value(v) : NULL;
                if (s != NULL && strcmp(s, "left") == 0) {
                    b.wheel = ODO_LEFT;
                } else if (s != NULL && strcmp(s, "right") == 0) {
                    b.wheel = ODO_RIGHT;
                } else {
                    return odo_errf_at(err, errlen, origin, w2, "expected \"left\" or \"right\"");
                }
                have_wheel = true;
            } else if (strcmp(key, "distance_mm") == 0) {
                if (param_from_json(&dist, v, &b.distance_mm, origin, w2, err, errlen) != 0) {
                    return -1;
                }
            } else if (strcmp(key, "height_mm") == 0) {
                if (param_from_json(&height, v, &b.height_mm, origin, w2, err, errlen) != 0) {
                    return -1;
                }
            } else {
                return odo_errf_at(err, errlen, origin, w2,
                                   "unknown key (known: truck, wheel, distance_mm, height_mm)");
            }
        }
        if (!have_truck || !have_wheel || b.distance_mm < 0.0) {
            return odo_errf_at(err, errlen, origin, where, "needs truck, wheel and distance_mm");
        }
        sc->bump[sc->n_bumps++] = b;
    }
    return 0;
}

/* One effect instance (an object in "effects"). *covered accumulates the trucks already set. */
static int parse_instance(const sim_effect_def_t *e, const json_t *obj, const char *prefix, sim_scenario_t *sc,
                          unsigned *covered, const char *origin, char *err, size_t errlen)
{
    if (!json_is_object(obj)) {
        return odo_errf_at(err, errlen, origin, prefix, "expected an object of parameters, got %s",
                           json_type_name(obj));
    }
    sim_effect_setting_t s = sc->eff[e->id][0];
    s.enabled = true;
    unsigned mask = 3U;
    const json_t *at = NULL;
    const char *key;
    json_t *v;
    json_object_foreach((json_t *)obj, key, v)
    {
        char where[200];
        snprintf(where, sizeof where, "%.140s.%.50s", prefix, key);
        if (strcmp(key, "enabled") == 0) {
            if (!json_is_boolean(v)) {
                return odo_errf_at(err, errlen, origin, where, "expected true or false, got %s", json_type_name(v));
            }
            s.enabled = json_is_true(v);
        } else if (strcmp(key, "truck") == 0) {
            if (e->scope != SIM_SCOPE_TRUCK) {
                return odo_errf_at(err, errlen, origin, where, "'%s' is a vehicle effect: no truck selection", e->name);
            }
            if (parse_truck(v, true, &mask, origin, where, err, errlen) != 0) {
                return -1;
            }
        } else if (strcmp(key, "at") == 0 && e->id == SIM_EFFECT_BUMPS) {
            at = v;
        } else {
            const int k = sim_effect_param_index(e, key);
            if (k < 0) {
                char known[160];
                known_params(e, known, sizeof known);
                return odo_errf_at(err, errlen, origin, where, "unknown parameter of '%s' (known: %s%s, enabled%s)",
                                   e->name, known, e->scope == SIM_SCOPE_TRUCK ? ", truck" : "",
                                   e->id == SIM_EFFECT_BUMPS ? ", at" : "");
            }
            if (param_from_json(&e->params[k], v, &s.p[k], origin, where, err, errlen) != 0) {
                return -1;
            }
        }
    }
    for (unsigned t = 0; t < ODO_TRUCKS; ++t) {
        if ((mask & (1U << t)) == 0U) {
            continue;
        }
        if ((*covered & (1U << t)) != 0U) {
            return odo_errf_at(err, errlen, origin, prefix, "truck %c is set twice for '%s'", (char)('A' + t), e->name);
        }
        *covered |= 1U << t;
        sc->eff[e->id][t] = s;
    }
    if (at != NULL && parse_bump_list(at, prefix, s.p[SIM_P_BUMPS_HEIGHT], sc, origin, err, errlen) != 0) {
        return -1;
    }
    return 0;
}

static int parse_root(const json_t *root, const char *origin, sim_scenario_t *sc, char *err, size_t errlen)
{
    sim_scenario_none(sc);
    if (!json_is_object(root)) {
        return odo_errf_at(err, errlen, origin, NULL, "a scenario is a JSON object, got %s", json_type_name(root));
    }
    const char *key;
    json_t *v;
    json_object_foreach((json_t *)root, key, v)
    {
        if (strcmp(key, "description") != 0 && strcmp(key, "seed") != 0 && strcmp(key, "bump_model") != 0 &&
            strcmp(key, "effects") != 0) {
            return odo_errf_at(err, errlen, origin, key, "unknown key (known: description, seed, bump_model, effects)");
        }
    }
    const json_t *d = json_object_get(root, "description");
    if (d != NULL) {
        if (!json_is_string(d)) {
            return odo_errf_at(err, errlen, origin, "description", "expected a string, got %s", json_type_name(d));
        }
        snprintf(sc->description, sizeof sc->description, "%s", json_string_value(d));
    }
    const json_t *seed = json_object_get(root, "seed");
    if (seed != NULL) {
        if (!json_is_integer(seed) || json_integer_value(seed) < 0) {
            return odo_errf_at(err, errlen, origin, "seed", "expected a non-negative integer, got %s",
                               json_type_name(seed));
        }
        sc->seed = (uint64_t)json_integer_value(seed);
        sc->has_seed = true;
    }
    const json_t *bm = json_object_get(root, "bump_model");
    if (bm != NULL) {
        sim_bump_model_t m;
        if (!json_is_string(bm) || !sim_bump_model_parse(json_string_value(bm), &m)) {
            return odo_errf_at(err, errlen, origin, "bump_model", "expected \"paper\" or \"exact\"");
        }
        for (unsigned t = 0; t < ODO_TRUCKS; ++t) {
            sc->eff[SIM_EFFECT_BUMPS][t].p[SIM_P_BUMPS_MODEL] = (double)m;
            sc->eff[SIM_EFFECT_ROUGHNESS][t].p[SIM_P_ROUGH_MODEL] = (double)m;
        }
    }
    const json_t *effects = json_object_get(root, "effects");
    if (effects == NULL) {
        return odo_errf_at(err, errlen, origin, NULL, "missing \"effects\" (use {} for none)");
    }
    if (!json_is_object(effects)) {
        return odo_errf_at(err, errlen, origin, "effects", "expected an object, got %s", json_type_name(effects));
    }
    json_object_foreach((json_t *)effects, key, v)
    {
        char prefix[160];
        snprintf(prefix, sizeof prefix, "effects.%.100s", key);
        const sim_effect_def_t *e = sim_effect_find(key);
        if (e == NULL) {
            char known[256];
            known_effects(known, sizeof known);
            return odo_errf_at(err, errlen, origin, prefix, "unknown effect (known: %s)", known);
        }
        unsigned covered = 0U;
        if (json_is_array(v)) {
            if (e->scope == SIM_SCOPE_VEHICLE) {
                return odo_errf_at(err, errlen, origin, prefix, "'%s' is a vehicle effect: give one object", e->name);
            }
            size_t i;
            json_t *item;
            json_array_foreach(v, i, item)
            {
                char p2[180];
                snprintf(p2, sizeof p2, "%.120s[%zu]", prefix, i);
                if (parse_instance(e, item, p2, sc, &covered, origin, err, errlen) != 0) {
                    return -1;
                }
            }
        } else if (parse_instance(e, v, prefix, sc, &covered, origin, err, errlen) != 0) {
            return -1;
        }
    }
    return 0;
}

static int parse_loaded(json_t *root, const json_error_t *jerr, const char *origin, sim_scenario_t *sc, char *err,
                        size_t errlen)
{
    if (root == NULL) {
        return odo_errf_at(err, errlen, origin, NULL, "malformed JSON at line %d column %d: %s", jerr->line,
                           jerr->column, jerr->text);
    }
    const int rc = parse_root(root, origin, sc, err, errlen);
    json_decref(root);
    return rc;
}

int sim_scenario_parse_string(const char *json, const char *origin, sim_scenario_t *sc, char *err, size_t errlen)
{
    json_error_t jerr;
    if (origin == NULL) {
        origin = "<string>";
    }
    if (json == NULL || sc == NULL) {
        return odo_errf_at(err, errlen, origin, NULL, "no input");
    }
    return parse_loaded(json_loads(json, JSON_REJECT_DUPLICATES, &jerr), &jerr, origin, sc, err, errlen);
}

int sim_scenario_parse_file(const char *path, sim_scenario_t *sc, char *err, size_t errlen)
{
    if (path == NULL || sc == NULL) {
        return odo_errf_at(err, errlen, "<scenario>", NULL, "no file given");
    }
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        return odo_errf_at(err, errlen, path, NULL, "cannot open scenario: %s", strerror(errno));
    }
    json_error_t jerr;
    json_t *root = json_loadf(f, JSON_REJECT_DUPLICATES, &jerr);
    fclose(f);
    return parse_loaded(root, &jerr, path, sc, err, errlen);
}

int sim_scenario_set(sim_scenario_t *sc, const char *effect, const char *param, unsigned truck_mask, double value,
                     char *err, size_t errlen)
{
    const sim_effect_def_t *e = sim_effect_find(effect);
    if (e == NULL) {
        char known[256];
        known_effects(known, sizeof known);
        return odo_errf_at(err, errlen, "scenario", effect, "unknown effect (known: %s)", known);
    }
    int k = -1;
    if (param != NULL) {
        k = sim_effect_param_index(e, param);
        if (k < 0) {
            char known[160];
            known_params(e, known, sizeof known);
            return odo_errf_at(err, errlen, "scenario", effect, "unknown parameter '%s' (known: %s)", param, known);
        }
        const sim_param_def_t *p = &e->params[k];
        if (!isfinite(value) || value < p->min || value > p->max ||
            (p->kind == SIM_PARAM_ENUM && value != floor(value))) {
            return odo_errf_at(err, errlen, "scenario", effect, "%s = %g is out of range [%g, %g] %s", param, value,
                               p->min, p->max, p->unit);
        }
    }
    if (e->scope == SIM_SCOPE_VEHICLE) {
        truck_mask = 3U;
    }
    for (unsigned t = 0; t < ODO_TRUCKS; ++t) {
        if ((truck_mask & (1U << t)) != 0U) {
            sc->eff[e->id][t].enabled = true;
            if (k >= 0) {
                sc->eff[e->id][t].p[k] = value;
            }
        }
    }
    return 0;
}

bool sim_scenario_enabled_on(const sim_scenario_t *sc, sim_effect_id_t id, unsigned truck)
{
    return (unsigned)id < SIM_EFFECT_COUNT && truck < ODO_TRUCKS && sc->eff[id][truck].enabled;
}

bool sim_scenario_enabled(const sim_scenario_t *sc, sim_effect_id_t id)
{
    return sim_scenario_enabled_on(sc, id, 0U) || sim_scenario_enabled_on(sc, id, 1U);
}

void sim_scenario_enabled_list(const sim_scenario_t *sc, bool out[SIM_EFFECT_COUNT])
{
    for (size_t i = 0; i < SIM_EFFECT_COUNT; ++i) {
        out[i] = sim_scenario_enabled(sc, (sim_effect_id_t)i);
    }
}

double sim_scenario_param(const sim_scenario_t *sc, sim_effect_id_t id, unsigned truck, size_t param)
{
    if ((unsigned)id >= SIM_EFFECT_COUNT || truck >= ODO_TRUCKS || param >= catalog[id].n_params) {
        return NAN;
    }
    return sc->eff[id][truck].p[param];
}

double sim_scenario_param_named(const sim_scenario_t *sc, const char *effect, const char *param, unsigned truck)
{
    const sim_effect_def_t *e = sim_effect_find(effect);
    const int k = sim_effect_param_index(e, param);
    if (e == NULL || k < 0) {
        return NAN;
    }
    return sim_scenario_param(sc, e->id, truck, (size_t)k);
}
