/// CAN codec (see odo/odo_can.h, which is the spec, and can/odometry.dbc, which is the contract).
///
/// Every message goes through the same two steps: the payload (at most 8 bytes) is handled as one
/// little-endian uint64, and each signal is a shift and mask of it at the start bit and length
/// given by the layout table below. The table is the only place where bit positions appear; the
/// per-message functions only say which struct field goes to which signal.
#include "odo/odo_can.h"

#define FRAME_FLAGS_NOT_OURS (ODO_CAN_FLAG_EXT | ODO_CAN_FLAG_RTR | ODO_CAN_FLAG_ERR)

/* ---- Layout, in DBC order. Signal tables are shared by the A and B variants of a message. ---- */

enum { WC_LEFT, WC_RIGHT, WC_SEQ, WC_STATUS };
static const odo_can_signal_info_t sig_wheel_counts[] = {
    {"LeftCount", 0U, 24U, false},
    {"RightCount", 24U, 24U, false},
    {"Seq", 48U, 8U, false},
    {"Status", 56U, 8U, false},
};

enum { LR_ALPHA, LR_BETA, LR_SEQ, LR_STATUS };
static const odo_can_signal_info_t sig_link_rotary[] = {
    {"Alpha", 0U, 16U, false},
    {"Beta", 16U, 16U, false},
    {"Seq", 32U, 8U, false},
    {"Status", 40U, 8U, false},
};

enum { LL_LENGTH, LL_SEQ, LL_STATUS };
static const odo_can_signal_info_t sig_link_linear[] = {
    {"Length", 0U, 32U, false},
    {"Seq", 32U, 8U, false},
    {"Status", 40U, 8U, false},
};

enum { PXY_X, PXY_Y };
static const odo_can_signal_info_t sig_pose_xy[] = {
    {"X", 0U, 32U, true},
    {"Y", 32U, 32U, true},
};

enum { PT_THETA, PT_SEQ, PT_FLAGS };
static const odo_can_signal_info_t sig_pose_theta[] = {
    {"Theta", 0U, 32U, false},
    {"Seq", 32U, 8U, false},
    {"Flags", 40U, 8U, false},
};

enum { IC_A, IC_B };
static const odo_can_signal_info_t sig_ipec_corr[] = {
    {"DThetaA", 0U, 32U, true},
    {"DThetaB", 32U, 32U, true},
};

enum { ST_FAULTS, ST_SEQ, ST_PARAM_STATE, ST_REJECTED };
static const odo_can_signal_info_t sig_status[] = {
    {"Faults", 0U, 32U, false},
    {"Seq", 32U, 8U, false},
    {"ParamState", 40U, 8U, false},
    {"Rejected", 48U, 16U, false},
};

#define N_SIGNALS(table) ((uint8_t)(sizeof(table) / sizeof((table)[0])))
#define MSG(name, id, dlc, table)                      \
    {                                                  \
        (name), (id), (dlc), N_SIGNALS(table), (table) \
    }

/* Indexed by odo_can_msg_t; entry 0 (UNKNOWN) is never returned. */
static const odo_can_msg_info_t msg_table[ODO_CAN_MSG_COUNT + 1U] = {
    [ODO_CAN_MSG_UNKNOWN] = {"UNKNOWN", 0U, 0U, 0U, NULL},
    [ODO_CAN_MSG_WHEEL_COUNTS_A] =
        MSG("WHEEL_COUNTS_A", ODO_CAN_ID_WHEEL_COUNTS_A, ODO_CAN_DLC_WHEEL_COUNTS, sig_wheel_counts),
    [ODO_CAN_MSG_WHEEL_COUNTS_B] =
        MSG("WHEEL_COUNTS_B", ODO_CAN_ID_WHEEL_COUNTS_B, ODO_CAN_DLC_WHEEL_COUNTS, sig_wheel_counts),
    [ODO_CAN_MSG_LINK_ROTARY] = MSG("LINK_ROTARY", ODO_CAN_ID_LINK_ROTARY, ODO_CAN_DLC_LINK_ROTARY, sig_link_rotary),
    [ODO_CAN_MSG_LINK_LINEAR] = MSG("LINK_LINEAR", ODO_CAN_ID_LINK_LINEAR, ODO_CAN_DLC_LINK_LINEAR, sig_link_linear),
    [ODO_CAN_MSG_POSE_XY_A] = MSG("POSE_XY_A", ODO_CAN_ID_POSE_XY_A, ODO_CAN_DLC_POSE_XY, sig_pose_xy),
    [ODO_CAN_MSG_POSE_THETA_A] = MSG("POSE_THETA_A", ODO_CAN_ID_POSE_THETA_A, ODO_CAN_DLC_POSE_THETA, sig_pose_theta),
    [ODO_CAN_MSG_POSE_XY_B] = MSG("POSE_XY_B", ODO_CAN_ID_POSE_XY_B, ODO_CAN_DLC_POSE_XY, sig_pose_xy),
    [ODO_CAN_MSG_POSE_THETA_B] = MSG("POSE_THETA_B", ODO_CAN_ID_POSE_THETA_B, ODO_CAN_DLC_POSE_THETA, sig_pose_theta),
    [ODO_CAN_MSG_IPEC_CORR] = MSG("IPEC_CORR", ODO_CAN_ID_IPEC_CORR, ODO_CAN_DLC_IPEC_CORR, sig_ipec_corr),
    [ODO_CAN_MSG_STATUS] = MSG("STATUS", ODO_CAN_ID_STATUS, ODO_CAN_DLC_STATUS, sig_status),
};

