/// libodosim (host_sim/include/odosim/odosim.h) over the SIL runner.
#include "odosim/odosim.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "effects.h"
#include "odo_robot.h"
#include "ratelimit.h"
#include "sil.h"
#include "world.h"

struct odosim_setup {
    sim_robot_t robot;
    sim_scenario_t scenario;
};

int odosim_api_version(void) { return ODOSIM_API_VERSION; }

odosim_setup_t *odosim_setup_load(const char *robot_path, const char *scenario_path, char *err, size_t errlen)
{
    odosim_setup_t *s = calloc(1, sizeof *s);
    if (s == NULL) {
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    if (sim_robot_parse_file(robot_path, &s->robot, err, errlen) != 0 ||
        sim_scenario_parse_file(scenario_path, &s->scenario, err, errlen) != 0) {
        free(s);
        return NULL;
    }
    return s;
}

odosim_setup_t *odosim_setup_parse(const char *robot_json, const char *scenario_json, char *err, size_t errlen)
{
    odosim_setup_t *s = calloc(1, sizeof *s);
    if (s == NULL) {
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    if (sim_robot_parse_string(robot_json, "<robot>", &s->robot, err, errlen) != 0 ||
        sim_scenario_parse_string(scenario_json, "<scenario>", &s->scenario, err, errlen) != 0) {
        free(s);
        return NULL;
    }
    return s;
}

int odosim_setup_set(odosim_setup_t *s, const char *effect, const char *param, unsigned truck_mask, double value,
                     char *err, size_t errlen)
{
    return sim_scenario_set(&s->scenario, effect, param, truck_mask, value, err, errlen);
}

void odosim_setup_clear(odosim_setup_t *s)
{
    const uint64_t seed = s->scenario.seed;
    sim_scenario_none(&s->scenario);
    s->scenario.seed = seed;
}

void odosim_setup_free(odosim_setup_t *s) { free(s); }

uint64_t odosim_run_seed(uint64_t base_seed, int ccw, unsigned run) { return sim_run_seed(base_seed, ccw, run); }

typedef struct {
    odosim_tick_row_t *rows;
    size_t capacity;
    size_t n;
} collect_t;

static void collect(void *user, const sim_tick_t *tk)
{
    collect_t *c = user;
    if (c->rows != NULL && c->n < c->capacity) {
        odosim_tick_row_t *r = &c->rows[c->n];
        memset(r, 0, sizeof *r);
        r->t_s = tk->t_s;
        for (unsigned t = 0; t < 2; ++t) {
            const odo_pose_t *p = &tk->output->pose[t];
            r->truth[t][0] = tk->truth[t].x_mm;
            r->truth[t][1] = tk->truth[t].y_mm;
            r->truth[t][2] = tk->truth[t].theta_rad;
            r->est[t][0] = (double)p->x_mm_q32 / 4294967296.0;
            r->est[t][1] = (double)p->y_mm_q32 / 4294967296.0;
            r->est[t][2] = (double)(int32_t)odo_heading_bam(p) * (M_PI / 2147483648.0);
            r->counts[t][0] = tk->input->wheel[t].left_raw;
            r->counts[t][1] = tk->input->wheel[t].right_raw;
        }
        r->link[0] = tk->link.alpha_rad;
        r->link[1] = tk->link.beta_rad;
        r->link[2] = tk->link.length_mm;
        r->faults = tk->output->faults;
        r->bump_events = (uint32_t)tk->n_events;
    }
    c->n++;
}

/// The run's return errors as the C API reports them.
static void fill_result(odosim_result_t *result, const sim_return_t *ret, size_t n_ticks)
{
    memset(result, 0, sizeof *result);
    result->x_abs_mm = ret->x_abs_mm;
    result->y_abs_mm = ret->y_abs_mm;
    result->theta_abs_deg = ret->theta_abs_deg;
    result->x_calc_mm = ret->x_calc_mm;
    result->y_calc_mm = ret->y_calc_mm;
    result->theta_calc_deg = ret->theta_calc_deg;
    result->ex_mm = ret->ex_mm;
    result->ey_mm = ret->ey_mm;
    result->etheta_deg = ret->etheta_deg;
    result->t_end_s = ret->t_end_s;
    result->n_ticks = n_ticks;
}

/// ipec: 0 off, 1 the paper's per-tick form, 2 the sub-resolution estimator (sil.h).
static int check_ipec(int ipec, char *err, size_t errlen)
{
    if (ipec < 0 || ipec > 2) {
        snprintf(err, errlen, "ipec must be 0 (off), 1 (paper) or 2 (estimator), not %d", ipec);
        return -1;
    }
    return 0;
}

int odosim_run(const odosim_setup_t *s, const char *experiment, int ccw, int bumps, int ipec, uint64_t seed,
               unsigned run_index, odosim_tick_row_t *rows, size_t capacity, odosim_result_t *result, char *err,
               size_t errlen)
{
    if (s == NULL || experiment == NULL || result == NULL) {
        snprintf(err, errlen, "NULL argument");
        return -1;
    }
    if (check_ipec(ipec, err, errlen) != 0) {
        return -1;
    }
    const sim_run_config_t cfg = {.robot = &s->robot,
                                  .scenario = &s->scenario,
                                  .experiment = experiment,
                                  .ccw = ccw ? 1 : 0,
                                  .bumps = bumps,
                                  .bump_height_mm = 10.0,
                                  .ipec = ipec,
                                  .seed = seed,
                                  .run_index = run_index};
    collect_t c = {rows, capacity, 0};
    sim_return_t ret;
    if (sim_run(&cfg, collect, &c, &ret, err, errlen) != 0) {
        return -1;
    }
    fill_result(result, &ret, c.n);
    return 0;
}

typedef struct {
    odosim_tick_row_ex_t *rows;
    size_t capacity, n;
    odosim_event_t *ev;
    size_t ev_capacity, n_ev;
} collect_ex_t;

static void collect_ex(void *user, const sim_tick_t *tk)
{
    collect_ex_t *c = user;
    for (size_t i = 0; i < tk->n_events; ++i, c->n_ev++) {
        if (c->ev != NULL && c->n_ev < c->ev_capacity) {
            const sim_bump_event_t *e = &tk->events[i];
            c->ev[c->n_ev] =
                (odosim_event_t){e->t_s, e->x_mm, e->y_mm, e->height_mm, e->at_distance_mm, e->truck, e->wheel};
        }
    }
    if (c->rows != NULL && c->n < c->capacity) {
        odosim_tick_row_ex_t *r = &c->rows[c->n];
        memset(r, 0, sizeof *r);
        r->t_s = tk->t_s;
        r->t_us = tk->input->t_us;
        for (unsigned t = 0; t < 2; ++t) {
            r->truth[t][0] = tk->truth[t].x_mm;
            r->truth[t][1] = tk->truth[t].y_mm;
            r->truth[t][2] = tk->truth[t].theta_rad;
            r->counts[t][0] = tk->input->wheel[t].left_raw;
            r->counts[t][1] = tk->input->wheel[t].right_raw;
            r->wheel_seq[t] = tk->input->wheel[t].seq;
            r->wheel_status[t] = tk->input->wheel[t].status;
            r->wheel_present[t] = tk->input->wheel[t].present ? 1U : 0U;
        }
        r->link_true[0] = tk->link.alpha_rad;
        r->link_true[1] = tk->link.beta_rad;
        r->link_true[2] = tk->link.length_mm;
        const odo_link_input_t *l = &tk->input->link;
        r->rotary_present = l->rotary_present ? 1U : 0U;
        r->linear_present = l->linear_present ? 1U : 0U;
        r->rotary_status = l->rotary_status;
        r->linear_status = l->linear_status;
        r->rotary_seq = l->rotary_seq;
        r->linear_seq = l->linear_seq;
        r->alpha_bam16 = l->alpha_bam16;
        r->beta_bam16 = l->beta_bam16;
        r->length_um = l->length_um;
        r->n_events = (uint32_t)tk->n_events;
    }
    c->n++;
}

int odosim_run_ex(const odosim_setup_t *s, const odosim_run_opts_t *o, odosim_tick_row_ex_t *rows, size_t capacity,
                  odosim_event_t *events, size_t ev_capacity, size_t *n_events, odosim_result_t *result, char *err,
                  size_t errlen)
{
    if (s == NULL || o == NULL || o->experiment == NULL || result == NULL) {
        snprintf(err, errlen, "NULL argument");
        return -1;
    }
    if (check_ipec(o->ipec, err, errlen) != 0) {
        return -1;
    }
    const sim_hidden_t hidden = {o->motor_tau_s, o->diam_var_amp, o->diam_var_period_s, o->diam_drift_per_s,
                                 o->backlash_rad};
    const sim_run_config_t cfg = {.robot = &s->robot,
                                  .scenario = &s->scenario,
                                  .experiment = o->experiment,
                                  .ccw = o->ccw ? 1 : 0,
                                  .bumps = o->bumps,
                                  .bump_height_mm = o->bump_height_mm > 0.0 ? o->bump_height_mm : 10.0,
                                  .ipec = o->ipec,
                                  .seed = o->seed,
                                  .run_index = o->run_index,
                                  .physics_dt_s = o->physics_dt_s,
                                  .hidden = &hidden};
    collect_ex_t c = {rows, capacity, 0, events, ev_capacity, 0};
    sim_return_t ret;
    if (sim_run(&cfg, collect_ex, &c, &ret, err, errlen) != 0) {
        return -1;
    }
    fill_result(result, &ret, c.n);
    if (n_events != NULL) {
        *n_events = c.n_ev;
    }
    return 0;
}

char *odosim_effects_json(void)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    if (f == NULL) {
        return NULL;
    }
    const int rc = sim_effects_write_json(f);
    if (fclose(f) != 0 || rc != 0) {
        free(buf);
        return NULL;
    }
    return buf;
}

size_t odosim_sizeof(const char *type_name)
{
    static const struct {
        const char *name;
        size_t size;
    } sizes[] = {
        {"odosim_tick_row_t", sizeof(odosim_tick_row_t)}, {"odosim_tick_row_ex_t", sizeof(odosim_tick_row_ex_t)},
        {"odosim_event_t", sizeof(odosim_event_t)},       {"odosim_result_t", sizeof(odosim_result_t)},
        {"odosim_run_opts_t", sizeof(odosim_run_opts_t)},
    };
    if (type_name == NULL) {
        return 0;
    }
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; ++i) {
        if (strcmp(sizes[i].name, type_name) == 0) {
            return sizes[i].size;
        }
    }
    return 0;
}

void odosim_free(void *p) { free(p); }

long odosim_link_clamp(const double *rel, size_t n, double lo_mm, double hi_mm, const unsigned char *gate, double *push)
{
    return sim_link_clamp_track(rel, n, lo_mm, hi_mm, gate, push);
}

int odosim_rate_limit(const double *v, const double *lim, size_t n, double *out)
{
    return sim_rate_limit(v, lim, n, out);
}

int odosim_rate_limit_2d(const double *vx, const double *vy, const double *lim, size_t n, double *ox, double *oy)
{
    return sim_rate_limit_2d(vx, vy, lim, n, ox, oy);
}

int odosim_rate_limit_track(const double *pose, size_t n, const double *dt, double acc, double *out)
{
    return sim_rate_limit_track(pose, n, dt, acc, out);
}
