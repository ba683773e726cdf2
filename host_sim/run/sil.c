#include "sil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "follower.h"
#include "hal_sim.h"
#include "odo/odo_can.h"
#include "odo/odo_fx.h"
#include "odo_loop.h"

#define MAX_RUN_S 3600.0
#define B_BUMP_MARGIN_MM \
    100.0 /* a bump this close to where B stops would be met while turning */ /* a run that has not finished after an hour is a bug, not a result */

/// Everything one run needs; large, so allocated once per run.
typedef struct {
    sim_world_t world;
    hal_ctx_t hal;
    odo_app_t app;
    odo_tick_input_t in;
    odo_tick_output_t out;
    sim_program_t prog;
    sim_follower_t follow;
    sim_clapper_follower_t follow2; ///< clapper: both trucks
} sil_state_t;

static double q32_mm(int64_t v) { return (double)v / 4294967296.0; }
static double q64_rad(uint64_t h)
{
    return (double)(int32_t)(uint32_t)((h + 0x80000000ULL) >> 32) * (M_PI / 2147483648.0);
}

/// Where truck B's wheel meets a floor bump placed at path distance p (*at, in B's wheel travel):
/// B runs the same path l behind A, so forward legs reach it l later and backward legs (B leading)
/// l earlier. A leg is a run of LINE/ARC segments between stops (PAUSE, TURN); B starts and ends
/// every leg l from A, so it never reaches a bump that lies between the two trucks at the leg's
/// end (forward: within l of the end) or start (backward: within l of the start): false then
/// (also within B_BUMP_MARGIN_MM of that, where B would stop on it).
static bool travel_of_b(const sim_program_t *prog, double p, double l, double *at)
{
    double pos = 0.0, leg_start = 0.0;
    for (size_t i = 0; i < prog->n_seg; ++i) {
        const sim_segment_t *s = &prog->seg[i];
        double len = 0.0;
        if (s->kind == SIM_SEG_LINE) {
            len = hypot(s->x1_mm - s->x0_mm, s->y1_mm - s->y0_mm);
        } else if (s->kind == SIM_SEG_ARC) {
            len = fabs(s->sweep_rad) * s->radius_mm;
        } else {
            leg_start = pos;
            continue;
        }
        if (p < pos + len) {
            double leg_end = pos + len;
            for (size_t j = i + 1;
                 j < prog->n_seg && (prog->seg[j].kind == SIM_SEG_LINE || prog->seg[j].kind == SIM_SEG_ARC); ++j) {
                const sim_segment_t *n = &prog->seg[j];
                leg_end += n->kind == SIM_SEG_LINE ? hypot(n->x1_mm - n->x0_mm, n->y1_mm - n->y0_mm)
                                                   : fabs(n->sweep_rad) * n->radius_mm;
            }
            if (s->kind == SIM_SEG_LINE && s->speed_mm_s < 0.0) {
                *at = p - l;
                return p >= leg_start + l + B_BUMP_MARGIN_MM;
            }
            *at = p + l;
            return p <= leg_end - l - B_BUMP_MARGIN_MM;
        }
        pos += len;
    }
    return false;
}

