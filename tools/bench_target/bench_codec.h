/// Portable byte form of one 40 ms tick's input and output, for the Cortex-M4 benchmark
/// (`make bench-target`, tools/bench_target/README.md): the host writes the inputs its replay of a
/// recorded run assembled and the outputs its own build produced; the emulated M4 unpacks the same
/// input bytes, runs odo_app_step and packs its output, and the two output byte strings must be
/// identical. Explicit little-endian fields, so struct padding and ABI never enter the comparison.
#ifndef ODO_BENCH_CODEC_H
#define ODO_BENCH_CODEC_H

#include <stdint.h>

#include "odo/odo_app.h"

#ifdef __cplusplus
extern "C" {
#endif

/// Bytes of a packed odo_tick_input_t: t_us, rx_faults, two wheel samples, the link sample.
#define ODO_BENCH_IN_SIZE  (8U + 4U + 2U * 12U + 16U)
/// Bytes of a packed odo_tick_output_t: poses, IPEC and dead-reckoning fields, faults, frames.
#define ODO_BENCH_OUT_SIZE (2U * 24U + 4U * 4U + 1U + 2U * 16U + 4U + 1U + ODO_APP_MAX_FRAMES * 14U)

/// Ticks file written by odo-target-ticks and read by odo-bench-target: "ODOT", version, tick
/// count, parameter-block length, the block, then per tick ODO_BENCH_IN_SIZE input bytes and
/// ODO_BENCH_OUT_SIZE bytes of the host's output (all counts little-endian uint32).
#define ODO_BENCH_FILE_MAGIC   "ODOT"
#define ODO_BENCH_FILE_VERSION 1U

void odo_bench_pack_input(const odo_tick_input_t *in, uint8_t buf[ODO_BENCH_IN_SIZE]);
void odo_bench_unpack_input(const uint8_t buf[ODO_BENCH_IN_SIZE], odo_tick_input_t *in);
void odo_bench_pack_output(const odo_tick_output_t *out, uint8_t buf[ODO_BENCH_OUT_SIZE]);

#ifdef __cplusplus
}
#endif
#endif
