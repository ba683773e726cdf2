/// hal_log behind hal/hal.h (issue 6 item 2): hal_can_recv feeds a candump log's frames in file
/// order with their timestamps, hal_time_us follows them, hal_can_send writes candump lines that
/// read back as the frames sent, and a backend without counters says so (hal_wheel_read false).
#include "check_support.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "hal_log_backend.h"

START_TEST(frames_in_order_with_their_timestamps)
{
    char in[64], outp[64];
    snprintf(in, sizeof in, "/tmp/odo-hal-log-in-%ld.log", (long)getpid());
    snprintf(outp, sizeof outp, "/tmp/odo-hal-log-out-%ld.log", (long)getpid());
    FILE *f = fopen(in, "w");
    ck_assert_ptr_nonnull(f);
    fputs("(10.000000) can0 110#0100000200000300\n(10.040000) can0 1ABCDEF0#\n(10.080000) can0 123#R\n", f);
    ck_assert_int_eq(fclose(f), 0);
    FILE *tx = fopen(outp, "w+");
    ck_assert_ptr_nonnull(tx);
    static hal_ctx_t ctx;
    ck_assert_int_eq(hal_log_backend_open(&ctx, in, tx, "vcan1"), 0);

    odo_wheel_input_t w;
    odo_link_input_t l;
    ck_assert(!hal_wheel_read(&ctx, ODO_TRUCK_A, &w));
    ck_assert(!w.present);
    ck_assert(!hal_link_read(&ctx, &l));

    odo_can_frame_t fr;
    uint64_t t = 0U;
    const uint32_t want_id[3] = {0x110U, 0x1ABCDEF0U, 0x123U};
    const uint8_t want_flags[3] = {0U, ODO_CAN_FLAG_EXT, ODO_CAN_FLAG_RTR};
    for (int i = 0; i < 3; ++i) {
        ck_assert(hal_can_recv(&ctx, &fr, &t));
        ck_assert_uint_eq(fr.id, want_id[i]);
        ck_assert_uint_eq(fr.flags, want_flags[i]);
        ck_assert_uint_eq(t, 10000000U + 40000U * (uint64_t)i);
        ck_assert_uint_eq(hal_time_us(&ctx), t);
        ck_assert(hal_can_send(&ctx, &fr)); /* echo it back out */
    }
    ck_assert(!hal_can_recv(&ctx, &fr, &t));
    ck_assert(ctx.at_eof);
    ck_assert_uint_eq(ctx.tx_frames, 3U);
    hal_log_backend_close(&ctx);

    rewind(tx);
    char line[128];
    const char *want[3] = {"(10.000000) vcan1 110#0100000200000300\n", "(10.040000) vcan1 1ABCDEF0#\n",
                           "(10.080000) vcan1 123#R\n"};
    for (int i = 0; i < 3; ++i) {
        ck_assert_ptr_nonnull(fgets(line, sizeof line, tx));
        ck_assert_str_eq(line, want[i]);
    }
    fclose(tx);
    remove(in);
    remove(outp);
}
END_TEST

START_TEST(a_malformed_line_stops_the_feed_with_its_line_number)
{
    char in[64];
    snprintf(in, sizeof in, "/tmp/odo-hal-log-bad-%ld.log", (long)getpid());
    FILE *f = fopen(in, "w");
    ck_assert_ptr_nonnull(f);
    fputs("(1.000000) can0 110#00\n(1.040000) can0 110#0\n", f);
    ck_assert_int_eq(fclose(f), 0);
    static hal_ctx_t ctx;
    ck_assert_int_eq(hal_log_backend_open(&ctx, in, NULL, NULL), 0);
    odo_can_frame_t fr;
    uint64_t t;
    ck_assert(hal_can_recv(&ctx, &fr, &t));
    ck_assert(!hal_can_send(&ctx, &fr)); /* no transmit stream: refused, counted */
    ck_assert_uint_eq(ctx.tx_refused, 1U);
    ck_assert(!hal_can_recv(&ctx, &fr, &t));
    ck_assert(!ctx.at_eof);
    ck_assert_ptr_nonnull(strstr(ctx.log.err, ":2: data must be hex digit pairs (odd number of digits)"));
    hal_log_backend_close(&ctx);
    remove(in);
}
END_TEST

int main(void)
{
    Suite *su = suite_create("hal_log_backend");
    TCase *tc = tcase_create("hal");
    tcase_add_test(tc, frames_in_order_with_their_timestamps);
    tcase_add_test(tc, a_malformed_line_stops_the_feed_with_its_line_number);
    suite_add_tcase(su, tc);
    return ts_run_suite(su);
}
