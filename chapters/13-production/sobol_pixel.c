/* sobol_pixel.c -- a pixel's Sobol points one after another (sobol_pixel.h). */
#include "13-production/sobol_pixel.h"

#include <threads.h>

/* step[c][d]: what coordinate d changes by when the index goes from i to
 * i + 1 and i ends in c ones: v_1 xor ... xor v_(c+1) of dimension d,
 * reversed as the points are. By count, then by dimension, so that a step
 * reads one row. */
static uint32_t step[32][SOBOL_DIMENSIONS];
static once_flag steps_made = ONCE_FLAG_INIT;

static void make_steps(void)
{
    for (int d = 0; d < SOBOL_DIMENSIONS; d++) {
        const uint32_t *v = sobol_direction_numbers(d);
        uint32_t flips = 0;
        for (int c = 0; c < 32; c++) {
            flips ^= v[c];
            step[c][d] = reverse_bits(flips);
        }
    }
}

void sobol_pixel_start(sobol_pixel *s, uint64_t seed, uint64_t pixel, uint32_t index, pcg32 *rng)
{
    call_once(&steps_made, make_steps);
    sobol_sampler from_scratch = sobol_sampler_start(seed, pixel, index, rng);
    for (int d = 0; d < SOBOL_DIMENSIONS; d++) {
        s->point_reversed[d] = reverse_bits(sobol_sequence_bits(index, d));
        s->scramble[d] = sobol_sampler_scramble(&from_scratch, d);
    }
    s->index = index;
    s->dimension = 0;
    s->rng = rng;
}

void sobol_pixel_next_sample(sobol_pixel *s)
{
    /* trailing ones of i: trailing zeros of ~i (i = 2^32 - 1 wraps to 0,
     * all 32 bits flipped) */
    uint32_t flipped = ~s->index;
    int c = flipped == 0 ? 31 : __builtin_ctz(flipped);
    const uint32_t *row = step[c];
    for (int d = 0; d < SOBOL_DIMENSIONS; d++)
        s->point_reversed[d] ^= row[d];
    s->index++;
    s->dimension = 0;
}
