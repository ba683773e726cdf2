/// hal_socketcan's bad-input contract (issue 6): opening a missing interface, a bad name or too
/// many filters fails with a message that says why, on any kernel (this one has no AF_CAN at all:
/// then the message says so and names the modules to load), and a failed handle is inert. The
/// working paths (frames, timestamps, interface down/up, error frames) run on a real kernel in
/// vcan.qemu_replay.
#include "check_support.h"
#include <stdlib.h>
#include <string.h>

#include "hal_socketcan.h"

START_TEST(missing_interface_is_a_clear_error)
{
    static hal_socketcan_t s;
    const uint32_t ids[] = {0x110U};
    ck_assert_int_eq(hal_socketcan_open(&s, "odonosuch0", ids, 1U), -1);
    ck_assert_msg(strstr(s.err, "no SocketCAN") != NULL || strstr(s.err, "no interface 'odonosuch0'") != NULL, "%s",
                  s.err);
    if (strstr(s.err, "no SocketCAN") != NULL) {
        ck_assert_ptr_nonnull(strstr(s.err, "can_raw"));
    }
    /* a handle that failed to open is inert: no frame, sends refused and counted */
    odo_can_frame_t f;
    memset(&f, 0, sizeof f);
    uint64_t t = 0U;
    ck_assert_int_eq(hal_socketcan_recv(&s, &f, &t), HAL_SC_DOWN);
    ck_assert(!hal_socketcan_send(&s, &f));
    ck_assert_uint_eq(s.stats.tx_dropped, 1U);
    ck_assert_int_eq(hal_socketcan_wait(&s, 0), 0);
    hal_socketcan_close(&s);
}
END_TEST

START_TEST(bad_names_and_too_many_filters)
{
    static hal_socketcan_t s;
    uint32_t ids[HAL_SC_MAX_FILTERS + 1U] = {0};
    ck_assert_int_eq(hal_socketcan_open(&s, "", ids, 1U), -1);
    ck_assert_ptr_nonnull(strstr(s.err, "1 to 15 characters"));
    ck_assert_int_eq(hal_socketcan_open(&s, "a_name_that_is_too_long", ids, 1U), -1);
    ck_assert_ptr_nonnull(strstr(s.err, "1 to 15 characters"));
    ck_assert_int_eq(hal_socketcan_open(&s, "vcan0", ids, HAL_SC_MAX_FILTERS + 1U), -1);
    ck_assert_ptr_nonnull(strstr(s.err, "filter"));
}
END_TEST

int main(void)
{
    Suite *su = suite_create("socketcan_errors");
    TCase *tc = tcase_create("open");
    tcase_add_test(tc, missing_interface_is_a_clear_error);
    tcase_add_test(tc, bad_names_and_too_many_filters);
    suite_add_tcase(su, tc);
    return ts_run_suite(su);
}
