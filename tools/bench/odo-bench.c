/// odo-bench: benchmark figures as one JSON object. Built optimised and without sanitizers in
/// every preset, so the figures mean the same everywhere. Timing-free: accuracy figures are
/// computed, and the cost of a step is counted in instructions by callgrind, which is repeatable
/// on a loaded machine (wall-clock figures added by later issues are reported beside a reference).
#include <errno.h>
#include <inttypes.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "odo_cli.h"
#include "odo/odo_app.h"
#include "odo_refcheck.h"
#include "odo_synth.h"
#include "replay_bench.h"
#include "robot.h"
#include "sil.h"
#include "trig_accuracy.h"

#define KERNEL_STEPS 20000U

static void usage(FILE *f)
{
    fprintf(f, "usage: odo-bench [--json] [--quick]\n"
               "       odo-bench --help | --version\n"
               "\n"
               "Prints the firmware's benchmark figures:\n"
               "  pos_err_mm_1km, heading_err_rad_1km  fixed point vs double after 1 km of mixed\n"
               "                                       driving (worst of 6 runs; targets 0.1, 1e-6)\n"
               "  pos_err_mm_1km_scrub, heading_err_rad_1km_scrub  the same with the tyre-scrub\n"
               "                                       term on, k = +-0.01 and +-0.2 (worst of 8 runs)\n"
               "  sincos_max_abs_err, atan2_max_abs_err_rad  vs libm over 10^6 random inputs + edges\n"
               "  ipec_step_instructions               the same with IPEC on (paper form, every tick)\n"
               "  step_instructions                    x86-64 instructions per 40 ms application\n"
               "                                       step for two trucks, counted by callgrind\n"
               "  scrub_step_instructions              the same with scrub k = 0.0095 on both trucks\n"
               "  scrub_arc_step_instructions          the same on arcs only (the term's worst case)\n"
               "  sim_umbmark_10runs_s                 wall seconds for the 10-run UMBmark set of the\n"
               "                                       000 s. 4.6.2 robot at 1 ms physics, firmware in\n"
               "                                       the loop (target < 1 s on one core)\n"
               "  sim_realtime_factor                  simulated seconds per wall second in that set\n"
               "  replay_ticks_per_s                   odo-replay's offline loop (parse, assemble, step,\n"
               "                                       output lines) on a 1-hour clapper sim log\n"
               "  replay_vs_python_can_ratio           its frames/s over python-can's CanutilsLogReader\n"
               "                                       merely reading the same file (target >= 20)\n"
               "  --json   one JSON object on stdout (progress goes to stderr)\n"
               "  --quick  fewer samples (for smoke tests; figures are then indicative only)\n");
}

typedef enum { KERNEL_PLAIN, KERNEL_IPEC, KERNEL_SCRUB, KERNEL_SCRUB_ARC } kernel_t;

/// Hidden mode run under callgrind: KERNEL_STEPS application steps of a clapper (two trucks).
static int run_kernel(kernel_t kind)
{
    static odo_app_t app;
    static odo_tick_output_t out;
    const int ipec = kind == KERNEL_IPEC;
    odo_params_t p;
    odo_params_defaults(&p);
    p.vehicle = ODO_VEHICLE_CLAPPER;
    p.ipec_mode = (uint8_t)(ipec ? ODO_IPEC_PAPER : ODO_IPEC_OFF); /* --kernel-ipec: 002 Eqs. 9-16 */
    if (kind == KERNEL_SCRUB || kind == KERNEL_SCRUB_ARC) {        /* the OptiOdom robot's k */
        p.truck[0].scrub_q30 = p.truck[1].scrub_q30 = (int32_t)llround(0.0095 * 1073741824.0);
    }
    if (odo_app_init_params(&app, &p) != ODO_PARAMS_OK) {
        return 2;
    }
    odo_synth_t s[2];
    odo_synth_init(&s[0], 1U, &p.truck[0], p.tick_us);
    odo_synth_init(&s[1], 2U, &p.truck[1], p.tick_us);
    if (kind == KERNEL_SCRUB_ARC) { /* both wheels forward at different speeds on every tick */
        odo_synth_segment(&s[0], 400.0, 700.0, KERNEL_STEPS + 1U);
        odo_synth_segment(&s[1], 900.0, 650.0, KERNEL_STEPS + 1U);
    }
    int64_t c[2][2] = {{0, 0}, {0, 0}};
    uint64_t sink = 0U;
    for (uint32_t i = 0U; i < KERNEL_STEPS; ++i) {
        odo_tick_input_t in;
        memset(&in, 0, sizeof in);
        in.t_us = (uint64_t)i * p.tick_us;
        for (int t = 0; t < 2; ++t) {
            int32_t dl, dr;
            odo_synth_next(&s[t], &dl, &dr);
            c[t][0] += dl;
            c[t][1] += dr;
            in.wheel[t].present = true;
            in.wheel[t].bits = 24U;
            in.wheel[t].seq = (uint8_t)i;
            in.wheel[t].left_raw = (uint32_t)((uint64_t)c[t][0] & 0xFFFFFFU);
            in.wheel[t].right_raw = (uint32_t)((uint64_t)c[t][1] & 0xFFFFFFU);
        }
        if (ipec) { /* a fresh, valid linkage sample every tick, so IPEC runs every tick */
            in.link.rotary_present = in.link.linear_present = true;
            in.link.rotary_seq = in.link.linear_seq = (uint8_t)i;
            in.link.rotary_status = ODO_LINK_STATUS_ALPHA_VALID | ODO_LINK_STATUS_BETA_VALID;
            in.link.linear_status = ODO_LINK_STATUS_LENGTH_VALID;
            in.link.alpha_bam16 = (uint16_t)(i & 0x3FU) << 6;
            in.link.beta_bam16 = (uint16_t)(0U - ((i & 0x3FU) << 6));
            in.link.length_um = 1000000U;
        }
        odo_app_step(&app, &in, &out);
        sink += out.frames[0].data[0];
    }
    return sink == UINT64_MAX ? 3 : 0;
}

