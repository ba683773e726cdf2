/// The simulator's world, bump geometry, effects catalog and robot description (issue 3, items 1,
/// 2 and 8). Each test is named after what it shows and cites the paper it reproduces.
#include <check.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check_support.h"
#include "bump.h"
#include "effects.h"
#include "odo/odo_params.h"
#include "odo_robot.h"
#include "ratelimit.h"
#include "world.h"

#ifndef ODOSIM_SOURCE_DIR
#error "ODOSIM_SOURCE_DIR must point at host_sim/"
#endif

#define DEG(rad) ((rad)*180.0 / M_PI)
#define DT       SIM_WORLD_DEFAULT_DT_S

static sim_world_t g_world, g_world2; /* ~36 KiB each: kept off the stack */

static void must(int rc, const char *err) { ck_assert_msg(rc == 0, "%s", err); }

static void load_robot(const char *name, sim_robot_t *r)
{
    char path[512], err[512];
    snprintf(path, sizeof path, "%s/robots/%s.json", ODOSIM_SOURCE_DIR, name);
    must(sim_robot_parse_file(path, r, err, sizeof err), err);
}

static void load_scenario(const char *name, sim_scenario_t *sc)
{
    char path[512], err[512];
    snprintf(path, sizeof path, "%s/scenarios/%s.json", ODOSIM_SOURCE_DIR, name);
    must(sim_scenario_parse_file(path, sc, err, sizeof err), err);
}

/* Hold wheel commands for `seconds` at the 1 ms physics step (last step shortened to land exactly).
 * Both trucks get the same command. */
static void drive(sim_world_t *w, double seconds, double left_mm_s, double right_mm_s)
{
    const double cmd[2][2] = {{left_mm_s, right_mm_s}, {left_mm_s, right_mm_s}};
    const long n = (long)floor(seconds / DT + 1e-9);
    for (long i = 0; i < n; ++i) {
        ck_assert_int_eq(sim_world_step(w, DT, cmd), 0);
    }
    const double rest = seconds - (double)n * DT;
    if (rest > 1e-12) {
        ck_assert_int_eq(sim_world_step(w, rest, cmd), 0);
    }
}

/* Open-loop motions at 200 mm/s (000 s. 4.1) for exact nominal distances and angles. */
static void straight(sim_world_t *w, double mm) { drive(w, mm / 200.0, 200.0, 200.0); }

static void turn_on_spot(sim_world_t *w, double deg_ccw, double wheelbase_nominal_mm)
{
    const double arc = fabs(deg_ccw) * M_PI / 180.0 * 0.5 * wheelbase_nominal_mm;
    const double s = deg_ccw > 0.0 ? 1.0 : -1.0;
    drive(w, arc / 200.0, -200.0 * s, 200.0 * s);
}

static sim_robot_t labmate(void)
{
    sim_robot_t r;
    load_robot("labmate", &r);
    return r;
}

/* ---------------------------------------------------------------------------------------------
 * Bump geometry
 * ------------------------------------------------------------------------------------------- */
START_TEST(table_I_of_004_reproduced_with_paper_formulas_and_exact_geometry)
{
    /* 004_997ef9ec5c850202.txt Table I: b 340, R 75, h 10 -> dD 2.63 mm, dtheta 0.44 deg, 77 mm. */
    sim_bump_geom_t paper, exact;
    ck_assert(sim_bump_geom(75.0, 10.0, SIM_BUMP_PAPER, &paper));
    ck_assert(sim_bump_geom(75.0, 10.0, SIM_BUMP_EXACT, &exact));
    const double th_p = DEG(sim_bump_dtheta_rad(paper.dd_mm, 340.0));
    const double th_e = DEG(sim_bump_dtheta_rad(exact.dd_mm, 340.0));
    const double el_p = sim_bump_elat_mm(paper.dd_mm, 340.0, 10000.0);
    const double el_e = sim_bump_elat_mm(exact.dd_mm, 340.0, 10000.0);
    printf("004 Table I (b 340, R 75, h 10 mm)\n");
    printf("  model  D_hor_mm  D_meas_mm  dD_mm  dtheta_deg  e_lat_10m_mm\n");
    printf("  paper  %8.3f  %9.3f  %5.3f  %10.4f  %12.2f\n", paper.d_hor_mm, paper.d_meas_mm, paper.dd_mm, th_p, el_p);
    printf("  exact  %8.3f  %9.3f  %5.3f  %10.4f  %12.2f\n", exact.d_hor_mm, exact.d_meas_mm, exact.dd_mm, th_e, el_e);
    ck_assert_double_eq_tol(paper.dd_mm, 2.63, 0.005);
    ck_assert_double_eq_tol(th_p, 0.44, 0.005);
    ck_assert_double_eq_tol(el_p, 77.0, 0.5);
    ck_assert_double_eq_tol(exact.dd_mm, 3.51, 0.005);
    ck_assert_double_eq_tol(th_e, 0.59, 0.005);
    /* Both share Eq. 2 for the horizontal part. */
    ck_assert_double_eq_tol(paper.d_hor_mm, sqrt(1400.0), 1e-12);
    ck_assert_double_eq_tol(exact.d_hor_mm, paper.d_hor_mm, 1e-12);
}
END_TEST

START_TEST(bump_profile_builds_the_error_up_gradually_over_the_bump)
{
    /* 004 s. 4 (Fig. 5 inset): the orientation error grows while the wheel is on the bump. */
    for (int m = 0; m < 2; ++m) {
        sim_bump_geom_t g;
        ck_assert(sim_bump_geom(75.0, 10.0, (sim_bump_model_t)m, &g));
        const double span = sim_bump_span_rot_mm(&g);
        double prev = 0.0;
        for (int i = 0; i <= 1000; ++i) {
            const double s = span * i / 1000.0;
            const double e = sim_bump_excess_mm(&g, s);
            ck_assert(e >= prev - 1e-12);
            prev = e;
            /* Inverse pair. */
            const double u = sim_bump_hor_of_rot(&g, s);
            ck_assert_double_eq_tol(sim_bump_rot_of_hor(&g, u), s, 1e-9);
        }
        ck_assert_double_eq_tol(prev, g.dd_mm, 1e-12);
        ck_assert_double_eq_tol(sim_bump_excess_mm(&g, 0.5 * span), 0.5 * g.dd_mm, 1e-12); /* symmetric */
        ck_assert_double_eq_tol(sim_bump_lift_mm(&g, g.d_hor_mm), 10.0, 1e-9);
        ck_assert_double_eq_tol(sim_bump_lift_mm(&g, 0.0), 0.0, 1e-9);
    }
    sim_bump_geom_t g;
    ck_assert(!sim_bump_geom(75.0, 75.0, SIM_BUMP_EXACT, &g));
    ck_assert(!sim_bump_geom(75.0, -1.0, SIM_BUMP_EXACT, &g));
    ck_assert(sim_bump_geom(75.0, 0.0, SIM_BUMP_EXACT, &g) && g.dd_mm == 0.0);
}
END_TEST

