/* render_loop.h -- the loop every chapter renders with: for each pixel, spp camera
 * rays, each traced by the chapter's radiance function, averaged in double.
 *
 * Usage:
 *   render_job job = {.cam = &cam, .spp = 1, .seed = 1, .threads = 2,
 *                     .radiance = ray_cast_radiance, .scene = &scene};
 *   image img = image_make(cam.width, cam.height);
 *   render_stats stats;
 *   render_image(&job, &img, &stats);     render.h: over MPI ranks, with progress, checkpoints
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
 *
 * Here is the lecture's loop: a pixel's samples, and the rows of an image.
 * Which rows a process renders, the progress line, gathering, checkpoints
 * are the program's (render.h), handed in as a render_rows_split.
 */
#ifndef RENDER_LOOP_H
#define RENDER_LOOP_H

#include <stdbool.h>

#include "camera.h"
#include "counters.h"
#include "image.h"
#include "rng.h"
#include "stats.h"

struct checkpointing;

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
     * the image is the one a single pass makes, bit for bit. Only
     * render_image (render.h) reads it: the loop here does not know it. */
    const struct checkpointing *checkpoints;
} render_job;

/* One pixel's render in progress: its random stream where the next sample
 * starts, and the running mean and variance of each channel. What a
 * checkpoint of a plain render holds, pixel by pixel. */
typedef struct {
    pcg32 rng;
    welford channel[3];
} render_pixel_state;

/* The camera ray through (px, py), counted, and shown by --explain as
 * sample `index` of the pixel: what render_pixel does before calling
 * radiance, for a render_sample_fn to do the same. */
ray render_camera_ray(const render_job *job, int index, float px, float py, ray_counters *counters);

/* One pixel, exactly as render_image computes it (for tests and for
 * explaining a pixel). std_error may be NULL. */
vec3 render_pixel(const render_job *job, int x, int y, ray_counters *counters, vec3 *std_error);

/* The state of pixel (x, y) before its first sample. */
render_pixel_state render_pixel_state_start(const render_job *job, int x, int y);
/* Samples first .. end - 1 of pixel (x, y), added to its state: one call
 * for all spp samples, or several for consecutive ranges, make the same
 * numbers in the same order. */
void render_pixel_add_samples(const render_job *job, int x, int y, int first, int end, render_pixel_state *st,
                              ray_counters *counters);
/* The pixel's value (the mean) and, if std_error is not NULL, its standard error. */
vec3 render_pixel_value(const render_pixel_state *st, vec3 *std_error);

/* The program's part of a render loop: which rows this process renders
 * (NULL: all of them), and who hears of each row done, with how many
 * samples per pixel it got (NULL: nobody; called from any thread). */
typedef struct {
    bool (*owns_row)(int y);
    void (*row_done)(void *context, int64_t samples_per_pixel);
    void *context;
} render_rows_split;

/* The threads a render of job runs on (job->threads, or all of OpenMP's). */
int render_threads(const render_job *job);

/* Every pixel of the rows split gives, all its samples at once, into out
 * (and job->standard_error); their counters are added to *total. Rows are
 * handed to threads one at a time (dynamic): rows that cross glass cost
 * more than rows of sky, and static blocks would leave a core idle. */
void render_rows(const render_job *job, image *out, const render_rows_split *split, ray_counters *total);
/* One pass: samples done .. done + n - 1 of every pixel of those rows,
 * added to states (width x height, row by row; a pass from done = 0 starts
 * them). */
void render_rows_pass(const render_job *job, render_pixel_state *states, int done, int n,
                      const render_rows_split *split, ray_counters *total);

#endif
