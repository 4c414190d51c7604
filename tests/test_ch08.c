/* test_ch08.c -- Monte Carlo integration.
 *
 *   1. the chi-square distribution (common/core/stats.c) against closed forms;
 *   2. every sampling routine: invert(sample(u)) == u, its pdf integrates to
 *      1, and a Pearson chi-square test of its samples against its pdf, each
 *      with a twin that feeds a deliberately wrong sampler and must fail;
 *   3. the estimators: unbiased, variance falling at the rate theory gives
 *      (-1, -2, -1.5), N Var equal to the closed-form per-sample variance,
 *      each with a twin; the point sets' stratification.
 *
 * Every random test has a fixed seed (replaying a failure gives the same
 * numbers) and a threshold chosen so that a correct implementation fails
 * with probability below about 1e-6 (it is computed from the statistic's
 * distribution, not tuned). No test looks at wall time. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "08-monte-carlo/estimators.h"
#include "08-monte-carlo/sampling.h"
#include "rng.h"
#include "stats.h"
#include "test_support.h"

/* ==== 1. the chi-square distribution ======================================= */

/* Relative accuracy of P and Q. Both expansions run to double's resolution;
 * lgamma and exp(a log x - x - lgamma a) add rounding of a few ulps of the
 * exponent, which is up to ~300 for the largest case below: 300 * 2.2e-16
 * ~ 7e-14. 1e-11 leaves a factor 100 and still catches a wrong term (which
 * is off by more than 1e-3). */
static const double GAMMA_RELATIVE_TOLERANCE = 1e-11;

static void assert_relative(double actual, double expected)
{
    assert_close(actual, expected, GAMMA_RELATIVE_TOLERANCE * fabs(expected));
}

static void test_chi_square_p_value_closed_forms(void **state)
{
    (void)state;
    const double xs[] = {0.01, 0.5, 1.0, 2.5, 3.841458820694124, 7.0, 15.0, 40.0, 120.0};
    for (size_t i = 0; i < sizeof xs / sizeof xs[0]; i++) {
        double x = xs[i];
        /* 1 degree of freedom: the square of a standard normal, P(|Z| > sqrt x). */
        assert_relative(stats_chi_square_p_value(x, 1), erfc(sqrt(x / 2)));
        /* 2: an exponential with mean 2. */
        assert_relative(stats_chi_square_p_value(x, 2), exp(-x / 2));
        /* 3: erfc(sqrt(x/2)) + sqrt(2x/pi) e^(-x/2). */
        assert_relative(stats_chi_square_p_value(x, 3), erfc(sqrt(x / 2)) + sqrt(2 * x / PI) * exp(-x / 2));
        /* The two tails add to 1. */
        assert_close(stats_chi_square_p_value(x, 5) + stats_chi_square_lower_tail(x, 5), 1.0, 1e-14);
    }
}

/* Even degrees of freedom 2k: Q(k, x/2) = e^(-x/2) sum_{j<k} (x/2)^j / j!
 * (a Poisson tail). k = 100 exercises both the series (x/2 < k + 1) and the
 * continued fraction (x/2 > k + 1), far into the upper tail. */
static void test_chi_square_p_value_many_degrees_of_freedom(void **state)
{
    (void)state;
    const int k = 100;
    const double xs[] = {120.0, 180.0, 199.0, 203.0, 250.0, 320.0, 400.0};
    for (size_t i = 0; i < sizeof xs / sizeof xs[0]; i++) {
        double half = xs[i] / 2, term = 1.0, sum = 1.0;
        for (int j = 1; j < k; j++) {
            term *= half / j;
            sum += term;
        }
        assert_relative(stats_chi_square_p_value(xs[i], 2 * k), exp(-half) * sum);
        /* The lower tail is the rest of the Poisson series, e^(-x/2) sum_{j>=k}
         * (x/2)^j / j!: summed directly, so small values keep their digits. */
        double lower = 0.0;
        term = exp(-half);
        for (int j = 1; j < k + 2000; j++) {
            term *= half / j;
            if (j >= k)
                lower += term;
        }
        assert_relative(stats_chi_square_lower_tail(xs[i], 2 * k), lower);
    }
}

/* Table values: the 95% points of chi-square with 1 and 10 degrees of freedom. */
static void test_chi_square_p_value_table_values(void **state)
{
    (void)state;
    assert_relative(stats_chi_square_p_value(3.841458820694124, 1), 0.05);
    assert_relative(stats_chi_square_p_value(18.307038053275146, 10), 0.05);
    /* Rounded, as printed in tables. */
    assert_close(stats_chi_square_p_value(3.84, 1), 0.05, 1e-4);
    assert_close(stats_chi_square_p_value(18.31, 10), 0.05, 1e-4);
    assert_true(isnan(stats_chi_square_p_value(1.0, 0)));
    assert_true(isnan(stats_gamma_q(-1.0, 1.0)));
    assert_close(stats_gamma_q(3.0, 0.0), 1.0, 0.0);
}

static void test_sidak_alpha(void **state)
{
    (void)state;
    assert_close(stats_sidak_alpha(0.05, 1), 0.05, 1e-15);
    for (int k = 2; k <= 1000; k *= 3) {
        double a = stats_sidak_alpha(1e-6, k);
        /* (1 - a)^k = 1 - 1e-6, compared as logarithms (no cancellation),
         * and a is a little more than 1e-6 / k. */
        assert_close(k * log1p(-a), log1p(-1e-6), 1e-15 * 1e-6);
        assert_true(a > 1e-6 / k && a < 1.0001e-6 / k);
    }
}

/* x with P(chi-square with dof degrees > x) = p, by bisection on the p-value
 * (which falls monotonically in x). For setting bounds in the tests below. */
static double chi_square_upper_quantile(double p, int dof)
{
    double lo = 0.0, hi = dof + 10.0;
    while (stats_chi_square_p_value(hi, dof) > p)
        hi *= 2.0;
    for (int i = 0; i < 200; i++) {
        double mid = 0.5 * (lo + hi);
        if (stats_chi_square_p_value(mid, dof) > p)
            lo = mid;
        else
            hi = mid;
    }
    return 0.5 * (lo + hi);
}

static void test_chi_square_quantile_helper(void **state)
{
    (void)state;
    assert_close(chi_square_upper_quantile(0.05, 1), 3.841458820694124, 1e-9);
    assert_close(chi_square_upper_quantile(0.05, 10), 18.307038053275146, 1e-9);
}

/* ==== 2. sampling routines =================================================== */

/* The cone the tests use: theta_max = acos(0.8), about 37 degrees. */
static const float CONE_COS_THETA_MAX = 0.8f;

/* A fixed, non-uniform table for the 1D piecewise-constant distribution,
 * with a zero bin to show that sampling never lands there. */
enum { TABLE_BINS = 8 };
static const double TABLE_VALUES[TABLE_BINS] = {0.5, 2.0, 0.0, 1.0, 4.0, 0.25, 3.0, 1.5};
static const double TABLE_MIN = -1.0, TABLE_MAX = 3.0;

static piecewise_constant_1d make_table(void)
{
    piecewise_constant_1d d;
    assert_true(piecewise_constant_1d_init(&d, TABLE_VALUES, TABLE_BINS, TABLE_MIN, TABLE_MAX));
    return d;
}

/* ---- round trips ----------------------------------------------------------- */

/* How far invert(sample(u)) may land from u. Each routine does about ten
 * float operations, each with a relative error of at most 2^-24 ~ 6e-8, and
 * the cone divides by 1 - cos_theta_max = 0.2, which magnifies the error of
 * 1 - z five-fold: about 1e-6 in the worst case (the worst measured over
 * 10^5 u is 2.4e-7). 32 ulps of 1.0 (3.8e-6) covers that; a wrong inverse
 * (a missing square or factor) is off by 1e-2 or more for most u. */
static const float ROUND_TRIP_TOLERANCE = 32.0f * FLT_EPSILON;
enum { ROUND_TRIP_SAMPLES = 100000 };

typedef struct {
    const char *name;
    vec2 (*round_trip)(vec2 u);
    bool azimuth_in_y; /* u.y is an angle: 0 and 1 are the same point */
    bool collapses_at_u_x_zero; /* the line u.x = 0 maps to one point (a pole, centre or vertex) */
} round_trip_case;

static vec2 rt_uniform_hemisphere(vec2 u) { return invert_uniform_hemisphere(sample_uniform_hemisphere(u)); }
static vec2 rt_cosine_hemisphere(vec2 u) { return invert_cosine_hemisphere(sample_cosine_hemisphere(u)); }
static vec2 rt_uniform_sphere(vec2 u) { return invert_uniform_sphere(sample_uniform_sphere(u)); }
static vec2 rt_disk_concentric(vec2 u) { return invert_uniform_disk_concentric(sample_uniform_disk_concentric(u)); }
static vec2 rt_disk_polar(vec2 u) { return invert_uniform_disk_polar(sample_uniform_disk_polar(u)); }
static vec2 rt_triangle(vec2 u) { return invert_uniform_triangle(sample_uniform_triangle(u)); }
static vec2 rt_cone(vec2 u)
{
    return invert_uniform_cone(sample_uniform_cone(u, CONE_COS_THETA_MAX), CONE_COS_THETA_MAX);
}
/* The twin: the polar disk's inverse without the square (u1 = r, not r^2). */
static vec2 rt_disk_polar_wrong_inverse(vec2 u)
{
    vec2 p = sample_uniform_disk_polar(u);
    vec2 v = invert_uniform_disk_polar(p);
    v.x = sqrtf(v.x);
    return v;
}

