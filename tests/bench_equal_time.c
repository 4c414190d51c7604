/* bench_equal_time.c -- error against time, renderer by renderer, on a common
 * reference: which renderer gives the smaller error for the same CPU time?
 *
 * Reads the runs listed in a manifest (one line per render, written by
 * bench_scenes --render and by tests/bench_cycles.py):
 *     renderer,scene,spp,threads,seed,cpu_seconds,wall_seconds,image.exr
 * and, for each scene, the reference REFDIR/SCENE.exr with its standard
 * error REFDIR/SCENE-stderr.exr (bench_scenes --reference: chapter 09's MIS
 * rung at many samples). For every run: relMSE and MSE against it, the
 * project's definitions, less the reference's own noise
 * (experiment_error), and relMSE x CPU seconds, which is constant while the
 * error is variance (it falls as 1/spp while the time grows as spp): its
 * inverse is the renderer's efficiency. Then, at the CPU times the anchor
 * (--anchor, default cycles) took, each renderer's relMSE interpolated in
 * log-log between its own runs (the mean over seeds at each spp), and its
 * ratio to the anchor's: below 1, that renderer wins at equal time.
 *
 * A floor in a renderer's relMSE as its spp grows is bias: it renders a
 * different image from the reference (a material or camera matched
 * imperfectly), and no time removes it.
 *
 * Prints the tables; --csv FILE writes every run's figures (for a plot of
 * error against CPU seconds). A benchmark: it asserts nothing. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "09-path-tracing/experiments.h"
#include "atomic_file.h"
#include "image.h"

typedef struct {
    char renderer[64], scene[128], path[1024];
    int spp, threads;
    unsigned long long seed;
    double cpu, wall, relmse, mse;
    bool measured;
} run;

enum { MAX_RUNS = 4096, MAX_NAMES = 16 };

/* One manifest line into r; false (with a message naming the line) if it
 * is not of the form above. */
static bool parse_run(const char *line, const char *source, int number, run *r)
{
    char copy[2048];
    snprintf(copy, sizeof copy, "%s", line);
    copy[strcspn(copy, "\r\n")] = '\0';
    char *fields[8];
    int n = 0;
    for (char *save = NULL, *f = strtok_r(copy, ",", &save); f != NULL && n < 8; f = strtok_r(NULL, ",", &save))
        fields[n++] = f;
    if (n != 8) {
        fprintf(stderr, "bench_equal_time: %s:%d: expected 8 fields (renderer,scene,spp,threads,seed,cpu,wall,file)\n",
                source, number);
        return false;
    }
    *r = (run){0};
    snprintf(r->renderer, sizeof r->renderer, "%s", fields[0]);
    snprintf(r->scene, sizeof r->scene, "%s", fields[1]);
    r->spp = atoi(fields[2]);
    r->threads = atoi(fields[3]);
    r->seed = strtoull(fields[4], NULL, 10);
    r->cpu = atof(fields[5]);
    r->wall = atof(fields[6]);
    snprintf(r->path, sizeof r->path, "%s", fields[7]);
    if (r->spp <= 0 || !(r->cpu > 0.0)) {
        fprintf(stderr, "bench_equal_time: %s:%d: spp and CPU seconds must be positive\n", source, number);
        return false;
    }
    return true;
}

static int load_manifest(const char *path, run *runs, int max)
{
    FILE *f = fopen(path, "r");
    if (f == NULL) {
        fprintf(stderr, "bench_equal_time: %s: cannot read it\n", path);
        return -1;
    }
    char line[2048];
    int n = 0, number = 0;
    while (fgets(line, sizeof line, f) != NULL && n < max) {
        number++;
        if (line[0] == '#' || line[0] == '\n')
            continue;
        if (!parse_run(line, path, number, &runs[n])) {
            fclose(f);
            return -1;
        }
        n++;
    }
    fclose(f);
    return n;
}

/* The distinct values of one field, in order of first appearance. */
static int distinct(const run *runs, int n, bool scene, const char *names[MAX_NAMES])
{
    int count = 0;
    for (int i = 0; i < n; i++) {
        const char *name = scene ? runs[i].scene : runs[i].renderer;
        bool seen = false;
        for (int k = 0; k < count && !seen; k++)
            seen = strcmp(names[k], name) == 0;
        if (!seen && count < MAX_NAMES)
            names[count++] = name;
    }
    return count;
}

/* A renderer's runs on a scene as points (CPU seconds, relMSE), the mean
 * over seeds at each spp, by growing spp. */
typedef struct {
    int spp;
    double cpu, relmse;
} curve_point;

