/* estimators.c -- integrands, sampling strategies, point sets and the
 * estimator itself (see estimators.h). */
#include "08-monte-carlo/estimators.h"

#include <math.h>
#include <stddef.h>
#include <time.h>

#include "stats.h"
#include "timer.h"

/* ---- integrands ----------------------------------------------------------- */

const double GAUSSIAN_SIGMA = 0.25;
const double DISK_RADIUS = 0.4;

static double f_x_squared(const double *x) { return x[0] * x[0]; }

/* cos(theta) is the direction's z in the local frame. */
static double f_hemisphere_cosine(const double *w) { return w[2] > 0.0 ? w[2] : 0.0; }

static double gaussian_factor(double t)
{
    double d = t - 0.5;
    return exp(-d * d / (2.0 * GAUSSIAN_SIGMA * GAUSSIAN_SIGMA));
}

static double f_gaussian(const double *x)
{
    double dx = x[0] - 0.5, dy = x[1] - 0.5;
    return exp(-(dx * dx + dy * dy) / (2.0 * GAUSSIAN_SIGMA * GAUSSIAN_SIGMA));
}

static double f_disk(const double *x)
{
    double dx = x[0] - 0.5, dy = x[1] - 0.5;
    return dx * dx + dy * dy < DISK_RADIUS * DISK_RADIUS ? 1.0 : 0.0;
}

/* The Gaussian separates: its integral over the square is the square of
 * integral_0^1 exp(-(t - 1/2)^2 / 2 sigma^2) dt = sigma sqrt(2 pi) erf(1 / (2 sqrt(2) sigma)).
 * With sigma = 1/4 that is (sqrt(2 pi)/4 erf(sqrt 2))^2. A constant
 * initializer cannot call erf, so the value is written out below and checked
 * against the erf formula in tests/test_ch08.c. */

const integrand integrand_x_squared = {"x2", "x^2 on [0,1]", 1, 1.0 / 3.0, f_x_squared};
const integrand integrand_hemisphere_cosine = {"hemisphere_cos", "cos(theta) over the hemisphere", 2, PI,
                                               f_hemisphere_cosine};
const integrand integrand_gaussian = {"gaussian", "Gaussian (sigma 1/4) on [0,1]^2", 2, 0.35777625270483815, f_gaussian};
const integrand integrand_disk = {"disk", "disk indicator (r 0.4) on [0,1]^2", 2, PI * 0.4 * 0.4, f_disk};

/* ---- sampling strategies -------------------------------------------------- */

/* A double in [0,1) to a float in [0,1): rounding to nearest could give 1.0f. */
static float unit_float(double u)
{
    float f = (float)u;
    return f < 1.0f ? f : 0x1.fffffep-1f;
}

double warp_uniform_interval(const void *ctx, const double *u, double *x)
{
    (void)ctx;
    x[0] = u[0];
    return 1.0;
}

double warp_uniform_square(const void *ctx, const double *u, double *x)
{
    (void)ctx;
    x[0] = u[0];
    x[1] = u[1];
    return 1.0;
}

double warp_uniform_hemisphere(const void *ctx, const double *u, double *x)
{
    (void)ctx;
    vec3 w = sample_uniform_hemisphere(vec2_make(unit_float(u[0]), unit_float(u[1])));
    x[0] = w.x;
    x[1] = w.y;
    x[2] = w.z;
    return uniform_hemisphere_pdf();
}

double warp_cosine_hemisphere(const void *ctx, const double *u, double *x)
{
    (void)ctx;
    vec3 w = sample_cosine_hemisphere(vec2_make(unit_float(u[0]), unit_float(u[1])));
    x[0] = w.x;
    x[1] = w.y;
    x[2] = w.z;
    return cosine_hemisphere_pdf(w.z);
}

double warp_tabulated_1d(const void *ctx, const double *u, double *x)
{
    double pdf;
    x[0] = sample_piecewise_constant_1d(ctx, u[0], &pdf);
    return pdf;
}

