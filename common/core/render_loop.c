/* render_loop.c -- a pixel's samples and the rows of an image (render_loop.h). */
#include "render_loop.h"

#include <stdio.h>
#include <string.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "explain.h"
#include "stats.h"

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

render_pixel_state render_pixel_state_start(const render_job *job, int x, int y)
{
    render_pixel_state st;
    memset(&st, 0, sizeof st);
    st.rng = pcg32_for_pixel(job->seed, (uint64_t)y * (uint64_t)job->cam->width + (uint64_t)x);
    return st;
}

void render_pixel_add_samples(const render_job *job, int x, int y, int first, int end, render_pixel_state *st,
                              ray_counters *counters)
{
    int strata = 1; /* k = floor(sqrt(spp)) cells a side, when stratified */
    while ((strata + 1) * (strata + 1) <= job->spp)
        strata++;
    for (int s = first; s < end; s++) {
        vec3 sample;
        if (job->sample != NULL) { /* the sample's own function decides all (render_loop.h) */
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

vec3 render_pixel_value(const render_pixel_state *st, vec3 *std_error)
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
    render_pixel_state st = render_pixel_state_start(job, x, y);
    render_pixel_add_samples(job, x, y, 0, job->spp, &st, counters);
    return render_pixel_value(&st, std_error);
}

int render_threads(const render_job *job)
{
#ifdef _OPENMP
    return job->threads > 0 ? job->threads : omp_get_max_threads();
#else
    (void)job;
    return 1;
#endif
}

static bool owns_row(const render_rows_split *split, int y)
{
    return split == NULL || split->owns_row == NULL || split->owns_row(y);
}

static void row_done(const render_rows_split *split, int64_t samples_per_pixel)
{
    if (split != NULL && split->row_done != NULL)
        split->row_done(split->context, samples_per_pixel);
}

void render_rows(const render_job *job, image *out, const render_rows_split *split, ray_counters *total)
{
    const int width = job->cam->width, height = job->cam->height;
#pragma omp parallel num_threads(render_threads(job))
    {
        ray_counters mine;
        memset(&mine, 0, sizeof mine);
#pragma omp for schedule(dynamic, 1)
        for (int y = 0; y < height; y++) {
            if (!owns_row(split, y))
                continue; /* another process's */
            for (int x = 0; x < width; x++) {
                vec3 std_error;
                vec3 c = render_pixel(job, x, y, &mine, job->standard_error ? &std_error : NULL);
                image_set(out, x, y, c);
                if (job->standard_error)
                    image_set(job->standard_error, x, y, std_error);
            }
            row_done(split, job->spp);
        }
#pragma omp critical(render_counters)
        counters_add(total, &mine);
    }
}

void render_rows_pass(const render_job *job, render_pixel_state *states, int done, int n,
                      const render_rows_split *split, ray_counters *total)
{
    const int width = job->cam->width, height = job->cam->height;
#pragma omp parallel num_threads(render_threads(job))
    {
        ray_counters mine;
        memset(&mine, 0, sizeof mine);
#pragma omp for schedule(dynamic, 1)
        for (int y = 0; y < height; y++) {
            if (!owns_row(split, y))
                continue;
            for (int x = 0; x < width; x++) {
                render_pixel_state *st = &states[(size_t)y * width + x];
                if (done == 0) /* here, not all at once: the pages fill as the rows are rendered */
                    *st = render_pixel_state_start(job, x, y);
                render_pixel_add_samples(job, x, y, done, done + n, st, &mine);
            }
            row_done(split, n);
        }
#pragma omp critical(render_counters)
        counters_add(total, &mine);
    }
}
