/// Recorded runs for `odo-calib fit` (fit_data.h).
#include "fit_data.h"
#include "odo_err.h"

#include <errno.h>
#include <fnmatch.h>
#include <glob.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hal_log.h"
#include "odo/odo_odometry.h"
#include "replay.h"
#include "odo_robot.h"

/* ---------------------------------------------------------------------------------------------
 * Counts: the log through the firmware's tick assembler; the deltas the firmware's odometry
 * step accepts (odo_truck_step on a shadow truck with the app's own model).
 * ------------------------------------------------------------------------------------------- */
typedef struct {
    fit_run_t *run;
    size_t cap;
    odo_truck_t shadow;
    int oom;
    int have_seq;
    uint8_t last_seq;
} collect_t;

static void on_tick(void *user, replay_t *r, uint64_t tick, const odo_tick_input_t *in, const odo_tick_output_t *out)
{
    (void)out;
    collect_t *c = user;
    fit_run_t *run = c->run;
    if (run->n == c->cap) {
        const size_t cap = c->cap ? 2 * c->cap : 4096;
        double *t = realloc(run->t_s, cap * sizeof *t);
        if (t != NULL) {
            run->t_s = t;
        }
        int32_t(*d)[2] = realloc(run->delta, cap * sizeof *d);
        if (d != NULL) {
            run->delta = d;
        }
        if (t == NULL || d == NULL) {
            c->oom = 1;
            return;
        }
        c->cap = cap;
    }
    odo_step_t st;
    memset(&st, 0, sizeof st);
    if (in->wheel[0].present) {
        /* ticks since the previous sample, from the sender's sequence number as the app takes it */
        const uint32_t skip = c->have_seq ? (uint32_t)(uint8_t)(in->wheel[0].seq - c->last_seq) : 1U;
        c->have_seq = 1;
        c->last_seq = in->wheel[0].seq;
        odo_truck_step(&c->shadow, &r->app.model[0], in->wheel[0].left_raw, in->wheel[0].right_raw, in->wheel[0].bits,
                       skip == 0U ? 1U : skip, &st);
    }
    /* on the log's clock (tick 0 at its first frame), the clock the truth CSV beside it uses */
    run->t_s[run->n] = (double)r->origin_us * 1e-6 + (double)tick * (double)r->tick_us * 1e-6;
    run->delta[run->n][0] = st.delta[0];
    run->delta[run->n][1] = st.delta[1];
    run->n++;
}

static int load_counts(fit_run_t *run, const odo_params_t *p, uint64_t *fd_skipped, char *err, size_t errlen)
{
    static replay_t rp; /* large; one at a time */
    collect_t c;
    memset(&c, 0, sizeof c);
    c.run = run;
    const odo_pose_t origin = {0, 0, 0};
    odo_truck_reset(&c.shadow, &origin);
    if (replay_init(&rp, p, on_tick, &c) != ODO_PARAMS_OK) {
        return odo_errf(err, errlen, "%s: the robot's parameter block does not boot the firmware", run->log_path);
    }
    hal_log_t lg;
    if (hal_log_open(&lg, run->log_path) != 0) {
        return odo_errf(err, errlen, "%s", lg.err);
    }
    candump_line_t l;
    hal_log_status_t st;
    while ((st = hal_log_next(&lg, &l)) == HAL_LOG_FRAME) {
        replay_push(&rp, &l.frame, l.t_us);
    }
    *fd_skipped += lg.stats.fd_skipped;
    if (st == HAL_LOG_ERROR) {
        odo_errf(err, errlen, "%s", lg.err);
        hal_log_close(&lg);
        return -1;
    }
    hal_log_close(&lg);
    replay_finish(&rp);
    if (c.oom) {
        return odo_errf(err, errlen, "%s: out of memory", run->log_path);
    }
    if (rp.stats.sensor_frames == 0 || run->n < 2) {
        return odo_errf(err, errlen, "%s: no WHEEL_COUNTS_A frames (a log of another robot or no sensor log)",
                        run->log_path);
    }
    if (rp.stats.time_backwards != 0) {
        return odo_errf(err, errlen, "%s: time goes backwards in the log (%llu frames)", run->log_path,
                        (unsigned long long)rp.stats.time_backwards);
    }
    return 0;
}

