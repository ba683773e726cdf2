/// odo-sim: run one of the papers' experiments in the simulator with the firmware in the loop.
/// Writes, per run, the sensor frames exactly as the robot's controllers put them on the bus
/// (candump -l, can/odometry.dbc) and a ground-truth CSV; and for the set, returns.csv
/// (000 Eq. 3.1) and summary.json. The output folder follows hostlib/odo_out.h: built in a temp
/// folder beside DIR and put into place at the end, so a failed run leaves DIR as it was.
#include <errno.h>
#include <getopt.h>
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
#include "odo_cli.h"
#include "odo_out.h"
#include "params_json.h"
#include "effects.h"
#include "odo/odo_can.h"
#include "robot.h"
#include "sil.h"
#include "summary.h"

#define MAX_RUNS 100

static void usage(FILE *f)
{
    fprintf(f, "usage: odo-sim --experiment NAME --vehicle labmate|clapper|set --scenario S.json --out DIR\n"
               "               [--robot R.json] [--params P.json|P.bin] [--runs N] [--bumps N]\n"
               "               [--ipec off|on|paper|estimator] [--seed S] [--log-start now|SECONDS]\n"
               "               [--force] [--quiet]\n"
               "       odo-sim --list-effects [--json]\n"
               "       odo-sim --help | --version\n"
               "\n"
               "Experiments (000, 004): umbmark, umbmark-ext, straight-36m, rect-7x4. Closed paths run N\n"
               "times in each direction (cw, ccw; default N = 5); straight-36m runs N times.\n"
               "--robot defaults to host_sim/robots/<vehicle>.json. --seed overrides the scenario's seed.\n"
               "Writes DIR/run-<dir>-NN.log (sensor frames, candump -l), DIR/run-<dir>-NN.truth.csv,\n"
               "DIR/returns.csv and DIR/summary.json; missing parent folders are created. DIR is built\n"
               "beside itself and renamed into place; an existing DIR must be empty or hold a previous\n"
               "odo-sim output (its .odo-manifest: only the files listed there are replaced or removed);\n"
               "--force writes into any other folder, replacing same-named files and removing nothing.\n"
               "--log-start: the logs' first timestamp, whole seconds since the epoch (default\n"
               "$SOURCE_DATE_EPOCH if set, else now; 0 for reproducible logs). The truth CSVs' t_s is\n"
               "on the same clock.\n"
               "--params P.json|P.bin: run the firmware with this parameter block's calibration (Ed, Eb,\n"
               "Es per truck, e.g. from odo-calib umbmark --out-params); the world keeps the robot's true\n"
               "geometry, and the block's nominal geometry must match the robot description's.\n"
               "Exit status: 0 ok, 1 rejected input or I/O error, 2 usage error.\n");
}

typedef struct {
    FILE *log;
    FILE *truth;
    uint64_t start_us; /* --log-start: added to every frame's time */
    unsigned trucks;
    int io_error;
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
            (double)(rf->start_us / 1000000U) + tk->t_s, tk->truth[0].x_mm, tk->truth[0].y_mm,
            tk->truth[0].theta_rad * deg, tk->truth[1].x_mm, tk->truth[1].y_mm, tk->truth[1].theta_rad * deg,
            tk->link.alpha_rad * deg, tk->link.beta_rad * deg, tk->link.length_mm);
    for (size_t i = 0; i < tk->n_events; ++i) {
        const sim_bump_event_t *e = &tk->events[i];
        fprintf(rf->truth, "%sbump:%c:%s:h%.3f:x%.3f:y%.3f", i ? "|" : "", e->truck ? 'B' : 'A',
                e->wheel == ODO_LEFT ? "left" : "right", e->height_mm, e->x_mm, e->y_mm);
    }
    fputc('\n', rf->truth);
}

static int write_returns(odo_out_dir_t *dir, const sim_return_t *r, size_t n, int straight, char *err, size_t errlen)
{
    FILE *f = odo_out_dir_fopen(dir, "returns.csv", err, errlen);
    if (f == NULL) {
        return -1;
    }
    fprintf(f, "run,direction,x_abs_mm,y_abs_mm,theta_abs_deg,x_calc_mm,y_calc_mm,theta_calc_deg\n");
    for (size_t i = 0; i < n; ++i) {
        fprintf(f, "%u,%s,%.3f,%.3f,%.4f,%.3f,%.3f,%.4f\n", r[i].run, straight ? "fwd" : (r[i].ccw ? "ccw" : "cw"),
                r[i].x_abs_mm, r[i].y_abs_mm, r[i].theta_abs_deg, r[i].x_calc_mm, r[i].y_calc_mm, r[i].theta_calc_deg);
    }
    return fclose(f) == 0 ? 0 : -1;
}

