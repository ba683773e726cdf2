/// odo-ipec selfcal / selfcal-link: IPEC's self-calibration procedures (004 s. 5.1 and 5.2), driven
/// through the SIL simulator. The estimator of 5.1 is the firmware's (odo/odo_selfcal.h); the
/// procedure of 5.2 needs an external reference (the truth at a reference mark) and lives here.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "ipec_tool.h"
#include "odo/odo_selfcal.h"
#include "params_json.h"

static const double TWO30 = 1073741824.0;

void ipec_apply_params(sim_robot_t *r, const odo_params_t *p)
{
    for (unsigned t = 0; t < r->n_trucks && t < ODO_TRUCKS; ++t) {
        r->truck[t].cal_ed = p->truck[t].ed_q30 / TWO30;
        r->truck[t].cal_eb = p->truck[t].eb_q30 / TWO30;
        r->truck[t].cal_es = p->truck[t].es_q30 / TWO30;
        r->truck[t].cal_scrub = p->truck[t].scrub_q30 / TWO30;
        r->truck[t].has_calibration = true;
    }
    r->link.cal_alpha_bias_deg = ipec_bam_deg(p->link.alpha_bias_bam);
    if (r->vehicle == SIM_VEHICLE_CLAPPER) {
        r->link.cal_beta_bias_deg = ipec_bam_deg(p->link.beta_bias_bam);
        r->link.cal_length_bias_mm = p->link.length_bias_nm / 1e6;
        r->link.cal_length_ecc_mm = p->link.length_ecc_nm / 1e6;
    }
}

/// Finish the params JSON begun with odo_out_file_begin (hostlib/odo_out.h); aborts it when p is NULL.
int ipec_write_params(odo_out_file_t *o, const odo_params_t *p)
{
    char err[4096 + 256];
    if (p == NULL) {
        odo_out_file_abort(o);
        return -1;
    }
    if (odo_params_json_write(o->f, p) != 0) {
        fprintf(stderr, "odo-ipec: cannot write %s\n", o->path);
        odo_out_file_abort(o);
        return -1;
    }
    if (odo_out_file_commit(o, err, sizeof err) != 0) {
        fprintf(stderr, "odo-ipec: %s\n", err);
        return -1;
    }
    return 0;
}

/* ---------------------------------------------------------------------------------------------
 * 004 s. 5.1: Ed and Eb from the corrective actions
 * ------------------------------------------------------------------------------------------- */
typedef struct {
    odo_selfcal_t cal;
    odo_params_t p;                  ///< what the firmware runs with
    double abs_corr_deg[ODO_TRUCKS]; ///< sum |C|
    double corr_deg[ODO_TRUCKS];     ///< sum C
} sc_ctx_t;

static void sc_tick(void *user, const sim_tick_t *tk)
{
    sc_ctx_t *c = user;
    const odo_tick_output_t *o = tk->output;
    if (!o->ipec_applied) {
        return;
    }
    for (uint8_t i = 0U; i < ODO_TRUCKS; ++i) {
        const uint32_t bf = (uint32_t)(((uint64_t)c->p.truck[i].wheelbase_nm * (uint32_t)c->p.truck[i].eb_q30) >> 30);
        odo_selfcal_add(&c->cal, i, bf, c->p.link.rotary_bits, o->dist_mm_q40[i], o->dturn_q64[i],
                        o->ipec_dtheta_bam[i]);
        c->abs_corr_deg[i] += fabs(ipec_bam_deg(o->ipec_dtheta_bam[i]));
        c->corr_deg[i] += ipec_bam_deg(o->ipec_dtheta_bam[i]);
    }
}

/// Systematic part of the corrections, per truck: |one-sided straight sum| + |one-sided turn sum|.
static double one_sided_deg(const odo_selfcal_truck_t *t)
{
    return fabs(ipec_bam_deg(t->straight_corr)) + fabs(ipec_bam_deg(t->turn_corr));
}

