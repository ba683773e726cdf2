/// `odo-calib fit`: calibrate from any runs with truth and judge on held-out runs (fit_model.h).
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fit_cli.h"
#include "fit_data.h"
#include "fit_model.h"
#include "params_json.h"
#include "robot.h"

#define MAX_ARGS 64

static const char k_help[] =
    "usage: odo-calib fit --runs DIR... --robot R.json [--fit GLOB...] [--judge GLOB...]\n"
    "                     [--free ed,eb,es,scrub] [--out-params P.json|P.bin]... [--json]\n"
    "\n"
    "Calibrate truck A's odometry from recorded runs on any path (OptiOdom's generic approach),\n"
    "not only UMBmark squares, and judge it on runs held out from the fit.\n"
    "\n"
    "  --runs DIR...    folders as odo-import writes them: run-<dir>-NN.log (candump) with\n"
    "                   run-<dir>-NN.truth.csv (a motion-capture track) or a returns.csv row\n"
    "                   (return pose), and robot.json (must describe --robot's robot)\n"
    "  --robot R.json   the robot description the runs were recorded with (its calibration, if\n"
    "                   any, is the starting point and the 'before')\n"
    "  --fit GLOB...    runs to fit, by name <folder>/<log stem> (shell globs, quote them);\n"
    "                   default every run\n"
    "  --judge GLOB...  runs to judge on; default every run not fitted\n"
    "  --free LIST      parameters to fit (default ed,eb,es,scrub; es only when a fitted run has\n"
    "                   a track: closed paths do not show the scale)\n"
    "  --out-params P   write the calibrated parameter block: .json (the shape odo-params show\n"
    "                   prints) or .bin (the 128-byte block); repeat for both. `odo-calib write`\n"
    "                   puts it into a firmware image\n"
    "  --json           print the result as JSON instead of tables\n"
    "\n"
    "Model: the firmware's odometry in double precision (tools/lib/odo_ref.c) with Ed, Eb, Es and\n"
    "the turn-radius-dependent wheelbase `scrub` (heading change x (1 - k m/v), tools/calib/README.md);\n"
    "per folder, the tracked point's lever arm and heading offset are fitted as nuisance.\n"
    "Prints per judged run the return error (000 Eq. 3.1, axle centre) before and after, per folder\n"
    "the mean and the factor, and the largest difference between the firmware replaying the\n"
    "written block and the double model over every run (should be <= 0.1 mm).\n"
    "\n"
    "Exit status: 0 ok, 1 bad input or a failed fit (nothing written), 2 usage error.\n";

/* Collect the values after an option up to the next "--" option. */
static int take_list(int argc, char **argv, int *i, const char **dst, size_t *n, const char *name)
{
    int got = 0;
    while (*i + 1 < argc && strncmp(argv[*i + 1], "--", 2) != 0) {
        if (*n == MAX_ARGS) {
            fprintf(stderr, "odo-calib fit: too many values for %s\n", name);
            return -1;
        }
        dst[(*n)++] = argv[++*i];
        got++;
    }
    if (got == 0) {
        fprintf(stderr, "odo-calib fit: %s needs a value\n", name);
        return -1;
    }
    return 0;
}

typedef struct {
    double before_pos, after_pos, before_th, after_th;
    size_t n;
} group_sum_t;

static void json_str(FILE *f, const char *s)
{
    fputc('"', f);
    for (; *s; ++s) {
        if (*s == '"' || *s == '\\') {
            fputc('\\', f);
        }
        fputc(*s, f);
    }
    fputc('"', f);
}

