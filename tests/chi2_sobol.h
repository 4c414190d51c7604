/* chi2_sobol.h -- the two kinds of points the chi-square tests of chapters
 * 09 and up draw their samples from (chi2.h): independent random numbers,
 * and the scrambled Sobol points of --sampler sobol (chapter 09). Include
 * after chi2.h.
 *
 *   chi2_sources src;
 *   chi2_points points = chi2_source(&src, seed, which);   which 0: random, 1: Sobol
 *   chi2_result r = chi2_run(&c, &tab, points, N);          src must outlive the run */
#ifndef CHI2_SOBOL_H
#define CHI2_SOBOL_H

#include "09-path-tracing/sobol_sampler.h"
#include "chi2.h"

/* Sobol points: attempt i is point i of one pixel's scrambled sequence,
 * coordinates 0, 1, ... (as a path's first numbers). */
typedef struct {
    uint64_t seed;
    pcg32 rng; /* beyond the sequence's dimensions (never, here) */
} chi2_sobol_state;

static inline void chi2_fill_sobol(void *state, uint32_t index, float *u, int count)
{
    chi2_sobol_state *st = state;
    sobol_sampler s = sobol_sampler_start(st->seed, 0, index, &st->rng);
    for (int k = 0; k < count; k++)
        u[k] = sobol_sampler_next(&s);
}

typedef struct {
    pcg32 rng;
    chi2_sobol_state sobol;
} chi2_sources;

/* The points of kind `which` (0 random, 1 Sobol), seeded from
 * test_seed(seed). */
static inline chi2_points chi2_source(chi2_sources *src, uint64_t seed, int which)
{
    if (which == 0) {
        src->rng = pcg32_for_pixel(test_seed(seed), 0);
        return chi2_random_points(&src->rng);
    }
    src->sobol.seed = test_seed(seed);
    src->sobol.rng = pcg32_for_pixel(test_seed(seed), 1);
    return (chi2_points){"sobol", chi2_fill_sobol, &src->sobol};
}

#endif
