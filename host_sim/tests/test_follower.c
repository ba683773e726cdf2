/// The path follower on an ideal differential-drive robot (no effects): it must pull a start
/// offset back onto the line driving forward AND backward (straight-36m's return leg, 004 s. 6.1),
/// and land on-the-spot turns within its tolerance.
#include <check.h>

#include <math.h>

#include "check_support.h"
#include "follower.h"
#include "program.h"

/// Drive the program with perfect odometry (the estimate is the truth) from (x0, y0, th0) and
/// return the largest |y| over the last quarter of the run, and the final pose.
static double drive(const sim_program_t *p, double x, double y, double th, double *xf, double *thf)
{
    sim_follower_t f;
    const double b = 340.0, dt = 0.04;
    sim_follower_init(&f, p, b, dt);
    double w[2], late_max = 0.0;
    int ticks = 0;
    while (sim_follower_step(&f, x, y, th, w) && ticks < 100000) {
        const double v = 0.5 * (w[0] + w[1]), om = (w[1] - w[0]) / b;
        for (int k = 0; k < 40; ++k) { /* 1 ms integration of the commanded motion */
            x += v * 0.001 * cos(th + 0.5 * om * 0.001);
            y += v * 0.001 * sin(th + 0.5 * om * 0.001);
            th += om * 0.001;
        }
        ++ticks;
        if (ticks > 200) {
            late_max = fmax(late_max, fabs(y));
        }
    }
    *xf = x;
    *thf = th;
    return late_max;
}

START_TEST(line_following_converges_forward_and_backward)
{
    sim_program_t p;
    char err[128];
    ck_assert_int_eq(0, sim_program_build("straight-36m", 0, 0, 10.0, 0, &p, err, sizeof err));
    double xf, thf;
    /* Forward: start 30 mm left of the line, 1 deg off; it must settle back onto y = 0. */
    double late = drive(&p, 0.0, 30.0, 1.0 * M_PI / 180.0, &xf, &thf);
    ck_assert_msg(late < 1.0, "forward: offset still %.2f mm late in the run", late);
    /* Backward alone (the return leg, robot still facing +x): the same start offset. */
    p.seg[0] = p.seg[2];
    p.n_seg = 1;
    late = drive(&p, 18000.0, 30.0, 1.0 * M_PI / 180.0, &xf, &thf);
    ck_assert_msg(late < 1.0, "backward: offset %.2f mm late in the run", late);
    ck_assert_msg(fabs(xf) < 5.0, "ended at x = %.1f mm", xf);
    ck_assert_msg(fabs(remainder(thf, 2 * M_PI)) < 0.5 * M_PI / 180.0, "heading %.3f rad", thf);
}
END_TEST

START_TEST(on_the_spot_turns_land_within_tolerance)
{
    sim_program_t p;
    char err[128];
    ck_assert_int_eq(0, sim_program_build("umbmark", 1, 0, 10.0, 0, &p, err, sizeof err));
    double xf, thf;
    (void)drive(&p, 0.0, 0.0, 0.0, &xf, &thf);
    ck_assert_msg(fabs(remainder(thf, 2 * M_PI)) < 0.05 * M_PI / 180.0, "final heading %.5f rad", thf);
    ck_assert_msg(fabs(xf) < 2.0, "final x %.2f mm", xf);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("follower");
    TCase *tc = tcase_create("core");
    tcase_add_test(tc, line_following_converges_forward_and_backward);
    tcase_add_test(tc, on_the_spot_turns_land_within_tolerance);
    suite_add_tcase(s, tc);
    return ts_run_suite(s);
}
