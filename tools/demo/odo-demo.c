/// odo-demo: the foundation's main job on built-in sample data. Drives a synthetic tick stream of
/// a 4 x 4 m UMBmark square (000 section 3.5: 0.2 m/s legs, stop and turn on the spot at every
/// corner, fourth turn included) through the firmware's HAL-driven tick (odo_loop_tick on the
/// hal_test backend), and writes:
///   DIR/pose.csv    per tick: time, the firmware's pose, and the true pose of the robot
///   DIR/output.log  the firmware's output frames as a candump -l log (decode with can/odometry.dbc)
/// The robot is the SET-simulation robot of 000 section 4.6.2 (true b 337 mm and Ed 0.9985,
/// nominal 340 mm and 1.0), so the return error shows the systematic dead-reckoning error that
/// UMBmark calibration (a later issue) removes.
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "candump.h"
#include "hal_test.h"
#include "odo/odo_app.h"
#include "odo_cli.h"
#include "odo_loop.h"
#include "odo_out.h"
#include "odo_ref.h"
#include "odo_synth.h"

static void usage(FILE *f)
{
    fprintf(f, "usage: odo-demo --out DIR [--direction cw|ccw] [--force]\n"
               "       odo-demo --help | --version\n"
               "Runs a 4 x 4 m UMBmark square through the firmware step and writes DIR/pose.csv and\n"
               "DIR/output.log (candump -l). Prints the return error (000 Eq. 3.1).\n"
               "DIR follows the output rule (hostlib/odo_out.h): built beside itself and renamed into\n"
               "place; an existing DIR must be empty or a previous odo-demo output unless --force.\n"
               "Exit status: 0 ok, 1 I/O error or refused output, 2 usage error.\n");
}

