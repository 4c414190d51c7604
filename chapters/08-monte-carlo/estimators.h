/* estimators.h -- the Monte Carlo estimator of lecture 16,
 *
 *     F_N = (1/N) sum_{i=1..N} f(X_i) / p(X_i),
 *
 * taken apart into the three choices it is made of:
 *
 *   - the integrand f and its domain (an interval, the unit square, the
 *     hemisphere of directions),
 *   - the sampling strategy: how a uniform point u in [0,1)^d becomes a
 *     sample X of the domain, and its density p(X) (sampling.h),
 *   - the point set the u come from: independent random points, jittered
 *     (stratified) points, or an Owen-scrambled Sobol sequence.
 *
 * Usage:
 *   experiment_catalogue cat; experiment_catalogue_init(&cat);   (do not copy it afterwards)
 *   const experiment *ex = &cat.experiments[0];                   (x^2 on [0, 1])
 *   double *scratch = malloc(n * 2 * sizeof(double));
 *   convergence_point c = estimator_run(ex->integrand, &ex->estimators[0], n, runs, seed, scratch);
 *   ... c.mean, c.variance, c.rmse, c.seconds
 *   experiment_catalogue_free(&cat);
 *
 * or one estimate by hand:
 *   points_generate(POINTS_JITTERED, &rng, n, 2, u);
 *   double F = monte_carlo_estimate(&integrand_gaussian, &strategy, u, n);
 */
#ifndef ESTIMATORS_H
#define ESTIMATORS_H

#include <stdint.h>

#include "08-monte-carlo/sampling.h"
#include "rng.h"

/* ---- integrands ----------------------------------------------------------- */

typedef struct {
    const char *name;        /* short key, used in CSV files: "x2" */
    const char *description; /* for people: "x^2 on [0,1]" */
    int dimension;           /* uniform numbers per sample: 1 or 2 */
    double exact;            /* the integral, in closed form */
    /* f at a point of the domain: x[0] on an interval, (x[0], x[1]) on the
     * square, the direction (x[0], x[1], x[2]) on the hemisphere. */
    double (*f)(const double *x);
} integrand;

extern const integrand integrand_x_squared;         /* x^2 on [0,1]: 1/3 */
extern const integrand integrand_hemisphere_cosine; /* cos(theta) over the hemisphere: pi */
extern const integrand integrand_gaussian;          /* exp(-|x-c|^2 / 2 sigma^2) on [0,1]^2 */
extern const integrand integrand_disk;              /* indicator of |x-c| < r on [0,1]^2: pi r^2 */

/* The Gaussian's and the disk's parameters (centre (0.5, 0.5) for both). */
extern const double GAUSSIAN_SIGMA;
extern const double DISK_RADIUS;

/* ---- sampling strategies -------------------------------------------------- */

/* Turns u (dimension numbers in [0,1)) into a sample x of the domain and
 * returns its density p(x). */
typedef double (*warp_fn)(const void *ctx, const double *u, double *x);

typedef struct {
    const char *name;
    warp_fn warp;
    const void *ctx; /* what the warp needs (a table), or NULL */
} sampling_strategy;

double warp_uniform_interval(const void *ctx, const double *u, double *x);   /* p = 1 */
double warp_uniform_square(const void *ctx, const double *u, double *x);     /* p = 1 */
double warp_uniform_hemisphere(const void *ctx, const double *u, double *x); /* p = 1/(2 pi) */
double warp_cosine_hemisphere(const void *ctx, const double *u, double *x);  /* p = cos/pi */
/* ctx: a piecewise_constant_1d over [0, 1]. */
double warp_tabulated_1d(const void *ctx, const double *u, double *x);

/* A density on the unit square that is a product p(x, y) = p_x(x) p_y(y) of
 * two tables: exact for a separable integrand such as the Gaussian. */
typedef struct {
    piecewise_constant_1d x, y;
} separable_table_2d;
double warp_tabulated_2d(const void *ctx, const double *u, double *x); /* ctx: separable_table_2d */

/* ---- point sets ------------------------------------------------------------ */

typedef enum {
    POINTS_INDEPENDENT, /* each coordinate a fresh random number */
    POINTS_JITTERED,    /* one random point in each cell of a grid (stratified) */
    POINTS_SOBOL_OWEN   /* the Sobol (0,2)-sequence, Owen-scrambled */
} point_set;

/* n points of [0,1)^dimension (dimension 1 or 2) into u[0 .. n*dimension),
 * point i at u[i*dimension ...]. Draws from rng. */
void points_generate(point_set kind, pcg32 *rng, int n, int dimension, double *u);

/* Jittered: the interval cut into n equal strata, or the square into an
 * nx x ny grid, with one uniformly random point in each cell. */
void points_jittered_1d(pcg32 *rng, int n, double *u);
void points_jittered_2d(pcg32 *rng, int nx, int ny, double *u);
/* The grid points_generate uses for n points: nx = the largest divisor of n
 * that is <= sqrt(n) (square cells for n = 4^k, 2:1 rectangles for
 * n = 2 * 4^k), ny = n / nx. */
void jittered_grid_shape(int n, int *nx, int *ny);

