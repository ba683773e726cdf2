/// Soak and frame-loss figures (see soak.h).
#include "soak.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "odo/odo_can.h"
#include "odo/odo_params.h"
#include "odo_synth.h"
#include "replay.h"

#define T0_US      1700000000000000ULL /* the drive's first frame: an ordinary Unix time */
#define RING       4096U               /* clean poses kept for the lagging faulty run */
#define CLEAN_EDGE 16U                 /* first and last ticks without faults */
#define WIRE_MASK  0xFFFFFFU           /* 24-bit counts in WHEEL_COUNTS (can/odometry.dbc) */

static uint64_t next_u64(uint64_t *state)
{
    uint64_t z = (*state += 0x9E3779B97F4A7C15ULL); /* splitmix64 */
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

static double uniform(uint64_t *state, double lo, double hi)
{
    return lo + (hi - lo) * ((double)(next_u64(state) >> 11) * (1.0 / 9007199254740992.0));
}

static bool chance(uint64_t *state, double p) { return uniform(state, 0.0, 1.0) < p; }

void soak_defaults(soak_config_t *c)
{
    memset(c, 0, sizeof *c);
    c->ticks = 2160000U;
    c->seed = 16U;
    c->v_max_mm_s = 3000.0;
    c->drop = 0.20;
    c->dup = 0.05;
    c->reorder = 0.02;
    c->burst_every = 15000U;
    c->burst_frames = 20U;
    c->clock_step_us = -2000000;
}

/// The next segment of the random program: straight, arc, turn on the spot or stop, 0.5-8 s,
/// no wheel faster than v_max.
static void next_segment(odo_synth_t *s, uint64_t *rng, double v_max)
{
    const uint64_t kind = next_u64(rng) % 8U;
    double vl = 0.0, vr = 0.0;
    if (kind < 3U) {
        vl = vr = uniform(rng, -v_max, v_max);
    } else if (kind < 6U) {
        const double v = uniform(rng, -0.8 * v_max, 0.8 * v_max);
        const double r = uniform(rng, 300.0, 20000.0) * ((next_u64(rng) & 1U) ? 1.0 : -1.0);
        vl = v * (1.0 - s->b_mm / (2.0 * r));
        vr = v * (1.0 + s->b_mm / (2.0 * r));
        const double top = fmax(fabs(vl), fabs(vr));
        if (top > v_max) {
            vl *= v_max / top;
            vr *= v_max / top;
        }
    } else if (kind < 7U) {
        vr = uniform(rng, -0.5 * v_max, 0.5 * v_max);
        vl = -vr;
    }
    odo_synth_segment(s, vl, vr, (uint32_t)(uniform(rng, 0.5, 8.0) / s->tick_s));
}

typedef struct {
    odo_pose_t pose[RING];
    uint64_t latest; ///< last tick the clean run stepped
    bool any;
    double path_mm;
    uint64_t ticks;
} clean_t;

typedef struct {
    const clean_t *clean;
    soak_result_t *r;
    uint64_t ticks;
} faulty_t;

static double dist_mm(int64_t q40) { return fabs((double)q40) / 1099511627776.0; }

static void on_clean(void *user, replay_t *rp, uint64_t tick, const odo_tick_input_t *in, const odo_tick_output_t *out)
{
    (void)rp;
    (void)in;
    clean_t *c = user;
    c->pose[tick % RING] = out->pose[ODO_TRUCK_A];
    c->latest = tick;
    c->any = true;
    c->path_mm += dist_mm(out->dist_mm_q40[ODO_TRUCK_A]);
    c->ticks++;
}

static double pos_err_mm(const odo_pose_t *a, const odo_pose_t *b)
{
    return hypot((double)(a->x_mm_q32 - b->x_mm_q32), (double)(a->y_mm_q32 - b->y_mm_q32)) / 4294967296.0;
}

static void on_faulty(void *user, replay_t *rp, uint64_t tick, const odo_tick_input_t *in, const odo_tick_output_t *out)
{
    (void)rp;
    faulty_t *f = user;
    f->ticks++;
    for (unsigned b = 0U; b < ODO_FAULT_COUNT; ++b) {
        f->r->fault_ticks[b] += (out->faults >> b) & 1U;
    }
    const clean_t *c = f->clean;
    if (!c->any || tick > c->latest || c->latest - tick >= RING) {
        return; /* cannot happen while the faulty run lags by less than RING ticks */
    }
    const double e = pos_err_mm(&out->pose[ODO_TRUCK_A], &c->pose[tick % RING]);
    f->r->max_lag_mm = fmax(f->r->max_lag_mm, e);
    const bool synced = in->wheel[ODO_TRUCK_A].present && (out->faults & ODO_FAULT_COUNTER_JUMP_A) == 0U;
    if (synced) {
        f->r->max_pos_err_mm = fmax(f->r->max_pos_err_mm, e);
    }
}

typedef struct {
    odo_can_frame_t f;
    uint64_t t_us;
} tframe_t;

int soak_run(const soak_config_t *c, soak_result_t *r, soak_progress_fn progress, void *user)
{
    memset(r, 0, sizeof *r);
    struct timespec t_start, t_end;
    clock_gettime(CLOCK_MONOTONIC, &t_start);
    replay_t *clean_rp = calloc(1U, sizeof *clean_rp);
    replay_t *bad_rp = calloc(1U, sizeof *bad_rp);
    clean_t *clean = calloc(1U, sizeof *clean);
    if (clean_rp == NULL || bad_rp == NULL || clean == NULL) {
        free(clean_rp);
        free(bad_rp);
        free(clean);
        return -1;
    }
    faulty_t faulty = {.clean = clean, .r = r};
    odo_params_t p;
    odo_params_defaults(&p);
    if (replay_init(clean_rp, &p, on_clean, clean) != ODO_PARAMS_OK ||
        replay_init(bad_rp, &p, on_faulty, &faulty) != ODO_PARAMS_OK) {
        free(clean_rp);
        free(bad_rp);
        free(clean);
        return -1;
    }

    odo_synth_t drive;
    odo_synth_init(&drive, c->seed, &p.truck[0], p.tick_us);
    uint64_t rng_drive = c->seed ^ 0xD1B54A32D192ED03ULL, rng_bus = c->seed ^ 0x8CB92BA72F3D8DD7ULL;
    const double v_max = fmin(fabs(c->v_max_mm_s), (double)p.max_wheel_speed_mm_s);
    if (c->straight_mm_s != 0.0) {
        odo_synth_segment(&drive, c->straight_mm_s, c->straight_mm_s, UINT32_MAX);
    }
    int64_t count[2] = {0, 0};
    bool held = false;
    uint64_t held_at = 0U;
    tframe_t hold;
    const uint64_t report_every = c->ticks / 10U + 1U;
    for (uint64_t k = 0U; k < c->ticks; ++k) {
        if (drive.remaining == 0U) {
            next_segment(&drive, &rng_drive, v_max);
        }
        /* The first sample sets the firmware's baseline and the last ones close the runs: keep
         * them clean, so both runs integrate the same counts from and to rest. */
        const bool tail = k < CLEAN_EDGE || k + CLEAN_EDGE >= c->ticks;
        if (c->straight_mm_s == 0.0 && (k == 0U || k + CLEAN_EDGE == c->ticks)) {
            odo_synth_segment(&drive, 0.0, 0.0, CLEAN_EDGE); /* start and end at rest */
        }
        int32_t d[2];
        odo_synth_next(&drive, &d[0], &d[1]);
        count[0] += d[0];
        count[1] += d[1];
        const odo_msg_wheel_counts_t m = {(uint32_t)((uint64_t)count[0] & WIRE_MASK),
                                          (uint32_t)((uint64_t)count[1] & WIRE_MASK), (uint8_t)k, 0U};
        tframe_t fr;
        odo_can_pack_wheel_counts(ODO_TRUCK_A, &m, &fr.f);
        fr.t_us = T0_US + k * (uint64_t)p.tick_us;
        replay_push(clean_rp, &fr.f, fr.t_us);
        r->frames_sent++;

        /* the faulty bus */
        if (c->clock_step_us != 0 && k >= c->ticks / 2U) {
            fr.t_us = (uint64_t)((int64_t)fr.t_us + c->clock_step_us);
        }
        bool lost = false;
        if (!tail && c->burst_every > 0U && chance(&rng_bus, 1.0 / (double)c->burst_every)) {
            for (unsigned e = 0U; e < c->burst_frames; ++e) {
                const odo_can_frame_t ef = {
                    .id = e + 1U == c->burst_frames ? 0x40U : 0x04U, .dlc = 8U, .flags = ODO_CAN_FLAG_ERR};
                replay_push(bad_rp, &ef, fr.t_us);
                r->error_frames++;
                r->frames_faulty++;
            }
            r->bursts++;
            lost = true; /* the burst took this tick's frame with it */
        }
        if (!lost && !tail && chance(&rng_bus, c->drop)) {
            lost = true;
            r->dropped++;
        }
        if (!lost && !tail && !held && chance(&rng_bus, c->reorder)) {
            hold = fr; /* sent after the next tick's frame */
            held = true;
            held_at = k;
            r->reordered++;
        } else if (!lost) {
            const int copies = (!tail && chance(&rng_bus, c->dup)) ? 2 : 1;
            for (int n = 0; n < copies; ++n) {
                replay_push(bad_rp, &fr.f, fr.t_us);
                r->frames_faulty++;
            }
            r->duplicated += copies == 2 ? 1U : 0U;
        }
        if (held && k > held_at) {
            replay_push(bad_rp, &hold.f, hold.t_us);
            r->frames_faulty++;
            held = false;
        }
        if (progress != NULL && (k + 1U) % report_every == 0U) {
            progress(user, k + 1U, c->ticks);
        }
    }
    if (held) {
        replay_push(bad_rp, &hold.f, hold.t_us);
        r->frames_faulty++;
    }
    replay_finish(clean_rp);
    replay_finish(bad_rp);

    r->ticks_clean = clean->ticks;
    r->ticks_faulty = faulty.ticks;
    r->clock_steps = bad_rp->stats.clock_steps;
    r->gaps = bad_rp->stats.gaps;
    r->path_m = clean->path_mm / 1000.0;
    const odo_pose_t *ce = &clean_rp->app.truck[ODO_TRUCK_A].pose;
    const odo_pose_t *fe = &bad_rp->app.truck[ODO_TRUCK_A].pose;
    r->end_pos_err_mm = pos_err_mm(fe, ce);
    r->end_heading_err_deg = (double)(int64_t)(fe->heading_q64 - ce->heading_q64) / 18446744073709551616.0 * 360.0;
    r->end_x_clean_mm = (double)ce->x_mm_q32 / 4294967296.0;
    r->end_x_faulty_mm = (double)fe->x_mm_q32 / 4294967296.0;
    clock_gettime(CLOCK_MONOTONIC, &t_end);
    r->wall_s = (double)(t_end.tv_sec - t_start.tv_sec) + 1e-9 * (double)(t_end.tv_nsec - t_start.tv_nsec);
    free(clean_rp);
    free(bad_rp);
    free(clean);
    return 0;
}