START_TEST(straight_run_over_one_bump_turns_toward_the_bumped_wheel_by_dtheta)
{
    /* 004 s. 3.1, Eqs. 4-5: a bump under the right wheel curves the truck right by asin(dD/b), and
     * the lateral error then grows as D * dD / b. */
    const sim_robot_t r = labmate();
    for (int m = 0; m < 2; ++m) {
        sim_scenario_t sc;
        char err[256];
        sim_scenario_none(&sc);
        must(sim_scenario_set(&sc, "bumps", "model", 1U, (double)m, err, sizeof err), err);
        must(sim_world_init(&g_world, &r, &sc, 1U, err, sizeof err), err);
        ck_assert_int_eq(sim_world_add_bump(&g_world, ODO_TRUCK_A, ODO_RIGHT, 1000.0, 10.0), 0);
        sim_bump_geom_t g;
        ck_assert(sim_bump_geom(75.0, 10.0, (sim_bump_model_t)m, &g));
        const double expect = -sim_bump_dtheta_rad(g.dd_mm, 340.0);

        straight(&g_world, 1000.0 + g.d_hor_mm); /* about halfway over the bump */
        const double mid = sim_world_pose(&g_world, 0).theta_rad;
        ck_assert_msg(mid < 0.25 * expect && mid > 0.75 * expect, "mid-bump heading %g of %g", mid, expect);

        straight(&g_world, 2000.0 - g.d_hor_mm);
        const sim_pose_t after = sim_world_pose(&g_world, 0);
        ck_assert_double_eq_tol(after.theta_rad, expect, 1e-3 * fabs(expect));
        size_t n = 0;
        const sim_bump_event_t *ev = sim_world_bump_events(&g_world, &n);
        ck_assert_uint_eq(n, 1U);
        ck_assert_uint_eq(ev[0].wheel, ODO_RIGHT);
        ck_assert_double_eq_tol(ev[0].x_mm, 1000.0, 1.0);
        ck_assert_double_eq_tol(ev[0].y_mm, -170.0, 0.01);

        /* Eq. 5: 10 m further on, the lateral error has grown by 10 m * dD / b (to the right). */
        const double y0 = after.y_mm;
        straight(&g_world, 10000.0);
        const double dy = sim_world_pose(&g_world, 0).y_mm - y0;
        ck_assert_double_eq_tol(dy, -sim_bump_elat_mm(g.dd_mm, 340.0, 10000.0),
                                0.01 * sim_bump_elat_mm(g.dd_mm, 340.0, 10000.0));
        /* The encoder still counted the full rotation: both wheels show the same phase. */
        ck_assert_double_eq_tol(sim_world_encoder_phase_counts(&g_world, 0, ODO_LEFT),
                                sim_world_encoder_phase_counts(&g_world, 0, ODO_RIGHT), 1e-6);
    }
}
END_TEST

/* ---------------------------------------------------------------------------------------------
 * Systematic effects
 * ------------------------------------------------------------------------------------------- */
START_TEST(ed_above_one_makes_a_straight_command_curve_left)
{
    /* 000 Eq. 2.7: Ed = DR/DL. Equal wheel rotations with DR > DL move the right wheel further, so
     * by Eq. 2.4 the heading grows: the robot turns left (ccw). Over L, dtheta = 2L(Ed-1)/((Ed+1)b). */
    const sim_robot_t r = labmate();
    const double eds[] = {1.005, 0.9985};
    for (int i = 0; i < 2; ++i) {
        sim_scenario_t sc;
        char err[256];
        sim_scenario_none(&sc);
        must(sim_scenario_set(&sc, "ed", "value", 3U, eds[i], err, sizeof err), err);
        must(sim_world_init(&g_world, &r, &sc, 1U, err, sizeof err), err);
        straight(&g_world, 4000.0);
        const double th = sim_world_pose(&g_world, 0).theta_rad;
        const double expect = 2.0 * 4000.0 * (eds[i] - 1.0) / ((eds[i] + 1.0) * 340.0);
        ck_assert_msg((eds[i] > 1.0) == (th > 0.0), "Ed %g turned %g rad", eds[i], th);
        ck_assert_double_eq_tol(th, expect, 1e-9);
        /* 000 Eq. 6.30: the mean diameter is kept, so the centre travels an arc of exactly 4 m; the
         * straight-line distance is that arc's chord. */
        const double chord = 4000.0 * sin(0.5 * expect) / (0.5 * expect);
        ck_assert_double_eq_tol(hypot(sim_world_pose(&g_world, 0).x_mm, sim_world_pose(&g_world, 0).y_mm), chord, 1e-6);
    }
}
END_TEST

START_TEST(eb_scales_on_the_spot_turns_by_one_over_eb)
{
    /* 000 Eqs. 2.4, 2.8, 6.27-6.29: the wheels travel the arcs for the nominal b, so the true turn
     * is the nominal angle times b_nominal/b_actual = 1/Eb. Appendix A: Ed leaves it unchanged. */
    const sim_robot_t r = labmate();
    const double ebs[] = {1.02, 337.0 / 340.0};
    for (int i = 0; i < 2; ++i) {
        sim_scenario_t sc;
        char err[256];
        sim_scenario_none(&sc);
        must(sim_scenario_set(&sc, "eb", "value", 3U, ebs[i], err, sizeof err), err);
        must(sim_scenario_set(&sc, "ed", "value", 3U, 0.995, err, sizeof err), err);
        must(sim_world_init(&g_world, &r, &sc, 1U, err, sizeof err), err);
        turn_on_spot(&g_world, 90.0, 340.0);
        ck_assert_double_eq_tol(DEG(sim_world_pose(&g_world, 0).theta_rad), 90.0 / ebs[i], 1e-9);
    }
}
END_TEST