static int selfcal_runs(const sim_robot_t *robot, const sim_scenario_t *sc, const char *exp, unsigned runs, int ipec,
                        uint64_t seed, sc_ctx_t *ctx)
{
    char err[256];
    memset(ctx, 0, sizeof *ctx);
    odo_selfcal_init(&ctx->cal);
    if (sim_robot_to_params(robot, &ctx->p, err, sizeof err) != 0) {
        fprintf(stderr, "odo-ipec: %s\n", err);
        return -1;
    }
    for (int d = 0; d < 2; ++d) {
        for (unsigned k = 0; k < runs; ++k) {
            sim_return_t ret;
            if (ipec_run(robot, sc, exp, d, 0, ipec, seed, k, sc_tick, ctx, &ret) != 0) {
                return -1;
            }
        }
    }
    return 0;
}

int ipec_selfcal(const sim_robot_t *robot, const sim_scenario_t *sc, const char *exp, unsigned runs, int ipec,
                 uint64_t seed, ipec_selfcal_t *out)
{
    static sc_ctx_t before, after;
    memset(out, 0, sizeof *out);
    if (selfcal_runs(robot, sc, exp, runs, ipec, seed, &before) != 0) {
        return -1;
    }
    odo_selfcal_result_t res;
    if (!odo_selfcal_estimate(&before.cal, &before.p, &out->params, &res)) {
        fprintf(stderr, "odo-ipec: selfcal: not enough straight travel or turning to estimate (or out of range)\n");
        return -1;
    }
    static sim_robot_t cal;
    cal = *robot;
    ipec_apply_params(&cal, &out->params);
    if (selfcal_runs(&cal, sc, exp, runs, ipec, seed + 1000U, &after) != 0) {
        return -1;
    }
    for (unsigned i = 0; i < ODO_TRUCKS; ++i) {
        out->ed[i] = out->params.truck[i].ed_q30 / TWO30;
        out->eb[i] = out->params.truck[i].eb_q30 / TWO30;
        out->have_ed[i] = res.have_ed[i];
        out->have_eb[i] = res.have_eb[i];
        out->straight_m[i] = (double)before.cal.truck[i].straight_um / 1e6;
        out->turn_deg[i] = ipec_bam_deg(before.cal.truck[i].turn_bam);
        out->corr_deg_per_m[i] = ipec_bam_deg(res.corr_per_m_bam[i]);
        out->corr_deg_per_turn[i] = ipec_bam_deg(res.corr_per_turn_bam[i]);
        out->one_sided_before_deg[i] = one_sided_deg(&before.cal.truck[i]);
        out->one_sided_after_deg[i] = one_sided_deg(&after.cal.truck[i]);
        out->abs_before_deg[i] = before.abs_corr_deg[i];
        out->abs_after_deg[i] = after.abs_corr_deg[i];
    }
    return 0;
}

/* ---------------------------------------------------------------------------------------------
 * 004 s. 5.2: rotary-encoder bias and link-length bias, against an external reference
 * ------------------------------------------------------------------------------------------- */
typedef struct {
    double far_x; ///< firmware x of A at the far end (largest so far)
    double e_theta_deg, e_y_mm;
} far_t;

/// Straight-36m outbound leg: the error (truth - firmware) of truck A at the far reference mark,
/// where the vehicle stops before the return (the firmware's x is largest there).
static void far_tick(void *user, const sim_tick_t *tk)
{
    far_t *f = user;
    const odo_pose_t *p = &tk->output->pose[0];
    const double x = (double)p->x_mm_q32 / 4294967296.0;
    if (x >= f->far_x) {
        f->far_x = x;
        f->e_theta_deg = remainder(tk->truth[0].theta_rad * 180.0 / M_PI - ipec_est_theta_deg(p), 360.0);
        f->e_y_mm = tk->truth[0].y_mm - (double)p->y_mm_q32 / 4294967296.0;
    }
}

/// The symptoms of one parameter set: rotary -> (e_theta, e_y / 100 mm) at the far mark;
/// link -> the return heading error of one UMBmark square cw and one ccw (four rigid 90 deg turns).
static int measure(const sim_robot_t *base, const sim_scenario_t *sc, const odo_params_t *p, int link, double m[2])
{
    static sim_robot_t r;
    r = *base;
    ipec_apply_params(&r, p);
    if (!link) {
        far_t f = {-1e18, 0, 0};
        sim_return_t ret;
        if (ipec_run(&r, sc, "straight-36m", 0, 0, 2, 1U, 0U, far_tick, &f, &ret) != 0) {
            return -1;
        }
        m[0] = f.e_theta_deg;
        m[1] = f.e_y_mm / 100.0;
        return 0;
    }
    for (int d = 0; d < 2; ++d) {
        sim_return_t ret;
        if (ipec_run(&r, sc, "umbmark", d, 0, 2, 1U, 0U, NULL, NULL, &ret) != 0) {
            return -1;
        }
        m[d] = ret.etheta_deg;
    }
    return 0;
}

