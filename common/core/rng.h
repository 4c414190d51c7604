/* rng.h -- PCG32 (O'Neill 2014), one independent stream per pixel.
 *
 * Usage: pcg32 rng = pcg32_for_pixel(seed, pixel_index); float u = pcg32_float(&rng);
 *
 * Every pixel owns its own generator, seeded from (scene seed, pixel index),
 * so a pixel's samples do not depend on which thread renders it or in which
 * order: the image is bit-identical for any thread count. Never create a
 * generator per call (every call would return the same "random" number), and
 * never share one between threads (a data race, and the order changes).
 */
#ifndef RNG_H
#define RNG_H

#include <stdint.h>

typedef struct {
    uint64_t state;
    uint64_t increment; /* selects the stream; always odd */
} pcg32;

/* The reference seeding: pcg32_srandom_r(rng, initstate, initseq) of pcg-c-basic. */
void pcg32_seed(pcg32 *rng, uint64_t initial_state, uint64_t stream);
/* The next 32 random bits: a 64-bit linear congruential step, output
 * permuted by an xorshift and a random rotation (XSH RR). Inline, like
 * pcg32_float: a path vertex draws five to eight numbers, and a call into
 * rng.c for each cost more than the generator. */
static inline uint32_t pcg32_next(pcg32 *rng)
{
    const uint64_t multiplier = 6364136223846793005ULL;
    uint64_t old = rng->state;
    rng->state = old * multiplier + rng->increment;
    uint32_t xorshifted = (uint32_t)(((old >> 18u) ^ old) >> 27u);
    uint32_t rotation = (uint32_t)(old >> 59u);
    return (xorshifted >> rotation) | (xorshifted << ((-rotation) & 31u));
}
/* Uniform in [0, 1): 24 random bits, so 1.0f can never come out. */
static inline float pcg32_float(pcg32 *rng) { return (float)(pcg32_next(rng) >> 8) * 0x1.0p-24f; }
/* Uniform in [0, 1) with 53 random bits, for statistics in double. */
double pcg32_double(pcg32 *rng);
/* Uniform integer in [0, bound), without modulo bias. */
uint32_t pcg32_bounded(pcg32 *rng, uint32_t bound);
/* The generator of one pixel of one render. */
pcg32 pcg32_for_pixel(uint64_t seed, uint64_t pixel_index);

#endif