int calib_fit_main(int argc, char **argv)
{
    const char *runs[MAX_ARGS], *fitg[MAX_ARGS], *judg[MAX_ARGS], *outs[MAX_ARGS];
    size_t n_runs = 0, n_fit = 0, n_judge = 0, n_out = 0;
    const char *robot = NULL, *free_list = "ed,eb,es,scrub";
    int json = 0;
    for (int i = 0; i < argc; ++i) {
        const char *a = argv[i];
        if (strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0) {
            fputs(k_help, stdout);
            return 0;
        }
        int rc = 0;
        if (strcmp(a, "--runs") == 0) {
            rc = take_list(argc, argv, &i, runs, &n_runs, a);
        } else if (strcmp(a, "--fit") == 0) {
            rc = take_list(argc, argv, &i, fitg, &n_fit, a);
        } else if (strcmp(a, "--judge") == 0) {
            rc = take_list(argc, argv, &i, judg, &n_judge, a);
        } else if (strcmp(a, "--out-params") == 0) {
            rc = take_list(argc, argv, &i, outs, &n_out, a);
        } else if (strcmp(a, "--robot") == 0 && i + 1 < argc) {
            robot = argv[++i];
        } else if (strcmp(a, "--free") == 0 && i + 1 < argc) {
            free_list = argv[++i];
        } else if (strcmp(a, "--json") == 0) {
            json = 1;
        } else {
            fprintf(stderr, "odo-calib fit: unknown argument or missing value '%s' (see odo-calib fit --help)\n", a);
            return 2;
        }
        if (rc != 0) {
            return 2;
        }
    }
    if (n_runs == 0 || robot == NULL) {
        fprintf(stderr, "odo-calib fit: --runs and --robot are required (see odo-calib fit --help)\n");
        return 2;
    }
    fit_free_t fr = {false, false, false, false};
    {
        char buf[128];
        snprintf(buf, sizeof buf, "%s", free_list);
        for (char *tok = strtok(buf, ","); tok != NULL; tok = strtok(NULL, ",")) {
            if (strcmp(tok, "ed") == 0)
                fr.ed = true;
            else if (strcmp(tok, "eb") == 0)
                fr.eb = true;
            else if (strcmp(tok, "es") == 0)
                fr.es = true;
            else if (strcmp(tok, "scrub") == 0)
                fr.k = true;
            else {
                fprintf(stderr, "odo-calib fit: --free: unknown parameter '%s' (ed, eb, es, scrub)\n", tok);
                return 2;
            }
        }
    }
    for (size_t k = 0; k < n_out; ++k) {
        const size_t L = strlen(outs[k]);
        if (!(L > 5 && strcmp(outs[k] + L - 5, ".json") == 0) && !(L > 4 && strcmp(outs[k] + L - 4, ".bin") == 0)) {
            fprintf(stderr, "odo-calib fit: --out-params %s: name it .json or .bin\n", outs[k]);
            return 2;
        }
    }
    /* Inputs never become outputs (hostlib/odo_out.h): the robot file, and anything inside a --runs folder. */
    odo_out_inputs_t ins;
    odo_out_inputs_init(&ins);
    {
        char ierr[256];
        (void)odo_out_inputs_add(&ins, robot, ierr, sizeof ierr);
        for (size_t k = 0; k < n_runs; ++k) {
            if (odo_out_inputs_add(&ins, runs[k], ierr, sizeof ierr) != 0) {
                fprintf(stderr, "odo-calib fit: %s\n", ierr);
                return 2;
            }
        }
        for (size_t k = 0; k < n_out; ++k) {
            char oerr[PATH_MAX + 256];
            if (odo_out_check_inputs(&ins, outs[k], oerr, sizeof oerr) != 0) {
                fprintf(stderr, "odo-calib fit: --out-params %s\n", oerr);
                return 1;
            }
        }
    }

    char err[1024];
    static sim_robot_t rob;
    odo_params_t p0;
    if (sim_robot_parse_file(robot, &rob, err, sizeof err) != 0 ||
        sim_robot_to_params(&rob, &p0, err, sizeof err) != 0) {
        fprintf(stderr, "odo-calib fit: %s\n", err);
        return 1;
    }
    if (rob.n_trucks != 1U) {
        fprintf(stderr, "odo-calib fit: %s: fit calibrates a one-truck robot (labmate-like); this is a %s\n", robot,
                sim_vehicle_name(rob.vehicle));
        return 1;
    }
    static fit_set_t set;
    int rc = 0;
    for (size_t k = 0; k < n_runs && rc == 0; ++k) {
        if (fit_data_load_dir(&set, runs[k], robot, &p0, err, sizeof err) != 0) {
            fprintf(stderr, "odo-calib fit: %s\n", err);
            rc = 1;
        }
        if (!json && rc == 0) {
            fprintf(stderr, "odo-calib fit: %s: %zu runs so far\n", runs[k], set.n_runs);
        }
    }
    if (rc == 0 && fit_data_select(&set, fitg, n_fit, judg, n_judge, err, sizeof err) != 0) {
        fprintf(stderr, "odo-calib fit: %s\n", err);
        rc = 1;
    }
    const odo_truck_params_t *base = &p0.truck[0];
    fit_params_t start;
    fit_params_from_truck(base, &start);
    fit_result_t res;
    if (rc == 0 && fit_run_fit(&set, base, p0.heading_form, &start, fr, &res, err, sizeof err) != 0) {
        fprintf(stderr, "odo-calib fit: %s\n", err);
        rc = 1;
    }
    if (rc != 0) {
        fit_data_free(&set);
        return rc;
    }

    /* The block: the robot's, with the fitted calibration. */
    odo_params_t pb = p0;
    fit_params_to_truck(&res.p, &pb.truck[0]);
    odo_param_field_t badf = ODO_PF_NONE;
    uint8_t badt = 0;
    if (odo_params_validate(&pb, &badf, &badt) != ODO_PARAMS_OK) {
        fprintf(stderr, "odo-calib fit: the fitted block fails validation (%s)\n", odo_params_field_name(badf));
        fit_data_free(&set);
        return 1;
    }
    fit_params_t in_block; /* the model as the block holds it (Q30) */
    fit_params_from_truck(&pb.truck[0], &in_block);

    /* Firmware replay of the block vs the double model of the same block, every run. */
    double fw_max = 0.0;
    size_t longest = 0;
    for (size_t i = 0; i < set.n_runs; ++i) {
        longest = set.run[i].n > longest ? set.run[i].n : longest;
    }
    double *fx = malloc(longest * sizeof *fx), *fy = malloc(longest * sizeof *fy);
    double *mx = malloc(longest * sizeof *mx), *my = malloc(longest * sizeof *my);
    if (fx == NULL || fy == NULL || mx == NULL || my == NULL) {
        fprintf(stderr, "odo-calib fit: out of memory\n");
        rc = 1;
    }
    for (size_t i = 0; i < set.n_runs && rc == 0; ++i) {
        const fit_run_t *r = &set.run[i];
        if (fit_data_firmware_track(r, &pb, fx, fy, err, sizeof err) != 0) {
            fprintf(stderr, "odo-calib fit: %s\n", err);
            rc = 1;
            break;
        }
        fit_integrate(r, base, pb.heading_form, &in_block, 0.0, 0.0, 0.0, mx, my, NULL);
        for (size_t t = 0; t < r->n; ++t) {
            const double d = hypot(fx[t] - mx[t], fy[t] - my[t]);
            fw_max = d > fw_max ? d : fw_max;
        }
    }
    free(fx);
    free(fy);
    free(mx);
    free(my);

    /* Before (the robot's calibration) and after (the fitted model), per run and folder. */
    static group_sum_t gs[FIT_MAX_GROUPS][2]; /* [group][0 judged, 1 fitted] */
    memset(gs, 0, sizeof gs);
    static fit_return_err_t eb_[FIT_MAX_RUNS], ea_[FIT_MAX_RUNS];
    for (size_t i = 0; i < set.n_runs; ++i) {
        const fit_run_t *r = &set.run[i];
        fit_return_error(r, base, pb.heading_form, &start, &res.rig[r->group], &eb_[i]);
        fit_return_error(r, base, pb.heading_form, &res.p, &res.rig[r->group], &ea_[i]);
        for (int w = 0; w < 2; ++w) {
            if ((w == 0 && r->judge) || (w == 1 && r->fit)) {
                group_sum_t *g = &gs[r->group][w];
                g->before_pos += eb_[i].pos_mm;
                g->after_pos += ea_[i].pos_mm;
                g->before_th += fabs(eb_[i].eth_deg);
                g->after_th += fabs(ea_[i].eth_deg);
                g->n++;
            }
        }
    }

    for (size_t k = 0; k < n_out && rc == 0; ++k) {
        if (calib_write_params(outs[k], &pb, &ins) != 0) {
            rc = 1;
        }
    }

    if (json) {
        printf("{\"tool\": \"odo-calib fit\", \"robot\": ");
        json_str(stdout, robot);
        printf(",\n \"params\": {\"ed\": %.9f, \"eb\": %.9f, \"es\": %.9f, \"scrub\": %.9f},\n", res.p.ed, res.p.eb,
               res.p.es, res.p.k);
        printf(" \"sd\": {\"ed\": %.3g, \"eb\": %.3g, \"es\": %.3g, \"scrub\": %.3g},\n", res.sd.ed, res.sd.eb,
               res.sd.es, res.sd.k);
        printf(" \"fitted\": {\"ed\": %s, \"eb\": %s, \"es\": %s, \"scrub\": %s},\n", fr.ed ? "true" : "false",
               fr.eb ? "true" : "false", res.es_free ? "true" : "false", res.k_free ? "true" : "false");
        printf(" \"rms_mm\": %.4f, \"residuals\": %zu, \"iterations\": %d,\n \"rig\": {", res.rms_mm, res.n_residuals,
               res.iterations);
        for (size_t g = 0; g < set.n_groups; ++g) {
            printf("%s", g ? ", " : "");
            json_str(stdout, set.group_name[g]);
            printf(": {\"lever_arm_mm\": [%.3f, %.3f], \"heading_offset_deg\": %.4f, \"fitted\": %s}", res.rig[g].lx_mm,
                   res.rig[g].ly_mm, res.rig[g].phi_rad * 180.0 / M_PI, res.rig[g].fitted ? "true" : "false");
        }
        printf("},\n \"runs\": [");
        for (size_t i = 0; i < set.n_runs; ++i) {
            const fit_run_t *r = &set.run[i];
            printf("%s\n  {\"name\": ", i ? "," : "");
            json_str(stdout, r->name);
            printf(", \"role\": \"%s\", \"truth\": \"%s\", \"before_mm\": %.3f, \"after_mm\": %.3f, "
                   "\"before_deg\": %.4f, \"after_deg\": %.4f}",
                   r->fit ? (r->judge ? "fit+judge" : "fit") : (r->judge ? "judge" : "unused"),
                   r->has_track ? "track" : "return", eb_[i].pos_mm, ea_[i].pos_mm, eb_[i].eth_deg, ea_[i].eth_deg);
        }
        printf("],\n \"groups\": [");
        int first = 1;
        for (size_t g = 0; g < set.n_groups; ++g) {
            for (int w = 0; w < 2; ++w) {
                const group_sum_t *s = &gs[g][w];
                if (s->n == 0) {
                    continue;
                }
                printf("%s\n  {\"folder\": ", first ? "" : ",");
                first = 0;
                json_str(stdout, set.group_name[g]);
                printf(", \"role\": \"%s\", \"runs\": %zu, \"pos_before_mm\": %.3f, \"pos_after_mm\": %.3f, "
                       "\"pos_factor\": %.3f, \"heading_before_deg\": %.4f, \"heading_after_deg\": %.4f, "
                       "\"heading_factor\": %.3f}",
                       w == 0 ? "judge" : "fit", s->n, s->before_pos / (double)s->n, s->after_pos / (double)s->n,
                       s->before_pos / s->after_pos, s->before_th / (double)s->n, s->after_th / (double)s->n,
                       s->before_th / s->after_th);
            }
        }
        printf("],\n \"firmware_vs_double_max_mm\": %.3e, \"can_fd_skipped\": %llu, \"out_params\": [", fw_max,
               (unsigned long long)set.can_fd_skipped);
        for (size_t k = 0; k < n_out; ++k) {
            printf("%s", k ? ", " : "");
            json_str(stdout, outs[k]);
        }
        printf("]}\n");
    } else {
        size_t nf = 0, nj = 0;
        for (size_t i = 0; i < set.n_runs; ++i) {
            nf += set.run[i].fit;
            nj += set.run[i].judge;
        }
        printf("odo-calib fit: %zu runs in %zu folders, %zu fitted, %zu judged; %d iterations, RMS %.2f mm\n",
               set.n_runs, set.n_groups, nf, nj, res.iterations, res.rms_mm);
        printf("  Ed    %.6f  (formal sd %.1e)%s\n", res.p.ed, res.sd.ed, fr.ed ? "" : "  fixed");
        printf("  Eb    %.6f  (formal sd %.1e)%s\n", res.p.eb, res.sd.eb, fr.eb ? "" : "  fixed");
        printf("  Es    %.6f  (formal sd %.1e)%s\n", res.p.es, res.sd.es,
               res.es_free ? ""
                           : (fr.es ? "  fixed: no fitted track (closed paths do not show the scale)" : "  fixed"));
        printf("  scrub %.6f  (formal sd %.1e)%s\n", res.p.k, res.sd.k, res.k_free ? "" : "  fixed");
        for (size_t g = 0; g < set.n_groups; ++g) {
            if (res.rig[g].fitted) {
                printf("  rig %-16s lever arm (%.2f, %.2f) mm, heading offset %.3f deg (nuisance)\n", set.group_name[g],
                       res.rig[g].lx_mm, res.rig[g].ly_mm, res.rig[g].phi_rad * 180.0 / M_PI);
            } else {
                printf("  rig %-16s no fitted track: truth used as is\n", set.group_name[g]);
            }
        }
        printf("\nreturn errors (000 Eq. 3.1, axle centre): before = %s, after = fitted\n", robot);
        printf("%-32s %-9s %10s %10s %11s %11s\n", "run", "role", "before mm", "after mm", "before deg", "after deg");
        for (size_t i = 0; i < set.n_runs; ++i) {
            const fit_run_t *r = &set.run[i];
            printf("%-32s %-9s %10.2f %10.2f %11.3f %11.3f\n", r->name,
                   r->fit ? (r->judge ? "fit+judge" : "fit") : (r->judge ? "judge" : "-"), eb_[i].pos_mm, ea_[i].pos_mm,
                   eb_[i].eth_deg, ea_[i].eth_deg);
        }
        printf("\n%-20s %-6s %5s %28s %28s\n", "folder", "role", "runs", "mean position mm (factor)",
               "mean |heading| deg (factor)");
        for (int w = 0; w < 2; ++w) {
            for (size_t g = 0; g < set.n_groups; ++g) {
                const group_sum_t *s = &gs[g][w];
                if (s->n == 0) {
                    continue;
                }
                printf("%-20s %-6s %5zu %9.2f -> %6.2f (x%5.1f) %9.3f -> %6.3f (x%5.1f)\n", set.group_name[g],
                       w == 0 ? "judge" : "fit", s->n, s->before_pos / (double)s->n, s->after_pos / (double)s->n,
                       s->before_pos / s->after_pos, s->before_th / (double)s->n, s->after_th / (double)s->n,
                       s->before_th / s->after_th);
            }
        }
        printf("\nfirmware replaying the written block vs the double model of it, every tick of every run: "
               "max %.2e mm (target <= 0.1 mm)\n",
               fw_max);
        if (set.can_fd_skipped) {
            printf("CAN FD lines skipped in the logs: %llu\n", (unsigned long long)set.can_fd_skipped);
        }
        for (size_t k = 0; k < n_out; ++k) {
            printf("parameters written to %s\n", outs[k]);
        }
    }
    fit_data_free(&set);
    return rc;
}