/* ---- Generic little-endian signal access on a 64-bit payload. ---- */

static uint64_t sig_mask(const odo_can_signal_info_t *s)
{
    return (UINT64_C(1) << s->bit_len) - 1U; /* bit_len <= 32: the shift is always defined */
}

static void put_u(uint64_t *payload, const odo_can_signal_info_t *s, uint32_t raw)
{
    *payload |= ((uint64_t)raw & sig_mask(s)) << s->start_bit;
}

static void put_s(uint64_t *payload, const odo_can_signal_info_t *s, int32_t value)
{
    put_u(payload, s, (uint32_t)value); /* modulo 2^32: the two's complement bits */
}

static uint32_t get_u(uint64_t payload, const odo_can_signal_info_t *s)
{
    return (uint32_t)((payload >> s->start_bit) & sig_mask(s));
}

static int32_t get_s(uint64_t payload, const odo_can_signal_info_t *s)
{
    uint32_t raw = get_u(payload, s);
    if ((raw & ((uint32_t)1U << (s->bit_len - 1U))) != 0U) {
        raw |= (uint32_t)~sig_mask(s);
        /* ~raw <= INT32_MAX here, so this reaches INT32_MIN without an implementation-defined
           unsigned-to-signed conversion. */
        return -(int32_t)(~raw) - 1;
    }
    return (int32_t)raw;
}

/* ---- Frame level. ---- */

static void frame_store(odo_can_msg_t m, uint64_t payload, odo_can_frame_t *f)
{
    const odo_can_msg_info_t *info = &msg_table[m];
    f->id = info->id;
    f->dlc = info->dlc;
    f->flags = 0U;
    for (uint8_t i = 0U; i < 8U; i++) {
        f->data[i] = (uint8_t)((i < info->dlc) ? (payload >> (8U * i)) : 0U);
    }
}

/* Accept a frame of message a (*which = ODO_TRUCK_A) or b (*which = ODO_TRUCK_B); pass a == b for
   messages that are not per truck.
   Only the DLC bytes are read, so stale bytes beyond it cannot leak into a signal. */
static odo_can_result_t frame_load(const odo_can_frame_t *f, odo_can_msg_t a, odo_can_msg_t b, uint8_t *which,
                                   uint64_t *payload)
{
    if ((f->flags & FRAME_FLAGS_NOT_OURS) != 0U) {
        return ODO_CAN_ERR_FLAGS;
    }
    uint8_t w;
    if (f->id == msg_table[a].id) {
        w = (uint8_t)ODO_TRUCK_A;
    } else if (f->id == msg_table[b].id) {
        w = (uint8_t)ODO_TRUCK_B;
    } else {
        return ODO_CAN_ERR_ID;
    }
    if (f->dlc != msg_table[a].dlc) {
        return ODO_CAN_ERR_DLC;
    }
    uint64_t p = 0U;
    for (uint8_t i = 0U; i < f->dlc; i++) {
        p |= (uint64_t)f->data[i] << (8U * i);
    }
    *which = w;
    *payload = p;
    return ODO_CAN_OK;
}

static bool msg_valid(odo_can_msg_t m) { return ((unsigned)m >= 1U) && ((unsigned)m <= ODO_CAN_MSG_COUNT); }

odo_can_msg_t odo_can_classify(const odo_can_frame_t *f)
{
    if ((f->flags & FRAME_FLAGS_NOT_OURS) != 0U) {
        return ODO_CAN_MSG_UNKNOWN;
    }
    for (unsigned i = 1U; i <= ODO_CAN_MSG_COUNT; i++) {
        if (msg_table[i].id == f->id) {
            return (odo_can_msg_t)i;
        }
    }
    return ODO_CAN_MSG_UNKNOWN;
}

uint8_t odo_can_expected_dlc(odo_can_msg_t m) { return msg_valid(m) ? msg_table[m].dlc : 0U; }

