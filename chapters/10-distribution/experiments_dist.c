/* experiments_dist.c -- rays per bounce against samples per pixel, at equal
 * time (experiments_dist.h). */
#include "10-distribution/experiments_dist.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "09-path-tracing/experiments.h"
#include "10-distribution/distribution.h"
#include "atomic_file.h"
#include "render.h"

enum { EXPERIMENT_DEPTH = 4 };

/* The size of the run: the image's side, the reference's samples per
 * pixel, and how far each setting doubles its samples (until a render
 * takes seconds_per_setting of CPU, or reaches max_spp). */
typedef struct {
    int size, reference_spp;
    double seconds_per_setting;
    int max_spp;
} dist_scale;

static const dist_scale FULL_RUN = {64, 16384, 3.0, 1024};
/* --quick: the same curves, rough, in a few seconds (the book's default). */
static const dist_scale QUICK_RUN = {32, 1024, 0.25, 64};

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

/* Both tables are opened, and their headers written through, before the
 * minute of rendering: a directory that cannot take them fails now. */
static bool open_tables(atomic_file *noise, atomic_file *counts, const char *dir, char *err, size_t err_size)
{
    if (!atomic_file_open_in(noise, dir, "ch10_noise.csv", err, err_size))
        return false;
    if (!atomic_file_open_in(counts, dir, "ch10_ray_counts.csv", err, err_size)) {
        atomic_file_abandon(noise);
        return false;
    }
    fprintf(noise->stream,
            "rays_per_bounce,spp,cpu_seconds,rmse,rays_per_camera_ray,shadow_per_camera_ray,glossy_per_camera_ray\n");
    fprintf(counts->stream,
            "glossy_samples,max_depth,rays_per_camera_ray,glossy_per_camera_ray,worst_case_glossy,cpu_seconds\n");
    bool noise_ok = fflush(noise->stream) == 0 && !ferror(noise->stream);
    bool counts_ok = fflush(counts->stream) == 0 && !ferror(counts->stream);
    if (!noise_ok || !counts_ok) {
        snprintf(err, err_size, "cannot write '%s': %s", noise_ok ? counts->path : noise->path, strerror(errno));
        atomic_file_abandon(noise);
        atomic_file_abandon(counts);
        return false;
    }
    return true;
}

/* N_light = N_glossy = N for N = 1, 2, 4, 8, each at doubling samples per
 * pixel until a render takes scale->seconds_per_setting: RMSE against the
 * reference, and rays per camera ray. */
static void measure_noise(distribution_tracer *dt, const camera *cam, const image *reference, int threads,
                          const dist_scale *scale, FILE *csv)
{
    image img = image_make(cam->width, cam->height);
    ray_counters counters;
    printf("%4s %6s %10s %10s %14s\n", "N", "spp", "CPU s", "RMSE", "rays/cam ray");
    const int settings[4] = {1, 2, 4, 8};
    for (int k = 0; k < 4; k++) {
        dt->light_samples = dt->glossy_samples = settings[k];
        for (int spp = 1;; spp *= 2) {
            double seconds = render_timed(dt, cam, spp, 1 + (uint64_t)spp * 16 + (uint64_t)k, threads, &img,
                                          &counters);
            double rmse = sqrt(image_mse(&img, reference));
            double cam_rays = (double)counters.camera_rays;
            double per_camera = (double)counters_total_rays(&counters) / cam_rays;
            fprintf(csv, "%d,%d,%.6f,%.6g,%.4f,%.4f,%.4f\n", settings[k], spp, seconds, rmse, per_camera,
                    (double)counters.shadow_rays / cam_rays, (double)counters.indirect_rays / cam_rays);
            printf("%4d %6d %10.3f %10.4g %14.2f\n", settings[k], spp, seconds, rmse, per_camera);
            if (seconds > scale->seconds_per_setting || spp >= scale->max_spp)
                break;
        }
    }
    image_free(&img);
}

/* The explosion itself: rays per camera ray as N_glossy and the depth grow
 * (N_light = 1), at 1 sample per pixel, against the worst case (every hit
 * glossy) sum N^d. */
static void measure_ray_counts(distribution_tracer *dt, const camera *cam, int threads, FILE *csv)
{
    image img = image_make(cam->width, cam->height);
    ray_counters counters;
    printf("\n%9s %6s %14s %14s %12s\n", "N_glossy", "depth", "rays/cam ray", "glossy/cam", "worst case");
    dt->light_samples = 1;
    const int glossy[4] = {1, 2, 4, 8};
    for (int g = 0; g < 4; g++)
        for (int depth = 1; depth <= 4; depth++) {
            dt->glossy_samples = glossy[g];
            dt->max_depth = depth;
            double seconds = render_timed(dt, cam, 1, 7, threads, &img, &counters);
            double cam_rays = (double)counters.camera_rays;
            double worst = distribution_glossy_rays_per_camera_ray(glossy[g], depth);
            fprintf(csv, "%d,%d,%.4f,%.4f,%.0f,%.6f\n", glossy[g], depth,
                    (double)counters_total_rays(&counters) / cam_rays, (double)counters.indirect_rays / cam_rays,
                    worst, seconds);
            printf("%9d %6d %14.2f %14.3f %12.0f\n", glossy[g], depth,
                   (double)counters_total_rays(&counters) / cam_rays, (double)counters.indirect_rays / cam_rays,
                   worst);
        }
    image_free(&img);
}

bool experiment_rays_per_bounce(const motion_scene *ms, int threads, bool quick, const char *dir, char *err,
                                size_t err_size)
{
    const dist_scale *scale = quick ? &QUICK_RUN : &FULL_RUN;
    const int size = scale->size;
    atomic_file noise, counts;
    if (!open_tables(&noise, &counts, dir, err, err_size))
        return false;
    camera cam = pt_scene_camera(&ms->base, size, size);
    distribution_tracer dt = distribution_tracer_defaults(ms, &cam);
    dt.max_depth = EXPERIMENT_DEPTH;
    image reference = image_make(size, size);
    ray_counters counters;
    printf("reference: %dx%d, N = 1, %d spp%s ...\n", size, size, scale->reference_spp, quick ? " (--quick)" : "");
    fflush(stdout);
    double reference_seconds = render_timed(&dt, &cam, scale->reference_spp, 999, threads, &reference, &counters);
    printf("reference: %.1f CPU s\n", reference_seconds);
    measure_noise(&dt, &cam, &reference, threads, scale, noise.stream);
    image_free(&reference);
    measure_ray_counts(&dt, &cam, threads, counts.stream);
    /* Both tables or neither. */
    if (!atomic_file_commit(&noise, err, err_size)) {
        atomic_file_abandon(&counts);
        return false;
    }
    return atomic_file_commit(&counts, err, err_size);
}
