/// The C tools' API (host_sim/include/odosim/odosim_sil.h) over the SIL runner (sil.h).
#include "odosim/odosim_sil.h"

#include <stdlib.h>
#include <string.h>

#include "effects.h"
#include "program.h"
#include "sil.h"
#include "summary.h"

/* odosim_sil.h states the program's bump limit; C99 has no _Static_assert, so a mismatch is a
 * negative array size. */
typedef char odosim_max_bumps_matches[(ODOSIM_MAX_BUMPS == SIM_PROGRAM_MAX_BUMPS) ? 1 : -1];

struct odosim_scenario {
    sim_scenario_t sc;
};

odosim_scenario_t *odosim_scenario_new(void)
{
    odosim_scenario_t *s = calloc(1, sizeof *s);
    if (s != NULL) {
        sim_scenario_none(&s->sc);
    }
    return s;
}

int odosim_scenario_load(odosim_scenario_t *sc, const char *path, char *err, size_t errlen)
{
    odosim_scenario_t *tmp = odosim_scenario_new();
    if (tmp == NULL) {
        snprintf(err, errlen, "out of memory");
        return -1;
    }
    const int rc = sim_scenario_parse_file(path, &tmp->sc, err, errlen);
    if (rc == 0) {
        sc->sc = tmp->sc;
    }
    free(tmp);
    return rc;
}

int odosim_scenario_set(odosim_scenario_t *sc, const char *effect, const char *param, unsigned truck_mask, double value,
                        char *err, size_t errlen)
{
    return sim_scenario_set(&sc->sc, effect, param, truck_mask, value, err, errlen);
}

void odosim_scenario_clear(odosim_scenario_t *sc)
{
    const uint64_t seed = sc->sc.seed;
    sim_scenario_none(&sc->sc);
    sc->sc.seed = seed;
}

uint64_t odosim_scenario_seed(const odosim_scenario_t *sc) { return sc->sc.seed; }

void odosim_scenario_set_seed(odosim_scenario_t *sc, uint64_t seed) { sc->sc.seed = seed; }

void odosim_scenario_free(odosim_scenario_t *sc) { free(sc); }

typedef struct {
    odosim_tick_fn fn;
    void *user;
    odosim_event_t events[SIM_WORLD_MAX_EVENTS];
} trampoline_t;

static void on_sim_tick(void *user, const sim_tick_t *tk)
{
    trampoline_t *t = user;
    odosim_tick_t out;
    memset(&out, 0, sizeof out);
    out.t_s = tk->t_s;
    out.tick = tk->tick;
    for (unsigned k = 0; k < ODO_TRUCKS; ++k) {
        out.truth[k] = (odosim_pose_t){tk->truth[k].x_mm, tk->truth[k].y_mm, tk->truth[k].theta_rad};
    }
    out.link = (odosim_link_geom_t){tk->link.theta_l_rad, tk->link.alpha_rad, tk->link.beta_rad, tk->link.length_mm};
    out.input = tk->input;
    out.output = tk->output;
    /* The world keeps at most SIM_WORLD_MAX_EVENTS events in all, so one tick never has more. */
    const size_t n = tk->n_events < SIM_WORLD_MAX_EVENTS ? tk->n_events : SIM_WORLD_MAX_EVENTS;
    for (size_t i = 0; i < n; ++i) {
        const sim_bump_event_t *e = &tk->events[i];
        t->events[i] = (odosim_event_t){e->t_s, e->x_mm, e->y_mm, e->height_mm, e->at_distance_mm, e->truck, e->wheel};
    }
    out.events = t->events;
    out.n_events = n;
    t->fn(t->user, &out);
}

int odosim_sil_run(const odosim_sil_config_t *cfg, odosim_tick_fn on_tick, void *user, odosim_return_t *ret, char *err,
                   size_t errlen)
{
    const sim_run_config_t c = {
        .robot = cfg->robot,
        .scenario = &cfg->scenario->sc,
        .experiment = cfg->experiment,
        .ccw = cfg->ccw,
        .bumps = cfg->bumps,
        .bump_height_mm = cfg->bump_height_mm,
        .ipec = cfg->ipec,
        .seed = cfg->seed,
        .run_index = cfg->run_index,
        .physics_dt_s = cfg->physics_dt_s,
        .hidden = NULL,
    };
    if (on_tick == NULL) {
        return sim_run(&c, NULL, NULL, ret, err, errlen);
    }
    trampoline_t *t = malloc(sizeof *t);
    if (t == NULL) {
        snprintf(err, errlen, "out of memory");
        return -1;
    }
    t->fn = on_tick;
    t->user = user;
    const int rc = sim_run(&c, on_sim_tick, t, ret, err, errlen);
    free(t);
    return rc;
}

void odosim_summarise(const odosim_return_t *runs, size_t n, odosim_summary_t *out) { sim_summarise(runs, n, out); }

const char *const *odosim_experiment_names(void) { return sim_experiment_names; }

int odosim_effects_write_json(FILE *out) { return sim_effects_write_json(out); }

int odosim_effects_write_markdown(FILE *out) { return sim_effects_write_markdown(out); }