double warp_tabulated_2d(const void *ctx, const double *u, double *x)
{
    const separable_table_2d *t = ctx;
    double pdf_x, pdf_y;
    x[0] = sample_piecewise_constant_1d(&t->x, u[0], &pdf_x);
    x[1] = sample_piecewise_constant_1d(&t->y, u[1], &pdf_y);
    return pdf_x * pdf_y;
}

/* ---- point sets ------------------------------------------------------------ */

static void points_independent(pcg32 *rng, int n, int dimension, double *u)
{
    for (int i = 0; i < n * dimension; i++)
        u[i] = pcg32_double(rng);
}

void points_jittered_1d(pcg32 *rng, int n, double *u)
{
    /* Stratum i is [i/n, (i+1)/n); one uniform point in each. */
    for (int i = 0; i < n; i++)
        u[i] = (i + pcg32_double(rng)) / n;
}

void points_jittered_2d(pcg32 *rng, int nx, int ny, double *u)
{
    for (int j = 0; j < ny; j++)
        for (int i = 0; i < nx; i++) {
            double *p = u + 2 * ((size_t)j * (size_t)nx + (size_t)i);
            p[0] = (i + pcg32_double(rng)) / nx;
            p[1] = (j + pcg32_double(rng)) / ny;
        }
}

void jittered_grid_shape(int n, int *nx, int *ny)
{
    int best = 1;
    for (int d = 1; (long)d * d <= n; d++)
        if (n % d == 0)
            best = d;
    *nx = best;
    *ny = n / best;
}

/* Dimension 0: the generator matrix is the identity, so point i is the
 * van der Corput radical inverse (bits of i mirrored). Dimension 1: the
 * direction numbers of x + 1, v_1 = 1/2, v_k = v_{k-1} xor v_{k-1}/2. Point i
 * is the xor of v_k over the set bits k of i. (Kollig and Keller 2002.) */
uint32_t sobol_bits(uint32_t index, int dimension)
{
    uint32_t result = 0;
    if (dimension == 0) {
        for (uint32_t v = 1u << 31; index != 0; index >>= 1, v >>= 1)
            if (index & 1u)
                result ^= v;
    } else {
        for (uint32_t v = 1u << 31; index != 0; index >>= 1, v ^= v >> 1)
            if (index & 1u)
                result ^= v;
    }
    return result;
}

/* Sobol's direction numbers v_1..v_32 of dimension d (the values
 * sobol_bits gives for index 1, 2, 4, ...). */
static void sobol_directions(int dimension, uint32_t v[32])
{
    v[0] = 1u << 31;
    for (int k = 1; k < 32; k++)
        v[k] = dimension == 0 ? v[k - 1] >> 1 : v[k - 1] ^ (v[k - 1] >> 1);
}

/* Points in Gray-code order (Antonov and Saleev 1979): point i is point i-1
 * xor one direction number (the one of the lowest set bit of i), so each
 * costs one xor instead of a loop over the bits of i. The order differs from
 * sobol_bits', but every block of 2^m points is the same set, so every
 * estimate at N = 2^m is the same. */