static int curve(const run *runs, int n, const char *scene, const char *renderer, curve_point *out, int max)
{
    int count = 0;
    for (int i = 0; i < n; i++) {
        const run *r = &runs[i];
        if (!r->measured || strcmp(r->scene, scene) != 0 || strcmp(r->renderer, renderer) != 0)
            continue;
        int k = 0;
        while (k < count && out[k].spp != r->spp)
            k++;
        if (k == count) {
            if (count == max)
                continue;
            out[count++] = (curve_point){r->spp, 0.0, 0.0};
        }
        /* summed here, divided by the number of seeds below */
        out[k].cpu += r->cpu;
        out[k].relmse += r->relmse;
    }
    for (int k = 0; k < count; k++) {
        int seeds = 0;
        for (int i = 0; i < n; i++)
            seeds += runs[i].measured && runs[i].spp == out[k].spp && strcmp(runs[i].scene, scene) == 0 &&
                     strcmp(runs[i].renderer, renderer) == 0;
        out[k].cpu /= seeds;
        out[k].relmse /= seeds;
    }
    for (int a = 1; a < count; a++) /* by spp: insertion sort, a handful of points */
        for (int b = a; b > 0 && out[b - 1].spp > out[b].spp; b--) {
            curve_point t = out[b];
            out[b] = out[b - 1];
            out[b - 1] = t;
        }
    return count;
}

/* relMSE at CPU time t by log-log interpolation between the curve's
 * points. Outside their range, *extrapolated is set and the nearest end
 * point is carried as relMSE ~ 1 / time (the variance's law: right while
 * the error is noise, wrong once bias shows). NAN for an empty curve. */
static double relmse_at(const curve_point *c, int n, double t, bool *extrapolated)
{
    *extrapolated = false;
    for (int k = 0; k + 1 < n; k++) {
        double t0 = c[k].cpu, t1 = c[k + 1].cpu;
        if (t >= fmin(t0, t1) && t <= fmax(t0, t1) && t0 != t1 && c[k].relmse > 0 && c[k + 1].relmse > 0) {
            double f = (log(t) - log(t0)) / (log(t1) - log(t0));
            return exp(log(c[k].relmse) + f * (log(c[k + 1].relmse) - log(c[k].relmse)));
        }
    }
    int nearest = -1;
    for (int k = 0; k < n; k++) {
        if (c[k].cpu == t)
            return c[k].relmse;
        if (nearest < 0 || fabs(log(c[k].cpu / t)) < fabs(log(c[nearest].cpu / t)))
            nearest = k;
    }
    if (nearest < 0)
        return NAN;
    *extrapolated = true;
    return c[nearest].relmse * c[nearest].cpu / t;
}

static bool measure(run *r, const char *reference_dir, estimate_image *reference, char *loaded_scene,
                    size_t loaded_size)
{
    char err[4200];
    image img = {0};
    if (!image_read_exr(&img, r->path, err, sizeof err)) {
        fprintf(stderr, "bench_equal_time: %s\n", err);
        return false;
    }
    if (strcmp(loaded_scene, r->scene) != 0) {
        if (loaded_scene[0] != '\0')
            estimate_image_free(reference);
        loaded_scene[0] = '\0';
        char path[4096];
        snprintf(path, sizeof path, "%s/%s.exr", reference_dir, r->scene);
        if (!experiment_reference_load(path, img.width, img.height, reference, err, sizeof err)) {
            fprintf(stderr, "bench_equal_time: no reference %s of %dx%d%s%s (bench_scenes --reference)\n", path,
                    img.width, img.height, err[0] ? ": " : "", err);
            image_free(&img);
            return false;
        }
        snprintf(loaded_scene, loaded_size, "%s", r->scene);
    }
    double rmse;
    experiment_error(&img, reference, &rmse, &r->relmse);
    r->mse = rmse * rmse;
    r->measured = true;
    image_free(&img);
    return true;
}

static double product_mean(const run *runs, int n, const char *scene, const char *renderer)
{
    double sum = 0.0;
    int count = 0;
    for (int i = 0; i < n; i++)
        if (runs[i].measured && runs[i].relmse > 0.0 && strcmp(runs[i].scene, scene) == 0 &&
            strcmp(runs[i].renderer, renderer) == 0) {
            sum += log(runs[i].relmse * runs[i].cpu);
            count++;
        }
    return count > 0 ? exp(sum / count) : NAN;
}

