/// The sim HAL backend: counters come from the HCTL-1100 emulators only through the data sheet's
/// read protocol ("Actual Position Registers R12H-R14H", R14H first), linkage encoders are quantised
/// like 10-bit absolute encoders and a 0.1 mm linear scale (004 section 2), sent frames are
/// captured, and identical runs read identically (issue 3 item 7).
#include <check.h>

#include <math.h>
#include <string.h>

#include "check_support.h"
#include "hal_sim.h"
#include "odo_loop.h"
#include "test_support.h"

static hal_ctx_t hal;

static hal_sim_config_t config(void)
{
    hal_sim_config_t c;
    memset(&c, 0, sizeof c);
    c.f_clk_hz = 1000000U;
    c.convention = ODOSIM_HCTL_CONV_1100;
    c.rotary_bits = 10U;
    c.linear_resolution_um = 100U;
    return c;
}

static void boot(uint8_t trucks, bool has_link)
{
    const hal_sim_config_t c = config();
    ck_assert(hal_sim_init(&hal, trucks, has_link, &c));
}

static double deg(double d) { return d * M_PI / 180.0; }

START_TEST(wheel_read_returns_the_decoder_positions_in_24_bits)
{
    /* HCTL-1100 "Actual Position Registers R12H-R14H": 24-bit counts, read R14H, R13H, R12H. */
    boot(2U, false);
    ck_assert(hal_sim_set_wheel_phase(&hal, ODO_TRUCK_A, ODO_LEFT, 0.5, 1000.5));
    ck_assert(hal_sim_set_wheel_phase(&hal, ODO_TRUCK_A, ODO_RIGHT, 0.5, -20.5));
    ck_assert(hal_sim_set_wheel_phase(&hal, ODO_TRUCK_B, ODO_LEFT, 0.5, 70000.5));
    ck_assert(hal_sim_set_wheel_phase(&hal, ODO_TRUCK_B, ODO_RIGHT, 0.5, 3.5));
    odo_wheel_input_t a, b;
    ck_assert(hal_wheel_read(&hal, ODO_TRUCK_A, &a));
    ck_assert(hal_wheel_read(&hal, ODO_TRUCK_B, &b));
    ck_assert(a.present && b.present);
    ck_assert_uint_eq(24U, a.bits);
    ck_assert_uint_eq(1000U, a.left_raw);
    ck_assert_uint_eq(ts_wrap_counter(-21, 24U), a.right_raw);
    ck_assert_uint_eq(70000U, b.left_raw);
    ck_assert_uint_eq(3U, b.right_raw);
    ck_assert_uint_eq(0U, a.status | b.status);

    /* The read goes through the latch: a stale latch left by someone reading R14H earlier does
     * not leak into the result, because hal_wheel_read reads R14H (re-latching) first. */
    odosim_hctl_t *l = hal_sim_decoder(&hal, ODO_TRUCK_A, ODO_LEFT);
    (void)odosim_hctl_read(l, ODOSIM_HCTL_REG_ACT_POS_LSB); /* latches 0x0003E8 */
    ck_assert(hal_sim_set_wheel_phase(&hal, ODO_TRUCK_A, ODO_LEFT, 1.5, 70000.5));
    ck_assert(hal_wheel_read(&hal, ODO_TRUCK_A, &a));
    ck_assert_uint_eq(70000U, a.left_raw);
    ck_assert(!l->latched); /* the R12H read released it */

    ck_assert(!hal_wheel_read(&hal, 2U, &a));
    boot(1U, false);
    ck_assert(!hal_wheel_read(&hal, ODO_TRUCK_B, &a));
    ck_assert(!hal_sim_set_wheel_phase(&hal, ODO_TRUCK_B, ODO_LEFT, 1.0, 1.0));
    ck_assert(!hal_sim_set_wheel_phase(&hal, ODO_TRUCK_A, 2U, 1.0, 1.0));
    ck_assert(!hal_sim_set_wheel_phase(&hal, ODO_TRUCK_A, ODO_LEFT, NAN, 1.0));
    ck_assert_uint_eq(3U, hal.faults.bad_wheel_inputs);
}
END_TEST

