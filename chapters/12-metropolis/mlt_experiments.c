/* mlt_experiments.c -- equal-time error of Metropolis and path tracing, and
 * start-up bias (see mlt_experiments.h). */
#include "12-metropolis/mlt_experiments.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "09-path-tracing/experiments.h"
#include "11-bidirectional/bdpt.h"
#include "timer.h"
#include "12-metropolis/mlt.h"
#include "12-metropolis/mlt_scene.h"
#include "atomic_file.h"

/* Images of 128 x 128: small, so the whole run stays near two minutes on
 * two cores, but not tiny -- on a 48 x 48 image Kelemen's small steps
 * (at most 1/64 of the film) move a path by under a pixel, so a chain
 * lingers in one pixel for tens of steps and its correlated samples cost
 * Metropolis its advantage (measured: README, "Hard cases"). */
enum { STARTUP_CHAINS = 1024 };
/* MLT's chains: enough to keep two threads busy, few enough that each is
 * long (its start matters little). */
enum { EXPERIMENT_CHAINS = 64 };

/* The size of a run: the image's side; the largest samples per pixel of
 * path tracing and mutations per pixel of MLT in the equal-time runs and
 * the start-up bias, and its replicas; the path-traced references (the
 * Cornell box converges fast, the lamp slowly); and what divides the
 * "which method" runs and their references. */
typedef struct {
    int size, pt_max_spp, mlt_max_mpp, startup_max_mpp, startup_replicas;
    int cornell_reference_spp, lamp_reference_spp;
    int methods_divisor;
} mlt_scale;

static const mlt_scale FULL_RUN = {128, 128, 64, 16, 3, 1024, 4096, 1};
/* --quick: every table in seconds, rough: 32 x 32 (where MLT's correlated
 * samples cost it its advantage, see above), short runs, small references. */
static const mlt_scale QUICK_RUN = {32, 32, 16, 4, 1, 256, 512, 8};

/* The bootstrap grows with the run: b's relative error scales every pixel
 * alike, so a bootstrap much smaller than the chains would put a floor
 * under the error. An eighth as many paths as mutations, at least 2^15. */
static int bootstrap_for(long long mutations)
{
    long long n = mutations / 8;
    return (int)(n < (1 << 15) ? (1 << 15) : n);
}

typedef struct {
    const char *name;
    void (*build)(pt_scene *sc);
    int reference_spp;
} experiment_scene;

/* Opens DIR/NAME (atomic_file.h) and writes its header at once: a disk
 * that cannot take the table fails here, before minutes of rendering the
 * reference. */
static bool open_table(atomic_file *table, const char *dir, const char *name, const char *header, char *err,
                       size_t err_size)
{
    if (!atomic_file_open_in(table, dir, name, err, err_size))
        return false;
    if (fprintf(table->stream, "%s\n", header) < 0 || fflush(table->stream) != 0) {
        snprintf(err, err_size, "cannot write '%s': %s", table->path, strerror(errno));
        atomic_file_abandon(table);
        return false;
    }
    return true;
}

/* The end of an experiment: frees its reference and scene, and keeps its
 * table only if everything went well. */
static bool finish_table(atomic_file *table, bool ok, estimate_image *reference, pt_scene *sc, char *err,
                         size_t err_size)
{
    estimate_image_free(reference);
    pt_scene_free(sc);
    if (!ok) {
        atomic_file_abandon(table);
        return false;
    }
    return atomic_file_commit(table, err, err_size);
}

static const double TARGETS[] = {1.0, 0.3, 0.1, 0.03};
enum { TARGET_COUNT = sizeof TARGETS / sizeof TARGETS[0], MAX_POINTS = 16 };