START_TEST(scrub_leaves_spot_turns_to_eb_and_widens_the_wheelbase_on_arcs)
{
    /* 000 s. 2.2 b: a tyre touches the floor in an area, so the effective wheelbase need not be one
     * number. Catalog `scrub`: on the spot the turn is 1/Eb of the nominal (as without scrub); on
     * an arc of radius R the effective wheelbase is b Eb / (1 - k (1 - b/(2R))); straight it does
     * nothing. Checked against that closed form for two radii and both signs of k. */
    const sim_robot_t r = labmate();
    const double b = 340.0, eb = 1.01;
    const double ks[] = {0.05, -0.1};
    for (int i = 0; i < 2; ++i) {
        sim_scenario_t sc;
        char err[256];
        sim_scenario_none(&sc);
        must(sim_scenario_set(&sc, "eb", "value", 3U, eb, err, sizeof err), err);
        must(sim_scenario_set(&sc, "scrub", "k", 3U, ks[i], err, sizeof err), err);
        must(sim_world_init(&g_world, &r, &sc, 1U, err, sizeof err), err);
        turn_on_spot(&g_world, 90.0, b);
        ck_assert_double_eq_tol(DEG(sim_world_pose(&g_world, 0).theta_rad), 90.0 / eb, 1e-9);
        const double radii[] = {500.0, 2000.0};
        for (int j = 0; j < 2; ++j) {
            must(sim_world_init(&g_world, &r, &sc, 1U, err, sizeof err), err);
            const double R = radii[j], v = 200.0;
            const double vl = v * (R - 0.5 * b) / R, vr = v * (R + 0.5 * b) / R;
            drive(&g_world, 2.0, vl, vr);
            const double s = b / (2.0 * R);
            const double nominal = (vr - vl) * 2.0 / (b * eb);
            const double expect = nominal * (1.0 - ks[i] * (1.0 - s));
            ck_assert_double_eq_tol(sim_world_pose(&g_world, 0).theta_rad, expect, 1e-12);
        }
        must(sim_world_init(&g_world, &r, &sc, 1U, err, sizeof err), err);
        straight(&g_world, 1000.0);
        ck_assert_double_eq_tol(sim_world_pose(&g_world, 0).theta_rad, 0.0, 1e-15);
        ck_assert_double_eq_tol(sim_world_pose(&g_world, 0).x_mm, 1000.0, 1e-9);
    }
}
END_TEST

START_TEST(es_makes_the_true_distance_the_calculated_one_over_es)
{
    /* 000 App. B, Eq. B.1: Es = L_calc / L_actual. */
    const sim_robot_t r = labmate();
    sim_scenario_t sc;
    load_scenario("effect-es", &sc);
    char err[256];
    must(sim_world_init(&g_world, &r, &sc, 1U, err, sizeof err), err);
    straight(&g_world, 4000.0);
    ck_assert_double_eq_tol(sim_world_pose(&g_world, 0).x_mm, 4000.0 / 1.004, 1e-6);
    ck_assert_double_eq_tol(sim_world_pose(&g_world, 0).y_mm, 0.0, 1e-9);
}
END_TEST

/* One open-loop 4 x 4 m square, returning the position error (the calculated pose is the nominal
 * square: the origin). */
static double square_return_error_mm(const sim_robot_t *r, const sim_scenario_t *sc, int ccw)
{
    char err[256];
    must(sim_world_init(&g_world, r, sc, 1U, err, sizeof err), err);
    for (int leg = 0; leg < 4; ++leg) {
        straight(&g_world, 4000.0);
        turn_on_spot(&g_world, ccw ? 90.0 : -90.0, 340.0);
    }
    const sim_pose_t p = sim_world_pose(&g_world, 0);
    return hypot(p.x_mm, p.y_mm);
}

START_TEST(uni_directional_square_hides_compensating_ed_and_eb_that_umbmark_exposes)
{
    /* 000 s. 3.1, Fig. 3.2: each nominally straight leg curves by dtheta_leg (Ed < 1: to the right);
     * an Eb chosen so every cw corner turns short by exactly that much makes the cw square close,
     * while in the ccw direction both errors add up (000 s. 3.2, UMBmark). */
    const sim_robot_t r = labmate();
    const double ed = 0.995, L = 4000.0;
    double eb = 1.0;
    for (int i = 0; i < 50; ++i) { /* fixed point: dtheta_leg depends on the true wheelbase */
        const double dth = 2.0 * L * (1.0 - ed) / ((ed + 1.0) * 340.0 * eb);
        eb = 1.0 / (1.0 - 2.0 * dth / M_PI);
    }
    sim_scenario_t sc;
    char err[256];
    sim_scenario_none(&sc);
    must(sim_scenario_set(&sc, "ed", "value", 3U, ed, err, sizeof err), err);
    must(sim_scenario_set(&sc, "eb", "value", 3U, eb, err, sizeof err), err);
    const double cw = square_return_error_mm(&r, &sc, 0);
    const double ccw = square_return_error_mm(&r, &sc, 1);
    printf("000 Fig. 3.2: Ed %.4f, Eb %.5f: cw return error %.3g mm, ccw %.1f mm\n", ed, eb, cw, ccw);
    ck_assert_msg(cw < 10.0, "cw error %g mm should be hidden", cw);
    ck_assert_msg(ccw > 500.0, "ccw error %g mm should be exposed", ccw);
    ck_assert(ccw > 50.0 * cw);
}
END_TEST

/* ---------------------------------------------------------------------------------------------
 * Determinism, vehicles, linkage
 * ------------------------------------------------------------------------------------------- */
static void run_rough(sim_world_t *w, uint64_t seed)
{
    const sim_robot_t r = labmate();
    sim_scenario_t sc;
    char err[256];
    load_scenario("set-sim", &sc);
    must(sim_world_init(w, &r, &sc, seed, err, sizeof err), err);
    ck_assert_int_eq(sim_world_add_bump(w, 0, ODO_LEFT, 500.0, 10.0), 0);
    straight(w, 4000.0);
    turn_on_spot(w, 90.0, 340.0);
    straight(w, 1000.0);
}

START_TEST(same_seed_gives_bit_identical_worlds_and_another_seed_differs)
{
    run_rough(&g_world, 42U);
    run_rough(&g_world2, 42U);
    const sim_pose_t a = sim_world_pose(&g_world, 0), b = sim_world_pose(&g_world2, 0);
    ck_assert(memcmp(&a, &b, sizeof a) == 0);
    for (unsigned wh = 0; wh < 2; ++wh) {
        const double pa = sim_world_encoder_phase_counts(&g_world, 0, wh);
        const double pb = sim_world_encoder_phase_counts(&g_world2, 0, wh);
        ck_assert(memcmp(&pa, &pb, sizeof pa) == 0);
    }
    size_t na, nb;
    const sim_bump_event_t *ea = sim_world_bump_events(&g_world, &na), *eb = sim_world_bump_events(&g_world2, &nb);
    ck_assert_uint_eq(na, nb);
    ck_assert(memcmp(&ea[0].x_mm, &eb[0].x_mm, sizeof(double)) == 0);
    ck_assert_uint_eq(g_world.bumps_dropped, 0U);

    run_rough(&g_world2, 43U);
    const sim_pose_t c = sim_world_pose(&g_world2, 0);
    ck_assert(c.x_mm != a.x_mm && c.theta_rad != a.theta_rad);
}
END_TEST

