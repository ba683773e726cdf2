/// The 40 ms application step (see odo_app.h). Pure: no HAL, no globals.
#include "odo/odo_app.h"

#include "odo/odo_can.h"

/// Initial poses: truck A at the origin heading +x; the rear truck (clapper, 004 Fig. 6) or the
/// trailer axle (set) straight behind it, so Eq. 16 holds from the first tick.
static void reset_poses(odo_app_t *app)
{
    const odo_link_params_t *l = &app->params.link;
    odo_pose_t pose = {0, 0, 0U};
    odo_truck_reset(&app->truck[ODO_TRUCK_A], &pose);
    uint64_t behind_nm = 0U;
    if (app->params.vehicle == (uint8_t)ODO_VEHICLE_CLAPPER) {
        behind_nm = l->length_nm;
    } else if (app->params.vehicle == (uint8_t)ODO_VEHICLE_SET) {
        behind_nm = (uint64_t)l->hitch_offset_nm + l->length_nm;
    }
    /* nm -> mm Q32: * 2^32 / 10^6, exact enough (< 1e-9 mm) and within int64 for <= 15 m. */
    pose.x_mm_q32 = -(int64_t)((behind_nm << 32) / 1000000U);
    odo_truck_reset(&app->truck[ODO_TRUCK_B], &pose);
}

static bool init_models(odo_app_t *app, const odo_params_t *p)
{
    /* Only the trucks the vehicle has: a single truck's unused record B keeps the defaults, whose
     * count rate need not fit a narrow counter (a 12-bit decoder on a 50 ms robot). */
    const uint8_t n = (p->vehicle == (uint8_t)ODO_VEHICLE_SINGLE) ? 1U : ODO_TRUCKS;
    for (uint8_t i = 0U; i < n; ++i) {
        if (odo_model_init(&app->model[i], &p->truck[i], p->counter_bits, p->heading_form, p->tick_us,
                           p->max_wheel_speed_mm_s) != ODO_MODEL_OK) {
            return false;
        }
    }
    return true;
}

odo_params_status_t odo_app_init_params(odo_app_t *app, const odo_params_t *p)
{
    memset(app, 0, sizeof *app);
    odo_params_status_t st = odo_params_validate(p, NULL, NULL);
    if (st == ODO_PARAMS_OK && !init_models(app, p)) {
        st = ODO_PARAMS_ERR_RANGE; /* valid fields, but multipliers that do not fit: see odometry */
    }
    if (st == ODO_PARAMS_OK) {
        app->params = *p;
    } else {
        odo_params_defaults(&app->params);
        (void)init_models(app, &app->params); /* the defaults always fit (unit-tested) */
    }
    app->params_status = st;
    app->trucks = (app->params.vehicle == (uint8_t)ODO_VEHICLE_SINGLE) ? 1U : 2U;
    reset_poses(app);
    return st;
}

odo_params_status_t odo_app_init(odo_app_t *app, const uint8_t *block, size_t len)
{
    odo_params_t p;
    const odo_params_status_t load = odo_params_load(block, len, &p);
    const odo_params_status_t st = odo_app_init_params(app, &p);
    if (load != ODO_PARAMS_OK) {
        app->params_status = load;
        return load;
    }
    return st;
}

/// Count each raised fault bit; a clean tick (faults == 0) costs one test.
static void count_faults(odo_fault_counters_t *c, uint32_t faults)
{
    for (unsigned b = 0U; faults != 0U && b < ODO_FAULT_COUNT; ++b, faults >>= 1) {
        if ((faults & 1U) != 0U && c->count[b] != UINT32_MAX) {
            c->count[b]++;
        }
    }
}

/// round(dt_us / tick_us) for dt_us < 2^32: one 32-bit division (a single UDIV on a Cortex-M4).
static uint32_t ticks_in(uint32_t dt_us, uint32_t tick_us)
{
    const uint32_t q = dt_us / tick_us;
    const uint32_t r = dt_us - q * tick_us;
    return q + (r >= tick_us - r ? 1U : 0U);
}

