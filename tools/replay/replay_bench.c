/// Replay benchmark (see replay_bench.h).
///
/// The 1-hour log: clapper straight-36m runs of the simulator (odo-sim's defaults: IPEC off; 1 ms
/// physics, firmware in the loop) back to back until 90,000 ticks, as one continuous bus recording: each run's wheel
/// counters continue from the previous run's (24-bit wrap), sequence numbers and time run on.
/// Written once to ODO_BINARY_DIR/cache/ and reused.
#include "replay_bench.h"

#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "hal_log.h"
#include "odo/odo_can.h"
#include "replay.h"
#include "robot.h"
#include "sil.h"

#define BENCH_TICKS 90000UL /* one hour at 40 ms */

typedef struct {
    FILE *f;
    unsigned long tick;           ///< global tick
    uint32_t off[ODO_TRUCKS][2];  ///< counter offset of this run
    uint32_t last[ODO_TRUCKS][2]; ///< raw counters at this run's last tick
    int io_error;
} gen_t;

static void put(gen_t *g, uint64_t t_us, const odo_can_frame_t *f)
{
    char line[CANDUMP_LINE_MAX];
    const size_t n = candump_format_line(line, t_us, "can0", f);
    g->io_error |= fwrite(line, 1U, n, g->f) != n;
}

static void gen_tick(void *user, const sim_tick_t *tk)
{
    gen_t *g = user;
    const odo_tick_input_t *in = tk->input;
    for (unsigned t = 0; t < ODO_TRUCKS; ++t) {
        g->last[t][0] = in->wheel[t].left_raw;
        g->last[t][1] = in->wheel[t].right_raw;
    }
    if (g->tick >= BENCH_TICKS) {
        return;
    }
    const uint64_t t_us = (uint64_t)g->tick * ODO_CAN_CYCLE_TIME_US;
    const uint8_t seq = (uint8_t)g->tick;
    odo_can_frame_t f;
    for (uint8_t t = 0; t < ODO_TRUCKS; ++t) {
        if (in->wheel[t].present) {
            const odo_msg_wheel_counts_t m = {(in->wheel[t].left_raw + g->off[t][0]) & ODO_CAN_COUNT_MASK,
                                              (in->wheel[t].right_raw + g->off[t][1]) & ODO_CAN_COUNT_MASK, seq,
                                              in->wheel[t].status};
            odo_can_pack_wheel_counts(t, &m, &f);
            put(g, t_us, &f);
        }
    }
    if (in->link.rotary_present) {
        const odo_msg_link_rotary_t m = {in->link.alpha_bam16, in->link.beta_bam16, seq, in->link.rotary_status};
        odo_can_pack_link_rotary(&m, &f);
        put(g, t_us, &f);
    }
    if (in->link.linear_present) {
        const odo_msg_link_linear_t m = {in->link.length_um, seq, in->link.linear_status};
        odo_can_pack_link_linear(&m, &f);
        put(g, t_us, &f);
    }
    g->tick++;
}