START_TEST(set_trailer_follows_the_robot_and_its_encoders_count_its_travel)
{
    /* 000 s. 4.6: a passive trailer behind a hitch point; after a turn and a long straight the joint
     * angle decays back to zero and the trailer's wheels have counted its path. */
    sim_robot_t r;
    load_robot("set", &r);
    sim_scenario_t sc;
    char err[256];
    sim_scenario_none(&sc);
    must(sim_world_init(&g_world, &r, &sc, 1U, err, sizeof err), err);
    sim_link_geom_t g = sim_world_link_true(&g_world);
    ck_assert_double_eq_tol(g.alpha_rad, 0.0, 1e-12);
    ck_assert_double_eq_tol(sim_world_pose(&g_world, 1).x_mm, -800.0, 1e-9);
    straight(&g_world, 2000.0);
    ck_assert_double_eq_tol(sim_world_pose(&g_world, 1).x_mm, 2000.0 - 800.0, 1e-6);
    const double cpr = sim_robot_counts_per_rev(&r.truck[1]);
    ck_assert_double_eq_tol(sim_world_encoder_phase_counts(&g_world, 1, ODO_LEFT), 2000.0 / (M_PI * 100.0) * cpr, 1e-6);
    turn_on_spot(&g_world, 90.0, 340.0);
    g = sim_world_link_true(&g_world);
    ck_assert_msg(DEG(g.alpha_rad) > 45.0, "joint angle after a 90 deg turn on the spot: %g deg", DEG(g.alpha_rad));
    straight(&g_world, 6000.0);
    g = sim_world_link_true(&g_world);
    ck_assert_double_eq_tol(DEG(g.alpha_rad), 0.0, 0.01);
    ck_assert_double_eq_tol(DEG(sim_world_pose(&g_world, 1).theta_rad), 90.0, 0.01);
    /* The bar stays rigid: axle exactly trailer_length behind the hitch. */
    const sim_pose_t a = sim_world_pose(&g_world, 0), t = sim_world_pose(&g_world, 1);
    const double hx = a.x_mm - 300.0 * cos(a.theta_rad), hy = a.y_mm - 300.0 * sin(a.theta_rad);
    ck_assert_double_eq_tol(hypot(hx - t.x_mm, hy - t.y_mm), 500.0, 1e-6);
}
END_TEST

START_TEST(clapper_linkage_geometry_follows_002_eq_10_11_16_and_clamps_at_its_range)
{
    sim_robot_t r;
    load_robot("clapper", &r);
    sim_scenario_t sc;
    char err[256];
    load_scenario("effect-rotary_bias", &sc);
    must(sim_scenario_set(&sc, "link_bias", "const_mm", 3U, 2.0, err, sizeof err), err);
    must(sim_world_init(&g_world, &r, &sc, 1U, err, sizeof err), err);
    sim_link_geom_t g = sim_world_link_true(&g_world);
    ck_assert_double_eq_tol(g.length_mm, 1000.0, 1e-9);
    ck_assert_double_eq_tol(g.theta_l_rad, 0.0, 1e-12);

    /* Truck A turns left on the spot while B stands: alpha = theta_A - theta_L grows, beta stays. */
    const double cmd[2][2] = {{-100.0, 100.0}, {0.0, 0.0}};
    for (int i = 0; i < 500; ++i) {
        ck_assert_int_eq(sim_world_step(&g_world, DT, cmd), 0);
    }
    g = sim_world_link_true(&g_world);
    const sim_pose_t a = sim_world_pose(&g_world, 0), b = sim_world_pose(&g_world, 1);
    ck_assert_double_eq_tol(g.alpha_rad, a.theta_rad - g.theta_l_rad, 1e-12);
    ck_assert_double_eq_tol(g.beta_rad, b.theta_rad - g.theta_l_rad, 1e-12);
    /* Eq. 16: B sits at distance l behind A along theta_L. */
    ck_assert_double_eq_tol(b.x_mm, a.x_mm - g.length_mm * cos(g.theta_l_rad), 1e-9);
    ck_assert_double_eq_tol(b.y_mm, a.y_mm - g.length_mm * sin(g.theta_l_rad), 1e-9);
    /* Encoders: rotary bias -1 deg on alpha, +1 deg on beta; link bias +2 mm; 10-bit, 0.1 mm. */
    const sim_link_reading_t m = sim_world_link_measured(&g_world);
    ck_assert_double_eq_tol(DEG(m.alpha_rad - g.alpha_rad), -1.0, 1e-9);
    ck_assert_double_eq_tol(DEG(m.beta_rad - g.beta_rad), 1.0, 1e-9);
    ck_assert_double_eq_tol(m.length_mm - g.length_mm, 2.0, 1e-9);
    ck_assert_uint_eq(m.alpha_bam16 & 0x3FU, 0U); /* 10-bit codes */
    double alpha_q = m.alpha_bam16 / 65536.0 * 360.0;
    alpha_q = alpha_q > 180.0 ? alpha_q - 360.0 : alpha_q;
    ck_assert_double_eq_tol(alpha_q, DEG(m.alpha_rad), 360.0 / 1024.0 / 2.0 + 1e-9);
    ck_assert_uint_eq(m.length_um % 100U, 0U);

    /* Truck A drives away from B: l stops at the 1100 mm end of the range and the clamp counts. */
    const double apart[2][2] = {{300.0, 300.0}, {0.0, 0.0}};
    ck_assert_uint_eq(sim_world_link_clamps(&g_world), 0U);
    for (int i = 0; i < 2000; ++i) {
        ck_assert_int_eq(sim_world_step(&g_world, DT, apart), 0);
    }
    ck_assert_double_eq_tol(sim_world_link_true(&g_world).length_mm, 1100.0, 1e-9);
    ck_assert_uint_gt(sim_world_link_clamps(&g_world), 0U);
}
END_TEST

/* The stop replayed over a recorded motion (what gap/model.py asks libodosim for): A drives 10 mm
 * a tick away from a standing B on a 1000 mm link with range [900, 1100]; the 200 mm beyond the
 * end are taken up half by each truck, one stop per tick beyond it. */
