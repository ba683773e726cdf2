/// odo-calib-fixture-elf: a host program that carries the default parameter block in its own
/// `.odo_params` section, generated at build time by hal/cortexm/gen_param_block.c exactly as the
/// Cortex-M image's is. Tests patch it with `odo-calib write` and run it: it exits 0 iff the
/// firmware's boot rule accepts the block it carries, and prints truck A's Ed, Eb and scrub k in
/// Q30.
#include <stdio.h>

#include "odo/odo_params.h"
#include "odo_board.h"

int main(void)
{
    odo_params_t p;
    const odo_params_status_t st = odo_params_load(odo_param_block, ODO_PARAMS_SIZE, &p);
    printf("%s %ld %ld %ld\n", odo_params_status_str(st), (long)p.truck[0].ed_q30, (long)p.truck[0].eb_q30,
           (long)p.truck[0].scrub_q30);
    return st == ODO_PARAMS_OK ? 0 : 1;
}
