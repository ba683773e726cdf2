/// Helpers shared by tests: a seeded PRNG (splitmix64) and counter wrapping. Host-only.
#ifndef TEST_SUPPORT_H
#define TEST_SUPPORT_H

#include <stdint.h>

typedef struct {
    uint64_t state;
} ts_rng_t;

/// Seed the generator; the same seed gives the same sequence on every platform.
void ts_rng_seed(ts_rng_t *r, uint64_t seed);
uint64_t ts_rng_u64(ts_rng_t *r);
/// Uniform in [lo, hi).
double ts_rng_uniform(ts_rng_t *r, double lo, double hi);
/// Uniform integer in [lo, hi] (inclusive).
int64_t ts_rng_range(ts_rng_t *r, int64_t lo, int64_t hi);

/// The low `bits` bits of a cumulative count, as a counter of that width would show it.
uint32_t ts_wrap_counter(int64_t count, uint8_t bits);

#endif