/* Largest distance between u and its round trip, over many random u. */
static float worst_round_trip_error(const round_trip_case *c, uint64_t seed)
{
    pcg32 rng = pcg32_for_pixel(test_seed(seed), 0);
    float worst = 0.0f;
    for (int i = 0; i < ROUND_TRIP_SAMPLES; i++) {
        vec2 u = vec2_make(pcg32_float(&rng), pcg32_float(&rng));
        vec2 v = c->round_trip(u);
        float dx = fabsf(v.x - u.x), dy = fabsf(v.y - u.y);
        if (c->azimuth_in_y)
            dy = fminf(dy, 1.0f - dy);
        /* Near u.x = 0 some maps send the line to one point: the pole of the
         * sphere and the cone, the centre of the polar disk, the vertex p0 of
         * the triangle. There no inverse can give u.y back. Exactly 0 is one
         * draw in 2^24; the cone's cos(theta) = 1 - 0.2 u.x also rounds to 1
         * (the pole) for u.x up to 2^-22. The seed sweep found both (round
         * trips off by 0.08 to 0.9 in 16 of 200 seeds). Below 2^-20 (one
         * draw in 10^6) u.y is not checked for those maps; u.x still is. */
        if (u.x < 0x1p-20f && c->collapses_at_u_x_zero)
            dy = 0.0f;
        worst = fmaxf(worst, fmaxf(dx, dy));
        if (!(dx == dx && dy == dy))
            return INFINITY; /* a NaN is never close */
    }
    return worst;
}

static void test_round_trips(void **state)
{
    (void)state;
    const round_trip_case cases[] = {
        {"uniform hemisphere", rt_uniform_hemisphere, true, false},
        {"cosine hemisphere", rt_cosine_hemisphere, false, false},
        {"uniform sphere", rt_uniform_sphere, true, true}, /* z = 1 - 2 u.x: the pole */
        {"concentric disk", rt_disk_concentric, false, false},
        {"polar disk", rt_disk_polar, true, true}, /* r = sqrt(u.x): the centre */
        {"triangle", rt_triangle, false, true},    /* b0 = 1 - sqrt(u.x): the vertex p0 */
        {"cone", rt_cone, true, true},             /* z = 1 - u.x (1 - cos theta_max): the pole */
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        float worst = worst_round_trip_error(&cases[i], 80 + i);
        print_message("round trip %-20s worst |invert(sample(u)) - u| = %.2g\n", cases[i].name, (double)worst);
        assert_true(worst <= ROUND_TRIP_TOLERANCE);
    }
}

static void test_round_trip_catches_a_wrong_inverse(void **state)
{
    (void)state;
    round_trip_case twin = {"polar disk, inverse without the square", rt_disk_polar_wrong_inverse, true, true};
    assert_true(worst_round_trip_error(&twin, 90) > ROUND_TRIP_TOLERANCE);
}

static void test_piecewise_constant_1d_round_trip_and_zero_bins(void **state)
{
    (void)state;
    exercise_checks("invert_cdf");
    piecewise_constant_1d d = make_table();
    /* The 1D table is double: the same ten-operation argument gives ~1e-15;
     * 1e-12 leaves room and still catches any wrong bin (>= 1/8 off). */
    const double tolerance = 1e-12;
    pcg32 rng = pcg32_for_pixel(test_seed(91), 0);
    double width = (TABLE_MAX - TABLE_MIN) / TABLE_BINS;
    for (int i = 0; i < ROUND_TRIP_SAMPLES; i++) {
        double u = pcg32_double(&rng), pdf;
        double x = sample_piecewise_constant_1d(&d, u, &pdf);
        assert_true(x >= TABLE_MIN && x < TABLE_MAX);
        int bin = (int)floor((x - TABLE_MIN) / width);
        assert_true(TABLE_VALUES[bin] > 0.0); /* never in the empty bin */
        assert_close(pdf, piecewise_constant_1d_pdf(&d, x), 1e-15);
        assert_close(invert_piecewise_constant_1d(&d, x), u, tolerance);
    }
    piecewise_constant_1d_free(&d);
}

static void test_piecewise_constant_1d_rejects_bad_tables(void **state)
{
    (void)state;
    piecewise_constant_1d d;
    const double negative[3] = {1.0, -0.5, 2.0}, with_nan[2] = {1.0, NAN}, zeros[4] = {0, 0, 0, 0};
    assert_false(piecewise_constant_1d_init(&d, negative, 3, 0.0, 1.0));
    assert_false(piecewise_constant_1d_init(&d, with_nan, 2, 0.0, 1.0));
    assert_false(piecewise_constant_1d_init(&d, zeros, 0, 0.0, 1.0));
    assert_false(piecewise_constant_1d_init(&d, zeros, 4, 1.0, 1.0));
    /* All zero: nothing to follow, so uniform (pdf 1/(max - min)). */
    assert_true(piecewise_constant_1d_init(&d, zeros, 4, 0.0, 2.0));
    assert_close(piecewise_constant_1d_pdf(&d, 0.3), 0.5, 1e-15);
    piecewise_constant_1d_free(&d);
}

/* ---- each pdf integrates to 1 ---------------------------------------------- */

/* Composite Simpson in 2D over [a0,a1] x [b0,b1] with n (even) intervals per
 * axis. For the smooth integrands here (sin, cos and constants times each
 * other) its error with n = 64 is below 1e-9. */
static double simpson_2d(double (*g)(double a, double b, const void *ctx), const void *ctx, double a0, double a1,
                         double b0, double b1, int n)
{
    double ha = (a1 - a0) / n, hb = (b1 - b0) / n, sum = 0.0;
    for (int i = 0; i <= n; i++) {
        double wa = (i == 0 || i == n) ? 1.0 : (i % 2 ? 4.0 : 2.0);
        for (int j = 0; j <= n; j++) {
            double wb = (j == 0 || j == n) ? 1.0 : (j % 2 ? 4.0 : 2.0);
            sum += wa * wb * g(a0 + i * ha, b0 + j * hb, ctx);
        }
    }
    return sum * ha * hb / 9.0;
}

/* How close to 1 a pdf's integral must be. The pdfs are float (a relative
 * error of a few 2^-24 ~ 1e-7) and Simpson adds < 1e-9; a pdf that is wrong
 * by any constant factor (a forgotten 1/pi, 1/2 or 2) is off by 0.5 or more. */
static const double PDF_INTEGRAL_TOLERANCE = 1e-6;
enum { PDF_INTEGRAL_INTERVALS = 64 };

/* Density over (theta, phi), including the Jacobian sin(theta) of dw. */
typedef float (*direction_pdf)(vec3 w, float parameter);
typedef struct {
    direction_pdf pdf;
    float parameter;
} direction_density;

static vec3 direction_at(double theta, double phi)
{
    return vec3_make((float)(sin(theta) * cos(phi)), (float)(sin(theta) * sin(phi)), (float)cos(theta));
}

static double theta_phi_density(double theta, double phi, const void *ctx)
{
    const direction_density *d = ctx;
    return d->pdf(direction_at(theta, phi), d->parameter) * sin(theta);
}

static float pdf_uniform_hemisphere(vec3 w, float p) { (void)p; return w.z >= 0.0f ? uniform_hemisphere_pdf() : 0.0f; }
static float pdf_cosine_hemisphere(vec3 w, float p) { (void)p; return cosine_hemisphere_pdf(w.z); }
static float pdf_uniform_sphere(vec3 w, float p) { (void)w; (void)p; return uniform_sphere_pdf(); }
static float pdf_uniform_cone(vec3 w, float cos_max) { return w.z >= cos_max ? uniform_cone_pdf(cos_max) : 0.0f; }
/* The RTIOW-style "normal + random point in the unit ball" density: the
 * chord from the origin along w has length 2 cos(theta), and the ball's
 * volume 4 pi/3 gives p(w) = (2 cos(theta))^3 / 3 / (4 pi / 3) = 2 cos^3(theta) / pi. */
static float pdf_cos_cubed(vec3 w, float p) { (void)p; return w.z > 0.0f ? 2.0f * w.z * w.z * w.z / (float)PI : 0.0f; }
/* Wrong pdfs for the twin: the cosine without its 1/pi, and the sphere's
 * 1/(4 pi) used on the hemisphere. */
static float pdf_cosine_without_pi(vec3 w, float p) { (void)p; return fmaxf(w.z, 0.0f); }
static float pdf_sphere_on_hemisphere(vec3 w, float p) { (void)w; (void)p; return uniform_sphere_pdf(); }

