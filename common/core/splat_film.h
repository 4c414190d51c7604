/* splat_film.h -- an image that samples are added to from any thread, at
 * any pixel, in any order, with the same result bit for bit.
 *
 * The render loop (render.h) gives every pixel its own sum, so the order of
 * the additions never changes. Light tracing, bidirectional connections
 * (t = 1) and Metropolis light transport cannot: a sample lands on whatever
 * pixel its path passes through, from whichever thread made it. Floating-
 * point addition is not associative, so a float image summed in thread
 * order would change with the thread count. Integer addition is: each
 * channel here is a 64-bit fixed-point sum with SPLAT_FILM_FRACTION_BITS
 * bits after the point, added atomically. Each splat is rounded once, to
 * the nearest multiple of 2^-SPLAT_FILM_FRACTION_BITS (an error of at most
 * 2^-25 = 3e-8 per splat, unbiased over many), and the sum is then exact.
 *
 * Usage:
 *   splat_film film;
 *   if (!splat_film_init(&film, width, height)) ... out of memory
 *   splat_film_add(&film, x, y, value, &counters);   from any thread
 *   image img = image_make(width, height);
 *   splat_film_resolve(&film, 1.0 / samples_per_pixel, &img);
 *   splat_film_free(&film);
 */
#ifndef SPLAT_FILM_H
#define SPLAT_FILM_H

#include <stdbool.h>
#include <stdint.h>

#include "counters.h"
#include "image.h"
#include "vec3.h"

#define SPLAT_FILM_FRACTION_BITS 24
/* The largest value one splat may carry: larger ones (and NaN, Inf) are
 * dropped and counted as non-finite samples, so the 64-bit sums cannot
 * overflow: 2^63 / 2^24 leaves room for 2^39 = 5.5e11 in all, e.g. 10^6
 * splats of 5e5 on one pixel. */
#define SPLAT_FILM_MAX_VALUE 5.0e5f

typedef struct {
    int width, height;
    int64_t *sum; /* width * height * 3, fixed point, row-major, top row first */
} splat_film;

/* A film of zeros. False if memory ran out or the size is not positive. */
bool splat_film_init(splat_film *film, int width, int height);
void splat_film_free(splat_film *film);

/* Adds value to pixel (x, y), given in continuous raster coordinates (the
 * pixel is floor(x), floor(y)); points outside the film are ignored.
 * Thread-safe. A value with a channel that is NaN, Inf or beyond
 * SPLAT_FILM_MAX_VALUE is not added; it is counted in
 * counters->nonfinite_samples (counters may be NULL). */
void splat_film_add(splat_film *film, float x, float y, vec3 value, ray_counters *counters);

/* The pixel's sum, times scale. */
vec3 splat_film_get(const splat_film *film, int x, int y, double scale);

/* out (already made at the film's size) = every pixel's sum times scale. */
void splat_film_resolve(const splat_film *film, double scale, image *out);

#endif