static int write_summary(odo_out_dir_t *dir, const char *experiment, const char *vehicle, unsigned runs, uint64_t seed,
                         const sim_return_t *r, size_t n, int straight, char *err, size_t errlen)
{
    sim_summary_t s;
    sim_summarise(r, n, &s);
    FILE *f = odo_out_dir_fopen(dir, "summary.json", err, errlen);
    if (f == NULL) {
        return -1;
    }
    fprintf(f,
            "{\n  \"experiment\": \"%s\",\n  \"vehicle\": \"%s\",\n  \"runs_per_direction\": %u,\n"
            "  \"seed\": %" PRIu64 ",\n",
            experiment, vehicle, runs, seed);
    fprintf(f,
            "  \"emax_syst_mm\": %.3f,\n  \"cg_cw_mm\": [%.3f, %.3f],\n  \"cg_ccw_mm\": [%.3f, %.3f],\n"
            "  \"sigma_mm\": %.3f,\n  \"sem_mm\": %.3f,\n  \"avg_abs_theta_err_deg\": %.4f,\n  \"runs\": [\n",
            s.emax_syst_mm, s.cg_cw_mm[0], s.cg_cw_mm[1], s.cg_ccw_mm[0], s.cg_ccw_mm[1], s.sigma_mm, s.sem_mm,
            s.avg_abs_theta_err_deg);
    for (size_t i = 0; i < n; ++i) {
        fprintf(f,
                "    {\"run\": %u, \"direction\": \"%s\", \"ex_mm\": %.3f, \"ey_mm\": %.3f, \"etheta_deg\": %.4f}%s\n",
                r[i].run, straight ? "fwd" : (r[i].ccw ? "ccw" : "cw"), r[i].ex_mm, r[i].ey_mm, r[i].etheta_deg,
                i + 1 < n ? "," : "");
    }
    fprintf(f, "  ]\n}\n");
    return fclose(f) == 0 ? 0 : -1;
}

