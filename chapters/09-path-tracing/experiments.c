/* experiments.c -- measuring error against time (see experiments.h). */
#include "experiments.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "timer.h"

/* relMSE's guard against dividing by near-black pixels (as image_relmse). */
static const double RELATIVE_ERROR_EPSILON = 1e-2;

void estimate_image_free(estimate_image *e)
{
    image_free(&e->mean);
    image_free(&e->standard_error);
}

estimate_image render_estimate(const path_tracer *pt, const camera *cam, int spp, uint64_t seed, int threads)
{
    estimate_image e;
    e.mean = image_make(cam->width, cam->height);
    e.standard_error = image_make(cam->width, cam->height);
    render_job job = {.cam = cam, .spp = spp, .seed = seed, .threads = threads, .quiet = true,
                      .radiance = path_trace_radiance, .scene = pt, .standard_error = &e.standard_error,
                      .jitter = true};
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

estimate_image render_progressive(const path_tracer *pt, const camera *cam, uint64_t seed, int threads,
                                  double seconds, double target_error, FILE *log)
{
    double start = timer_seconds();
    estimate_image total = render_estimate(pt, cam, 1, seed, threads);
    for (int pass = 1;; pass++) {
        double elapsed = timer_seconds() - start, error = estimate_relative_error(&total);
        if (log != NULL)
            fprintf(log, "pass %2d: %6ld spp, %8.2f s, estimated relative error %.4f\n", pass, total.spp, elapsed, error);
        if (target_error > 0.0 && error <= target_error) {
            if (log != NULL)
                fprintf(log, "reached the target error %.4f\n", target_error);
            break;
        }
        /* The next pass doubles the samples so far: stop now if it would
         * overrun the budget (passes take time in proportion to spp). */
        double per_sample = elapsed / (double)total.spp;
        if (seconds > 0.0 && elapsed + per_sample * (double)total.spp > seconds) {
            if (log != NULL)
                fprintf(log, "stopped at the time budget %.1f s (another pass would take %.1f s)\n", seconds,
                        per_sample * (double)total.spp);
            break;
        }
        estimate_image next = render_estimate(pt, cam, (int)total.spp, seed + (uint64_t)pass * 0x9e3779b9ULL, threads);
        merge_estimates(&total, &next);
        estimate_image_free(&next);
    }
    total.seconds = timer_seconds() - start;
    return total;
}

/* ---- the reference ------------------------------------------------------------ */

static void standard_error_path(const char *path, char *out, size_t size)
{
    size_t n = strlen(path);
    snprintf(out, size, "%.*s-stderr.exr", (int)(n > 4 ? n - 4 : n), path);
}

bool experiment_reference(const path_tracer *pt, const camera *cam, int spp, int threads, const char *path,
                          estimate_image *out, char *err, size_t err_size)
{
    char se_path[4096];
    standard_error_path(path, se_path, sizeof se_path);
    image mean = {0}, se = {0};
    if (access(path, R_OK) == 0 && access(se_path, R_OK) == 0 && image_read_exr(&mean, path, err, err_size) &&
        image_read_exr(&se, se_path, err, err_size) && mean.width == cam->width && mean.height == cam->height &&
        se.width == cam->width && se.height == cam->height) {
        out->mean = mean;
        out->standard_error = se;
        out->spp = spp;
        out->seconds = 0.0;
        memset(&out->counters, 0, sizeof out->counters);
        printf("reference: %s (cached; delete it to render it again)\n", path);
        return true;
    }
    image_free(&mean);
    image_free(&se);
    path_tracer reference = *pt;
    reference.integrator = PT_MIS;
    reference.russian_roulette = RR_THROUGHPUT;
    printf("reference: rendering %dx%d at %d spp with MIS ...\n", cam->width, cam->height, spp);
    fflush(stdout);
    *out = render_estimate(&reference, cam, spp, 0x5eedULL, threads);
    printf("reference: %.1f s, estimated relative error %.4f -> %s\n", out->seconds, estimate_relative_error(out), path);
    if (!image_write_exr(&out->mean, path, err, err_size))
        return false;
    /* The cache is the pair: a new mean beside an old standard error (or
     * none) must not be taken for one next time. */
    if (!image_write_exr(&out->standard_error, se_path, err, err_size)) {
        unlink(path);
        return false;
    }
    return true;
}

/* ---- error against the reference ---------------------------------------------------
 * The reference has noise of its own, which adds its variance to every
 * measured MSE; subtracting the mean of its squared standard error leaves the
 * error of the image under test (an unbiased correction). */
static void measure_error(const estimate_image *e, const estimate_image *ref, double *rmse, double *relmse)
{
    size_t n = (size_t)e->mean.width * (size_t)e->mean.height * 3;
    double sum = 0.0, sum_relative = 0.0;
    for (size_t i = 0; i < n; i++) {
        double d = (double)e->mean.rgb[i] - (double)ref->mean.rgb[i];
        double s = ref->standard_error.rgb[i], r = ref->mean.rgb[i];
        double squared = d * d - s * s;
        sum += squared;
        sum_relative += squared / (r * r + RELATIVE_ERROR_EPSILON);
    }
    *rmse = sqrt(fmax(0.0, sum / (double)n));
    *relmse = fmax(0.0, sum_relative / (double)n);
}

/* A CSV is written as "<path>.tmp" and renamed into place only when every
 * write succeeded: a full disk or a killed run leaves the old table (or
 * none), never half of one that a plot would draw without complaint. */
static void csv_temp_path(const char *path, char *temp, size_t size) { snprintf(temp, size, "%s.tmp", path); }

static FILE *open_csv(const char *dir, const char *name, char *path, size_t path_size, char *err, size_t err_size)
{
    char temp[4200];
    snprintf(path, path_size, "%s/%s", dir, name);
    csv_temp_path(path, temp, sizeof temp);
    FILE *f = fopen(temp, "w");
    if (f == NULL)
        snprintf(err, err_size, "%s: %s", path, strerror(errno));
    return f;
}

/* Closes without keeping anything: for a run that failed elsewhere. */
static void discard_csv(FILE *f, const char *path)
{
    char temp[4200];
    csv_temp_path(path, temp, sizeof temp);
    fclose(f);
    unlink(temp);
}

static bool close_csv(FILE *f, const char *path, char *err, size_t err_size)
{
    char temp[4200];
    csv_temp_path(path, temp, sizeof temp);
    /* An earlier fprintf may have failed (ferror); the final flush and close
     * may fail too (a full disk shows up there). */
    bool written = !ferror(f) && fflush(f) == 0;
    int reason = errno;
    if (fclose(f) != 0 && written) {
        written = false;
        reason = errno;
    }
    if (!written) {
        snprintf(err, err_size, "%s: write failed (%s)", path, reason != 0 ? strerror(reason) : "stream error");
        unlink(temp);
        return false;
    }
    if (rename(temp, path) != 0) {
        snprintf(err, err_size, "%s: %s", path, strerror(errno));
        unlink(temp);
        return false;
    }
    return true;
}

typedef struct {
    pt_integrator integrator;
    pt_russian_roulette rr;
    const char *label;
} rung;

static const rung rungs[] = {
    {PT_LECTURE, RR_FIXED, "lecture (uniform hemisphere, P_RR 0.8)"},
    {PT_COSINE, RR_FIXED, "cosine-weighted (P_RR 0.8)"},
    {PT_MIS, RR_FIXED, "BSDF sampling + MIS (P_RR 0.8)"},
    {PT_MIS, RR_THROUGHPUT, "BSDF sampling + MIS, RR on throughput"},
};
enum { RUNG_COUNT = sizeof rungs / sizeof rungs[0] };

bool experiment_convergence(const pt_scene *sc, const camera *cam, const estimate_image *reference, int max_spp,
                            int threads, double target_relmse, const char *dir, char *err, size_t err_size)
{
    char path[4096], time_path[4096];
    FILE *csv = open_csv(dir, "ch09_convergence.csv", path, sizeof path, err, err_size);
    if (csv == NULL)
        return false;
    FILE *time_csv = open_csv(dir, "ch09_time_to_error.csv", time_path, sizeof time_path, err, err_size);
    if (time_csv == NULL) {
        discard_csv(csv, path);
        return false;
    }
    fprintf(csv, "rung,integrator,russian_roulette,spp,seconds,rmse,relmse,rays_per_sample\n");
    fprintf(time_csv, "rung,label,target_relmse,seconds,spp\n");
    printf("\n%-42s %6s %9s %10s %10s\n", "rung", "spp", "seconds", "RMSE", "relMSE");
    for (int k = 0; k < RUNG_COUNT; k++) {
        path_tracer pt = path_tracer_defaults(sc);
        pt.integrator = rungs[k].integrator;
        pt.russian_roulette = rungs[k].rr;
        double previous_seconds = 0.0, previous_relmse = 0.0, reached_seconds = -1.0;
        int reached_spp = 0;
        for (int spp = 1; spp <= max_spp; spp *= 2) {
            estimate_image e = render_estimate(&pt, cam, spp, 1000 + (uint64_t)spp, threads);
            double rmse, relmse;
            measure_error(&e, reference, &rmse, &relmse);
            double rays = (double)counters_total_rays(&e.counters) / ((double)spp * cam->width * cam->height);
            fprintf(csv, "%d,%s,%s,%d,%.6f,%.6e,%.6e,%.3f\n", k, pt_integrator_name(pt.integrator),
                    pt.russian_roulette == RR_FIXED ? "fixed" : "throughput", spp, e.seconds, rmse, relmse, rays);
            printf("%-42s %6d %9.3f %10.4f %10.5f\n", rungs[k].label, spp, e.seconds, rmse, relmse);
            /* Time to reach the target: interpolate log(relMSE) against
             * log(seconds) between the two renders either side of it. */
            if (reached_seconds < 0.0 && relmse <= target_relmse && relmse > 0.0) {
                if (previous_relmse > target_relmse && previous_seconds > 0.0) {
                    double f = log(previous_relmse / target_relmse) / log(previous_relmse / relmse);
                    reached_seconds = exp(log(previous_seconds) + f * log(e.seconds / previous_seconds));
                } else {
                    reached_seconds = e.seconds;
                }
                reached_spp = spp;
            }
            previous_seconds = e.seconds;
            previous_relmse = relmse;
            estimate_image_free(&e);
        }
        fprintf(time_csv, "%d,\"%s\",%g,%.6f,%d\n", k, rungs[k].label, target_relmse, reached_seconds, reached_spp);
    }
    printf("\ntime to reach relMSE %g (%dx%d):\n", target_relmse, cam->width, cam->height);
    fflush(time_csv);
    bool ok = close_csv(csv, path, err, err_size);
    if (ok)
        ok = close_csv(time_csv, time_path, err, err_size);
    else
        discard_csv(time_csv, time_path);
    if (ok) {
        FILE *again = fopen(time_path, "r");
        char line[512];
        while (again != NULL && fgets(line, sizeof line, again))
            if (line[0] != 'r')
                printf("  %s", line);
        if (again != NULL)
            fclose(again);
    }
    return ok;
}

bool experiment_russian_roulette(const pt_scene *sc, const camera *cam, const estimate_image *reference, int spp,
                                 int threads, const char *dir, char *err, size_t err_size)
{
    char path[4096];
    FILE *csv = open_csv(dir, "ch09_russian_roulette.csv", path, sizeof path, err, err_size);
    if (csv == NULL)
        return false;
    const float probabilities[] = {0.2f, 0.4f, 0.6f, 0.8f, 0.9f, 0.95f};
    fprintf(csv, "p_rr,seconds,mse,efficiency,rays_per_sample\n");
    printf("\nRussian roulette (cosine rung, %d spp): P_RR, seconds, MSE, efficiency 1/(MSE x time)\n", spp);
    for (int i = 0; i < 6; i++) {
        path_tracer pt = path_tracer_defaults(sc);
        pt.integrator = PT_COSINE;
        pt.russian_roulette = RR_FIXED;
        pt.rr_probability = probabilities[i];
        estimate_image e = render_estimate(&pt, cam, spp, 77, threads);
        double rmse, relmse;
        measure_error(&e, reference, &rmse, &relmse);
        double mse = rmse * rmse;
        double rays = (double)counters_total_rays(&e.counters) / ((double)spp * cam->width * cam->height);
        fprintf(csv, "%.2f,%.6f,%.6e,%.6e,%.3f\n", (double)probabilities[i], e.seconds, mse, 1.0 / (mse * e.seconds), rays);
        printf("  %.2f %8.3f s  %.4e  %.4e  %.2f rays/sample\n", (double)probabilities[i], e.seconds, mse,
               1.0 / (mse * e.seconds), rays);
        estimate_image_free(&e);
    }
    return close_csv(csv, path, err, err_size);
}