START_TEST(clapper_stop_replayed_over_a_track_pushes_half_way_and_obeys_its_gate)
{
    enum { N = 31 };
    double rel[2 * N], push[2 * N];
    unsigned char gate[N];
    for (size_t i = 0; i < N; ++i) {
        rel[2 * i] = 1000.0 + 10.0 * (double)i;
        rel[2 * i + 1] = 0.0;
        gate[i] = 1U;
    }
    ck_assert_int_eq(sim_link_clamp_track(rel, N, 900.0, 1100.0, NULL, push), 20);
    ck_assert_double_eq(push[2 * 10], 0.0); /* at 1100 mm: still inside */
    ck_assert_double_eq_tol(push[2 * 11], -5.0, 1e-12);
    ck_assert_double_eq_tol(push[2 * (N - 1)], -100.0, 1e-9);
    ck_assert_double_eq_tol(rel[2 * (N - 1)] + 2.0 * push[2 * (N - 1)], 1100.0, 1e-9);
    ck_assert_double_eq(push[2 * (N - 1) + 1], 0.0);
    /* a tick whose gate is closed lets the link run past the stop; the next open one takes it back */
    gate[11] = gate[12] = 0U;
    ck_assert_int_eq(sim_link_clamp_track(rel, N, 900.0, 1100.0, gate, push), 18);
    ck_assert_double_eq(push[2 * 12], 0.0);
    ck_assert_double_eq_tol(push[2 * 13], -15.0, 1e-12);
    ck_assert_double_eq_tol(push[2 * (N - 1)], -100.0, 1e-9);
    /* too short: pushed apart, along the link */
    for (size_t i = 0; i < N; ++i) {
        rel[2 * i] = 0.0;
        rel[2 * i + 1] = -(1000.0 - 10.0 * (double)i);
    }
    ck_assert_int_eq(sim_link_clamp_track(rel, N, 900.0, 1100.0, NULL, push), 20);
    ck_assert_double_eq_tol(push[2 * (N - 1) + 1], -100.0, 1e-9);
    ck_assert_double_eq_tol(push[2 * (N - 1)], 0.0, 1e-12);
    /* bad calls */
    ck_assert_int_eq(sim_link_clamp_track(NULL, N, 900.0, 1100.0, NULL, push), -1);
    ck_assert_int_eq(sim_link_clamp_track(rel, N, 900.0, 1100.0, NULL, NULL), -1);
    ck_assert_int_eq(sim_link_clamp_track(rel, N, 1100.0, 900.0, NULL, push), -1);
    ck_assert_int_eq(sim_link_clamp_track(rel, N, NAN, 1100.0, NULL, push), -1);
    ck_assert_int_eq(sim_link_clamp_track(rel, 0U, 900.0, 1100.0, NULL, push), 0);
    /* A and B on one spot: pushed apart along the fallback direction the caller gives */
    double px, py;
    ck_assert(sim_link_push(0.0, 0.0, 900.0, 1100.0, 0.0, 1.0, &px, &py));
    ck_assert_double_eq(px, 0.0);
    ck_assert_double_eq_tol(py, 450.0, 1e-12);
    ck_assert(!sim_link_push(0.0, 1000.0, 900.0, 1100.0, 1.0, 0.0, &px, &py));
    ck_assert_double_eq(px, 0.0);
}
END_TEST

/* The floor that follows a wheel by at most lim per step: a step from 0 to 10 with lim 3 is
 * reached in four steps (3, 6, 9, 10), a drop to 0 the same way down; its plane form on a pose
 * track (the friction circle); NULL and aliased arrays are refused. */
START_TEST(rate_limiter_follows_its_input_by_at_most_the_limit)
{
    const double v[8] = {10.0, 10.0, 10.0, 10.0, 10.0, 0.0, 0.0, 0.0};
    const double lim[8] = {3.0, 3.0, 3.0, 3.0, 3.0, 4.0, 4.0, 4.0};
    const double want[8] = {3.0, 6.0, 9.0, 10.0, 10.0, 6.0, 2.0, 0.0};
    double out[8];
    ck_assert_int_eq(sim_rate_limit(v, lim, 8U, out), 0);
    for (size_t i = 0; i < 8U; ++i) {
        ck_assert_double_eq(out[i], want[i]);
    }
    ck_assert_int_eq(sim_rate_limit(NULL, lim, 8U, out), -1);
    ck_assert_int_eq(sim_rate_limit(v, NULL, 8U, out), -1);
    ck_assert_int_eq(sim_rate_limit(v, lim, 8U, NULL), -1);
    ck_assert_int_eq(sim_rate_limit(v, lim, 0U, out), 0);

    /* the plane form: a wanted velocity (3, 4) (length 5) reached by steps of 2 along it, then a
     * quarter turn to (-4, 3) limited to 2 along the difference (-7, -1), length sqrt(50) */
    const double vx[4] = {3.0, 3.0, 3.0, -4.0}, vy[4] = {4.0, 4.0, 4.0, 3.0}, l2[4] = {2.0, 2.0, 2.0, 2.0};
    double ox[4], oy[4];
    ck_assert_int_eq(sim_rate_limit_2d(vx, vy, l2, 4U, ox, oy), 0);
    ck_assert_double_eq_tol(ox[0], 1.2, 1e-12);
    ck_assert_double_eq_tol(oy[0], 1.6, 1e-12);
    ck_assert_double_eq_tol(ox[1], 2.4, 1e-12);
    ck_assert_double_eq(ox[2], 3.0);
    ck_assert_double_eq(oy[2], 4.0);
    ck_assert_double_eq_tol(ox[3], 3.0 - 14.0 / sqrt(50.0), 1e-12);
    ck_assert_double_eq_tol(oy[3], 4.0 - 2.0 / sqrt(50.0), 1e-12);
    ck_assert_int_eq(sim_rate_limit_2d(vx, NULL, l2, 4U, ox, oy), -1);
    ck_assert_int_eq(sim_rate_limit_2d(vx, vy, l2, 4U, ox, NULL), -1);

    /* and on a pose track whose steps ask the same velocities: the followed ones summed from
     * the start (1, 2), the heading the track's */
    const double pose[15] = {1.0, 2.0, 0.1, 4.0, 6.0, 0.2, 7.0, 10.0, 0.3, 10.0, 14.0, 0.4, 6.0, 17.0, 0.5};
    const double dt[4] = {1.0, 1.0, 1.0, 1.0};
    double track[15];
    ck_assert_int_eq(sim_rate_limit_track(pose, 5U, dt, 2.0, track), 0);
    const double follows[15] = {
        1.0, 2.0, 0.1, 2.2, 3.6, 0.2, 4.6, 6.8, 0.3, 7.6, 10.8, 0.4, 10.6 - 14.0 / sqrt(50.0), 14.8 - 2.0 / sqrt(50.0),
        0.5};
    for (size_t i = 0; i < 15U; ++i) {
        ck_assert_double_eq_tol(track[i], follows[i], 1e-12);
    }
    /* half-second steps: the wanted velocity (6, 8), limited to acc dt = 2 a step, (1.2, 1.6)
     * for half a second */
    const double half[4] = {0.5, 0.5, 0.5, 0.5};
    ck_assert_int_eq(sim_rate_limit_track(pose, 5U, half, 4.0, track), 0);
    ck_assert_double_eq_tol(track[3], 1.6, 1e-12);
    ck_assert_double_eq_tol(track[4], 2.8, 1e-12);
    ck_assert_int_eq(sim_rate_limit_track(pose, 1U, dt, 2.0, track), 0); /* the start alone */
    ck_assert_double_eq(track[2], 0.1);
    ck_assert_int_eq(sim_rate_limit_track(pose, 0U, dt, 2.0, track), 0);
    ck_assert_int_eq(sim_rate_limit_track(NULL, 5U, dt, 2.0, track), -1);
    ck_assert_int_eq(sim_rate_limit_track(pose, 5U, NULL, 2.0, track), -1);
    ck_assert_int_eq(sim_rate_limit_track(pose, 5U, dt, 2.0, NULL), -1);
    ck_assert_int_eq(sim_rate_limit_track(track, 5U, dt, 2.0, track), -1);
}
END_TEST

