/// libFuzzer harness: the tick assembler (tools/replay/replay.h) and the firmware's 40 ms step
/// behind it, on a clapper (two trucks, rotary and linear link encoders) so the IPEC link check
/// runs on every tick. Input: byte 0 = IPEC mode (off / paper / estimator) and counter width,
/// then 12-byte records: dt_us (2 bytes LE), a selector (bits 0-2 frame ID, 3 RTR, 4 EXT, 5 ERR,
/// 6 dt x 2^8 (up to 16.8 s: gaps stepped through or skipped), 7 step back in time instead), dlc,
/// 8 data bytes. Any sequence: no UB, no crash. A record costs at most REPLAY_MAX_GAP_TICKS + 1
/// steps; most cost none or one.
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "odo/odo_can.h"
#include "odo/odo_params.h"
#include "replay.h"
#include "robot.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerInitialize(int *argc, char ***argv);

static odo_params_t g_params;

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    static sim_robot_t r;
    char err[512];
    if (sim_robot_parse_file(ODO_SOURCE_DIR "/host_sim/robots/clapper.json", &r, err, sizeof err) != 0 ||
        sim_robot_to_params(&r, &g_params, err, sizeof err) != 0) {
        fprintf(stderr, "fuzz_replay_step: %s\n", err);
        abort();
    }
    return 0;
}

static void on_tick(void *user, replay_t *r, uint64_t tick, const odo_tick_input_t *in, const odo_tick_output_t *out)
{
    (void)r;
    (void)tick;
    (void)in;
    *(uint64_t *)user += out->n_frames;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1U) {
        return 0;
    }
    static const uint32_t ids[] = {ODO_CAN_ID_WHEEL_COUNTS_A,
                                   ODO_CAN_ID_WHEEL_COUNTS_B,
                                   ODO_CAN_ID_LINK_ROTARY,
                                   ODO_CAN_ID_LINK_LINEAR,
                                   ODO_CAN_ID_POSE_XY_A,
                                   ODO_CAN_ID_STATUS,
                                   0x7FFU,
                                   ODO_CAN_ID_WHEEL_COUNTS_A};
    static const uint8_t bits[] = {24U, 16U, 32U, 8U};
    odo_params_t p = g_params;
    p.ipec_mode = (uint8_t)((data[0] & 3U) % 3U); /* ODO_IPEC_OFF, _PAPER, _ESTIMATOR */
    p.counter_bits = bits[(data[0] >> 2) & 3U];
    static replay_t r;
    uint64_t frames = 0;
    (void)replay_init(&r, &p, on_tick, &frames);
    uint64_t t_us = 1000000U;
    for (size_t k = 1; k + 12U <= size; k += 12U) {
        const uint8_t *rec = data + k;
        uint64_t dt = (uint64_t)rec[0] | (uint64_t)rec[1] << 8;
        const uint8_t sel = rec[2];
        if (sel & 0x40U) {
            dt <<= 8;
        }
        t_us = (sel & 0x80U) ? (t_us > dt ? t_us - dt : 0U) : t_us + dt;
        odo_can_frame_t f;
        memset(&f, 0, sizeof f);
        f.id = ids[sel & 7U];
        f.flags = (uint8_t)(((sel >> 3) & 1U ? ODO_CAN_FLAG_RTR : 0U) | ((sel >> 4) & 1U ? ODO_CAN_FLAG_EXT : 0U) |
                            ((sel >> 5) & 1U ? ODO_CAN_FLAG_ERR : 0U));
        f.dlc = (uint8_t)(rec[3] % 9U);
        memcpy(f.data, rec + 4, f.dlc);
        replay_push(&r, &f, t_us);
    }
    replay_finish(&r);
    return 0;
}