int main(int argc, char **argv)
{
    const char *experiment = NULL, *vehicle_name = NULL, *scenario_path = NULL, *robot_path = NULL, *out = NULL;
    long runs = 5, bumps = -1;
    int ipec = 0, quiet = 0, seed_given = 0, list_effects = 0, list_json = 0;
    uint64_t seed = 0;
    const char *params_path = NULL; /* --params: calibration for the firmware */
    bool force = false;
    uint64_t log_start_us = 0U; /* --log-start; else SOURCE_DATE_EPOCH, else the wall clock */
    bool log_start_given = false;
    enum {
        O_EXPERIMENT = 256,
        O_VEHICLE,
        O_SCENARIO,
        O_ROBOT,
        O_PARAMS,
        O_OUT,
        O_RUNS,
        O_BUMPS,
        O_IPEC,
        O_SEED,
        O_FORCE,
        O_QUIET,
        O_JSON,
        O_LIST,
        O_VERSION,
        O_LOG_START
    };
    static const struct option longopts[] = {{"experiment", required_argument, NULL, O_EXPERIMENT},
                                             {"vehicle", required_argument, NULL, O_VEHICLE},
                                             {"scenario", required_argument, NULL, O_SCENARIO},
                                             {"robot", required_argument, NULL, O_ROBOT},
                                             {"params", required_argument, NULL, O_PARAMS},
                                             {"out", required_argument, NULL, O_OUT},
                                             {"runs", required_argument, NULL, O_RUNS},
                                             {"bumps", required_argument, NULL, O_BUMPS},
                                             {"ipec", required_argument, NULL, O_IPEC},
                                             {"seed", required_argument, NULL, O_SEED},
                                             {"force", no_argument, NULL, O_FORCE},
                                             {"quiet", no_argument, NULL, O_QUIET},
                                             {"json", no_argument, NULL, O_JSON},
                                             {"list-effects", no_argument, NULL, O_LIST},
                                             {"version", no_argument, NULL, O_VERSION},
                                             {"help", no_argument, NULL, 'h'},
                                             {"log-start", required_argument, NULL, O_LOG_START},
                                             {NULL, 0, NULL, 0}};
    opterr = 1;
    for (int c; (c = getopt_long(argc, argv, "h", longopts, NULL)) != -1;) {
        switch (c) {
        case 'h': usage(stdout); return 0;
        case O_VERSION: odo_cli_print_version("odo-sim"); return 0;
        case O_EXPERIMENT: experiment = optarg; break;
        case O_VEHICLE: vehicle_name = optarg; break;
        case O_SCENARIO: scenario_path = optarg; break;
        case O_ROBOT: robot_path = optarg; break;
        case O_PARAMS: params_path = optarg; break;
        case O_OUT: out = optarg; break;
        case O_RUNS:
            if (!odo_cli_long("odo-sim", "--runs", optarg, 1, MAX_RUNS, &runs)) {
                return 2;
            }
            break;
        case O_BUMPS:
            if (!odo_cli_long("odo-sim", "--bumps", optarg, 0, MAX_RUNS, &bumps)) {
                return 2;
            }
            break;
        case O_IPEC:
            /* on = paper (002 Eqs. 9-16 per tick); estimator = the sub-resolution form. */
            if ((ipec = odo_cli_ipec("odo-sim", optarg)) < 0) {
                return 2;
            }
            break;
        case O_SEED:
            if (!odo_cli_seed("odo-sim", optarg, &seed)) {
                return 2;
            }
            seed_given = 1;
            break;
        case O_LOG_START:
            if (odo_log_start_parse(optarg, &log_start_us) != 0) {
                fprintf(stderr, "odo-sim: --log-start must be now or whole seconds 0..%llu, not '%s'\n",
                        (unsigned long long)ODO_LOG_START_MAX_S, optarg);
                return 2;
            }
            log_start_given = true;
            break;
        case O_FORCE: force = true; break;
        case O_QUIET: quiet = 1; break;
        case O_JSON: list_json = 1; break;
        case O_LIST: list_effects = 1; break;
        default: odo_cli_usage_hint("odo-sim"); return 2;
        }
    }
    /* the default is read only when it is needed, so --help and --log-start work whatever
       SOURCE_DATE_EPOCH holds */
    if (!log_start_given && odo_log_start_default(&log_start_us) != 0) {
        fprintf(stderr, "odo-sim: SOURCE_DATE_EPOCH must be whole seconds 0..%llu\n",
                (unsigned long long)ODO_LOG_START_MAX_S);
        return 2;
    }
    if (optind < argc) {
        fprintf(stderr, "odo-sim: unexpected argument '%s'\n", argv[optind]);
        odo_cli_usage_hint("odo-sim");
        return 2;
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

    /* Inputs are never outputs: the robot, the scenario and the block must survive any --out. */
    odo_out_inputs_t ins;
    odo_out_inputs_init(&ins);
    (void)odo_out_inputs_add(&ins, robot_path, err, sizeof err);
    (void)odo_out_inputs_add(&ins, scenario_path, err, sizeof err);
    (void)odo_out_inputs_add(&ins, params_path, err, sizeof err);
    odo_out_dir_t *dir = odo_out_dir_begin(out, "odo-sim", force, &ins, err, sizeof err);
    if (dir == NULL) {
        fprintf(stderr, "odo-sim: %s\n", err);
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
            char name[64];
            run_files_t rf = {.trucks = robot.n_trucks, .start_us = log_start_us};
            snprintf(name, sizeof name, "run-%s-%02u.log", dname, k + 1);
            rf.log = odo_out_dir_fopen(dir, name, err, sizeof err);
            snprintf(name, sizeof name, "run-%s-%02u.truth.csv", dname, k + 1);
            rf.truth = rf.log != NULL ? odo_out_dir_fopen(dir, name, err, sizeof err) : NULL;
            if (rf.log == NULL || rf.truth == NULL) {
                fprintf(stderr, "odo-sim: %s\n", err);
                rc = -1;
            } else {
                fprintf(rf.truth, "t_s,a_x_mm,a_y_mm,a_theta_deg,b_x_mm,b_y_mm,b_theta_deg,alpha_deg,"
                                  "beta_deg,l_mm,events\n");
                const sim_run_config_t cfg = {
                    .robot = &robot,
                    .scenario = &scenario,
                    .experiment = experiment,
                    .ccw = d,
                    .bumps = (int)bumps,
                    .bump_height_mm = 10.0,
                    .ipec = ipec,
                    .seed = sim_run_seed(seed, d, k),
                    .run_index = k,
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
            if ((rf.log != NULL && fclose(rf.log) != 0) || (rf.truth != NULL && fclose(rf.truth) != 0) || rf.io_error) {
                if (rc == 0) {
                    fprintf(stderr, "odo-sim: writing run files failed\n");
                }
                rc = -1;
            }
        }
    }
    if (rc == 0 && (write_returns(dir, rets, n_ret, straight, err, sizeof err) != 0 ||
                    write_summary(dir, experiment, vehicle_name, (unsigned)runs, seed, rets, n_ret, straight, err,
                                  sizeof err) != 0)) {
        fprintf(stderr, "odo-sim: writing the summary failed: %s\n", err);
        rc = -1;
    }
    if (rc != 0) {
        odo_out_dir_abort(dir);
        return 1;
    }
    if (odo_out_dir_commit(dir, err, sizeof err) != 0) {
        fprintf(stderr, "odo-sim: %s\n", err);
        return 1;
    }
    {
        if (!quiet) {
            sim_summary_t s;
            sim_summarise(rets, n_ret, &s);
            fprintf(stderr, "odo-sim: Emax,syst %.1f mm (000 Eq. 3.4), SEM %.1f mm, avg |etheta| %.3f deg -> %s\n",
                    s.emax_syst_mm, s.sem_mm, s.avg_abs_theta_err_deg, out);
        }
    }
    return 0;
}