static int setup(sil_state_t *st, const sim_run_config_t *cfg, char *err, size_t errlen)
{
    const sim_robot_t *r = cfg->robot;
    const bool clapper = r->vehicle == SIM_VEHICLE_CLAPPER;
    if (sim_world_init(&st->world, r, cfg->scenario, cfg->seed, err, errlen) != 0) {
        return -1;
    }
    if (cfg->hidden != NULL && sim_world_set_hidden(&st->world, cfg->hidden, err, errlen) != 0) {
        return -1;
    }
    if (sim_program_build(cfg->experiment, cfg->ccw, cfg->bumps, cfg->bump_height_mm, cfg->run_index, &st->prog, err,
                          errlen) != 0) {
        return -1;
    }
    if (clapper && sim_program_for_clapper(&st->prog, r->link.length_mm) != 0) {
        snprintf(err, errlen, "the clapper's link length must be positive");
        return -1;
    }
    /* A floor bump lies under that side's wheels of every driven truck that passes it (004 s. 6.1:
     * under the right-side wheels of both trucks; "some affected only one of the two trucks");
     * the set's trailer keeps off the program's bumps. */
    for (size_t i = 0; i < st->prog.n_bumps; ++i) {
        const sim_bump_t *b = &st->prog.bump[i];
        double at_b = 0.0;
        if (sim_world_add_bump(&st->world, ODO_TRUCK_A, b->side, b->at_path_mm, b->height_mm) != 0 ||
            (clapper && travel_of_b(&st->prog, b->at_path_mm, r->link.length_mm, &at_b) &&
             sim_world_add_bump(&st->world, ODO_TRUCK_B, b->side, at_b, b->height_mm) != 0)) {
            snprintf(err, errlen, "bump %zu of the program does not fit the world", i);
            return -1;
        }
    }

    odo_params_t p;
    if (sim_robot_to_params(r, &p, err, errlen) != 0) {
        return -1;
    }
    /* cfg->ipec: 0 off, 1 the paper's per-tick form, 2 the sub-resolution estimator. */
    p.ipec_mode = (uint8_t)(cfg->ipec == 2 ? ODO_IPEC_ESTIMATOR : cfg->ipec ? ODO_IPEC_PAPER : ODO_IPEC_OFF);
    /* Boot like the target: from an encoded parameter block. */
    uint8_t block[ODO_PARAMS_SIZE];
    (void)odo_params_encode(&p, block, sizeof block);
    const odo_params_status_t ps = odo_app_init(&st->app, block, sizeof block);
    if (ps != ODO_PARAMS_OK) {
        snprintf(err, errlen, "the firmware refused the robot's parameters: %s", odo_params_status_str(ps));
        return -1;
    }

    const double f_clk = sim_world_count_loss_f_clk_hz(&st->world, ODO_TRUCK_A);
    hal_sim_config_t hc = {
        .f_clk_hz = f_clk > 0.0 ? (uint32_t)f_clk : ODOSIM_HCTL_F_CLK_MAX_HZ,
        .convention = r->truck[0].decoder == SIM_DECODER_HCTL20XX ? ODOSIM_HCTL_CONV_20XX : ODOSIM_HCTL_CONV_1100,
        .force_per_edge = false,
        .rotary_bits = (uint8_t)(r->link.rotary_bits ? r->link.rotary_bits : 10U),
        .linear_resolution_um = (uint32_t)fmax(1.0, round(r->link.linear_resolution_mm * 1000.0)),
    };
    if (!hal_sim_init(&st->hal, (uint8_t)r->n_trucks, r->vehicle != SIM_VEHICLE_LABMATE, &hc)) {
        snprintf(err, errlen, "the sim HAL refused its configuration");
        return -1;
    }
    sim_follower_init(&st->follow, &st->prog, r->truck[0].wheelbase_mm, r->tick_ms / 1000.0);
    if (clapper) {
        sim_clapper_follower_init(&st->follow2, &st->prog, r->truck[0].wheelbase_mm, r->truck[1].wheelbase_mm,
                                  r->link.length_mm, r->tick_ms / 1000.0);
    }
    return 0;
}

/// Give the decoders the wheels' new phases, honouring each decoder's counting convention: the
/// sim HAL counts up for the HCTL-1100 direction, and an inverted encoder turns the other way.
static void feed_encoders(sil_state_t *st, const sim_robot_t *r, double t_s)
{
    for (unsigned t = 0; t < r->n_trucks; ++t) {
        for (unsigned w = 0; w < 2; ++w) {
            const bool inv = w == ODO_LEFT ? r->truck[t].invert_left : r->truck[t].invert_right;
            const double ph = sim_world_encoder_phase_counts(&st->world, t, w);
            (void)hal_sim_set_wheel_phase(&st->hal, (uint8_t)t, (uint8_t)w, t_s, inv ? -ph : ph);
        }
    }
}

