/// Host side of the target self-test check: the image's boot self-test (hal/cortexm/odo_selftest.c,
/// the same source) on the host, from a parameter block read from a file (the bytes of the image's
/// .odo_params section). Prints the result as one line of key=value pairs, in the order and format
/// tests/target/run_target_test.py prints the values it reads from the image's RAM under qemu.
/// Usage: selftest_host BLOCK.bin
///        selftest_host --codes   the status and fault codes the comparison expects, from the
///                                firmware's headers (so the runner retypes none of them)
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "odo/odo_params.h"
#include "odo/odo_status.h"
#include "odo_bxcan.h"
#include "odo_clock.h"
#include "odo_selftest.h"

static odo_app_t app;
static odo_tick_input_t in;
static odo_tick_output_t out;

int main(int argc, char **argv)
{
    if (argc == 2 && strcmp(argv[1], "--codes") == 0) {
        printf("params_ok=%d params_err_magic=%d params_err_crc=%d fault_params_defaulted=%lu "
               "selftest_done=%lu clock_hsi=%d clock_hsi_hz=%lu bxcan_err_init_mode=%d\n",
               (int)ODO_PARAMS_OK, (int)ODO_PARAMS_ERR_MAGIC, (int)ODO_PARAMS_ERR_CRC,
               (unsigned long)ODO_FAULT_PARAMS_DEFAULTED, (unsigned long)ODO_BOARD_SELFTEST_DONE, (int)ODO_CLOCK_HSI,
               (unsigned long)ODO_CLOCK_HSI_HZ, (int)ODO_BXCAN_ERR_INIT_MODE);
        return 0;
    }
    if (argc != 2) {
        fprintf(stderr, "usage: %s BLOCK.bin (the image's .odo_params bytes)\n", argv[0]);
        return 2;
    }
    FILE *f = fopen(argv[1], "rb");
    if (f == NULL) {
        perror(argv[1]);
        return 2;
    }
    static uint8_t block[4096];
    const size_t len = fread(block, 1, sizeof block, f);
    const int bad = ferror(f);
    fclose(f);
    if (bad != 0) {
        fprintf(stderr, "%s: read error\n", argv[1]);
        return 2;
    }
    odo_board_selftest_t r;
    odo_selftest_run(&app, &in, &out, block, len, &r);
    printf("params_status=%lu steps=%lu faults_or=0x%08lx frames=%lu x_mm_q32=%lld y_mm_q32=%lld "
           "heading_bam=0x%08lx done=0x%08lx\n",
           (unsigned long)r.params_status, (unsigned long)r.steps, (unsigned long)r.faults_or, (unsigned long)r.frames,
           (long long)r.x_mm_q32, (long long)r.y_mm_q32, (unsigned long)r.heading_bam, (unsigned long)r.done);
    return 0;
}
