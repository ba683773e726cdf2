/// odo-replay: run the firmware's 40 ms application step on recorded or live CAN sensor frames.
///
///   offline: odo-replay --log run.log --robot R.json [--params P.bin|P.json] [--ipec MODE] --out DIR
///   live:    odo-replay --iface vcan0 --robot R.json ... [--out DIR] [--idle-exit S] [--no-send]
///
/// Both modes feed the same tick assembler (replay.h), so the same frames give the same outputs.
/// DIR receives poses.csv, out.log (the firmware's output frames, candump -l) and summary.json,
/// built in a temp folder beside DIR and put into place at the end (hostlib/odo_out.h).
#define _DEFAULT_SOURCE 1
#include <errno.h>
#include <getopt.h>
#include <inttypes.h>
#include <limits.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <jansson.h>

#include "hal_log.h"
#include "hal_socketcan.h"
#include "odo_cli.h"
#include "odo_out.h"
#include "odo/odo_can.h"
#include "odo/odo_params.h"
#include "params_json.h"
#include "replay.h"
#include "robot.h"

#define PROGRESS_TICKS 25000U

static void usage(FILE *f)
{
    fprintf(f, "usage: odo-replay --log RUN.log  (--robot R.json | --params P) [options] --out DIR\n"
               "       odo-replay --iface vcan0  (--robot R.json | --params P) [options] [--out DIR]\n"
               "       odo-replay --help | --version\n"
               "\n"
               "Runs the firmware's 40 ms step on CAN sensor frames (WHEEL_COUNTS_A/B, LINK_ROTARY,\n"
               "LINK_LINEAR; can/odometry.dbc) read from a candump -l log or a SocketCAN interface,\n"
               "on the frames' timestamps (tick k collects the frames within half a period of\n"
               "t0 + k * 40 ms). Live mode publishes the output frames on the interface.\n"
               "\n"
               "  --robot R.json     robot description (host_sim/robots/*.json) -> parameters\n"
               "  --params P         parameter block, raw (P.bin) or JSON (P.json, odo-params show);\n"
               "                     overrides --robot\n"
               "  --ipec MODE        off, on (= paper), paper or estimator, as in odo-sim;\n"
               "                     default: what the robot/parameters say (odo-sim's default is off)\n"
               "  --out DIR          poses.csv, out.log (output frames, candump -l), summary.json;\n"
               "                     missing parents are created; an existing DIR must be empty or a\n"
               "                     previous odo-replay output (.odo-manifest), unless --force\n"
               "  --force            write into a non-empty folder odo-replay did not write (same-named\n"
               "                     files are replaced, nothing is removed)\n"
               "  --out-iface NAME   interface name written in out.log (default: the input's)\n"
               "  --idle-exit S      live: exit S seconds after the last frame (default: run until\n"
               "                     SIGINT/SIGTERM)\n"
               "  --no-send          live: do not publish the output frames on the bus\n"
               "  --margin-ms M      live: close a tick M ms after its last frame may arrive (default 5)\n"
               "  --quiet            no progress on stderr\n"
               "\n"
               "Exit status: 0 done, 1 bad input (the message names file and line), 2 usage.\n");
}

typedef struct {
    FILE *csv;
    FILE *log;
    char iface[CANDUMP_IFACE_MAX + 1];
    hal_socketcan_t *sc; ///< live: publish here (NULL: offline or --no-send)
    int quiet;
    int io_error;
    uint64_t out_frames;
} sink_t;

static double q32_mm(int64_t v) { return (double)v / 4294967296.0; }
static double q64_deg(uint64_t h) { return ldexp((double)h, -64) * 360.0; }

