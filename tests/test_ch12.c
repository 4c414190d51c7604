/* test_ch12.c -- Metropolis light transport: the chain samples f / b (a 1-D
 * toy with a known density), the image converges to chapter 09's, the
 * normalization b agrees with the path tracer's image mean, and the image
 * is the same bit for bit on 1 and 2 threads, and short runs from a fixed
 * start have start-up bias; the three unbiased methods of the "which
 * method" comparison (path tracing, BDPT, MLT) make the same image of
 * chapter 11's ceiling lamp. Each statistical check has a
 * twin on a deliberately wrong implementation that it must reject. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "09-path-tracing/path_tracer.h"
#include "11-bidirectional/bdpt.h"
#include "12-metropolis/mlt.h"
#include "12-metropolis/mlt_experiments.h"
#include "render.h"
#include "stats.h"
#include "12-metropolis/mlt_scene.h"
#include "pt_scene_check.h"
#include "test_support.h"

/* The false-alarm budget of each statistical check (as chapter 09's). */
static const double FALSE_ALARM = 1e-6;
static const double STANDARD_ERRORS = 5.0;

/* ---- stationarity on a 1-D toy ------------------------------------------------
 * The "path" reads u0 and, if u0 < 1/2, also u1 (so u1 is sometimes unused
 * and must be brought up to date lazily). Its contribution:
 *   f(u0, u1) = g(u0) h(u1)  for u0 < 1/2,    g(u0)  otherwise,
 * with g = 1, 4, 0, 2 on the quarters of [0, 1) and h(u1) = 2 u1 (mean 1).
 * The chain's stationary density f / b then has the marginal g / 1.75 for u0,
 * and given u0 < 1/2, density 2 u1 for u1. */
static double toy_g(double u) { return u < 0.25 ? 1.0 : u < 0.5 ? 4.0 : u < 0.75 ? 0.0 : 2.0; }

typedef struct {
    double u0, u1, f;
} toy_state;

static toy_state toy_evaluate(mlt_sampler *s)
{
    toy_state t;
    t.u0 = mlt_sampler_next(s);
    t.u1 = -1.0;
    t.f = toy_g(t.u0);
    if (t.u0 < 0.5) {
        t.u1 = mlt_sampler_next(s);
        t.f *= 2.0 * t.u1;
    }
    return t;
}

static double always_accept(double f_current, double f_proposed)
{
    (void)f_current;
    (void)f_proposed;
    return 1.0;
}

enum { TOY_BINS = 20 };

/* Runs `chains` chains of `steps` steps from the sampler's first (uniform)
 * state and histograms their final states: long enough that the start is
 * forgotten (each step is a large step accepted with probability at least
 * 0.3 x 1.75 / 8 = 0.066, so after 400 steps the start weighs < 1e-11). Returns
 * the smaller p-value of two chi-square tests: u0 against g / 1.75, and u1
 * (where u0 < 1/2) against 2 u1. */
static double toy_p_value(mlt_acceptance_fn acceptance, uint64_t seed)
{
    const int chains = 6000, steps = 400;
    long u0_counts[TOY_BINS] = {0}, u1_counts[TOY_BINS] = {0};
    long u1_total = 0;
    for (int c = 0; c < chains; c++) {
        mlt_sampler s;
        mlt_sampler_init(&s, pcg32_for_pixel(seed, (uint64_t)c));
        toy_state current = toy_evaluate(&s);
        pcg32 rng = pcg32_for_pixel(seed ^ 0xabcdefULL, (uint64_t)c);
        for (int m = 0; m < steps; m++) {
            mlt_sampler_start_iteration(&s, pcg32_float(&rng) < 0.3f);
            toy_state proposed = toy_evaluate(&s);
            if (pcg32_double(&rng) < acceptance(current.f, proposed.f)) {
                mlt_sampler_accept(&s);
                current = proposed;
            } else {
                mlt_sampler_reject(&s);
            }
        }
        u0_counts[(int)(current.u0 * TOY_BINS)]++;
        if (current.u0 < 0.5) {
            u1_counts[(int)(current.u1 * TOY_BINS)]++;
            u1_total++;
        }
        mlt_sampler_free(&s);
    }
    /* u0: bins in a zero-density quarter must stay empty. */
    double chi2 = 0.0;
    int dof = -1;
    for (int i = 0; i < TOY_BINS; i++) {
        double expected = chains * toy_g((i + 0.5) / TOY_BINS) / 1.75 / TOY_BINS;
        if (expected == 0.0) {
            if (u0_counts[i] > 0)
                return 0.0;
            continue;
        }
        double d = (double)u0_counts[i] - expected;
        chi2 += d * d / expected;
        dof++;
    }
    double p0 = stats_chi_square_p_value(chi2, dof);
    chi2 = 0.0;
    for (int i = 0; i < TOY_BINS; i++) {
        double a = (double)i / TOY_BINS, b = (double)(i + 1) / TOY_BINS;
        double expected = (double)u1_total * (b * b - a * a);
        double d = (double)u1_counts[i] - expected;
        chi2 += d * d / expected;
    }
    double p1 = stats_chi_square_p_value(chi2, TOY_BINS - 1);
    print_message("toy chain: p-values %.3g (u0), %.3g (u1)\n", p0, p1);
    return fmin(p0, p1);
}

