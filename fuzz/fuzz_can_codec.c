/// libFuzzer harness: the firmware's CAN codec (firmware/include/odo/odo_can.h) on any frame.
/// Classification and every unpacker accept or refuse without UB; what an unpacker accepts packs
/// to a frame that unpacks and packs again to the same bytes (the codec is a fixed point).
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "odo/odo_can.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void same(const odo_can_frame_t *a, const odo_can_frame_t *b)
{
    if (a->id != b->id || a->dlc != b->dlc || a->flags != b->flags || memcmp(a->data, b->data, 8) != 0) {
        abort();
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 4U) {
        return 0;
    }
    odo_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = (uint32_t)data[0] | (uint32_t)data[1] << 8 | (uint32_t)data[2] << 16 | (uint32_t)data[3] << 24;
    /* Mostly the project's IDs, so the unpackers see real traffic. */
    if ((f.id & 0x80000000U) == 0U) {
        static const uint32_t ids[] = {0x110U, 0x111U, 0x120U, 0x121U, 0x180U, 0x181U, 0x182U, 0x183U, 0x190U, 0x1A0U};
        f.id = ids[(f.id >> 8) % (sizeof ids / sizeof ids[0])];
    } else {
        f.id &= 0x1FFFFFFFU;
    }
    f.flags = size > 4U ? (uint8_t)(data[4] & 0x07U) : 0U;
    f.dlc = size > 5U ? (uint8_t)(data[5] % 10U) : 0U; /* 9: out of range on purpose */
    const size_t n = size > 6U ? size - 6U : 0U;
    memcpy(f.data, data + 6, n < 8U ? n : 8U);

    (void)odo_can_classify(&f);
    uint8_t truck = 0;
    odo_can_frame_t g, h;
    odo_msg_wheel_counts_t wc;
    if (odo_can_unpack_wheel_counts(&f, &truck, &wc) == ODO_CAN_OK) {
        odo_can_pack_wheel_counts(truck, &wc, &g);
        if (odo_can_unpack_wheel_counts(&g, &truck, &wc) != ODO_CAN_OK) {
            abort();
        }
        odo_can_pack_wheel_counts(truck, &wc, &h);
        same(&g, &h);
    }
    odo_msg_link_rotary_t lr;
    if (odo_can_unpack_link_rotary(&f, &lr) == ODO_CAN_OK) {
        odo_can_pack_link_rotary(&lr, &g);
        if (odo_can_unpack_link_rotary(&g, &lr) != ODO_CAN_OK) {
            abort();
        }
        odo_can_pack_link_rotary(&lr, &h);
        same(&g, &h);
    }
    odo_msg_link_linear_t ll;
    if (odo_can_unpack_link_linear(&f, &ll) == ODO_CAN_OK) {
        odo_can_pack_link_linear(&ll, &g);
        if (odo_can_unpack_link_linear(&g, &ll) != ODO_CAN_OK) {
            abort();
        }
        odo_can_pack_link_linear(&ll, &h);
        same(&g, &h);
    }
    odo_msg_pose_xy_t xy;
    if (odo_can_unpack_pose_xy(&f, &truck, &xy) == ODO_CAN_OK) {
        odo_can_pack_pose_xy(truck, &xy, &g);
        if (odo_can_unpack_pose_xy(&g, &truck, &xy) != ODO_CAN_OK) {
            abort();
        }
        odo_can_pack_pose_xy(truck, &xy, &h);
        same(&g, &h);
    }
    odo_msg_pose_theta_t th;
    if (odo_can_unpack_pose_theta(&f, &truck, &th) == ODO_CAN_OK) {
        odo_can_pack_pose_theta(truck, &th, &g);
        if (odo_can_unpack_pose_theta(&g, &truck, &th) != ODO_CAN_OK) {
            abort();
        }
        odo_can_pack_pose_theta(truck, &th, &h);
        same(&g, &h);
    }
    odo_msg_ipec_corr_t ic;
    if (odo_can_unpack_ipec_corr(&f, &ic) == ODO_CAN_OK) {
        odo_can_pack_ipec_corr(&ic, &g);
        if (odo_can_unpack_ipec_corr(&g, &ic) != ODO_CAN_OK) {
            abort();
        }
        odo_can_pack_ipec_corr(&ic, &h);
        same(&g, &h);
    }
    odo_msg_status_t st;
    if (odo_can_unpack_status(&f, &st) == ODO_CAN_OK) {
        odo_can_pack_status(&st, &g);
        if (odo_can_unpack_status(&g, &st) != ODO_CAN_OK) {
            abort();
        }
        odo_can_pack_status(&st, &h);
        same(&g, &h);
    }
    (void)odo_can_seq_delta(data[0], data[1]);
    return 0;
}
