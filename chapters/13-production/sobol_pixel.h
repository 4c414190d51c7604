/* sobol_pixel.h -- chapter 09's Sobol numbers (sobol_sampler.h), made the
 * way a production sampler makes them: one pixel's samples in order, each
 * point found from the one before with one xor per dimension, and its
 * numbers scrambled eight dimensions per instruction.
 *
 * Chapter 09 finds coordinate d of point i from scratch at every draw: a
 * hash for the dimension's scramble, and an xor of one direction number per
 * set bit of i, in a loop whose branches follow the bits of i (a wrong
 * guess every other bit). But the lanes of the eight-path renderer take a
 * pixel's samples 0, 1, 2, ... in order, so most of that is done once per
 * pixel or once per sample instead of once per draw:
 *
 *   - the scrambles depend on the pixel and the dimension only: hashed
 *     once per pixel, as far as its samples draw;
 *   - going from point i to point i + 1 flips bits 0 .. c of the index,
 *     where c is the number of trailing ones of i (i = ...0111 becomes
 *     ...1000), so coordinate d changes by the xor of v_1 .. v_(c+1) of d:
 *     one table entry, the same for every pixel;
 *   - a draw needs the scrambled number of its own dimension, but the
 *     next seven are about to be drawn: Owen's scramble runs on eight
 *     dimensions at once (AVX2 where the processor has it) and a draw
 *     reads one float.
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

#include <stdbool.h>
#include <stdint.h>

#include "09-path-tracing/sobol_sampler.h"

enum { SOBOL_PIXEL_BLOCK = 8 }; /* dimensions scrambled at once */

typedef struct {
    /* sobol_sequence_bits(index, d), not yet scrambled, its bits reversed:
     * the order Owen's scramble works in, and reversing is linear (the
     * reverse of a xor b is the xor of their reverses), so the steps can
     * be reversed once instead of the point at every draw */
    _Alignas(32) uint32_t point_reversed[SOBOL_DIMENSIONS];
    /* the scrambles (sobol_sampler_scramble) of dimensions 0 .. scrambled - 1,
     * hashed when a sample of the pixel first draws that far */
    _Alignas(32) uint32_t owen_seed[SOBOL_DIMENSIONS];
    _Alignas(32) uint32_t shift[SOBOL_DIMENSIONS];
    /* the sample's numbers, dimensions 0 .. ready - 1 */
    _Alignas(32) float number[SOBOL_DIMENSIONS];
    int scrambled, ready;
    sobol_sampler key; /* the pixel's, for the hashes */
    uint32_t index;    /* the sample's point */
    int dimension;     /* the coordinate the next number is */
    pcg32 *rng;        /* the pixel's stream, for coordinates past SOBOL_DIMENSIONS */
} sobol_pixel;

/* Point `index` of the pixel's sequence: sobol_sampler_start()'s. */
void sobol_pixel_start(sobol_pixel *s, uint64_t seed, uint64_t pixel, uint32_t index, pcg32 *rng);

/* The next point of the pixel (index + 1), from its coordinate 0. */
void sobol_pixel_next_sample(sobol_pixel *s);

/* Scrambles the sample's next block of dimensions (the one holding d). */
void sobol_pixel_fill(sobol_pixel *s, int d);

/* The next coordinate of the point, in [0, 1): sobol_sampler_next()'s. */
static inline float sobol_pixel_next(sobol_pixel *s)
{
    int d = s->dimension++;
    if (d >= SOBOL_DIMENSIONS)
        return pcg32_float(s->rng);
    if (d >= s->ready)
        sobol_pixel_fill(s, d);
    return s->number[d];
}

/* Eight dimensions per AVX2 instruction where the processor has it (true,
 * the default), or one at a time: the same bits either way. For the
 * tests; not thread-safe. */
void sobol_pixel_use_simd(bool on);

#endif
