/// odo-ipec: IPEC's acceptance figures and per-tick traces
/// (tools/ipec/README.md). Every figure is computed here by re-running the software-in-the-loop
/// simulator (host_sim/run/sil.h) with the firmware's own IPEC in the loop; nothing is timed.
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "data_dir.h"
#include "odo_cli.h"
#include "ipec_tool.h"

static void usage(FILE *f)
{
    fprintf(f,
            "usage: odo-ipec goals [--runs N] [--quick]\n"
            "       odo-ipec --help | --version\n"
            "       odo-ipec trace --experiment E --vehicle clapper|set [--ipec off|paper|estimator]\n"
            "                      [--scenario S.json] [--robot R.json] [--ccw] [--bumps N] [--run K] [--seed S]\n"
            "       odo-ipec selfcal --scenario S.json --out P.json [--robot R.json] [--params P0.json]\n"
            "                      [--experiment umbmark|rect-7x4|...] [--runs N] [--ipec estimator|paper] [--seed S]\n"
            "       odo-ipec selfcal-link --scenario S.json --out P.json [--robot R.json] [--params P0.json]\n"

            "\n"
            "goals  prints the IPEC acceptance figures as JSON on stdout (straight-36m, rect-7x4,\n"
            "       umbmark-ext, link-length and rotary-encoder bias, paper vs estimator); progress on\n"
            "       stderr. --runs N runs per case (default 10; --quick: 4).\n"
            "trace  prints one CSV row per 40 ms tick of one run: truth and firmware headings of both\n"
            "       trucks, the link angles, IPEC corrections and innovations.\n"
            "selfcal  004 s. 5.1: estimates Ed and Eb of both clapper trucks from IPEC's corrections over\n"
            "       N cw + N ccw runs (default 2 of umbmark) on the scenario's floor, writes the parameter\n"
            "       block (odo-params show JSON) to P.json, re-runs with it and prints JSON: estimates,\n"
            "       correction rates, systematic (one-sided) corrections before/after.\n"
            "selfcal-link  004 s. 5.2: rotary-encoder biases from the error at a reference mark 18 m out,\n"
            "       then the link-length bias from UMBmark return headings (needs the external reference,\n"
            "       the simulator's truth); writes link.alpha/beta_bias_bam and length_bias_nm to P.json.\n"
            "Robots default to host_sim/robots/<vehicle>.json; scenarios to host_sim/scenarios/none.json.\n");
}

/* ---------------------------------------------------------------------------------------------
 * Shared helpers (ipec_tool.h)
 * ------------------------------------------------------------------------------------------- */
static char g_src[PATH_MAX - 256];

const char *ipec_src_dir(void)
{
    if (g_src[0] == '\0') {
        (void)odo_data_path(".", g_src, sizeof g_src); /* "" if too long: paths then fail to open */
    }
    return g_src;
}

int ipec_load(const char *vehicle, const char *robot_path, const char *scenario_path, sim_robot_t *robot,
              sim_scenario_t *sc)
{
    char path[PATH_MAX];
    char err[512];
    if (robot_path == NULL) {
        snprintf(path, sizeof path, "%s/host_sim/robots/%s.json", ipec_src_dir(), vehicle);
        robot_path = path;
    }
    if (sim_robot_parse_file(robot_path, robot, err, sizeof err) != 0) {
        fprintf(stderr, "odo-ipec: %s\n", err);
        return -1;
    }
    if (scenario_path == NULL) {
        sim_scenario_none(sc);
        return 0;
    }
    if (sim_scenario_parse_file(scenario_path, sc, err, sizeof err) != 0) {
        fprintf(stderr, "odo-ipec: %s\n", err);
        return -1;
    }
    return 0;
}

int ipec_run(const sim_robot_t *robot, const sim_scenario_t *sc, const char *experiment, int ccw, int bumps, int ipec,
             uint64_t seed, unsigned run, sim_tick_fn fn, void *user, sim_return_t *ret)
{
    char err[512];
    const sim_run_config_t cfg = {
        .robot = robot,
        .scenario = sc,
        .experiment = experiment,
        .ccw = ccw,
        .bumps = bumps,
        .bump_height_mm = 10.0,
        .ipec = ipec,
        .seed = sim_run_seed(seed, ccw, run),
        .run_index = run,
    };
    if (sim_run(&cfg, fn, user, ret, err, sizeof err) != 0) {
        fprintf(stderr, "odo-ipec: %s\n", err);
        return -1;
    }
    return 0;
}

double ipec_bam_deg(int64_t bam) { return (double)bam * (360.0 / 4294967296.0); }

static double wrap_deg(double d) { return remainder(d, 360.0); }

double ipec_est_theta_deg(const odo_pose_t *p) { return ipec_bam_deg((int32_t)odo_heading_bam(p)); }

/* ---------------------------------------------------------------------------------------------
 * trace
 * ------------------------------------------------------------------------------------------- */
