/// odo-calib acceptance: simulated robots through UMBmark, calibration, and UMBmark again.
///
/// Each robot is a labmate (host_sim/robots/labmate.json) whose truth differs from the nominal:
/// Ed ~ U[0.995, 1.005] (mean diameter kept, 000 Eq. 6.30), b ~ U[0.97, 1.03] x 340 mm, and floor
/// roughness (0-1 mm grains about every 2 cm per wheel, 000 s. 4.6.2). One pass: runs per direction
/// cw and ccw uncalibrated, `calib_umbmark` (exact and paper), the same number of runs again with
/// each new parameter block (fresh seeds). Improvement = Emax,syst before / after (000 Table III).
/// The 3-SEM test uses the SEM of the runs after calibration (000 s. 6.3).
///
/// E-7/E-8 analogues (000 Table III): the s. 4.6.2 robot (b 337 against 340 mm, Ed 0.9985,
/// roughness) with 3 loops of 0.1 mm tape on the right wheel (E-7: D_R + 0.6 mm) or 5 on the left
/// (E-8: D_L + 1.0 mm); tape changes the mean diameter too (Es = Dn / mean). The paper needed two
/// passes for E-7; both methods get two here, side by side.
///
/// Noise-free: the same random robots without roughness; the exact fit must recover Ed within
/// 1e-5 and b within 0.05 mm.
#include "acceptance.h"

#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "calib_core.h"
#include "effects.h"
#include "robot.h"
#include "sil.h"

#define Q30        1073741824.0
#define SIDE_MM    4000.0 /* host_sim's umbmark square (000 s. 3.5) */
#define MAX_ROBOTS 200

static uint64_t splitmix(uint64_t *s)
{
    uint64_t z = (*s += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

static double uniform(uint64_t *s, double lo, double hi)
{
    return lo + (hi - lo) * ((double)(splitmix(s) >> 11) / 9007199254740992.0);
}

/// `runs` runs each way of the umbmark square; returns in *r (000 Eq. 3.1).
static int run_umbmark(const sim_robot_t *robot, const sim_scenario_t *sc, unsigned runs, uint64_t seed, returns_t *r,
                       char *err, size_t errlen)
{
    memset(r, 0, sizeof *r);
    for (int d = 0; d < 2; ++d) {
        for (unsigned k = 0; k < runs; ++k) {
            const sim_run_config_t cfg = {
                .robot = robot,
                .scenario = sc,
                .experiment = "umbmark",
                .ccw = d,
                .bumps = -1,
                .bump_height_mm = 10.0,
                .ipec = 0,
                .seed = sim_run_seed(seed, d, k),
                .run_index = k,
            };
            sim_return_t ret;
            if (sim_run(&cfg, NULL, NULL, &ret, err, errlen) != 0) {
                return -1;
            }
            const size_t i = r->n[d]++;
            r->run[d][i] = k + 1;
            r->ex_mm[d][i] = ret.ex_mm;
            r->ey_mm[d][i] = ret.ey_mm;
            r->etheta_deg[d][i] = ret.etheta_deg;
        }
    }
    return 0;
}

typedef struct {
    double emax_mm, sem_mm;
} stat_t;

static int stats_of(const returns_t *r, stat_t *s, char *err, size_t errlen)
{
    static odo_umb_return_t u[2][RETURNS_MAX_RUNS];
    odo_umb_stats_t st;
    if (returns_to_umb(r, u, err, errlen) != 0) {
        return -1;
    }
    const odo_umb_status_t rc = odo_umb_stats(u[0], r->n[0], u[1], r->n[1], &st);
    if (rc != ODO_UMB_OK) {
        snprintf(err, errlen, "%s", odo_umb_status_str(rc));
        return -1;
    }
    s->emax_mm = st.emax_syst_um / 1000.0;
    s->sem_mm = st.sem_um / 1000.0;
    return 0;
}

/// The robot with a parameter block's truck A calibration (what `odo-sim --params` does).
static void with_calibration(const sim_robot_t *base, const odo_params_t *p, sim_robot_t *out)
{
    *out = *base;
    out->truck[0].cal_ed = p->truck[0].ed_q30 / Q30;
    out->truck[0].cal_eb = p->truck[0].eb_q30 / Q30;
    out->truck[0].cal_es = p->truck[0].es_q30 / Q30;
    out->truck[0].cal_scrub = p->truck[0].scrub_q30 / Q30;
    out->truck[0].has_calibration = true;
}

typedef struct {
    double ed_true, b_true;
    stat_t before;
    stat_t after[2][2]; ///< [method][pass]
    double ed_fit[2];   ///< first pass, [method]
    double b_fit[2];
} robot_result_t;

/// Calibrate from `r` with params `in_force`, run again; `passes` times. Returns 0 or -1.
static int calibrate_and_rerun(const sim_robot_t *base, const sim_scenario_t *sc, const returns_t *first, unsigned runs,
                               uint64_t seed, calib_method_t m, unsigned passes, robot_result_t *rr, char *err,
                               size_t errlen)
{
    static returns_t r;
    r = *first;
    odo_params_t in_force;
    if (sim_robot_to_params(base, &in_force, err, errlen) != 0) {
        return -1;
    }
    for (unsigned pass = 0; pass < passes; ++pass) {
        calib_result_t c;
        if (calib_umbmark(&r, SIDE_MM, &in_force, m, &c, err, errlen) != 0) {
            return -1;
        }
        if (pass == 0) {
            rr->ed_fit[m] = c.ed_q30 / Q30;
            rr->b_fit[m] = c.b_actual_mm;
        }
        odo_params_t np;
        calib_apply(&in_force, &c, &np);
        sim_robot_t cal;
        with_calibration(base, &np, &cal);
        if (run_umbmark(&cal, sc, runs, seed + 7919U * (pass + 1U), &r, err, errlen) != 0 ||
            stats_of(&r, &rr->after[m][pass], err, errlen) != 0) {
            return -1;
        }
        in_force = np;
    }
    return 0;
}

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *v, size_t n)
{
    qsort(v, n, sizeof *v, cmp_double);
    return n == 0 ? (double)NAN : (n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]));
}

