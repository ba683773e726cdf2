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
        /* The sequence number wraps at 256: from 128 ticks on, the clock counts them
         * (tick_us <= 1 s keeps 128 ticks below 2^32 us). */
        const uint64_t last = app->last_wheel_t_us[truck];
        const uint32_t tick_us = app->params.tick_us;
        const uint64_t dt = t_us - last;
        if (t_us >= last && ((dt >> 32) != 0U || (uint32_t)dt >= (tick_us << 7))) {
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
typedef char fault_bit_bad_dlc_matches[(ODO_FAULT_CAN_BAD_DLC >> FAULT_BIT_CAN_BAD_DLC) == 1U ? 1 : -1];
typedef char fault_bit_unknown_id_matches[(ODO_FAULT_CAN_UNKNOWN_ID >> FAULT_BIT_CAN_UNKNOWN_ID) == 1U ? 1 : -1];

/// One POSE_XY coordinate: mm Q32 to 10 um, saturated to int32 (the frame's +-21.47 km).
static inline int32_t xy_10um(int64_t v_mm_q32, bool *sat)
{
    const int64_t v = odo_mm_q32_to_10um_wide(v_mm_q32);
    if (v > INT32_MAX || v < INT32_MIN) {
        *sat = true;
        return v > 0 ? INT32_MAX : INT32_MIN;
    }
    return (int32_t)v;
}

/// A truck's POSE_XY and POSE_THETA frames into f[0..1]. A position beyond POSE_XY's range is
/// sent saturated and flagged (the truck's flags and, through *faults, STATUS).
static void publish_truck(const odo_pose_t *pose, uint8_t truck, uint8_t seq, uint8_t flags, uint32_t *faults,
                          odo_can_frame_t *f)
{
    bool sat = false;
    const odo_msg_pose_xy_t xy = {xy_10um(pose->x_mm_q32, &sat), xy_10um(pose->y_mm_q32, &sat)};
    if (sat) {
        *faults |= ODO_FAULT_POSE_XY_SATURATED;
        flags |= ODO_POSE_FLAG_XY_SATURATED;
    }
    const odo_msg_pose_theta_t th = {(uint32_t)((pose->heading_q64 + 0x80000000ULL) >> 32), seq, flags};
    odo_can_pack_pose_xy(truck, &xy, &f[0]);
    odo_can_pack_pose_theta(truck, &th, &f[1]);
}

/// STATUS: this tick's faults, the sequence number, the boot-time parameter state and the
/// rejected frames since boot, this tick's included (the counters are updated after publishing).
static void publish_status(const odo_app_t *app, uint32_t faults, odo_can_frame_t *f)
{
    const uint32_t c_dlc = app->faults.count[FAULT_BIT_CAN_BAD_DLC];
    const uint32_t c_id = app->faults.count[FAULT_BIT_CAN_UNKNOWN_ID];
    const uint32_t now = ((faults >> FAULT_BIT_CAN_BAD_DLC) & 1U) + ((faults >> FAULT_BIT_CAN_UNKNOWN_ID) & 1U);
    /* saturating at 65535 without a 64-bit sum: each count saturates at 2^32 - 1 */
    const uint32_t rejected = (c_dlc > UINT16_MAX || c_id > UINT16_MAX) ? UINT16_MAX : c_dlc + c_id + now;
    const odo_msg_status_t st = {faults, app->out_seq, (uint8_t)app->params_status,
                                 (uint16_t)(rejected > UINT16_MAX ? UINT16_MAX : rejected)};
    odo_can_pack_status(&st, f);
}

/// Linkage check and, with IPEC on, the correction of both trucks (odo_ipec.h). Returns faults.
/// With IPEC off only the check runs (its faults are reported); the reading is not decoded.
static uint32_t ipec_tick(odo_app_t *app, const odo_tick_input_t *in, bool dr_ok, uint8_t pose_flags[ODO_TRUCKS],
                          odo_tick_output_t *out)
{
    if (app->params.ipec_mode == (uint8_t)ODO_IPEC_OFF) {
        return odo_ipec_check(&app->ipec, &app->params, &in->link, NULL);
    }
    odo_ipec_reading_t rd;
    const uint32_t f = odo_ipec_check(&app->ipec, &app->params, &in->link, &rd);
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

/// Flags that mean a truck's dead reckoning did not run this tick (IPEC must not compare).
#define POSE_FLAGS_NOT_INTEGRATED (ODO_POSE_FLAG_MISSING | ODO_POSE_FLAG_JUMP | ODO_POSE_FLAG_RANGE)

/// One truck's wheel sample: presence, decoder and sequence checks, then odometry over the ticks
/// elapsed (odo_truck_tick). Writes this tick's dist_mm_q40/dturn_q64 of the truck, ORs its
/// faults into *faults and returns its pose flags.
static uint8_t truck_tick(odo_app_t *app, uint8_t i, const odo_wheel_input_t *w, uint64_t t_us, uint32_t *faults,
                          odo_tick_output_t *out)
{
    uint32_t f = 0U;
    uint8_t flags = 0U;
    uint32_t r;
    int64_t motion[2] = {0, 0};
    if (!w->present) {
        f = FAULT_MISSING[i];
        flags = ODO_POSE_FLAG_MISSING;
        r = odo_pose_in_range(&app->truck[i].pose) ? 0U : ODO_STEP_RANGE;
    } else {
        if ((w->status & (ODO_WHEEL_STATUS_LEFT_SKIPPED | ODO_WHEEL_STATUS_RIGHT_SKIPPED | ODO_WHEEL_STATUS_LEFT_FAULT |
                          ODO_WHEEL_STATUS_RIGHT_FAULT)) != 0U) {
            f = FAULT_DECODER[i];
        }
        uint32_t ticks = 1U;
        f |= check_seq(app, i, w->seq, t_us, &ticks);
        r = odo_truck_tick(&app->truck[i], &app->model[i], w, ticks, motion);
    }
    out->dist_mm_q40[i] = motion[0];
    out->dturn_q64[i] = motion[1];
    if ((r & ODO_STEP_JUMP) != 0U) {
        f |= FAULT_JUMP[i];
        flags |= ODO_POSE_FLAG_JUMP;
    }
    if ((r & ODO_STEP_RANGE) != 0U) {
        f |= ODO_FAULT_POSE_RANGE; /* held from the next step on; IPEC must not move it either */
        flags |= ODO_POSE_FLAG_RANGE;
    }
    *faults |= f;
    return flags;
}

void odo_app_step(odo_app_t *app, const odo_tick_input_t *in, odo_tick_output_t *out)
{
    uint32_t faults = in->rx_faults;
    if (app->params_status != ODO_PARAMS_OK) {
        faults |= ODO_FAULT_PARAMS_DEFAULTED;
    }
    if (app->have_time && in->t_us < app->last_t_us) {
        faults |= ODO_FAULT_TIME_BACKWARDS; /* still stepped: counts, not time, carry the motion */
    }
    app->have_time = true;
    app->last_t_us = in->t_us;

    /* Every output field is written below; no memset of the whole struct (frames beyond
     * n_frames are left as they were). */
    out->ipec_applied = false;
    out->ipec_dtheta_bam[ODO_TRUCK_A] = 0;
    out->ipec_dtheta_bam[ODO_TRUCK_B] = 0;
    out->ipec_innov_bam[ODO_TRUCK_A] = 0;
    out->ipec_innov_bam[ODO_TRUCK_B] = 0;
    uint8_t flags[ODO_TRUCKS] = {0U, 0U};
    flags[ODO_TRUCK_A] = truck_tick(app, ODO_TRUCK_A, &in->wheel[ODO_TRUCK_A], in->t_us, &faults, out);
    if (app->trucks == 2U) {
        flags[ODO_TRUCK_B] = truck_tick(app, ODO_TRUCK_B, &in->wheel[ODO_TRUCK_B], in->t_us, &faults, out);
        const bool dr_ok = ((flags[ODO_TRUCK_A] | flags[ODO_TRUCK_B]) & POSE_FLAGS_NOT_INTEGRATED) == 0U;
        faults |= ipec_tick(app, in, dr_ok, flags, out);
    } else {
        out->dist_mm_q40[ODO_TRUCK_B] = 0;
        out->dturn_q64[ODO_TRUCK_B] = 0;
    }

    out->pose[ODO_TRUCK_A] = app->truck[ODO_TRUCK_A].pose;
    out->pose[ODO_TRUCK_B] = app->truck[ODO_TRUCK_B].pose;
    odo_can_frame_t *f = out->frames;
    publish_truck(&out->pose[ODO_TRUCK_A], ODO_TRUCK_A, app->out_seq, flags[ODO_TRUCK_A], &faults, f);
    f += 2;
    if (app->trucks == 2U) {
        publish_truck(&out->pose[ODO_TRUCK_B], ODO_TRUCK_B, app->out_seq, flags[ODO_TRUCK_B], &faults, f);
        const odo_msg_ipec_corr_t corr = {out->ipec_dtheta_bam[ODO_TRUCK_A], out->ipec_dtheta_bam[ODO_TRUCK_B]};
        odo_can_pack_ipec_corr(&corr, &f[2]);
        f += 3;
    }
    publish_status(app, faults, f++);
    out->n_frames = (uint8_t)(f - out->frames);
    out->faults = faults;
    if (faults != 0U) {
        count_faults(&app->faults, faults);
    }
    app->out_seq++;
    app->ticks++;
}
