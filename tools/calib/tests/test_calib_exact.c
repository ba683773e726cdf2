/// The exact UMBmark fit (tools/calib/umb_exact.h) against the paper's small-angle model
/// (000_12e7709aa9cd375a.txt Eqs. 6.19-6.20), host_sim's reproduction of 000 Fig. 3.2, and itself
/// on noise-free data; and the returns.csv reader's refusals.
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "calib_core.h"
#include "check_support.h"
#include "returns_csv.h"
#include "umb_exact.h"

static const umb_setup_t k_labmate = {4000.0, 340.0, 1.0, 1.0};

/// 000 Eqs. 6.19/6.20 (and the y forms): for small errors the exact model agrees with the
/// paper's to first order, so both share one sign convention.
START_TEST(small_errors_agree_with_the_papers_first_order_model)
{
    const double ed = 1.0004, b = 341.0, l = 4000.0;
    const double alpha = (M_PI / 2.0) * (1.0 - 340.0 / b);
    const double beta = 2.0 * l * (ed - 1.0) / ((ed + 1.0) * b);
    const double paper[2][2] = {{-2 * l * (alpha + beta), -2 * l * (alpha + beta)},
                                {-2 * l * (alpha - beta), 2 * l * (alpha - beta)}};
    for (int d = 0; d < 2; ++d) {
        double e[3];
        umb_exact_forward(&k_labmate, ed, b, d, e);
        for (int k = 0; k < 2; ++k) {
            /* second-order terms: a few percent of a ~100 mm error */
            ck_assert_msg(fabs(e[k] - paper[d][k]) < 0.05 * fabs(paper[d][k]) + 1.0,
                          "dir %d axis %d: exact %.3f paper %.3f", d, k, e[k], paper[d][k]);
        }
    }
}
END_TEST

/// 000 Fig. 3.2 as host_sim reproduces it (host_sim/README.md): Ed 0.995 with the Eb that
/// compensates it in a cw uni-directional square, 1.0375: cw ~0, ccw 1354 mm.
START_TEST(compensating_errors_hide_in_cw_and_show_in_ccw_as_in_fig_3_2)
{
    double cw[3], ccw[3];
    umb_exact_forward(&k_labmate, 0.995, 340.0 * 1.0375, 0, cw);
    umb_exact_forward(&k_labmate, 0.995, 340.0 * 1.0375, 1, ccw);
    ck_assert_double_lt(hypot(cw[0], cw[1]), 30.0);
    ck_assert_double_eq_tol(hypot(ccw[0], ccw[1]), 1354.0, 15.0);
}
END_TEST

/// Noise-free recovery: centres of gravity made by the model are fitted back from the paper
/// method's answer to far better than the 1e-5 / 0.05 mm, for calibrated and uncalibrated
/// firmware alike.
START_TEST(noise_free_fit_recovers_ed_and_b_from_the_papers_start)
{
    unsigned seed = 12345;
    for (int i = 0; i < 40; ++i) {
        const double ed = 0.995 + 0.01 * rand_r(&seed) / (double)RAND_MAX;
        const double b = 340.0 * (0.97 + 0.06 * rand_r(&seed) / (double)RAND_MAX);
        const umb_setup_t s = {4000.0, 340.0, i % 2 ? 1.002 : 1.0, i % 2 ? 0.99 : 1.0};
        double cg[2][2];
        for (int d = 0; d < 2; ++d) {
            double e[3];
            umb_exact_forward(&s, ed, b, d, e);
            cg[d][0] = e[0];
            cg[d][1] = e[1];
        }
        /* the paper method's answer as the start, through the same path the CLI takes */
        static returns_t r;
        r.n[0] = r.n[1] = 2;
        for (int d = 0; d < 2; ++d) {
            for (int k = 0; k < 2; ++k) {
                r.ex_mm[d][k] = cg[d][0];
                r.ey_mm[d][k] = cg[d][1];
                r.run[d][k] = (unsigned)k + 1;
            }
        }
        odo_params_t p;
        odo_params_defaults(&p);
        p.truck[0].ed_q30 = (int32_t)lround(s.ed_fw * 1073741824.0);
        p.truck[0].eb_q30 = (int32_t)lround(s.eb_fw * 1073741824.0);
        calib_result_t c;
        char err[256];
        ck_assert_msg(calib_umbmark(&r, 4000.0, &p, CALIB_EXACT, &c, err, sizeof err) == 0, "%s", err);
        ck_assert_msg(c.fit.converged && c.fit.identifiable, "robot %d", i);
        /* cg rounded to 1 um by the statistics: recovery to ~1e-7 and ~1e-4 mm */
        ck_assert_msg(fabs(c.fit.ed - ed) < 1e-6, "robot %d: Ed %.9f fitted %.9f", i, ed, c.fit.ed);
        ck_assert_msg(fabs(c.fit.b_mm - b) < 0.005, "robot %d: b %.5f fitted %.5f", i, b, c.fit.b_mm);
        /* the paper's small-angle answer is further off for the larger errors */
        ck_assert_double_lt(fabs(c.fit.ed - ed), fabs(c.paper.ed_q30 / 1073741824.0 - ed) + 1e-7);
    }
}
END_TEST