static void report_scene(const run *runs, int n, const char *scene, const char *anchor)
{
    const char *renderers[MAX_NAMES];
    int rcount = distinct(runs, n, false, renderers);
    printf("\n%s: error against the common reference (chapter 09 mis, converged), CPU seconds of the render alone\n",
           scene);
    printf("%-14s %6s %6s %8s %10s %10s %12s %12s %14s\n", "renderer", "spp", "seed", "threads", "CPU s", "wall s",
           "relMSE", "MSE", "relMSE x CPU");
    for (int k = 0; k < rcount; k++)
        for (int i = 0; i < n; i++) {
            const run *r = &runs[i];
            if (r->measured && strcmp(r->scene, scene) == 0 && strcmp(r->renderer, renderers[k]) == 0)
                printf("%-14s %6d %6llu %8d %10.3f %10.3f %12.4g %12.4g %14.4g\n", r->renderer, r->spp, r->seed,
                       r->threads, r->cpu, r->wall, r->relmse, r->mse, r->relmse * r->cpu);
        }
    curve_point anchor_curve[64];
    int an = curve(runs, n, scene, anchor, anchor_curve, 64);
    if (an == 0) {
        printf("(no %s runs on %s: no equal-time table)\n", anchor, scene);
        return;
    }
    printf("equal CPU time: relMSE interpolated at %s's CPU times, and its ratio to %s's (< 1: fewer errors "
           "at the same cost)\n", anchor, anchor);
    printf("%-14s", "CPU s");
    for (int j = 0; j < an; j++)
        printf(" %19.3f ", anchor_curve[j].cpu);
    printf("\n");
    for (int k = 0; k < rcount; k++) {
        curve_point c[64];
        int cn = curve(runs, n, scene, renderers[k], c, 64);
        printf("%-14s", renderers[k]);
        for (int j = 0; j < an; j++) {
            bool extrapolated;
            double e = relmse_at(c, cn, anchor_curve[j].cpu, &extrapolated);
            if (isnan(e))
                printf(" %19s", "(no runs)");
            else
                printf(" %10.4g (%5.2fx)%s", e, e / anchor_curve[j].relmse, extrapolated ? "*" : " ");
        }
        printf("\n");
    }
    printf("(* outside that renderer's runs: its nearest run carried as relMSE ~ 1 / CPU time)\n");
    /* relMSE x CPU seconds over all of a renderer's runs (the geometric
     * mean): its inverse is the efficiency, whatever the sample count,
     * while the error is variance */
    double anchor_product = product_mean(runs, n, scene, anchor);
    printf("relMSE x CPU s, geometric mean of each renderer's runs, and its ratio to %s's (< 1: more efficient):", anchor);
    for (int k = 0; k < rcount; k++) {
        double p = product_mean(runs, n, scene, renderers[k]);
        printf(" %s %.4g (%.2fx)%s", renderers[k], p, p / anchor_product, k + 1 < rcount ? ";" : "");
    }
    printf("\n");
}

static void usage(void)
{
    printf("usage: bench_equal_time --manifest FILE.csv --references DIR [--anchor NAME] [--csv FILE]\n"
           "Error against CPU time of each renderer's runs on a common reference, and at equal CPU time.\n"
           "  --manifest FILE   runs, one per line: renderer,scene,spp,threads,seed,cpu_s,wall_s,image.exr\n"
           "  --references DIR  DIR/SCENE.exr and DIR/SCENE-stderr.exr (bench_scenes --reference)\n"
           "  --anchor NAME     the renderer the others are compared with at its CPU times (default cycles)\n"
           "  --csv FILE        every run with its relMSE and MSE, for a plot\n");
}

static run runs[MAX_RUNS];

int main(int argc, char **argv)
{
    const char *manifest = NULL, *reference_dir = NULL, *anchor = "cycles", *csv_path = NULL;
    for (int i = 1; i < argc; i++) {
        const char *value = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(argv[i], "--help") == 0) {
            usage();
            return 0;
        } else if (value != NULL && strcmp(argv[i], "--manifest") == 0) {
            manifest = value;
        } else if (value != NULL && strcmp(argv[i], "--references") == 0) {
            reference_dir = value;
        } else if (value != NULL && strcmp(argv[i], "--anchor") == 0) {
            anchor = value;
        } else if (value != NULL && strcmp(argv[i], "--csv") == 0) {
            csv_path = value;
        } else {
            fprintf(stderr, "bench_equal_time: unknown or incomplete argument '%s' (try --help)\n", argv[i]);
            return 2;
        }
        i++;
    }
    if (manifest == NULL || reference_dir == NULL) {
        fprintf(stderr, "bench_equal_time: --manifest and --references are needed (try --help)\n");
        return 2;
    }
    int n = load_manifest(manifest, runs, MAX_RUNS);
    if (n < 0)
        return 1;
    estimate_image reference;
    char loaded[128] = "";
    int failed = 0;
    for (int i = 0; i < n; i++)
        failed += !measure(&runs[i], reference_dir, &reference, loaded, sizeof loaded);
    if (loaded[0] != '\0')
        estimate_image_free(&reference);
    const char *scenes[MAX_NAMES];
    int scount = distinct(runs, n, true, scenes);
    for (int s = 0; s < scount; s++)
        report_scene(runs, n, scenes[s], anchor);
    if (csv_path != NULL) {
        char err[4200];
        atomic_file f;
        if (!atomic_file_open(&f, csv_path, err, sizeof err)) {
            fprintf(stderr, "bench_equal_time: %s\n", err);
            return 1;
        }
        fprintf(f.stream, "scene,renderer,spp,threads,seed,cpu_s,wall_s,relmse,mse\n");
        for (int i = 0; i < n; i++)
            if (runs[i].measured)
                fprintf(f.stream, "%s,%s,%d,%d,%llu,%.6f,%.6f,%.6g,%.6g\n", runs[i].scene, runs[i].renderer,
                        runs[i].spp, runs[i].threads, runs[i].seed, runs[i].cpu, runs[i].wall, runs[i].relmse,
                        runs[i].mse);
        if (!atomic_file_commit(&f, err, sizeof err)) {
            fprintf(stderr, "bench_equal_time: %s\n", err);
            return 1;
        }
    }
    return failed ? 1 : 0;
}