/* ---------------------------------------------------------------------------------------------
 * Truth track: t_s,a_x_mm,a_y_mm,a_theta_deg (extra columns ignored), interpolated to the ticks.
 * ------------------------------------------------------------------------------------------- */
static int load_track(fit_run_t *run, const char *path, char *err, size_t errlen)
{
    FILE *f = fopen(path, "r");
    if (f == NULL) {
        return odo_errf(err, errlen, "%s: cannot open: %s", path, strerror(errno));
    }
    size_t cap = 4096, n = 0;
    double *a = malloc(cap * 4 * sizeof *a);
    char line[1024];
    unsigned ln = 0;
    int rc = 0;
    while (a != NULL && fgets(line, sizeof line, f) != NULL) {
        ln++;
        if (ln == 1) {
            if (strncmp(line, "t_s,a_x_mm,a_y_mm,a_theta_deg", 29) != 0) {
                rc = odo_errf(err, errlen, "%s:1: expected a header starting t_s,a_x_mm,a_y_mm,a_theta_deg", path);
                break;
            }
            continue;
        }
        if (line[0] == '\n' || line[0] == '\0') {
            continue;
        }
        double v[4];
        char *s = line, *e = NULL;
        for (int k = 0; k < 4 && rc == 0; ++k) {
            errno = 0;
            v[k] = strtod(s, &e);
            if (e == s || errno != 0 || !isfinite(v[k]) ||
                (*e != ',' && !(k == 3 && (*e == '\n' || *e == '\r' || *e == '\0')))) {
                rc = odo_errf(err, errlen, "%s:%u: field %d is not a finite number", path, ln, k + 1);
            }
            s = e + 1;
        }
        if (rc != 0) {
            break;
        }
        if (n > 0 && !(v[0] > a[4 * (n - 1)])) {
            rc = odo_errf(err, errlen, "%s:%u: time %.6g does not increase (time goes backwards)", path, ln, v[0]);
            break;
        }
        if (n == cap) {
            cap *= 2;
            double *b = realloc(a, cap * 4 * sizeof *a);
            if (b == NULL) {
                break;
            }
            a = b;
        }
        memcpy(&a[4 * n], v, sizeof v);
        n++;
    }
    fclose(f);
    if (a == NULL) {
        return odo_errf(err, errlen, "%s: out of memory", path);
    }
    if (rc == 0 && n < 2) {
        rc = odo_errf(err, errlen, "%s: fewer than 2 truth samples", path);
    }
    if (rc == 0) {
        const double t_end = run->t_s[run->n - 1], tick = run->n > 1 ? run->t_s[1] - run->t_s[0] : 0.0;
        if (a[0] > run->t_s[0] + 0.5 * tick || a[4 * (n - 1)] < t_end - 0.5 * tick) {
            rc = odo_errf(err, errlen,
                          "%s: the truth track covers %.3f-%.3f s but the log %s has %zu ticks over %.3f-%.3f s "
                          "(mismatched ticks/truth lengths)",
                          path, a[0], a[4 * (n - 1)], run->log_path, run->n, run->t_s[0], t_end);
        }
    }
    if (rc == 0) {
        run->tx_mm = malloc(run->n * sizeof(double));
        run->ty_mm = malloc(run->n * sizeof(double));
        run->tth_rad = malloc(run->n * sizeof(double));
        if (run->tx_mm == NULL || run->ty_mm == NULL || run->tth_rad == NULL) {
            rc = odo_errf(err, errlen, "%s: out of memory", path);
        }
    }
    if (rc == 0) {
        /* Unwrap the heading, then interpolate linearly (the ticks are at most half a sample off). */
        double prev = 0.0, off = 0.0;
        for (size_t i = 0; i < n; ++i) {
            double th = a[4 * i + 3] * M_PI / 180.0 + off;
            if (i > 0) {
                while (th - prev > M_PI) {
                    th -= 2 * M_PI;
                    off -= 2 * M_PI;
                }
                while (th - prev < -M_PI) {
                    th += 2 * M_PI;
                    off += 2 * M_PI;
                }
            }
            a[4 * i + 3] = prev = th;
        }
        size_t j = 0;
        for (size_t i = 0; i < run->n; ++i) {
            const double t = run->t_s[i];
            while (j + 2 < n && a[4 * (j + 1)] < t) {
                j++;
            }
            double w = (t - a[4 * j]) / (a[4 * (j + 1)] - a[4 * j]);
            w = w < 0.0 ? 0.0 : (w > 1.0 ? 1.0 : w);
            run->tx_mm[i] = a[4 * j + 1] + w * (a[4 * (j + 1) + 1] - a[4 * j + 1]);
            run->ty_mm[i] = a[4 * j + 2] + w * (a[4 * (j + 1) + 2] - a[4 * j + 2]);
            run->tth_rad[i] = a[4 * j + 3] + w * (a[4 * (j + 1) + 3] - a[4 * j + 3]);
        }
        run->has_track = true;
    }
    free(a);
    return rc;
}