/// Sequence check of a truck's wheel sample, and the ticks elapsed since its previous one (see
/// odo_app_step): a repeat is a duplicate, a skip is lost frames. Counters are cumulative, so
/// the sample is integrated over the whole gap.
static uint32_t check_seq(odo_app_t *app, uint8_t truck, uint8_t seq, uint64_t t_us, uint32_t *ticks)
{
    uint32_t f = 0U;
    uint32_t n = 1U;
    if (app->seen_seq[truck]) {
        const uint8_t step = (uint8_t)(seq - app->last_seq[truck]);
        if (step == 0U) {
            f |= ODO_FAULT_SEQ_DUP;
        } else {
            if (step != 1U) {
                f |= ODO_FAULT_SEQ_GAP;
            }
            n = step < 128U ? step : 256U - step; /* older than the last sample: its distance back */
        }
        /* The sequence number wraps at 256: from 128 ticks on, the clock counts them. */
        const uint64_t last = app->last_wheel_t_us[truck];
        const uint32_t tick_us = app->params.tick_us;
        if (t_us >= last && t_us - last >= ((uint64_t)tick_us << 7)) {
            const uint64_t dt = t_us - last;
            n = dt > UINT32_MAX ? UINT32_MAX : ticks_in((uint32_t)dt, tick_us);
        }
    }
    app->seen_seq[truck] = true;
    app->last_seq[truck] = seq;
    app->last_wheel_t_us[truck] = t_us;
    *ticks = n;
    return f;
}

static const uint32_t FAULT_MISSING[ODO_TRUCKS] = {ODO_FAULT_WHEEL_MISSING_A, ODO_FAULT_WHEEL_MISSING_B};
static const uint32_t FAULT_JUMP[ODO_TRUCKS] = {ODO_FAULT_COUNTER_JUMP_A, ODO_FAULT_COUNTER_JUMP_B};
static const uint32_t FAULT_DECODER[ODO_TRUCKS] = {ODO_FAULT_DECODER_A, ODO_FAULT_DECODER_B};

/// Bit indices of the two faults STATUS.Rejected counts (checked against odo_status.h below).
#define FAULT_BIT_CAN_BAD_DLC    14U
#define FAULT_BIT_CAN_UNKNOWN_ID 15U
typedef char fault_bit_bad_dlc_matches[(1UL << FAULT_BIT_CAN_BAD_DLC) == ODO_FAULT_CAN_BAD_DLC ? 1 : -1];
typedef char fault_bit_unknown_id_matches[(1UL << FAULT_BIT_CAN_UNKNOWN_ID) == ODO_FAULT_CAN_UNKNOWN_ID ? 1 : -1];

/// Pack this tick's frames. A position beyond POSE_XY's range is sent saturated and flagged here,
/// in out->faults and that truck's POSE_THETA flags, before STATUS is packed.
static void publish(const odo_app_t *app, uint8_t pose_flags[ODO_TRUCKS], odo_tick_output_t *out)
{
    uint8_t n = 0U;
    for (uint8_t i = 0U; i < app->trucks; ++i) {
        bool sat = false;
        const odo_msg_pose_xy_t xy = {odo_mm_q32_to_10um(out->pose[i].x_mm_q32, &sat),
                                      odo_mm_q32_to_10um(out->pose[i].y_mm_q32, &sat)};
        if (sat) {
            out->faults |= ODO_FAULT_POSE_XY_SATURATED;
            pose_flags[i] |= ODO_POSE_FLAG_XY_SATURATED;
        }
        const odo_msg_pose_theta_t th = {odo_heading_bam(&out->pose[i]), app->out_seq, pose_flags[i]};
        odo_can_pack_pose_xy(i, &xy, &out->frames[n++]);
        odo_can_pack_pose_theta(i, &th, &out->frames[n++]);
    }
    if (app->trucks == 2U) {
        const odo_msg_ipec_corr_t corr = {out->ipec_dtheta_bam[0], out->ipec_dtheta_bam[1]};
        odo_can_pack_ipec_corr(&corr, &out->frames[n++]);
    }
    /* Rejected frames since boot, this tick's included (counted after publishing). */
    const uint64_t rejected =
        (uint64_t)app->faults.count[FAULT_BIT_CAN_BAD_DLC] + app->faults.count[FAULT_BIT_CAN_UNKNOWN_ID] +
        ((out->faults >> FAULT_BIT_CAN_BAD_DLC) & 1U) + ((out->faults >> FAULT_BIT_CAN_UNKNOWN_ID) & 1U);
    const odo_msg_status_t st = {out->faults, app->out_seq, (uint8_t)app->params_status,
                                 (uint16_t)(rejected > UINT16_MAX ? UINT16_MAX : rejected)};
    odo_can_pack_status(&st, &out->frames[n++]);
    out->n_frames = n;
}