static double integrate_direction_pdf(direction_pdf pdf, float parameter, double theta_max)
{
    direction_density d = {pdf, parameter};
    return simpson_2d(theta_phi_density, &d, 0.0, theta_max, 0.0, 2 * PI, PDF_INTEGRAL_INTERVALS);
}

static double disk_density(double r, double phi, const void *ctx)
{
    (void)phi;
    (void)ctx;
    return uniform_disk_pdf() * r; /* dA = r dr dphi */
}

static void test_pdfs_integrate_to_one(void **state)
{
    (void)state;
    double cone_theta_max = acos((double)CONE_COS_THETA_MAX);
    assert_close(integrate_direction_pdf(pdf_uniform_hemisphere, 0, PI / 2), 1.0, PDF_INTEGRAL_TOLERANCE);
    assert_close(integrate_direction_pdf(pdf_cosine_hemisphere, 0, PI / 2), 1.0, PDF_INTEGRAL_TOLERANCE);
    assert_close(integrate_direction_pdf(pdf_uniform_sphere, 0, PI), 1.0, PDF_INTEGRAL_TOLERANCE);
    assert_close(integrate_direction_pdf(pdf_uniform_cone, CONE_COS_THETA_MAX, cone_theta_max), 1.0,
                 PDF_INTEGRAL_TOLERANCE);
    assert_close(integrate_direction_pdf(pdf_cos_cubed, 0, PI / 2), 1.0, PDF_INTEGRAL_TOLERANCE);
    assert_close(simpson_2d(disk_density, NULL, 0.0, 1.0, 0.0, 2 * PI, PDF_INTEGRAL_INTERVALS), 1.0,
                 PDF_INTEGRAL_TOLERANCE);
    /* Triangle: pdf times the area, the area found independently (Heron). */
    vec3 p0 = vec3_make(0.3f, -1.0f, 2.0f), p1 = vec3_make(2.5f, 0.5f, 1.0f), p2 = vec3_make(-0.7f, 1.5f, 0.2f);
    double a = vec3_length(vec3_sub(p1, p0)), b = vec3_length(vec3_sub(p2, p1)), c = vec3_length(vec3_sub(p0, p2));
    double s = 0.5 * (a + b + c), heron = sqrt(s * (s - a) * (s - b) * (s - c));
    assert_close(uniform_triangle_pdf(p0, p1, p2) * heron, 1.0, PDF_INTEGRAL_TOLERANCE);
    /* 1D table: a midpoint sum on a grid that refines its bins is exact. */
    piecewise_constant_1d d = make_table();
    const int steps = 64 * TABLE_BINS;
    double h = (TABLE_MAX - TABLE_MIN) / steps, sum = 0.0;
    for (int i = 0; i < steps; i++)
        sum += piecewise_constant_1d_pdf(&d, TABLE_MIN + (i + 0.5) * h) * h;
    assert_close(sum, 1.0, 1e-12);
    piecewise_constant_1d_free(&d);
}

static void test_pdf_integral_catches_wrong_pdfs(void **state)
{
    (void)state;
    assert_false(fabs(integrate_direction_pdf(pdf_cosine_without_pi, 0, PI / 2) - 1.0) <= PDF_INTEGRAL_TOLERANCE);
    assert_false(fabs(integrate_direction_pdf(pdf_sphere_on_hemisphere, 0, PI / 2) - 1.0) <= PDF_INTEGRAL_TOLERANCE);
}

/* ---- chi-square goodness of fit ------------------------------------------- */

/* The samples of each routine are counted in a grid of cells over its own
 * coordinates: (theta, phi) for directions, (r, phi) for the disk,
 * (b1, b2) for the triangle, x for the 1D table. Each cell's expected count
 * is N times the integral of the routine's pdf over the cell (Simpson, or
 * in closed form where the density jumps inside a cell). Cells expected to
 * hold fewer than 5 samples are merged (the chi-square approximation needs
 * about 5 per cell), and Pearson's statistic sum (O - E)^2 / E is compared
 * with the chi-square distribution with (cells - 1) degrees of freedom. */
enum { CHI2_SAMPLES = 200000, CHI2_ROWS = 16, CHI2_COLS = 32, CHI2_CELL_SIMPSON = 8 };
static const double CHI2_MIN_EXPECTED = 5.0;

/* All the chi-square tests that a correct implementation must pass, counted
 * for Sidak's correction: uniform and cosine hemisphere, sphere, concentric
 * and polar disk, triangle, cone, 1D table, and the two "offset sphere /
 * ball" Lambertian constructions. Together they reject a correct sampler
 * with probability CHI2_ALPHA_TOTAL; each alone at stats_sidak_alpha(). */
enum { CHI2_PASSING_TESTS = 10 };
static const double CHI2_ALPHA_TOTAL = 1e-6;

typedef struct {
    const char *name;
    int rows, cols;         /* cells along s and t */
    double s_max, t_max;    /* the domain [0, s_max] x [0, t_max] */
    /* Draw a sample (from uniform numbers of rng) and give its coordinates;
     * false if it fell outside the domain (an impossible sample). */
    bool (*draw)(pcg32 *rng, const void *ctx, double *s, double *t);
    /* The claimed density in (s, t), Jacobian included... */
    double (*density)(double s, double t, const void *ctx);
    /* ...or, if not NULL, the claimed probability of a cell in closed form. */
    double (*cell_probability)(double s0, double s1, double t0, double t1, const void *ctx);
    const void *ctx;
} chi2_case;

static int compare_by_expected(const void *a, const void *b, const double *expected)
{
    double ea = expected[*(const int *)a], eb = expected[*(const int *)b];
    return (ea > eb) - (ea < eb);
}

static const double *sort_expected; /* qsort has no context argument */
static int compare_cells(const void *a, const void *b) { return compare_by_expected(a, b, sort_expected); }

/* Pearson's chi-square p-value of observed against expected counts, merging
 * the smallest cells until each (merged) cell expects at least 5. */
static double pearson_p_value(const double *observed, const double *expected, int cells)
{
    int *order = malloc(sizeof(int) * (size_t)cells);
    for (int i = 0; i < cells; i++)
        order[i] = i;
    sort_expected = expected;
    qsort(order, (size_t)cells, sizeof(int), compare_cells);
    double chi2 = 0.0, pool_o = 0.0, pool_e = 0.0;
    int used = 0;
    for (int k = 0; k < cells; k++) {
        int i = order[k];
        if (expected[i] <= 0.0 && observed[i] > 0.0) {
            free(order);
            return 0.0; /* a sample where the pdf says none can be */
        }
        if (expected[i] < CHI2_MIN_EXPECTED || pool_e > 0.0) {
            pool_o += observed[i];
            pool_e += expected[i];
            if (pool_e >= CHI2_MIN_EXPECTED) {
                chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
                used++;
                pool_o = pool_e = 0.0;
            }
            continue;
        }
        chi2 += (observed[i] - expected[i]) * (observed[i] - expected[i]) / expected[i];
        used++;
    }
    if (pool_e > 0.0) { /* what is left of the pool is the last cell */
        chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        used++;
    }
    free(order);
    return used < 2 ? 1.0 : stats_chi_square_p_value(chi2, used - 1);
}

typedef struct {
    double (*density)(double s, double t, const void *ctx);
    const void *ctx;
} density_ref;

static double density_call(double s, double t, const void *ctx)
{
    const density_ref *d = ctx;
    return d->density(s, t, d->ctx);
}

static double chi_square_sampler_p_value(const chi2_case *c, uint64_t seed)
{
    int cells = c->rows * c->cols;
    double *observed = calloc((size_t)cells, sizeof(double));
    double *expected = calloc((size_t)cells, sizeof(double));
    double hs = c->s_max / c->rows, ht = c->t_max / c->cols;
    for (int i = 0; i < c->rows; i++)
        for (int j = 0; j < c->cols; j++) {
            double s0 = i * hs, t0 = j * ht, p;
            if (c->cell_probability != NULL) {
                p = c->cell_probability(s0, s0 + hs, t0, t0 + ht, c->ctx);
            } else {
                density_ref d = {c->density, c->ctx};
                p = simpson_2d(density_call, &d, s0, s0 + hs, t0, t0 + ht, CHI2_CELL_SIMPSON);
            }
            expected[i * c->cols + j] = CHI2_SAMPLES * p;
        }
    pcg32 rng = pcg32_for_pixel(test_seed(seed), 0);
    bool impossible = false;
    for (int n = 0; n < CHI2_SAMPLES; n++) {
        double s, t;
        if (!c->draw(&rng, c->ctx, &s, &t) || !(s >= 0.0 && s <= c->s_max && t >= 0.0 && t <= c->t_max)) {
            impossible = true;
            continue;
        }
        int i = (int)(s / hs), j = (int)(t / ht);
        i = i < c->rows ? i : c->rows - 1;
        j = j < c->cols ? j : c->cols - 1;
        observed[i * c->cols + j] += 1.0;
    }
    double p = impossible ? 0.0 : pearson_p_value(observed, expected, cells);
    free(observed);
    free(expected);
    return p;
}

static double chi2_alpha_per_test(void) { return stats_sidak_alpha(CHI2_ALPHA_TOTAL, CHI2_PASSING_TESTS); }