START_TEST(seq_counts_reads_and_wraps_at_256)
{
    /* A direct reader makes one sample per read; the firmware checks the sequence (odo_app). */
    boot(1U, false);
    odo_wheel_input_t w;
    for (unsigned i = 0U; i < 300U; ++i) {
        ck_assert(hal_wheel_read(&hal, ODO_TRUCK_A, &w));
        ck_assert_uint_eq(i & 0xFFU, w.seq);
    }
}
END_TEST

START_TEST(skipped_states_raise_the_status_bit_once)
{
    /* HCTL-1100 "Quadrature Decoder": a two-state jump is illegal; reported as decoder status. */
    boot(1U, false);
    odo_wheel_input_t w;
    ck_assert(hal_sim_set_wheel_phase(&hal, ODO_TRUCK_A, ODO_LEFT, 0.0, 2.5)); /* jump: 2 states */
    ck_assert(hal_sim_set_wheel_phase(&hal, ODO_TRUCK_A, ODO_LEFT, 0.01, 2.5));
    ck_assert(hal_wheel_read(&hal, ODO_TRUCK_A, &w));
    ck_assert_uint_eq(ODO_WHEEL_STATUS_LEFT_SKIPPED, w.status);
    ck_assert_uint_eq(0U, w.left_raw); /* not counted */
    ck_assert(hal_wheel_read(&hal, ODO_TRUCK_A, &w));
    ck_assert_uint_eq(0U, w.status);
    /* Above f_CLK/3 on the right wheel: lost counts and skipped states. */
    for (int i = 1; i <= 10; ++i) {
        ck_assert(hal_sim_set_wheel_phase(&hal, ODO_TRUCK_A, ODO_RIGHT, 0.01 + i * 1e-3,
                                          0.3 + 400.0 * i)); /* 400 kstates/s at 1 MHz */
    }
    ck_assert(hal_wheel_read(&hal, ODO_TRUCK_A, &w));
    ck_assert_uint_eq(ODO_WHEEL_STATUS_RIGHT_SKIPPED, w.status);
    ck_assert_uint_lt(w.right_raw, 4000U);
}
END_TEST

START_TEST(linkage_encoders_are_quantised_to_10_bits_and_0_1_mm)
{
    /* 004 section 2: two 10-bit absolute rotary encoders (0.35 deg steps), 0.1 mm linear. */
    boot(2U, true);
    const uint8_t all = ODO_LINK_STATUS_ALPHA_VALID | ODO_LINK_STATUS_BETA_VALID | ODO_LINK_STATUS_LENGTH_VALID;
    odo_link_input_t l;
    ck_assert(hal_sim_set_link(&hal, deg(0.35), deg(0.36), 1000.09, all));
    ck_assert(hal_link_read(&hal, &l));
    ck_assert(l.rotary_present && l.linear_present);
    ck_assert_uint_eq(0U, l.alpha_bam16); /* below one step of 360/1024 = 0.3516 deg */
    ck_assert_uint_eq(64U, l.beta_bam16); /* one step: code 1 << 6 */
    ck_assert_uint_eq(1000000U, l.length_um);
    ck_assert_uint_eq(all, l.rotary_status | l.linear_status);
    ck_assert_uint_eq(1U, l.rotary_seq);
    ck_assert(hal_link_read(&hal, &l));
    ck_assert(!l.rotary_present && !l.linear_present); /* delivered once */

    ck_assert(hal_sim_set_link(&hal, deg(-0.1), deg(180.0), 999.99, all));
    ck_assert(hal_link_read(&hal, &l));
    ck_assert_uint_eq(0xFFC0U, l.alpha_bam16); /* code 1023 */
    ck_assert_uint_eq(0x8000U, l.beta_bam16);
    ck_assert_uint_eq(999900U, l.length_um);
    ck_assert_uint_eq(2U, l.rotary_seq);

    /* Over the whole circle: a 10-bit code, never more than one step below the true angle. */
    ts_rng_t r;
    ts_rng_seed(&r, 10U);
    for (int i = 0; i < 100000; ++i) {
        const double a = ts_rng_uniform(&r, -4.0 * M_PI, 4.0 * M_PI);
        uint16_t q;
        ck_assert(hal_sim_quantise_angle(a, 10U, &q));
        ck_assert_uint_eq(0U, q & 0x3FU);
        double turns = a / (2.0 * M_PI) - floor(a / (2.0 * M_PI));
        double under = turns - q / 65536.0;
        under -= floor(under + 0.5) == 1.0 ? 1.0 : 0.0; /* just below a full turn reads 0 */
        ck_assert(under >= -1e-12 && under < 1.0 / 1024.0 + 1e-12);
    }

    /* Bad readings are reported invalid, not asserted on. */
    ck_assert(hal_sim_set_link(&hal, NAN, deg(10.0), -5.0, all));
    ck_assert(hal_link_read(&hal, &l));
    ck_assert_uint_eq(ODO_LINK_STATUS_BETA_VALID, l.rotary_status);
    ck_assert_uint_eq(0U, l.linear_status);
    ck_assert_uint_eq(2U, hal.faults.bad_link_inputs);
    ck_assert(hal_sim_set_link(&hal, 0.0, 0.0, 1000.0, ODO_LINK_STATUS_ALPHA_VALID));
    ck_assert(hal_link_read(&hal, &l));
    ck_assert_uint_eq(ODO_LINK_STATUS_ALPHA_VALID, l.rotary_status); /* caller's flags kept */

    boot(1U, false);
    ck_assert(!hal_sim_set_link(&hal, 0.0, 0.0, 1000.0, all));
    ck_assert(!hal_link_read(&hal, &l));
}
END_TEST