/// The external reference of the calibration bay (004 s. 6: sonar on the vehicle; here the
/// simulator's truth): both trucks' true poses every tick, hence the true alpha, beta and l.
typedef struct {
    double sum_a, sum_b, sum_l; ///< code centre - true angle (deg) over sweep ticks; l_meas - l_true (mm)
    unsigned n_a, n_b, n_l;
    uint16_t last_a, last_b;
    bool have_last;
    double half_step_deg;
} bay_t;

/// A code that changed since the last tick was just crossed by the motion: over a sweep the true
/// angle is uniform within the codes, so code centre - true angle averages to the bias (a held
/// code would leave an unknown offset of up to half a step). l: every tick (0.1 mm resolution).
static void bay_tick(void *user, const sim_tick_t *tk)
{
    bay_t *b = user;
    const odo_link_input_t *in = &tk->input->link;
    if (!in->rotary_present || !in->linear_present) {
        return;
    }
    if (b->have_last) {
        const double ca = ipec_bam_deg((int32_t)((uint32_t)in->alpha_bam16 << 16)) + b->half_step_deg;
        const double cb = ipec_bam_deg((int32_t)((uint32_t)in->beta_bam16 << 16)) + b->half_step_deg;
        if (in->alpha_bam16 != b->last_a) {
            b->sum_a += remainder(ca - tk->link.alpha_rad * 180.0 / M_PI, 360.0);
            b->n_a++;
        }
        if (in->beta_bam16 != b->last_b) {
            b->sum_b += remainder(cb - tk->link.beta_rad * 180.0 / M_PI, 360.0);
            b->n_b++;
        }
    }
    b->sum_l += in->length_um / 1000.0 - tk->link.length_mm;
    b->n_l++;
    b->have_last = true;
    b->last_a = in->alpha_bam16;
    b->last_b = in->beta_bam16;
}

int ipec_selfcal_link(const sim_robot_t *robot, const sim_scenario_t *sc, const odo_params_t *start,
                      ipec_selfcal_link_t *out)
{
    memset(out, 0, sizeof *out);
    out->params = *start;
    /* Before: the symptoms of 002 s. 5.2 at the references (far mark, UMBmark returns). */
    if (measure(robot, sc, start, 0, out->rotary_before) != 0 || measure(robot, sc, start, 1, out->link_before) != 0) {
        return -1;
    }
    static sim_robot_t r;
    r = *robot;
    ipec_apply_params(&r, start);
    bay_t b;
    memset(&b, 0, sizeof b);
    b.half_step_deg = 180.0 / ldexp(1.0, (int)start->link.rotary_bits);
    /* One UMBmark square each way: the spins sweep alpha and beta through 90 deg and back. */
    for (int d = 0; d < 2; ++d) {
        b.have_last = false;
        sim_return_t ret;
        if (ipec_run(&r, sc, "umbmark", d, 0, 2, 1U, 0U, bay_tick, &b, &ret) != 0) {
            return -1;
        }
    }
    if (b.n_a < 64U || b.n_b < 64U || b.n_l == 0U) {
        fprintf(stderr, "odo-ipec: selfcal-link: too few code changes to average (%u, %u)\n", b.n_a, b.n_b);
        return -1;
    }
    out->alpha_bias_deg = b.sum_a / b.n_a;
    out->beta_bias_deg = b.sum_b / b.n_b;
    out->length_bias_mm = b.sum_l / b.n_l;
    out->sweep_ticks[0] = b.n_a;
    out->sweep_ticks[1] = b.n_b;
    out->params.link.alpha_bias_bam = (int32_t)lround(out->alpha_bias_deg / 360.0 * 4294967296.0);
    out->params.link.beta_bias_bam = (int32_t)lround(out->beta_bias_deg / 360.0 * 4294967296.0);
    out->params.link.length_bias_nm = (int32_t)lround(out->length_bias_mm * 1e6);
    char err[256];
    if (odo_params_validate(&out->params, NULL, NULL) != ODO_PARAMS_OK) {
        snprintf(err, sizeof err, "the estimated biases are out of the parameter block's range");
        fprintf(stderr, "odo-ipec: selfcal-link: %s\n", err);
        return -1;
    }
    /* After: the same references with the calibrated block. */
    if (measure(robot, sc, &out->params, 0, out->rotary_after) != 0 ||
        measure(robot, sc, &out->params, 1, out->link_after) != 0) {
        return -1;
    }
    return 0;
}