static bool equal_time(const experiment_scene *es, const mlt_scale *scale, const char *dir, int threads, char *err,
                       size_t err_size)
{
    pt_scene sc;
    es->build(&sc);
    path_tracer pt = path_tracer_defaults(&sc);
    pt.integrator = PT_MIS;
    pt.russian_roulette = RR_THROUGHPUT;
    camera cam = pt_scene_camera(&sc, scale->size, scale->size);
    char reference_path[4096], file[256];
    snprintf(reference_path, sizeof reference_path, "%s/ch12_reference_%s_%d.exr", dir, es->name, scale->size);
    printf("\n== scene %s (%dx%d)\n", es->name, scale->size, scale->size);
    snprintf(file, sizeof file, "ch12_equal_time_%s.csv", es->name);
    atomic_file table;
    if (!open_table(&table, dir, file, "method,label,samples_per_pixel,wall_seconds,cpu_seconds,rmse,relmse,acceptance",
                    err, err_size)) {
        pt_scene_free(&sc);
        return false;
    }
    FILE *csv = table.stream;
    /* Freed on failure too: a reference that was rendered but could not be
     * saved is still held. */
    estimate_image reference = {0};
    if (!experiment_reference(&pt, &cam, es->reference_spp, threads, reference_path, &reference, err, err_size))
        return finish_table(&table, false, &reference, &sc, err, err_size);
    static const char *const labels[2] = {"path tracing (MIS + RR on throughput)", "Metropolis (PSSMLT)"};
    double seconds[2][MAX_POINTS], relmses[2][MAX_POINTS];
    int samples[2][MAX_POINTS], count[2] = {0, 0};
    bool ok = true;
    for (int method = 0; method < 2 && ok; method++) {
        /* up to about the same CPU time: a mutation costs about twice a path */
        for (int spp = 1; spp <= (method == 0 ? scale->pt_max_spp : scale->mlt_max_mpp); spp *= 2) {
            image img = image_make(cam.width, cam.height);
            double cpu_start = experiment_cpu_seconds(), wall = 0.0, acceptance = 0.0;
            if (method == 0) {
                estimate_image e = render_estimate(&pt, &cam, spp, 0x1234ULL + (uint64_t)spp, threads);
                image_free(&img);
                img = e.mean;
                image_free(&e.standard_error);
                wall = e.seconds;
            } else {
                mlt_options o = mlt_defaults(&pt, &cam);
                o.mutations_per_pixel = spp;
                o.chains = EXPERIMENT_CHAINS;
                o.bootstrap = bootstrap_for((long long)spp * cam.width * cam.height);
                o.seed = 0x1234ULL + (uint64_t)spp;
                o.threads = threads;
                mlt_result r;
                if (!mlt_render(&o, &img, &r)) {
                    snprintf(err, err_size, "out of memory");
                    ok = false;
                    image_free(&img);
                    break;
                }
                wall = r.seconds;
                acceptance = r.proposed > 0 ? (double)r.accepted / (double)r.proposed : 0.0;
            }
            double cpu = experiment_cpu_seconds() - cpu_start, rmse, relmse;
            experiment_error(&img, &reference, &rmse, &relmse);
            image_free(&img);
            fprintf(csv, "%d,%s,%d,%.6f,%.6f,%.8g,%.8g,%.4f\n", method, labels[method], spp, wall, cpu, rmse, relmse,
                    acceptance);
            int k = count[method]++;
            seconds[method][k] = cpu;
            relmses[method][k] = relmse;
            samples[method][k] = spp;
        }
    }
    if (!ok)
        return finish_table(&table, false, &reference, &sc, err, err_size);
    printf("CPU seconds to reach relMSE (from %s):\n", table.path);
    printf("  %-40s", "");
    for (int t = 0; t < TARGET_COUNT; t++)
        printf("  relMSE %-6g", TARGETS[t]);
    printf("\n");
    for (int method = 0; method < 2; method++) {
        printf("  %-40s", labels[method]);
        for (int t = 0; t < TARGET_COUNT; t++) {
            int spp;
            double s = experiment_time_to_reach(seconds[method], relmses[method], samples[method], count[method],
                                                TARGETS[t], &spp);
            if (s < 0.0)
                printf("  %-13s", "not reached");
            else
                printf("  %7.3f s    ", s);
        }
        printf("\n");
    }
    printf("  relMSE at the largest run: path tracing %.4g in %.2f s, Metropolis %.4g in %.2f s\n",
           relmses[0][count[0] - 1], seconds[0][count[0] - 1], relmses[1][count[1] - 1], seconds[1][count[1] - 1]);
    return finish_table(&table, true, &reference, &sc, err, err_size);
}

