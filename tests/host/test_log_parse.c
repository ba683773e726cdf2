/// The candump -l grammar of hal/log (issue 6 item 2): every form can-utils' candump writes is
/// read back exactly (standard and extended IDs, empty data, RTR with and without a DLC, error
/// frames, the optional " R"/" T"), every malformed class is rejected with its reason, and the
/// reader names the file and line. The formatter and the parser round-trip every frame shape.
#include "check_support.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "candump.h"
#include "hal_log.h"
#include "test_support.h"

static candump_result_t parse(const char *s, candump_line_t *l, const char **why)
{
    *why = NULL;
    return candump_parse_line(s, strlen(s), l, why);
}

START_TEST(standard_frame_with_data)
{
    candump_line_t l;
    const char *why;
    ck_assert_int_eq(parse("(1700000000.123456) can0 110#0102030405060708\n", &l, &why), CANDUMP_OK);
    ck_assert_uint_eq(l.t_us, 1700000000123456ULL);
    ck_assert_str_eq(l.iface, "can0");
    ck_assert_uint_eq(l.frame.id, 0x110U);
    ck_assert_uint_eq(l.frame.flags, 0U);
    ck_assert_uint_eq(l.frame.dlc, 8U);
    ck_assert_uint_eq(l.frame.data[0], 1U);
    ck_assert_uint_eq(l.frame.data[7], 8U);
    ck_assert_int_eq(l.direction, 0);
}
END_TEST

START_TEST(extended_empty_rtr_error_and_direction)
{
    candump_line_t l;
    const char *why;
    ck_assert_int_eq(parse("(0.000001) vcan0 1ABCDEF0#aBcD", &l, &why), CANDUMP_OK);
    ck_assert_uint_eq(l.frame.id, 0x1ABCDEF0U);
    ck_assert_uint_eq(l.frame.flags, ODO_CAN_FLAG_EXT);
    ck_assert_uint_eq(l.frame.dlc, 2U);
    ck_assert_uint_eq(l.frame.data[0], 0xABU);
    ck_assert_uint_eq(l.t_us, 1U);

    ck_assert_int_eq(parse("(5.5) can1 7FF#", &l, &why), CANDUMP_OK); /* empty data, short fraction */
    ck_assert_uint_eq(l.frame.dlc, 0U);
    ck_assert_uint_eq(l.t_us, 5500000U);

    ck_assert_int_eq(parse("(1.000000) can0 123#R", &l, &why), CANDUMP_OK);
    ck_assert_uint_eq(l.frame.flags, ODO_CAN_FLAG_RTR);
    ck_assert_uint_eq(l.frame.dlc, 0U);
    ck_assert_int_eq(parse("(1.000000) can0 123#R6 T", &l, &why), CANDUMP_OK);
    ck_assert_uint_eq(l.frame.dlc, 6U);
    ck_assert_int_eq(l.direction, 'T');

    ck_assert_int_eq(parse("(1.000000) can0 20000040#0000000000000000 R\r\n", &l, &why), CANDUMP_OK);
    ck_assert_uint_eq(l.frame.flags, ODO_CAN_FLAG_ERR);
    ck_assert_uint_eq(l.frame.id, 0x40U); /* CAN_ERR_BUSOFF */
    ck_assert_int_eq(l.direction, 'R');

    ck_assert_int_eq(parse("(1.000000) can0 121#11.22.33", &l, &why), CANDUMP_OK); /* canplayer's dots */
    ck_assert_uint_eq(l.frame.dlc, 3U);
    ck_assert_uint_eq(l.frame.data[2], 0x33U);

    /* Another node's CAN FD frame on a mixed bus, and python-can's trailing direction. */
    ck_assert_int_eq(parse("(1.000000) can0 123##1112233", &l, &why), CANDUMP_FD);
    ck_assert_int_eq(parse("(2.000000) can1 12345678##0AABB R", &l, &why), CANDUMP_FD);
    ck_assert_int_eq(parse("(1.000000) can0 110#0011 T", &l, &why), CANDUMP_OK);
    ck_assert_int_eq(l.direction, 'T');

    ck_assert_int_eq(parse("   \r\n", &l, &why), CANDUMP_BLANK);
    ck_assert_int_eq(parse("", &l, &why), CANDUMP_BLANK);
}
END_TEST

/// One malformed line and the words its reason must contain.
typedef struct {
    const char *line;
    const char *because;
} bad_t;