static void test_chain_samples_f_over_b(void **state)
{
    (void)state;
    exercise_checks("mlt_acceptance");
    exercise_checks("mlt_small_step");
    /* two tests: Sidak's share of the budget */
    double p = toy_p_value(mlt_acceptance, test_seed(1201)), alpha = stats_sidak_alpha(FALSE_ALARM, 2);
    if (!(p > alpha)) {
        print_error("the toy chain's final states do not follow f / b: p = %.3g, expected above %.3g (a chain "
                    "that moves by min(1, f(y) / f(x)) with a symmetric step passes)\n", p, alpha);
        fail();
    }
}

/* Twin: accepting every proposal ignores f: the chain stays uniform. */
static void test_twin_chain_without_acceptance_ratio_fails(void **state)
{
    (void)state;
    assert_true(toy_p_value(always_accept, test_seed(1201)) < stats_sidak_alpha(FALSE_ALARM, 2));
}

/* Small steps wrap around [0, 1) and stay inside it. */
static void test_small_step_wraps(void **state)
{
    (void)state;
    exercise_checks("mlt_small_step");
    pcg32 rng = pcg32_for_pixel(test_seed(1202), 0);
    float extremes[] = {0.0f, 1e-9f, 0.5f, 0.99999994f};
    for (int k = 0; k < 4; k++)
        for (int i = 0; i < 10000; i++) {
            float v = mlt_small_step(extremes[k], &rng);
            float distance = fabsf(v - extremes[k]);
            distance = fminf(distance, 1.0f - distance);
            if (!(v >= 0.0f && v < 1.0f) ||
                !(distance <= MLT_SMALL_STEP_MAX * 1.0001f && distance >= MLT_SMALL_STEP_MIN * 0.999f)) {
                print_error("mlt_small_step(%.9g) = %.9g: expected a value in [0, 1) at a distance around the "
                            "circle between s1 = 1/1024 and s2 = 1/64 (it is %.3g)\n",
                            (double)extremes[k], (double)v, (double)distance);
                fail();
            }
        }
}

/* Kelemen's kernel, in distribution: the step's size s is log-uniform on
 * [s1, s2] (ln(s2 / s) / ln(s2 / s1) is uniform on [0, 1)), and its sign is
 * + or - with probability 1/2 each. N steps from 0.5 (no wrap): Pearson's
 * chi-square of the 20 bins of that fraction, and the z-score of the count
 * of steps up, two checks sharing the false-alarm budget (Sidak). The
 * twin, a size uniform on [s1, s2] (which is also symmetric, but not the
 * kernel), is caught. */
enum { KERNEL_STEPS = 200000, KERNEL_BINS = 20 };

static float uniform_size_step(float value, pcg32 *rng)
{
    float size = MLT_SMALL_STEP_MIN + (MLT_SMALL_STEP_MAX - MLT_SMALL_STEP_MIN) * pcg32_float(rng);
    return pcg32_float(rng) < 0.5f ? value - size : value + size;
}

