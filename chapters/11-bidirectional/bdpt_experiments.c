/* bdpt_experiments.c -- equal-time error: chapter 09's best path tracer
 * against bidirectional path tracing (see bdpt_experiments.h). */
#include "11-bidirectional/bdpt_experiments.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "atomic_file.h"

typedef struct {
    double cpu[BDPT_EXPERIMENT_MAX_POINTS], relmse[BDPT_EXPERIMENT_MAX_POINTS];
    int spp[BDPT_EXPERIMENT_MAX_POINTS];
    int count;
} error_curve;

/* relMSE at `seconds`, interpolated log-log between the two renders either
 * side (or -1 if the curve does not reach that far). */
static double relmse_at(const error_curve *c, double seconds)
{
    for (int i = 1; i < c->count; i++)
        if (c->cpu[i - 1] <= seconds && seconds <= c->cpu[i] && c->relmse[i - 1] > 0.0 && c->relmse[i] > 0.0) {
            double f = log(seconds / c->cpu[i - 1]) / log(c->cpu[i] / c->cpu[i - 1]);
            return exp(log(c->relmse[i - 1]) + f * log(c->relmse[i] / c->relmse[i - 1]));
        }
    return -1.0;
}

static const char *const METHOD_LABELS[2] = {"path tracing (ch09 MIS, RR on throughput)",
                                               "bidirectional (power heuristic)"};

/* One render of `method` (0: path tracing, 1: bidirectional) at spp
 * samples per pixel; false if the splat film found no memory. */
static bool render_method(int method, const pt_scene *sc, const camera *cam, int spp, uint64_t seed, int threads,
                          estimate_image *e)
{
    if (method == 0) {
        path_tracer pt = path_tracer_defaults(sc);
        pt.integrator = PT_MIS;
        pt.russian_roulette = RR_THROUGHPUT;
        *e = render_estimate(&pt, cam, spp, seed, threads);
        return true;
    }
    bdpt b = bdpt_defaults(sc, cam);
    return bdpt_render(&b, spp, seed, threads, true, e);
}

/* One method's error curve: doubling spp until the next render would
 * overrun the budget; a row per render into csv. */
static bool measure_method(int method, const pt_scene *sc, const camera *cam, const estimate_image *reference,
                           double seconds_per_method, int threads, FILE *csv, error_curve *c)
{
    c->count = 0;
    double spent = 0.0;
    for (int spp = 1; c->count < BDPT_EXPERIMENT_MAX_POINTS; spp *= 2) {
        estimate_image e;
        double start = experiment_cpu_seconds();
        if (!render_method(method, sc, cam, spp, 2000 + (uint64_t)spp, threads, &e))
            return false;
        double cpu = experiment_cpu_seconds() - start;
        double rmse, relmse;
        experiment_error(&e.mean, reference, &rmse, &relmse);
        estimate_image_free(&e);
        fprintf(csv, "%d,\"%s\",%d,%.6f,%.6e,%.6e\n", method, METHOD_LABELS[method], spp, cpu, relmse, rmse);
        printf("%-44s %6d %9.3f %10.5f\n", METHOD_LABELS[method], spp, cpu, relmse);
        fflush(stdout);
        c->cpu[c->count] = cpu;
        c->relmse[c->count] = relmse;
        c->spp[c->count] = spp;
        c->count++;
        spent += cpu;
        if (2.0 * cpu > seconds_per_method - spent)
            break;
    }
    return true;
}

bool bdpt_experiment_equal_time(const pt_scene *sc, const char *name, const camera *cam,
                                const estimate_image *reference, double seconds_per_method, int threads,
                                const char *dir, bdpt_experiment_result *result, char *err, size_t err_size)
{
    char file[256];
    snprintf(file, sizeof file, "ch11_equal_time_%s.csv", name);
    atomic_file csv;
    if (!atomic_file_open_in(&csv, dir, file, err, err_size))
        return false;
    fprintf(csv.stream, "method,label,spp,cpu_seconds,relmse,rmse\n");
    error_curve curves[2];
    printf("\n%-44s %6s %9s %10s\n", name, "spp", "CPU s", "relMSE");
    for (int method = 0; method < 2; method++)
        if (!measure_method(method, sc, cam, reference, seconds_per_method, threads, csv.stream, &curves[method])) {
            snprintf(err, err_size, "out of memory for the splat film");
            atomic_file_abandon(&csv);
            return false;
        }
    /* Equal time: both at the longest time both curves reach */
    double t = fmin(curves[0].cpu[curves[0].count - 1], curves[1].cpu[curves[1].count - 1]);
    result->seconds = t;
    result->relmse_path_tracing = relmse_at(&curves[0], t);
    result->relmse_bidirectional = relmse_at(&curves[1], t);
    printf("%s at %.2f CPU s: relMSE %.4g path tracing, %.4g bidirectional (%.2fx)\n", name, t,
           result->relmse_path_tracing, result->relmse_bidirectional,
           result->relmse_path_tracing / result->relmse_bidirectional);
    return atomic_file_commit(&csv, err, err_size);
}