static void on_tick(void *user, replay_t *r, uint64_t tick, const odo_tick_input_t *in, const odo_tick_output_t *out)
{
    sink_t *s = user;
    char line[CANDUMP_LINE_MAX];
    for (uint8_t k = 0U; k < out->n_frames; ++k) {
        if (s->sc != NULL && !hal_socketcan_send(s->sc, &out->frames[k]) && r->app.tx_dropped != UINT32_MAX) {
            r->app.tx_dropped++; /* counted; the tick goes on (hal.h hal_can_send) */
        }
        const size_t n = candump_format_line(line, in->t_us, s->iface, &out->frames[k]);
        s->io_error |= fwrite(line, 1U, n, s->log) != n;
        s->out_frames++;
    }
    const odo_pose_t *a = &out->pose[ODO_TRUCK_A], *b = &out->pose[ODO_TRUCK_B];
    /* t_s: the tick's time on the log's clock relative to the first tick (steps back after a
     * clock step, jumps over a skipped gap; replay.h). */
    const double t_s =
        in->t_us >= r->origin_us ? (double)(in->t_us - r->origin_us) / 1e6 : -(double)(r->origin_us - in->t_us) / 1e6;
    fprintf(s->csv, "%" PRIu64 ",%.6f,%.6f,%.6f,%.9f,%.6f,%.6f,%.9f,%" PRId32 ",%" PRId32 ",0x%05" PRIX32 "\n", tick,
            t_s, q32_mm(a->x_mm_q32), q32_mm(a->y_mm_q32), q64_deg(a->heading_q64), q32_mm(b->x_mm_q32),
            q32_mm(b->y_mm_q32), q64_deg(b->heading_q64), out->ipec_dtheta_bam[0], out->ipec_dtheta_bam[1],
            out->faults);
    if (!s->quiet && tick > 0U && tick % PROGRESS_TICKS == 0U) {
        fprintf(stderr, "odo-replay: %" PRIu64 " ticks (%.0f s of log)\n", tick, t_s);
    }
}

static volatile sig_atomic_t g_stop = 0;
static void on_signal(int sig)
{
    (void)sig;
    g_stop = 1;
}

/// Parameters from --params (a block) or --robot (the simulator's robot description).
static int load_params(const char *robot, const char *params, odo_params_t *p)
{
    char err[512];
    if (params != NULL) { /* a 128-byte block or its JSON form (odo-params show), by content */
        if (odo_params_file_load(params, p, err, sizeof err) != 0) {
            fprintf(stderr, "odo-replay: %s\n", err);
            return -1;
        }
        return 0;
    }
    static sim_robot_t r;
    if (sim_robot_parse_file(robot, &r, err, sizeof err) != 0 || sim_robot_to_params(&r, p, err, sizeof err) != 0) {
        fprintf(stderr, "odo-replay: %s\n", err);
        return -1;
    }
    return 0;
}

/// A JSON string for any bytes: jansson refuses invalid UTF-8, so such a path is written with '?'
/// for every byte above 0x7F (the summary stays valid JSON; the file names the input anyway).
static json_t *json_path(const char *s)
{
    json_t *j = json_string(s);
    if (j != NULL) {
        return j;
    }
    char buf[PATH_MAX];
    snprintf(buf, sizeof buf, "%s", s);
    for (char *c = buf; *c != '\0'; ++c) {
        if ((unsigned char)*c > 0x7FU) {
            *c = '?';
        }
    }
    return json_string(buf);
}

static int set_u64(json_t *o, const char *key, uint64_t v)
{
    return json_object_set_new(o, key, json_integer(v > (uint64_t)INT64_MAX ? INT64_MAX : (json_int_t)v));
}

