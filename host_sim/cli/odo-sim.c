/// odo-sim: run one of the papers' experiments in the simulator with the firmware in the loop.
/// Writes, per run, the sensor frames exactly as the robot's controllers put them on the bus
/// (candump -l, can/odometry.dbc) and a ground-truth CSV; and for the set, returns.csv
/// (000 Eq. 3.1) and summary.json. Output goes to a temporary folder renamed into place at the end,
/// so a failed run leaves nothing behind.
#include <dirent.h>
#include <errno.h>
#include <inttypes.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "candump.h"
#include "data_dir.h"
#include "params_json.h"
#include "effects.h"
#include "odo/odo_can.h"
#include "robot.h"
#include "sil.h"
#include "summary.h"

#define MAX_RUNS 100

static void usage(FILE *f)
{
    fprintf(f,
            "usage: odo-sim --experiment NAME --vehicle labmate|clapper|set --scenario S.json --out DIR\n"
            "               [--robot R.json] [--runs N] [--bumps N] [--ipec on|off|paper|estimator] [--seed S] [--quiet]\n"
            "               [--log-start now|SECONDS]\n"
            "       odo-sim --list-effects [--json]\n"
            "\n"
            "Experiments (000, 004): umbmark, umbmark-ext, straight-36m, rect-7x4. Closed paths run N\n"
            "times in each direction (cw, ccw; default N = 5); straight-36m runs N times.\n"
            "--robot defaults to host_sim/robots/<vehicle>.json. --seed overrides the scenario's seed.\n"
            "Writes DIR/run-<dir>-NN.log (sensor frames, candump -l), DIR/run-<dir>-NN.truth.csv,\n"
            "DIR/returns.csv and DIR/summary.json. An existing DIR is replaced only if it holds a\n"
            "previous odo-sim output.\n"
            "--log-start: the logs' first timestamp, whole seconds since the epoch (default\n"
            "$SOURCE_DATE_EPOCH if set, else now; 0 for reproducible logs). The truth CSVs' t_s is\n"
            "on the same clock.\n"
            "--params P.json|P.bin: run the firmware with this parameter block's calibration (Ed, Eb,\n"
            "Es per truck, e.g. from odo-calib umbmark --out-params); the world keeps the robot's true\n"
            "geometry, and the block's nominal geometry must match the robot description's.\n");
}

typedef struct {
    FILE    *log;
    FILE    *truth;
    uint64_t start_us; /* --log-start: added to every frame's time */
    unsigned trucks;
    int      io_error;
} run_files_t;

static void write_sensor_frames(run_files_t *rf, const sim_tick_t *tk)
{
    const odo_tick_input_t *in = tk->input;
    odo_can_frame_t f;
    for (uint8_t t = 0; t < rf->trucks; ++t) {
        if (!in->wheel[t].present) {
            continue;
        }
        const odo_msg_wheel_counts_t m = {in->wheel[t].left_raw, in->wheel[t].right_raw, in->wheel[t].seq,
                                          in->wheel[t].status};
        odo_can_pack_wheel_counts(t, &m, &f);
        rf->io_error |= odo_candump_write(rf->log, rf->start_us + in->t_us, "can0", &f);
    }
    if (in->link.rotary_present) {
        const odo_msg_link_rotary_t m = {in->link.alpha_bam16, in->link.beta_bam16, in->link.rotary_seq,
                                         in->link.rotary_status};
        odo_can_pack_link_rotary(&m, &f);
        rf->io_error |= odo_candump_write(rf->log, rf->start_us + in->t_us, "can0", &f);
    }
    if (in->link.linear_present) {
        const odo_msg_link_linear_t m = {in->link.length_um, in->link.linear_seq, in->link.linear_status};
        odo_can_pack_link_linear(&m, &f);
        rf->io_error |= odo_candump_write(rf->log, rf->start_us + in->t_us, "can0", &f);
    }
}