static void assert_chi2_passes(const chi2_case *c, uint64_t seed)
{
    double p = chi_square_sampler_p_value(c, seed);
    print_message("chi-square %-44s p = %.3g\n", c->name, p);
    assert_true(p >= chi2_alpha_per_test());
}

static void assert_chi2_fails(const chi2_case *c, uint64_t seed)
{
    double p = chi_square_sampler_p_value(c, seed);
    print_message("chi-square %-44s p = %.3g (must fail)\n", c->name, p);
    assert_true(p < chi2_alpha_per_test());
}

/* -- directions: s = theta, t = phi -- */

typedef struct {
    vec3 (*sample)(pcg32 *rng, float parameter);
    direction_pdf pdf;
    float parameter;
} direction_case;

static vec2 next_u(pcg32 *rng) { return vec2_make(pcg32_float(rng), pcg32_float(rng)); }

static double angle_phi(vec3 w)
{
    double phi = atan2(w.y, w.x);
    return phi < 0.0 ? phi + 2 * PI : phi;
}

static bool draw_direction(pcg32 *rng, const void *ctx, double *s, double *t)
{
    const direction_case *d = ctx;
    vec3 w = d->sample(rng, d->parameter);
    double len = vec3_length(w);
    if (!(fabs(len - 1.0) < 1e-5)) /* not a unit vector: not a direction at all */
        return false;
    *s = acos(fmin(fmax(w.z / len, -1.0), 1.0));
    *t = angle_phi(w);
    return true;
}

static double direction_case_density(double theta, double phi, const void *ctx)
{
    const direction_case *d = ctx;
    return d->pdf(direction_at(theta, phi), d->parameter) * sin(theta);
}

static chi2_case direction_chi2(const char *name, const direction_case *d, double theta_max)
{
    return (chi2_case){name, CHI2_ROWS, CHI2_COLS, theta_max, 2 * PI, draw_direction, direction_case_density, NULL, d};
}

static vec3 s_uniform_hemisphere(pcg32 *rng, float p) { (void)p; return sample_uniform_hemisphere(next_u(rng)); }
static vec3 s_cosine_hemisphere(pcg32 *rng, float p) { (void)p; return sample_cosine_hemisphere(next_u(rng)); }
static vec3 s_uniform_sphere(pcg32 *rng, float p) { (void)p; return sample_uniform_sphere(next_u(rng)); }
static vec3 s_uniform_cone(pcg32 *rng, float cos_max) { return sample_uniform_cone(next_u(rng), cos_max); }

/* Twins: the classic wrong samplers. */
/* theta uniform instead of cos(theta): crowds the pole. */
static vec3 s_hemisphere_uniform_theta(pcg32 *rng, float p)
{
    (void)p;
    vec2 u = next_u(rng);
    return direction_at(0.5 * PI * u.x, 2 * PI * u.y);
}
static vec3 s_sphere_uniform_theta(pcg32 *rng, float p)
{
    (void)p;
    vec2 u = next_u(rng);
    return direction_at(PI * u.x, 2 * PI * u.y);
}
static vec3 s_cone_uniform_theta(pcg32 *rng, float cos_max)
{
    vec2 u = next_u(rng);
    return direction_at(u.x * acos((double)cos_max), 2 * PI * u.y);
}
/* Cosine sampling with the sqrt missing: r = u1 on the disk (not sqrt(u1)),
 * lifted to the hemisphere. */
static vec3 s_cosine_sqrt_missing(pcg32 *rng, float p)
{
    (void)p;
    vec2 u = next_u(rng);
    float r = u.x, phi = 2.0f * (float)PI * u.y;
    return vec3_make(r * cosf(phi), r * sinf(phi), sqrtf(fmaxf(0.0f, 1.0f - r * r)));
}

/* "Lambertian" directions the Ray Tracing in One Weekend way: the normal
 * (0,0,1) plus a uniform point ON the unit sphere (the corrected book) or
 * IN the unit ball (the first edition), normalized. */
static vec3 s_normal_plus_sphere_point(pcg32 *rng, float p)
{
    (void)p;
    vec3 d = vec3_add(vec3_make(0, 0, 1), sample_uniform_sphere(next_u(rng)));
    return vec3_normalize(d);
}
static vec3 s_normal_plus_ball_point(pcg32 *rng, float p)
{
    (void)p;
    /* A uniform point in the ball: a uniform direction, and a radius with
     * density 3 r^2 (cdf r^3, so r = cbrt(u3)). */
    vec3 on_sphere = sample_uniform_sphere(next_u(rng));
    float radius = cbrtf(pcg32_float(rng));
    vec3 d = vec3_add(vec3_make(0, 0, 1), vec3_scale(on_sphere, radius));
    return vec3_normalize(d);
}

static void test_chi_square_directions(void **state)
{
    (void)state;
    const direction_case hemisphere = {s_uniform_hemisphere, pdf_uniform_hemisphere, 0};
    const direction_case cosine = {s_cosine_hemisphere, pdf_cosine_hemisphere, 0};
    const direction_case sphere = {s_uniform_sphere, pdf_uniform_sphere, 0};
    const direction_case cone = {s_uniform_cone, pdf_uniform_cone, CONE_COS_THETA_MAX};
    double cone_theta_max = acos((double)CONE_COS_THETA_MAX);
    chi2_case c;
    c = direction_chi2("uniform hemisphere", &hemisphere, PI / 2);
    assert_chi2_passes(&c, 100);
    c = direction_chi2("cosine hemisphere", &cosine, PI / 2);
    assert_chi2_passes(&c, 101);
    c = direction_chi2("uniform sphere", &sphere, PI);
    assert_chi2_passes(&c, 102);
    c = direction_chi2("uniform cone", &cone, cone_theta_max);
    assert_chi2_passes(&c, 103);
}

static void test_chi_square_directions_twins_fail(void **state)
{
    (void)state;
    const direction_case hemisphere = {s_hemisphere_uniform_theta, pdf_uniform_hemisphere, 0};
    const direction_case cosine = {s_cosine_sqrt_missing, pdf_cosine_hemisphere, 0};
    const direction_case sphere = {s_sphere_uniform_theta, pdf_uniform_sphere, 0};
    const direction_case cone = {s_cone_uniform_theta, pdf_uniform_cone, CONE_COS_THETA_MAX};
    double cone_theta_max = acos((double)CONE_COS_THETA_MAX);
    chi2_case c;
    c = direction_chi2("hemisphere, theta uniform", &hemisphere, PI / 2);
    assert_chi2_fails(&c, 100);
    c = direction_chi2("cosine hemisphere, sqrt missing (r = u1)", &cosine, PI / 2);
    assert_chi2_fails(&c, 101);
    c = direction_chi2("sphere, theta uniform", &sphere, PI);
    assert_chi2_fails(&c, 102);
    c = direction_chi2("cone, theta uniform", &cone, cone_theta_max);
    assert_chi2_fails(&c, 103);
}

/* cos or cos^3? normal + a point on the unit sphere is exactly cosine
 * distributed; normal + a point in the unit ball is 2 cos^3(theta) / pi. */
static void test_chi_square_lambertian_offset_constructions(void **state)
{
    (void)state;
    const direction_case on_sphere = {s_normal_plus_sphere_point, pdf_cosine_hemisphere, 0};
    const direction_case in_ball = {s_normal_plus_ball_point, pdf_cos_cubed, 0};
    chi2_case c;
    c = direction_chi2("normal + point on sphere vs cos/pi", &on_sphere, PI / 2);
    assert_chi2_passes(&c, 104);
    c = direction_chi2("normal + point in ball vs 2 cos^3/pi", &in_ball, PI / 2);
    assert_chi2_passes(&c, 105);
}

static void test_chi_square_lambertian_offset_twins_fail(void **state)
{
    (void)state;
    const direction_case in_ball = {s_normal_plus_ball_point, pdf_cosine_hemisphere, 0};
    const direction_case on_sphere = {s_normal_plus_sphere_point, pdf_cos_cubed, 0};
    chi2_case c;
    c = direction_chi2("normal + point in ball vs cos/pi", &in_ball, PI / 2);
    assert_chi2_fails(&c, 104);
    c = direction_chi2("normal + point on sphere vs 2 cos^3/pi", &on_sphere, PI / 2);
    assert_chi2_fails(&c, 105);
}

/* -- the disk: s = r, t = phi -- */

/* A point on the rim (u.x = 0 in the concentric map: r = 1 exactly) comes
 * out as r cos(phi), r sin(phi) in float, whose length may exceed 1 by the
 * rounding of those products: up to about 2 FLT_EPSILON (measured: 2.9e-8).
 * That is not a sample outside the disk; farther out is. Found by the seed
 * sweep (p = 0 in 4 of 200 seeds). Such a point counts in the outer ring. */
static const double DISK_RIM_ROUNDING = 4.0 * FLT_EPSILON;