/// summary.json, built with jansson so every string is escaped. Returns 0, or -1 on a write error.
static int write_summary(FILE *f, const char *mode, const char *input, const replay_t *r, const hal_log_stats_t *ls,
                         const hal_sc_stats_t *ss, const sink_t *s)
{
    const replay_stats_t *st = &r->stats;
    json_t *o = json_object();
    int bad = o == NULL;
    bad |= json_object_set_new(o, "tool", json_string("odo-replay"));
    bad |= json_object_set_new(o, "mode", json_string(mode));
    bad |= json_object_set_new(o, "input", json_path(input));
    bad |= set_u64(o, "ticks", st->ticks);
    bad |= set_u64(o, "frames", st->frames);
    bad |= set_u64(o, "sensor_frames", st->sensor_frames);
    bad |= set_u64(o, "ignored", st->ignored);
    bad |= set_u64(o, "bad_dlc", st->bad_dlc);
    bad |= set_u64(o, "error_frames", st->error_frames);
    bad |= set_u64(o, "bus_off", st->bus_off);
    bad |= set_u64(o, "time_backwards", st->time_backwards);
    bad |= set_u64(o, "clock_steps", st->clock_steps);
    bad |= set_u64(o, "gaps_skipped", st->gaps);
    bad |= json_object_set_new(o, "gap_skipped_s", json_real((double)st->gap_us / 1e6));
    bad |= json_object_set_new(o, "longest_gap_s", json_real((double)st->longest_gap_us / 1e6));
    bad |= set_u64(o, "late", st->late);
    bad |= set_u64(o, "dup_dropped", st->dup_dropped);
    bad |= set_u64(o, "out_frames", s->out_frames);
    bad |= set_u64(o, "tx_dropped", r->app.tx_dropped);
    bad |= json_object_set_new(o, "params_status", json_string(odo_params_status_str(r->app.params_status)));
    if (ls != NULL) {
        bad |= set_u64(o, "log_lines", ls->lines);
        bad |= set_u64(o, "log_blank", ls->blank);
        bad |= set_u64(o, "log_can_fd_skipped", ls->fd_skipped);
    }
    if (ss != NULL) {
        json_t *b = json_object();
        bad |= b == NULL;
        bad |= set_u64(b, "rx_frames", ss->rx_frames);
        bad |= set_u64(b, "rx_dropped", ss->rx_dropped);
        bad |= set_u64(b, "tx_frames", ss->tx_frames);
        bad |= set_u64(b, "tx_retries", ss->tx_retries);
        bad |= set_u64(b, "tx_dropped", ss->tx_dropped);
        bad |= set_u64(b, "down_events", ss->down_events);
        bad |= set_u64(b, "reopens", ss->reopens);
        bad |= json_object_set_new(o, "bus", b);
    }
    bad |= json_dumpf(o, f, JSON_REAL_PRECISION(12)) != 0; /* one line, as before */
    bad |= fputc('\n', f) == EOF;
    json_decref(o);
    return bad ? -1 : 0;
}

/// Report gaps as replay_push skips them, --quiet or not: the output has a hole there (at most
/// GAP_REPORTS lines; the summary counts all).
#define GAP_REPORTS 10U
static void report_gaps(const replay_t *r, uint64_t *seen, const char *where)
{
    if (r->stats.gaps == *seen) {
        return;
    }
    *seen = r->stats.gaps;
    if (*seen > GAP_REPORTS) {
        return;
    }
    fprintf(stderr,
            "odo-replay: %s: a gap of %.6g s in the frames (more than %u ticks): skipped, not stepped "
            "through%s\n",
            where, (double)r->stats.last_gap_us / 1e6, REPLAY_MAX_GAP_TICKS,
            *seen == GAP_REPORTS ? " (further gaps only in summary.json)" : "");
}

/// Push every frame waiting on the socket. Returns 0, or 1 on a socket error (reported).
static int drain(hal_socketcan_t *sc, replay_t *r, bool *seen, uint64_t *last_frame_us, bool *down, int quiet)
{
    for (;;) {
        odo_can_frame_t f;
        uint64_t t_us = 0U;
        const hal_sc_status_t st = hal_socketcan_recv(sc, &f, &t_us);
        if (st == HAL_SC_FRAME) {
            replay_push(r, &f, t_us);
            *seen = true;
            *last_frame_us = hal_socketcan_now_us();
            continue;
        }
        if (st == HAL_SC_DOWN && !*down) {
            *down = true;
            r->in.rx_faults |= ODO_FAULT_BUS_ERROR; /* the open tick learns the bus was lost */
            if (!quiet) {
                fprintf(stderr, "odo-replay: %s went down; waiting for it to come back\n", sc->ifname);
            }
        } else if (st == HAL_SC_ERROR) {
            fprintf(stderr, "odo-replay: %s\n", sc->err);
            return 1;
        }
        return 0;
    }
}

