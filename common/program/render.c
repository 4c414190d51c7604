/* render.c -- render_image(): the loop of render_loop.c over MPI ranks,
 * with a progress line and, when asked, in passes that keep checkpoints. */
#include "render.h"

#include <float.h>
#include <math.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "memory.h"
#include "mpi_split.h"
#include "progress.h"
#include "timer.h"

/* The rows this rank renders (all of them on one). */
static int owned_rows(int height)
{
    int n = 0;
    for (int y = 0; y < height; y++)
        n += mpi_split_owns_row(y);
    return n;
}

/* After the ranks rendered their rows: every rank gets every row of the
 * image (and of its standard error), and every rank's counters. */
static double gather_image(const render_job *job, image *out, ray_counters *total, double *wait_seconds)
{
    if (mpi_split_ranks() == 1)
        return 0.0;
    /* the wait for the slowest rank, apart from handing the rows over */
    double arrived = timer_seconds();
    mpi_split_barrier();
    double start = timer_seconds();
    *wait_seconds += start - arrived;
    size_t row_bytes = (size_t)out->width * 3 * sizeof(float);
    mpi_split_gather_rows(out->rgb, row_bytes, out->height);
    if (job->standard_error != NULL)
        mpi_split_gather_rows(job->standard_error->rgb, row_bytes, out->height);
    mpi_split_sum_counters(total);
    return timer_seconds() - start;
}

/* The program's part of the loop: this rank's rows, and the progress line
 * (in rows for a render in one pass, in rows times samples in passes). */
static bool rank_owns_row(int y) { return mpi_split_owns_row(y); }

static void advance_row(void *bar, int64_t samples_per_pixel)
{
    (void)samples_per_pixel;
    progress_advance(bar, 1);
}

static void advance_bar(void *bar, int64_t samples_per_pixel) { progress_advance(bar, samples_per_pixel); }

/* The render in one pass: each pixel all its samples at once. */
static void render_whole(const render_job *job, image *out, render_stats *stats)
{
    progress bar;
    progress_begin(&bar, job->label ? job->label : "render", owned_rows(job->cam->height), job->quiet);
    ray_counters total;
    memset(&total, 0, sizeof total);
    double start = timer_seconds();
    render_rows_split split = {.owns_row = rank_owns_row, .row_done = advance_row, .context = &bar};
    render_rows(job, out, &split, &total);
    progress_end(&bar);
    double wait = 0.0, gather = gather_image(job, out, &total, &wait);
    if (stats != NULL) {
        stats->seconds = timer_seconds() - start;
        stats->counters = total;
        stats->gather_seconds = gather;
        stats->wait_seconds = wait;
    }
}

/* ---- in passes, with checkpoints ------------------------------------------------
 * A pass adds samples [done, done + n) to every pixel's state; between
 * passes the states are the whole render so far, and rank 0 writes them
 * to the checkpoint when checkpoints->every_seconds have passed since the
 * last. Where the passes end does not change a pixel's numbers (its stream
 * and its sums carry on), so rank 0 sizes them by its clock: about
 * every_seconds each, from the time per sample the passes so far took. */

/* Samples per pixel of the next pass (rank 0 decides, every rank is told). */
static int next_pass_samples(const render_job *job, int done, double per_sample_seconds)
{
    int n = 1;
    double every = job->checkpoints->every_seconds;
    if (per_sample_seconds > 0.0 && every > 0.0) {
        double fit = every / per_sample_seconds;
        n = fit >= (double)job->spp ? job->spp : fit < 1.0 ? 1 : (int)fit;
    }
    if (n > job->spp - done)
        n = job->spp - done;
    return mpi_split_broadcast_int(n);
}

/* Rank 0 writes the states (all rows: every rank sent its own) and the
 * counters of every rank so far. */
static void write_checkpoint(const render_job *job, render_pixel_state *states, int done, double seconds,
                             const ray_counters *counters)
{
    const checkpointing *cp = job->checkpoints;
    size_t pixels = (size_t)job->cam->width * (size_t)job->cam->height;
    mpi_split_gather_rows(states, (size_t)job->cam->width * sizeof *states, job->cam->height);
    ray_counters all = *counters;
    mpi_split_sum_counters(&all);
    if (!mpi_split_is_root())
        return;
    checkpoint c = {.id = cp->id, .done = done, .spp_done = done, .seconds = seconds, .counters = all,
                    .payload_bytes = pixels * sizeof *states, .payload = states};
    char err[1024];
    if (!checkpoint_write(cp->path, &c, err, sizeof err))
        fprintf(stderr, "%s: warning: no checkpoint: %s\n", job->label ? job->label : "render", err);
    else if (!cp->quiet)
        fprintf(stderr, "%s: checkpoint: %d of %d samples per pixel -> %s (--resume %s continues)\n",
                job->label ? job->label : "render", done, job->spp, cp->path, cp->path);
}