static bool draw_disk_point(vec2 p, double *s, double *t)
{
    *s = sqrt((double)p.x * p.x + (double)p.y * p.y);
    *t = angle_phi(vec3_make(p.x, p.y, 0.0f));
    if (*s > 1.0 && *s <= 1.0 + DISK_RIM_ROUNDING)
        *s = 1.0;
    return *s <= 1.0;
}
static bool draw_disk_concentric(pcg32 *rng, const void *ctx, double *s, double *t)
{
    (void)ctx;
    return draw_disk_point(sample_uniform_disk_concentric(next_u(rng)), s, t);
}
static bool draw_disk_polar(pcg32 *rng, const void *ctx, double *s, double *t)
{
    (void)ctx;
    return draw_disk_point(sample_uniform_disk_polar(next_u(rng)), s, t);
}
/* Twins: r = u1 in the polar map; the square squashed radially onto the
 * disk (each point scaled by its square-radius over its length), which is
 * continuous and covers the disk but is not area-preserving. */
static bool draw_disk_polar_sqrt_missing(pcg32 *rng, const void *ctx, double *s, double *t)
{
    (void)ctx;
    vec2 u = next_u(rng);
    float phi = 2.0f * (float)PI * u.y;
    return draw_disk_point(vec2_make(u.x * cosf(phi), u.x * sinf(phi)), s, t);
}
static bool draw_disk_radial_squash(pcg32 *rng, const void *ctx, double *s, double *t)
{
    (void)ctx;
    vec2 u = next_u(rng);
    float ox = 2.0f * u.x - 1.0f, oy = 2.0f * u.y - 1.0f;
    float length = hypotf(ox, oy), square_radius = fmaxf(fabsf(ox), fabsf(oy));
    float scale = length > 0.0f ? square_radius / length : 0.0f;
    return draw_disk_point(vec2_make(ox * scale, oy * scale), s, t);
}

static double disk_cell_density(double r, double phi, const void *ctx) { return disk_density(r, phi, ctx); }

static chi2_case disk_chi2(const char *name, bool (*draw)(pcg32 *, const void *, double *, double *))
{
    return (chi2_case){name, CHI2_ROWS, CHI2_COLS, 1.0, 2 * PI, draw, disk_cell_density, NULL, NULL};
}

static void test_chi_square_disks(void **state)
{
    (void)state;
    chi2_case c = disk_chi2("concentric disk", draw_disk_concentric);
    assert_chi2_passes(&c, 110);
    c = disk_chi2("polar disk", draw_disk_polar);
    assert_chi2_passes(&c, 111);
}

static void test_chi_square_disks_twins_fail(void **state)
{
    (void)state;
    chi2_case c = disk_chi2("disk, radial squash of the square", draw_disk_radial_squash);
    assert_chi2_fails(&c, 110);
    c = disk_chi2("polar disk, r = u1 (sqrt missing)", draw_disk_polar_sqrt_missing);
    assert_chi2_fails(&c, 111);
}

/* -- the triangle: s = b1, t = b2, over the reference triangle -- */

static bool draw_triangle(pcg32 *rng, const void *ctx, double *s, double *t)
{
    (void)ctx;
    vec3 b = sample_uniform_triangle(next_u(rng));
    *s = b.y;
    *t = b.z;
    return b.x >= -1e-6f && b.y >= 0.0f && b.z >= 0.0f;
}
/* Twin: the sqrt missing, b0 = 1 - u1, b1 = u1 u2. */
static bool draw_triangle_sqrt_missing(pcg32 *rng, const void *ctx, double *s, double *t)
{
    (void)ctx;
    vec2 u = next_u(rng);
    *s = u.x * u.y;
    *t = u.x - u.x * u.y;
    return true;
}

/* In (b1, b2) the density is pdf * |d area / d(b1, b2)| = pdf * 2 * area,
 * constant on the triangle b1 + b2 <= 1 and zero beyond it. The grid is
 * square with CHI2_ROWS cells a side, so the diagonal runs through cell
 * corners: a cell is inside, outside, or cut exactly in half. */
static double triangle_cell_probability(double s0, double s1, double t0, double t1, const void *ctx)
{
    (void)ctx;
    vec3 p0 = vec3_make(0, 0, 0), p1 = vec3_make(1, 0, 0), p2 = vec3_make(0, 1, 0);
    double density = uniform_triangle_pdf(p0, p1, p2) * 2.0 * triangle_area(p0, p1, p2);
    double cell_area = (s1 - s0) * (t1 - t0);
    double h = 1.0 / CHI2_ROWS, corner = (s0 + t0) / h; /* an integer, up to rounding */
    int k = (int)lround(corner);
    double inside = k <= CHI2_ROWS - 2 ? cell_area : k == CHI2_ROWS - 1 ? 0.5 * cell_area : 0.0;
    return density * inside;
}

static chi2_case triangle_chi2(const char *name, bool (*draw)(pcg32 *, const void *, double *, double *))
{
    return (chi2_case){name, CHI2_ROWS, CHI2_ROWS, 1.0, 1.0, draw, NULL, triangle_cell_probability, NULL};
}

static void test_chi_square_triangle(void **state)
{
    (void)state;
    chi2_case c = triangle_chi2("uniform triangle", draw_triangle);
    assert_chi2_passes(&c, 120);
}

static void test_chi_square_triangle_twin_fails(void **state)
{
    (void)state;
    chi2_case c = triangle_chi2("triangle, sqrt missing", draw_triangle_sqrt_missing);
    assert_chi2_fails(&c, 120);
}

/* -- the 1D table: s = x - min, one column -- */

static bool draw_table(pcg32 *rng, const void *ctx, double *s, double *t)
{
    *s = sample_piecewise_constant_1d(ctx, pcg32_double(rng), NULL) - TABLE_MIN;
    *t = 0.5;
    return true;
}
/* Twin: a sampler that picks each bin equally often (the cdf ignored). */
static bool draw_table_ignoring_cdf(pcg32 *rng, const void *ctx, double *s, double *t)
{
    (void)ctx;
    *s = pcg32_double(rng) * (TABLE_MAX - TABLE_MIN);
    *t = 0.5;
    return true;
}
/* Cells are quarters of the table's bins: the pdf is constant in each. */
static double table_cell_probability(double s0, double s1, double t0, double t1, const void *ctx)
{
    (void)t0;
    (void)t1;
    return piecewise_constant_1d_pdf(ctx, TABLE_MIN + 0.5 * (s0 + s1)) * (s1 - s0);
}

static chi2_case table_chi2(const char *name, bool (*draw)(pcg32 *, const void *, double *, double *),
                            const piecewise_constant_1d *d)
{
    return (chi2_case){name, 4 * TABLE_BINS, 1, TABLE_MAX - TABLE_MIN, 1.0, draw, NULL, table_cell_probability, d};
}

static void test_chi_square_piecewise_constant_1d(void **state)
{
    (void)state;
    exercise_checks("invert_cdf");
    piecewise_constant_1d d = make_table();
    chi2_case c = table_chi2("1D piecewise-constant table", draw_table, &d);
    assert_chi2_passes(&c, 130);
    piecewise_constant_1d_free(&d);
}

static void test_chi_square_piecewise_constant_1d_twin_fails(void **state)
{
    (void)state;
    piecewise_constant_1d d = make_table();
    chi2_case c = table_chi2("1D table, cdf ignored", draw_table_ignoring_cdf, &d);
    assert_chi2_fails(&c, 130);
    piecewise_constant_1d_free(&d);
}

/* ==== 3. estimators =========================================================== */

enum { MAX_POINTS = 1 << 14 };
static double scratch[2 * MAX_POINTS];

/* One estimate F_N from a generator: the catalogue's estimators, and the
 * broken ones of the twins, all take this shape. */
typedef double (*estimate_fn)(const void *ctx, int n, pcg32 *rng);

typedef struct {
    const integrand *f;
    const estimator *e;
} catalogue_entry;

static double estimate_catalogue(const void *ctx, int n, pcg32 *rng)
{
    const catalogue_entry *c = ctx;
    return estimator_estimate(c->f, c->e, n, rng, scratch);
}

/* `runs` independent estimates with n samples: their mean and variance. */
static welford run_estimates(estimate_fn fn, const void *ctx, int n, int runs, uint64_t seed)
{
    welford w = {0};
    uint64_t stream = experiment_stream_seed(test_seed(seed), 0, 0, n);
    for (int r = 0; r < runs; r++) {
        pcg32 rng = pcg32_for_pixel(stream, (uint64_t)r);
        welford_add(&w, fn(ctx, n, &rng));
    }
    return w;
}

/* ---- unbiased ---------------------------------------------------------------- */

/* Each estimator is run UNBIASED_RUNS times with UNBIASED_N samples, and the
 * mean must be within z standard errors of the exact value. z is set so that
 * all UNBIASED_TESTS tests together fail a correct implementation with
 * probability 1e-6 (Sidak; two-sided normal tail P(|Z| > z) = P(chi2_1 > z^2)):
 * z = 5.40, a little more than the 5 of a single test. The mean of 256
 * estimates is close to normal: each is already a mean of 16 samples. */
enum { UNBIASED_RUNS = 256, UNBIASED_N = 16, UNBIASED_TESTS = 15 };
static const double UNBIASED_ALPHA_TOTAL = 1e-6;
/* The zero-variance estimator (cosine sampling of cos) has a standard error
 * of ~1e-8 from float rounding alone, and a rounding bias of the same size
 * (1/pi in float is off by 4e-8 relative). A floor of 1e-6 relative is 20
 * times that, and 100 times below the smallest bias the twins have. */