/* The kernel's two p-values from N steps from 0.5: sizes, then signs. */
static void kernel_p_values(float (*step)(float, pcg32 *), uint64_t seed, double *p_size, double *p_sign)
{
    pcg32 rng = pcg32_for_pixel(seed, 0);
    long counts[KERNEL_BINS] = {0}, up = 0;
    double log_range = log((double)MLT_SMALL_STEP_MAX / (double)MLT_SMALL_STEP_MIN);
    for (int i = 0; i < KERNEL_STEPS; i++) {
        double v = step(0.5f, &rng);
        up += v > 0.5;
        double size = fabs(v - 0.5), t = log((double)MLT_SMALL_STEP_MAX / size) / log_range;
        /* rounding (6e-8 near 0.5) may put t a hair outside [0, 1); a step
         * of 0 (or NaN) makes it infinite: the last bin */
        int bin = t >= 0.0 && t < 1.0 ? (int)(t * KERNEL_BINS) : t < 0.0 ? 0 : KERNEL_BINS - 1;
        counts[bin]++;
    }
    double chi2 = 0.0, expected = (double)KERNEL_STEPS / KERNEL_BINS;
    for (int b = 0; b < KERNEL_BINS; b++)
        chi2 += ((double)counts[b] - expected) * ((double)counts[b] - expected) / expected;
    *p_size = stats_chi_square_p_value(chi2, KERNEL_BINS - 1);
    double z = ((double)up - 0.5 * KERNEL_STEPS) / sqrt(0.25 * KERNEL_STEPS);
    *p_sign = erfc(fabs(z) / sqrt(2.0));
    print_message("small steps: sizes p = %.3g (chi-square %.1f on %d), %ld of %d up (z = %.2f, p = %.3g)\n",
                  *p_size, chi2, KERNEL_BINS - 1, up, KERNEL_STEPS, z, *p_sign);
}

static void test_small_step_is_kelemens_kernel(void **state)
{
    (void)state;
    exercise_checks("mlt_small_step");
    double alpha = stats_sidak_alpha(FALSE_ALARM, 2), p_size, p_sign;
    kernel_p_values(mlt_small_step, test_seed(1203), &p_size, &p_sign);
    if (!(p_size > alpha) || !(p_sign > alpha)) {
        print_error("the small steps are not Kelemen's kernel: p = %.3g for the sizes (expected log-uniform on "
                    "[s1, s2]), p = %.3g for the signs (expected + and - equally often), each expected above "
                    "%.3g\n", p_size, p_sign, alpha);
        fail();
    }
    /* the twin */
    kernel_p_values(uniform_size_step, test_seed(1203), &p_size, &p_sign);
    assert_true(p_size < alpha);
}

/* ---- the image against chapter 09's ---------------------------------------------- */

enum { SIDE = 16, REPLICAS = 16, MLT_MPP = 64, PT_SPP = 1024 };

typedef struct {
    pt_scene scene;
    path_tracer pt;
    camera cam;
} setup;

static void setup_cornell(setup *s)
{
    pt_scene_build_cornell_box(&s->scene);
    s->pt = path_tracer_defaults(&s->scene);
    s->pt.integrator = PT_MIS;
    s->pt.russian_roulette = RR_THROUGHPUT;
    s->cam = pt_scene_camera(&s->scene, SIDE, SIDE);
}

/* Per-pixel luminance of K independent MLT runs: their mean, and the
 * standard error of that mean from the spread of the replicas (MLT's
 * samples are correlated, so one run's own spread would understate it). */
typedef struct {
    double mean[SIDE * SIDE], standard_error[SIDE * SIDE];
    double b_mean, b_standard_error;
} mlt_replicas;

/* One MLT render on one thread: each pixel's luminance, and the result. */
static mlt_result render_luminance(const mlt_options *o, double *luminance)
{
    image img = image_make(SIDE, SIDE);
    mlt_result r;
    assert_true(mlt_render(o, &img, &r));
    for (int i = 0; i < SIDE * SIDE; i++)
        luminance[i] = vec3_luminance(vec3_make(img.rgb[3 * i], img.rgb[3 * i + 1], img.rgb[3 * i + 2]));
    image_free(&img);
    return r;
}

/* The mean of n independent values (given their sum and sum of squares)
 * and its standard error. */
static void mean_and_standard_error(double sum, double sum2, int n, double *mean, double *standard_error)
{
    *mean = sum / n;
    *standard_error = sqrt(fmax(0.0, (sum2 - sum * *mean) / (n - 1)) / n);
}

