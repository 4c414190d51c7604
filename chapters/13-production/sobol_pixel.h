/* sobol_pixel.h -- chapter 09's Sobol numbers (sobol_sampler.h), made the
 * way a production sampler makes them: one pixel's samples in order, each
 * point found from the one before with one xor per dimension.
 *
 * Chapter 09 finds coordinate d of point i from scratch at every draw: a
 * hash for the dimension's scramble, and an xor of one direction number per
 * set bit of i, in a loop whose branches follow the bits of i (a wrong
 * guess every other bit). Measured on a path of about thirty numbers, that
 * cost more than the path's rays. But the lanes of the eight-path renderer
 * take a pixel's samples 0, 1, 2, ... in order, so both parts can be done
 * once per step instead of once per draw:
 *
 *   - the scrambles depend on the pixel and the dimension only: worked out
 *     once per pixel, for all SOBOL_DIMENSIONS dimensions;
 *   - going from point i to point i + 1 flips bits 0 .. c of the index,
 *     where c is the number of trailing ones of i (i = ...0111 becomes
 *     ...1000), so coordinate d changes by the xor of v_1 .. v_(c+1) of d:
 *     one table entry, the same for every pixel.
 *
 * The numbers are chapter 09's, bit for bit (the test compares them), so
 * an image rendered with them is the one chapter 09's sampler would give.
 *
 * Usage (a pixel's samples index, index + 1, ...):
 *   sobol_pixel s;
 *   sobol_pixel_start(&s, seed, pixel, index, &pixel_rng);
 *   float u = sobol_pixel_next(&s);  coordinate 0, 1, 2 ... of point index
 *   sobol_pixel_next_sample(&s);     point index + 1, from coordinate 0
 */
#ifndef SOBOL_PIXEL_H
#define SOBOL_PIXEL_H

#include <stdint.h>

#include "08-monte-carlo/estimators.h"
#include "09-path-tracing/sobol_sampler.h"

typedef struct {
    /* sobol_sequence_bits(index, d), not yet scrambled, its bits reversed:
     * the order Owen's scramble works in, and reversing is linear (the
     * reverse of a xor b is the xor of their reverses), so the steps can
     * be reversed once instead of the point at every draw */
    uint32_t point_reversed[SOBOL_DIMENSIONS];
    sobol_scramble scramble[SOBOL_DIMENSIONS];
    uint32_t index; /* the sample's point */
    int dimension;  /* the coordinate the next number is */
    pcg32 *rng;     /* the pixel's stream, for coordinates past SOBOL_DIMENSIONS */
} sobol_pixel;

/* Point `index` of the pixel's sequence: sobol_sampler_start()'s. */
void sobol_pixel_start(sobol_pixel *s, uint64_t seed, uint64_t pixel, uint32_t index, pcg32 *rng);

/* The next point of the pixel (index + 1), from its coordinate 0. */
void sobol_pixel_next_sample(sobol_pixel *s);

/* The next coordinate of the point, in [0, 1): sobol_sampler_next()'s. */
static inline float sobol_pixel_next(sobol_pixel *s)
{
    int d = s->dimension++;
    if (d >= SOBOL_DIMENSIONS)
        return pcg32_float(s->rng);
    uint32_t bits = reverse_bits(owen_scramble_reversed(s->point_reversed[d], s->scramble[d].owen_seed)) ^
                    s->scramble[d].shift; /* owen_scramble(point), then the shift */
    return (float)(bits >> 8) * 0x1.0p-24f;
}

#endif
