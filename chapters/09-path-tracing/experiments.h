/* experiments.h -- what accuracy costs in time: chapter 09's measurements.
 *
 *   experiment_reference()   the image every error is measured against,
 *                            rendered once at high sample count and cached
 *   experiment_convergence() RMSE and relMSE against the reference for each
 *                            rung, as a function of samples per pixel and
 *                            of seconds (CSV for plots/ch09_*.gp)
 *   experiment_russian_roulette()  variance, time and efficiency for a
 *                            range of P_RR
 *   experiment_roulettes()   the same for the lecture's, pbrt's and
 *                            smallpt's roulettes and none (RTROWL's)
 *   render_progressive()     passes of doubling sample counts until a time
 *                            budget or a target error (estimated from the
 *                            per-pixel variance) is reached
 */
#ifndef EXPERIMENTS_H
#define EXPERIMENTS_H

#include <stdbool.h>
#include <stdio.h>

#include "09-path-tracing/path_tracer.h"
#include "image.h"
#include "progressive.h"
#include "render.h"

/* progressive.h's estimate_render and progressive_render (estimate_image,
 * estimate_relative_error, estimate_image_free are there too), with the
 * path tracer as the integrator. */
estimate_image render_estimate(const path_tracer *pt, const camera *cam, int spp, uint64_t seed, int threads);
estimate_image render_progressive(const path_tracer *pt, const camera *cam, uint64_t seed, int threads,
                                  double seconds, double target_error, FILE *log);

/* Loads the cached reference from `path` if it is there and of this size,
 * else renders it (MIS, `spp` samples) and saves it. */
bool experiment_reference(const path_tracer *pt, const camera *cam, int spp, int threads, const char *path,
                          estimate_image *out, char *err, size_t err_size);

/* The cache experiment_reference keeps, for references made otherwise
 * (chapter 12's, by other methods): _load fills *out from the pair
 * `path` and its "-stderr.exr" if both are there and width x height (else
 * false, *out untouched); _save writes the pair (neither, on failure). */
bool experiment_reference_load(const char *path, int width, int height, estimate_image *out, char *err,
                               size_t err_size);
bool experiment_reference_save(const estimate_image *e, const char *path, char *err, size_t err_size);

/* Writes DIR/ch09_convergence_NAME.csv (RMSE and relMSE of each rung at 1,
 * 2, 4, ... max_spp samples, with wall and CPU seconds) and
 * DIR/ch09_time_to_error_NAME.csv, and prints a table of the CPU time each
 * rung needs to reach relMSE 0.1, 0.03 and 0.01. */
bool experiment_convergence(const pt_scene *sc, const char *name, const camera *cam, const estimate_image *reference,
                            int max_spp, int threads, const char *dir, char *err, size_t err_size);

/* Writes DIR/ch09_russian_roulette.csv (a fixed P_RR from 0.2 to 0.95),
 * then experiment_roulettes(). */
bool experiment_russian_roulette(const pt_scene *sc, const camera *cam, const estimate_image *reference, int spp,
                                 int threads, const char *dir, char *err, size_t err_size);
/* Writes DIR/ch09_roulettes.csv: the lecture's, pbrt's and smallpt's
 * roulettes and none (RTROWL's 50 bounces), CPU seconds, MSE, efficiency
 * 1 / (MSE x time) and rays per camera sample of each. */
bool experiment_roulettes(const pt_scene *sc, const camera *cam, const estimate_image *reference, int spp, int threads,
                          const char *dir, char *err, size_t err_size);

/* The pieces the experiments are made of, shared with chapter 12's:
 * CPU seconds of the whole process (all threads: on a shared machine it
 * measures the work done, where wall time also measures the neighbours). */
double experiment_cpu_seconds(void);
/* RMSE and relMSE of img against the reference, less the reference's own
 * noise (the mean of its squared standard error, an unbiased correction). */
void experiment_error(const image *img, const estimate_image *reference, double *rmse, double *relmse);
/* A CSV file DIR/NAME (path receives it), written as NAME.tmp and renamed
 * into place by experiment_csv_close only if every write succeeded;
 * experiment_csv_discard drops it. NULL / false with err on failure. */
FILE *experiment_csv_open(const char *dir, const char *name, char *path, size_t path_size, char *err,
                          size_t err_size);
bool experiment_csv_close(FILE *f, const char *path, char *err, size_t err_size);
void experiment_csv_discard(FILE *f, const char *path);
/* The time at which relMSE falls to `target`, from n renders at doubling
 * sample counts (log-log interpolation); -1 if none reached it, and
 * *spp_out the first sample count that did. */
double experiment_time_to_reach(const double *seconds, const double *relmse, const int *spp, int n, double target,
                                int *spp_out);

#endif
