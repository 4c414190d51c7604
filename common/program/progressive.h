/* progressive.h -- renders whose error can be estimated, and rendering in
 * passes until a time budget or a target error is reached.
 *
 * Usage (any integrator of render.h's shape):
 *   estimate_image e = estimate_render(path_trace_radiance, &pt, &cam, 64, seed, threads);
 *   printf("%.4f\n", estimate_relative_error(&e));     what the variance predicts
 *   estimate_image_free(&e);
 *   e = progressive_render(path_trace_radiance, &pt, &cam, seed, threads, 10.0, 0.01, stdout);
 *
 * The samples land anywhere in the pixel (render.h's jitter), even at one
 * sample per pixel: every pass estimates the same image, the pixel's average
 * over its area, so passes can be merged.
 */
#ifndef PROGRESSIVE_H
#define PROGRESSIVE_H

#include <stdint.h>
#include <stdio.h>

#include "camera.h"
#include "checkpoint.h"
#include "counters.h"
#include "image.h"
#include "render.h"

/* A render whose error can be estimated: the mean and, per pixel, the
 * standard error of that mean. */
typedef struct {
    image mean;
    image standard_error;
    long spp;
    double seconds;
    ray_counters counters;
} estimate_image;

void estimate_image_free(estimate_image *e);

/* Renders with `spp` samples per pixel; seed picks the random streams. */
estimate_image estimate_render(radiance_fn radiance, const void *scene, const camera *cam, int spp, uint64_t seed,
                               int threads);
/* The same, each sample by `sample` when it is not NULL (render.h's
 * render_sample_fn, such as chapter 09's Sobol sampler). */
estimate_image estimate_render_sampled(radiance_fn radiance, render_sample_fn sample, const void *scene,
                                       const camera *cam, int spp, uint64_t seed, int threads);

/* The same, keeping checkpoints or resuming one (render.h's checkpoints;
 * NULL: neither). */
estimate_image estimate_render_checkpointed(radiance_fn radiance, render_sample_fn sample, const void *scene,
                                            const camera *cam, int spp, uint64_t seed, int threads,
                                            const checkpointing *cp);

/* The error the image's own variance predicts: sqrt of the mean over pixels
 * and channels of standard_error^2 / (mean^2 + eps), a relative RMSE. */
double estimate_relative_error(const estimate_image *e);

/* Renders passes of 2, 2, 4, 8, ... samples per pixel (each with its own
 * seed), merging them, until `seconds` have passed or the estimated relative
 * error is below `target_error`, judged only from 16 samples per pixel on,
 * where the per-pixel variance can be trusted (either may be 0: not used; both 0, one
 * pass). Prints one line per pass to `log` (if not NULL). */
estimate_image progressive_render(radiance_fn radiance, const void *scene, const camera *cam, uint64_t seed,
                                  int threads, double seconds, double target_error, FILE *log);
estimate_image progressive_render_sampled(radiance_fn radiance, render_sample_fn sample, const void *scene,
                                          const camera *cam, uint64_t seed, int threads, double seconds,
                                          double target_error, FILE *log);

/* What is wrong with a progressive render's checkpoint (checkpoint_read
 * has matched its identity and size), or NULL: its passes k between 1 and
 * PROGRESSIVE_MAX_PASSES with 2^k samples, as the passes make them, its
 * mean finite and its standard error finite and not negative. */
const char *progressive_resume_problem(const checkpoint *c);

/* The same, keeping checkpoints of the passes so far (cp->path, at least
 * cp->every_seconds apart), or continuing cp->resume; cp NULL: neither.
 * A resumed render goes on with the next pass, as the uninterrupted one
 * would have (the same seeds, the same merges): with a target error the
 * image is the same bit for bit. The time budget counts the seconds
 * before the interruption too. Under mpirun every pass is split over the
 * ranks (render.h), and rank 0's clock decides when to stop. */
estimate_image progressive_render_resumable(radiance_fn radiance, render_sample_fn sample, const void *scene,
                                            const camera *cam, uint64_t seed, int threads, double seconds,
                                            double target_error, FILE *log, const checkpointing *cp);

#endif
