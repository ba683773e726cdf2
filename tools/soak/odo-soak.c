/// odo-soak: frame-loss and 24 h soak figures of the firmware's receive path, as one JSON object
/// (tools/soak/README.md). Built optimised and unsanitised in every preset, like odo-bench.
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "odo_cli.h"
#include "soak.h"

static void usage(FILE *f)
{
    fprintf(f, "usage: odo-soak [--json] [--quick] [--ticks N] [--seed S]\n"
               "       odo-soak --help | --version\n"
               "\n"
               "Replays a seeded labmate drive through odo-replay's tick assembler and the firmware's\n"
               "step twice, clean and through a faulty bus, and prints how far the faulty run's pose\n"
               "is from the clean run's:\n"
               "  loss   straight 40 s drives at 1, 1.6 and 2.5 m/s with 20 %% of the frames lost,\n"
               "         10 seeds each: travel lost (target < 1 %% at 2.5 m/s)\n"
               "  soak   24 h (2,160,000 ticks) of random driving with wheels up to 3 m/s, 20 %% lost,\n"
               "         5 %% duplicated, 2 %% reordered, error-frame bursts and a 2 s clock step back:\n"
               "         pose error at the end and at worst, path lost, faults flagged\n"
               "  --json     one JSON object on stdout (progress on stderr)\n"
               "  --quick    a 50,000-tick soak and 3 seeds per speed (smoke runs)\n"
               "  --ticks N  soak length in ticks (default 2160000)\n"
               "  --seed S   soak seed (default 16)\n"
               "Exit status: 0 done, 1 a run failed, 2 usage.\n");
}

static void on_progress(void *user, uint64_t done, uint64_t total)
{
    (void)user;
    fprintf(stderr, "odo-soak: %" PRIu64 " / %" PRIu64 " ticks\n", done, total);
}

static int parse_u64(const char *s, uint64_t *v)
{
    char *end = NULL;
    errno = 0;
    const unsigned long long x = strtoull(s, &end, 10);
    if (end == s || *end != '\0' || errno != 0 || s[0] == '-') {
        return -1;
    }
    *v = x;
    return 0;
}