/* Short runs of many chains, each started at a bootstrap path picked in
 * proportion to f, or all at one fixed path: the error of the fixed start
 * is the start-up bias, largest when the chains are shortest. */
static bool startup_bias(const mlt_scale *scale, const char *dir, int threads, char *err, size_t err_size)
{
    pt_scene sc;
    pt_scene_build_cornell_box(&sc);
    path_tracer pt = path_tracer_defaults(&sc);
    pt.integrator = PT_MIS;
    pt.russian_roulette = RR_THROUGHPUT;
    camera cam = pt_scene_camera(&sc, scale->size, scale->size);
    char reference_path[4096];
    snprintf(reference_path, sizeof reference_path, "%s/ch12_reference_cornell_%d.exr", dir, scale->size);
    printf("\n== start-up bias (Cornell box, %d chains, mean of %d runs)\n", STARTUP_CHAINS, scale->startup_replicas);
    atomic_file table;
    if (!open_table(&table, dir, "ch12_startup_bias.csv",
                    "start,label,mutations_per_pixel,mutations_per_chain,cpu_seconds,relmse", err, err_size)) {
        pt_scene_free(&sc);
        return false;
    }
    FILE *csv = table.stream;
    estimate_image reference = {0};
    if (!experiment_reference(&pt, &cam, scale->cornell_reference_spp, threads, reference_path, &reference, err, err_size))
        return finish_table(&table, false, &reference, &sc, err, err_size);
    static const char *const labels[2] = {"bootstrap start", "fixed start"};
    printf("  %-18s %-18s %-14s %s\n", "mutations/pixel", "mutations/chain", "bootstrap", "fixed start");
    bool ok = true;
    double mean_relmse[2][MAX_POINTS];
    int points = 0;
    /* one start after the other, so each is a contiguous line in the CSV */
    for (int start = 0; start < 2 && ok; start++) {
        points = 0;
        for (int mpp = 1; mpp <= scale->startup_max_mpp && ok; mpp *= 2) {
            long long per_chain = (long long)mpp * cam.width * cam.height / STARTUP_CHAINS;
            double cpu_total = 0.0, relmse_total = 0.0;
            for (int replica = 0; replica < scale->startup_replicas; replica++) {
                mlt_options o = mlt_defaults(&pt, &cam);
                o.mutations_per_pixel = mpp;
                o.chains = STARTUP_CHAINS;
                o.bootstrap = 1 << 16;
                o.seed = 0x5747ULL + (uint64_t)(replica * 1000 + mpp);
                o.threads = threads;
                o.start = start == 0 ? MLT_START_BOOTSTRAP : MLT_START_FIXED;
                image img = image_make(cam.width, cam.height);
                mlt_result r;
                double cpu_start = experiment_cpu_seconds();
                if (!mlt_render(&o, &img, &r)) {
                    snprintf(err, err_size, "out of memory");
                    ok = false;
                }
                cpu_total += experiment_cpu_seconds() - cpu_start;
                double rmse, relmse;
                experiment_error(&img, &reference, &rmse, &relmse);
                relmse_total += relmse;
                image_free(&img);
            }
            mean_relmse[start][points++] = relmse_total / scale->startup_replicas;
            fprintf(csv, "%d,%s,%d,%lld,%.6f,%.8g\n", start, labels[start], mpp, per_chain,
                    cpu_total / scale->startup_replicas, relmse_total / scale->startup_replicas);
        }
    }
    for (int k = 0, mpp = 1; ok && k < points; k++, mpp *= 2)
        printf("  %-18d %-18lld %-14.4g %.4g\n", mpp, (long long)mpp * cam.width * cam.height / STARTUP_CHAINS,
               mean_relmse[0][k], mean_relmse[1][k]);
    return finish_table(&table, ok, &reference, &sc, err, err_size);
}

/* ---- which method for which scene ---------------------------------------------- */