START_TEST(sent_frames_are_captured_and_overflow_is_counted)
{
    /* HAL contract (hal.h): a full buffer refuses the frame; the caller carries on. */
    boot(1U, false);
    odo_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.dlc = 1U;
    for (uint32_t i = 0U; i < HAL_SIM_MAX_TX + 6U; ++i) {
        hal_sim_set_time_us(&hal, 1000U * i);
        f.id = 0x100U + i;
        ck_assert(hal_can_send(&hal, &f) == (i < HAL_SIM_MAX_TX));
    }
    ck_assert_uint_eq(6U, hal.faults.tx_overflows);
    odo_can_frame_t g;
    uint64_t t;
    for (uint32_t i = 0U; i < HAL_SIM_MAX_TX; ++i) {
        ck_assert(hal_sim_take_tx(&hal, &g, &t));
        ck_assert_uint_eq(0x100U + i, g.id);
        ck_assert_uint_eq(1000U * i, t);
    }
    ck_assert(!hal_sim_take_tx(&hal, &g, &t));
    ck_assert(hal_can_send(&hal, &f)); /* drained: accepted again, across the ring's end */
    ck_assert(hal_sim_take_tx(&hal, &g, &t));
    ck_assert_uint_eq(f.id, g.id);

    hal_sim_set_time_us(&hal, 5U); /* time never runs backwards */
    ck_assert_uint_eq(1000U * (HAL_SIM_MAX_TX + 5U), hal_time_us(&hal));
    ck_assert_uint_eq(1U, hal.faults.bad_times);

    ck_assert(!hal_can_recv(&hal, &g, &t));
    for (uint32_t i = 0U; i < HAL_SIM_MAX_RX; ++i) {
        f.id = 0x200U + i;
        ck_assert(hal_sim_push_rx(&hal, &f, 7U + i));
    }
    ck_assert(!hal_sim_push_rx(&hal, &f, 0U));
    ck_assert_uint_eq(1U, hal.faults.rx_overflows);
    ck_assert(hal_can_recv(&hal, &g, &t));
    ck_assert_uint_eq(0x200U, g.id);
    ck_assert_uint_eq(7U, t);
}
END_TEST

/// A scripted run through the firmware loop with seeded wheel motion (some of it above the
/// decoder's limit); returns every wheel sample and frame in `log`.
typedef struct {
    odo_wheel_input_t wheel[250][2];
    odo_can_frame_t frames[250 * 8];
    uint32_t n_frames;
    odo_pose_t pose;
} run_log_t;