/// Live loop: frames from the socket, ticks closed by later frames or by their deadline.
static int run_live(hal_socketcan_t *sc, replay_t *r, double idle_exit_s, uint64_t margin_us, int quiet)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    if (!quiet) {
        fprintf(stderr, "odo-replay: listening on %s\n", sc->ifname);
    }
    bool seen = false, down = false;
    uint64_t last_frame_us = hal_socketcan_now_us(), last_check_us = 0U, gaps_seen = 0U;
    while (!g_stop) {
        uint64_t deadline = 0U;
        const bool open_tick = replay_deadline_us(r, margin_us, &deadline);
        uint64_t now = hal_socketcan_now_us();
        int timeout_ms = 100;
        if (open_tick) {
            timeout_ms = deadline > now ? (int)((deadline - now + 999U) / 1000U) : 0;
            timeout_ms = timeout_ms > 100 ? 100 : timeout_ms;
        }
        if (hal_socketcan_wait(sc, down ? 100 : timeout_ms) < 0) {
            fprintf(stderr, "odo-replay: %s\n", sc->err);
            return 1;
        }
        if (drain(sc, r, &seen, &last_frame_us, &down, quiet) != 0) {
            return 1;
        }
        report_gaps(r, &gaps_seen, sc->ifname);
        now = hal_socketcan_now_us();
        if (replay_deadline_us(r, margin_us, &deadline) && now >= deadline) {
            /* Frames queued while we looked at the clock were stamped before it: take them first. */
            if (drain(sc, r, &seen, &last_frame_us, &down, quiet) != 0) {
                return 1;
            }
            replay_close_tick(r);
        }
        if (down && now - last_check_us >= 100000U) {
            last_check_us = now;
            if (hal_socketcan_check_up(sc)) {
                down = false;
                if (!quiet) {
                    fprintf(stderr, "odo-replay: %s is up again\n", sc->ifname);
                }
            }
        }
        if (idle_exit_s > 0.0 && seen && (double)(now - last_frame_us) > idle_exit_s * 1e6) {
            break;
        }
    }
    return 0;
}