static void render_replicas(const setup *s, mlt_acceptance_fn acceptance, bool unnormalized, uint64_t seed,
                            mlt_replicas *out)
{
    static double values[REPLICAS][SIDE * SIDE];
    double b_sum = 0.0, b_sum2 = 0.0;
    for (int k = 0; k < REPLICAS; k++) {
        mlt_options o = mlt_defaults(&s->pt, &s->cam);
        o.mutations_per_pixel = MLT_MPP;
        o.bootstrap = SIDE * SIDE * MLT_MPP;
        o.chains = 16;
        o.seed = seed + (uint64_t)k * 7919u;
        o.threads = 1;
        o.acceptance = acceptance;
        mlt_result r = render_luminance(&o, values[k]);
        /* the twin that forgets b: every pixel as if b were 1 */
        for (int i = 0; unnormalized && i < SIDE * SIDE; i++)
            values[k][i] /= r.b;
        b_sum += r.b;
        b_sum2 += r.b * r.b;
    }
    mean_and_standard_error(b_sum, b_sum2, REPLICAS, &out->b_mean, &out->b_standard_error);
    for (int i = 0; i < SIDE * SIDE; i++) {
        double sum = 0.0, sum2 = 0.0;
        for (int k = 0; k < REPLICAS; k++) {
            sum += values[k][i];
            sum2 += values[k][i] * values[k][i];
        }
        mean_and_standard_error(sum, sum2, REPLICAS, &out->mean[i], &out->standard_error[i]);
    }
}

/* Chapter 09's image of the same pixels: luminance and its standard error. */
static void render_path_traced(const setup *s, uint64_t seed, double *mean, double *standard_error,
                               double *image_mean, double *image_mean_se)
{
    image img = image_make(SIDE, SIDE), se = image_make(SIDE, SIDE);
    render_job job = {.cam = &s->cam, .spp = PT_SPP, .seed = seed, .threads = 1, .quiet = true,
                      .radiance = path_trace_radiance, .scene = &s->pt, .standard_error = &se, .jitter = true};
    render_stats stats;
    render_image(&job, &img, &stats);
    double total = 0.0, total_variance = 0.0;
    for (int i = 0; i < SIDE * SIDE; i++) {
        mean[i] = vec3_luminance(vec3_make(img.rgb[3 * i], img.rgb[3 * i + 1], img.rgb[3 * i + 2]));
        /* The channels of one pixel come from the same paths: the luminance's
         * standard error is at most the weighted sum of the channels'. */
        standard_error[i] = 0.2126 * se.rgb[3 * i] + 0.7152 * se.rgb[3 * i + 1] + 0.0722 * se.rgb[3 * i + 2];
        total += mean[i];
        total_variance += standard_error[i] * standard_error[i];
    }
    *image_mean = total / (SIDE * SIDE);
    *image_mean_se = sqrt(total_variance) / (SIDE * SIDE);
    image_free(&img);
    image_free(&se);
}

/* Pixels further apart than 5 standard errors in quadrature. With 16
 * replicas the studentized difference has heavier tails than a normal one
 * (Student's t with 15 degrees of freedom: P(|t| > 5) = 1.6e-4, so about
 * 0.04 of 256 pixels); a few pixels are allowed. */
static const int ALLOWED_DISAGREEMENTS = 3;

static int count_disagreements(const mlt_replicas *m, const double *pt_mean, const double *pt_se)
{
    int bad = 0;
    for (int i = 0; i < SIDE * SIDE; i++) {
        double tolerance = STANDARD_ERRORS * sqrt(m->standard_error[i] * m->standard_error[i] + pt_se[i] * pt_se[i]);
        if (fabs(m->mean[i] - pt_mean[i]) > fmax(tolerance, 1e-6))
            bad++;
    }
    return bad;
}

typedef struct {
    int disagreements;
    double b, b_standard_error, image_mean, image_mean_se;
} comparison;

static comparison compare_with_path_tracer(mlt_acceptance_fn acceptance, bool unnormalized)
{
    setup s;
    setup_cornell(&s);
    static mlt_replicas m;
    static double pt_mean[SIDE * SIDE], pt_se[SIDE * SIDE];
    comparison c;
    render_replicas(&s, acceptance, unnormalized, test_seed(1210), &m);
    render_path_traced(&s, test_seed(1211), pt_mean, pt_se, &c.image_mean, &c.image_mean_se);
    c.disagreements = count_disagreements(&m, pt_mean, pt_se);
    c.b = m.b_mean;
    c.b_standard_error = m.b_standard_error;
    print_message("MLT vs path tracing: %d of %d pixels beyond %.0f standard errors; b %.5f +- %.5f, path-traced "
                  "image mean %.5f +- %.5f\n", c.disagreements, SIDE * SIDE, STANDARD_ERRORS, c.b, c.b_standard_error, c.image_mean,
                  c.image_mean_se);
    pt_scene_free(&s.scene);
    return c;
}

