/* bdpt_experiments.c -- equal-time error: chapter 09's best path tracer
 * against bidirectional path tracing (see bdpt_experiments.h). */
#include "11-bidirectional/bdpt_experiments.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

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

bool bdpt_experiment_equal_time(const pt_scene *sc, const char *name, const camera *cam,
                                const estimate_image *reference, double seconds_per_method, int threads,
                                const char *dir, bdpt_experiment_result *result, char *err, size_t err_size)
{
    char path[4096], file[256];
    snprintf(file, sizeof file, "ch11_equal_time_%s.csv", name);
    FILE *csv = experiment_csv_open(dir, file, path, sizeof path, err, err_size);
    if (csv == NULL)
        return false;
    fprintf(csv, "method,label,spp,cpu_seconds,relmse,rmse\n");
    const char *labels[2] = {"path tracing (ch09 MIS, RR on throughput)", "bidirectional (power heuristic)"};
    error_curve curves[2];
    printf("\n%-44s %6s %9s %10s\n", name, "spp", "CPU s", "relMSE");
    for (int method = 0; method < 2; method++) {
        error_curve *c = &curves[method];
        c->count = 0;
        double spent = 0.0;
        /* doubling spp until the next render would overrun the budget */
        for (int spp = 1; c->count < BDPT_EXPERIMENT_MAX_POINTS; spp *= 2) {
            estimate_image e;
            uint64_t seed = 2000 + (uint64_t)spp;
            double start = experiment_cpu_seconds();
            if (method == 0) {
                path_tracer pt = path_tracer_defaults(sc);
                pt.integrator = PT_MIS;
                pt.russian_roulette = RR_THROUGHPUT;
                e = render_estimate(&pt, cam, spp, seed, threads);
            } else {
                bdpt b = bdpt_defaults(sc, cam);
                if (!bdpt_render(&b, spp, seed, threads, true, &e)) {
                    snprintf(err, err_size, "out of memory for the splat film");
                    experiment_csv_discard(csv, path);
                    return false;
                }
            }
            double cpu = experiment_cpu_seconds() - start;
            double rmse, relmse;
            experiment_error(&e.mean, reference, &rmse, &relmse);
            estimate_image_free(&e);
            fprintf(csv, "%d,\"%s\",%d,%.6f,%.6e,%.6e\n", method, labels[method], spp, cpu, relmse, rmse);
            printf("%-44s %6d %9.3f %10.5f\n", labels[method], spp, cpu, relmse);
            fflush(stdout);
            c->cpu[c->count] = cpu;
            c->relmse[c->count] = relmse;
            c->spp[c->count] = spp;
            c->count++;
            spent += cpu;
            if (2.0 * cpu > seconds_per_method - spent)
                break;
        }
    }
    /* Equal time: both at the longest time both curves reach */
    double t = fmin(curves[0].cpu[curves[0].count - 1], curves[1].cpu[curves[1].count - 1]);
    result->seconds = t;
    result->relmse_path_tracing = relmse_at(&curves[0], t);
    result->relmse_bidirectional = relmse_at(&curves[1], t);
    printf("%s at %.2f CPU s: relMSE %.4g path tracing, %.4g bidirectional (%.2fx)\n", name, t,
           result->relmse_path_tracing, result->relmse_bidirectional,
           result->relmse_path_tracing / result->relmse_bidirectional);
    return experiment_csv_close(csv, path, err, err_size);
}