START_TEST(world_refuses_bad_steps_and_bumps)
{
    const sim_robot_t r = labmate();
    sim_scenario_t sc;
    char err[256];
    sim_scenario_none(&sc);
    must(sim_world_init(&g_world, &r, &sc, 1U, err, sizeof err), err);
    const double cmd[2][2] = {{100.0, NAN}, {0.0, 0.0}};
    const double ok[2][2] = {{100.0, 100.0}, {0.0, 0.0}};
    ck_assert_int_eq(sim_world_step(&g_world, DT, cmd), -1);
    ck_assert_int_eq(sim_world_step(&g_world, 0.0, ok), -1);
    ck_assert_int_eq(sim_world_step(&g_world, 1.0, ok), -1);
    ck_assert_int_eq(sim_world_add_bump(&g_world, 1, 0, 10.0, 1.0), -1);  /* labmate has no truck B */
    ck_assert_int_eq(sim_world_add_bump(&g_world, 0, 0, 10.0, 80.0), -1); /* higher than the wheel */
    ck_assert(sim_world_pose(&g_world, 0).x_mm == 0.0);                   /* refused steps did not move it */
    /* Tyre load offset beyond half the wheelbase. */
    must(sim_scenario_set(&sc, "tire_compression", "lateral_offset_mm", 3U, 200.0, err, sizeof err), err);
    ck_assert_int_eq(sim_world_init(&g_world, &r, &sc, 1U, err, sizeof err), -1);
    ck_assert_ptr_nonnull(strstr(err, "lateral_offset_mm"));
}
END_TEST

START_TEST(tire_compression_with_an_offset_load_acts_like_an_ed)
{
    /* 000 s. 2.2 a: tyres compress differently under asymmetric load. Load left of centre squeezes
     * the left tyre more, so DR > DL and the robot curves left like an Ed > 1. */
    const sim_robot_t r = labmate();
    sim_scenario_t sc;
    char err[256];
    load_scenario("effect-tire_compression", &sc);
    must(sim_world_init(&g_world, &r, &sc, 1U, err, sizeof err), err);
    const double rl = sim_world_wheel_radius_mm(&g_world, 0, ODO_LEFT),
                 rr = sim_world_wheel_radius_mm(&g_world, 0, ODO_RIGHT);
    ck_assert(rr > rl && rl < 75.0);
    straight(&g_world, 4000.0);
    ck_assert(sim_world_pose(&g_world, 0).theta_rad > 0.0);
}
END_TEST

/* ---------------------------------------------------------------------------------------------
 * Scenario and robot files
 * ------------------------------------------------------------------------------------------- */
START_TEST(every_catalog_effect_has_an_example_scenario_that_enables_only_it)
{
    size_t n = 0;
    const sim_effect_def_t *cat = sim_effects_catalog(&n);
    ck_assert_uint_eq(n, SIM_EFFECT_COUNT);
    for (size_t i = 0; i < n; ++i) {
        ck_assert_int_eq((int)cat[i].id, (int)i);
        char name[64];
        snprintf(name, sizeof name, "effect-%s", cat[i].name);
        sim_scenario_t sc;
        load_scenario(name, &sc);
        bool on[SIM_EFFECT_COUNT];
        sim_scenario_enabled_list(&sc, on);
        for (size_t k = 0; k < n; ++k) {
            ck_assert_msg(on[k] == (k == i), "%s: effect %s enabled=%d", name, cat[k].name, (int)on[k]);
        }
        for (size_t k = 0; k < cat[i].n_params; ++k) { /* defaults lie in their own ranges */
            ck_assert(cat[i].params[k].def >= cat[i].params[k].min && cat[i].params[k].def <= cat[i].params[k].max);
        }
    }
    sim_scenario_t sc;
    load_scenario("none", &sc);
    for (size_t k = 0; k < n; ++k) {
        ck_assert(!sim_scenario_enabled(&sc, (sim_effect_id_t)k));
    }
    load_scenario("set-sim", &sc);
    ck_assert_double_eq_tol(sim_scenario_param_named(&sc, "eb", "value", 0), 337.0 / 340.0, 1e-15);
    ck_assert_double_eq_tol(sim_scenario_param_named(&sc, "ed", "value", 1), 0.9985, 1e-15);
    ck_assert(sim_scenario_enabled(&sc, SIM_EFFECT_ROUGHNESS) && !sim_scenario_enabled(&sc, SIM_EFFECT_BUMPS));
    load_scenario("effect-bumps", &sc);
    ck_assert_uint_eq(sc.n_bumps, 3U);
    FILE *null = fopen("/dev/null", "w");
    ck_assert_ptr_nonnull(null);
    ck_assert_int_eq(sim_effects_write_json(null), 0);
    ck_assert_int_eq(sim_effects_write_markdown(null), 0);
    fclose(null);
}
END_TEST

static void expect_scenario_error(const char *json, const char *const *needles)
{
    sim_scenario_t sc;
    char err[512] = "";
    ck_assert_int_eq(sim_scenario_parse_string(json, "bad.json", &sc, err, sizeof err), -1);
    for (const char *const *n = needles; *n != NULL; ++n) {
        ck_assert_msg(strstr(err, *n) != NULL, "message '%s' lacks '%s'", err, *n);
    }
}

