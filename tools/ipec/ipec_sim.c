/// odo-ipec's shared helpers (ipec_sim.h): the data root, robots and scenarios, one SIL run.
#include "ipec_sim.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>

#include "odo_data_dir.h"

static char g_src[PATH_MAX - 256];

const char *ipec_src_dir(void)
{
    if (g_src[0] == '\0') {
        (void)odo_data_path(".", g_src, sizeof g_src); /* "" if too long: paths then fail to open */
    }
    return g_src;
}

int ipec_load(const char *vehicle, const char *robot_path, const char *scenario_path, sim_robot_t *robot,
              odosim_scenario_t *sc)
{
    char path[PATH_MAX];
    char err[512];
    if (robot_path == NULL) {
        snprintf(path, sizeof path, "%s/host_sim/robots/%s.json", ipec_src_dir(), vehicle);
        robot_path = path;
    }
    if (sim_robot_parse_file(robot_path, robot, err, sizeof err) != 0) {
        fprintf(stderr, "odo-ipec: %s\n", err);
        return -1;
    }
    if (scenario_path == NULL) {
        odosim_scenario_clear(sc);
        return 0;
    }
    if (odosim_scenario_load(sc, scenario_path, err, sizeof err) != 0) {
        fprintf(stderr, "odo-ipec: %s\n", err);
        return -1;
    }
    return 0;
}

int ipec_run(const sim_robot_t *robot, const odosim_scenario_t *sc, const char *experiment, int ccw, int bumps,
             int ipec, uint64_t seed, unsigned run, odosim_tick_fn fn, void *user, odosim_return_t *ret)
{
    char err[512];
    const odosim_sil_config_t cfg = {
        .robot = robot,
        .scenario = sc,
        .experiment = experiment,
        .ccw = ccw,
        .bumps = bumps,
        .bump_height_mm = 10.0,
        .ipec = ipec,
        .seed = odosim_run_seed(seed, ccw, run),
        .run_index = run,
    };
    if (odosim_sil_run(&cfg, fn, user, ret, err, sizeof err) != 0) {
        fprintf(stderr, "odo-ipec: %s\n", err);
        return -1;
    }
    return 0;
}

double ipec_bam_deg(int64_t bam) { return (double)bam * (360.0 / 4294967296.0); }

double ipec_est_theta_deg(const odo_pose_t *p) { return ipec_bam_deg((int32_t)odo_heading_bam(p)); }
