/// Where an installed or build-tree CLI finds its shipped files (tools/lib/data_dir.h), and a
/// recorded log's start time (tools/lib/candump.h: --log-start, SOURCE_DATE_EPOCH). The installed
/// layout itself (PREFIX/bin -> PREFIX/share/odometry) is exercised by tests/package.
#include <check.h>

#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "candump.h"
#include "check_support.h"
#include "data_dir.h"

static int is_file(const char *p)
{
    struct stat st;
    return stat(p, &st) == 0 && S_ISREG(st.st_mode);
}

START_TEST(source_dir_variable_wins)
{
    char out[256];
    setenv("ODO_SOURCE_DIR", "/opt/odo", 1);
    ck_assert_int_eq(0, odo_data_path("host_sim/robots/labmate.json", out, sizeof out));
    ck_assert_str_eq("/opt/odo/host_sim/robots/labmate.json", out);
    unsetenv("ODO_SOURCE_DIR");
}
END_TEST

START_TEST(a_build_tree_binary_finds_its_checkout)
{
    /* this test runs from build/<preset>/tests, at the depth of build/<preset>/bin */
    unsetenv("ODO_SOURCE_DIR");
    char out[4096];
    ck_assert_int_eq(0, odo_data_path("can/odometry.dbc", out, sizeof out));
    ck_assert_msg(is_file(out), "%s", out);
    ck_assert_int_eq(0, odo_data_path("host_sim/robots/labmate.json", out, sizeof out));
    ck_assert_msg(is_file(out), "%s", out);
}
END_TEST

START_TEST(too_small_a_buffer_gives_an_empty_path)
{
    setenv("ODO_SOURCE_DIR", "/opt/odo", 1);
    char out[16] = "x";
    ck_assert_int_eq(-1, odo_data_path("host_sim/robots/labmate.json", out, sizeof out));
    ck_assert_str_eq("", out);
    ck_assert_int_eq(-1, odo_data_path("a", out, 0U));
    unsetenv("ODO_SOURCE_DIR");
}
END_TEST

START_TEST(log_start_whole_seconds_and_now)
{
    uint64_t s = 7U;
    ck_assert_int_eq(0, odo_log_start_parse("0", &s));
    ck_assert_uint_eq(0U, s);
    ck_assert_int_eq(0, odo_log_start_parse("1700000000", &s));
    ck_assert_uint_eq(1700000000ULL * 1000000ULL, s);
    ck_assert_int_eq(0, odo_log_start_parse("8589934592", &s)); /* ODO_LOG_START_MAX_S */
    ck_assert_uint_eq(ODO_LOG_START_MAX_S * 1000000ULL, s);
    /* the clock "now" reads: time() may lag it by a coarse tick across a second boundary */
    struct timespec t0, t1;
    clock_gettime(CLOCK_REALTIME, &t0);
    ck_assert_int_eq(0, odo_log_start_parse("now", &s));
    clock_gettime(CLOCK_REALTIME, &t1);
    const time_t before = t0.tv_sec, after = t1.tv_sec;
    ck_assert_uint_eq(0U, s % 1000000U); /* a whole second */
    ck_assert(s / 1000000U >= (uint64_t)before && s / 1000000U <= (uint64_t)after);
}
END_TEST

static const char *const BAD_START[] = {
    "", "-1", "+1", " 1", "1.5", "1e9", "abc", "NOW", "8589934593", "99999999999999999999999", "12 "};

START_TEST(log_start_rejects_anything_else)
{
    uint64_t s = 42U;
    ck_assert_int_eq(-1, odo_log_start_parse(BAD_START[_i], &s));
    ck_assert_uint_eq(42U, s);
    ck_assert_int_eq(-1, odo_log_start_parse(NULL, &s));
}
END_TEST

START_TEST(source_date_epoch_is_the_reproducible_default)
{
    uint64_t s = 0U;
    setenv("SOURCE_DATE_EPOCH", "123", 1);
    ck_assert_int_eq(0, odo_log_start_default(&s));
    ck_assert_uint_eq(123000000U, s);
    setenv("SOURCE_DATE_EPOCH", "yesterday", 1);
    ck_assert_int_eq(-1, odo_log_start_default(&s));
    unsetenv("SOURCE_DATE_EPOCH");
    ck_assert_int_eq(0, odo_log_start_default(&s));
    ck_assert(s / 1000000U + 5U >= (uint64_t)time(NULL)); /* the wall clock */
}
END_TEST

static Suite *suite(void)
{
    Suite *s = suite_create("data_dir");
    TCase *tc = tcase_create("data_dir");
    tcase_add_test(tc, source_dir_variable_wins);
    tcase_add_test(tc, a_build_tree_binary_finds_its_checkout);
    tcase_add_test(tc, too_small_a_buffer_gives_an_empty_path);
    tcase_add_test(tc, log_start_whole_seconds_and_now);
    tcase_add_loop_test(tc, log_start_rejects_anything_else, 0, (int)(sizeof BAD_START / sizeof BAD_START[0]));
    tcase_add_test(tc, source_date_epoch_is_the_reproducible_default);
    suite_add_tcase(s, tc);
    return s;
}

int main(void) { return ts_run_suite(suite()); }