START_TEST(bad_scenarios_are_refused_with_the_file_effect_and_parameter_named)
{
    expect_scenario_error("{\"effects\": {\"wobble\": {}}}",
                          (const char *const[]){"bad.json", "effects.wobble", "unknown effect", "roughness", NULL});
    expect_scenario_error("{\"effects\": {\"ed\": {\"valu\": 1.0}}}",
                          (const char *const[]){"bad.json", "effects.ed.valu", "unknown parameter", "value", NULL});
    expect_scenario_error("{\"effects\": {\"ed\": {\"value\": 1.5}}}",
                          (const char *const[]){"effects.ed.value", "out of range", "1.25", NULL});
    expect_scenario_error("{\"effects\": {\"roughness\": {\"spacing_mm\": \"20\"}}}",
                          (const char *const[]){"effects.roughness.spacing_mm", "expected a number", "string", NULL});
    expect_scenario_error("{\"effects\": {\"bumps\": {\"model\": \"approx\"}}}",
                          (const char *const[]){"effects.bumps.model", "paper|exact", NULL});
    expect_scenario_error("{\"effects\": {\"ed\": [{\"value\": 1.01}, {\"truck\": \"B\", \"value\": 0.99}]}}",
                          (const char *const[]){"effects.ed[1]", "truck B is set twice", NULL});
    expect_scenario_error("{\"effects\": {\"link_bias\": {\"truck\": \"A\"}}}",
                          (const char *const[]){"effects.link_bias.truck", "vehicle effect", NULL});
    expect_scenario_error("{\"effects\": {\"ed\": {\"value\": 1.0,}}}",
                          (const char *const[]){"bad.json", "malformed JSON", "line 1", NULL});
    expect_scenario_error("{\"seed\": -3, \"effects\": {}}", (const char *const[]){"seed", NULL});
    expect_scenario_error("{\"efects\": {}}", (const char *const[]){"efects", "unknown key", NULL});
    expect_scenario_error("[]", (const char *const[]){"JSON object", NULL});
    expect_scenario_error("{\"effects\": {\"bumps\": {\"at\": [{\"truck\": \"A\", \"wheel\": \"middle\", "
                          "\"distance_mm\": 5}]}}}",
                          (const char *const[]){"effects.bumps.at[0].wheel", "left", NULL});

    sim_scenario_t sc;
    char err[512];
    ck_assert_int_eq(sim_scenario_parse_file("/nonexistent/scenario.json", &sc, err, sizeof err), -1);
    ck_assert_ptr_nonnull(strstr(err, "/nonexistent/scenario.json"));
    ck_assert_ptr_nonnull(strstr(err, "No such file"));

    /* Per-truck instances and "enabled": false parse as documented. */
    must(sim_scenario_parse_string("{\"seed\": 9, \"bump_model\": \"paper\", \"effects\": {"
                                   "\"ed\": [{\"truck\": \"A\", \"value\": 1.01}, {\"truck\": \"B\", \"value\": 0.99}],"
                                   "\"es\": {\"value\": 1.01, \"enabled\": false}}}",
                                   "ok.json", &sc, err, sizeof err),
         err);
    ck_assert(sc.has_seed && sc.seed == 9U);
    ck_assert(sim_scenario_enabled_on(&sc, SIM_EFFECT_ED, 0) && sim_scenario_enabled_on(&sc, SIM_EFFECT_ED, 1));
    ck_assert_double_eq(sim_scenario_param(&sc, SIM_EFFECT_ED, 1, 0), 0.99);
    ck_assert(!sim_scenario_enabled(&sc, SIM_EFFECT_ES));
    ck_assert_double_eq(sim_scenario_param(&sc, SIM_EFFECT_BUMPS, 0, SIM_P_BUMPS_MODEL), (double)SIM_BUMP_PAPER);
    ck_assert_int_eq(sim_scenario_set(&sc, "ed", "value", 1U, 2.0, err, sizeof err), -1);
    ck_assert_ptr_nonnull(strstr(err, "out of range"));
}
END_TEST

START_TEST(robot_descriptions_convert_to_parameter_blocks_the_firmware_accepts)
{
    const char *names[] = {"labmate", "clapper", "set"};
    const uint8_t vehicles[] = {ODO_VEHICLE_SINGLE, ODO_VEHICLE_CLAPPER, ODO_VEHICLE_SET};
    for (int i = 0; i < 3; ++i) {
        sim_robot_t r;
        odo_params_t p;
        char err[256];
        load_robot(names[i], &r);
        must(sim_robot_to_params(&r, &p, err, sizeof err), err);
        ck_assert_int_eq(odo_params_validate(&p, NULL, NULL), ODO_PARAMS_OK);
        ck_assert_uint_eq(p.vehicle, vehicles[i]);
        ck_assert_uint_eq(p.truck[0].wheel_diameter_nm, 150000000U);
        ck_assert_uint_eq(p.truck[0].counts_per_rev_milli, 39000000U); /* 4 * 500 * 19.5 */
        ck_assert_uint_eq(p.truck[0].wheelbase_nm, 340000000U);
        ck_assert_int_eq(p.truck[0].ed_q30, ODO_RATIO_Q30_ONE);
        ck_assert_uint_eq(p.tick_us, 40000U);
        ck_assert_uint_eq(p.link.rotary_bits, 10U);
        /* The stock description equals the built-in default for that vehicle. */
        sim_robot_t d;
        ck_assert_int_eq(sim_robot_default(r.vehicle, &d), 0);
        odo_params_t pd;
        must(sim_robot_to_params(&d, &pd, err, sizeof err), err);
        ck_assert(memcmp(&p, &pd, sizeof p) == 0);
    }
    sim_robot_t r;
    odo_params_t p;
    char err[256];
    load_robot("set", &r);
    must(sim_robot_to_params(&r, &p, err, sizeof err), err);
    ck_assert_uint_eq(p.link.length_nm, 500000000U);
    ck_assert_uint_eq(p.link.hitch_offset_nm, 300000000U);
    ck_assert_uint_eq(p.truck[1].counts_per_rev_milli, 4000000U);

    /* A calibration block lands in the Q30 ratios. */
    must(sim_robot_parse_string("{\"vehicle\": \"labmate\", \"trucks\": {\"A\": {\"wheel_diameter_mm\": 150, "
                                "\"wheelbase_mm\": 340, \"encoder_lines\": 500, \"gear_ratio\": 19.5, "
                                "\"calibration\": {\"ed\": 1.0015, \"eb\": 0.99}}}}",
                                "cal.json", &r, err, sizeof err),
         err);
    must(sim_robot_to_params(&r, &p, err, sizeof err), err);
    ck_assert_int_eq(p.truck[0].ed_q30, (int32_t)llround(1.0015 * 1073741824.0));
    ck_assert_int_eq(p.truck[0].eb_q30, (int32_t)llround(0.99 * 1073741824.0));
    ck_assert_int_eq(p.truck[0].es_q30, ODO_RATIO_Q30_ONE);
    ck_assert_int_eq(p.truck[0].scrub_q30, 0);

    /* ... and "scrub", k of the firmware's tyre-scrub term, in scrub_q30 (|k| <= 0.25). */
    must(sim_robot_parse_string("{\"vehicle\": \"labmate\", \"trucks\": {\"A\": {\"wheel_diameter_mm\": 150, "
                                "\"wheelbase_mm\": 340, \"encoder_lines\": 500, \"gear_ratio\": 19.5, "
                                "\"calibration\": {\"eb\": 1.0065, \"scrub\": -0.0095}}}}",
                                "scrub.json", &r, err, sizeof err),
         err);
    must(sim_robot_to_params(&r, &p, err, sizeof err), err);
    ck_assert_int_eq(p.truck[0].scrub_q30, (int32_t)llround(-0.0095 * 1073741824.0));
    ck_assert_int_eq(p.truck[0].eb_q30, (int32_t)llround(1.0065 * 1073741824.0));
    ck_assert_int_ne(sim_robot_parse_string("{\"vehicle\": \"labmate\", \"trucks\": {\"A\": {\"wheel_diameter_mm\": "
                                            "150, \"wheelbase_mm\": 340, \"encoder_lines\": 500, \"gear_ratio\": "
                                            "19.5, \"calibration\": {\"scrub\": 0.3}}}}",
                                            "scrub.json", &r, err, sizeof err),
                     0);
    ck_assert_ptr_nonnull(strstr(err, "trucks.A.calibration.scrub"));
    load_robot("labmate", &r);
    r.truck[0].cal_scrub = -0.26; /* built in code: caught by odo_params_validate, named */
    ck_assert_int_eq(sim_robot_to_params(&r, &p, err, sizeof err), -1);
    ck_assert_ptr_nonnull(strstr(err, "trucks.A.calibration.scrub"));

    /* An out-of-range value built in code is caught by odo_params_validate and named. */
    load_robot("labmate", &r);
    r.truck[0].wheelbase_mm = 20.0;
    ck_assert_int_eq(sim_robot_to_params(&r, &p, err, sizeof err), -1);
    ck_assert_ptr_nonnull(strstr(err, "trucks.A.wheelbase_mm"));
}
END_TEST