/// Count instructions inside odo_app_step with callgrind. Returns -1 if valgrind is unavailable.
static double step_instructions(char *tool, size_t tool_len, const char *kernel)
{
    char self[PATH_MAX];
    const ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1U);
    if (n <= 0) {
        return -1.0;
    }
    self[n] = '\0';
    char out_file[] = "/tmp/odo-bench-callgrind-XXXXXX";
    const int fd = mkstemp(out_file);
    if (fd < 0) {
        return -1.0;
    }
    close(fd);
    char cmd[3 * PATH_MAX];
    snprintf(cmd, sizeof cmd,
             "valgrind --tool=callgrind --toggle-collect=odo_app_step --callgrind-out-file=%s "
             "'%s' %s >/dev/null 2>&1",
             out_file, self, kernel);
    const int rc = system(cmd);
    double per_step = -1.0;
    FILE *f = (rc == 0) ? fopen(out_file, "r") : NULL;
    if (f != NULL) {
        char line[512];
        while (fgets(line, sizeof line, f) != NULL) {
            unsigned long long total;
            if (sscanf(line, "totals: %llu", &total) == 1 || sscanf(line, "summary: %llu", &total) == 1) {
                per_step = (double)total / KERNEL_STEPS;
                break;
            }
        }
        fclose(f);
    }
    remove(out_file);
    FILE *v = popen("valgrind --version 2>/dev/null", "r");
    char ver[64] = "valgrind";
    if (v != NULL) {
        if (fgets(ver, sizeof ver, v) != NULL) {
            ver[strcspn(ver, "\n")] = '\0';
        }
        pclose(v);
    }
    snprintf(tool, tool_len, "callgrind (%s), --toggle-collect=odo_app_step", ver);
    return per_step;
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

/// The 10-run UMBmark set (5 cw, 5 ccw) of the 000 s. 4.6.2 robot (b 337 vs 340 mm, Ed 0.9985,
/// 0-1 mm roughness). Returns wall seconds, and simulated seconds in *sim_s; -1 on error.
static double sim_umbmark_10runs(double *sim_s)
{
    static sim_robot_t robot;
    static sim_scenario_t sc;
    char err[256];
    if (sim_robot_default(SIM_VEHICLE_LABMATE, &robot) != 0) {
        return -1.0;
    }
    sim_scenario_none(&sc);
    if (sim_scenario_set(&sc, "eb", "value", 1U, 337.0 / 340.0, err, sizeof err) != 0 ||
        sim_scenario_set(&sc, "ed", "value", 1U, 0.9985, err, sizeof err) != 0 ||
        sim_scenario_set(&sc, "roughness", NULL, 1U, 0.0, err, sizeof err) != 0) {
        fprintf(stderr, "odo-bench: %s\n", err);
        return -1.0;
    }
    *sim_s = 0.0;
    const double t0 = now_s();
    for (int d = 0; d < 2; ++d) {
        for (unsigned k = 0; k < 5U; ++k) {
            sim_run_config_t cfg = {.robot = &robot,
                                    .scenario = &sc,
                                    .experiment = "umbmark",
                                    .ccw = d,
                                    .bumps = -1,
                                    .bump_height_mm = 10.0,
                                    .seed = 100U + k,
                                    .run_index = k};
            sim_return_t ret;
            if (sim_run(&cfg, NULL, NULL, &ret, err, sizeof err) != 0) {
                fprintf(stderr, "odo-bench: %s\n", err);
                return -1.0;
            }
            *sim_s += ret.t_end_s;
        }
    }
    return now_s() - t0;
}

