/// Packing of tick inputs and outputs (bench_codec.h).
#include "bench_codec.h"

#include <string.h>

static uint8_t *put(uint8_t *p, uint64_t v, unsigned n)
{
    for (unsigned i = 0U; i < n; ++i) {
        p[i] = (uint8_t)(v >> (8U * i));
    }
    return p + n;
}

static uint64_t get(const uint8_t **pp, unsigned n)
{
    uint64_t v = 0U;
    for (unsigned i = 0U; i < n; ++i) {
        v |= (uint64_t)(*pp)[i] << (8U * i);
    }
    *pp += n;
    return v;
}

void odo_bench_pack_input(const odo_tick_input_t *in, uint8_t buf[ODO_BENCH_IN_SIZE])
{
    uint8_t *p = put(buf, in->t_us, 8U);
    p = put(p, in->rx_faults, 4U);
    for (unsigned t = 0U; t < ODO_TRUCKS; ++t) {
        const odo_wheel_input_t *w = &in->wheel[t];
        p = put(p, w->present ? 1U : 0U, 1U);
        p = put(p, w->bits, 1U);
        p = put(p, w->seq, 1U);
        p = put(p, w->status, 1U);
        p = put(p, w->left_raw, 4U);
        p = put(p, w->right_raw, 4U);
    }
    const odo_link_input_t *l = &in->link;
    p = put(p, l->rotary_present ? 1U : 0U, 1U);
    p = put(p, l->rotary_seq, 1U);
    p = put(p, l->rotary_status, 1U);
    p = put(p, l->linear_present ? 1U : 0U, 1U);
    p = put(p, l->alpha_bam16, 2U);
    p = put(p, l->beta_bam16, 2U);
    p = put(p, l->linear_seq, 1U);
    p = put(p, l->linear_status, 1U);
    p = put(p, 0U, 2U);
    (void)put(p, l->length_um, 4U);
}

void odo_bench_unpack_input(const uint8_t buf[ODO_BENCH_IN_SIZE], odo_tick_input_t *in)
{
    const uint8_t *p = buf;
    memset(in, 0, sizeof *in);
    in->t_us = get(&p, 8U);
    in->rx_faults = (uint32_t)get(&p, 4U);
    for (unsigned t = 0U; t < ODO_TRUCKS; ++t) {
        odo_wheel_input_t *w = &in->wheel[t];
        w->present = get(&p, 1U) != 0U;
        w->bits = (uint8_t)get(&p, 1U);
        w->seq = (uint8_t)get(&p, 1U);
        w->status = (uint8_t)get(&p, 1U);
        w->left_raw = (uint32_t)get(&p, 4U);
        w->right_raw = (uint32_t)get(&p, 4U);
    }
    odo_link_input_t *l = &in->link;
    l->rotary_present = get(&p, 1U) != 0U;
    l->rotary_seq = (uint8_t)get(&p, 1U);
    l->rotary_status = (uint8_t)get(&p, 1U);
    l->linear_present = get(&p, 1U) != 0U;
    l->alpha_bam16 = (uint16_t)get(&p, 2U);
    l->beta_bam16 = (uint16_t)get(&p, 2U);
    l->linear_seq = (uint8_t)get(&p, 1U);
    l->linear_status = (uint8_t)get(&p, 1U);
    (void)get(&p, 2U);
    l->length_um = (uint32_t)get(&p, 4U);
}

void odo_bench_pack_output(const odo_tick_output_t *out, uint8_t buf[ODO_BENCH_OUT_SIZE])
{
    memset(buf, 0, ODO_BENCH_OUT_SIZE);
    uint8_t *p = buf;
    for (unsigned t = 0U; t < ODO_TRUCKS; ++t) {
        p = put(p, (uint64_t)out->pose[t].x_mm_q32, 8U);
        p = put(p, (uint64_t)out->pose[t].y_mm_q32, 8U);
        p = put(p, out->pose[t].heading_q64, 8U);
    }
    for (unsigned t = 0U; t < ODO_TRUCKS; ++t) {
        p = put(p, (uint32_t)out->ipec_dtheta_bam[t], 4U);
        p = put(p, (uint32_t)out->ipec_innov_bam[t], 4U);
    }
    p = put(p, out->ipec_applied ? 1U : 0U, 1U);
    for (unsigned t = 0U; t < ODO_TRUCKS; ++t) {
        p = put(p, (uint64_t)out->dist_mm_q40[t], 8U);
        p = put(p, (uint64_t)out->dturn_q64[t], 8U);
    }
    p = put(p, out->faults, 4U);
    const unsigned n = out->n_frames <= ODO_APP_MAX_FRAMES ? out->n_frames : ODO_APP_MAX_FRAMES;
    p = put(p, out->n_frames, 1U);
    for (unsigned k = 0U; k < n; ++k) {
        const odo_can_frame_t *f = &out->frames[k];
        p = put(p, f->id, 4U);
        p = put(p, f->dlc, 1U);
        p = put(p, f->flags, 1U);
        memcpy(p, f->data, 8U);
        p += 8;
    }
}