int main(int argc, char **argv)
{
    const char *log = NULL, *iface = NULL, *robot = NULL, *params = NULL, *out = NULL, *out_iface = NULL;
    int ipec = -1, quiet = 0, no_send = 0;
    bool force = false;
    double idle_exit_s = 0.0, margin_ms = 5.0;
    enum {
        O_LOG = 256,
        O_IFACE,
        O_ROBOT,
        O_PARAMS,
        O_OUT,
        O_OUT_IFACE,
        O_IPEC,
        O_IDLE,
        O_MARGIN,
        O_NO_SEND,
        O_FORCE,
        O_QUIET,
        O_VERSION
    };
    static const struct option longopts[] = {{"log", required_argument, NULL, O_LOG},
                                             {"iface", required_argument, NULL, O_IFACE},
                                             {"robot", required_argument, NULL, O_ROBOT},
                                             {"params", required_argument, NULL, O_PARAMS},
                                             {"out", required_argument, NULL, O_OUT},
                                             {"out-iface", required_argument, NULL, O_OUT_IFACE},
                                             {"ipec", required_argument, NULL, O_IPEC},
                                             {"idle-exit", required_argument, NULL, O_IDLE},
                                             {"margin-ms", required_argument, NULL, O_MARGIN},
                                             {"no-send", no_argument, NULL, O_NO_SEND},
                                             {"force", no_argument, NULL, O_FORCE},
                                             {"quiet", no_argument, NULL, O_QUIET},
                                             {"version", no_argument, NULL, O_VERSION},
                                             {"help", no_argument, NULL, 'h'},
                                             {NULL, 0, NULL, 0}};
    for (int c; (c = getopt_long(argc, argv, "h", longopts, NULL)) != -1;) {
        switch (c) {
        case 'h': usage(stdout); return 0;
        case O_VERSION: odo_cli_print_version("odo-replay"); return 0;
        case O_LOG: log = optarg; break;
        case O_IFACE: iface = optarg; break;
        case O_ROBOT: robot = optarg; break;
        case O_PARAMS: params = optarg; break;
        case O_OUT: out = optarg; break;
        case O_OUT_IFACE: out_iface = optarg; break;
        case O_IPEC:
            if ((ipec = odo_cli_ipec("odo-replay", optarg)) < 0) {
                return 2;
            }
            break;
        case O_IDLE:
        case O_MARGIN: {
            char *end = NULL;
            const double v = strtod(optarg, &end);
            if (end == optarg || *end != '\0' || !(v >= 0.0) || v > 86400.0) {
                fprintf(stderr, "odo-replay: %s needs a number of %s >= 0, not '%s'\n",
                        c == O_IDLE ? "--idle-exit" : "--margin-ms", c == O_IDLE ? "seconds" : "milliseconds", optarg);
                return 2;
            }
            *(c == O_IDLE ? &idle_exit_s : &margin_ms) = v;
            break;
        }
        case O_NO_SEND: no_send = 1; break;
        case O_FORCE: force = true; break;
        case O_QUIET: quiet = 1; break;
        default: odo_cli_usage_hint("odo-replay"); return 2;
        }
    }
    if (optind < argc) {
        fprintf(stderr, "odo-replay: unexpected argument '%s'\n", argv[optind]);
        odo_cli_usage_hint("odo-replay");
        return 2;
    }
    if ((log == NULL) == (iface == NULL)) {
        fprintf(stderr, "odo-replay: give exactly one of --log FILE and --iface NAME\n\n");
        usage(stderr);
        return 2;
    }
    if (robot == NULL && params == NULL) {
        fprintf(stderr, "odo-replay: --robot R.json or --params P.bin|P.json is required\n");
        return 2;
    }
    if (log != NULL && out == NULL) {
        fprintf(stderr, "odo-replay: --out DIR is required with --log\n");
        return 2;
    }

    odo_params_t p;
    if (load_params(robot, params, &p) != 0) {
        return 1;
    }
    if (ipec >= 0) {
        p.ipec_mode = (uint8_t)(ipec == 2 ? ODO_IPEC_ESTIMATOR : ipec == 1 ? ODO_IPEC_PAPER : ODO_IPEC_OFF);
    }

    /* Inputs first: a missing log or interface fails before anything is created. */
    static hal_log_t reader;
    static hal_socketcan_t sc;
    sc.fd = -1;
    static const uint32_t ids[] = {ODO_CAN_ID_WHEEL_COUNTS_A, ODO_CAN_ID_WHEEL_COUNTS_B, ODO_CAN_ID_LINK_ROTARY,
                                   ODO_CAN_ID_LINK_LINEAR};
    if (log != NULL && hal_log_open(&reader, log) != 0) {
        fprintf(stderr, "odo-replay: %s\n", reader.err);
        return 1;
    }
    if (iface != NULL && hal_socketcan_open(&sc, iface, ids, sizeof ids / sizeof ids[0]) != 0) {
        fprintf(stderr, "odo-replay: %s\n", sc.err);
        return 1;
    }

    odo_out_dir_t *dir = NULL;
    char oerr[PATH_MAX + 256];
    sink_t sink;
    memset(&sink, 0, sizeof sink);
    sink.quiet = quiet;
    sink.sc = (iface != NULL && !no_send) ? &sc : NULL;
    snprintf(sink.iface, sizeof sink.iface, "%s", out_iface != NULL ? out_iface : (iface != NULL ? iface : "can0"));
    snprintf(oerr, sizeof oerr, "/dev/null: %s", "cannot open");
    if (out != NULL) {
        /* The log, the robot and the block are inputs: no --out may touch them. */
        odo_out_inputs_t ins;
        odo_out_inputs_init(&ins);
        (void)odo_out_inputs_add(&ins, log, oerr, sizeof oerr);
        (void)odo_out_inputs_add(&ins, robot, oerr, sizeof oerr);
        (void)odo_out_inputs_add(&ins, params, oerr, sizeof oerr);
        dir = odo_out_dir_begin(out, "odo-replay", force, &ins, oerr, sizeof oerr);
        if (dir == NULL) {
            fprintf(stderr, "odo-replay: %s\n", oerr);
            hal_log_close(&reader);
            hal_socketcan_close(&sc);
            return 1;
        }
        sink.csv = odo_out_dir_fopen(dir, "poses.csv", oerr, sizeof oerr);
        sink.log = sink.csv != NULL ? odo_out_dir_fopen(dir, "out.log", oerr, sizeof oerr) : NULL;
    } else {
        sink.csv = fopen("/dev/null", "w");
        sink.log = fopen("/dev/null", "w");
    }
    if (sink.csv == NULL || sink.log == NULL) {
        fprintf(stderr, "odo-replay: %s\n", oerr);
        if (sink.csv != NULL) {
            fclose(sink.csv);
        }
        if (sink.log != NULL) {
            fclose(sink.log);
        }
        odo_out_dir_abort(dir); /* ours: nothing half-written stays behind */
        hal_log_close(&reader);
        hal_socketcan_close(&sc);
        return 1;
    }
    static char csv_buf[1 << 16], log_buf[1 << 16];
    setvbuf(sink.csv, csv_buf, _IOFBF, sizeof csv_buf);
    setvbuf(sink.log, log_buf, _IOFBF, sizeof log_buf);
    fprintf(sink.csv, "tick,t_s,x_a_mm,y_a_mm,theta_a_deg,x_b_mm,y_b_mm,theta_b_deg,ipec_a_bam,ipec_b_bam,faults\n");

    static replay_t r;
    const odo_params_status_t ps = replay_init(&r, &p, on_tick, &sink);
    if (ps != ODO_PARAMS_OK) {
        fprintf(stderr, "odo-replay: warning: the firmware refused the parameters (%s); running on defaults\n",
                odo_params_status_str(ps));
    }

    int rc = 0;
    if (log != NULL) {
        candump_line_t l;
        hal_log_status_t st;
        bool iface_set = out_iface != NULL;
        uint64_t gaps_seen = 0U;
        while ((st = hal_log_next(&reader, &l)) == HAL_LOG_FRAME) {
            if (!iface_set) {
                snprintf(sink.iface, sizeof sink.iface, "%s", l.iface);
                iface_set = true;
            }
            replay_push(&r, &l.frame, l.t_us);
            if (r.stats.gaps != gaps_seen) {
                char where[PATH_MAX + 32];
                snprintf(where, sizeof where, "%s:%" PRIu64, log, reader.line_no);
                report_gaps(&r, &gaps_seen, where);
            }
        }
        if (st == HAL_LOG_ERROR) {
            fprintf(stderr, "odo-replay: %s\n", reader.err);
            rc = 1;
        }
        replay_finish(&r);
    } else {
        rc = run_live(&sc, &r, idle_exit_s, (uint64_t)llround(margin_ms * 1000.0), quiet);
        replay_finish(&r);
    }
    if (r.stats.time_backwards > 0U && !quiet) {
        fprintf(stderr,
                "odo-replay: warning: %" PRIu64 " frames stamped before the previous frame "
                "(flagged TIME_BACKWARDS)\n",
                r.stats.time_backwards);
    }
    if (r.stats.clock_steps > 0U && !quiet) {
        fprintf(stderr,
                "odo-replay: warning: the clock stepped back %" PRIu64 " time(s) by more than %u ticks; "
                "the tick clock was re-anchored each time\n",
                r.stats.clock_steps, REPLAY_CLOCK_STEP_TICKS);
    }
    if (r.stats.gaps > 0U) { /* reported even with --quiet: the output has a hole */
        fprintf(stderr,
                "odo-replay: warning: %" PRIu64 " gap(s) longer than %u ticks skipped, %.6g s in all "
                "(longest %.6g s)\n",
                r.stats.gaps, REPLAY_MAX_GAP_TICKS, (double)r.stats.gap_us / 1e6, (double)r.stats.longest_gap_us / 1e6);
    }
    if (log != NULL && reader.stats.fd_skipped > 0U && !quiet) {
        fprintf(stderr, "odo-replay: %" PRIu64 " CAN FD lines (another node's traffic) skipped\n",
                reader.stats.fd_skipped);
    }
    if (r.stats.ignored > 0U && !quiet) {
        fprintf(stderr,
                "odo-replay: %" PRIu64 " frames not consumed (unknown ID, RTR, extended or output "
                "frames) ignored\n",
                r.stats.ignored);
    }

    if (out != NULL) {
        FILE *sf = odo_out_dir_fopen(dir, "summary.json", oerr, sizeof oerr);
        int sum_bad = 0;
        if (sf != NULL) {
            sum_bad = write_summary(sf, log != NULL ? "offline" : "live", log != NULL ? log : iface, &r,
                                    log != NULL ? &reader.stats : NULL, iface != NULL ? &sc.stats : NULL, &sink);
        }
        const int bad = sf == NULL || sum_bad != 0 || fclose(sf) != 0;
        const int bad2 = fclose(sink.csv) != 0 || fclose(sink.log) != 0 || sink.io_error;
        if (rc == 0 && (bad || bad2)) {
            fprintf(stderr, "odo-replay: writing %s failed: %s\n", out, sf == NULL ? oerr : strerror(errno));
            rc = 1;
        }
        if (rc == 0) {
            if (odo_out_dir_commit(dir, oerr, sizeof oerr) != 0) {
                fprintf(stderr, "odo-replay: %s\n", oerr);
                rc = 1;
            }
        } else {
            odo_out_dir_abort(dir);
        }
    } else {
        fclose(sink.csv);
        fclose(sink.log);
    }
    if (rc == 0 && !quiet) {
        fprintf(stderr, "odo-replay: %" PRIu64 " ticks from %" PRIu64 " frames%s%s\n", r.stats.ticks, r.stats.frames,
                out != NULL ? " -> " : "", out != NULL ? out : "");
    }
    hal_log_close(&reader);
    hal_socketcan_close(&sc);
    return rc;
}