static void on_tick(void *user, const sim_tick_t *tk)
{
    run_files_t *rf = user;
    write_sensor_frames(rf, tk);
    const double deg = 180.0 / M_PI;
    /* on the log's clock: a whole-second start (--log-start) plus the run's time */
    fprintf(rf->truth, "%.3f,%.4f,%.4f,%.6f,%.4f,%.4f,%.6f,%.6f,%.6f,%.4f,",
            (double)(rf->start_us / 1000000U) + tk->t_s, tk->truth[0].x_mm,
            tk->truth[0].y_mm, tk->truth[0].theta_rad * deg, tk->truth[1].x_mm, tk->truth[1].y_mm,
            tk->truth[1].theta_rad * deg, tk->link.alpha_rad * deg, tk->link.beta_rad * deg,
            tk->link.length_mm);
    for (size_t i = 0; i < tk->n_events; ++i) {
        const sim_bump_event_t *e = &tk->events[i];
        fprintf(rf->truth, "%sbump:%c:%s:h%.3f:x%.3f:y%.3f", i ? "|" : "", e->truck ? 'B' : 'A',
                e->wheel == ODO_LEFT ? "left" : "right", e->height_mm, e->x_mm, e->y_mm);
    }
    fputc('\n', rf->truth);
}

/// Remove a folder holding only files (our own outputs).
static void remove_flat_dir(const char *dir)
{
    DIR *d = opendir(dir);
    if (d != NULL) {
        struct dirent *e;
        char path[PATH_MAX];
        while ((e = readdir(d)) != NULL) {
            if (strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0) {
                snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
                remove(path);
            }
        }
        closedir(d);
    }
    rmdir(dir);
}

static int finish(const char *tmp, const char *out)
{
    struct stat sb;
    if (stat(out, &sb) == 0) {
        char marker[PATH_MAX];
        snprintf(marker, sizeof marker, "%s/summary.json", out);
        DIR *d = opendir(out);
        int entries = 0;
        if (d != NULL) {
            for (struct dirent *e; (e = readdir(d)) != NULL;) {
                entries += strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0;
            }
            closedir(d);
        }
        if (!S_ISDIR(sb.st_mode) || (entries > 0 && access(marker, F_OK) != 0)) {
            fprintf(stderr, "odo-sim: %s exists and is not a previous odo-sim output; not replacing it\n", out);
            return -1;
        }
        char old[PATH_MAX];
        snprintf(old, sizeof old, "%s.old.%ld", out, (long)getpid());
        if (rename(out, old) != 0) {
            fprintf(stderr, "odo-sim: cannot replace %s: %s\n", out, strerror(errno));
            return -1;
        }
        if (rename(tmp, out) != 0) {
            fprintf(stderr, "odo-sim: cannot move results to %s: %s\n", out, strerror(errno));
            rename(old, out);
            return -1;
        }
        remove_flat_dir(old);
        return 0;
    }
    if (rename(tmp, out) != 0) {
        fprintf(stderr, "odo-sim: cannot move results to %s: %s\n", out, strerror(errno));
        return -1;
    }
    return 0;
}

static int write_returns(const char *dir, const sim_return_t *r, size_t n, int straight)
{
    char path[PATH_MAX];
    snprintf(path, sizeof path, "%s/returns.csv", dir);
    FILE *f = fopen(path, "w");
    if (f == NULL) {
        return -1;
    }
    fprintf(f, "run,direction,x_abs_mm,y_abs_mm,theta_abs_deg,x_calc_mm,y_calc_mm,theta_calc_deg\n");
    for (size_t i = 0; i < n; ++i) {
        fprintf(f, "%u,%s,%.3f,%.3f,%.4f,%.3f,%.3f,%.4f\n", r[i].run, straight ? "fwd" : (r[i].ccw ? "ccw" : "cw"),
                r[i].x_abs_mm, r[i].y_abs_mm, r[i].theta_abs_deg, r[i].x_calc_mm, r[i].y_calc_mm,
                r[i].theta_calc_deg);
    }
    return fclose(f) == 0 ? 0 : -1;
}