const char *const mlt_method_names[MLT_METHOD_COUNT] = {"path tracing (ch09 MIS)", "bidirectional (ch11)",
                                                        "Metropolis (ch12 PSSMLT)"};

bool mlt_method_render(mlt_method method, const pt_scene *sc, const camera *cam, int samples, uint64_t seed,
                       int threads, image *out)
{
    path_tracer pt = path_tracer_defaults(sc);
    pt.integrator = PT_MIS;
    pt.russian_roulette = RR_THROUGHPUT;
    if (method == MLT_METHOD_PATH_TRACING) {
        estimate_image e = render_estimate(&pt, cam, samples, seed, threads);
        image_free(&e.standard_error);
        *out = e.mean;
        return true;
    }
    if (method == MLT_METHOD_BIDIRECTIONAL) {
        bdpt b = bdpt_defaults(sc, cam);
        estimate_image e;
        if (!bdpt_render(&b, samples, seed, threads, true, &e))
            return false;
        image_free(&e.standard_error);
        *out = e.mean;
        return true;
    }
    mlt_options o = mlt_defaults(&pt, cam);
    o.mutations_per_pixel = samples;
    o.chains = EXPERIMENT_CHAINS;
    o.bootstrap = bootstrap_for((long long)samples * cam->width * cam->height);
    o.seed = seed;
    o.threads = threads;
    *out = image_make(cam->width, cam->height);
    mlt_result r;
    if (!mlt_render(&o, out, &r)) {
        image_free(out);
        return false;
    }
    return true;
}

/* The largest sample count of each method: about the same CPU time each
 * (measured: a BDPT sample, a camera path and a light path joined in every
 * way, costs about 5 path-traced samples; a mutation about 2). */
static const int METHOD_MAX_SAMPLES[MLT_METHOD_COUNT] = {512, 128, 256};
/* Each reference is the mean of 16 independent renders by the method that
 * converges fastest on its scene, each pixel's standard error the spread
 * of the 16 over sqrt(16) (BDPT's splats and MLT's chains have no
 * per-pixel standard error of their own; the replicas' spread is right
 * for any unbiased method). Their size is chosen so that the reference's
 * own relMSE is well below every error plotted: the run checks and prints
 * it, and its variance is subtracted as well (experiment_error). Path
 * traced references of the two lamps were not good enough: 8192 spp on the
 * ceiling lamp had relMSE 0.002, and 16384 spp on the lamp in a housing
 * 0.004, both about BDPT's own error after 128 samples; BDPT's 16 x 128
 * reach 5e-5 and 2.5e-4. */
enum { REFERENCE_REPLICAS = 16 };

typedef struct {
    const char *name, *title;
    void (*build)(pt_scene *sc);
    mlt_method reference_method;
    int reference_samples; /* per replica */
    /* The relMSE whose CPU time the table gives: chosen from the measured
     * run, reached by as many methods as possible. */
    double target_relmse;
} methods_scene;