int main(int argc, char **argv)
{
    const char *out_dir = NULL;
    int ccw = 0;
    bool force = false;
    enum { O_OUT = 256, O_DIRECTION, O_FORCE, O_VERSION };
    static const struct option longopts[] = {
        {"out", required_argument, NULL, O_OUT}, {"direction", required_argument, NULL, O_DIRECTION},
        {"force", no_argument, NULL, O_FORCE},   {"version", no_argument, NULL, O_VERSION},
        {"help", no_argument, NULL, 'h'},        {NULL, 0, NULL, 0}};
    for (int c; (c = getopt_long(argc, argv, "h", longopts, NULL)) != -1;) {
        switch (c) {
        case 'h': usage(stdout); return 0;
        case O_VERSION: odo_cli_print_version("odo-demo"); return 0;
        case O_OUT: out_dir = optarg; break;
        case O_FORCE: force = true; break;
        case O_DIRECTION:
            if (strcmp(optarg, "ccw") == 0) {
                ccw = 1;
            } else if (strcmp(optarg, "cw") != 0) {
                fprintf(stderr, "odo-demo: --direction must be cw or ccw, not '%s'\n", optarg);
                return 2;
            }
            break;
        default: usage(stderr); return 2;
        }
    }
    if (optind < argc) {
        fprintf(stderr, "odo-demo: unexpected argument '%s'\n", argv[optind]);
        usage(stderr);
        return 2;
    }
    if (out_dir == NULL) {
        usage(stderr);
        return 2;
    }
    char err[4096 + 256];
    odo_out_dir_t *dir = odo_out_dir_begin(out_dir, "odo-demo", force, NULL, err, sizeof err);
    if (dir == NULL) {
        fprintf(stderr, "odo-demo: cannot write %s\n", err);
        return 1;
    }
    FILE *pf = odo_out_dir_fopen(dir, "pose.csv", err, sizeof err);
    FILE *lf = pf != NULL ? odo_out_dir_fopen(dir, "output.log", err, sizeof err) : NULL;
    if (pf == NULL || lf == NULL) {
        fprintf(stderr, "odo-demo: cannot write %s\n", err);
        if (pf) {
            fclose(pf);
        }
        odo_out_dir_abort(dir);
        return 1;
    }

    /* The firmware believes the nominal labmate; the true robot differs (000 s. 4.6.2). */
    odo_params_t p;
    odo_params_defaults(&p);
    odo_truck_params_t truth = p.truck[0];
    truth.wheelbase_nm = 337000000U;
    truth.ed_q30 = (int32_t)llround(0.9985 * 1073741824.0);
    static odo_app_t app;
    static hal_ctx_t hal;
    static odo_tick_output_t out;
    static odo_tick_input_t loop_in;
    odo_app_init_params(&app, &p);
    hal_test_init(&hal, 1U, false);
    odo_ref_t real;
    odo_ref_init(&real, &truth, ODO_HEADING_MIDPOINT, 0.0, 0.0, 0.0);

    /* Scripted square at the nominal geometry: 4 m legs at 200 mm/s, 90 deg turns on the spot
     * with wheel speeds of +-200 mm/s, a pause between segments. */
    odo_synth_t s;
    odo_synth_init(&s, 1U, &p.truck[0], p.tick_us);
    const double tick_s = p.tick_us * 1e-6, b = 340.0, v = 200.0;
    const uint32_t leg_ticks = (uint32_t)lround(4000.0 / v / tick_s);
    const uint32_t turn_ticks = (uint32_t)lround((M_PI / 2.0) * (b / 2.0) / v / tick_s);
    const double turn_sign = ccw ? 1.0 : -1.0;
    int64_t cl = 0, cr = 0;
    uint64_t t_us = 0U;
    uint8_t seq = 0U;
    fprintf(pf, "t_s,x_mm,y_mm,theta_deg,true_x_mm,true_y_mm,true_theta_deg\n");
    /* The robot boots at rest: the first sample only sets the counter baseline. */
    hal_test_set_wheel(&hal, 0U, 0U, 0U, 24U, seq++);
    odo_loop_tick(&app, &hal, &loop_in, &out);
    for (uint32_t f = 0U; f < hal.n_tx; ++f) {
        odo_candump_write(lf, t_us, "vcan0", &hal.tx[f]);
    }
    fprintf(pf, "0.000,0.0000,0.0000,0.000000,0.0000,0.0000,0.000000\n");
    t_us += p.tick_us;
    for (int seg = 0; seg < 16; ++seg) {
        const int kind = seg % 4; /* 0 leg, 1 pause, 2 turn, 3 pause */
        uint32_t ticks = kind == 0 ? leg_ticks : (kind == 2 ? turn_ticks : 25U);
        /* Speeds are trimmed so each segment covers exactly its nominal distance: the robot's
         * controller drives to its own odometry, as on a real robot. */
        if (kind == 0) {
            const double vl = 4000.0 / (ticks * tick_s);
            odo_synth_segment(&s, vl, vl, ticks);
        } else if (kind == 2) {
            const double vt = (M_PI / 2.0) * (b / 2.0) / (ticks * tick_s);
            odo_synth_segment(&s, -turn_sign * vt, turn_sign * vt, ticks);
        } else {
            odo_synth_segment(&s, 0.0, 0.0, ticks);
        }
        for (uint32_t k = 0U; k < ticks; ++k) {
            int32_t dl, dr;
            odo_synth_next(&s, &dl, &dr);
            cl += dl;
            cr += dr;
            odo_ref_step(&real, dl, dr);
            hal.now_us = t_us;
            hal_test_set_wheel(&hal, 0U, (uint32_t)((uint64_t)cl & 0xFFFFFFU), (uint32_t)((uint64_t)cr & 0xFFFFFFU),
                               24U, seq++);
            hal.n_tx = 0U;
            odo_loop_tick(&app, &hal, &loop_in, &out);
            for (uint32_t f = 0U; f < hal.n_tx; ++f) {
                odo_candump_write(lf, t_us, "vcan0", &hal.tx[f]);
            }
            const odo_pose_t *pose = &out.pose[0];
            fprintf(pf, "%.3f,%.4f,%.4f,%.6f,%.4f,%.4f,%.6f\n", (double)t_us * 1e-6,
                    (double)pose->x_mm_q32 / 4294967296.0, (double)pose->y_mm_q32 / 4294967296.0,
                    (double)(int32_t)odo_heading_bam(pose) * (360.0 / 4294967296.0), real.x_mm, real.y_mm,
                    real.theta_rad * 180.0 / M_PI);
            t_us += p.tick_us;
        }
    }
    const int werr = ferror(pf) || ferror(lf);
    const int cerr = (fclose(pf) != 0) | (fclose(lf) != 0);
    if (werr || cerr) {
        fprintf(stderr, "odo-demo: writing %s failed: %s\n", out_dir, strerror(errno));
        odo_out_dir_abort(dir);
        return 1;
    }
    if (odo_out_dir_commit(dir, err, sizeof err) != 0) {
        fprintf(stderr, "odo-demo: cannot write %s\n", err);
        return 1;
    }
    const odo_pose_t *pose = &out.pose[0];
    const double xc = (double)pose->x_mm_q32 / 4294967296.0, yc = (double)pose->y_mm_q32 / 4294967296.0;
    const double thc = (double)(int32_t)odo_heading_bam(pose) * (360.0 / 4294967296.0);
    printf("odo-demo: %s square, %u ticks, %u frames published\n", ccw ? "ccw" : "cw", app.ticks, app.ticks * 3U);
    printf("  firmware believes  x %8.1f mm  y %8.1f mm  theta %7.2f deg\n", xc, yc, thc);
    printf("  robot really is    x %8.1f mm  y %8.1f mm  theta %7.2f deg\n", real.x_mm, real.y_mm,
           remainder(real.theta_rad * 180.0 / M_PI, 360.0));
    printf("  return error (000 Eq. 3.1)  ex %.1f mm  ey %.1f mm\n", real.x_mm - xc, real.y_mm - yc);
    printf("  wrote %s/pose.csv and %s/output.log\n", out_dir, out_dir);
    return 0;
}
