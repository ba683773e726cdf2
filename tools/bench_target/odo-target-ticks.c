/// odo-target-ticks: the host half of `make bench-target`. Replays a recorded run (a candump -l
/// log, e.g. from odo-sim) through the host build of the firmware exactly as odo-replay does, and
/// writes every tick's assembled input and the host's output in the portable form of
/// bench_codec.h, after the encoded parameter block the run booted on. odo-bench-target then feeds
/// the same inputs to the Cortex-M4 build in an emulator and compares the outputs byte for byte.
///
///   odo-target-ticks --log RUN.log --robot R.json --ipec off|paper|estimator --out TICKS.bin
///
/// Exit 0 on success; 1 with a message (and no output file) on any error: the output is written
/// to a temporary file and renamed into place.
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_codec.h"
#include "hal_log.h"
#include "odo/odo_params.h"
#include "replay.h"
#include "robot.h"

typedef struct {
    FILE *f;
    uint32_t ticks;
    bool io_error;
} sink_t;

static void on_tick(void *user, struct replay *r, uint64_t tick, const odo_tick_input_t *in,
                    const odo_tick_output_t *out)
{
    (void)r;
    (void)tick;
    sink_t *s = user;
    uint8_t bin[ODO_BENCH_IN_SIZE];
    uint8_t bout[ODO_BENCH_OUT_SIZE];
    odo_bench_pack_input(in, bin);
    odo_bench_pack_output(out, bout);
    if (fwrite(bin, 1, sizeof bin, s->f) != sizeof bin || fwrite(bout, 1, sizeof bout, s->f) != sizeof bout) {
        s->io_error = true;
    }
    s->ticks++;
}

static void put32(uint8_t *p, uint32_t v)
{
    for (unsigned i = 0U; i < 4U; ++i) {
        p[i] = (uint8_t)(v >> (8U * i));
    }
}

static int usage(FILE *to, int rc)
{
    fprintf(to, "usage: odo-target-ticks --log RUN.log --robot R.json --ipec off|paper|estimator --out TICKS.bin\n"
                "Replay RUN.log (candump -l) on the host build of the firmware and write each tick's input\n"
                "and output (tools/bench_target/bench_codec.h) for odo-bench-target.\n");
    return rc;
}

int main(int argc, char **argv)
{
    const char *log = NULL, *robot = NULL, *ipec = NULL, *out = NULL;
    for (int i = 1; i < argc; ++i) {
        const bool has = i + 1 < argc;
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            return usage(stdout, 0);
        } else if (has && strcmp(argv[i], "--log") == 0) {
            log = argv[++i];
        } else if (has && strcmp(argv[i], "--robot") == 0) {
            robot = argv[++i];
        } else if (has && strcmp(argv[i], "--ipec") == 0) {
            ipec = argv[++i];
        } else if (has && strcmp(argv[i], "--out") == 0) {
            out = argv[++i];
        } else {
            fprintf(stderr, "odo-target-ticks: unknown or incomplete argument '%s'\n", argv[i]);
            return usage(stderr, 1);
        }
    }
    if (log == NULL || robot == NULL || ipec == NULL || out == NULL) {
        return usage(stderr, 1);
    }
    odo_params_t p;
    char err[512];
    static sim_robot_t rob;
    if (sim_robot_parse_file(robot, &rob, err, sizeof err) != 0 ||
        sim_robot_to_params(&rob, &p, err, sizeof err) != 0) {
        fprintf(stderr, "odo-target-ticks: %s\n", err);
        return 1;
    }
    if (strcmp(ipec, "off") == 0) {
        p.ipec_mode = (uint8_t)ODO_IPEC_OFF;
    } else if (strcmp(ipec, "paper") == 0) {
        p.ipec_mode = (uint8_t)ODO_IPEC_PAPER;
    } else if (strcmp(ipec, "estimator") == 0) {
        p.ipec_mode = (uint8_t)ODO_IPEC_ESTIMATOR;
    } else {
        fprintf(stderr, "odo-target-ticks: --ipec must be off, paper or estimator, not '%s'\n", ipec);
        return 1;
    }
    uint8_t block[ODO_PARAMS_SIZE];
    if (odo_params_encode(&p, block, sizeof block) != sizeof block) {
        fprintf(stderr, "odo-target-ticks: cannot encode the parameter block\n");
        return 1;
    }

    static hal_log_t reader;
    if (hal_log_open(&reader, log) != 0) {
        fprintf(stderr, "odo-target-ticks: %s\n", reader.err);
        return 1;
    }
    char tmp[4096];
    if ((size_t)snprintf(tmp, sizeof tmp, "%s.tmp", out) >= sizeof tmp) {
        fprintf(stderr, "odo-target-ticks: output path too long\n");
        hal_log_close(&reader);
        return 1;
    }
    sink_t sink = {fopen(tmp, "wb"), 0U, false};
    if (sink.f == NULL) {
        perror(tmp);
        hal_log_close(&reader);
        return 1;
    }
    uint8_t hdr[16];
    memcpy(hdr, ODO_BENCH_FILE_MAGIC, 4);
    put32(hdr + 4, ODO_BENCH_FILE_VERSION);
    put32(hdr + 8, 0U); /* tick count, written at the end */
    put32(hdr + 12, (uint32_t)sizeof block);
    sink.io_error =
        fwrite(hdr, 1, sizeof hdr, sink.f) != sizeof hdr || fwrite(block, 1, sizeof block, sink.f) != sizeof block;

    static replay_t r;
    const odo_params_status_t st = replay_init(&r, &p, on_tick, &sink);
    int rc = 0;
    if (st != ODO_PARAMS_OK) {
        fprintf(stderr, "odo-target-ticks: %s: parameters rejected: %s\n", robot, odo_params_status_str(st));
        rc = 1;
    }
    candump_line_t l;
    hal_log_status_t ls;
    while (rc == 0 && (ls = hal_log_next(&reader, &l)) == HAL_LOG_FRAME) {
        replay_push(&r, &l.frame, l.t_us);
    }
    if (rc == 0 && ls == HAL_LOG_ERROR) {
        fprintf(stderr, "odo-target-ticks: %s\n", reader.err);
        rc = 1;
    }
    replay_finish(&r);
    hal_log_close(&reader);
    put32(hdr + 8, sink.ticks);
    if (rc == 0 && (sink.io_error || fseek(sink.f, 8L, SEEK_SET) != 0 || fwrite(hdr + 8, 1, 4, sink.f) != 4)) {
        fprintf(stderr, "odo-target-ticks: write error on %s\n", tmp);
        rc = 1;
    }
    if (fclose(sink.f) != 0 && rc == 0) {
        fprintf(stderr, "odo-target-ticks: write error on %s\n", tmp);
        rc = 1;
    }
    if (rc == 0 && sink.ticks == 0U) {
        fprintf(stderr, "odo-target-ticks: %s holds no sensor frames\n", log);
        rc = 1;
    }
    if (rc == 0 && rename(tmp, out) != 0) {
        perror(out);
        rc = 1;
    }
    if (rc != 0) {
        remove(tmp);
        return rc;
    }
    printf("odo-target-ticks: %" PRIu32 " ticks (IPEC %s) -> %s\n", sink.ticks, ipec, out);
    return 0;
}
