/// libodosim: the robot-description contract and the firmware's odometry step for tools
/// (odosim.h: odosim_robot_describe, odosim_robot_limits_json, odosim_firmware_track).
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "odo/odo_app.h"
#include "odosim/odosim.h"
#include "robot.h"

char *odosim_robot_describe(const char *robot_path, char *err, size_t errlen)
{
    static const char *const flds[] = {"wheel_diameter_mm", "wheelbase_mm", "encoder_lines", "gear_ratio"};
    sim_robot_t *r = calloc(1, sizeof *r);
    odo_params_t p;
    if (r == NULL) {
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    if (sim_robot_parse_file(robot_path, r, err, errlen) != 0) {
        free(r);
        return NULL;
    }
    if (sim_robot_to_params(r, &p, err, errlen) != 0) {
        /* "robot: <field>: <why>" -> "<path>: <field>: <why>", as the parser's messages read */
        char tmp[1024];
        snprintf(tmp, sizeof tmp, "%s", strncmp(err, "robot: ", 7) == 0 ? err + 7 : err);
        snprintf(err, errlen, "%s: %s", robot_path, tmp);
        free(r);
        return NULL;
    }
    json_t *o = json_object();
    json_object_set_new(o, "vehicle", json_string(sim_vehicle_name(r->vehicle)));
    json_object_set_new(o, "tick_ms", json_real(r->tick_ms));
    json_object_set_new(o, "heading_form", json_integer(r->heading_form));
    json_object_set_new(o, "max_wheel_speed_mm_s", json_real(r->max_wheel_speed_mm_s));
    json_t *trucks = json_array();
    for (unsigned t = 0; t < r->n_trucks; ++t) {
        const sim_truck_desc_t *d = &r->truck[t];
        const double v[] = {d->wheel_diameter_mm, d->wheelbase_mm, (double)d->encoder_lines, d->gear_ratio};
        json_t *j = json_object();
        for (size_t k = 0; k < 4; ++k) {
            json_object_set_new(j, flds[k], json_real(v[k]));
        }
        json_object_set_new(j, "counter_bits", json_integer(d->counter_bits));
        json_object_set_new(j, "invert_left", json_boolean(d->invert_left));
        json_object_set_new(j, "invert_right", json_boolean(d->invert_right));
        json_object_set_new(j, "ed", json_real(d->cal_ed));
        json_object_set_new(j, "eb", json_real(d->cal_eb));
        json_object_set_new(j, "es", json_real(d->cal_es));
        json_object_set_new(j, "scrub", json_real(d->cal_scrub));
        json_array_append_new(trucks, j);
    }
    json_object_set_new(o, "trucks", trucks);
    if (r->vehicle == SIM_VEHICLE_CLAPPER) {
        json_object_set_new(o, "linkage",
                            json_pack("{s:f, s:[f, f], s:i, s:f}", "length_mm", r->link.length_mm, "range_mm",
                                      r->link.min_mm, r->link.max_mm, "rotary_bits", (json_int_t)r->link.rotary_bits,
                                      "linear_resolution_mm", r->link.linear_resolution_mm));
    } else if (r->vehicle == SIM_VEHICLE_SET) {
        json_object_set_new(o, "trailer",
                            json_pack("{s:f, s:f, s:i}", "hitch_offset_mm", r->set.hitch_offset_mm, "trailer_length_mm",
                                      r->set.trailer_length_mm, "rotary_bits", (json_int_t)r->link.rotary_bits));
    }
    char *s = json_dumps(o, JSON_COMPACT);
    json_decref(o);
    free(r);
    if (s == NULL) {
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    /* json_dumps allocates with jansson's allocator (malloc by default), released by odosim_free. */
    return s;
}

char *odosim_robot_limits_json(void)
{
    size_t n = 0;
    const sim_robot_limit_t *l = sim_robot_limits(&n);
    json_t *a = json_array();
    for (size_t i = 0; i < n; ++i) {
        json_array_append_new(
            a, json_pack("{s:s, s:f, s:f, s:s}", "key", l[i].key, "lo", l[i].lo, "hi", l[i].hi, "unit", l[i].unit));
    }
    char *s = json_dumps(a, JSON_COMPACT);
    json_decref(a);
    return s;
}

int odosim_firmware_track(const char *robot_path, const uint32_t *raw, size_t n, double *pose, char *err, size_t errlen)
{
    sim_robot_t *r = calloc(1, sizeof *r);
    odo_app_t *app = calloc(1, sizeof *app);
    odo_params_t p;
    int rc = 0;
    if (r == NULL || app == NULL) {
        snprintf(err, errlen, "out of memory");
        rc = -1;
    } else if (sim_robot_parse_file(robot_path, r, err, errlen) != 0 || sim_robot_to_params(r, &p, err, errlen) != 0) {
        rc = -1;
    } else if (r->n_trucks != 1U) {
        snprintf(err, errlen, "%s: odosim_firmware_track runs a one-truck robot (this is a %s)", robot_path,
                 sim_vehicle_name(r->vehicle));
        rc = -1;
    } else if (odo_app_init_params(app, &p) != ODO_PARAMS_OK) {
        snprintf(err, errlen, "%s: the firmware refuses the robot's parameter block", robot_path);
        rc = -1;
    }
    /* The firmware's step, tick by tick, on the counters as the decoder holds them; the heading
     * is unwrapped from the step's own heading changes (the pose's heading wraps every turn). */
    double theta = 0.0;
    for (size_t i = 0; i < n && rc == 0; ++i) {
        odo_tick_input_t in;
        odo_tick_output_t out;
        memset(&in, 0, sizeof in);
        in.t_us = (uint64_t)i * p.tick_us;
        in.wheel[0].present = true;
        in.wheel[0].bits = p.counter_bits;
        in.wheel[0].seq = (uint8_t)i;
        in.wheel[0].left_raw = raw[2 * i];
        in.wheel[0].right_raw = raw[2 * i + 1];
        odo_app_step(app, &in, &out);
        theta += (double)out.dturn_q64[0] / 18446744073709551616.0 * 2.0 * M_PI;
        pose[3 * i] = (double)out.pose[0].x_mm_q32 / 4294967296.0;
        pose[3 * i + 1] = (double)out.pose[0].y_mm_q32 / 4294967296.0;
        pose[3 * i + 2] = theta;
    }
    free(r);
    free(app);
    return rc;
}
