/* render.h -- the loop every chapter renders with: for each pixel, spp camera
 * rays, each traced by the chapter's radiance function, averaged in double.
 *
 * Usage:
 *   render_job job = {.cam = &cam, .spp = 1, .seed = 1, .threads = 2,
 *                     .radiance = ray_cast_radiance, .scene = &scene};
 *   image img = image_make(cam.width, cam.height);
 *   render_stats stats;
 *   render_image(&job, &img, &stats);
 *
 * The integrator shape is one function: radiance(scene, ray, rng, counters)
 * -> RGB, so ray casting, Whitted and path tracing render the same scene and
 * can be compared on one plot.
 *
 * Same seed, same image, bit for bit, for any thread count: each pixel has its
 * own random stream (rng.h) and its own sum, and rows are handed to threads
 * dynamically but each pixel is computed by exactly one of them.
 *
 * With spp = 1 the ray goes through the pixel centre (lecture 13); with more,
 * or with `jitter` set, each sample is placed uniformly at random inside the
 * pixel (lecture 16): the pixel's value is then the average over its area,
 * and estimates with different sample counts estimate the same thing.
 * Samples that are NaN or Inf are dropped before they are added, and counted.
 */
#ifndef RENDER_H
#define RENDER_H

#include <stdbool.h>

#include "camera.h"
#include "checkpoint.h"
#include "counters.h"
#include "image.h"
#include "rng.h"
#include "stats.h"

typedef vec3 (*radiance_fn)(const void *scene, ray r, pcg32 *rng, ray_counters *counters);

/* One whole sample of pixel (x, y): where in the pixel, and the radiance
 * that arrives there. For samplers whose numbers depend on which sample of
 * the pixel is drawn (index 0 .. job->spp - 1), such as a low-discrepancy
 * sequence (chapter 09's --sampler sobol); the render loop still sums,
 * drops NaN and Inf and takes the standard error. rng is the pixel's
 * stream, as radiance_fn's. */
struct render_job;
typedef vec3 (*render_sample_fn)(const struct render_job *job, int x, int y, int index, pcg32 *rng,
                                 ray_counters *counters);

typedef struct render_job {
    const camera *cam;   /* image size comes from cam->width, cam->height */
    int spp;
    uint64_t seed;
    int threads;         /* 0: all OpenMP threads */
    bool quiet;          /* no progress line */
    const char *label;   /* for the progress line */
    radiance_fn radiance;
    const void *scene;
    image *standard_error; /* optional: per-pixel standard error of the mean, per channel */
    bool jitter;           /* random positions in the pixel even when spp = 1 */
    /* Stratified ("jittered", Cook 1984) positions: the pixel cut into a
     * k x k grid, k = floor(sqrt(spp)), one random position in each cell;
     * samples beyond k x k anywhere in the pixel. Implies jitter. */
    bool stratify;
    /* Optional: each sample by this function instead (then jitter, stratify
     * and radiance are its own business). */
    render_sample_fn sample;
    /* Optional: keep checkpoints, or continue one (checkpoint.h). The
     * render then runs in passes of a few samples per pixel, each pixel
     * keeping its random stream and its running sums between passes, so
     * the image is the one a single pass makes, bit for bit. */
    const checkpointing *checkpoints;
} render_job;

typedef struct {
    double seconds;        /* the render's wall time (with the time before a resume) */
    ray_counters counters; /* of every rank, added */
    double gather_seconds; /* of seconds: handing rows between MPI ranks (0 on one) */
    double wait_seconds;   /* of seconds: this rank waiting for the slowest before that */
} render_stats;

/* One pixel's render in progress: its random stream where the next sample
 * starts, and the running mean and variance of each channel. What a
 * checkpoint of a plain render holds, pixel by pixel. */
typedef struct {
    pcg32 rng;
    welford channel[3];
} render_pixel_state;

/* What is wrong with a checkpoint's pixel states (checkpoint_read has
 * matched its identity and its size), or NULL: a render's checkpoint
 * holds as many samples done as spp-done says, at most its spp, and every
 * pixel's sums are finite, its mean and standard error within a float's
 * range, its squared deviations not negative and its counts at most the
 * samples done. A file that passes its checksum was
 * written whole, or crafted: this is what the resume trusts of it. */
const char *render_resume_problem(const checkpoint *c);

/* Renders into out (already made at the camera's size). Under mpirun
 * (mpi_split.h) every rank renders its rows and then holds the whole
 * image; the counters are every rank's. */
void render_image(const render_job *job, image *out, render_stats *stats);

/* The camera ray through (px, py), counted, and shown by --explain as
 * sample `index` of the pixel: what render_pixel does before calling
 * radiance, for a render_sample_fn to do the same. */
ray render_camera_ray(const render_job *job, int index, float px, float py, ray_counters *counters);

/* One pixel, exactly as render_image computes it (for tests and for
 * explaining a pixel). std_error may be NULL. */
vec3 render_pixel(const render_job *job, int x, int y, ray_counters *counters, vec3 *std_error);

#endif
