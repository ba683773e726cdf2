/// The Cortex-M4 side of `make bench-target`: the firmware's public API (odo_app_init,
/// odo_app_step) behind two entry points that odo-bench-target calls in the unicorn emulator, and
/// a main() for qemu's mps2-an386 (semihosting) that runs the same calls over a ticks file, for
/// the once-only cross-check of the instruction counts with qemu's execution log.
///
/// Only the instructions between entry to odo_app_init/odo_app_step and their return are counted;
/// unpacking and packing around them are not.
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "bench_codec.h"
#include "odo/odo_app.h"

/// Large enough for any parameter-block version this firmware may grow to.
#define ODO_BENCH_BLOCK_MAX 1024U

uint8_t odo_bench_block[ODO_BENCH_BLOCK_MAX];
uint8_t odo_bench_in[ODO_BENCH_IN_SIZE];
uint8_t odo_bench_out[ODO_BENCH_OUT_SIZE];

static odo_app_t s_app;
static odo_tick_input_t s_in;
static odo_tick_output_t s_out;

uint32_t odo_bench_init(uint32_t len);
void odo_bench_step(void);

/// Boot on odo_bench_block[0..len). Returns the odo_params_status_t.
__attribute__((noinline)) uint32_t odo_bench_init(uint32_t len)
{
    return (uint32_t)odo_app_init(&s_app, odo_bench_block, len);
}

/// One tick: odo_bench_in -> odo_app_step -> odo_bench_out.
__attribute__((noinline)) void odo_bench_step(void)
{
    odo_bench_unpack_input(odo_bench_in, &s_in);
    odo_app_step(&s_app, &s_in, &s_out);
    odo_bench_pack_output(&s_out, odo_bench_out);
}

static uint32_t le32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

/// qemu mode: every tick of odo_ticks.bin (a ticks file, bench_codec.h) from qemu's working
/// directory, read through semihosting. Exit 0 iff every output equals the host's.
int main(void)
{
    FILE *f = fopen("odo_ticks.bin", "rb");
    uint8_t hdr[16];
    if (f == NULL || fread(hdr, 1, sizeof hdr, f) != sizeof hdr || memcmp(hdr, ODO_BENCH_FILE_MAGIC, 4) != 0) {
        puts("odo_bench: cannot read odo_ticks.bin");
        return 2;
    }
    const uint32_t n = le32(hdr + 8), blen = le32(hdr + 12);
    if (blen > ODO_BENCH_BLOCK_MAX || fread(odo_bench_block, 1, blen, f) != blen) {
        puts("odo_bench: bad parameter block");
        return 2;
    }
    (void)odo_bench_init(blen);
    static uint8_t want[ODO_BENCH_OUT_SIZE];
    uint32_t bad = 0U, run = 0U;
    for (uint32_t i = 0U; i < n; ++i) {
        if (fread(odo_bench_in, 1, sizeof odo_bench_in, f) != sizeof odo_bench_in ||
            fread(want, 1, sizeof want, f) != sizeof want) {
            puts("odo_bench: truncated ticks file");
            return 2;
        }
        odo_bench_step();
        bad += memcmp(want, odo_bench_out, sizeof want) != 0 ? 1U : 0U;
        run++;
    }
    fclose(f);
    printf("odo_bench: %lu ticks, %lu outputs differ from the host's\n", (unsigned long)run, (unsigned long)bad);
    return bad == 0U ? 0 : 1;
}
