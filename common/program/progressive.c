/* progressive.c -- estimates with their error, rendered in passes (see
 * progressive.h). */
#include "progressive.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "memory.h"
#include "mpi_split.h"

#include "timer.h"

/* relMSE's guard against dividing by near-black pixels (as image_relmse). */
static const double RELATIVE_ERROR_EPSILON = 1e-2;

void estimate_image_free(estimate_image *e)
{
    image_free(&e->mean);
    image_free(&e->standard_error);
}

estimate_image estimate_render(radiance_fn radiance, const void *scene, const camera *cam, int spp, uint64_t seed,
                               int threads)
{
    return estimate_render_sampled(radiance, NULL, scene, cam, spp, seed, threads);
}

estimate_image estimate_render_sampled(radiance_fn radiance, render_sample_fn sample, const void *scene,
                                       const camera *cam, int spp, uint64_t seed, int threads)
{
    return estimate_render_checkpointed(radiance, sample, scene, cam, spp, seed, threads, NULL);
}

estimate_image estimate_render_checkpointed(radiance_fn radiance, render_sample_fn sample, const void *scene,
                                            const camera *cam, int spp, uint64_t seed, int threads,
                                            const checkpointing *cp)
{
    estimate_image e;
    e.mean = image_make(cam->width, cam->height);
    e.standard_error = image_make(cam->width, cam->height);
    render_job job = {.cam = cam, .spp = spp, .seed = seed, .threads = threads, .quiet = true,
                      .radiance = radiance, .scene = scene, .standard_error = &e.standard_error,
                      .jitter = true, .sample = sample, .checkpoints = cp};
    render_stats stats;
    render_image(&job, &e.mean, &stats);
    e.spp = spp;
    e.seconds = stats.seconds;
    e.counters = stats.counters;
    return e;
}

double estimate_relative_error(const estimate_image *e)
{
    size_t n = (size_t)e->mean.width * (size_t)e->mean.height * 3;
    double sum = 0.0;
    for (size_t i = 0; i < n; i++) {
        double m = e->mean.rgb[i], s = e->standard_error.rgb[i];
        sum += s * s / (m * m + RELATIVE_ERROR_EPSILON);
    }
    return sqrt(sum / (double)n);
}

/* Merge pass b into a: means weighted by sample counts; the variance of the
 * merged mean is sum n_k^2 se_k^2 / N^2. */
static void merge_estimates(estimate_image *a, const estimate_image *b)
{
    double na = (double)a->spp, nb = (double)b->spp, n = na + nb;
    size_t count = (size_t)a->mean.width * (size_t)a->mean.height * 3;
    for (size_t i = 0; i < count; i++) {
        double mean = (na * a->mean.rgb[i] + nb * b->mean.rgb[i]) / n;
        double sa = a->standard_error.rgb[i], sb = b->standard_error.rgb[i];
        double variance = (na * na * sa * sa + nb * nb * sb * sb) / (n * n);
        a->mean.rgb[i] = (float)mean;
        a->standard_error.rgb[i] = (float)sqrt(variance);
    }
    a->spp += b->spp;
    a->seconds += b->seconds;
    counters_add(&a->counters, &b->counters);
}

/* The per-pixel variance is trusted from this many samples on: from n
 * samples of a normal variable the sample variance is off by a factor
 * sqrt(2 / (n - 1)), a third at 16 (and more for a path tracer's skewed
 * samples, where the first few often all miss the light and read 0). */
enum { PROGRESSIVE_TRUSTED_SPP = 16 };

estimate_image progressive_render(radiance_fn radiance, const void *scene, const camera *cam, uint64_t seed,
                                  int threads, double seconds, double target_error, FILE *log)
{
    return progressive_render_sampled(radiance, NULL, scene, cam, seed, threads, seconds, target_error, log);
}

/* The state of a progressive render between passes, for its checkpoint:
 * the merged mean, then its standard error (floats, row by row). */
static void write_progress(const checkpointing *cp, const estimate_image *total, int pass, double seconds)
{
    if (cp == NULL || cp->path == NULL || !mpi_split_is_root())
        return;
    size_t floats = (size_t)total->mean.width * (size_t)total->mean.height * 3;
    float *payload = memory_allocate(2 * floats, sizeof *payload);
    memcpy(payload, total->mean.rgb, floats * sizeof *payload);
    memcpy(payload + floats, total->standard_error.rgb, floats * sizeof *payload);
    checkpoint c = {.id = cp->id, .done = pass, .spp_done = total->spp, .seconds = seconds,
                    .counters = total->counters, .payload_bytes = 2 * floats * sizeof *payload, .payload = payload};
    char err[1024];
    if (!checkpoint_write(cp->path, &c, err, sizeof err))
        fprintf(stderr, "warning: no checkpoint: %s\n", err);
    else if (!cp->quiet)
        fprintf(stderr, "checkpoint: %ld samples per pixel after pass %d -> %s (--resume %s continues)\n", total->spp,
                pass, cp->path, cp->path);
    free(payload);
}

/* Each pass doubles the samples (2 after the first, 2^k after k): 2^31
 * is past the int a pass's spp is given as. */