/// Linkage check and, with IPEC on, the correction of both trucks (odo_ipec.h). Returns faults.
static uint32_t ipec_tick(odo_app_t *app, const odo_tick_input_t *in, bool dr_ok, uint8_t pose_flags[ODO_TRUCKS],
                          odo_tick_output_t *out)
{
    odo_ipec_reading_t rd;
    uint32_t f = odo_ipec_check(&app->ipec, &app->params, &in->link, &rd);
    if (app->params.ipec_mode == (uint8_t)ODO_IPEC_OFF) {
        return f;
    }
    if (f != 0U || !dr_ok) {
        pose_flags[ODO_TRUCK_A] |= ODO_POSE_FLAG_IPEC_GATED;
        pose_flags[ODO_TRUCK_B] |= ODO_POSE_FLAG_IPEC_GATED;
        return f | ODO_FAULT_IPEC_GATED;
    }
    odo_pose_t pose[ODO_TRUCKS] = {app->truck[ODO_TRUCK_A].pose, app->truck[ODO_TRUCK_B].pose};
    odo_ipec_result_t r;
    odo_ipec_step(&app->params, &rd, pose, out->dist_mm_q40[ODO_TRUCK_A], &r);
    for (uint8_t i = 0U; i < ODO_TRUCKS; ++i) {
        app->truck[i].pose = pose[i];
        out->ipec_dtheta_bam[i] = r.dtheta_bam[i];
        out->ipec_innov_bam[i] = r.innov_bam[i];
        if (r.dtheta_bam[i] != 0) {
            pose_flags[i] |= ODO_POSE_FLAG_IPEC;
        }
    }
    out->ipec_applied = true;
    return f;
}

/// One truck's wheel sample: sequence and decoder checks, then odometry over the ticks elapsed.
/// Returns odo_step_t.range (the pose is beyond ODO_POSE_LIMIT_MM_Q32).
static bool wheel_step(odo_app_t *app, uint8_t i, const odo_wheel_input_t *w, uint64_t t_us, uint32_t *faults,
                       uint8_t *pose_flags, bool *dr_ok, odo_tick_output_t *out)
{
    if ((w->status & (ODO_WHEEL_STATUS_LEFT_SKIPPED | ODO_WHEEL_STATUS_RIGHT_SKIPPED | ODO_WHEEL_STATUS_LEFT_FAULT |
                      ODO_WHEEL_STATUS_RIGHT_FAULT)) != 0U) {
        *faults |= FAULT_DECODER[i];
    }
    uint32_t ticks = 1U;
    *faults |= check_seq(app, i, w->seq, t_us, &ticks);
    odo_step_t st;
    odo_truck_step(&app->truck[i], &app->model[i], w->left_raw, w->right_raw, w->bits, ticks, &st);
    if (st.jump) {
        *dr_ok = false;
        *faults |= FAULT_JUMP[i];
        *pose_flags |= ODO_POSE_FLAG_JUMP;
    }
    out->dist_mm_q40[i] = st.dist_mm_q40;
    out->dturn_q64[i] = st.dturn_q64;
    return st.range;
}

void odo_app_step(odo_app_t *app, const odo_tick_input_t *in, odo_tick_output_t *out)
{
    uint32_t faults = in->rx_faults;
    uint8_t pose_flags[ODO_TRUCKS] = {0U, 0U};
    memset(out, 0, sizeof *out);

    if (app->params_status != ODO_PARAMS_OK) {
        faults |= ODO_FAULT_PARAMS_DEFAULTED;
    }
    if (app->have_time && in->t_us < app->last_t_us) {
        faults |= ODO_FAULT_TIME_BACKWARDS; /* still stepped: counts, not time, carry the motion */
    }
    app->have_time = true;
    app->last_t_us = in->t_us;

    bool dr_ok = true; /* every truck's sample integrated: IPEC may compare */
    for (uint8_t i = 0U; i < app->trucks; ++i) {
        const odo_wheel_input_t *w = &in->wheel[i];
        bool range;
        if (!w->present) {
            dr_ok = false;
            faults |= FAULT_MISSING[i];
            pose_flags[i] |= ODO_POSE_FLAG_MISSING;
            range = !odo_pose_in_range(&app->truck[i].pose);
        } else {
            range = wheel_step(app, i, w, in->t_us, &faults, &pose_flags[i], &dr_ok, out);
        }
        if (range) {
            dr_ok = false; /* held from the next step on; IPEC must not move it either */
            faults |= ODO_FAULT_POSE_RANGE;
            pose_flags[i] |= ODO_POSE_FLAG_RANGE;
        }
    }

    if (app->trucks == 2U) {
        faults |= ipec_tick(app, in, dr_ok, pose_flags, out);
    }

    for (uint8_t i = 0U; i < ODO_TRUCKS; ++i) {
        out->pose[i] = app->truck[i].pose;
    }
    out->faults = faults;
    publish(app, pose_flags, out);
    count_faults(&app->faults, out->faults);
    app->out_seq++;
    app->ticks++;
}
