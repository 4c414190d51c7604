/* experiments_dist.c -- rays per bounce against samples per pixel, at equal
 * time (experiments_dist.h). */
#include "10-distribution/experiments_dist.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "09-path-tracing/experiments.h"
#include "10-distribution/distribution.h"
#include "render.h"

enum { EXPERIMENT_SIZE = 64, REFERENCE_SPP = 16384, EXPERIMENT_DEPTH = 4 };
/* Each setting doubles its samples per pixel until a render takes this long. */
static const double CPU_SECONDS_PER_SETTING = 3.0;

static double render_timed(const distribution_tracer *dt, const camera *cam, int spp, uint64_t seed, int threads,
                           image *out, ray_counters *counters)
{
    render_job job = {.cam = cam, .spp = spp, .seed = seed, .threads = threads, .quiet = true,
                      .radiance = distribution_radiance, .scene = dt, .stratify = true};
    render_stats stats;
    double start = experiment_cpu_seconds();
    render_image(&job, out, &stats);
    *counters = stats.counters;
    return experiment_cpu_seconds() - start;
}

bool experiment_rays_per_bounce(const motion_scene *ms, int threads, const char *dir, char *err, size_t err_size)
{
    /* Both tables are opened, and their headers written through, before the
     * minute of rendering: a directory that cannot take them fails now. */
    char noise_path[4096], counts_path[4096];
    FILE *noise = experiment_csv_open(dir, "ch10_noise.csv", noise_path, sizeof noise_path, err, err_size);
    if (noise == NULL)
        return false;
    FILE *counts = experiment_csv_open(dir, "ch10_ray_counts.csv", counts_path, sizeof counts_path, err, err_size);
    if (counts == NULL) {
        experiment_csv_discard(noise, noise_path);
        return false;
    }
    fprintf(noise, "rays_per_bounce,spp,cpu_seconds,rmse,rays_per_camera_ray,shadow_per_camera_ray,glossy_per_camera_ray\n");
    fprintf(counts, "glossy_samples,max_depth,rays_per_camera_ray,glossy_per_camera_ray,worst_case_glossy,cpu_seconds\n");
    bool noise_ok = fflush(noise) == 0 && !ferror(noise), counts_ok = fflush(counts) == 0 && !ferror(counts);
    if (!noise_ok || !counts_ok) {
        snprintf(err, err_size, "%s: write failed (%s)", noise_ok ? counts_path : noise_path, strerror(errno));
        experiment_csv_discard(noise, noise_path);
        experiment_csv_discard(counts, counts_path);
        return false;
    }

    camera cam = pt_scene_camera(&ms->base, EXPERIMENT_SIZE, EXPERIMENT_SIZE);
    distribution_tracer dt = distribution_tracer_defaults(ms, &cam);
    dt.max_depth = EXPERIMENT_DEPTH;
    image reference = image_make(EXPERIMENT_SIZE, EXPERIMENT_SIZE), img = image_make(EXPERIMENT_SIZE, EXPERIMENT_SIZE);
    ray_counters counters;
    printf("reference: %dx%d, N = 1, %d spp ...\n", EXPERIMENT_SIZE, EXPERIMENT_SIZE, REFERENCE_SPP);
    fflush(stdout);
    double reference_seconds = render_timed(&dt, &cam, REFERENCE_SPP, 999, threads, &reference, &counters);
    printf("reference: %.1f CPU s\n", reference_seconds);

    printf("%4s %6s %10s %10s %14s\n", "N", "spp", "CPU s", "RMSE", "rays/cam ray");
    const int settings[4] = {1, 2, 4, 8};
    for (int k = 0; k < 4; k++) {
        dt.light_samples = dt.glossy_samples = settings[k];
        for (int spp = 1;; spp *= 2) {
            double seconds = render_timed(&dt, &cam, spp, 1 + (uint64_t)spp * 16 + (uint64_t)k, threads, &img,
                                          &counters);
            double rmse = sqrt(image_mse(&img, &reference));
            double cam_rays = (double)counters.camera_rays;
            double per_camera = (double)counters_total_rays(&counters) / cam_rays;
            fprintf(noise, "%d,%d,%.6f,%.6g,%.4f,%.4f,%.4f\n", settings[k], spp, seconds, rmse, per_camera,
                    (double)counters.shadow_rays / cam_rays, (double)counters.indirect_rays / cam_rays);
            printf("%4d %6d %10.3f %10.4g %14.2f\n", settings[k], spp, seconds, rmse, per_camera);
            if (seconds > CPU_SECONDS_PER_SETTING || spp >= 1024)
                break;
        }
    }

    /* The explosion itself: rays per camera ray as N_glossy and the depth
     * grow (N_light = 1), at 1 sample per pixel, against the worst case
     * (every hit glossy) sum N^d. */
    printf("\n%9s %6s %14s %14s %12s\n", "N_glossy", "depth", "rays/cam ray", "glossy/cam", "worst case");
    dt.light_samples = 1;
    const int glossy[4] = {1, 2, 4, 8};
    for (int g = 0; g < 4; g++)
        for (int depth = 1; depth <= 4; depth++) {
            dt.glossy_samples = glossy[g];
            dt.max_depth = depth;
            double seconds = render_timed(&dt, &cam, 1, 7, threads, &img, &counters);
            double cam_rays = (double)counters.camera_rays;
            double worst = distribution_glossy_rays_per_camera_ray(glossy[g], depth);
            fprintf(counts, "%d,%d,%.4f,%.4f,%.0f,%.6f\n", glossy[g], depth,
                    (double)counters_total_rays(&counters) / cam_rays, (double)counters.indirect_rays / cam_rays,
                    worst, seconds);
            printf("%9d %6d %14.2f %14.3f %12.0f\n", glossy[g], depth,
                   (double)counters_total_rays(&counters) / cam_rays, (double)counters.indirect_rays / cam_rays,
                   worst);
        }
    image_free(&reference);
    image_free(&img);
    if (!experiment_csv_close(noise, noise_path, err, err_size)) {
        experiment_csv_discard(counts, counts_path);
        return false;
    }
    return experiment_csv_close(counts, counts_path, err, err_size);
}
