/// One-line error messages (hostlib/odo_err.h): the prefix form, truncation to the buffer, and no
/// write at all without one.
#include <check.h>

#include <string.h>

#include "check_support.h"
#include "odo_err.h"

START_TEST(plain_message_returns_minus_one)
{
    char e[64] = "old";
    ck_assert_int_eq(-1, odo_errf(e, sizeof e, "%s:%u: field %d is bad", "run.csv", 12U, 3));
    ck_assert_str_eq("run.csv:12: field 3 is bad", e);
}
END_TEST

START_TEST(origin_and_where_prefix)
{
    char e[64];
    ck_assert_int_eq(-1, odo_errf_at(e, sizeof e, "robot.json", "trucks.A.wheelbase_mm", "%g is out of range", 9.5));
    ck_assert_str_eq("robot.json: trucks.A.wheelbase_mm: 9.5 is out of range", e);
    ck_assert_int_eq(-1, odo_errf_at(e, sizeof e, "robot.json", NULL, "not an object"));
    ck_assert_str_eq("robot.json: not an object", e);
}
END_TEST

START_TEST(truncated_to_the_buffer)
{
    char e[8];
    memset(e, 'x', sizeof e);
    ck_assert_int_eq(-1, odo_errf(e, sizeof e, "%s", "0123456789"));
    ck_assert_str_eq("0123456", e);
    /* a prefix longer than the buffer: truncated, terminated, the message never appended */
    memset(e, 'x', sizeof e);
    ck_assert_int_eq(-1, odo_errf_at(e, sizeof e, "a-long-origin", "field", "why"));
    ck_assert_str_eq("a-long-", e);
}
END_TEST

START_TEST(no_buffer_no_write)
{
    char e[4] = "abc";
    ck_assert_int_eq(-1, odo_errf(NULL, 16U, "x"));
    ck_assert_int_eq(-1, odo_errf(e, 0U, "x"));
    ck_assert_int_eq(-1, odo_errf_at(e, 0U, "o", "w", "x"));
    ck_assert_str_eq("abc", e);
}
END_TEST

static Suite *suite(void)
{
    Suite *s = suite_create("odo_err");
    TCase *t = tcase_create("core");
    tcase_add_test(t, plain_message_returns_minus_one);
    tcase_add_test(t, origin_and_where_prefix);
    tcase_add_test(t, truncated_to_the_buffer);
    tcase_add_test(t, no_buffer_no_write);
    suite_add_tcase(s, t);
    return s;
}

int main(void) { return ts_run_suite(suite()); }