static int read_text(const char *text, returns_t *r, char *err, size_t n)
{
    char path[] = "/tmp/odo_calib_returns_XXXXXX";
    const int fd = mkstemp(path);
    ck_assert_int_ge(fd, 0);
    ck_assert_int_eq(write(fd, text, strlen(text)), (ssize_t)strlen(text));
    close(fd);
    const int rc = returns_read(path, r, err, n);
    unlink(path);
    return rc;
}

#define HDR "run,direction,x_abs_mm,y_abs_mm,theta_abs_deg,x_calc_mm,y_calc_mm,theta_calc_deg\n"

/// Bad input: malformed rows, NaN/inf, a wrong header, "fwd" runs: file:line and why.
START_TEST(returns_reader_names_the_line_of_bad_input)
{
    static returns_t r;
    char err[512];
    ck_assert_int_eq(read_text(HDR "1,cw,1,2,3,0,0,0\n1,ccw,1,2,3,0,0,0\n", &r, err, sizeof err), 0);
    ck_assert_int_eq((int)r.n[0], 1);
    ck_assert_double_eq_tol(r.ex_mm[0][0], 1.0, 1e-12);
    ck_assert_int_eq(read_text(HDR "1,cw,1,2,3,0,0\n", &r, err, sizeof err), -1);
    ck_assert_msg(strstr(err, ":2: 7 fields") != NULL, "%s", err);
    ck_assert_int_eq(read_text(HDR "1,cw,1,nan,3,0,0,0\n", &r, err, sizeof err), -1);
    ck_assert_msg(strstr(err, ":2: field 4 (y_abs_mm): 'nan' is not a finite number") != NULL, "%s", err);
    ck_assert_int_eq(read_text(HDR "1,cw,1,2,3,0,0,0\n2,ccw,inf,2,3,0,0,0\n", &r, err, sizeof err), -1);
    ck_assert_msg(strstr(err, ":3: field 3") != NULL, "%s", err);
    ck_assert_int_eq(read_text(HDR "1,fwd,1,2,3,0,0,0\n", &r, err, sizeof err), -1);
    ck_assert_msg(strstr(err, "cw or ccw") != NULL, "%s", err);
    ck_assert_int_eq(read_text("run,dir\n", &r, err, sizeof err), -1);
    ck_assert_msg(strstr(err, ":1: header") != NULL, "%s", err);
    ck_assert_int_eq(read_text(HDR "1,cw,1,2x,3,0,0,0\n", &r, err, sizeof err), -1);
    ck_assert_int_eq(read_text("", &r, err, sizeof err), -1);
}
END_TEST

/// A direction with fewer than 2 runs and a side <= 0 are refused before any arithmetic.
START_TEST(calibration_refuses_too_few_runs_and_a_bad_side)
{
    static returns_t r;
    char err[512];
    ck_assert_int_eq(read_text(HDR "1,cw,1,2,3,0,0,0\n2,cw,1,2,3,0,0,0\n1,ccw,1,2,3,0,0,0\n", &r, err, sizeof err), 0);
    odo_params_t p;
    odo_params_defaults(&p);
    calib_result_t c;
    ck_assert_int_eq(calib_umbmark(&r, 4000.0, &p, CALIB_EXACT, &c, err, sizeof err), -1);
    ck_assert_msg(strstr(err, "1 ccw run") != NULL, "%s", err);
    r.n[1] = 2;
    r.ex_mm[1][1] = 1.0;
    ck_assert_int_eq(calib_umbmark(&r, 0.0, &p, CALIB_EXACT, &c, err, sizeof err), -1);
    ck_assert_msg(strstr(err, "positive") != NULL, "%s", err);
    ck_assert_int_eq(calib_umbmark(&r, -4000.0, &p, CALIB_PAPER, &c, err, sizeof err), -1);
    ck_assert_int_eq(calib_umbmark(&r, NAN, &p, CALIB_PAPER, &c, err, sizeof err), -1);
    ck_assert_int_eq(calib_umbmark(&r, 4000.0, &p, CALIB_PAPER, &c, err, sizeof err), 0);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("calib_exact");
    TCase *tc = tcase_create("core");
    tcase_add_test(tc, small_errors_agree_with_the_papers_first_order_model);
    tcase_add_test(tc, compensating_errors_hide_in_cw_and_show_in_ccw_as_in_fig_3_2);
    tcase_add_test(tc, noise_free_fit_recovers_ed_and_b_from_the_papers_start);
    tcase_add_test(tc, returns_reader_names_the_line_of_bad_input);
    tcase_add_test(tc, calibration_refuses_too_few_runs_and_a_bad_side);
    suite_add_tcase(s, tc);
    return ts_run_suite(s);
}