static int write_summary(const char *dir, const char *experiment, const char *vehicle, unsigned runs,
                         uint64_t seed, const sim_return_t *r, size_t n, int straight)
{
    sim_summary_t s;
    sim_summarise(r, n, &s);
    char path[PATH_MAX];
    snprintf(path, sizeof path, "%s/summary.json", dir);
    FILE *f = fopen(path, "w");
    if (f == NULL) {
        return -1;
    }
    fprintf(f, "{\n  \"experiment\": \"%s\",\n  \"vehicle\": \"%s\",\n  \"runs_per_direction\": %u,\n"
               "  \"seed\": %" PRIu64 ",\n",
            experiment, vehicle, runs, seed);
    fprintf(f, "  \"emax_syst_mm\": %.3f,\n  \"cg_cw_mm\": [%.3f, %.3f],\n  \"cg_ccw_mm\": [%.3f, %.3f],\n"
               "  \"sigma_mm\": %.3f,\n  \"sem_mm\": %.3f,\n  \"avg_abs_theta_err_deg\": %.4f,\n  \"runs\": [\n",
            s.emax_syst_mm, s.cg_cw_mm[0], s.cg_cw_mm[1], s.cg_ccw_mm[0], s.cg_ccw_mm[1], s.sigma_mm,
            s.sem_mm, s.avg_abs_theta_err_deg);
    for (size_t i = 0; i < n; ++i) {
        fprintf(f, "    {\"run\": %u, \"direction\": \"%s\", \"ex_mm\": %.3f, \"ey_mm\": %.3f, \"etheta_deg\": %.4f}%s\n",
                r[i].run, straight ? "fwd" : (r[i].ccw ? "ccw" : "cw"), r[i].ex_mm, r[i].ey_mm, r[i].etheta_deg,
                i + 1 < n ? "," : "");
    }
    fprintf(f, "  ]\n}\n");
    return fclose(f) == 0 ? 0 : -1;
}