/* ---------------------------------------------------------------------------------------------
 * CLI
 * ------------------------------------------------------------------------------------------- */
static int load_start(const char *vehicle, const char *robot_path, const char *scenario, const char *params,
                      sim_robot_t *robot, sim_scenario_t *sc, odo_params_t *p)
{
    char err[512];
    if (ipec_load(vehicle, robot_path, scenario, robot, sc) != 0) {
        return -1;
    }
    if (robot->vehicle != SIM_VEHICLE_CLAPPER) {
        fprintf(stderr, "odo-ipec: self-calibration is for the clapper\n");
        return -1;
    }
    if (params != NULL) {
        if (odo_params_file_load(params, p, err, sizeof err) != 0) {
            fprintf(stderr, "odo-ipec: %s\n", err);
            return -1;
        }
        odo_params_t nominal;
        if (sim_robot_to_params(robot, &nominal, err, sizeof err) != 0) {
            fprintf(stderr, "odo-ipec: %s\n", err);
            return -1;
        }
        for (unsigned t = 0; t < ODO_TRUCKS; ++t) {
            if (p->truck[t].wheel_diameter_nm != nominal.truck[t].wheel_diameter_nm ||
                p->truck[t].wheelbase_nm != nominal.truck[t].wheelbase_nm ||
                p->truck[t].counts_per_rev_milli != nominal.truck[t].counts_per_rev_milli ||
                p->vehicle != nominal.vehicle || p->link.length_nm != nominal.link.length_nm) {
                fprintf(stderr, "odo-ipec: %s: the nominal geometry differs from the robot's\n", params);
                return -1;
            }
        }
        ipec_apply_params(robot, p);
    }
    if (sim_robot_to_params(robot, p, err, sizeof err) != 0) {
        fprintf(stderr, "odo-ipec: %s\n", err);
        return -1;
    }
    return 0;
}