int sim_run(const sim_run_config_t *cfg, sim_tick_fn on_tick, void *user, sim_return_t *ret, char *err, size_t errlen)
{
    sil_state_t *st = calloc(1, sizeof *st);
    if (st == NULL) {
        snprintf(err, errlen, "out of memory");
        return -1;
    }
    int rc = setup(st, cfg, err, errlen);
    const sim_robot_t *r = cfg->robot;
    const double dt = cfg->physics_dt_s > 0.0 ? cfg->physics_dt_s : SIM_WORLD_DEFAULT_DT_S;
    const double tick_s = r->tick_ms / 1000.0;
    const unsigned steps = (unsigned)llround(tick_s / dt);
    double cmd[2][2] = {{0, 0}, {0, 0}};
    bool running = true;
    size_t events_seen = 0;
    uint32_t tick = 0;
    unsigned settle = 0;
    while (rc == 0) {
        /* The firmware samples, publishes; the navigation computer reacts for the next tick. */
        hal_sim_set_time_us(&st->hal, (uint64_t)llround(sim_world_time_s(&st->world) * 1e6));
        if (r->vehicle != SIM_VEHICLE_LABMATE) {
            const sim_link_reading_t lr = sim_world_link_measured(&st->world);
            (void)hal_sim_set_link(&st->hal, lr.alpha_rad, lr.beta_rad, lr.length_mm,
                                   ODO_LINK_STATUS_ALPHA_VALID | ODO_LINK_STATUS_BETA_VALID |
                                       ODO_LINK_STATUS_LENGTH_VALID);
        }
        odo_loop_tick(&st->app, &st->hal, &st->in, &st->out);
        odo_can_frame_t f;
        uint64_t f_t;
        while (hal_sim_take_tx(&st->hal, &f, &f_t)) {
            /* outputs are in st->out too; the capture ring only must not fill up */
        }
        size_t n_ev = 0;
        const sim_bump_event_t *ev = sim_world_bump_events(&st->world, &n_ev);
        if (on_tick != NULL) {
            sim_tick_t tk = {
                .t_s = sim_world_time_s(&st->world),
                .tick = tick,
                .truth = {sim_world_pose(&st->world, 0), sim_world_pose(&st->world, 1)},
                .link = sim_world_link_true(&st->world),
                .input = &st->in,
                .output = &st->out,
                .events = ev + events_seen,
                .n_events = n_ev - events_seen,
            };
            on_tick(user, &tk);
        }
        events_seen = n_ev;
        tick++;
        if (!running && ++settle > 2) {
            break; /* stopped for a couple of ticks after the last segment */
        }
        if (r->vehicle == SIM_VEHICLE_CLAPPER) {
            /* The navigation computer drives both trucks from the firmware's poses and the
             * linkage encoders as the firmware read them (IPEC, when on, lives in the poses). */
            double pose[2][3];
            for (unsigned t = 0; t < 2U; ++t) {
                const odo_pose_t *pt = &st->out.pose[t];
                pose[t][0] = q32_mm(pt->x_mm_q32);
                pose[t][1] = q32_mm(pt->y_mm_q32);
                pose[t][2] = q64_rad(pt->heading_q64);
            }
            /* An absolute encoder's code k covers [k, k+1) steps: steer on its centre. */
            const double half_step = M_PI / ldexp(1.0, (int)st->app.params.link.rotary_bits);
            const sim_link_meas_t link = {
                .length_mm = st->in.link.length_um / 1000.0,
                .alpha_rad = (int16_t)st->in.link.alpha_bam16 * (M_PI / 32768.0) + half_step,
                .beta_rad = (int16_t)st->in.link.beta_bam16 * (M_PI / 32768.0) + half_step,
            };
            running = sim_clapper_follower_step(&st->follow2, (const double(*)[3])pose, &link, cmd) && running;
        } else {
            const odo_pose_t *pa = &st->out.pose[ODO_TRUCK_A];
            double wheel[2];
            running = sim_follower_step(&st->follow, q32_mm(pa->x_mm_q32), q32_mm(pa->y_mm_q32),
                                        q64_rad(pa->heading_q64), wheel) &&
                      running;
            cmd[0][0] = wheel[0];
            cmd[0][1] = wheel[1];
        }
        for (unsigned k = 0; k < steps && rc == 0; ++k) {
            if (sim_world_step(&st->world, dt, (const double(*)[2])cmd) != 0) {
                snprintf(err, errlen, "the world refused a step at t = %.3f s", sim_world_time_s(&st->world));
                rc = -1;
            }
            feed_encoders(st, r, sim_world_time_s(&st->world));
        }
        if (sim_world_time_s(&st->world) > MAX_RUN_S) {
            snprintf(err, errlen, "%s did not finish within %.0f s of simulated time", cfg->experiment, MAX_RUN_S);
            rc = -1;
        }
    }
    if (rc == 0) {
        const sim_pose_t truth = sim_world_pose(&st->world, ODO_TRUCK_A);
        const odo_pose_t *est = &st->out.pose[ODO_TRUCK_A];
        memset(ret, 0, sizeof *ret);
        ret->run = cfg->run_index + 1U;
        ret->ccw = cfg->ccw;
        ret->x_abs_mm = truth.x_mm;
        ret->y_abs_mm = truth.y_mm;
        ret->theta_abs_deg = remainder(truth.theta_rad * 180.0 / M_PI, 360.0);
        ret->x_calc_mm = q32_mm(est->x_mm_q32);
        ret->y_calc_mm = q32_mm(est->y_mm_q32);
        ret->theta_calc_deg = q64_rad(est->heading_q64) * 180.0 / M_PI;
        ret->t_end_s = sim_world_time_s(&st->world);
        sim_return_errors(ret);
    }
    free(st);
    return rc;
}