static void expect_robot_error(const char *json, const char *const *needles)
{
    sim_robot_t r;
    char err[512] = "";
    ck_assert_int_eq(sim_robot_parse_string(json, "robot.json", &r, err, sizeof err), -1);
    for (const char *const *n = needles; *n != NULL; ++n) {
        ck_assert_msg(strstr(err, *n) != NULL, "message '%s' lacks '%s'", err, *n);
    }
}

#define TRUCK "{\"wheel_diameter_mm\": 150, \"wheelbase_mm\": 340, \"encoder_lines\": 500, \"gear_ratio\": 19.5"
START_TEST(bad_robot_descriptions_are_refused_with_the_field_named)
{
    expect_robot_error("{\"vehicle\": \"tank\"}", (const char *const[]){"robot.json", "vehicle", "\"tank\"", NULL});
    expect_robot_error("{\"vehicle\": \"labmate\", \"trucks\": {\"A\": {\"wheelbase_mm\": 340}}}",
                       (const char *const[]){"trucks.A.wheel_diameter_mm", "missing", NULL});
    expect_robot_error("{\"vehicle\": \"labmate\", \"trucks\": {\"A\": " TRUCK ", \"counter_bits\": 7}}}",
                       (const char *const[]){"trucks.A.counter_bits", "out of range [8, 32]", NULL});
    expect_robot_error("{\"vehicle\": \"labmate\", \"trucks\": {\"A\": " TRUCK ", \"wheelbase\": 3}}}",
                       (const char *const[]){"trucks.A.wheelbase", "unknown key", NULL});
    expect_robot_error("{\"vehicle\": \"labmate\", \"trucks\": {\"A\": {\"wheel_diameter_mm\": 150, "
                       "\"wheelbase_mm\": 340, \"encoder_lines\": 2.5, \"gear_ratio\": 19.5}}}",
                       (const char *const[]){"trucks.A.encoder_lines", "expected an integer", NULL});
    expect_robot_error("{\"vehicle\": \"labmate\", \"trucks\": {\"A\": " TRUCK "}, \"B\": " TRUCK "}}}",
                       (const char *const[]){"trucks.B", "unknown key", NULL});
    expect_robot_error("{\"vehicle\": \"clapper\", \"trucks\": {\"A\": " TRUCK "}, \"B\": " TRUCK
                       ", \"counter_bits\": 16}}, "
                       "\"linkage\": {\"length_mm\": 1000}}",
                       (const char *const[]){"trucks.B.counter_bits", "one counter width", NULL});
    expect_robot_error("{\"vehicle\": \"clapper\", \"trucks\": {\"A\": " TRUCK "}, \"B\": " TRUCK "}}}",
                       (const char *const[]){"linkage", "missing", NULL});
    expect_robot_error("{\"vehicle\": \"labmate\", \"trucks\": {\"A\": " TRUCK ", \"calibration\": {\"ed\": 2}}}}",
                       (const char *const[]){"trucks.A.calibration.ed", "out of range", NULL});
    expect_robot_error("{\"vehicle\": \"labmate\", \"trailer\": {}, \"trucks\": {\"A\": " TRUCK "}}}",
                       (const char *const[]){"trailer", "only a set", NULL});
    expect_robot_error("{\"vehicle\": \"labmate\", \"tick_ms\": \"40\", \"trucks\": {\"A\": " TRUCK "}}}",
                       (const char *const[]){"tick_ms", "expected a number", NULL});
    expect_robot_error("{\"vehicle\": \"labmate\" \"trucks\": {}}",
                       (const char *const[]){"malformed JSON", "line 1", NULL});
    sim_robot_t r;
    char err[512];
    ck_assert_int_eq(sim_robot_parse_file("/nonexistent/robot.json", &r, err, sizeof err), -1);
    ck_assert_ptr_nonnull(strstr(err, "/nonexistent/robot.json"));
}
END_TEST

static Suite *suite(void)
{
    Suite *s = suite_create("host_sim world");
    TCase *tc = tcase_create("world");
    tcase_set_timeout(tc, 120);
    tcase_add_test(tc, table_I_of_004_reproduced_with_paper_formulas_and_exact_geometry);
    tcase_add_test(tc, bump_profile_builds_the_error_up_gradually_over_the_bump);
    tcase_add_test(tc, straight_run_over_one_bump_turns_toward_the_bumped_wheel_by_dtheta);
    tcase_add_test(tc, ed_above_one_makes_a_straight_command_curve_left);
    tcase_add_test(tc, eb_scales_on_the_spot_turns_by_one_over_eb);
    tcase_add_test(tc, scrub_leaves_spot_turns_to_eb_and_widens_the_wheelbase_on_arcs);
    tcase_add_test(tc, es_makes_the_true_distance_the_calculated_one_over_es);
    tcase_add_test(tc, uni_directional_square_hides_compensating_ed_and_eb_that_umbmark_exposes);
    tcase_add_test(tc, same_seed_gives_bit_identical_worlds_and_another_seed_differs);
    tcase_add_test(tc, set_trailer_follows_the_robot_and_its_encoders_count_its_travel);
    tcase_add_test(tc, clapper_linkage_geometry_follows_002_eq_10_11_16_and_clamps_at_its_range);
    tcase_add_test(tc, clapper_stop_replayed_over_a_track_pushes_half_way_and_obeys_its_gate);
    tcase_add_test(tc, rate_limiter_follows_its_input_by_at_most_the_limit);
    tcase_add_test(tc, world_refuses_bad_steps_and_bumps);
    tcase_add_test(tc, tire_compression_with_an_offset_load_acts_like_an_ed);
    tcase_add_test(tc, every_catalog_effect_has_an_example_scenario_that_enables_only_it);
    tcase_add_test(tc, bad_scenarios_are_refused_with_the_file_effect_and_parameter_named);
    tcase_add_test(tc, robot_descriptions_convert_to_parameter_blocks_the_firmware_accepts);
    tcase_add_test(tc, bad_robot_descriptions_are_refused_with_the_field_named);
    suite_add_tcase(s, tc);
    return s;
}

int main(void) { return ts_run_suite(suite()); }
