/// The board's receive path (odo_board_rx.h).
#include "odo_board_rx.h"

#include <string.h>

#include "odo/odo_can.h"
#include "odo/odo_status.h"

static void inc(uint32_t *c)
{
    if (*c != UINT32_MAX) {
        (*c)++;
    }
}

void odo_board_rx_init(odo_board_rx_t *rx, bool can_wheel_a, bool can_wheel_b)
{
    memset(rx, 0, sizeof *rx);
    rx->can_wheels[ODO_TRUCK_A] = can_wheel_a;
    rx->can_wheels[ODO_TRUCK_B] = can_wheel_b;
}

static bool consumed(const odo_board_rx_t *rx, odo_can_msg_t m)
{
    switch (m) {
    case ODO_CAN_MSG_WHEEL_COUNTS_A: return rx->can_wheels[ODO_TRUCK_A];
    case ODO_CAN_MSG_WHEEL_COUNTS_B: return rx->can_wheels[ODO_TRUCK_B];
    case ODO_CAN_MSG_LINK_ROTARY:
    case ODO_CAN_MSG_LINK_LINEAR: return true;
    case ODO_CAN_MSG_UNKNOWN:
    case ODO_CAN_MSG_POSE_XY_A:
    case ODO_CAN_MSG_POSE_THETA_A:
    case ODO_CAN_MSG_POSE_XY_B:
    case ODO_CAN_MSG_POSE_THETA_B:
    case ODO_CAN_MSG_IPEC_CORR:
    case ODO_CAN_MSG_STATUS:
    default: return false;
    }
}

void odo_board_rx_frame(odo_board_rx_t *rx, const odo_can_frame_t *f, uint8_t raw_dlc)
{
    inc(&rx->count.frames);
    if ((f->flags & ODO_CAN_FLAG_ERR) != 0U) {
        rx->faults |= ODO_FAULT_BUS_ERROR;
        inc(&rx->count.error_frames);
        return;
    }
    const odo_can_msg_t m = odo_can_classify(f); /* UNKNOWN for extended and remote frames too */
    if (!consumed(rx, m)) {
        rx->faults |= ODO_FAULT_CAN_UNKNOWN_ID;
        inc(&rx->count.unknown_id);
        return;
    }
    if (raw_dlc != odo_can_expected_dlc(m)) {
        rx->faults |= ODO_FAULT_CAN_BAD_DLC;
        inc(&rx->count.bad_dlc);
        return;
    }
    if (m == ODO_CAN_MSG_LINK_ROTARY) {
        odo_msg_link_rotary_t r;
        if (odo_can_unpack_link_rotary(f, &r) == ODO_CAN_OK) {
            rx->link.rotary_present = true;
            rx->link.rotary_seq = r.seq;
            rx->link.rotary_status = r.status;
            rx->link.alpha_bam16 = r.alpha_bam16;
            rx->link.beta_bam16 = r.beta_bam16;
        }
    } else if (m == ODO_CAN_MSG_LINK_LINEAR) {
        odo_msg_link_linear_t l;
        if (odo_can_unpack_link_linear(f, &l) == ODO_CAN_OK) {
            rx->link.linear_present = true;
            rx->link.linear_seq = l.seq;
            rx->link.linear_status = l.status;
            rx->link.length_um = l.length_um;
        }
    } else {
        uint8_t truck = 0U;
        odo_msg_wheel_counts_t w;
        if (odo_can_unpack_wheel_counts(f, &truck, &w) == ODO_CAN_OK && truck < ODO_TRUCKS) {
            odo_wheel_input_t *s = &rx->wheel[truck];
            s->present = true;
            s->bits = 24U; /* WHEEL_COUNTS carries 24-bit counters (ODO_CAN_COUNT_MASK) */
            s->seq = w.seq;
            s->status = w.status;
            s->left_raw = w.left_count;
            s->right_raw = w.right_count;
        }
    }
    inc(&rx->count.accepted);
}

void odo_board_rx_bus_off(odo_board_rx_t *rx)
{
    rx->faults |= ODO_FAULT_BUS_ERROR;
    inc(&rx->count.error_frames);
}

void odo_board_rx_overrun(odo_board_rx_t *rx) { inc(&rx->count.overruns); }

void odo_board_rx_take(odo_board_rx_t *rx, odo_wheel_input_t wheel[ODO_TRUCKS], odo_link_input_t *link,
                       uint32_t *faults)
{
    for (uint8_t i = 0U; i < ODO_TRUCKS; ++i) {
        wheel[i] = rx->wheel[i];
    }
    *link = rx->link;
    *faults = rx->faults;
    memset(rx->wheel, 0, sizeof rx->wheel);
    memset(&rx->link, 0, sizeof rx->link);
    rx->faults = 0U;
}