static const double UNBIASED_ROUNDING_FLOOR = 1e-6;

static double unbiased_z(void)
{
    double alpha = stats_sidak_alpha(UNBIASED_ALPHA_TOTAL, UNBIASED_TESTS);
    return sqrt(chi_square_upper_quantile(alpha, 1));
}

static bool looks_unbiased(estimate_fn fn, const void *ctx, double exact, uint64_t seed, const char *name)
{
    welford w = run_estimates(fn, ctx, UNBIASED_N, UNBIASED_RUNS, seed);
    double error = fabs(welford_mean(&w) - exact);
    double bound = unbiased_z() * welford_standard_error(&w) + UNBIASED_ROUNDING_FLOOR * fabs(exact);
    print_message("unbiased? %-52s |mean - exact| = %.3g, bound %.3g\n", name, error, bound);
    return error <= bound;
}

static void test_every_estimator_is_unbiased(void **state)
{
    (void)state;
    exercise_checks("mc_estimator");
    experiment_catalogue cat;
    experiment_catalogue_init(&cat);
    int tests = 0;
    for (int e = 0; e < EXPERIMENT_COUNT; e++)
        for (int j = 0; j < cat.experiments[e].estimator_count; j++) {
            const experiment *ex = &cat.experiments[e];
            catalogue_entry entry = {ex->integrand, &ex->estimators[j]};
            char name[128];
            snprintf(name, sizeof name, "%s / %s", ex->integrand->name, ex->estimators[j].name);
            assert_true(looks_unbiased(estimate_catalogue, &entry, ex->integrand->exact, 200 + 10 * e + j, name));
            tests++;
        }
    assert_int_equal(tests, UNBIASED_TESTS);
    experiment_catalogue_free(&cat);
}

/* Twins: four biased estimators, each a mistake learners make. */

/* Cosine-distributed directions divided by the uniform pdf 1/(2 pi): gives
 * 2 pi E[cos] = 2 pi * 2/3 = 4 pi / 3 for the integral of cos. */
static double estimate_cosine_with_uniform_pdf(const void *ctx, int n, pcg32 *rng)
{
    (void)ctx;
    double sum = 0.0;
    for (int i = 0; i < n; i++) {
        vec3 w = sample_cosine_hemisphere(vec2_make(pcg32_float(rng), pcg32_float(rng)));
        sum += w.z / uniform_hemisphere_pdf();
    }
    return sum / n;
}

/* The table's values used as the pdf without dividing by their integral. */
static double estimate_unnormalized_table(const void *ctx, int n, pcg32 *rng)
{
    const piecewise_constant_1d *d = ctx;
    double sum = 0.0;
    for (int i = 0; i < n; i++) {
        double x = sample_piecewise_constant_1d(d, pcg32_double(rng), NULL);
        double width = 1.0 / d->count;
        sum += x * x / d->func[(int)(x / width)];
    }
    return sum / n;
}

/* "Jittered" points with no jitter: the corner of each stratum (a left
 * Riemann sum, biased low by 1/(2N) for x^2). */
static double estimate_strata_corners(const void *ctx, int n, pcg32 *rng)
{
    (void)ctx;
    (void)rng;
    double sum = 0.0;
    for (int i = 0; i < n; i++)
        sum += ((double)i / n) * ((double)i / n);
    return sum / n;
}

/* Sobol points without scrambling: a fixed point set, the same every run,
 * so the "runs" do not vary and the error is a bias. */
static double estimate_unscrambled_sobol(const void *ctx, int n, pcg32 *rng)
{
    (void)ctx;
    (void)rng;
    double sum = 0.0;
    for (int i = 0; i < n; i++) {
        double x = sobol_bits((uint32_t)i, 0) * 0x1.0p-32;
        sum += x * x;
    }
    return sum / n;
}

static void test_biased_estimators_fail_the_unbiased_test(void **state)
{
    (void)state;
    experiment_catalogue cat;
    experiment_catalogue_init(&cat);
    assert_false(looks_unbiased(estimate_cosine_with_uniform_pdf, NULL, PI, 300, "cosine samples, uniform pdf"));
    assert_false(looks_unbiased(estimate_unnormalized_table, &cat.x_squared_table, 1.0 / 3, 301,
                                "x^2 table not normalized"));
    assert_false(looks_unbiased(estimate_strata_corners, NULL, 1.0 / 3, 302, "strata corners, no jitter"));
    assert_false(looks_unbiased(estimate_unscrambled_sobol, NULL, 1.0 / 3, 303, "Sobol, not scrambled"));
    experiment_catalogue_free(&cat);
}

/* p proportional to f: cosine-weighted sampling of the integral of cos gives
 * f/p = cos / (cos/pi) = pi for every sample. Zero variance, up to float
 * rounding (relative error of a few 2^-24). */
static const double ZERO_VARIANCE_RELATIVE_TOLERANCE = 1e-6;

static void test_p_proportional_to_f_has_zero_variance(void **state)
{
    (void)state;
    exercise_checks("mc_estimator");
    const sampling_strategy cosine = {"cosine", warp_cosine_hemisphere, NULL};
    const sampling_strategy uniform = {"uniform", warp_uniform_hemisphere, NULL};
    pcg32 rng = pcg32_for_pixel(test_seed(310), 0);
    double worst_cosine = 0.0, worst_uniform = 0.0;
    for (int i = 0; i < 100000; i++) {
        double u[2] = {pcg32_double(&rng), pcg32_double(&rng)};
        double cos_estimate = monte_carlo_estimate(&integrand_hemisphere_cosine, &cosine, u, 1);
        double uni_estimate = monte_carlo_estimate(&integrand_hemisphere_cosine, &uniform, u, 1);
        worst_cosine = fmax(worst_cosine, fabs(cos_estimate - PI));
        worst_uniform = fmax(worst_uniform, fabs(uni_estimate - PI));
    }
    assert_true(worst_cosine <= ZERO_VARIANCE_RELATIVE_TOLERANCE * PI);
    /* The twin: uniform sampling of the same integral does vary, by pi or more. */
    assert_false(worst_uniform <= ZERO_VARIANCE_RELATIVE_TOLERANCE * PI);
}

/* ---- variance against N ---------------------------------------------------- */

/* The least-squares slope of log Var[F_N] against log N must be within 0.15
 * of theory. With SLOPE_RUNS = 256 runs per N, each log variance has a
 * standard deviation of about sqrt(2/255) = 0.09 (a little more for
 * non-normal estimates); over 9 values of N spanning a factor of 256 (log
 * span 5.5) the slope's standard deviation is 0.09 / sqrt(sum (log N -
 * mean)^2) = 0.09 / 5.4 ~ 0.017. 0.15 is 9 of those: a correct
 * implementation misses it with probability far below 1e-6, while a rate
 * wrong by 0.5 (the twins) cannot pass. */
static const double SLOPE_TOLERANCE = 0.15;
enum { SLOPE_RUNS = 256, SLOPE_POINTS = 9 };

static double variance_slope(estimate_fn fn, const void *ctx, const int *ns, uint64_t seed)
{
    double x[SLOPE_POINTS], y[SLOPE_POINTS];
    for (int k = 0; k < SLOPE_POINTS; k++) {
        welford w = run_estimates(fn, ctx, ns[k], SLOPE_RUNS, seed + (uint64_t)k);
        x[k] = ns[k];
        y[k] = welford_variance(&w);
    }
    return stats_loglog_slope(x, y, SLOPE_POINTS);
}

/* Independent samples: Var[F_N] = sigma^2 / N exactly, at every N, so any
 * range will do; N = 4 .. 1024 keeps it quick. */
static const int INDEPENDENT_NS[SLOPE_POINTS] = {4, 8, 16, 32, 64, 128, 256, 512, 1024};

static double estimate_x_squared_uniform(const void *ctx, int n, pcg32 *rng)
{
    (void)ctx;
    const estimator e = {"uniform", "", POINTS_INDEPENDENT, {"uniform", warp_uniform_interval, NULL}};
    return estimator_estimate(&integrand_x_squared, &e, n, rng, scratch);
}

/* The twin: a generator seeded afresh for every sample ("never seed per
 * call"): all N samples are the same number, and the variance does not fall. */
static double estimate_x_squared_reseeded(const void *ctx, int n, pcg32 *rng)
{
    (void)ctx;
    uint64_t seed = pcg32_next(rng); /* one seed per estimate ... */
    double sum = 0.0;
    for (int i = 0; i < n; i++) {
        pcg32 fresh = pcg32_for_pixel(seed, 0); /* ... but the generator re-created per sample */
        double x = pcg32_double(&fresh);
        sum += x * x;
    }
    return sum / n;
}

