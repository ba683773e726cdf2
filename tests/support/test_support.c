#include "test_support.h"

void ts_rng_seed(ts_rng_t *r, uint64_t seed) { r->state = seed; }

uint64_t ts_rng_u64(ts_rng_t *r)
{
    /* splitmix64 (Steele, Lea, Flood 2014): tiny, full period, good enough for test inputs. */
    uint64_t z = (r->state += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

double ts_rng_uniform(ts_rng_t *r, double lo, double hi)
{
    return lo + (hi - lo) * ((double)(ts_rng_u64(r) >> 11) * (1.0 / 9007199254740992.0));
}

int64_t ts_rng_range(ts_rng_t *r, int64_t lo, int64_t hi)
{
    uint64_t span = (uint64_t)(hi - lo) + 1U;
    return span == 0U ? (int64_t)ts_rng_u64(r) : lo + (int64_t)(ts_rng_u64(r) % span);
}

uint32_t ts_wrap_counter(int64_t count, uint8_t bits)
{
    uint64_t mask = bits >= 32U ? 0xFFFFFFFFULL : ((1ULL << bits) - 1U);
    return (uint32_t)((uint64_t)count & mask);
}