enum { PROGRESSIVE_MAX_PASSES = 30 };

const char *progressive_resume_problem(const checkpoint *c)
{
    if (c->done < 1 || c->done > PROGRESSIVE_MAX_PASSES || c->spp_done != 1L << c->done)
        return "its passes and samples are not those of a progressive render (2^k samples after k passes)";
    const float *payload = c->payload;
    size_t floats = c->payload_bytes / sizeof *payload / 2;
    for (size_t i = 0; i < floats; i++)
        if (!isfinite(payload[i]) || !isfinite(payload[floats + i]) || payload[floats + i] < 0.0f)
            return "its image is not one a render makes (a value not finite, or a negative standard error)";
    return NULL;
}

/* The render so far from the resumed checkpoint (rank 0 read it and tells
 * the others): its image, samples, passes, seconds and counters. */
static estimate_image resume_progress(const checkpointing *cp, const camera *cam, int *pass, double *seconds)
{
    estimate_image total;
    memset(&total, 0, sizeof total);
    total.mean = image_make(cam->width, cam->height);
    total.standard_error = image_make(cam->width, cam->height);
    size_t floats = (size_t)cam->width * (size_t)cam->height * 3;
    long passes = 0;
    if (mpi_split_is_root()) {
        const float *payload = cp->resume->payload;
        memcpy(total.mean.rgb, payload, floats * sizeof *payload);
        memcpy(total.standard_error.rgb, payload + floats, floats * sizeof *payload);
        total.spp = cp->resume->spp_done;
        total.counters = cp->resume->counters;
        passes = cp->resume->done;
        *seconds = cp->resume->seconds;
    }
    mpi_split_broadcast(total.mean.rgb, floats * sizeof(float));
    mpi_split_broadcast(total.standard_error.rgb, floats * sizeof(float));
    mpi_split_broadcast(&total.spp, sizeof total.spp);
    mpi_split_broadcast(&total.counters, sizeof total.counters);
    mpi_split_broadcast(&passes, sizeof passes);
    mpi_split_broadcast(seconds, sizeof *seconds);
    *pass = (int)passes;
    return total;
}

estimate_image progressive_render_sampled(radiance_fn radiance, render_sample_fn sample, const void *scene,
                                          const camera *cam, uint64_t seed, int threads, double seconds,
                                          double target_error, FILE *log)
{
    return progressive_render_resumable(radiance, sample, scene, cam, seed, threads, seconds, target_error, log, NULL);
}

estimate_image progressive_render_resumable(radiance_fn radiance, render_sample_fn sample, const void *scene,
                                            const camera *cam, uint64_t seed, int threads, double seconds,
                                            double target_error, FILE *log, const checkpointing *cp)
{
    double start = timer_seconds(), before = 0.0, last_checkpoint = start;
    int pass = 1;
    /* Two samples at least: one sample per pixel has no variance to
     * estimate its error from (its standard error would read 0, and the
     * target would seem reached at once). */
    estimate_image total = cp != NULL && cp->resuming
                               ? resume_progress(cp, cam, &pass, &before)
                               : estimate_render_sampled(radiance, sample, scene, cam, 2, seed, threads);
    for (;; pass++) {
        double elapsed = before + timer_seconds() - start, error = estimate_relative_error(&total);
        bool trusted = total.spp >= PROGRESSIVE_TRUSTED_SPP;
        if (log != NULL)
            fprintf(log, "pass %2d: %6ld spp, %8.2f s, estimated relative error %.4f%s\n", pass, total.spp, elapsed,
                    error, trusted ? "" : " (not trusted below 16 spp)");
        bool stop = false;
        if (seconds <= 0.0 && target_error <= 0.0) {
            stop = true; /* nothing to wait for */
        } else if (target_error > 0.0 && trusted && error <= target_error) {
            if (log != NULL)
                fprintf(log, "reached the target error %.4f\n", target_error);
            stop = true;
        } else {
            /* The next pass doubles the samples so far: stop now if it would
             * overrun the budget (passes take time in proportion to spp). */
            double per_sample = elapsed / (double)total.spp;
            if (seconds > 0.0 && elapsed + per_sample * (double)total.spp > seconds) {
                if (log != NULL)
                    fprintf(log, "stopped at the time budget %.1f s (another pass would take %.1f s)\n", seconds,
                            per_sample * (double)total.spp);
                stop = true;
            }
        }
        /* Rank 0's clock decides for every rank (mpi_split.h). */
        if (mpi_split_broadcast_int(stop))
            break;
        if (cp != NULL &&
            mpi_split_broadcast_int(timer_seconds() - last_checkpoint >= cp->every_seconds)) {
            write_progress(cp, &total, pass, elapsed);
            last_checkpoint = timer_seconds();
        }
        estimate_image next =
            estimate_render_sampled(radiance, sample, scene, cam, (int)total.spp, seed + (uint64_t)pass * 0x9e3779b9ULL,
                                    threads);
        merge_estimates(&total, &next);
        estimate_image_free(&next);
    }
    total.seconds = before + timer_seconds() - start;
    return total;
}