/* Sobol's sequence, dimensions 0 and 1, as 32-bit fractions (value / 2^32):
 * dimension 0 is the van der Corput sequence (the index's bits mirrored
 * about the binary point), dimension 1 uses the direction numbers of the
 * polynomial x + 1. Every block of 2^m consecutive points starting at a
 * multiple of 2^m is a (0, m, 2)-net: each box [a/2^j, (a+1)/2^j) x
 * [b/2^k, (b+1)/2^k) with j + k = m holds exactly one point. */
uint32_t sobol_bits(uint32_t index, int dimension);
/* x's bits in the opposite order: bit 0 becomes bit 31. */
static inline uint32_t reverse_bits(uint32_t x)
{
    x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
    x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
    x = ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
    x = ((x >> 8) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8);
    return (x >> 16) | (x << 16);
}

/* Owen's nested scrambling, hash-based (Laine and Karras 2011; Vegdahl 2021):
 * each bit is flipped or not depending on the seed and on the bits above it,
 * which keeps every net property. points_generate adds a random xor on top,
 * which makes each point exactly uniform. (Here in the header, inline: a
 * path tracer calls it for every number it draws, chapters 09 and 13.)
 *
 * Owen scrambling flips each bit of the fraction (most significant first)
 * by a random choice that depends only on the bits above it: the points of
 * an elementary box stay in one box, and the boxes are permuted at random,
 * level by level. In the bit-reversed word "above" becomes "below", and each
 * step below changes bit k by a function of the bits under k only:
 *   x ^= x * even   (bit k of x * even depends on bits < k),
 *   x += seed       (the carry into bit k comes from bits < k),
 *   x *= odd        (bit k of the product is x_k xor a function of bits < k).
 * So the whole is an Owen scrambling chosen by the seed (Laine and Karras
 * 2011). These steps and constants are Vegdahl's improved hash (2021, also
 * Blender Cycles'), whose scrambles behave much more like independent ones
 * than the original's. (The hash alone does not promise that each output is
 * exactly uniform over random seeds: the seed-dependent multiplier can
 * cancel the seed's own bit. points_sobol_owen adds a random xor on top.)
 * owen_scramble_reversed is the steps alone, on the reversed word, for a
 * caller that keeps its points reversed. */
static inline uint32_t owen_scramble_reversed(uint32_t x, uint32_t seed)
{
    x ^= x * 0x3d20adeau;
    x += seed;
    x *= (seed >> 16) | 1u;
    x ^= x * 0x05526c56u;
    x ^= x * 0x53a22864u;
    return x;
}

static inline uint32_t owen_scramble(uint32_t bits, uint32_t seed)
{
    return reverse_bits(owen_scramble_reversed(reverse_bits(bits), seed));
}

/* ---- the estimator --------------------------------------------------------- */

/* F_N over the n points in u. Samples with p(x) = 0 add nothing: they cannot
 * occur under the density, and f/p would be 0/0. */
double monte_carlo_estimate(const integrand *f, const sampling_strategy *s, const double *u, int n);

typedef struct {
    const char *name;        /* key for CSV files and plots: uniform, jittered, importance, sobol_owen */
    const char *description; /* for people */
    point_set points;
    sampling_strategy strategy;
} estimator;

/* F_N from one estimator, drawing its points from rng. scratch: room for
 * n * dimension doubles. */
double estimator_estimate(const integrand *f, const estimator *e, int n, pcg32 *rng, double *scratch);

typedef struct {
    int n, runs;
    double mean;     /* of the runs' estimates */
    double variance; /* unbiased sample variance of the runs' estimates */
    double rmse;     /* sqrt(mean of (F_N - exact)^2) */
    double seconds;     /* wall time per estimate: points, warps and f */
    double cpu_seconds; /* the same in CPU time of the thread: what it costs
                           when nothing else wants the core (efficiency uses it) */
} convergence_point;

/* `runs` independent estimates with n samples each; run r draws from
 * pcg32_for_pixel(stream_seed, r), so results do not depend on which thread
 * runs what. scratch: room for n * dimension doubles. */
convergence_point estimator_run(const integrand *f, const estimator *e, int n, int runs, uint64_t stream_seed,
                                double *scratch);

/* A seed for one (experiment, estimator, n) triple, from the program's seed:
 * every cell of the experiment gets its own independent streams. */
uint64_t experiment_stream_seed(uint64_t seed, int experiment, int estimator, int n);

/* ---- the chapter's experiments ---------------------------------------------- */

enum { EXPERIMENT_MAX_ESTIMATORS = 4, EXPERIMENT_COUNT = 4, IMPORTANCE_TABLE_BINS = 16 };

typedef struct {
    const integrand *integrand;
    int estimator_count;
    estimator estimators[EXPERIMENT_MAX_ESTIMATORS];
} experiment;

/* The four integrals and the estimators run on each. The importance tables
 * live inside the catalogue and the estimators point at them: initialise it
 * where it will stay. */
typedef struct {
    piecewise_constant_1d x_squared_table; /* x^2 tabulated at 16 bin midpoints */
    separable_table_2d gaussian_table;     /* the Gaussian's factor, 16 bins per axis */
    experiment experiments[EXPERIMENT_COUNT];
} experiment_catalogue;

void experiment_catalogue_init(experiment_catalogue *c);
void experiment_catalogue_free(experiment_catalogue *c);

#endif