static void scripted_run(run_log_t *log)
{
    static odo_app_t app;
    odo_params_t p;
    odo_params_defaults(&p);
    p.vehicle = ODO_VEHICLE_CLAPPER;
    ck_assert_int_eq(ODO_PARAMS_OK, odo_app_init_params(&app, &p));
    boot(2U, true);
    memset(log, 0, sizeof *log);
    ts_rng_t r;
    ts_rng_seed(&r, 42U);
    double phase[2][2] = {{0.0, 0.0}, {0.0, 0.0}};
    for (int tick = 0; tick < 250; ++tick) {
        for (int ms = 1; ms <= 40; ++ms) {
            const double t = (tick * 40 + ms) * 1e-3;
            for (uint8_t tr = 0U; tr < 2U; ++tr) {
                for (uint8_t w = 0U; w < 2U; ++w) {
                    /* 0.2 m/s is 16.6 kcounts/s; now and then a burst above f_CLK/3. */
                    const double rate = tick % 50 == 7 ? 400000.0 : ts_rng_uniform(&r, 0.0, 33000.0);
                    phase[tr][w] += rate * 1e-3;
                    ck_assert(hal_sim_set_wheel_phase(&hal, tr, w, t, phase[tr][w]));
                }
            }
        }
        hal_sim_set_time_us(&hal, (uint64_t)(tick + 1) * 40000U);
        ck_assert(hal_sim_set_link(
            &hal, deg(ts_rng_uniform(&r, -5, 5)), deg(ts_rng_uniform(&r, -5, 5)), ts_rng_uniform(&r, 990, 1010),
            ODO_LINK_STATUS_ALPHA_VALID | ODO_LINK_STATUS_BETA_VALID | ODO_LINK_STATUS_LENGTH_VALID));
        odo_tick_output_t out;
        odo_tick_input_t loop_in;
        odo_loop_tick(&app, &hal, &loop_in, &out);
        for (uint8_t tr = 0U; tr < 2U; ++tr) {
            /* What the firmware was given, re-read the same way (the reads do not disturb). */
            log->wheel[tick][tr].left_raw = odosim_hctl_read_position(&hal.dec[tr][ODO_LEFT]);
            log->wheel[tick][tr].right_raw = odosim_hctl_read_position(&hal.dec[tr][ODO_RIGHT]);
            log->wheel[tick][tr].status = (uint8_t)odosim_hctl_skipped(&hal.dec[tr][ODO_RIGHT]);
        }
        uint64_t t_us;
        while (hal_sim_take_tx(&hal, &log->frames[log->n_frames], &t_us)) {
            log->n_frames++;
        }
        log->pose = out.pose[0];
    }
}

START_TEST(firmware_runs_on_emulated_counters_and_identical_runs_read_identically)
{
    /* Issue 3 item 7: same inputs give byte-identical outputs (no globals, no randomness). */
    static run_log_t a, b;
    scripted_run(&a);
    scripted_run(&b);
    ck_assert_uint_gt(a.n_frames, 250U);
    ck_assert_uint_eq(a.n_frames, b.n_frames);
    ck_assert_mem_eq(&a, &b, sizeof a);
    ck_assert_int_gt(a.pose.x_mm_q32, 0);          /* the truck went forward */
    ck_assert_uint_gt(a.wheel[249][0].status, 0U); /* the bursts left skipped states */
}
END_TEST

int main(void)
{
    Suite *s = suite_create("hal_sim");
    TCase *tc = tcase_create("core");
    tcase_set_timeout(tc, 60);
    tcase_add_test(tc, wheel_read_returns_the_decoder_positions_in_24_bits);
    tcase_add_test(tc, seq_counts_reads_and_wraps_at_256);
    tcase_add_test(tc, skipped_states_raise_the_status_bit_once);
    tcase_add_test(tc, linkage_encoders_are_quantised_to_10_bits_and_0_1_mm);
    tcase_add_test(tc, sent_frames_are_captured_and_overflow_is_counted);
    tcase_add_test(tc, firmware_runs_on_emulated_counters_and_identical_runs_read_identically);
    suite_add_tcase(s, tc);
    return ts_run_suite(s);
}