static int make_log(const char *path)
{
    static sim_robot_t robot;
    static sim_scenario_t sc;
    char err[256], tmp[600];
    if (sim_robot_default(SIM_VEHICLE_CLAPPER, &robot) != 0) {
        return -1;
    }
    sim_scenario_none(&sc);
    snprintf(tmp, sizeof tmp, "%s.tmp.%ld", path, (long)getpid());
    gen_t g;
    memset(&g, 0, sizeof g);
    g.f = fopen(tmp, "w");
    if (g.f == NULL) {
        fprintf(stderr, "odo-bench: cannot write %s: %s\n", tmp, strerror(errno));
        return -1;
    }
    for (unsigned run = 0; g.tick < BENCH_TICKS; ++run) {
        sim_run_config_t cfg = {.robot = &robot,
                                .scenario = &sc,
                                .experiment = "straight-36m",
                                .ccw = 0,
                                .bumps = -1,
                                .bump_height_mm = 10.0,
                                .ipec = 0,
                                .seed = 1000U + run,
                                .run_index = 0};
        sim_return_t ret;
        if (sim_run(&cfg, gen_tick, &g, &ret, err, sizeof err) != 0) {
            fprintf(stderr, "odo-bench: %s\n", err);
            fclose(g.f);
            remove(tmp);
            return -1;
        }
        for (unsigned t = 0; t < ODO_TRUCKS; ++t) {
            for (unsigned w = 0; w < 2U; ++w) {
                g.off[t][w] = (g.off[t][w] + g.last[t][w]) & ODO_CAN_COUNT_MASK;
            }
        }
    }
    if (fclose(g.f) != 0 || g.io_error || rename(tmp, path) != 0) {
        fprintf(stderr, "odo-bench: cannot write %s\n", path);
        remove(tmp);
        return -1;
    }
    return 0;
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

typedef struct {
    FILE *out;
    char buf[1 << 16];
    size_t n;
} sink_t;

/// What odo-replay does per tick, minus the CSV: format the output frames as candump lines.
static void on_tick(void *user, replay_t *r, uint64_t tick, const odo_tick_input_t *in, const odo_tick_output_t *out)
{
    (void)r;
    (void)tick;
    sink_t *s = user;
    for (uint8_t k = 0U; k < out->n_frames; ++k) {
        if (s->n + CANDUMP_LINE_MAX > sizeof s->buf) {
            fwrite(s->buf, 1U, s->n, s->out);
            s->n = 0U;
        }
        s->n += candump_format_line(s->buf + s->n, in->t_us, "can0", &out->frames[k]);
    }
}

static int replay_once(const char *path, const odo_params_t *p, int with_output, double *wall_s, unsigned long *ticks,
                       unsigned long *frames)
{
    static hal_log_t l;
    static replay_t r;
    static sink_t s;
    s.out = fopen("/dev/null", "w");
    s.n = 0U;
    if (s.out == NULL || hal_log_open(&l, path) != 0) {
        fprintf(stderr, "odo-bench: %s\n", l.err);
        return -1;
    }
    const double t0 = now_s();
    (void)replay_init(&r, p, with_output ? on_tick : NULL, &s);
    candump_line_t line;
    hal_log_status_t st;
    while ((st = hal_log_next(&l, &line)) == HAL_LOG_FRAME) {
        replay_push(&r, &line.frame, line.t_us);
    }
    replay_finish(&r);
    fwrite(s.buf, 1U, s.n, s.out);
    *wall_s = now_s() - t0;
    *ticks = (unsigned long)r.stats.ticks;
    *frames = (unsigned long)r.stats.frames;
    hal_log_close(&l);
    fclose(s.out);
    if (st != HAL_LOG_EOF) {
        fprintf(stderr, "odo-bench: %s\n", l.err);
        return -1;
    }
    return 0;
}

static double python_can_rate(const char *python, const char *log, int reps)
{
    char cmd[2048];
    snprintf(cmd, sizeof cmd, "'%s' '%s/tools/replay/pycan_read_rate.py' --reps %d '%s'", python, ODO_SOURCE_DIR, reps,
             log);
    FILE *p = popen(cmd, "r");
    if (p == NULL) {
        return -1.0;
    }
    double v = -1.0;
    if (fscanf(p, "%lf", &v) != 1) {
        v = -1.0;
    }
    return pclose(p) == 0 ? v : -1.0;
}

int replay_bench_run(int reps, const char *python, replay_bench_t *out)
{
    memset(out, 0, sizeof *out);
    out->python_can_frames_per_s = -1.0;
    out->ratio = -1.0;
    out->ipec_ratio = -1.0;
    mkdir(ODO_BINARY_DIR "/cache", 0777);
    snprintf(out->log_path, sizeof out->log_path, "%s", ODO_BINARY_DIR "/cache/replay-1h-clapper.log");
    if (access(out->log_path, R_OK) != 0) {
        fprintf(stderr, "odo-bench: writing the 1-hour clapper log (once) to %s ...\n", out->log_path);
        if (make_log(out->log_path) != 0) {
            return -1;
        }
    }
    static sim_robot_t robot;
    odo_params_t p;
    char err[256];
    if (sim_robot_default(SIM_VEHICLE_CLAPPER, &robot) != 0 || sim_robot_to_params(&robot, &p, err, sizeof err) != 0) {
        return -1;
    }
    /* As the log was simulated (IPEC off, so the replay reproduces the simulator's outputs), with
     * the output lines formatted too, and with IPEC on (the firmware's full clapper step). */
    odo_params_t p_ipec = p;
    p.ipec_mode = ODO_IPEC_OFF;
    p_ipec.ipec_mode = ODO_IPEC_PAPER;
    double best = 1e30, best_out = 1e30, best_ipec = 1e30;
    for (int i = 0; i < reps; ++i) {
        double wall = 0.0, wall_out = 0.0, wall_ipec = 0.0;
        if (replay_once(out->log_path, &p, 0, &wall, &out->ticks, &out->frames) != 0 ||
            replay_once(out->log_path, &p, 1, &wall_out, &out->ticks, &out->frames) != 0 ||
            replay_once(out->log_path, &p_ipec, 0, &wall_ipec, &out->ticks, &out->frames) != 0) {
            return -1;
        }
        best = wall < best ? wall : best;
        best_out = wall_out < best_out ? wall_out : best_out;
        best_ipec = wall_ipec < best_ipec ? wall_ipec : best_ipec;
    }
    out->ticks_per_s = (double)out->ticks / best;
    out->frames_per_s = (double)out->frames / best;
    out->with_output_ticks_per_s = (double)out->ticks / best_out;
    out->ipec_ticks_per_s = (double)out->ticks / best_ipec;
    if (python == NULL) {
        python = ODO_VENV_PYTHON;
    }
    if (access(python, X_OK) == 0) {
        out->python_can_frames_per_s = python_can_rate(python, out->log_path, reps > 2 ? 2 : reps);
        if (out->python_can_frames_per_s > 0.0) {
            out->ratio = out->frames_per_s / out->python_can_frames_per_s;
            out->ipec_ratio =
                out->ipec_ticks_per_s * (double)out->frames / (double)out->ticks / out->python_can_frames_per_s;
        }
    }
    return 0;
}
