#include "render.h"

#include <string.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "explain.h"
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

vec3 render_pixel(const render_job *job, int x, int y, ray_counters *counters, vec3 *std_error)
{
    const camera *cam = job->cam;
    pcg32 rng = pcg32_for_pixel(job->seed, (uint64_t)y * (uint64_t)cam->width + (uint64_t)x);
    welford channel[3] = {{0}, {0}, {0}};
    int strata = 1; /* k = floor(sqrt(spp)) cells a side, when stratified */
    while ((strata + 1) * (strata + 1) <= job->spp)
        strata++;
    for (int s = 0; s < job->spp; s++) {
        vec3 sample;
        if (job->sample != NULL) { /* the sample's own function decides all (render.h) */
            sample = job->sample(job, x, y, s, &rng, counters);
        } else {
            float px = (float)x + 0.5f, py = (float)y + 0.5f;
            if (job->stratify && s < strata * strata) {
                /* cell (s mod k, s div k), and a uniform point inside it */
                px = (float)x + ((float)(s % strata) + pcg32_float(&rng)) / (float)strata;
                py = (float)y + ((float)(s / strata) + pcg32_float(&rng)) / (float)strata;
            } else if (job->spp > 1 || job->jitter || job->stratify) {
                px = (float)x + pcg32_float(&rng);
                py = (float)y + pcg32_float(&rng);
            }
            ray r = render_camera_ray(job, s, px, py, counters);
            sample = job->radiance(job->scene, r, &rng, counters);
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
        welford_add(&channel[0], sample.x);
        welford_add(&channel[1], sample.y);
        welford_add(&channel[2], sample.z);
    }
    if (std_error != NULL)
        *std_error = vec3_make((float)welford_standard_error(&channel[0]), (float)welford_standard_error(&channel[1]),
                               (float)welford_standard_error(&channel[2]));
    return vec3_make((float)welford_mean(&channel[0]), (float)welford_mean(&channel[1]),
                     (float)welford_mean(&channel[2]));
}

void render_image(const render_job *job, image *out, render_stats *stats)
{
    const int width = job->cam->width, height = job->cam->height;
    int threads = job->threads;
#ifdef _OPENMP
    if (threads <= 0)
        threads = omp_get_max_threads();
#else
    threads = 1;
#endif
    progress bar;
    progress_begin(&bar, job->label ? job->label : "render", height, job->quiet);
    ray_counters total;
    memset(&total, 0, sizeof total);
    double start = timer_seconds();

    /* Rows are handed out one at a time (dynamic): rows that cross glass cost
     * more than rows of sky, and static blocks would leave a core idle. */
#pragma omp parallel num_threads(threads)
    {
        ray_counters mine;
        memset(&mine, 0, sizeof mine);
#pragma omp for schedule(dynamic, 1)
        for (int y = 0; y < height; y++) {
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
    if (stats != NULL) {
        stats->seconds = timer_seconds() - start;
        stats->counters = total;
    }
}