const odo_can_msg_info_t *odo_can_msg_info(odo_can_msg_t m) { return msg_valid(m) ? &msg_table[m] : NULL; }

uint8_t odo_can_seq_delta(uint8_t prev_seq, uint8_t seq) { return (uint8_t)(seq - prev_seq); }

/* ---- Messages: which field goes to which signal, nothing else. ---- */

void odo_can_pack_wheel_counts(uint8_t truck, const odo_msg_wheel_counts_t *m, odo_can_frame_t *f)
{
    uint64_t p = 0U;
    put_u(&p, &sig_wheel_counts[WC_LEFT], m->left_count);
    put_u(&p, &sig_wheel_counts[WC_RIGHT], m->right_count);
    put_u(&p, &sig_wheel_counts[WC_SEQ], m->seq);
    put_u(&p, &sig_wheel_counts[WC_STATUS], m->status);
    frame_store(truck == ODO_TRUCK_A ? ODO_CAN_MSG_WHEEL_COUNTS_A : ODO_CAN_MSG_WHEEL_COUNTS_B, p, f);
}

odo_can_result_t odo_can_unpack_wheel_counts(const odo_can_frame_t *f, uint8_t *truck, odo_msg_wheel_counts_t *m)
{
    uint64_t p;
    uint8_t w;
    odo_can_result_t r = frame_load(f, ODO_CAN_MSG_WHEEL_COUNTS_A, ODO_CAN_MSG_WHEEL_COUNTS_B, &w, &p);
    if (r == ODO_CAN_OK) {
        *truck = w;
        m->left_count = get_u(p, &sig_wheel_counts[WC_LEFT]);
        m->right_count = get_u(p, &sig_wheel_counts[WC_RIGHT]);
        m->seq = (uint8_t)get_u(p, &sig_wheel_counts[WC_SEQ]);
        m->status = (uint8_t)get_u(p, &sig_wheel_counts[WC_STATUS]);
    }
    return r;
}

void odo_can_pack_link_rotary(const odo_msg_link_rotary_t *m, odo_can_frame_t *f)
{
    uint64_t p = 0U;
    put_u(&p, &sig_link_rotary[LR_ALPHA], m->alpha_bam16);
    put_u(&p, &sig_link_rotary[LR_BETA], m->beta_bam16);
    put_u(&p, &sig_link_rotary[LR_SEQ], m->seq);
    put_u(&p, &sig_link_rotary[LR_STATUS], m->status);
    frame_store(ODO_CAN_MSG_LINK_ROTARY, p, f);
}

odo_can_result_t odo_can_unpack_link_rotary(const odo_can_frame_t *f, odo_msg_link_rotary_t *m)
{
    uint64_t p;
    uint8_t w;
    odo_can_result_t r = frame_load(f, ODO_CAN_MSG_LINK_ROTARY, ODO_CAN_MSG_LINK_ROTARY, &w, &p);
    if (r == ODO_CAN_OK) {
        m->alpha_bam16 = (uint16_t)get_u(p, &sig_link_rotary[LR_ALPHA]);
        m->beta_bam16 = (uint16_t)get_u(p, &sig_link_rotary[LR_BETA]);
        m->seq = (uint8_t)get_u(p, &sig_link_rotary[LR_SEQ]);
        m->status = (uint8_t)get_u(p, &sig_link_rotary[LR_STATUS]);
    }
    return r;
}

void odo_can_pack_link_linear(const odo_msg_link_linear_t *m, odo_can_frame_t *f)
{
    uint64_t p = 0U;
    put_u(&p, &sig_link_linear[LL_LENGTH], m->length_um);
    put_u(&p, &sig_link_linear[LL_SEQ], m->seq);
    put_u(&p, &sig_link_linear[LL_STATUS], m->status);
    frame_store(ODO_CAN_MSG_LINK_LINEAR, p, f);
}

odo_can_result_t odo_can_unpack_link_linear(const odo_can_frame_t *f, odo_msg_link_linear_t *m)
{
    uint64_t p;
    uint8_t w;
    odo_can_result_t r = frame_load(f, ODO_CAN_MSG_LINK_LINEAR, ODO_CAN_MSG_LINK_LINEAR, &w, &p);
    if (r == ODO_CAN_OK) {
        m->length_um = get_u(p, &sig_link_linear[LL_LENGTH]);
        m->seq = (uint8_t)get_u(p, &sig_link_linear[LL_SEQ]);
        m->status = (uint8_t)get_u(p, &sig_link_linear[LL_STATUS]);
    }
    return r;
}