static void points_sobol_owen(pcg32 *rng, int n, int dimension, double *u)
{
    /* each draw its own declaration: the order of an initializer list's
     * side effects is left open by C */
    uint32_t seed_first = pcg32_next(rng), seed_second = pcg32_next(rng);
    uint32_t seed[2] = {seed_first, seed_second};
    /* A random digital shift after the hash: xor with a uniformly random
     * word flips each bit regardless of the bits above it, so it is itself a
     * nested scramble (the nets survive), and it makes every point exactly
     * uniform over the 2^32 fractions whatever the hash's quality: the
     * estimator is unbiased. */
    uint32_t shift_first = pcg32_next(rng), shift_second = pcg32_next(rng);
    uint32_t shift[2] = {shift_first, shift_second};
    uint32_t v[2][32], x[2] = {0u, 0u};
    for (int d = 0; d < dimension; d++)
        sobol_directions(d, v[d]);
    for (int i = 0; i < n; i++) {
        if (i > 0) {
            int k = 0; /* the lowest set bit of i */
            while (!((unsigned)i & (1u << k)))
                k++;
            for (int d = 0; d < dimension; d++)
                x[d] ^= v[d][k];
        }
        /* 32 scrambled bits per coordinate, then 16 random ones below them:
         * uniform in [0, 1) at a resolution of 2^-48. */
        uint32_t low = pcg32_next(rng);
        for (int d = 0; d < dimension; d++) {
            uint64_t bits = owen_scramble(x[d], seed[d]) ^ shift[d];
            uint64_t below = d == 0 ? low >> 16 : low & 0xffffu;
            u[i * dimension + d] = (double)((bits << 16) | below) * 0x1.0p-48;
        }
    }
}

void points_generate(point_set kind, pcg32 *rng, int n, int dimension, double *u)
{
    switch (kind) {
    case POINTS_INDEPENDENT:
        points_independent(rng, n, dimension, u);
        return;
    case POINTS_JITTERED:
        if (dimension == 1) {
            points_jittered_1d(rng, n, u);
        } else {
            int nx, ny;
            jittered_grid_shape(n, &nx, &ny);
            points_jittered_2d(rng, nx, ny, u);
        }
        return;
    case POINTS_SOBOL_OWEN:
        points_sobol_owen(rng, n, dimension, u);
        return;
    }
}

/* ---- the estimator --------------------------------------------------------- */

double monte_carlo_estimate(const integrand *f, const sampling_strategy *s, const double *u, int n)
{
    /* exercise: mc_estimator */
    double sum = 0.0;
    for (int i = 0; i < n; i++) {
        double x[3];
        double pdf = s->warp(s->ctx, u + (size_t)i * (size_t)f->dimension, x);
        /* f(X_i) / p(X_i) */
        if (pdf > 0.0)
            sum += f->f(x) / pdf;
    }
    /* (1/N) sum */
    return sum / n;
    /* end of exercise mc_estimator */
}

double estimator_estimate(const integrand *f, const estimator *e, int n, pcg32 *rng, double *scratch)
{
    points_generate(e->points, rng, n, f->dimension, scratch);
    return monte_carlo_estimate(f, &e->strategy, scratch, n);
}

/* CPU time of the calling thread: unlike the wall clock, it does not count
 * the time other processes (or threads) had the core. */
static double thread_cpu_seconds(void)
{
    struct timespec ts;
    if (clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts) != 0)
        return timer_seconds();
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

convergence_point estimator_run(const integrand *f, const estimator *e, int n, int runs, uint64_t stream_seed,
                                double *scratch)
{
    welford w = {0};
    double squared_error = 0.0;
    double start = timer_seconds(), cpu_start = thread_cpu_seconds();
    for (int r = 0; r < runs; r++) {
        pcg32 rng = pcg32_for_pixel(stream_seed, (uint64_t)r);
        double estimate = estimator_estimate(f, e, n, &rng, scratch);
        welford_add(&w, estimate);
        squared_error += (estimate - f->exact) * (estimate - f->exact);
    }
    double seconds = timer_seconds() - start, cpu_seconds = thread_cpu_seconds() - cpu_start;
    convergence_point c;
    c.n = n;
    c.runs = runs;
    c.mean = welford_mean(&w);
    c.variance = welford_variance(&w);
    c.rmse = sqrt(squared_error / runs);
    c.seconds = seconds / runs;
    c.cpu_seconds = cpu_seconds / runs;
    return c;
}

/* SplitMix64's finaliser (as in common/core/rng.c), to spread small integers. */
static uint64_t mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

