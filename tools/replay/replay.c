/// replay: frames -> tick inputs -> odo_app_step (see replay.h).
#include "replay.h"

#include <string.h>

#include "odo/odo_can.h"

#define CAN_ERR_BUSOFF_CLASS 0x40U /* linux/can/error.h CAN_ERR_BUSOFF */

odo_params_status_t replay_init(replay_t *r, const odo_params_t *p, replay_tick_fn fn, void *user)
{
    memset(r, 0, sizeof *r);
    uint8_t block[ODO_PARAMS_SIZE];
    const size_t n = odo_params_encode(p, block, sizeof block);
    const odo_params_status_t st = odo_app_init(&r->app, n > 0U ? block : NULL, n);
    r->tick_us = r->app.params.tick_us;
    r->fn = fn;
    r->user = user;
    return st;
}

/// Time of tick k (>= anchor_tick) on the log's clock.
static uint64_t tick_time(const replay_t *r, uint64_t k)
{
    return r->anchor_us + (k - r->anchor_tick) * (uint64_t)r->tick_us;
}

static void step(replay_t *r)
{
    r->in.t_us = tick_time(r, r->cur);
    odo_app_step(&r->app, &r->in, &r->out);
    r->stats.ticks++;
    if (r->fn != NULL) {
        r->fn(r->user, r, r->cur, &r->in, &r->out);
    }
    memset(&r->in, 0, sizeof r->in);
    r->cur++;
    r->pending = false;
}

void replay_close_tick(replay_t *r)
{
    if (r->have_origin && r->pending) {
        step(r);
    }
}

void replay_finish(replay_t *r) { replay_close_tick(r); }

bool replay_deadline_us(const replay_t *r, uint64_t margin_us, uint64_t *deadline_us)
{
    if (!r->have_origin || !r->pending) {
        return false;
    }
    *deadline_us = tick_time(r, r->cur) + r->tick_us / 2U + margin_us;
    return true;
}

/// The four consumed frames by identifier (what odo_can_classify would say, without its table
/// walk: this runs for every frame of a replay); ODO_CAN_MSG_UNKNOWN for anything else.
static odo_can_msg_t sensor_msg(const odo_can_frame_t *f)
{
    if (f->flags != 0U) {
        return ODO_CAN_MSG_UNKNOWN;
    }
    switch (f->id) {
    case ODO_CAN_ID_WHEEL_COUNTS_A: return ODO_CAN_MSG_WHEEL_COUNTS_A;
    case ODO_CAN_ID_WHEEL_COUNTS_B: return ODO_CAN_MSG_WHEEL_COUNTS_B;
    case ODO_CAN_ID_LINK_ROTARY: return ODO_CAN_MSG_LINK_ROTARY;
    case ODO_CAN_ID_LINK_LINEAR: return ODO_CAN_MSG_LINK_LINEAR;
    default: return ODO_CAN_MSG_UNKNOWN;
    }
}

/// Sequence number of a sensor frame of the right length: byte 6 of WHEEL_COUNTS, byte 4 of the
/// linkage frames (can/odometry.dbc). False for anything else.
static bool sensor_seq(const odo_can_frame_t *f, odo_can_msg_t m, uint8_t *seq)
{
    if (m == ODO_CAN_MSG_UNKNOWN || f->dlc != odo_can_expected_dlc(m)) {
        return false;
    }
    *seq = f->data[(m == ODO_CAN_MSG_WHEEL_COUNTS_A || m == ODO_CAN_MSG_WHEEL_COUNTS_B) ? 6U : 4U];
    return true;
}

/// `seq` is a newer sample than `held` (1..127 ahead, modulo 256).
static bool newer(uint8_t held, uint8_t seq)
{
    const uint8_t d = odo_can_seq_delta(held, seq);
    return d >= 1U && d < 128U;
}

static void take(replay_t *r, const odo_can_frame_t *f)
{
    odo_tick_input_t *in = &r->in;
    if ((f->flags & ODO_CAN_FLAG_ERR) != 0U) {
        in->rx_faults |= ODO_FAULT_BUS_ERROR;
        r->stats.error_frames++;
        r->stats.bus_off += (f->id & CAN_ERR_BUSOFF_CLASS) != 0U;
        return;
    }
    const odo_can_msg_t m = sensor_msg(f);
    if (m == ODO_CAN_MSG_UNKNOWN) {
        r->stats.ignored++;
        return;
    }
    if (f->dlc != odo_can_expected_dlc(m)) {
        in->rx_faults |= ODO_FAULT_CAN_BAD_DLC;
        r->stats.bad_dlc++;
        return;
    }
    bool stale = false;
    if (m == ODO_CAN_MSG_LINK_ROTARY) {
        odo_msg_link_rotary_t lr = {0};
        (void)odo_can_unpack_link_rotary(f, &lr);
        stale = in->link.rotary_present && !newer(in->link.rotary_seq, lr.seq);
        if (!stale) {
            in->link.rotary_present = true;
            in->link.rotary_seq = lr.seq;
            in->link.rotary_status = lr.status;
            in->link.alpha_bam16 = lr.alpha_bam16;
            in->link.beta_bam16 = lr.beta_bam16;
        }
    } else if (m == ODO_CAN_MSG_LINK_LINEAR) {
        odo_msg_link_linear_t ll = {0};
        (void)odo_can_unpack_link_linear(f, &ll);
        stale = in->link.linear_present && !newer(in->link.linear_seq, ll.seq);
        if (!stale) {
            in->link.linear_present = true;
            in->link.linear_seq = ll.seq;
            in->link.linear_status = ll.status;
            in->link.length_um = ll.length_um;
        }
    } else {
        uint8_t truck = 0U;
        odo_msg_wheel_counts_t wc = {0};
        (void)odo_can_unpack_wheel_counts(f, &truck, &wc);
        odo_wheel_input_t *w = &in->wheel[truck];
        stale = w->present && !newer(w->seq, wc.seq);
        if (!stale) {
            w->present = true;
            w->bits = REPLAY_WIRE_COUNTER_BITS;
            w->seq = wc.seq;
            w->status = wc.status;
            w->left_raw = wc.left_count;
            w->right_raw = wc.right_count;
        }
    }
    if (stale) {
        in->rx_faults |= ODO_FAULT_SEQ_DUP;
        r->stats.dup_dropped++;
    } else {
        r->stats.sensor_frames++;
        uint8_t seq = 0U;
        (void)sensor_seq(f, m, &seq);
        const unsigned i = (unsigned)m - (unsigned)ODO_CAN_MSG_WHEEL_COUNTS_A;
        r->seq_known[i] = true;
        r->seq_last[i] = seq;
        r->seq_tick[i] = r->cur;
    }
}