static int make_scenario(sim_scenario_t *sc, double ed, double eb, double es, int rough, uint64_t seed, char *err,
                         size_t errlen)
{
    sim_scenario_none(sc);
    sc->seed = seed;
    if (sim_scenario_set(sc, "ed", "value", 1U, ed, err, errlen) != 0 ||
        sim_scenario_set(sc, "eb", "value", 1U, eb, err, errlen) != 0 ||
        (es != 1.0 && sim_scenario_set(sc, "es", "value", 1U, es, err, errlen) != 0) ||
        (rough && sim_scenario_set(sc, "roughness", NULL, 1U, 0.0, err, errlen) != 0)) {
        return -1;
    }
    return 0;
}

int calib_acceptance_main(int argc, char **argv)
{
    long n_robots = 20, runs = 5;
    uint64_t seed = 1;
    int json = 0, quiet = 0, tape = 1, check = 0;
    for (int i = 0; i < argc; ++i) {
        const char *a = argv[i];
        if (strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0) {
            printf("usage: odo-calib acceptance [--robots N] [--seed S] [--runs N] [--json] [--no-tape] [--quiet]\n"
                   "                            [--check]\n"
                   "\n"
                   "N simulated labmates (default 20; Ed ~ U[0.995, 1.005], b ~ U[0.97, 1.03] x 340 mm,\n"
                   "floor roughness) through UMBmark (--runs per direction, default 5), one calibration\n"
                   "pass with the exact and with the paper method, and UMBmark again. Prints a table like\n"
                   "000 Table III and the summary (median improvement, share of robots with Emax,syst <=\n"
                   "3 SEM after one pass), the E-7/E-8 tape analogues (unless --no-tape) and the\n"
                   "noise-free recovery of Ed and b. --json: one JSON object instead. --check: exit 1\n"
                   "unless the issue's targets hold (median exact improvement >= 20x, >= 95%% within\n"
                   "3 SEM, noise-free |dEd| <= 1e-5 and |db| <= 0.05 mm). Progress on stderr.\n");
            return 0;
        } else if (strcmp(a, "--json") == 0) {
            json = 1;
        } else if (strcmp(a, "--quiet") == 0) {
            quiet = 1;
        } else if (strcmp(a, "--no-tape") == 0) {
            tape = 0;
        } else if (strcmp(a, "--check") == 0) {
            check = 1;
        } else if ((strcmp(a, "--robots") == 0 || strcmp(a, "--runs") == 0 || strcmp(a, "--seed") == 0) &&
                   i + 1 < argc) {
            char *end = NULL;
            errno = 0;
            const char *v = argv[++i];
            const unsigned long long x = strtoull(v, &end, 10);
            const unsigned long long hi = strcmp(a, "--robots") == 0 ? MAX_ROBOTS
                                          : strcmp(a, "--runs") == 0 ? 100
                                                                     : UINT64_MAX;
            if (errno != 0 || end == v || *end != '\0' || v[0] == '-' ||
                (strcmp(a, "--seed") != 0 && (x < 1 || x > hi)) || (strcmp(a, "--runs") == 0 && x < 2)) {
                fprintf(stderr, "odo-calib acceptance: %s: '%s' is not valid (robots 1-%d, runs 2-100)\n", a, v,
                        MAX_ROBOTS);
                return 2;
            }
            if (strcmp(a, "--robots") == 0) {
                n_robots = (long)x;
            } else if (strcmp(a, "--runs") == 0) {
                runs = (long)x;
            } else {
                seed = x;
            }
        } else {
            fprintf(stderr, "odo-calib acceptance: unknown or incomplete argument '%s'\n", a);
            return 2;
        }
    }
    static sim_robot_t base;
    char err[512];
    if (sim_robot_default(SIM_VEHICLE_LABMATE, &base) != 0) {
        fprintf(stderr, "odo-calib acceptance: no stock labmate\n");
        return 1;
    }
    static robot_result_t res[MAX_ROBOTS];
    static returns_t first;
    static sim_scenario_t sc;
    uint64_t rng = seed * 0x2545F4914F6CDD1DULL + 1U;
    double nf_ed_max = 0.0, nf_b_max = 0.0;
    for (long i = 0; i < n_robots; ++i) {
        robot_result_t *rr = &res[i];
        rr->ed_true = uniform(&rng, 0.995, 1.005);
        rr->b_true = uniform(&rng, 0.97, 1.03) * 340.0;
        const uint64_t rseed = splitmix(&rng);
        if (make_scenario(&sc, rr->ed_true, rr->b_true / 340.0, 1.0, 1, rseed, err, sizeof err) != 0 ||
            run_umbmark(&base, &sc, (unsigned)runs, rseed, &first, err, sizeof err) != 0 ||
            stats_of(&first, &rr->before, err, sizeof err) != 0 ||
            calibrate_and_rerun(&base, &sc, &first, (unsigned)runs, rseed, CALIB_EXACT, 1, rr, err, sizeof err) != 0 ||
            calibrate_and_rerun(&base, &sc, &first, (unsigned)runs, rseed, CALIB_PAPER, 1, rr, err, sizeof err) != 0) {
            fprintf(stderr, "odo-calib acceptance: robot %ld: %s\n", i + 1, err);
            return 1;
        }
        /* Noise-free: same robot, no roughness, 2 runs each way (deterministic). */
        static returns_t nf;
        calib_result_t c;
        odo_params_t in_force;
        if (make_scenario(&sc, rr->ed_true, rr->b_true / 340.0, 1.0, 0, rseed, err, sizeof err) != 0 ||
            run_umbmark(&base, &sc, 2, rseed, &nf, err, sizeof err) != 0 ||
            sim_robot_to_params(&base, &in_force, err, sizeof err) != 0 ||
            calib_umbmark(&nf, SIDE_MM, &in_force, CALIB_EXACT, &c, err, sizeof err) != 0) {
            fprintf(stderr, "odo-calib acceptance: robot %ld (noise-free): %s\n", i + 1, err);
            return 1;
        }
        nf_ed_max = fmax(nf_ed_max, fabs(c.fit.ed - rr->ed_true));
        nf_b_max = fmax(nf_b_max, fabs(c.fit.b_mm - rr->b_true));
        if (!quiet) {
            fprintf(stderr,
                    "odo-calib acceptance: robot %2ld/%ld  Ed %.5f  b %.2f mm  Emax,syst %7.1f -> exact %5.1f, "
                    "paper %6.1f mm   noise-free dEd %.1e db %.4f mm\n",
                    i + 1, n_robots, rr->ed_true, rr->b_true, rr->before.emax_mm, rr->after[CALIB_EXACT][0].emax_mm,
                    rr->after[CALIB_PAPER][0].emax_mm, fabs(c.fit.ed - rr->ed_true), fabs(c.fit.b_mm - rr->b_true));
        }
    }
    /* Summary. */
    double imp[2][MAX_ROBOTS];
    unsigned within[2] = {0, 0};
    for (int m = 0; m < 2; ++m) {
        for (long i = 0; i < n_robots; ++i) {
            const stat_t *a = &res[i].after[m][0];
            imp[m][i] = res[i].before.emax_mm / fmax(a->emax_mm, 1e-3);
            within[m] += a->emax_mm <= 3.0 * a->sem_mm;
        }
    }
    double med[2];
    for (int m = 0; m < 2; ++m) {
        double tmp[MAX_ROBOTS];
        memcpy(tmp, imp[m], sizeof(double) * (size_t)n_robots);
        med[m] = median(tmp, (size_t)n_robots);
    }
    const double frac[2] = {within[0] / (double)n_robots, within[1] / (double)n_robots};

    /* E-7 / E-8 analogues. */
    typedef struct {
        const char *name, *what;
        double ed, es;
        stat_t before;
        robot_result_t rr;
    } tape_t;
    tape_t tp[2];
    memset(tp, 0, sizeof tp);
    tp[0].name = "E-7";
    tp[0].what = "3 loops of 0.1 mm tape on the right wheel";
    tp[1].name = "E-8";
    tp[1].what = "5 loops of 0.1 mm tape on the left wheel";
    if (tape) {
        const double ed0 = 0.9985, dn = 150.0, eb0 = 337.0 / 340.0;
        for (int k = 0; k < 2; ++k) {
            double dl = dn * 2.0 / (ed0 + 1.0), dr = dn * 2.0 * ed0 / (ed0 + 1.0);
            if (k == 0) {
                dr += 2.0 * 3.0 * 0.1;
            } else {
                dl += 2.0 * 5.0 * 0.1;
            }
            tp[k].ed = dr / dl;
            tp[k].es = dn / ((dl + dr) / 2.0);
            const uint64_t tseed = seed * 1000U + 7U + (uint64_t)k;
            if (make_scenario(&sc, tp[k].ed, eb0, tp[k].es, 1, tseed, err, sizeof err) != 0 ||
                run_umbmark(&base, &sc, (unsigned)runs, tseed, &first, err, sizeof err) != 0 ||
                stats_of(&first, &tp[k].before, err, sizeof err) != 0 ||
                calibrate_and_rerun(&base, &sc, &first, (unsigned)runs, tseed, CALIB_EXACT, 2, &tp[k].rr, err,
                                    sizeof err) != 0 ||
                calibrate_and_rerun(&base, &sc, &first, (unsigned)runs, tseed, CALIB_PAPER, 2, &tp[k].rr, err,
                                    sizeof err) != 0) {
                fprintf(stderr, "odo-calib acceptance: %s: %s\n", tp[k].name, err);
                return 1;
            }
            if (!quiet) {
                fprintf(stderr, "odo-calib acceptance: %s  Emax,syst %.1f -> exact %.1f, %.1f; paper %.1f, %.1f mm\n",
                        tp[k].name, tp[k].before.emax_mm, tp[k].rr.after[1][0].emax_mm, tp[k].rr.after[1][1].emax_mm,
                        tp[k].rr.after[0][0].emax_mm, tp[k].rr.after[0][1].emax_mm);
            }
        }
    }
    const int pass = med[CALIB_EXACT] >= 20.0 && frac[CALIB_EXACT] >= 0.95 && nf_ed_max <= 1e-5 && nf_b_max <= 0.05;

    if (json) {
        printf("{\"robots\": %ld, \"seed\": %" PRIu64 ", \"runs_per_direction\": %ld, \"side_mm\": %.0f,\n", n_robots,
               seed, runs, SIDE_MM);
        printf(" \"exact\": {\"median_improvement\": %.3f, \"within_3sem_fraction\": %.4f},\n", med[CALIB_EXACT],
               frac[CALIB_EXACT]);
        printf(" \"paper\": {\"median_improvement\": %.3f, \"within_3sem_fraction\": %.4f},\n", med[CALIB_PAPER],
               frac[CALIB_PAPER]);
        printf(" \"noise_free\": {\"max_abs_ed_error\": %.3e, \"max_abs_b_error_mm\": %.5f},\n", nf_ed_max, nf_b_max);
        printf(" \"targets_met\": %s,\n \"per_robot\": [\n", pass ? "true" : "false");
        for (long i = 0; i < n_robots; ++i) {
            const robot_result_t *rr = &res[i];
            printf("  {\"ed_true\": %.7f, \"b_true_mm\": %.4f, \"emax_before_mm\": %.3f, "
                   "\"exact\": {\"ed\": %.7f, \"b_mm\": %.4f, \"emax_after_mm\": %.3f, \"sem_after_mm\": %.3f}, "
                   "\"paper\": {\"ed\": %.7f, \"b_mm\": %.4f, \"emax_after_mm\": %.3f, \"sem_after_mm\": %.3f}}%s\n",
                   rr->ed_true, rr->b_true, rr->before.emax_mm, rr->ed_fit[1], rr->b_fit[1], rr->after[1][0].emax_mm,
                   rr->after[1][0].sem_mm, rr->ed_fit[0], rr->b_fit[0], rr->after[0][0].emax_mm, rr->after[0][0].sem_mm,
                   i + 1 < n_robots ? "," : "");
        }
        printf(" ],\n \"tape\": [");
        for (int k = 0; tape && k < 2; ++k) {
            const tape_t *t = &tp[k];
            printf("%s\n  {\"experiment\": \"%s\", \"what\": \"%s\", \"ed_true\": %.6f, \"es_true\": %.6f, "
                   "\"emax_before_mm\": %.3f, \"exact_after_mm\": [%.3f, %.3f], \"paper_after_mm\": [%.3f, %.3f], "
                   "\"sem_after_exact_mm\": %.3f}",
                   k ? "," : "", t->name, t->what, t->ed, t->es, t->before.emax_mm, t->rr.after[1][0].emax_mm,
                   t->rr.after[1][1].emax_mm, t->rr.after[0][0].emax_mm, t->rr.after[0][1].emax_mm,
                   t->rr.after[1][0].sem_mm);
        }
        printf("]}\n");
    } else {
        printf("UMBmark calibration, %ld simulated labmates (seed %" PRIu64 ", %ld runs per direction, 4 x 4 m,\n"
               "floor roughness 0-1 mm every ~2 cm), one pass; Emax,syst in mm (000 Eq. 3.4), cf. 000 Table III\n\n",
               n_robots, seed, runs);
        printf("%5s %9s %8s | %8s | %8s %7s %6s | %8s %7s %6s\n", "robot", "Ed true", "b true", "before", "exact", "x",
               "<=3SEM", "paper", "x", "<=3SEM");
        for (long i = 0; i < n_robots; ++i) {
            const robot_result_t *rr = &res[i];
            const stat_t *e = &rr->after[1][0], *p = &rr->after[0][0];
            printf("%5ld %9.5f %8.2f | %8.1f | %8.1f %6.1fx %6s | %8.1f %6.1fx %6s\n", i + 1, rr->ed_true, rr->b_true,
                   rr->before.emax_mm, e->emax_mm, imp[1][i], e->emax_mm <= 3 * e->sem_mm ? "yes" : "no", p->emax_mm,
                   imp[0][i], p->emax_mm <= 3 * p->sem_mm ? "yes" : "no");
        }
        printf("\n%-40s %12s %12s %10s\n", "", "exact", "paper", "target");
        printf("%-40s %11.1fx %11.1fx %10s\n", "median improvement (before/after)", med[1], med[0], ">= 20x");
        printf("%-40s %11.0f%% %11.0f%% %10s\n", "Emax,syst <= 3 SEM after one pass", 100 * frac[1], 100 * frac[0],
               ">= 95%");
        printf("%-40s %12.1e %12s %10s\n", "noise-free max |Ed error|", nf_ed_max, "", "<= 1e-5");
        printf("%-40s %12.4f %12s %10s\n", "noise-free max |b error| (mm)", nf_b_max, "", "<= 0.05");
        if (tape) {
            printf("\nTape analogues of 000 Table III E-7/E-8 on the s. 4.6.2 robot (b 337/340 mm, Ed 0.9985):\n");
            printf("%-5s %-44s %8s | %15s | %15s\n", "", "", "before", "exact 1st, 2nd", "paper 1st, 2nd");
            for (int k = 0; k < 2; ++k) {
                const tape_t *t = &tp[k];
                printf("%-5s %-44s %8.1f | %6.1f, %6.1f | %6.1f, %6.1f\n", t->name, t->what, t->before.emax_mm,
                       t->rr.after[1][0].emax_mm, t->rr.after[1][1].emax_mm, t->rr.after[0][0].emax_mm,
                       t->rr.after[0][1].emax_mm);
            }
            printf("(paper, 000 Table III: E-7 423 -> 66 -> 20 mm; E-8 232 -> 12 mm)\n");
        }
        printf("\ntargets %s\n", pass ? "met" : "NOT met");
    }
    return check && !pass ? 1 : 0;
}
