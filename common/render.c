#include "render.h"

#include <float.h>
#include <math.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "explain.h"
#include "memory.h"
#include "mpi_split.h"
#include "progress.h"
#include "stats.h"
#include "timer.h"

ray render_camera_ray(const render_job *job, int index, float px, float py, ray_counters *counters)
{
    ray r = camera_ray(job->cam, px, py);
    counters->camera_rays++;
    if (explain_on()) {
        explain_line(0, "sample %d of %d, at (%.3f, %.3f) in the image", index + 1, job->spp, (double)px, (double)py);
        explain_ray(1, "camera ray", r);
    }
    return r;
}

/* The state of pixel (x, y) before its first sample. */
static render_pixel_state pixel_state_start(const render_job *job, int x, int y)
{
    render_pixel_state st;
    memset(&st, 0, sizeof st);
    st.rng = pcg32_for_pixel(job->seed, (uint64_t)y * (uint64_t)job->cam->width + (uint64_t)x);
    return st;
}

/* Samples first .. end - 1 of pixel (x, y), added to its state: one call
 * for all spp samples, or several for consecutive ranges, make the same
 * numbers in the same order. */
static void pixel_add_samples(const render_job *job, int x, int y, int first, int end, render_pixel_state *st,
                              ray_counters *counters)
{
    int strata = 1; /* k = floor(sqrt(spp)) cells a side, when stratified */
    while ((strata + 1) * (strata + 1) <= job->spp)
        strata++;
    for (int s = first; s < end; s++) {
        vec3 sample;
        if (job->sample != NULL) { /* the sample's own function decides all (render.h) */
            sample = job->sample(job, x, y, s, &st->rng, counters);
        } else {
            float px = (float)x + 0.5f, py = (float)y + 0.5f;
            if (job->stratify && s < strata * strata) {
                /* cell (s mod k, s div k), and a uniform point inside it */
                px = (float)x + ((float)(s % strata) + pcg32_float(&st->rng)) / (float)strata;
                py = (float)y + ((float)(s / strata) + pcg32_float(&st->rng)) / (float)strata;
            } else if (job->spp > 1 || job->jitter || job->stratify) {
                px = (float)x + pcg32_float(&st->rng);
                py = (float)y + pcg32_float(&st->rng);
            }
            ray r = render_camera_ray(job, s, px, py, counters);
            sample = job->radiance(job->scene, r, &st->rng, counters);
        }
        if (explain_on()) {
            char c[64];
            explain_line(1, "sample radiance %s", explain_vec3(c, sample));
        }
        /* Drop NaN and Inf here, before they are added: one bad sample would
         * otherwise turn the whole pixel NaN (or white) for good. Dropping
         * biases the mean: the pixel becomes the mean of the finite samples
         * alone, as if the dropped ones had had that mean (an Inf stood for
         * a huge value, a NaN for an unknown one). The counters say how many
         * (nonfinite_samples_dropped, and a warning after the render); 0 in
         * every picture of the book, where the bias is therefore nil. */
        if (!vec3_is_finite(sample)) {
            counters->nonfinite_samples++;
            explain_line(1, "NaN or Inf: dropped, not averaged");
            continue;
        }
        welford_add(&st->channel[0], sample.x);
        welford_add(&st->channel[1], sample.y);
        welford_add(&st->channel[2], sample.z);
    }
}

/* The pixel's value (the mean) and, if wanted, its standard error. */
static vec3 pixel_state_value(const render_pixel_state *st, vec3 *std_error)
{
    const welford *channel = st->channel;
    if (std_error != NULL)
        *std_error = vec3_make((float)welford_standard_error(&channel[0]), (float)welford_standard_error(&channel[1]),
                               (float)welford_standard_error(&channel[2]));
    return vec3_make((float)welford_mean(&channel[0]), (float)welford_mean(&channel[1]),
                     (float)welford_mean(&channel[2]));
}

vec3 render_pixel(const render_job *job, int x, int y, ray_counters *counters, vec3 *std_error)
{
    render_pixel_state st = pixel_state_start(job, x, y);
    pixel_add_samples(job, x, y, 0, job->spp, &st, counters);
    return pixel_state_value(&st, std_error);
}

static int render_threads(const render_job *job)
{
#ifdef _OPENMP
    return job->threads > 0 ? job->threads : omp_get_max_threads();
#else
    (void)job;
    return 1;
#endif
}

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

/* The render in one pass: each pixel all its samples at once. */
static void render_whole(const render_job *job, image *out, render_stats *stats)
{
    const int width = job->cam->width, height = job->cam->height;
    progress bar;
    progress_begin(&bar, job->label ? job->label : "render", owned_rows(height), job->quiet);
    ray_counters total;
    memset(&total, 0, sizeof total);
    double start = timer_seconds();

    /* Rows are handed out one at a time (dynamic): rows that cross glass cost
     * more than rows of sky, and static blocks would leave a core idle. */
#pragma omp parallel num_threads(render_threads(job))
    {
        ray_counters mine;
        memset(&mine, 0, sizeof mine);
#pragma omp for schedule(dynamic, 1)
        for (int y = 0; y < height; y++) {
            if (!mpi_split_owns_row(y))
                continue; /* another rank's */
            for (int x = 0; x < width; x++) {
                vec3 std_error;
                vec3 c = render_pixel(job, x, y, &mine, job->standard_error ? &std_error : NULL);
                image_set(out, x, y, c);
                if (job->standard_error)
                    image_set(job->standard_error, x, y, std_error);
            }
            progress_advance(&bar, 1);
        }
#pragma omp critical(render_counters)
        counters_add(&total, &mine);
    }
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
        return states; /* each pixel's starts with its first sample (render_in_passes) */
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
    double start = timer_seconds(), last_checkpoint = start, per_sample = 0.0, gather = 0.0;
    while (done < job->spp) {
        int n = next_pass_samples(job, done, per_sample);
        double pass_start = timer_seconds();
#pragma omp parallel num_threads(render_threads(job))
        {
            ray_counters mine;
            memset(&mine, 0, sizeof mine);
#pragma omp for schedule(dynamic, 1)
            for (int y = 0; y < height; y++) {
                if (!mpi_split_owns_row(y))
                    continue;
                for (int x = 0; x < width; x++) {
                    render_pixel_state *st = &states[(size_t)y * width + x];
                    if (done == 0) /* here, not all at once: the pages fill as the rows are rendered */
                        *st = pixel_state_start(job, x, y);
                    pixel_add_samples(job, x, y, done, done + n, st, &mine);
                }
                progress_advance(&bar, n);
            }
#pragma omp critical(render_counters)
            counters_add(&total, &mine);
        }
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
                image_set(out, x, y, pixel_state_value(&states[(size_t)y * width + x], &std_error));
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