const char *render_resume_problem(const checkpoint *c)
{
    if (c->done > c->id.spp || c->spp_done != c->done)
        return "its samples done are not between 0 and its spp, or disagree with its spp-done";
    const render_pixel_state *states = c->payload;
    size_t pixels = c->payload_bytes / sizeof *states;
    for (size_t i = 0; i < pixels; i++)
        for (int k = 0; k < 3; k++) {
            const welford *w = &states[i].channel[k];
            /* (a mean or standard error past a float's range is finite in
             * double and infinite in the image: the fuzzer found one) */
            if (!isfinite(w->mean) || !isfinite(w->m2) || w->m2 < 0.0 || w->count > (uint64_t)c->done ||
                fabs(w->mean) > FLT_MAX || !(welford_standard_error(w) <= FLT_MAX))
                return "a pixel's running sums are not ones a render makes (not finite, past a float's range, "
                       "negative, or of more samples than it has done)";
        }
    return NULL;
}

/* Every rank's pixel states to start from: a fresh one per pixel, or the
 * resumed checkpoint's (rank 0 read it; it tells the others). *done,
 * *seconds and *counters get how far it got (the counters on rank 0 only,
 * so that adding every rank's counts them once). */
static render_pixel_state *start_states(const render_job *job, int *done, double *seconds, ray_counters *counters)
{
    const int width = job->cam->width, height = job->cam->height;
    size_t pixels = (size_t)width * (size_t)height;
    render_pixel_state *states = memory_allocate(pixels, sizeof *states);
    const checkpointing *cp = job->checkpoints;
    *done = 0;
    *seconds = 0.0;
    memset(counters, 0, sizeof *counters);
    if (!cp->resuming)
        return states; /* each pixel's starts with its first sample (render_rows_pass) */
    if (mpi_split_is_root()) {
        memcpy(states, cp->resume->payload, pixels * sizeof *states);
        *done = (int)cp->resume->done;
        *seconds = cp->resume->seconds;
        *counters = cp->resume->counters;
    }
    mpi_split_broadcast(states, pixels * sizeof *states);
    *done = mpi_split_broadcast_int(*done);
    mpi_split_broadcast(seconds, sizeof *seconds);
    return states;
}

static void render_in_passes(const render_job *job, image *out, render_stats *stats)
{
    const int width = job->cam->width, height = job->cam->height;
    int done;
    double before;
    ray_counters total;
    render_pixel_state *states = start_states(job, &done, &before, &total);
    progress bar;
    progress_begin(&bar, job->label ? job->label : "render", (int64_t)owned_rows(height) * (job->spp - done),
                   job->quiet);
    render_rows_split split = {.owns_row = rank_owns_row, .row_done = advance_bar, .context = &bar};
    double start = timer_seconds(), last_checkpoint = start, per_sample = 0.0, gather = 0.0;
    while (done < job->spp) {
        int n = next_pass_samples(job, done, per_sample);
        double pass_start = timer_seconds();
        render_rows_pass(job, states, done, n, &split, &total);
        done += n;
        per_sample = (timer_seconds() - pass_start) / n;
        /* every rank must agree on whether to send its states now */
        int due = mpi_split_broadcast_int(timer_seconds() - last_checkpoint >= job->checkpoints->every_seconds);
        if (done < job->spp && due && job->checkpoints->path != NULL) {
            double t = timer_seconds();
            write_checkpoint(job, states, done, before + (t - start), &total);
            gather += timer_seconds() - t;
            last_checkpoint = timer_seconds();
        }
    }
    progress_end(&bar);
    for (int y = 0; y < height; y++)
        if (mpi_split_owns_row(y))
            for (int x = 0; x < width; x++) {
                vec3 std_error;
                image_set(out, x, y, render_pixel_value(&states[(size_t)y * width + x], &std_error));
                if (job->standard_error)
                    image_set(job->standard_error, x, y, std_error);
            }
    free(states);
    double wait = 0.0;
    gather += gather_image(job, out, &total, &wait);
    if (stats != NULL) {
        stats->seconds = before + (timer_seconds() - start);
        stats->counters = total;
        stats->gather_seconds = gather;
        stats->wait_seconds = wait;
    }
}

void render_image(const render_job *job, image *out, render_stats *stats)
{
    mpi_split_enter_collective();
    if (job->checkpoints != NULL && (job->checkpoints->path != NULL || job->checkpoints->resuming))
        render_in_passes(job, out, stats);
    else
        render_whole(job, out, stats);
    mpi_split_exit_collective();
}