void odo_can_pack_pose_xy(uint8_t truck, const odo_msg_pose_xy_t *m, odo_can_frame_t *f)
{
    uint64_t p = 0U;
    put_s(&p, &sig_pose_xy[PXY_X], m->x_10um);
    put_s(&p, &sig_pose_xy[PXY_Y], m->y_10um);
    frame_store(truck == ODO_TRUCK_A ? ODO_CAN_MSG_POSE_XY_A : ODO_CAN_MSG_POSE_XY_B, p, f);
}

odo_can_result_t odo_can_unpack_pose_xy(const odo_can_frame_t *f, uint8_t *truck, odo_msg_pose_xy_t *m)
{
    uint64_t p;
    uint8_t w;
    odo_can_result_t r = frame_load(f, ODO_CAN_MSG_POSE_XY_A, ODO_CAN_MSG_POSE_XY_B, &w, &p);
    if (r == ODO_CAN_OK) {
        *truck = w;
        m->x_10um = get_s(p, &sig_pose_xy[PXY_X]);
        m->y_10um = get_s(p, &sig_pose_xy[PXY_Y]);
    }
    return r;
}

void odo_can_pack_pose_theta(uint8_t truck, const odo_msg_pose_theta_t *m, odo_can_frame_t *f)
{
    uint64_t p = 0U;
    put_u(&p, &sig_pose_theta[PT_THETA], m->theta_bam);
    put_u(&p, &sig_pose_theta[PT_SEQ], m->seq);
    put_u(&p, &sig_pose_theta[PT_FLAGS], m->flags);
    frame_store(truck == ODO_TRUCK_A ? ODO_CAN_MSG_POSE_THETA_A : ODO_CAN_MSG_POSE_THETA_B, p, f);
}

odo_can_result_t odo_can_unpack_pose_theta(const odo_can_frame_t *f, uint8_t *truck, odo_msg_pose_theta_t *m)
{
    uint64_t p;
    uint8_t w;
    odo_can_result_t r = frame_load(f, ODO_CAN_MSG_POSE_THETA_A, ODO_CAN_MSG_POSE_THETA_B, &w, &p);
    if (r == ODO_CAN_OK) {
        *truck = w;
        m->theta_bam = get_u(p, &sig_pose_theta[PT_THETA]);
        m->seq = (uint8_t)get_u(p, &sig_pose_theta[PT_SEQ]);
        m->flags = (uint8_t)get_u(p, &sig_pose_theta[PT_FLAGS]);
    }
    return r;
}

void odo_can_pack_ipec_corr(const odo_msg_ipec_corr_t *m, odo_can_frame_t *f)
{
    uint64_t p = 0U;
    put_s(&p, &sig_ipec_corr[IC_A], m->dtheta_a_bam);
    put_s(&p, &sig_ipec_corr[IC_B], m->dtheta_b_bam);
    frame_store(ODO_CAN_MSG_IPEC_CORR, p, f);
}

odo_can_result_t odo_can_unpack_ipec_corr(const odo_can_frame_t *f, odo_msg_ipec_corr_t *m)
{
    uint64_t p;
    uint8_t w;
    odo_can_result_t r = frame_load(f, ODO_CAN_MSG_IPEC_CORR, ODO_CAN_MSG_IPEC_CORR, &w, &p);
    if (r == ODO_CAN_OK) {
        m->dtheta_a_bam = get_s(p, &sig_ipec_corr[IC_A]);
        m->dtheta_b_bam = get_s(p, &sig_ipec_corr[IC_B]);
    }
    return r;
}

void odo_can_pack_status(const odo_msg_status_t *m, odo_can_frame_t *f)
{
    uint64_t p = 0U;
    put_u(&p, &sig_status[ST_FAULTS], m->faults);
    put_u(&p, &sig_status[ST_SEQ], m->seq);
    put_u(&p, &sig_status[ST_PARAM_STATE], m->param_state);
    put_u(&p, &sig_status[ST_REJECTED], m->rejected);
    frame_store(ODO_CAN_MSG_STATUS, p, f);
}

odo_can_result_t odo_can_unpack_status(const odo_can_frame_t *f, odo_msg_status_t *m)
{
    uint64_t p;
    uint8_t w;
    odo_can_result_t r = frame_load(f, ODO_CAN_MSG_STATUS, ODO_CAN_MSG_STATUS, &w, &p);
    if (r == ODO_CAN_OK) {
        m->faults = get_u(p, &sig_status[ST_FAULTS]);
        m->seq = (uint8_t)get_u(p, &sig_status[ST_SEQ]);
        m->param_state = (uint8_t)get_u(p, &sig_status[ST_PARAM_STATE]);
        m->rejected = (uint16_t)get_u(p, &sig_status[ST_REJECTED]);
    }
    return r;
}