static const bad_t BAD[] = {
    {"(1.000000) can0 123##", "flags digit"},
    {"(1.000000) can0 123##1112", "odd number"},
    {"(1.000000) can0 12345678##0aX", "hex digits"},
    {"(1.000000) can0 123##100 X", "after the CAN FD"},
    {"(1.000000) can0 123#00112233445566778899", "more than 8"},
    {"(1.000000) can0 123#0", "odd"},
    {"(1.000000) can0 123#0G", "hex"},
    {"(1.000000) can0 1234#00", "3 (standard) or 8"},
    {"(1.000000) can0 800#00", "above 0x7FF"},
    {"(1.000000) can0 C0000000#00", "bits 30"},
    {"(1.000000) can0 123", "missing '#'"},
    {"1.000000 can0 123#00", "'('"},
    {"(1.000000 can0 123#00", "')'"},
    {"(1,000000) can0 123#00", "seconds.fraction"},
    {"(1.) can0 123#00", "1 to 9 digits"},
    {"(1.0000000000) can0 123#00", "1 to 9 digits"},
    {"(1.000000)  can0 123#00", "interface"},
    {"(1.000000) can0123456789abcdef 123#00", "1 to 15"},
    {"(1.000000) ca\x01n0 123#00", "printable"}, /* fuzz_candump: a control byte in the name */
    {"(1.000000) can\xc3\xa9"
     "0 123#00",
     "printable"},
    {"(1.000000) can0 123#R9", "above 8"},
    {"(1.000000) can0 123#00 X", "unexpected text"},
    {"(1.000000) can0 123#00 R extra", "unexpected text"},
    {"(1.000000) can0 20000040#R", "error frame"},
    {"(1.000000) can0 123#_0000", "CAN XL"},
    {" (1.000000) can0 123#00", "leading whitespace"},
    {"(99999999999999999999.000000) can0 123#00", "out of range"},
};

START_TEST(malformed_lines_are_rejected_with_their_reason)
{
    const bad_t *b = &BAD[_i];
    candump_line_t l;
    const char *why = NULL;
    ck_assert_msg(parse(b->line, &l, &why) == CANDUMP_ERR, "accepted: %s", b->line);
    ck_assert_ptr_nonnull(why);
    ck_assert_msg(strstr(why, b->because) != NULL, "'%s': reason '%s' lacks '%s'", b->line, why, b->because);
}
END_TEST

static void write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    ck_assert_ptr_nonnull(f);
    fputs(text, f);
    ck_assert_int_eq(fclose(f), 0);
}

START_TEST(reader_names_file_and_line)
{
    char path[64];
    snprintf(path, sizeof path, "/tmp/odo-test-log-%ld.log", (long)getpid());
    write_file(path, "(0.000000) can0 110#0000000000000000\n\n(0.040000) can0 111#0000000000000000\n"
                     "(0.080000) can0 120##10011\n(0.120000) can0 121#000000000000\n(0.16) can0 12#00\n");
    static hal_log_t l;
    ck_assert_int_eq(hal_log_open(&l, path), 0);
    candump_line_t line;
    ck_assert_int_eq(hal_log_next(&l, &line), HAL_LOG_FRAME);
    ck_assert_int_eq(hal_log_next(&l, &line), HAL_LOG_FRAME); /* blank line 2 skipped */
    ck_assert_uint_eq(line.frame.id, 0x111U);
    ck_assert_uint_eq(l.line_no, 3U);
    ck_assert_int_eq(hal_log_next(&l, &line), HAL_LOG_FRAME); /* CAN FD line 4 counted and skipped */
    ck_assert_uint_eq(line.frame.id, 0x121U);
    ck_assert_uint_eq(l.stats.fd_skipped, 1U);
    ck_assert_int_eq(hal_log_next(&l, &line), HAL_LOG_ERROR);
    char want[96];
    snprintf(want, sizeof want, "%s:6: identifier", path);
    ck_assert_msg(strstr(l.err, want) != NULL, "error '%s' lacks '%s'", l.err, want);
    ck_assert_uint_eq(l.stats.blank, 1U);
    hal_log_close(&l);
    remove(path);

    ck_assert_int_eq(hal_log_open(&l, "/nonexistent/odo.log"), -1);
    ck_assert_ptr_nonnull(strstr(l.err, "/nonexistent/odo.log: cannot open"));
    hal_log_close(&l);
}
END_TEST