int main(int argc, char **argv)
{
    int json = 0, quick = 0;
    soak_config_t soak;
    soak_defaults(&soak);
    if (!odo_cli_split_equals(&argc, &argv)) {
        return 1;
    }
    for (int i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            usage(stdout);
            return 0;
        } else if (strcmp(argv[i], "--version") == 0) {
            odo_cli_print_version("odo-soak");
            return 0;
        } else if (strcmp(argv[i], "--json") == 0) {
            json = 1;
        } else if (strcmp(argv[i], "--quick") == 0) {
            quick = 1;
        } else if (i + 1 < argc && strcmp(argv[i], "--ticks") == 0) {
            if (parse_u64(argv[++i], &soak.ticks) != 0 || soak.ticks < 100U || soak.ticks > 100000000U) {
                fprintf(stderr, "odo-soak: --ticks needs a whole number in [100, 1e8], not '%s'\n", argv[i]);
                return 2;
            }
        } else if (i + 1 < argc && strcmp(argv[i], "--seed") == 0) {
            if (parse_u64(argv[++i], &soak.seed) != 0) {
                fprintf(stderr, "odo-soak: --seed needs a whole number >= 0, not '%s'\n", argv[i]);
                return 2;
            }
        } else {
            fprintf(stderr, "odo-soak: unknown or incomplete argument '%s'\n\n", argv[i]);
            usage(stderr);
            return 2;
        }
    }
    if (quick && soak.ticks == 2160000U) {
        soak.ticks = 50000U;
    }

    /* Frame loss at speed: the three robots, straight for 40 s. */
    static const double speeds[] = {1000.0, 1600.0, 2500.0};
    const unsigned seeds = quick ? 3U : 10U;
    double lost_m[3], lost_pct[3], dist_m[3];
    for (unsigned v = 0U; v < 3U; ++v) {
        lost_m[v] = lost_pct[v] = dist_m[v] = 0.0;
        for (unsigned s = 0U; s < seeds; ++s) {
            soak_config_t c;
            memset(&c, 0, sizeof c);
            c.ticks = 1000U;
            c.seed = 1000U + s;
            c.straight_mm_s = speeds[v];
            c.drop = 0.20;
            soak_result_t r;
            if (soak_run(&c, &r, NULL, NULL) != 0) {
                fprintf(stderr, "odo-soak: the loss run failed\n");
                return 1;
            }
            const double lost = (r.end_x_clean_mm - r.end_x_faulty_mm) / 1000.0;
            dist_m[v] = r.end_x_clean_mm / 1000.0;
            if (fabs(lost) >= fabs(lost_m[v])) {
                lost_m[v] = lost;
                lost_pct[v] = 100.0 * lost / dist_m[v];
            }
        }
    }

    soak_result_t r;
    if (!json) {
        fprintf(stderr, "odo-soak: soak of %" PRIu64 " ticks ...\n", soak.ticks);
    }
    if (soak_run(&soak, &r, on_progress, NULL) != 0) {
        fprintf(stderr, "odo-soak: the soak run failed\n");
        return 1;
    }

    if (json) {
        printf("{\n  \"loss\": [\n");
        for (unsigned v = 0U; v < 3U; ++v) {
            printf("    {\"speed_m_s\": %.1f, \"drop\": 0.20, \"seeds\": %u, \"distance_m\": %.3f, "
                   "\"worst_travel_lost_m\": %.6g, \"worst_travel_lost_pct\": %.6g}%s\n",
                   speeds[v] / 1000.0, seeds, dist_m[v], lost_m[v], lost_pct[v], v < 2U ? "," : "");
        }
        printf("  ],\n  \"soak\": {\n");
        printf("    \"ticks\": %" PRIu64 ", \"hours\": %.3f, \"seed\": %" PRIu64 ", \"v_max_m_s\": %.1f,\n", soak.ticks,
               (double)soak.ticks * 0.04 / 3600.0, soak.seed, soak.v_max_mm_s / 1000.0);
        printf("    \"drop\": %.2f, \"dup\": %.2f, \"reorder\": %.2f, \"burst_every_ticks\": %" PRIu64
               ", \"burst_frames\": %u, \"clock_step_s\": %.3f,\n",
               soak.drop, soak.dup, soak.reorder, soak.burst_every, soak.burst_frames,
               (double)soak.clock_step_us / 1e6);
        printf("    \"frames_sent\": %" PRIu64 ", \"frames_on_faulty_bus\": %" PRIu64 ", \"dropped\": %" PRIu64
               ", \"duplicated\": %" PRIu64 ", \"reordered\": %" PRIu64 ", \"bursts\": %" PRIu64
               ", \"error_frames\": %" PRIu64 ",\n",
               r.frames_sent, r.frames_faulty, r.dropped, r.duplicated, r.reordered, r.bursts, r.error_frames);
        printf("    \"ticks_clean\": %" PRIu64 ", \"ticks_faulty\": %" PRIu64 ", \"clock_steps\": %" PRIu64
               ", \"gaps_skipped\": %" PRIu64 ",\n",
               r.ticks_clean, r.ticks_faulty, r.clock_steps, r.gaps);
        printf("    \"path_km\": %.6f,\n", r.path_m / 1000.0);
        printf("    \"end_pos_err_mm\": %.6f, \"end_heading_err_deg\": %.9f, \"max_pos_err_mm\": %.6f, "
               "\"max_lag_mm\": %.3f,\n",
               r.end_pos_err_mm, r.end_heading_err_deg, r.max_pos_err_mm, r.max_lag_mm);
        printf("    \"ticks_flagged\": {\"wheel_missing\": %" PRIu64 ", \"seq_gap\": %" PRIu64 ", \"seq_dup\": %" PRIu64
               ", \"counter_jump\": %" PRIu64 ", \"bus_error\": %" PRIu64 ", \"time_backwards\": %" PRIu64 "},\n",
               r.fault_ticks[3], r.fault_ticks[5], r.fault_ticks[6], r.fault_ticks[1], r.fault_ticks[16],
               r.fault_ticks[17]);
        printf("    \"wall_s\": %.2f, \"ticks_per_s\": %.0f\n  }\n}\n", r.wall_s,
               r.wall_s > 0.0 ? 2.0 * (double)soak.ticks / r.wall_s : 0.0);
    } else {
        for (unsigned v = 0U; v < 3U; ++v) {
            printf("loss at %.1f m/s, 20 %% of frames dropped, worst of %u: %.3g m of %.1f m (%.3g %%)\n",
                   speeds[v] / 1000.0, seeds, lost_m[v], dist_m[v], lost_pct[v]);
        }
        printf("soak %.1f h: path %.3f km; end error %.3f mm / %.6f deg; worst %.3f mm "
               "(lag while frames are missing up to %.1f mm); %" PRIu64 " counter jumps\n",
               (double)soak.ticks * 0.04 / 3600.0, r.path_m / 1000.0, r.end_pos_err_mm, r.end_heading_err_deg,
               r.max_pos_err_mm, r.max_lag_mm, r.fault_ticks[1]);
    }
    return 0;
}