static void test_variance_of_independent_samples_falls_as_one_over_n(void **state)
{
    (void)state;
    exercise_checks("mc_estimator");
    double slope = variance_slope(estimate_x_squared_uniform, NULL, INDEPENDENT_NS, 400);
    print_message("independent, x^2: slope of log Var against log N = %.3f (theory -1)\n", slope);
    assert_close(slope, -1.0, SLOPE_TOLERANCE);
    double twin = variance_slope(estimate_x_squared_reseeded, NULL, INDEPENDENT_NS, 401);
    print_message("generator re-seeded per sample: slope = %.3f (must fail)\n", twin);
    assert_false(fabs(twin - -1.0) <= SLOPE_TOLERANCE);
}

/* Jittered samples on the unit square, m x m strata (N = m^2), or N strips
 * (stratified in x only: the twin). */
typedef struct {
    const integrand *f;
    bool strips;
} jitter_ctx;

static double estimate_jittered_square(const void *ctx, int n, pcg32 *rng)
{
    const jitter_ctx *j = ctx;
    const sampling_strategy square = {"uniform", warp_uniform_square, NULL};
    if (j->strips) {
        points_jittered_2d(rng, n, 1, scratch);
    } else {
        int m = (int)lround(sqrt((double)n));
        points_jittered_2d(rng, m, m, scratch);
    }
    return monte_carlo_estimate(j->f, &square, scratch, n);
}

/* Square strata only (N = m^2): 2:1 rectangles have a different constant,
 * and mixing the two shapes would zigzag the curve. m doubles every two
 * steps (a factor sqrt 2 in m, 2 in N). For the smooth Gaussian the
 * variance is sum over strata of (h^2 |grad f|^2 / 12) / N^2 ~ N^-2 once a
 * stratum (side h = 1/m) is small next to the Gaussian's width sigma = 1/4:
 * m >= 8 (h <= sigma/2), so N = 64 .. 16384. */
static const int JITTERED_SMOOTH_NS[SLOPE_POINTS] = {64, 121, 256, 529, 1024, 2025, 4096, 8281, 16384};
/* For the disk only the strata the circle crosses vary; there are about
 * 2 pi r m of them, each contributing at most 1/(4 N^2): Var ~ m / N^2 =
 * N^-1.5. That needs strata small next to the radius (h <= r/3, m >= 8) so
 * that the circle looks straight inside each one: the same range. */
static const int JITTERED_DISK_NS[SLOPE_POINTS] = {64, 121, 256, 529, 1024, 2025, 4096, 8281, 16384};

static void test_jittered_variance_falls_as_n_to_the_minus_two_on_a_smooth_integrand(void **state)
{
    (void)state;
    jitter_ctx grid = {&integrand_gaussian, false}, strips = {&integrand_gaussian, true};
    double slope = variance_slope(estimate_jittered_square, &grid, JITTERED_SMOOTH_NS, 410);
    print_message("jittered, Gaussian: slope = %.3f (theory -2)\n", slope);
    assert_close(slope, -2.0, SLOPE_TOLERANCE);
    double twin = variance_slope(estimate_jittered_square, &strips, JITTERED_SMOOTH_NS, 411);
    print_message("strips (x stratified only), Gaussian: slope = %.3f (must fail)\n", twin);
    assert_false(fabs(twin - -2.0) <= SLOPE_TOLERANCE);
}

static void test_jittered_variance_falls_as_n_to_the_minus_three_halves_on_a_disk(void **state)
{
    (void)state;
    jitter_ctx grid = {&integrand_disk, false}, strips = {&integrand_disk, true};
    double slope = variance_slope(estimate_jittered_square, &grid, JITTERED_DISK_NS, 420);
    print_message("jittered, disk: slope = %.3f (theory -1.5)\n", slope);
    assert_close(slope, -1.5, SLOPE_TOLERANCE);
    double twin = variance_slope(estimate_jittered_square, &strips, JITTERED_DISK_NS, 421);
    print_message("strips (x stratified only), disk: slope = %.3f (must fail)\n", twin);
    assert_false(fabs(twin - -1.5) <= SLOPE_TOLERANCE);
}

/* The step beyond the lecture: Owen-scrambled Sobol points at N = 2^m are
 * stratified in every elementary box at once, and their scrambles are
 * nested-random, which gives Var ~ N^-3 (log N) on a smooth integrand (Owen
 * 1997): a local slope of about -3 + 1/ln N ~ -2.86 over this range. The
 * test asks only for a rate clearly beyond jittered's -2: at most
 * SOBOL_SMOOTH_MAX_SLOPE, which is 0.36 above the expected value (20
 * standard deviations of the fit, see SLOPE_TOLERANCE) and 0.5 below -2. */
static const double SOBOL_SMOOTH_MAX_SLOPE = -2.5;
static const int SOBOL_NS[SLOPE_POINTS] = {64, 128, 256, 512, 1024, 2048, 4096, 8192, 16384};

static double estimate_gaussian_points(const void *ctx, int n, pcg32 *rng)
{
    const point_set *kind = ctx;
    const sampling_strategy square = {"uniform", warp_uniform_square, NULL};
    points_generate(*kind, rng, n, 2, scratch);
    return monte_carlo_estimate(&integrand_gaussian, &square, scratch, n);
}

static void test_owen_sobol_variance_falls_faster_than_jittered_on_a_smooth_integrand(void **state)
{
    (void)state;
    const point_set sobol = POINTS_SOBOL_OWEN, jittered = POINTS_JITTERED;
    double slope = variance_slope(estimate_gaussian_points, &sobol, SOBOL_NS, 430);
    print_message("Owen-scrambled Sobol, Gaussian: slope = %.3f (theory about -2.86)\n", slope);
    assert_true(slope <= SOBOL_SMOOTH_MAX_SLOPE);
    double twin = variance_slope(estimate_gaussian_points, &jittered, SOBOL_NS, 431);
    print_message("jittered, Gaussian, N = 2^m: slope = %.3f (must fail)\n", twin);
    assert_false(twin <= SOBOL_SMOOTH_MAX_SLOPE);
}

/* ---- N Var against the closed form ---------------------------------------- */

/* For x^2 with uniform samples the per-sample variance is
 * E[X^4] - E[X^2]^2 = 1/5 - 1/9 = 4/45, so N Var[F_N] = 4/45 at every N.
 * With R runs, (R - 1) s^2 / (4/45 / N) is chi-square with R - 1 degrees of
 * freedom if F_N is normal. It is not quite (F_1 = U^2 is flatter than a
 * normal: excess kurtosis -6/7), which makes s^2 vary LESS than the
 * chi-square says: the bound is conservative. Two-sided, at a total of 1e-6
 * over the NVAR_COUNT values of N (Sidak). */
enum { NVAR_RUNS = 2048, NVAR_COUNT = 7 };
static const int NVAR_NS[NVAR_COUNT] = {1, 2, 4, 8, 16, 64, 256};
static const double NVAR_ALPHA_TOTAL = 1e-6;
static const double X_SQUARED_PER_SAMPLE_VARIANCE = 4.0 / 45.0;

static bool n_var_matches(estimate_fn fn, uint64_t seed, const char *name)
{
    double alpha = stats_sidak_alpha(NVAR_ALPHA_TOTAL, NVAR_COUNT);
    bool ok = true;
    for (int k = 0; k < NVAR_COUNT; k++) {
        welford w = run_estimates(fn, NULL, NVAR_NS[k], NVAR_RUNS, seed + (uint64_t)k);
        double n_var = NVAR_NS[k] * welford_variance(&w);
        double statistic = (NVAR_RUNS - 1) * n_var / X_SQUARED_PER_SAMPLE_VARIANCE;
        double upper = stats_chi_square_p_value(statistic, NVAR_RUNS - 1);
        double lower = stats_chi_square_lower_tail(statistic, NVAR_RUNS - 1);
        double p = 2.0 * fmin(upper, lower);
        print_message("%s: N = %3d, N Var = %.5f (4/45 = %.5f), two-sided p = %.3g\n", name, NVAR_NS[k], n_var,
                      X_SQUARED_PER_SAMPLE_VARIANCE, p);
        ok = ok && p >= alpha;
    }
    return ok;
}

/* The twin: each random number used for two samples in a row (a "saved"
 * call): still unbiased, and the variance still falls as 1/N, so the two
 * tests above pass it; but it is twice as large. Only this test sees it. */
static double estimate_x_squared_pairs(const void *ctx, int n, pcg32 *rng)
{
    (void)ctx;
    double sum = 0.0, x = 0.0;
    for (int i = 0; i < n; i++) {
        if (i % 2 == 0)
            x = pcg32_double(rng);
        sum += x * x;
    }
    return sum / n;
}

static void test_n_var_is_the_closed_form_per_sample_variance(void **state)
{
    (void)state;
    assert_true(n_var_matches(estimate_x_squared_uniform, 500, "uniform"));
    assert_false(n_var_matches(estimate_x_squared_pairs, 501, "each number used twice"));
}

/* ---- point sets --------------------------------------------------------------- */

