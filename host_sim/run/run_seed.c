#include "sil.h"

uint64_t sim_run_seed(uint64_t base, int ccw, unsigned run)
{
    /* splitmix64 finaliser over the base seed, the direction and the run number */
    uint64_t z = base * 0x9E3779B97F4A7C15ULL + (uint64_t)(ccw ? 1 : 0) * 0xBF58476D1CE4E5B9ULL + run;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}