static void test_converges_to_path_traced_image(void **state)
{
    (void)state;
    exercise_checks("mlt_acceptance");
    exercise_checks("mlt_small_step");
    comparison c = compare_with_path_tracer(NULL, false);
    if (!(c.disagreements <= ALLOWED_DISAGREEMENTS)) {
        print_error("MLT's image is not chapter 09's: %d of %d pixels differ by more than %.0f standard errors, "
                    "expected at most %d\n", c.disagreements, SIDE * SIDE, STANDARD_ERRORS, ALLOWED_DISAGREEMENTS);
        fail();
    }
    /* b estimates the image's mean luminance (the integral of f over the
     * film and all paths), as does the path tracer's image mean. */
    assert_true(fabs(c.b - c.image_mean) <
                STANDARD_ERRORS * sqrt(c.b_standard_error * c.b_standard_error + c.image_mean_se * c.image_mean_se));
}

/* Twin: accept every proposal (the chain then samples uniformly, but the
 * splats are still weighted 1 / f): dark pixels come out too bright. */
static void test_twin_accept_all_fails(void **state)
{
    (void)state;
    comparison c = compare_with_path_tracer(always_accept, false);
    assert_true(c.disagreements > ALLOWED_DISAGREEMENTS);
}

/* Twin: forget the normalization b (scale by 1 instead). */
static void test_twin_without_normalization_fails(void **state)
{
    (void)state;
    comparison c = compare_with_path_tracer(NULL, true);
    assert_true(c.disagreements > ALLOWED_DISAGREEMENTS);
}

/* ---- start-up bias ------------------------------------------------------------------
 * Many chains of one mutation each: the image is little more than the
 * chains' starting states. Started from bootstrap paths picked in
 * proportion to f they are (nearly) samples of f / b; all started at one
 * fixed path they pile onto its pixel. The mean squared error against the
 * path tracer over K runs each, compared by Welch's difference of means in
 * its standard errors. */
enum { STARTUP_RUNS = 8 };

static void startup_errors(const setup *s, const double *pt_mean, mlt_start start, uint64_t seed, double *mean,
                           double *standard_error)
{
    double sum = 0.0, sum2 = 0.0;
    for (int k = 0; k < STARTUP_RUNS; k++) {
        mlt_options o = mlt_defaults(&s->pt, &s->cam);
        o.mutations_per_pixel = 1;
        o.chains = SIDE * SIDE; /* one mutation per chain */
        o.bootstrap = 4096;
        o.seed = seed + (uint64_t)k * 104729u;
        o.threads = 1;
        o.start = start;
        double luminance[SIDE * SIDE], mse = 0.0;
        render_luminance(&o, luminance);
        for (int i = 0; i < SIDE * SIDE; i++)
            mse += (luminance[i] - pt_mean[i]) * (luminance[i] - pt_mean[i]) / (SIDE * SIDE);
        sum += mse;
        sum2 += mse * mse;
    }
    mean_and_standard_error(sum, sum2, STARTUP_RUNS, mean, standard_error);
}

/* Is the error of `worse` larger than that of `better` by more than 5
 * standard errors of the difference? */
static bool startup_error_larger(mlt_start worse, mlt_start better)
{
    setup s;
    setup_cornell(&s);
    static double pt_mean[SIDE * SIDE], pt_se[SIDE * SIDE];
    double image_mean, image_mean_se, mean_worse, se_worse, mean_better, se_better;
    render_path_traced(&s, test_seed(1220), pt_mean, pt_se, &image_mean, &image_mean_se);
    startup_errors(&s, pt_mean, worse, test_seed(1221), &mean_worse, &se_worse);
    startup_errors(&s, pt_mean, better, test_seed(1222), &mean_better, &se_better);
    print_message("short runs: MSE %.4g +- %.2g against %.4g +- %.2g\n", mean_worse, se_worse, mean_better,
                  se_better);
    pt_scene_free(&s.scene);
    return mean_worse - mean_better > STANDARD_ERRORS * sqrt(se_worse * se_worse + se_better * se_better);
}

