/// libFuzzer harness: the simulator's robot description and scenario JSON (host_sim/src/robot.h,
/// effects.h): one validator each, the limits table the Python tools use too. Any text: an error
/// naming the origin, or a description that converts to a parameter block the firmware accepts.
#include "effects.h"
#include "fuzz_common.h"
#include "robot.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static sim_robot_t r;
    static sim_scenario_t sc;
    char err[512];
    char *text = fuzz_string(data, size);
    if (sim_robot_parse_string(text, "fuzz.json", &r, err, sizeof err) == 0) {
        odo_params_t p;
        if (sim_robot_to_params(&r, &p, err, sizeof err) == 0 && odo_params_validate(&p, NULL, NULL) != ODO_PARAMS_OK) {
            abort();
        }
    }
    (void)sim_scenario_parse_string(text, "fuzz.json", &sc, err, sizeof err);
    free(text);
    return 0;
}