START_TEST(last_line_without_newline_and_long_files)
{
    char path[64];
    snprintf(path, sizeof path, "/tmp/odo-test-log2-%ld.log", (long)getpid());
    /* more than one read chunk of lines, the last without its newline */
    FILE *f = fopen(path, "w");
    ck_assert_ptr_nonnull(f);
    const uint32_t n = 40000U; /* ~1.5 MB: lines cross the 1 MiB chunk boundary */
    for (uint32_t i = 0; i < n; ++i) {
        fprintf(f, "(%u.%06u) can0 %03X#%08X%s", i / 25U, (i % 25U) * 40000U, 0x100U + (i % 0x600U), i,
                i + 1U < n ? "\n" : "");
    }
    ck_assert_int_eq(fclose(f), 0);
    static hal_log_t l;
    ck_assert_int_eq(hal_log_open(&l, path), 0);
    candump_line_t line;
    uint32_t got = 0;
    hal_log_status_t st;
    while ((st = hal_log_next(&l, &line)) == HAL_LOG_FRAME) {
        ck_assert_uint_eq(line.frame.id, 0x100U + (got % 0x600U));
        ck_assert_uint_eq(((uint32_t)line.frame.data[0] << 24) | ((uint32_t)line.frame.data[3]),
                          (got & 0xFF000000U) | (got & 0xFFU));
        ck_assert_uint_eq(line.t_us, (uint64_t)(got / 25U) * 1000000U + (got % 25U) * 40000U);
        got++;
    }
    ck_assert_int_eq(st, HAL_LOG_EOF);
    ck_assert_uint_eq(got, n);
    hal_log_close(&l);
    remove(path);
}
END_TEST

/// The formatter writes what tools/lib candump.h writes, and the parser reads back every shape.
START_TEST(format_and_parse_round_trip)
{
    ts_rng_t rng;
    ts_rng_seed(&rng, 6U);
    char path[64];
    snprintf(path, sizeof path, "/tmp/odo-test-log3-%ld.log", (long)getpid());
    for (int i = 0; i < 20000; ++i) {
        odo_can_frame_t f;
        memset(&f, 0, sizeof f);
        const int kind = (int)ts_rng_range(&rng, 0, 3);
        f.flags = kind == 1 ? ODO_CAN_FLAG_EXT : kind == 2 ? ODO_CAN_FLAG_RTR : kind == 3 ? ODO_CAN_FLAG_ERR : 0U;
        f.id = (uint32_t)ts_rng_range(&rng, 0, kind == 0 || kind == 2 ? 0x7FF : 0x1FFFFFFF);
        f.dlc = (uint8_t)ts_rng_range(&rng, 0, 8);
        if (kind != 2) {
            for (uint8_t k = 0; k < f.dlc; ++k) {
                f.data[k] = (uint8_t)ts_rng_range(&rng, 0, 255);
            }
        }
        const uint64_t t = (uint64_t)ts_rng_range(&rng, 0, INT64_MAX / 2);
        char buf[CANDUMP_LINE_MAX];
        const size_t n = candump_format_line(buf, t, "vcan0", &f);
        candump_line_t l;
        const char *why = "";
        ck_assert_msg(candump_parse_line(buf, n, &l, &why) == CANDUMP_OK, "%.*s: %s", (int)n, buf, why);
        ck_assert_uint_eq(l.t_us, t);
        ck_assert_uint_eq(l.frame.id, f.id);
        ck_assert_uint_eq(l.frame.flags, f.flags);
        ck_assert_uint_eq(l.frame.dlc, f.dlc); /* an RTR frame's requested length too ("#R3") */
        ck_assert_mem_eq(l.frame.data, f.data, 8);
        if (kind != 3 && i < 200) { /* same text as tools/lib's writer (which has no error frames) */
            FILE *fp = fopen(path, "w+");
            ck_assert_ptr_nonnull(fp);
            ck_assert_int_eq(odo_candump_write(fp, t, "vcan0", &f), 0);
            rewind(fp);
            char other[CANDUMP_LINE_MAX + 1] = "";
            ck_assert_ptr_nonnull(fgets(other, sizeof other, fp));
            fclose(fp);
            ck_assert_int_eq(strncmp(other, buf, n), 0);
        }
    }
    remove(path);
}
END_TEST

static Suite *suite(void)
{
    Suite *s = suite_create("log_parse");
    TCase *tc = tcase_create("grammar");
    tcase_add_test(tc, standard_frame_with_data);
    tcase_add_test(tc, extended_empty_rtr_error_and_direction);
    tcase_add_loop_test(tc, malformed_lines_are_rejected_with_their_reason, 0, (int)(sizeof BAD / sizeof BAD[0]));
    tcase_add_test(tc, reader_names_file_and_line);
    tcase_add_test(tc, last_line_without_newline_and_long_files);
    tcase_add_test(tc, format_and_parse_round_trip);
    suite_add_tcase(s, tc);
    return s;
}

int main(void) { return ts_run_suite(suite()); }