static bool methods_reference(const methods_scene *ms, int samples, const pt_scene *sc, const camera *cam, int threads,
                              const char *dir, estimate_image *out, char *err, size_t err_size)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/ch12_methods_reference_%s_%d.exr", dir, ms->name, cam->width);
    if (experiment_reference_load(path, cam->width, cam->height, out, err, err_size))
        return true;
    printf("reference: rendering %dx%d by %s, %d runs of %d samples per pixel ...\n", cam->width, cam->height,
           mlt_method_names[ms->reference_method], REFERENCE_REPLICAS, samples);
    fflush(stdout);
    size_t n = (size_t)cam->width * (size_t)cam->height * 3;
    double *sum = calloc(n, sizeof *sum), *sum2 = calloc(n, sizeof *sum2);
    bool ok = sum != NULL && sum2 != NULL;
    double start = experiment_cpu_seconds();
    for (int k = 0; k < REFERENCE_REPLICAS && ok; k++) {
        image img;
        ok = mlt_method_render(ms->reference_method, sc, cam, samples, 0x5eed00ULL + (uint64_t)k,
                               threads, &img);
        for (size_t i = 0; ok && i < n; i++) {
            sum[i] += img.rgb[i];
            sum2[i] += (double)img.rgb[i] * img.rgb[i];
        }
        if (ok)
            image_free(&img);
    }
    if (!ok) {
        free(sum);
        free(sum2);
        snprintf(err, err_size, "out of memory");
        return false;
    }
    out->mean = image_make(cam->width, cam->height);
    out->standard_error = image_make(cam->width, cam->height);
    out->spp = (long)REFERENCE_REPLICAS * samples;
    out->seconds = experiment_cpu_seconds() - start;
    memset(&out->counters, 0, sizeof out->counters);
    for (size_t i = 0; i < n; i++) {
        double mean = sum[i] / REFERENCE_REPLICAS;
        double variance = fmax(0.0, (sum2[i] - sum[i] * mean) / (REFERENCE_REPLICAS - 1));
        out->mean.rgb[i] = (float)mean;
        out->standard_error.rgb[i] = (float)sqrt(variance / REFERENCE_REPLICAS);
    }
    free(sum);
    free(sum2);
    printf("reference: %.1f CPU s, estimated relative error %.4f -> %s\n", out->seconds,
           estimate_relative_error(out), path);
    return experiment_reference_save(out, path, err, err_size);
}

typedef struct {
    double cpu[MAX_POINTS], relmse[MAX_POINTS];
    int samples[MAX_POINTS];
    int count;
} method_curve;

static bool methods_scene_run(const methods_scene *ms, const mlt_scale *scale, const char *dir, int threads,
                              FILE *time_table, char *err, size_t err_size)
{
    pt_scene sc;
    ms->build(&sc);
    char message[256];
    if (!bdpt_supports(&sc, message, sizeof message)) {
        /* every scene here is diffuse with emitting triangles: this is a
         * guard for a scene added later */
        snprintf(err, err_size, "%s: bidirectional path tracing refuses it: %s", ms->name, message);
        pt_scene_free(&sc);
        return false;
    }
    camera cam = pt_scene_camera(&sc, scale->size, scale->size);
    char file[256];
    printf("\n== which method: %s (%dx%d)\n", ms->title, scale->size, scale->size);
    snprintf(file, sizeof file, "ch12_methods_%s.csv", ms->name);
    atomic_file table;
    if (!open_table(&table, dir, file, "method,label,samples,cpu_seconds,relmse,rmse", err, err_size)) {
        pt_scene_free(&sc);
        return false;
    }
    FILE *csv = table.stream;
    estimate_image reference = {0};
    if (!methods_reference(ms, ms->reference_samples / scale->methods_divisor, &sc, &cam, threads, dir, &reference, err,
                           err_size))
        return finish_table(&table, false, &reference, &sc, err, err_size);
    method_curve curves[MLT_METHOD_COUNT];
    double smallest = INFINITY;
    bool ok = true;
    printf("  %-26s %8s %9s %11s\n", "method", "samples", "CPU s", "relMSE");
    for (int m = 0; m < MLT_METHOD_COUNT && ok; m++) {
        method_curve *c = &curves[m];
        c->count = 0;
        for (int n = 1; n <= METHOD_MAX_SAMPLES[m] / scale->methods_divisor; n *= 2) {
            image img;
            double start = experiment_cpu_seconds();
            if (!mlt_method_render((mlt_method)m, &sc, &cam, n, 0x3e7ULL + (uint64_t)n, threads, &img)) {
                snprintf(err, err_size, "out of memory");
                ok = false;
                break;
            }
            double cpu = experiment_cpu_seconds() - start, rmse, relmse;
            experiment_error(&img, &reference, &rmse, &relmse);
            image_free(&img);
            fprintf(csv, "%d,%s,%d,%.6f,%.8g,%.8g\n", m, mlt_method_names[m], n, cpu, relmse, rmse);
            printf("  %-26s %8d %9.3f %11.5g\n", mlt_method_names[m], n, cpu, relmse);
            fflush(stdout);
            c->cpu[c->count] = cpu;
            c->relmse[c->count] = relmse;
            c->samples[c->count] = n;
            c->count++;
            smallest = fmin(smallest, relmse);
        }
    }
    if (ok) {
        /* The reference's own relMSE, as its variance predicts it: small
         * against the smallest error measured, or the curves flatten on
         * its noise rather than on theirs. */
        double reference_error = estimate_relative_error(&reference);
        double reference_relmse = reference_error * reference_error;
        printf("  reference relMSE %.3g = %.3f of the smallest measured (%.3g)%s\n", reference_relmse,
               reference_relmse / smallest, smallest,
               reference_relmse > 0.1 * smallest ? ": NOT well below -- render it with more samples" : "");
        printf("  CPU seconds to reach relMSE %g:", ms->target_relmse);
        for (int m = 0; m < MLT_METHOD_COUNT; m++) {
            int samples = 0;
            double s = experiment_time_to_reach(curves[m].cpu, curves[m].relmse, curves[m].samples, curves[m].count,
                                                ms->target_relmse, &samples);
            if (s < 0.0) {
                printf("  %s not reached;", mlt_method_names[m]);
                fprintf(time_table, "%s,%d,%s,%g,,,%.4g\n", ms->name, m, mlt_method_names[m], ms->target_relmse,
                        reference_relmse);
            } else {
                printf("  %s %.2f s;", mlt_method_names[m], s);
                fprintf(time_table, "%s,%d,%s,%g,%.4f,%d,%.4g\n", ms->name, m, mlt_method_names[m], ms->target_relmse, s,
                        samples, reference_relmse);
            }
        }
        printf("\n");
    }
    return finish_table(&table, ok, &reference, &sc, err, err_size);
}