static void test_fixed_start_has_start_up_bias(void **state)
{
    (void)state;
    assert_true(startup_error_larger(MLT_START_FIXED, MLT_START_BOOTSTRAP));
}

/* Twin: the same comparison between two sets of bootstrap-started runs
 * finds no difference (the check is not passed by any two sets of runs). */
static void test_twin_startup_check_on_equal_starts_fails(void **state)
{
    (void)state;
    assert_false(startup_error_larger(MLT_START_BOOTSTRAP, MLT_START_BOOTSTRAP));
}

/* ---- the same image for any thread count ------------------------------------------- */

static void test_same_image_for_one_and_two_threads(void **state)
{
    (void)state;
    setup s;
    setup_cornell(&s);
    image a = image_make(SIDE, SIDE), b = image_make(SIDE, SIDE);
    mlt_result ra, rb;
    mlt_options o = mlt_defaults(&s.pt, &s.cam);
    o.mutations_per_pixel = 16;
    o.bootstrap = 4096;
    o.chains = 8;
    o.seed = 3;
    o.threads = 1;
    assert_true(mlt_render(&o, &a, &ra));
    o.threads = 2;
    assert_true(mlt_render(&o, &b, &rb));
    assert_memory_equal(a.rgb, b.rgb, sizeof(float) * 3 * SIDE * SIDE);
    assert_true(ra.b == rb.b && ra.accepted == rb.accepted);
    image_free(&a);
    image_free(&b);
    pt_scene_free(&s.scene);
}

/* ---- the three methods of the comparison agree ------------------------------------
 * Comparing the errors of path tracing, BDPT and MLT means something only
 * if all three converge to the same image: each is unbiased, so their
 * images of one scene differ only by noise. Here: chapter 11's ceiling
 * lamp (where the three differ most in noise) at 8 x 8, each image cut
 * into 2 x 2 blocks of mean luminance, each method run K times with
 * its own seeds (the spread of the replicas gives the standard error for
 * all three alike: BDPT's splats and MLT's chains have no per-pixel one).
 * Every pair of methods must agree in every block within 5 standard
 * errors in quadrature. With K = 32 the studentized difference is about
 * Student's t with 31 degrees of freedom or more: P(|t| > 5) < 2.1e-5, so
 * over 3 pairs x 4 blocks a false alarm is under 3e-4. */
enum { AGREE_SIDE = 8, AGREE_BLOCK = AGREE_SIDE / 2, AGREE_BLOCKS = 4, AGREE_REPLICAS = 32 };
/* Samples per pixel of each method: about equal time, and every block
 * lit well enough to have a spread. */
static const int AGREE_SAMPLES[MLT_METHOD_COUNT] = {256, 64, 128};

typedef struct {
    double mean[AGREE_BLOCKS], standard_error[AGREE_BLOCKS];
} block_estimate;

/* K renders by one method (bidirectional with `fault` if not NONE) into
 * block means and their standard errors. */
static void render_blocks(mlt_method method, bdpt_fault fault, const pt_scene *sc, const camera *cam, uint64_t seed,
                          block_estimate *out)
{
    double sum[AGREE_BLOCKS] = {0}, sum2[AGREE_BLOCKS] = {0};
    for (int k = 0; k < AGREE_REPLICAS; k++) {
        uint64_t replica_seed = seed + 7919u * (uint64_t)k;
        image img;
        if (method == MLT_METHOD_BIDIRECTIONAL && fault != BDPT_FAULT_NONE) {
            bdpt b = bdpt_defaults(sc, cam);
            b.fault = fault;
            estimate_image e;
            assert_true(bdpt_render(&b, AGREE_SAMPLES[method], replica_seed, 1, true, &e));
            img = e.mean;
            image_free(&e.standard_error);
        } else {
            assert_true(mlt_method_render(method, sc, cam, AGREE_SAMPLES[method], replica_seed, 1, &img));
        }
        double block[AGREE_BLOCKS] = {0};
        for (int y = 0; y < AGREE_SIDE; y++)
            for (int x = 0; x < AGREE_SIDE; x++) {
                const float *p = &img.rgb[3 * (y * AGREE_SIDE + x)];
                block[(y / AGREE_BLOCK) * 2 + x / AGREE_BLOCK] +=
                    vec3_luminance(vec3_make(p[0], p[1], p[2])) / (AGREE_BLOCK * AGREE_BLOCK);
            }
        for (int i = 0; i < AGREE_BLOCKS; i++) {
            sum[i] += block[i];
            sum2[i] += block[i] * block[i];
        }
        image_free(&img);
    }
    for (int i = 0; i < AGREE_BLOCKS; i++)
        mean_and_standard_error(sum[i], sum2[i], AGREE_REPLICAS, &out->mean[i], &out->standard_error[i]);
}