int main(int argc, char **argv)
{
    const char *experiment = NULL, *vehicle_name = NULL, *scenario_path = NULL, *robot_path = NULL,
               *out = NULL;
    long runs = 5, bumps = -1;
    int ipec = 0, quiet = 0, seed_given = 0, list_effects = 0, list_json = 0;
    uint64_t seed = 0;
    const char *params_path = NULL; /* --params: calibration for the firmware */
    uint64_t log_start_us = 0U;     /* --log-start; else SOURCE_DATE_EPOCH, else the wall clock */
    if (odo_log_start_default(&log_start_us) != 0) {
        fprintf(stderr, "odo-sim: SOURCE_DATE_EPOCH must be whole seconds 0..%llu\n",
                (unsigned long long)ODO_LOG_START_MAX_S);
        return 2;
    }
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        char *end = NULL;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            usage(stdout);
            return 0;
        } else if (strcmp(a, "--list-effects") == 0) {
            list_effects = 1;
        } else if (strcmp(a, "--json") == 0) {
            list_json = 1;
        } else if (strcmp(a, "--quiet") == 0) {
            quiet = 1;
        } else if (v == NULL) {
            fprintf(stderr, "odo-sim: %s needs a value (or is unknown)\n", a);
            return 2;
        } else if (strcmp(a, "--log-start") == 0) {
            if (odo_log_start_parse(argv[++i], &log_start_us) != 0) {
                fprintf(stderr, "odo-sim: --log-start must be now or whole seconds 0..%llu, not '%s'\n",
                        (unsigned long long)ODO_LOG_START_MAX_S, argv[i]);
                return 2;
            }
        } else if (strcmp(a, "--experiment") == 0) {
            experiment = argv[++i];
        } else if (strcmp(a, "--vehicle") == 0) {
            vehicle_name = argv[++i];
        } else if (strcmp(a, "--scenario") == 0) {
            scenario_path = argv[++i];
        } else if (strcmp(a, "--robot") == 0) {
            robot_path = argv[++i];
        } else if (strcmp(a, "--params") == 0) {
            params_path = argv[++i];
        } else if (strcmp(a, "--out") == 0) {
            out = argv[++i];
        } else if (strcmp(a, "--runs") == 0 || strcmp(a, "--bumps") == 0) {
            errno = 0;
            const long n = strtol(argv[++i], &end, 10);
            if (errno != 0 || *end != '\0' || n < 0 || n > MAX_RUNS || (strcmp(a, "--runs") == 0 && n < 1)) {
                fprintf(stderr, "odo-sim: %s must be an integer in [%d, %d], not '%s'\n", a,
                        strcmp(a, "--runs") == 0 ? 1 : 0, MAX_RUNS, argv[i]);
                return 2;
            }
            *(strcmp(a, "--runs") == 0 ? &runs : &bumps) = n;
        } else if (strcmp(a, "--ipec") == 0) {
            ++i;
            /* on = paper (002 Eqs. 9-16 per tick); estimator = the sub-resolution form. */
            if (strcmp(argv[i], "on") != 0 && strcmp(argv[i], "off") != 0 &&
                strcmp(argv[i], "paper") != 0 && strcmp(argv[i], "estimator") != 0) {
                fprintf(stderr, "odo-sim: --ipec must be on, off, paper or estimator, not '%s'\n", argv[i]);
                return 2;
            }
            ipec = strcmp(argv[i], "off") == 0 ? 0 : strcmp(argv[i], "estimator") == 0 ? 2 : 1;
        } else if (strcmp(a, "--seed") == 0) {
            errno = 0;
            seed = strtoull(argv[++i], &end, 10);
            if (errno != 0 || *end != '\0' || argv[i][0] == '-') {
                fprintf(stderr, "odo-sim: --seed must be a non-negative integer, not '%s'\n", argv[i]);
                return 2;
            }
            seed_given = 1;
        } else {
            fprintf(stderr, "odo-sim: unknown argument '%s'\n", a);
            usage(stderr);
            return 2;
        }
    }
    if (list_effects) {
        return (list_json ? sim_effects_write_json(stdout) : sim_effects_write_markdown(stdout)) == 0 ? 0 : 1;
    }
    if (experiment == NULL || vehicle_name == NULL || scenario_path == NULL || out == NULL) {
        fprintf(stderr, "odo-sim: --experiment, --vehicle, --scenario and --out are required\n");
        usage(stderr);
        return 2;
    }
    int known = 0;
    for (const char *const *n = sim_experiment_names; *n != NULL; ++n) {
        known |= strcmp(*n, experiment) == 0;
    }
    if (!known) {
        fprintf(stderr, "odo-sim: unknown experiment '%s' (umbmark, umbmark-ext, straight-36m, rect-7x4)\n",
                experiment);
        return 2;
    }
    sim_vehicle_t vehicle;
    if (!sim_vehicle_parse(vehicle_name, &vehicle)) {
        fprintf(stderr, "odo-sim: unknown vehicle '%s' (labmate, clapper, set)\n", vehicle_name);
        return 2;
    }
    static sim_robot_t robot;
    static sim_scenario_t scenario;
    char err[512];
    char default_robot[PATH_MAX];
    if (robot_path == NULL) {
        /* The stock descriptions: the checkout's, or the installed ones (tools/lib/data_dir.h). */
        char rel[96];
        snprintf(rel, sizeof rel, "host_sim/robots/%s.json", vehicle_name);
        if (odo_data_path(rel, default_robot, sizeof default_robot) != 0) {
            fprintf(stderr, "odo-sim: the robot file's path is too long; give --robot\n");
            return 1;
        }
        robot_path = default_robot;
    }
    if (sim_robot_parse_file(robot_path, &robot, err, sizeof err) != 0) {
        fprintf(stderr, "odo-sim: %s\n", err);
        return 1;
    }
    if (robot.vehicle != vehicle) {
        fprintf(stderr, "odo-sim: %s describes a %s, not a %s\n", robot_path, sim_vehicle_name(robot.vehicle),
                vehicle_name);
        return 1;
    }
    if (params_path != NULL) {
        /* The firmware boots with the block's calibration; the world's truth stays the robot's
         * nominal geometry plus the scenario, so the geometry the block describes must match. */
        odo_params_t cal, nominal;
        if (odo_params_file_load(params_path, &cal, err, sizeof err) != 0 ||
            sim_robot_to_params(&robot, &nominal, err, sizeof err) != 0) {
            fprintf(stderr, "odo-sim: %s\n", err);
            return 1;
        }
        for (unsigned t = 0; t < robot.n_trucks; ++t) {
            const odo_truck_params_t *c = &cal.truck[t], *n = &nominal.truck[t];
            if (c->wheel_diameter_nm != n->wheel_diameter_nm || c->wheelbase_nm != n->wheelbase_nm ||
                c->counts_per_rev_milli != n->counts_per_rev_milli) {
                fprintf(stderr, "odo-sim: %s: truck %c's nominal geometry (Dn, b, counts/rev) differs from %s\n",
                        params_path, 'A' + t, robot_path);
                return 1;
            }
            robot.truck[t].cal_ed = c->ed_q30 / 1073741824.0;
            robot.truck[t].cal_eb = c->eb_q30 / 1073741824.0;
            robot.truck[t].cal_es = c->es_q30 / 1073741824.0;
            robot.truck[t].cal_scrub = c->scrub_q30 / 1073741824.0;
            robot.truck[t].has_calibration = true;
        }
    }
    if (sim_scenario_parse_file(scenario_path, &scenario, err, sizeof err) != 0) {
        fprintf(stderr, "odo-sim: %s\n", err);
        return 1;
    }
    if (!seed_given) {
        seed = scenario.seed;
    }

    char tmp[PATH_MAX - 64];
    if (strlen(out) + 32 >= sizeof tmp) {
        fprintf(stderr, "odo-sim: output path too long\n");
        return 2;
    }
    snprintf(tmp, sizeof tmp, "%s.tmp.%ld", out, (long)getpid());
    if (mkdir(tmp, 0777) != 0) {
        fprintf(stderr, "odo-sim: cannot create %s: %s\n", tmp, strerror(errno));
        return 1;
    }
    const int straight = strcmp(experiment, "straight-36m") == 0;
    const int dirs = straight ? 1 : 2;
    static sim_return_t rets[2 * MAX_RUNS];
    size_t n_ret = 0;
    int rc = 0;
    for (int d = 0; d < dirs && rc == 0; ++d) {
        for (unsigned k = 0; k < (unsigned)runs && rc == 0; ++k) {
            const char *dname = straight ? "fwd" : (d ? "ccw" : "cw");
            char path[PATH_MAX];
            run_files_t rf = {.trucks = robot.n_trucks, .start_us = log_start_us};
            snprintf(path, sizeof path, "%s/run-%s-%02u.log", tmp, dname, k + 1);
            rf.log = fopen(path, "w");
            snprintf(path, sizeof path, "%s/run-%s-%02u.truth.csv", tmp, dname, k + 1);
            rf.truth = fopen(path, "w");
            if (rf.log == NULL || rf.truth == NULL) {
                fprintf(stderr, "odo-sim: cannot write in %s: %s\n", tmp, strerror(errno));
                rc = -1;
            } else {
                fprintf(rf.truth, "t_s,a_x_mm,a_y_mm,a_theta_deg,b_x_mm,b_y_mm,b_theta_deg,alpha_deg,"
                                  "beta_deg,l_mm,events\n");
                const sim_run_config_t cfg = {
                    .robot = &robot, .scenario = &scenario, .experiment = experiment, .ccw = d,
                    .bumps = (int)bumps, .bump_height_mm = 10.0, .ipec = ipec,
                    .seed = sim_run_seed(seed, d, k), .run_index = k,
                };
                if (sim_run(&cfg, on_tick, &rf, &rets[n_ret], err, sizeof err) != 0) {
                    fprintf(stderr, "odo-sim: %s\n", err);
                    rc = -1;
                } else if (!quiet) {
                    fprintf(stderr, "odo-sim: %s %s run %u/%ld: ex %8.1f mm  ey %8.1f mm  etheta %7.3f deg\n",
                            experiment, dname, k + 1, runs, rets[n_ret].ex_mm, rets[n_ret].ey_mm,
                            rets[n_ret].etheta_deg);
                }
                n_ret++;
            }
            if ((rf.log != NULL && fclose(rf.log) != 0) || (rf.truth != NULL && fclose(rf.truth) != 0) ||
                rf.io_error) {
                if (rc == 0) {
                    fprintf(stderr, "odo-sim: writing run files failed\n");
                }
                rc = -1;
            }
        }
    }
    if (rc == 0 && (write_returns(tmp, rets, n_ret, straight) != 0 ||
                    write_summary(tmp, experiment, vehicle_name, (unsigned)runs, seed, rets, n_ret, straight) != 0)) {
        fprintf(stderr, "odo-sim: writing the summary failed\n");
        rc = -1;
    }
    if (rc == 0 && finish(tmp, out) == 0) {
        if (!quiet) {
            sim_summary_t s;
            sim_summarise(rets, n_ret, &s);
            fprintf(stderr, "odo-sim: Emax,syst %.1f mm (000 Eq. 3.4), SEM %.1f mm, avg |etheta| %.3f deg -> %s\n",
                    s.emax_syst_mm, s.sem_mm, s.avg_abs_theta_err_deg, out);
        }
        return 0;
    }
    remove_flat_dir(tmp);
    return 1;
}