/* returns.csv rows: run,direction,x_abs_mm,y_abs_mm,theta_abs_deg,... -> the run named
 * run-<direction>-<NN>. Only the absolute (true) columns are used. */
static int load_return(fit_run_t *run, const char *path, const char *dir_word, unsigned idx, char *err, size_t errlen)
{
    FILE *f = fopen(path, "r");
    if (f == NULL) {
        return 1; /* no returns.csv: not an error, the run just has no return pose */
    }
    char line[1024];
    unsigned ln = 0;
    int rc = 1;
    while (fgets(line, sizeof line, f) != NULL) {
        ln++;
        if (ln == 1) {
            if (strncmp(line, "run,direction,x_abs_mm,y_abs_mm,theta_abs_deg", 45) != 0) {
                rc = odo_errf(err, errlen, "%s:1: expected the returns.csv header (run,direction,x_abs_mm,...)", path);
                break;
            }
            continue;
        }
        unsigned r = 0;
        char d[16];
        double x, y, th;
        if (sscanf(line, "%u,%15[a-z],%lf,%lf,%lf", &r, d, &x, &y, &th) != 5 || !isfinite(x) || !isfinite(y) ||
            !isfinite(th)) {
            if (line[0] != '\n' && line[0] != '#') {
                rc = odo_errf(err, errlen, "%s:%u: malformed row", path, ln);
                break;
            }
            continue;
        }
        if (r == idx && strcmp(d, dir_word) == 0) {
            run->ret[0] = x;
            run->ret[1] = y;
            run->ret[2] = th * M_PI / 180.0;
            run->has_return = true;
            rc = 0;
        }
    }
    fclose(f);
    return rc < 0 ? -1 : 0;
}

/* robot.json beside the runs must describe the robot given to the fit: same parameter block. */
static int check_robot(const char *dir, const char *robot_path, const odo_params_t *p, char *err, size_t errlen)
{
    char path[4200];
    snprintf(path, sizeof path, "%.4000s/robot.json", dir);
    FILE *f = fopen(path, "r");
    if (f == NULL) {
        return 0; /* folders written by hand may lack it */
    }
    fclose(f);
    static sim_robot_t r;
    odo_params_t q;
    char e[512];
    if (sim_robot_parse_file(path, &r, e, sizeof e) != 0 || sim_robot_to_params(&r, &q, e, sizeof e) != 0) {
        return odo_errf(err, errlen, "%s", e);
    }
    const odo_truck_params_t *a = &p->truck[0], *b = &q.truck[0];
    const char *what = NULL;
    if (a->wheel_diameter_nm != b->wheel_diameter_nm)
        what = "wheel_diameter_mm";
    else if (a->wheelbase_nm != b->wheelbase_nm)
        what = "wheelbase_mm";
    else if (a->counts_per_rev_milli != b->counts_per_rev_milli)
        what = "encoder_lines/gear_ratio";
    else if (a->flags != b->flags)
        what = "invert_left/invert_right";
    else if (p->counter_bits != q.counter_bits)
        what = "counter_bits";
    else if (p->tick_us != q.tick_us)
        what = "tick_ms";
    else if (p->vehicle != q.vehicle)
        what = "vehicle";
    if (what != NULL) {
        return odo_errf(err, errlen, "%s: runs of a different robot: %s differs from %s", path, what, robot_path);
    }
    return 0;
}