/* The number of (pair of methods, block) further apart than 5 standard
 * errors, BDPT run with `fault`. */
static int count_method_disagreements(bdpt_fault fault)
{
    pt_scene sc;
    bdpt_scene_build_ceiling_lamp(&sc);
    camera cam = pt_scene_camera(&sc, AGREE_SIDE, AGREE_SIDE);
    block_estimate e[MLT_METHOD_COUNT];
    for (int m = 0; m < MLT_METHOD_COUNT; m++)
        render_blocks((mlt_method)m, fault, &sc, &cam, test_seed(1230) + 1000003u * (uint64_t)m, &e[m]);
    int disagreements = 0;
    for (int a = 0; a < MLT_METHOD_COUNT; a++)
        for (int b = a + 1; b < MLT_METHOD_COUNT; b++)
            for (int i = 0; i < AGREE_BLOCKS; i++) {
                double d = e[a].mean[i] - e[b].mean[i];
                double se = sqrt(e[a].standard_error[i] * e[a].standard_error[i] +
                                 e[b].standard_error[i] * e[b].standard_error[i]);
                print_message("block %d: %s %.4f +- %.4f, %s %.4f +- %.4f: %.1f standard errors\n", i,
                              mlt_method_names[a], e[a].mean[i], e[a].standard_error[i], mlt_method_names[b],
                              e[b].mean[i], e[b].standard_error[i], fabs(d) / se);
                if (fabs(d) > STANDARD_ERRORS * se)
                    disagreements++;
            }
    pt_scene_free(&sc);
    return disagreements;
}

static void test_three_methods_make_the_same_image(void **state)
{
    (void)state;
    assert_int_equal(count_method_disagreements(BDPT_FAULT_NONE), 0);
}

/* Twin: BDPT leaving out the cosine at the light vertex when it joins a
 * camera vertex to a light sample (s = 1) is biased; the check sees it. */
static void test_twin_biased_bidirectional_disagrees(void **state)
{
    (void)state;
    assert_true(count_method_disagreements(BDPT_FAULT_NO_LIGHT_COSINE) > 0);
}

/* The shipped scene file is the built-in scene: the same triangles, bit for
 * bit, materials, lights and camera (tests/pt_scene_check.h), so every
 * render of it is the built-in scene's. */
static void test_scene_file_is_the_built_in_scene(void **state)
{
    (void)state;
    pt_scene from_file, built_in;
    load_pt_scene_file(&from_file, "chapters/12-metropolis/scenes/lamp.scene");
    mlt_scene_build_lamp(&built_in);
    assert_same_pt_scene(&from_file, &built_in);
    pt_scene_free(&from_file);
    pt_scene_free(&built_in);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_scene_file_is_the_built_in_scene),
        cmocka_unit_test(test_small_step_wraps),
        cmocka_unit_test(test_small_step_is_kelemens_kernel),
        cmocka_unit_test(test_chain_samples_f_over_b),
        cmocka_unit_test(test_twin_chain_without_acceptance_ratio_fails),
        cmocka_unit_test(test_converges_to_path_traced_image),
        cmocka_unit_test(test_twin_accept_all_fails),
        cmocka_unit_test(test_twin_without_normalization_fails),
        cmocka_unit_test(test_fixed_start_has_start_up_bias),
        cmocka_unit_test(test_twin_startup_check_on_equal_starts_fails),
        cmocka_unit_test(test_same_image_for_one_and_two_threads),
        cmocka_unit_test(test_three_methods_make_the_same_image),
        cmocka_unit_test(test_twin_biased_bidirectional_disagrees),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
