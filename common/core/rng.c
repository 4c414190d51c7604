/* rng.c -- PCG32's seeding and the less frequent draws (pcg32_next and
 * pcg32_float are inline in rng.h). Checked against the reference
 * implementation's published output in tests/test_common.c. */
#include "rng.h"

void pcg32_seed(pcg32 *rng, uint64_t initial_state, uint64_t stream)
{
    rng->state = 0u;
    rng->increment = (stream << 1u) | 1u;
    pcg32_next(rng);
    rng->state += initial_state;
    pcg32_next(rng);
}

double pcg32_double(pcg32 *rng)
{
    uint64_t high = pcg32_next(rng) >> 5; /* 27 bits */
    uint64_t low = pcg32_next(rng) >> 6;  /* 26 bits */
    return (double)((high << 26) | low) * 0x1.0p-53;
}

uint32_t pcg32_bounded(pcg32 *rng, uint32_t bound)
{
    /* Reject the few values that would make small results more likely. */
    uint32_t threshold = (-bound) % bound;
    for (;;) {
        uint32_t r = pcg32_next(rng);
        if (r >= threshold)
            return r % bound;
    }
}

/* SplitMix64's finaliser: neighbouring inputs give unrelated outputs. PCG
 * streams that differ only in their increment are known to be correlated when
 * started from the same state, so each pixel also gets a hashed start state. */
static uint64_t mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

pcg32 pcg32_for_pixel(uint64_t seed, uint64_t pixel_index)
{
    pcg32 rng;
    pcg32_seed(&rng, mix64(seed ^ mix64(pixel_index + 0x9e3779b97f4a7c15ULL)), pixel_index);
    return rng;
}