static void test_jittered_points_fill_every_stratum_once(void **state)
{
    (void)state;
    pcg32 rng = pcg32_for_pixel(test_seed(600), 0);
    const int shapes[][2] = {{1, 1}, {4, 4}, {8, 4}, {3, 7}, {16, 16}};
    for (size_t s = 0; s < sizeof shapes / sizeof shapes[0]; s++) {
        int nx = shapes[s][0], ny = shapes[s][1];
        int count[256] = {0};
        points_jittered_2d(&rng, nx, ny, scratch);
        for (int i = 0; i < nx * ny; i++) {
            int cx = (int)(scratch[2 * i] * nx), cy = (int)(scratch[2 * i + 1] * ny);
            assert_true(cx >= 0 && cx < nx && cy >= 0 && cy < ny);
            count[cy * nx + cx]++;
        }
        for (int c = 0; c < nx * ny; c++)
            assert_int_equal(count[c], 1);
    }
    int nx, ny;
    jittered_grid_shape(1024, &nx, &ny);
    assert_true(nx == 32 && ny == 32);
    jittered_grid_shape(2048, &nx, &ny);
    assert_true(nx == 32 && ny == 64);
    jittered_grid_shape(1, &nx, &ny);
    assert_true(nx == 1 && ny == 1);
}

/* Does every elementary box of area 2^-m (2^a x 2^(m-a) of them, for every
 * a) hold exactly one of the 2^m points? (The (0, m, 2)-net property.) */
static bool is_0_m_2_net(const double *u, int m)
{
    int n = 1 << m;
    int *count = calloc((size_t)n, sizeof(int));
    bool ok = true;
    for (int a = 0; a <= m && ok; a++) {
        memset(count, 0, sizeof(int) * (size_t)n);
        for (int i = 0; i < n; i++) {
            int cx = (int)(u[2 * i] * (1 << a)), cy = (int)(u[2 * i + 1] * (1 << (m - a)));
            count[(cy << a) + cx]++;
        }
        for (int c = 0; c < n; c++)
            ok = ok && count[c] == 1;
    }
    free(count);
    return ok;
}

static void test_owen_scrambled_sobol_prefixes_are_nets(void **state)
{
    (void)state;
    for (int m = 0; m <= 12; m++) {
        pcg32 rng = pcg32_for_pixel(test_seed(610), (uint64_t)m);
        points_generate(POINTS_SOBOL_OWEN, &rng, 1 << m, 2, scratch);
        assert_true(is_0_m_2_net(scratch, m));
        /* ... and unscrambled, the sequence itself */
        for (int i = 0; i < 1 << m; i++) {
            scratch[2 * i] = sobol_bits((uint32_t)i, 0) * 0x1.0p-32;
            scratch[2 * i + 1] = sobol_bits((uint32_t)i, 1) * 0x1.0p-32;
        }
        assert_true(is_0_m_2_net(scratch, m));
    }
    /* The twins: jittered points are stratified in one grid only, and
     * independent points in none; neither is a net for m = 8. */
    pcg32 rng = pcg32_for_pixel(test_seed(611), 0);
    points_generate(POINTS_JITTERED, &rng, 256, 2, scratch);
    assert_false(is_0_m_2_net(scratch, 8));
    points_generate(POINTS_INDEPENDENT, &rng, 256, 2, scratch);
    assert_false(is_0_m_2_net(scratch, 8));
}

static void test_owen_scramble_is_a_permutation_of_nested_boxes(void **state)
{
    (void)state;
    /* Two fractions that share their first k bits still share their first k
     * bits after scrambling (nested boxes go to nested boxes), and different
     * values stay different. */
    pcg32 rng = pcg32_for_pixel(test_seed(620), 0);
    for (int i = 0; i < 10000; i++) {
        uint32_t seed = pcg32_next(&rng), a = pcg32_next(&rng);
        int k = (int)pcg32_bounded(&rng, 32);
        uint32_t keep = k == 0 ? 0u : ~0u << (32 - k);
        uint32_t b = (a & keep) | (pcg32_next(&rng) & ~keep);
        uint32_t sa = owen_scramble(a, seed), sb = owen_scramble(b, seed);
        assert_int_equal(sa & keep, sb & keep);
        if (a != b)
            assert_true(sa != sb);
    }
}

/* ---- sin and cos of an angle in turns ----------------------------------------
 * sincos_turns(u) is sinf and cosf of phi = 2 pi u, phi a float. Its error
 * is the angle's: |phi - 2 pi u| <= u |(float)(2 pi) - 2 pi| + half an ulp
 * of phi <= 1.75e-7 + 2.38e-7, and sin and cos change by at most that much;
 * plus sinf's or cosf's own rounding, under an ulp of a value <= 1 (6e-8).
 * So within SINCOS_TURNS_ERROR of sin and cos of 2 pi u in double, on every
 * 101st float in [0, 1]. The twin swaps the sine and the cosine. */
static const double SINCOS_TURNS_ERROR = 4.8e-7;

typedef void (*sincos_fn)(float u, float *s, float *c);

static void sincos_swapped(float u, float *s, float *c) { sincos_turns(u, c, s); }

static double sincos_worst_error(sincos_fn f)
{
    double worst = 0.0;
    for (uint32_t bits = 0; bits <= 0x3f800000u; bits += 101) {
        float u;
        memcpy(&u, &bits, sizeof u);
        float s, c;
        f(u, &s, &c);
        worst = fmax(worst, fmax(fabs(s - sin(2.0 * PI * u)), fabs(c - cos(2.0 * PI * u))));
    }
    return worst;
}

static void test_sincos_turns_is_sin_and_cos_of_two_pi_u(void **state)
{
    (void)state;
    double worst = sincos_worst_error(sincos_turns);
    print_message("sincos_turns: at most %.3g from sin and cos of 2 pi u\n", worst);
    assert_true(worst <= SINCOS_TURNS_ERROR);
    double twin = sincos_worst_error(sincos_swapped);
    print_message("twin (sine and cosine swapped): %.3g\n", twin);
    assert_true(twin > SINCOS_TURNS_ERROR);
}

/* ---- the integrals' exact values ------------------------------------------- */

static void test_exact_values(void **state)
{
    (void)state;
    double one_axis = GAUSSIAN_SIGMA * sqrt(2 * PI) * erf(0.5 / (sqrt(2.0) * GAUSSIAN_SIGMA));
    assert_close(integrand_gaussian.exact, one_axis * one_axis, 1e-15);
    assert_close(integrand_disk.exact, PI * DISK_RADIUS * DISK_RADIUS, 1e-15);
    assert_close(integrand_x_squared.exact, 1.0 / 3.0, 0.0);
    assert_close(integrand_hemisphere_cosine.exact, PI, 0.0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_chi_square_p_value_closed_forms),
        cmocka_unit_test(test_chi_square_p_value_many_degrees_of_freedom),
        cmocka_unit_test(test_chi_square_p_value_table_values),
        cmocka_unit_test(test_sidak_alpha),
        cmocka_unit_test(test_chi_square_quantile_helper),
        cmocka_unit_test(test_round_trips),
        cmocka_unit_test(test_round_trip_catches_a_wrong_inverse),
        cmocka_unit_test(test_piecewise_constant_1d_round_trip_and_zero_bins),
        cmocka_unit_test(test_piecewise_constant_1d_rejects_bad_tables),
        cmocka_unit_test(test_pdfs_integrate_to_one),
        cmocka_unit_test(test_pdf_integral_catches_wrong_pdfs),
        cmocka_unit_test(test_chi_square_directions),
        cmocka_unit_test(test_chi_square_directions_twins_fail),
        cmocka_unit_test(test_chi_square_lambertian_offset_constructions),
        cmocka_unit_test(test_chi_square_lambertian_offset_twins_fail),
        cmocka_unit_test(test_chi_square_disks),
        cmocka_unit_test(test_chi_square_disks_twins_fail),
        cmocka_unit_test(test_chi_square_triangle),
        cmocka_unit_test(test_chi_square_triangle_twin_fails),
        cmocka_unit_test(test_chi_square_piecewise_constant_1d),
        cmocka_unit_test(test_chi_square_piecewise_constant_1d_twin_fails),
        cmocka_unit_test(test_sincos_turns_is_sin_and_cos_of_two_pi_u),
        cmocka_unit_test(test_exact_values),
        cmocka_unit_test(test_every_estimator_is_unbiased),
        cmocka_unit_test(test_biased_estimators_fail_the_unbiased_test),
        cmocka_unit_test(test_p_proportional_to_f_has_zero_variance),
        cmocka_unit_test(test_variance_of_independent_samples_falls_as_one_over_n),
        cmocka_unit_test(test_jittered_variance_falls_as_n_to_the_minus_two_on_a_smooth_integrand),
        cmocka_unit_test(test_jittered_variance_falls_as_n_to_the_minus_three_halves_on_a_disk),
        cmocka_unit_test(test_owen_sobol_variance_falls_faster_than_jittered_on_a_smooth_integrand),
        cmocka_unit_test(test_n_var_is_the_closed_form_per_sample_variance),
        cmocka_unit_test(test_jittered_points_fill_every_stratum_once),
        cmocka_unit_test(test_owen_scrambled_sobol_prefixes_are_nets),
        cmocka_unit_test(test_owen_scramble_is_a_permutation_of_nested_boxes),
    };
    return cmocka_run_group_tests_name("ch08 Monte Carlo integration", tests, NULL, NULL);
}