int fit_data_load_dir(fit_set_t *s, const char *dir, const char *robot_path, const odo_params_t *p, char *err,
                      size_t errlen)
{
    if (s->n_groups == FIT_MAX_GROUPS) {
        return odo_errf(err, errlen, "%s: more than %u folders", dir, FIT_MAX_GROUPS);
    }
    if (check_robot(dir, robot_path, p, err, errlen) != 0) {
        return -1;
    }
    char pat[4200];
    snprintf(pat, sizeof pat, "%.4000s/run-*.log", dir);
    glob_t g;
    const int gr = glob(pat, 0, NULL, &g);
    if (gr != 0) {
        if (gr == GLOB_NOMATCH) {
            return odo_errf(err, errlen, "%s: no run-*.log files (a folder odo-import writes)", dir);
        }
        return odo_errf(err, errlen, "%s: cannot list the folder", dir);
    }
    const unsigned group = (unsigned)s->n_groups;
    /* group name: the folder's last path component */
    char tmp[4096];
    snprintf(tmp, sizeof tmp, "%s", dir);
    size_t L = strlen(tmp);
    while (L > 1 && tmp[L - 1] == '/') {
        tmp[--L] = '\0';
    }
    const char *base = strrchr(tmp, '/');
    base = base != NULL ? base + 1 : tmp;
    for (size_t k = 0; k < s->n_groups; ++k) {
        if (strcmp(s->group_name[k], base) == 0) {
            globfree(&g);
            return odo_errf(err, errlen, "%s: two folders named %s (run names would clash)", dir, base);
        }
    }
    snprintf(s->group_name[group], sizeof s->group_name[group], "%.95s", base);
    snprintf(s->group_dir[group], sizeof s->group_dir[group], "%s", tmp);
    s->n_groups++;
    int rc = 0;
    for (size_t i = 0; i < g.gl_pathc && rc == 0; ++i) {
        if (s->n_runs == FIT_MAX_RUNS) {
            rc = odo_errf(err, errlen, "%s: more than %u runs", dir, FIT_MAX_RUNS);
            break;
        }
        fit_run_t *run = &s->run[s->n_runs];
        memset(run, 0, sizeof *run);
        const char *fn = strrchr(g.gl_pathv[i], '/');
        fn = fn != NULL ? fn + 1 : g.gl_pathv[i];
        char stem[128];
        snprintf(stem, sizeof stem, "%.*s", (int)(strlen(fn) - 4), fn);
        snprintf(run->name, sizeof run->name, "%.95s/%.95s", base, stem);
        snprintf(run->log_path, sizeof run->log_path, "%s", g.gl_pathv[i]);
        run->group = group;
        s->n_runs++;
        if (load_counts(run, p, &s->can_fd_skipped, err, errlen) != 0) {
            rc = -1;
            break;
        }
        char tp[4200];
        snprintf(tp, sizeof tp, "%.4000s/%.127s.truth.csv", tmp, stem);
        FILE *tf = fopen(tp, "r");
        if (tf != NULL) {
            fclose(tf);
            rc = load_track(run, tp, err, errlen);
        } else {
            char d[16];
            unsigned idx = 0;
            if (sscanf(stem, "run-%15[a-z]-%u", d, &idx) == 2) {
                char rp[4200];
                snprintf(rp, sizeof rp, "%.4000s/returns.csv", tmp);
                rc = load_return(run, rp, d, idx, err, errlen);
            }
            if (rc == 0 && !run->has_return) {
                rc = odo_errf(err, errlen, "%s: no truth (neither %s.truth.csv nor a row in returns.csv)",
                              run->log_path, stem);
            }
        }
    }
    globfree(&g);
    return rc;
}