/// Move the tick clock's anchor to (t_us, tick k >= cur). The open tick is closed first unless k
/// is the open tick itself, and the empty ticks before k are stepped (at most 127).
static void reanchor(replay_t *r, uint64_t t_us, uint64_t k)
{
    while (r->cur < k) {
        step(r);
    }
    r->anchor_us = t_us;
    r->anchor_tick = r->cur;
    r->last_t_us = t_us;
}

/// The tick a frame opens after the clock stepped back: its sensor's previous sample's tick plus
/// the sequence step (1..127) if that is not in the past; otherwise the tick after the open one.
static uint64_t tick_by_seq(const replay_t *r, const odo_can_frame_t *f)
{
    const uint64_t next = r->pending ? r->cur + 1U : r->cur;
    const odo_can_msg_t m = sensor_msg(f);
    uint8_t seq = 0U;
    if (!sensor_seq(f, m, &seq)) {
        return next;
    }
    const unsigned i = (unsigned)m - (unsigned)ODO_CAN_MSG_WHEEL_COUNTS_A;
    const uint8_t d = odo_can_seq_delta(r->seq_last[i], seq);
    if (!r->seq_known[i] || d == 0U || d >= 128U) {
        return next;
    }
    const uint64_t k = r->seq_tick[i] + d;
    return k >= r->cur ? k : next;
}

static uint64_t sat_add(uint64_t a, uint64_t b) { return a > UINT64_MAX - b ? UINT64_MAX : a + b; }

void replay_push(replay_t *r, const odo_can_frame_t *f, uint64_t t_us)
{
    r->stats.frames++;
    if (!r->have_origin) {
        r->have_origin = true;
        r->origin_us = t_us;
        r->anchor_us = t_us;
        r->anchor_tick = 0U;
        r->cur = 0U;
    }
    const uint64_t tick = r->tick_us;
    const uint64_t half = tick / 2U;
    if (r->have_last && t_us < r->last_t_us) {
        r->stats.time_backwards++;
        if (r->last_t_us - t_us > REPLAY_CLOCK_STEP_TICKS * tick) {
            r->stats.clock_steps++;
            /* the clock stepped back: new ticks, not folded into the open one */
            reanchor(r, t_us, tick_by_seq(r, f));
        }
        r->in.rx_faults |= ODO_FAULT_TIME_BACKWARDS; /* reordered frames join the open tick */
    } else {
        /* Tick of t relative to the anchor (t >= last frame >= anchor). Most frames fall in the
         * open tick: test its window first and divide only for a frame beyond it (a 64-bit
         * division per frame is ~10 % of a replay). Differences only: any t_us is safe. */
        const uint64_t d = t_us - r->anchor_us;
        const uint64_t open = r->cur - r->anchor_tick;
        uint64_t k = r->cur;
        if (d >= open * tick + (tick - half)) { /* beyond the open tick's window */
            const uint64_t q = d / tick;
            k = r->anchor_tick + q + ((d - q * tick) >= tick - half ? 1U : 0U);
        } else if (open > 0U && d + half < open * tick) {
            r->stats.late++; /* a tick already closed (live): joins the open one */
        }
        if (k - r->cur > REPLAY_MAX_GAP_TICKS) {
            const uint64_t gap = t_us - (r->have_last ? r->last_t_us : t_us);
            r->stats.gaps++;
            r->stats.gap_us = sat_add(r->stats.gap_us, gap);
            r->stats.longest_gap_us = gap > r->stats.longest_gap_us ? gap : r->stats.longest_gap_us;
            r->stats.last_gap_us = gap;
            reanchor(r, t_us, r->pending ? r->cur + 1U : r->cur); /* skipped, never ground through */
            k = r->cur;
        }
        r->last_t_us = t_us;
        r->have_last = true;
        while (r->cur < k) {
            step(r); /* ticks without frames step too: the firmware flags what is missing */
        }
    }
    take(r, f);
    r->pending = true;
}