int ipec_cmd_selfcal(int argc, char **argv, int link)
{
    const char *robot_path = NULL, *scenario = NULL, *params = NULL, *out = NULL, *exp = "umbmark";
    long runs = 2, seed = 1;
    int ipec = 2; /* the estimator form: see tools/ipec/README.md (self-calibration) */
    for (int i = 0; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (v == NULL) {
            fprintf(stderr, "odo-ipec: %s needs a value (or is unknown)\n", a);
            return 2;
        }
        ++i;
        if (strcmp(a, "--robot") == 0) {
            robot_path = v;
        } else if (strcmp(a, "--scenario") == 0) {
            scenario = v;
        } else if (strcmp(a, "--params") == 0) {
            params = v;
        } else if (strcmp(a, "--out") == 0) {
            out = v;
        } else if (!link && strcmp(a, "--experiment") == 0) {
            exp = v;
        } else if (!link && strcmp(a, "--ipec") == 0) {
            ipec = strcmp(v, "paper") == 0 || strcmp(v, "on") == 0 ? 1 : strcmp(v, "estimator") == 0 ? 2 : -1;
            if (ipec < 0) {
                fprintf(stderr, "odo-ipec: --ipec must be paper (on) or estimator, not '%s'\n", v);
                return 2;
            }
        } else if (!link && (strcmp(a, "--runs") == 0 || strcmp(a, "--seed") == 0)) {
            char *end = NULL;
            const long n = strtol(v, &end, 10);
            if (end == v || *end != '\0' || n < (strcmp(a, "--runs") == 0 ? 1 : 0) || n > 1000000) {
                fprintf(stderr, "odo-ipec: %s must be a non-negative integer (runs >= 1), not '%s'\n", a, v);
                return 2;
            }
            *(strcmp(a, "--runs") == 0 ? &runs : &seed) = n;
        } else {
            fprintf(stderr, "odo-ipec: unknown argument '%s'\n", a);
            return 2;
        }
    }
    if (scenario == NULL || out == NULL) {
        fprintf(stderr, "odo-ipec %s: --scenario and --out are required\n", link ? "selfcal-link" : "selfcal");
        return 2;
    }
    static sim_robot_t robot;
    static sim_scenario_t sc;
    odo_params_t start;
    if (load_start("clapper", robot_path, scenario, params, &robot, &sc, &start) != 0) {
        return 1;
    }
    /* The output is checked (and its temp made) before the runs: an input is never overwritten. */
    char err[4096 + 256];
    odo_out_inputs_t ins;
    odo_out_inputs_init(&ins);
    (void)odo_out_inputs_add(&ins, robot_path, err, sizeof err);
    (void)odo_out_inputs_add(&ins, scenario, err, sizeof err);
    (void)odo_out_inputs_add(&ins, params, err, sizeof err);
    odo_out_file_t of;
    if (odo_out_file_begin(&of, out, &ins, err, sizeof err) != 0) {
        fprintf(stderr, "odo-ipec: %s\n", err);
        return 1;
    }
    if (!link) {
        static ipec_selfcal_t r;
        if (ipec_selfcal(&robot, &sc, exp, (unsigned)runs, ipec, (uint64_t)seed, &r) != 0) {
            odo_out_file_abort(&of);
            return 1;
        }
        if (ipec_write_params(&of, &r.params) != 0) {
            return 1;
        }
        printf("{\n  \"experiment\": \"%s\", \"runs_per_direction\": %ld, \"params\": \"%s\",\n  \"truck\": [\n", exp,
               runs, out);
        for (unsigned i = 0; i < ODO_TRUCKS; ++i) {
            printf(
                "    {\"ed\": %.6f, \"eb\": %.6f, \"straight_m\": %.2f, \"turn_deg\": %.1f, "
                "\"corr_deg_per_m\": %.5f, \"corr_deg_per_turn\": %.4f, \"one_sided_corr_deg_before\": %.3f, "
                "\"one_sided_corr_deg_after\": %.3f, \"abs_corr_deg_before\": %.3f, \"abs_corr_deg_after\": %.3f}%s\n",
                r.ed[i], r.eb[i], r.straight_m[i], r.turn_deg[i], r.corr_deg_per_m[i], r.corr_deg_per_turn[i],
                r.one_sided_before_deg[i], r.one_sided_after_deg[i], r.abs_before_deg[i], r.abs_after_deg[i],
                i + 1U < ODO_TRUCKS ? "," : "");
        }
        printf("  ]\n}\n");
        return 0;
    }
    static ipec_selfcal_link_t r;
    if (ipec_selfcal_link(&robot, &sc, &start, &r) != 0) {
        odo_out_file_abort(&of);
        return 1;
    }
    if (ipec_write_params(&of, &r.params) != 0) {
        return 1;
    }
    printf("{\n  \"params\": \"%s\",\n  \"alpha_bias_deg\": %.4f, \"beta_bias_deg\": %.4f, \"length_bias_mm\": %.4f,\n"
           "  \"far_mark_before\": {\"etheta_deg\": %.4f, \"ey_mm\": %.2f},\n"
           "  \"far_mark_after\": {\"etheta_deg\": %.4f, \"ey_mm\": %.2f},\n"
           "  \"umbmark_etheta_before_deg\": {\"cw\": %.4f, \"ccw\": %.4f},\n"
           "  \"umbmark_etheta_after_deg\": {\"cw\": %.4f, \"ccw\": %.4f},\n  \"sweep_ticks\": [%u, %u]\n}\n",
           out, r.alpha_bias_deg, r.beta_bias_deg, r.length_bias_mm, r.rotary_before[0], r.rotary_before[1] * 100.0,
           r.rotary_after[0], r.rotary_after[1] * 100.0, r.link_before[0], r.link_before[1], r.link_after[0],
           r.link_after[1], r.sweep_ticks[0], r.sweep_ticks[1]);
    return 0;
}
