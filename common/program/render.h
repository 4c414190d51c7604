/* render.h -- render_image(): the render loop of render_loop.h as a program
 * runs it: its rows dealt out over MPI ranks and gathered (mpi_split.h), a
 * progress line, and, when asked, in passes that keep checkpoints
 * (checkpoint.h) and resume them.
 *
 * Usage:
 *   render_job job = {.cam = &cam, .spp = 1, .seed = 1, .threads = 2,
 *                     .radiance = ray_cast_radiance, .scene = &scene};
 *   image img = image_make(cam.width, cam.height);
 *   render_stats stats;
 *   render_image(&job, &img, &stats);
 */
#ifndef RENDER_H
#define RENDER_H

#include "checkpoint.h"
#include "render_loop.h"

typedef struct {
    double seconds;        /* the render's wall time (with the time before a resume) */
    ray_counters counters; /* of every rank, added */
    double gather_seconds; /* of seconds: handing rows between MPI ranks (0 on one) */
    double wait_seconds;   /* of seconds: this rank waiting for the slowest before that */
} render_stats;

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

#endif