int main(int argc, char **argv)
{
    int json = 0, quick = 0;
    for (int i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "--kernel") == 0) {
            return run_kernel(KERNEL_PLAIN);
        } else if (strcmp(argv[i], "--kernel-ipec") == 0) {
            return run_kernel(KERNEL_IPEC);
        } else if (strcmp(argv[i], "--kernel-scrub") == 0) {
            return run_kernel(KERNEL_SCRUB);
        } else if (strcmp(argv[i], "--kernel-scrub-arc") == 0) {
            return run_kernel(KERNEL_SCRUB_ARC);
        } else if (strcmp(argv[i], "--json") == 0) {
            json = 1;
        } else if (strcmp(argv[i], "--quick") == 0) {
            quick = 1;
        } else if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            usage(stdout);
            return 0;
        } else if (strcmp(argv[i], "--version") == 0) {
            odo_cli_print_version("odo-bench");
            return 0;
        } else {
            fprintf(stderr, "odo-bench: unknown argument '%s'\n\n", argv[i]);
            usage(stderr);
            return 2;
        }
    }

    fprintf(stderr, "odo-bench: fixed vs double over 1 km of mixed driving ...\n");
    double pos = 0.0, head = 0.0;
    const uint8_t widths[3] = {16U, 24U, 32U};
    odo_params_t p;
    odo_params_defaults(&p);
    for (int run = 0; run < (quick ? 2 : 6); ++run) {
        odo_refcheck_t r;
        if (odo_refcheck_run(1000U + (uint64_t)run, widths[run % 3], (uint8_t)(run / 3), &p.truck[0], &p.truck[0],
                             1.0e6, &r) != 0) {
            fprintf(stderr, "odo-bench: default parameters refused by the model\n");
            return 1;
        }
        pos = fmax(pos, r.pos_err_mm);
        head = fmax(head, r.heading_err_rad);
    }
    fprintf(stderr, "odo-bench: the same with the tyre-scrub term, k = +-0.01 and +-0.2 ...\n");
    double pos_scrub = 0.0, head_scrub = 0.0;
    static const double scrub_k[4] = {0.01, -0.01, 0.2, -0.2};
    for (int run = 0; run < (quick ? 4 : 8); ++run) {
        odo_truck_params_t tp = p.truck[0];
        tp.scrub_q30 = (int32_t)llround(scrub_k[run % 4] * 1073741824.0);
        odo_refcheck_t r;
        if (odo_refcheck_run(2000U + (uint64_t)run, widths[run % 3], (uint8_t)(run / 4), &tp, &tp, 1.0e6, &r) != 0) {
            fprintf(stderr, "odo-bench: scrub parameters refused by the model\n");
            return 1;
        }
        pos_scrub = fmax(pos_scrub, r.pos_err_mm);
        head_scrub = fmax(head_scrub, r.heading_err_rad);
    }
    fprintf(stderr, "odo-bench: trig accuracy against libm ...\n");
    double sc = 0.0, at = 0.0;
    odo_trig_accuracy(42U, quick ? 100000U : 1000000U, &sc, &at);
    fprintf(stderr, "odo-bench: instructions per step (callgrind) ...\n");
    char tool[160] = "";
    const double instr = step_instructions(tool, sizeof tool, "--kernel");
    const double ipec_instr = instr >= 0.0 ? step_instructions(tool, sizeof tool, "--kernel-ipec") : -1.0;
    const double scrub_instr = instr >= 0.0 ? step_instructions(tool, sizeof tool, "--kernel-scrub") : -1.0;
    const double scrub_arc_instr = instr >= 0.0 ? step_instructions(tool, sizeof tool, "--kernel-scrub-arc") : -1.0;
    fprintf(stderr, "odo-bench: 10-run UMBmark in the simulator ...\n");
    double sim_s = 0.0;
    const double sim_wall = sim_umbmark_10runs(&sim_s);
    fprintf(stderr, "odo-bench: offline replay of a 1-hour clapper log vs python-can ...\n");
    replay_bench_t rb;
    const int rb_ok = replay_bench_run(quick ? 1 : 3, NULL, &rb) == 0;

    if (json) {
        printf("{\"pos_err_mm_1km\": %.6g, \"heading_err_rad_1km\": %.6g, "
               "\"pos_err_mm_1km_scrub\": %.6g, \"heading_err_rad_1km_scrub\": %.6g, "
               "\"sincos_max_abs_err\": %.6g, \"atan2_max_abs_err_rad\": %.6g, ",
               pos, head, pos_scrub, head_scrub, sc, at);
        if (instr >= 0.0) {
            printf("\"step_instructions\": %.0f, \"step_instructions_tool\": \"%s\", ", instr, tool);
        } else {
            printf("\"step_instructions\": null, \"step_instructions_tool\": \"valgrind not available\", ");
        }
        printf("\"step_instructions_trucks\": 2, ");
        if (ipec_instr >= 0.0) {
            printf("\"ipec_step_instructions\": %.0f, ", ipec_instr); /* two trucks + IPEC (paper form) */
        } else {
            printf("\"ipec_step_instructions\": null, ");
        }
        if (scrub_instr >= 0.0 && scrub_arc_instr >= 0.0) { /* two trucks, scrub term on (k 0.0095) */
            printf("\"scrub_step_instructions\": %.0f, \"scrub_arc_step_instructions\": %.0f, ", scrub_instr,
                   scrub_arc_instr);
        } else {
            printf("\"scrub_step_instructions\": null, \"scrub_arc_step_instructions\": null, ");
        }
        if (sim_wall >= 0.0) {
            printf("\"sim_umbmark_10runs_s\": %.4f, \"sim_realtime_factor\": %.0f, \"sim_seconds\": %.1f, ", sim_wall,
                   sim_s / sim_wall, sim_s);
        } else {
            printf("\"sim_umbmark_10runs_s\": null, \"sim_realtime_factor\": null, ");
        }
        if (rb_ok) { /* issue 6: replay throughput and the python-can reference */
            printf("\"replay_ticks_per_s\": %.0f, \"replay_frames_per_s\": %.0f, \"replay_ticks\": %lu, "
                   "\"replay_with_output_ticks_per_s\": %.0f, ",
                   rb.ticks_per_s, rb.frames_per_s, rb.ticks, rb.with_output_ticks_per_s);
            if (rb.ratio > 0.0) {
                printf("\"python_can_frames_per_s\": %.0f, \"replay_vs_python_can_ratio\": %.1f, "
                       "\"replay_ipec_ticks_per_s\": %.0f, \"replay_ipec_vs_python_can_ratio\": %.1f, ",
                       rb.python_can_frames_per_s, rb.ratio, rb.ipec_ticks_per_s, rb.ipec_ratio);
            } else {
                printf("\"python_can_frames_per_s\": null, \"replay_vs_python_can_ratio\": null, ");
            }
        } else {
            printf("\"replay_ticks_per_s\": null, \"replay_vs_python_can_ratio\": null, ");
        }
        printf("\"targets\": {\"pos_err_mm_1km\": 0.1, "
               "\"heading_err_rad_1km\": 1e-06, \"pos_err_mm_1km_scrub\": 0.1, "
               "\"heading_err_rad_1km_scrub\": 1e-06, \"sincos_max_abs_err\": 2e-08, "
               "\"atan2_max_abs_err_rad\": 1e-07, \"sim_umbmark_10runs_s\": 1.0, "
               "\"replay_vs_python_can_ratio\": 20}}\n");
    } else {
        printf("fixed vs double, 1 km     position %.3g mm (target <= 0.1)  heading %.3g rad (<= 1e-6)\n", pos, head);
        printf("  with scrub k +-0.01/0.2 position %.3g mm  heading %.3g rad\n", pos_scrub, head_scrub);
        printf("sin/cos max abs error     %.3g (target <= 2e-8)\n", sc);
        printf("atan2 max abs error       %.3g rad (target <= 1e-7)\n", at);
        if (instr >= 0.0) {
            printf("application step          %.0f instructions (2 trucks; %s)\n", instr, tool);
            printf("  with scrub k 0.0095     %.0f (mixed driving), %.0f (arcs only)\n", scrub_instr, scrub_arc_instr);
        } else {
            printf("application step          not measured (valgrind not available)\n");
        }
        if (sim_wall >= 0.0) {
            printf("simulator, 10-run UMBmark  %.3f s wall for %.0f s simulated (x%.0f real time; target < 1 s)\n",
                   sim_wall, sim_s, sim_s / sim_wall);
        }
        if (rb_ok) {
            printf("replay, 1-hour clapper log %.0f ticks/s, %.0f frames/s", rb.ticks_per_s, rb.frames_per_s);
            if (rb.ratio > 0.0) {
                printf("; python-can reading it %.0f frames/s (x%.1f; target >= 20)", rb.python_can_frames_per_s,
                       rb.ratio);
            }
            printf("\n");
        }
    }
    const int ok = pos <= 0.1 && head <= 1e-6 && pos_scrub <= 0.1 && head_scrub <= 1e-6 && sc <= 2e-8 && at <= 1e-7;
    return ok ? 0 : 1;
}
