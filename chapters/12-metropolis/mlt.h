/* mlt.h -- Metropolis light transport in primary sample space (Kelemen,
 * Szirmay-Kalos, Antal and Csonka 2002), on chapter 09's path tracer.
 *
 * A path tracer is a deterministic function of the uniform numbers it draws:
 * two for the point on the image plane, then five to eight per bounce. Call
 * that vector u in [0,1)^n a "primary sample" and the luminance of the
 * radiance it returns f(u). Path tracing averages f over independent u;
 * Metropolis instead runs a Markov chain over u whose stationary density is
 * f(u) / b, with b = integral of f, so bright paths are visited in
 * proportion to their brightness and a path that took effort to find is
 * explored by small changes instead of being thrown away.
 *
 *   mlt_sampler   the chain's state u: lazily extended, mutated by large
 *                 steps (all coordinates new) and small steps (each
 *                 coordinate perturbed a little), with the per-coordinate
 *                 timestamps that let an unused coordinate catch up later
 *   mlt_acceptance  min(1, f(proposal) / f(current)): Metropolis-Hastings
 *                 for the symmetric mutations used here
 *   mlt_render    bootstrap (b and the chains' starting states), then the
 *                 chains, splatting to a common/core/splat_film.h film
 *
 * Usage:
 *   mlt_options o = mlt_defaults(&pt, &cam);
 *   o.mutations_per_pixel = 64;
 *   image img = image_make(cam.width, cam.height);
 *   mlt_result r;
 *   if (!mlt_render(&o, &img, &r)) ... out of memory
 */
#ifndef MLT_H
#define MLT_H

#include <stdbool.h>
#include <stdint.h>

#include "09-path-tracing/path_tracer.h"
#include "camera.h"
#include "counters.h"
#include "image.h"
#include "rng.h"
#include "splat_film.h"

/* ---- the primary sample vector ------------------------------------------------ */

typedef struct {
    float value;   /* in [0, 1) */
    long modified; /* the iteration this value belongs to (-1: never drawn) */
    float saved_value;
    long saved_modified;
} mlt_coordinate;

typedef struct {
    mlt_coordinate *u;
    int count, capacity;
    int next_index;       /* the coordinate the path reads next */
    long iteration;       /* accepted iterations so far (a rejected one is undone) */
    long last_large_step; /* the iteration of the latest large step */
    long saved_last_large_step;
    bool large_step;
    bool out_of_memory;   /* a coordinate could not be added: next returns 0.5 */
    pcg32 rng;            /* draws the new values and perturbations */
} mlt_sampler;

/* Kelemen's small-step sizes: a perturbation of each coordinate by
 * +-s2 exp(-log(s2 / s1) v), v uniform: between 1/1024 and 1/64, most
 * often small. */
#define MLT_SMALL_STEP_MIN (1.0f / 1024.0f)
#define MLT_SMALL_STEP_MAX (1.0f / 64.0f)

/* An empty sampler drawing from rng; its first path is a large step (every
 * coordinate a fresh uniform number). */
void mlt_sampler_init(mlt_sampler *s, pcg32 rng);
void mlt_sampler_free(mlt_sampler *s);
/* Begins a proposal: a large step, or a small step from the current state. */
void mlt_sampler_start_iteration(mlt_sampler *s, bool large_step);
/* The next coordinate of the proposal, brought up to date on first use. */
float mlt_sampler_next(mlt_sampler *s);
/* The proposal becomes the current state, or is undone. */
void mlt_sampler_accept(mlt_sampler *s);
void mlt_sampler_reject(mlt_sampler *s);
/* One small step of value, wrapping around in [0, 1). */
float mlt_small_step(float value, pcg32 *rng);
/* The Metropolis-Hastings acceptance probability of a symmetric mutation. */
double mlt_acceptance(double f_current, double f_proposed);

/* ---- paths as functions of primary samples ------------------------------------- */

typedef struct {
    float x, y;    /* where on the film (continuous raster coordinates) */
    vec3 radiance; /* what the path carries there */
    double f;      /* its scalar contribution: the luminance of radiance */
} mlt_path;

/* The path of the sampler's current proposal: u0, u1 pick the point on the
 * film, the rest drive chapter 09's path tracer. A NaN or Inf radiance is
 * counted and returned as a path of f = 0. */
mlt_path mlt_path_evaluate(const path_tracer *pt, const camera *cam, mlt_sampler *s, ray_counters *counters);

/* ---- rendering -------------------------------------------------------------------- */

typedef enum {
    MLT_START_BOOTSTRAP, /* each chain starts at a bootstrap path picked in proportion to f */
    MLT_START_FIXED,     /* every chain starts at the same path (the first bootstrap path with f > 0) */
} mlt_start;

typedef double (*mlt_acceptance_fn)(double f_current, double f_proposed);

typedef struct {
    const path_tracer *pt;
    const camera *cam;
    int mutations_per_pixel; /* the chains together make this many per pixel of the image */
    float p_large;           /* probability of a large step */
    int bootstrap;           /* paths that estimate b and seed the chains */
    int chains;
    uint64_t seed;
    int threads;             /* 0: all OpenMP threads */
    mlt_start start;
    bool quiet;              /* no progress line */
    const char *label;       /* for the progress line */
    /* NULL: mlt_acceptance. (The tests pass wrong ones, to see their
     * checks fail.) */
    mlt_acceptance_fn acceptance;
} mlt_options;

typedef struct {
    double b;                  /* the bootstrap estimate of the integral of f */
    double b_standard_error;
    long long proposed, accepted;
    double seconds;            /* wall time, bootstrap included */
    double bootstrap_seconds;
    ray_counters counters;
} mlt_result;

/* 64 mutations per pixel, p_large 0.3, 100000 bootstrap paths, 64 chains,
 * seed 1, bootstrap starts, all threads. */
mlt_options mlt_defaults(const path_tracer *pt, const camera *cam);

/* Renders into out (made at the camera's size). The same options give the
 * same image bit for bit for any thread count: every chain draws from its
 * own stream, and the film sums in fixed point. False if memory ran out. */
bool mlt_render(const mlt_options *o, image *out, mlt_result *result);

#endif