int fit_data_select(fit_set_t *s, const char *const *fit, size_t n_fit, const char *const *judge, size_t n_judge,
                    char *err, size_t errlen)
{
    const char *const *pats[2] = {fit, judge};
    const size_t np[2] = {n_fit, n_judge};
    for (int w = 0; w < 2; ++w) {
        for (size_t k = 0; k < np[w]; ++k) {
            bool any = false;
            for (size_t i = 0; i < s->n_runs; ++i) {
                if (fnmatch(pats[w][k], s->run[i].name, 0) == 0) {
                    any = true;
                    if (w == 0) {
                        s->run[i].fit = true;
                    } else {
                        s->run[i].judge = true;
                    }
                }
            }
            if (!any) {
                return odo_errf(err, errlen, "%s '%s' matches no run (runs are named <folder>/<log stem>, e.g. %s)",
                                w == 0 ? "--fit" : "--judge", pats[w][k],
                                s->n_runs ? s->run[0].name : "square/run-cw-01");
            }
        }
    }
    size_t n_fitted = 0;
    for (size_t i = 0; i < s->n_runs; ++i) {
        if (n_fit == 0) {
            s->run[i].fit = true;
        }
        if (n_judge == 0) {
            s->run[i].judge = !s->run[i].fit;
        }
        n_fitted += s->run[i].fit;
    }
    if (n_fitted == 0) {
        return odo_errf(err, errlen, "no run selected for fitting");
    }
    return 0;
}

typedef struct {
    double *x, *y;
    size_t n, cap;
} poses_t;

static void on_pose(void *user, replay_t *r, uint64_t tick, const odo_tick_input_t *in, const odo_tick_output_t *out)
{
    (void)r;
    (void)tick;
    (void)in;
    poses_t *ps = user;
    if (ps->n < ps->cap) {
        ps->x[ps->n] = (double)out->pose[0].x_mm_q32 / 4294967296.0;
        ps->y[ps->n] = (double)out->pose[0].y_mm_q32 / 4294967296.0;
    }
    ps->n++;
}

int fit_data_firmware_track(const fit_run_t *run, const odo_params_t *block, double *x, double *y, char *err,
                            size_t errlen)
{
    static replay_t rp;
    poses_t ps = {x, y, 0, run->n};
    if (replay_init(&rp, block, on_pose, &ps) != ODO_PARAMS_OK) {
        return odo_errf(err, errlen, "%s: the fitted block does not boot the firmware", run->log_path);
    }
    hal_log_t lg;
    if (hal_log_open(&lg, run->log_path) != 0) {
        return odo_errf(err, errlen, "%s", lg.err);
    }
    candump_line_t l;
    hal_log_status_t st;
    while ((st = hal_log_next(&lg, &l)) == HAL_LOG_FRAME) {
        replay_push(&rp, &l.frame, l.t_us);
    }
    hal_log_close(&lg);
    replay_finish(&rp);
    if (st == HAL_LOG_ERROR || ps.n != run->n) {
        return odo_errf(err, errlen, "%s: changed while reading (%zu ticks, then %zu)", run->log_path, run->n, ps.n);
    }
    return 0;
}

void fit_data_free(fit_set_t *s)
{
    for (size_t i = 0; i < s->n_runs; ++i) {
        fit_run_t *r = &s->run[i];
        free(r->t_s);
        free(r->delta);
        free(r->tx_mm);
        free(r->ty_mm);
        free(r->tth_rad);
        memset(r, 0, sizeof *r);
    }
    s->n_runs = 0;
    s->n_groups = 0;
}