uint64_t experiment_stream_seed(uint64_t seed, int experiment, int estimator, int n)
{
    uint64_t z = mix64(seed + 0x9e3779b97f4a7c15ULL);
    z = mix64(z ^ ((uint64_t)experiment << 40) ^ ((uint64_t)estimator << 32) ^ (uint64_t)(uint32_t)n);
    return z;
}

/* ---- the chapter's experiments ---------------------------------------------- */

/* Tabulate g at the bin midpoints over [0, 1]. Midpoints are fine for these
 * two functions because both are positive everywhere on the open interval:
 * a table with a zero bin where f > 0 would make the estimator biased. */
static void tabulate(piecewise_constant_1d *d, double (*g)(double))
{
    double values[IMPORTANCE_TABLE_BINS];
    for (int i = 0; i < IMPORTANCE_TABLE_BINS; i++)
        values[i] = g((i + 0.5) / IMPORTANCE_TABLE_BINS);
    piecewise_constant_1d_init(d, values, IMPORTANCE_TABLE_BINS, 0.0, 1.0);
}

static double square(double t) { return t * t; }

void experiment_catalogue_init(experiment_catalogue *c)
{
    tabulate(&c->x_squared_table, square);
    tabulate(&c->gaussian_table.x, gaussian_factor);
    tabulate(&c->gaussian_table.y, gaussian_factor);

    const sampling_strategy interval = {"uniform", warp_uniform_interval, NULL};
    const sampling_strategy square_uniform = {"uniform", warp_uniform_square, NULL};
    const sampling_strategy hemisphere = {"uniform hemisphere", warp_uniform_hemisphere, NULL};
    const sampling_strategy cosine = {"cosine-weighted", warp_cosine_hemisphere, NULL};
    const sampling_strategy table_1d = {"16-bin table", warp_tabulated_1d, &c->x_squared_table};
    const sampling_strategy table_2d = {"16x16 separable table", warp_tabulated_2d, &c->gaussian_table};

    c->experiments[0] = (experiment){&integrand_x_squared, 4, {
        {"uniform", "independent uniform", POINTS_INDEPENDENT, interval},
        {"jittered", "jittered (N strata)", POINTS_JITTERED, interval},
        {"importance", "importance: 16-bin table of x^2", POINTS_INDEPENDENT, table_1d},
        {"sobol_owen", "Owen-scrambled Sobol", POINTS_SOBOL_OWEN, interval},
    }};
    c->experiments[1] = (experiment){&integrand_hemisphere_cosine, 4, {
        {"uniform", "independent uniform hemisphere", POINTS_INDEPENDENT, hemisphere},
        {"jittered", "jittered uniform hemisphere", POINTS_JITTERED, hemisphere},
        {"importance", "cosine-weighted (p proportional to f)", POINTS_INDEPENDENT, cosine},
        {"sobol_owen", "Owen-scrambled Sobol, uniform hemisphere", POINTS_SOBOL_OWEN, hemisphere},
    }};
    c->experiments[2] = (experiment){&integrand_gaussian, 4, {
        {"uniform", "independent uniform", POINTS_INDEPENDENT, square_uniform},
        {"jittered", "jittered (grid of strata)", POINTS_JITTERED, square_uniform},
        {"importance", "importance: 16x16 separable table", POINTS_INDEPENDENT, table_2d},
        {"sobol_owen", "Owen-scrambled Sobol", POINTS_SOBOL_OWEN, square_uniform},
    }};
    c->experiments[3] = (experiment){&integrand_disk, 3, {
        {"uniform", "independent uniform", POINTS_INDEPENDENT, square_uniform},
        {"jittered", "jittered (grid of strata)", POINTS_JITTERED, square_uniform},
        {"sobol_owen", "Owen-scrambled Sobol", POINTS_SOBOL_OWEN, square_uniform},
    }};
}

void experiment_catalogue_free(experiment_catalogue *c)
{
    piecewise_constant_1d_free(&c->x_squared_table);
    piecewise_constant_1d_free(&c->gaussian_table.x);
    piecewise_constant_1d_free(&c->gaussian_table.y);
}