/* The three unbiased methods on the three scenes, each against one
 * reference: DIR/ch12_methods_NAME.csv and ch12_methods_time_to_error.csv. */
static bool methods_compare(const mlt_scale *scale, const char *dir, int threads, char *err, size_t err_size)
{
    /* name, title, scene, the method and samples per replica of its
     * reference, the target relMSE of the time-to-error table */
    const methods_scene scenes[] = {
        {"cornell", "Cornell box (light seen directly)", pt_scene_build_cornell_box, MLT_METHOD_PATH_TRACING, 512,
         0.01},
        {"ceiling-lamp", "ceiling lamp (ch11: lit only by the ceiling's bright patch)",
         bdpt_scene_build_ceiling_lamp, MLT_METHOD_BIDIRECTIONAL, 128, 0.1},
        {"lamp", "lamp in a housing (light only through a 2 cm channel)", mlt_scene_build_lamp,
         MLT_METHOD_BIDIRECTIONAL, 128, 0.3},
    };
    atomic_file table;
    if (!open_table(&table, dir, "ch12_methods_time_to_error.csv",
                    "scene,method,label,target_relmse,cpu_seconds,samples,reference_relmse", err, err_size))
        return false;
    double start = experiment_cpu_seconds(), wall_start = timer_seconds();
    for (size_t i = 0; i < sizeof scenes / sizeof scenes[0]; i++)
        if (!methods_scene_run(&scenes[i], scale, dir, threads, table.stream, err, err_size)) {
            atomic_file_abandon(&table);
            return false;
        }
    printf("\nwhich method for which scene: %.1f CPU s, %.1f s wall in all\n", experiment_cpu_seconds() - start,
           timer_seconds() - wall_start);
    return atomic_file_commit(&table, err, err_size);
}

bool mlt_experiments_run(const char *dir, int threads, bool quick, char *err, size_t err_size)
{
    const mlt_scale *scale = quick ? &QUICK_RUN : &FULL_RUN;
    const experiment_scene scenes[] = {
        {"cornell", pt_scene_build_cornell_box, scale->cornell_reference_spp},
        {"lamp", mlt_scene_build_lamp, scale->lamp_reference_spp},
    };
    for (size_t i = 0; i < sizeof scenes / sizeof scenes[0]; i++)
        if (!equal_time(&scenes[i], scale, dir, threads, err, err_size))
            return false;
    return startup_bias(scale, dir, threads, err, err_size) && methods_compare(scale, dir, threads, err, err_size);
}