static void trace_tick(void *user, const sim_tick_t *tk)
{
    (void)user;
    const odo_tick_output_t *o = tk->output;
    const double ta = tk->truth[0].theta_rad * 180.0 / M_PI, tb = tk->truth[1].theta_rad * 180.0 / M_PI;
    const double ea = ipec_est_theta_deg(&o->pose[0]), eb = ipec_est_theta_deg(&o->pose[1]);
    printf("%.3f,%.2f,%.2f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.3f,%u,%zu\n", tk->t_s, tk->truth[0].x_mm,
           tk->truth[0].y_mm, ta, wrap_deg(ea - ta), wrap_deg(eb - tb), tk->link.alpha_rad * 180.0 / M_PI,
           tk->link.beta_rad * 180.0 / M_PI, ipec_bam_deg(o->ipec_dtheta_bam[0]), ipec_bam_deg(o->ipec_dtheta_bam[1]),
           ipec_bam_deg(o->ipec_innov_bam[0]), ipec_bam_deg(o->ipec_innov_bam[1]),
           ipec_bam_deg((int32_t)(uint32_t)((uint32_t)tk->input->link.alpha_bam16 << 16)), tk->link.length_mm,
           (unsigned)o->faults, tk->n_events);
}

static int parse_ipec(const char *s, int *out)
{
    if (strcmp(s, "off") == 0) {
        *out = 0;
    } else if (strcmp(s, "paper") == 0 || strcmp(s, "on") == 0) {
        *out = 1;
    } else if (strcmp(s, "estimator") == 0) {
        *out = 2;
    } else {
        fprintf(stderr, "odo-ipec: --ipec must be off, paper (on) or estimator, not '%s'\n", s);
        return -1;
    }
    return 0;
}

static int parse_long(const char *opt, const char *s, long lo, long hi, long *out)
{
    char *end = NULL;
    errno = 0;
    const long v = strtol(s, &end, 10);
    if (errno != 0 || end == s || *end != '\0' || v < lo || v > hi) {
        fprintf(stderr, "odo-ipec: %s must be an integer in [%ld, %ld], not '%s'\n", opt, lo, hi, s);
        return -1;
    }
    *out = v;
    return 0;
}

static int cmd_trace(int argc, char **argv)
{
    const char *experiment = NULL, *vehicle = "clapper", *scenario = NULL, *robot_path = NULL;
    int ipec = 1, ccw = 0;
    long bumps = -1, run = 0, seed = 1;
    for (int i = 0; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(a, "--ccw") == 0) {
            ccw = 1;
            continue;
        }
        if (v == NULL) {
            fprintf(stderr, "odo-ipec: %s needs a value (or is unknown)\n", a);
            return 2;
        }
        ++i;
        if (strcmp(a, "--experiment") == 0) {
            experiment = v;
        } else if (strcmp(a, "--vehicle") == 0) {
            vehicle = v;
        } else if (strcmp(a, "--scenario") == 0) {
            scenario = v;
        } else if (strcmp(a, "--robot") == 0) {
            robot_path = v;
        } else if (strcmp(a, "--ipec") == 0) {
            if (parse_ipec(v, &ipec) != 0) {
                return 2;
            }
        } else if (strcmp(a, "--bumps") == 0) {
            if (parse_long(a, v, 0, SIM_PROGRAM_MAX_BUMPS, &bumps) != 0) {
                return 2;
            }
        } else if (strcmp(a, "--run") == 0) {
            if (parse_long(a, v, 0, 1000, &run) != 0) {
                return 2;
            }
        } else if (strcmp(a, "--seed") == 0) {
            if (parse_long(a, v, 0, LONG_MAX, &seed) != 0) {
                return 2;
            }
        } else {
            fprintf(stderr, "odo-ipec: unknown argument '%s'\n", a);
            return 2;
        }
    }
    if (experiment == NULL) {
        fprintf(stderr, "odo-ipec trace: --experiment is required\n");
        return 2;
    }
    static sim_robot_t robot;
    static sim_scenario_t sc;
    if (ipec_load(vehicle, robot_path, scenario, &robot, &sc) != 0) {
        return 1;
    }
    printf("t_s,a_x_mm,a_y_mm,a_theta_deg,a_err_deg,b_err_deg,alpha_deg,beta_deg,dtheta_a_deg,dtheta_b_deg,"
           "innov_a_deg,innov_b_deg,alpha_code_deg,l_mm,faults,bump_events\n");
    sim_return_t ret;
    if (ipec_run(&robot, &sc, experiment, ccw, (int)bumps, ipec, (uint64_t)seed, (unsigned)run, trace_tick, NULL,
                 &ret) != 0) {
        return 1;
    }
    fprintf(stderr, "odo-ipec: return ex %.1f mm ey %.1f mm etheta %.3f deg\n", ret.ex_mm, ret.ey_mm, ret.etheta_deg);
    return 0;
}

int main(int argc, char **argv)
{
    if (!odo_cli_split_equals(&argc, &argv)) {
        return 1;
    }
    if (argc >= 2 && strcmp(argv[1], "--version") == 0) {
        odo_cli_print_version("odo-ipec");
        return 0;
    }
    if (argc < 2 || strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0) {
        usage(argc < 2 ? stderr : stdout);
        return argc < 2 ? 2 : 0;
    }
    for (int i = 2; i < argc; ++i) {
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            usage(stdout);
            return 0;
        }
    }
    if (strcmp(argv[1], "trace") == 0) {
        return cmd_trace(argc - 2, argv + 2);
    }
    if (strcmp(argv[1], "goals") == 0) {
        return ipec_cmd_goals(argc - 2, argv + 2);
    }
    if (strcmp(argv[1], "selfcal") == 0 || strcmp(argv[1], "selfcal-link") == 0) {
        return ipec_cmd_selfcal(argc - 2, argv + 2, strcmp(argv[1], "selfcal-link") == 0);
    }
    fprintf(stderr, "odo-ipec: unknown command '%s' (goals, trace, selfcal, selfcal-link)\n", argv[1]);
    usage(stderr);
    return 2;
}
