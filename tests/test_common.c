/* test_common.c -- the shared core: RNG, statistics, camera, ray offsets,
 * the render loop and the command line. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "camera.h"
#include "cli.h"
#include "counters.h"
#include "counters_file.h"
#include "image.h"
#include "program.h"
#include "progressive.h"
#include "ray.h"
#include "render.h"
#include "rng.h"
#include "splat_film.h"
#include "stats.h"
#include "run_record.h"
#include "test_support.h"

/* ---- PCG32 ---------------------------------------------------------------- */

/* The reference implementation (pcg-c-basic's pcg32-demo) seeded with
 * initstate 42, initseq 54 prints these six numbers first. */
static void test_pcg32_matches_reference_output(void **state)
{
    (void)state;
    pcg32 rng;
    pcg32_seed(&rng, 42u, 54u);
    assert_int_equal(rng.state, 1753877967969059832ULL);
    assert_int_equal(rng.increment, 109u);
    const uint32_t expected[6] = {0xa15c02b7u, 0x7b47f409u, 0xba1d3330u, 0x83d2f293u, 0xbfa4784bu, 0xcbed606eu};
    for (int i = 0; i < 6; i++)
        assert_int_equal(pcg32_next(&rng), expected[i]);
}

static void test_pcg32_float_is_in_unit_interval_and_uniform(void **state)
{
    (void)state;
    pcg32 rng = pcg32_for_pixel(test_seed(7), 0);
    enum { N = 100000, BINS = 10 };
    int count[BINS] = {0};
    for (int i = 0; i < N; i++) {
        float u = pcg32_float(&rng);
        assert_true(u >= 0.0f && u < 1.0f);
        count[(int)(u * BINS)]++;
    }
    /* Pearson chi-square with 9 degrees of freedom: P(chi2 > 33.7) ~ 1e-4. */
    double chi2 = 0;
    for (int b = 0; b < BINS; b++) {
        double expected = (double)N / BINS;
        chi2 += (count[b] - expected) * (count[b] - expected) / expected;
    }
    assert_true(chi2 < 33.7);
}

static void test_pcg32_pixel_streams_differ(void **state)
{
    (void)state;
    /* Neighbouring pixels must not see the same numbers, or noise would be
     * correlated across the image. */
    pcg32 a = pcg32_for_pixel(1, 100), b = pcg32_for_pixel(1, 101), c = pcg32_for_pixel(2, 100);
    int same_ab = 0, same_ac = 0;
    for (int i = 0; i < 64; i++) {
        uint32_t x = pcg32_next(&a), y = pcg32_next(&b), z = pcg32_next(&c);
        same_ab += x == y;
        same_ac += x == z;
    }
    assert_int_equal(same_ab, 0);
    assert_int_equal(same_ac, 0);
    /* ... and the same (seed, pixel) gives the same stream. */
    pcg32 d = pcg32_for_pixel(1, 100), e = pcg32_for_pixel(1, 100);
    for (int i = 0; i < 16; i++)
        assert_int_equal(pcg32_next(&d), pcg32_next(&e));
}

static void test_pcg32_bounded_stays_in_range(void **state)
{
    (void)state;
    pcg32 rng = pcg32_for_pixel(test_seed(3), 3);
    int seen[7] = {0};
    for (int i = 0; i < 7000; i++) {
        uint32_t k = pcg32_bounded(&rng, 7);
        assert_true(k < 7);
        seen[k]++;
    }
    for (int k = 0; k < 7; k++)
        assert_true(seen[k] > 800 && seen[k] < 1200); /* 1000 +- 6.4 sigma */
}

/* ---- statistics ----------------------------------------------------------- */

static void test_welford_matches_two_pass_formula(void **state)
{
    (void)state;
    const double data[] = {2, 4, 4, 4, 5, 5, 7, 9};
    welford w = {0};
    for (int i = 0; i < 8; i++)
        welford_add(&w, data[i]);
    assert_close(welford_mean(&w), 5.0, 1e-12);
    /* sum of squared deviations 32, over n - 1 = 7 */
    assert_close(welford_variance(&w), 32.0 / 7.0, 1e-12);
    assert_close(welford_standard_error(&w), sqrt(32.0 / 7.0 / 8.0), 1e-12);
}

static void test_welford_is_stable_with_a_large_offset(void **state)
{
    (void)state;
    /* The textbook E[x^2] - E[x]^2 loses every digit here: x^2 ~ 1e18 while
     * the variance is 1. */
    welford w = {0};
    for (int i = 0; i < 1000; i++)
        welford_add(&w, 1e9 + (i % 2 ? 1.0 : -1.0));
    assert_close(welford_variance(&w), 1000.0 / 999.0, 1e-6);
}

static void test_welford_merge_equals_one_pass(void **state)
{
    (void)state;
    welford all = {0}, a = {0}, b = {0};
    pcg32 rng = pcg32_for_pixel(5, 5);
    for (int i = 0; i < 1000; i++) {
        double x = pcg32_double(&rng) * 10.0;
        welford_add(&all, x);
        welford_add(i < 300 ? &a : &b, x);
    }
    welford_merge(&a, &b);
    assert_int_equal(a.count, all.count);
    assert_close(a.mean, all.mean, 1e-12);
    assert_close(welford_variance(&a), welford_variance(&all), 1e-10);
}

static void test_loglog_slope_recovers_power_law(void **state)
{
    (void)state;
    double x[6], y[6];
    for (int i = 0; i < 6; i++) {
        x[i] = pow(2.0, i);
        y[i] = 3.0 / x[i];
    }
    assert_close(stats_loglog_slope(x, y, 6), -1.0, 1e-12);
    for (int i = 0; i < 6; i++)
        y[i] = 0.5 * pow(x[i], -0.5);
    assert_close(stats_loglog_slope(x, y, 6), -0.5, 1e-12);
}

/* ---- camera --------------------------------------------------------------- */

static void test_camera_centre_ray_looks_at_target(void **state)
{
    (void)state;
    camera cam = camera_look_at(vec3_make(1, 2, 3), vec3_make(1, 2, -7), vec3_make(0, 1, 0), 60.0f, 200, 100);
    ray r = camera_ray(&cam, 100.0f, 50.0f);
    assert_float_equal(r.direction.x, 0.0f, 1e-6);
    assert_float_equal(r.direction.y, 0.0f, 1e-6);
    assert_float_equal(r.direction.z, -1.0f, 1e-6);
    assert_float_equal(r.origin.y, 2.0f, 0.0f);
}

static void test_camera_edges_span_the_field_of_view(void **state)
{
    (void)state;
    const float fov = 60.0f;
    camera cam = camera_look_at(vec3_make(0, 0, 0), vec3_make(0, 0, -1), vec3_make(0, 1, 0), fov, 200, 100);
    /* Top edge, centre column: the ray is fov/2 above the axis, and up is +y. */
    ray top = camera_ray(&cam, 100.0f, 0.0f);
    float angle = atan2f(top.direction.y, -top.direction.z) * 180.0f / (float)PI;
    assert_float_equal(angle, fov / 2, 1e-4);
    /* Right edge: tan of the horizontal half-angle is aspect * tan(fov/2). */
    ray right = camera_ray(&cam, 200.0f, 50.0f);
    assert_float_equal(right.direction.x / -right.direction.z, 2.0f * tanf(fov / 2 * (float)PI / 180.0f), 1e-5);
    assert_float_equal(vec3_length(right.direction), 1.0f, 1e-6);
}

/* ---- leaving a surface ---------------------------------------------------- */

static void test_offset_origin_moves_to_the_normal_side_at_every_scale(void **state)
{
    (void)state;
    /* Points of an object of size `scale` placed up to 1e5 from the origin
     * (where it is still many float steps across), random unit normals. */
    const float scales[] = {1e-7f, 1e-4f, 1.0f, 1e2f, 1e4f, 1e6f};
    const float places[] = {0.0f, 1.0f, 1e3f, 1e5f};
    pcg32 rng = pcg32_for_pixel(11, 0);
    for (int s = 0; s < 6; s++) {
        for (int w = 0; w < 4; w++) {
            vec3 centre = vec3_splat(places[w]);
            if (ray_too_small_for_position(scales[s], places[w] + scales[s]))
                continue;
            for (int i = 0; i < 1000; i++) {
                vec3 p = vec3_add(centre, vec3_scale(vec3_make(pcg32_float(&rng) * 2 - 1, pcg32_float(&rng) * 2 - 1,
                                                               pcg32_float(&rng) * 2 - 1), scales[s]));
                vec3 n = vec3_normalize(vec3_make(pcg32_float(&rng) - 0.5f, pcg32_float(&rng) - 0.5f,
                                                  pcg32_float(&rng) - 0.5f));
                float error = ray_point_error(p, n, scales[s]);
                vec3 q = ray_offset_origin(p, error, n);
                /* Strictly on the side n points to, by at least half the
                 * bound (the origin's own rounding takes at most one of the
                 * 2 roundings of the coordinates it holds), in double. */
                double moved = ((double)q.x - p.x) * n.x + ((double)q.y - p.y) * n.y + ((double)q.z - p.z) * n.z;
                assert_true(moved > 0.0);
                assert_true(moved >= 0.5 * error);
                /* ... and by little: the bound is 2 roundings of the
                 * coordinates (at most 2 sqrt(3) u |p|, 2.1e-7 |p|) and 64
                 * of the size (3.8e-6 of it). */
                assert_true(error < 4e-6f * scales[s] + 2.1e-7f * vec3_max_component(vec3_abs(p)));
            }
        }
    }
    /* The small object: 1e-4 across, near 0. The offset once was a
     * fixed 2^-16 there, 15 % of the object; now it is 4e-10 or less. */
    vec3 p = vec3_make(3e-5f, -2e-5f, 1e-5f), n = vec3_make(0, 0, 1);
    assert_true(ray_point_error(p, n, 1e-4f) < 4e-10f);
}

static void test_spawn_offsets_towards_the_direction(void **state)
{
    (void)state;
    vec3 p = vec3_make(3.0f, 0.0f, 0.0f), n = vec3_make(1, 0, 0);
    float error = ray_point_error(p, n, 1.0f);
    ray out = ray_spawn(p, error, n, vec3_make(1, 1, 0));
    ray in = ray_spawn(p, error, n, vec3_make(-1, 1, 0));
    assert_true(out.origin.x > 3.0f);
    assert_true(in.origin.x < 3.0f);
    ray to = ray_spawn_to(p, error, n, vec3_make(10, 0, 0), 0.0f, vec3_splat(0.0f));
    assert_float_equal(to.t_max, 1.0f, 0.0f);
    vec3 end = ray_at(to, 1.0f);
    assert_float_equal(end.x, 10.0f, 1e-5);
    /* A target on a surface facing the origin: the far end is pulled back
     * towards the origin by its error bound and 64 roundings of the
     * segment's length. */
    ray to_wall = ray_spawn_to(p, error, n, vec3_make(10, 0, 0), 1e-4f, vec3_make(1, 0, 0));
    float pulled = 10.0f - ray_at(to_wall, 1.0f).x;
    assert_close(pulled, 1e-4 + 64.0 * 0x1.0p-24 * 7.0, 1e-6);
}

/* ---- render loop ---------------------------------------------------------- */

/* A radiance function that uses the random stream and the ray: if pixels
 * shared a generator, or a sample depended on thread order, images would
 * differ between runs. */
static vec3 noisy_radiance(const void *scene, ray r, pcg32 *rng, ray_counters *counters)
{
    (void)scene;
    counters->shadow_rays++;
    float u = pcg32_float(rng);
    return vec3_make(u, fabsf(r.direction.x) + u * u, fabsf(r.direction.y));
}

static image render_noisy(int threads, int spp, ray_counters *counters)
{
    camera cam = camera_look_at(vec3_make(0, 0, 0), vec3_make(0, 0, -1), vec3_make(0, 1, 0), 50.0f, 37, 23);
    render_job job = {.cam = &cam, .spp = spp, .seed = 99, .threads = threads, .quiet = true,
                      .radiance = noisy_radiance};
    image img = image_make(37, 23);
    render_stats stats;
    render_image(&job, &img, &stats);
    if (counters)
        *counters = stats.counters;
    return img;
}

static void test_render_is_bit_identical_for_any_thread_count(void **state)
{
    (void)state;
    image one = render_noisy(1, 4, NULL), two = render_noisy(2, 4, NULL), three = render_noisy(3, 4, NULL);
    size_t bytes = 37 * 23 * 3 * sizeof(float);
    assert_memory_equal(one.rgb, two.rgb, bytes);
    assert_memory_equal(one.rgb, three.rgb, bytes);
    image_free(&one);
    image_free(&two);
    image_free(&three);
}

static void test_render_counts_every_camera_ray(void **state)
{
    (void)state;
    ray_counters c;
    image img = render_noisy(2, 3, &c);
    assert_int_equal(c.camera_rays, 37 * 23 * 3);
    assert_int_equal(c.shadow_rays, 37 * 23 * 3); /* per-thread counters were all added */
    image_free(&img);
}

/* The pilot before a long render (common/program/program.c): 64 pixels at the
 * full spp on an 8 x 8 grid over the whole image, none for small images. */
static int pilot_calls;
static float pilot_left, pilot_right, pilot_top, pilot_bottom;

static vec3 pilot_counting_radiance(const void *scene, ray r, pcg32 *rng, ray_counters *counters)
{
    (void)scene;
    (void)rng;
    (void)counters;
    pilot_calls++;
    pilot_left = fminf(pilot_left, r.direction.x / -r.direction.z);
    pilot_right = fmaxf(pilot_right, r.direction.x / -r.direction.z);
    pilot_bottom = fminf(pilot_bottom, r.direction.y / -r.direction.z);
    pilot_top = fmaxf(pilot_top, r.direction.y / -r.direction.z);
    return vec3_splat(1.0f);
}

static void test_pilot_samples_the_whole_image_at_full_spp(void **state)
{
    (void)state;
    /* 90 degrees: the image plane at z = -1 spans -1..1 both ways. */
    camera big = camera_look_at(vec3_make(0, 0, 0), vec3_make(0, 0, -1), vec3_make(0, 1, 0), 90.0f, 256, 256);
    render_job job = {.cam = &big, .spp = 5, .seed = 1, .threads = 1, .quiet = true,
                      .radiance = pilot_counting_radiance};
    pilot_calls = 0;
    pilot_left = pilot_bottom = 1e9f;
    pilot_right = pilot_top = -1e9f;
    assert_true(program_pilot_seconds(&job) >= 0.0);
    assert_int_equal(pilot_calls, 64 * 5);
    /* The grid's outer cells are centred 1/16 of the image in from each
     * edge: 7/8 of the way out from the middle. */
    assert_float_equal(pilot_left, -0.875f, 0.01f);
    assert_float_equal(pilot_right, 0.875f, 0.01f);
    assert_float_equal(pilot_bottom, -0.875f, 0.01f);
    assert_float_equal(pilot_top, 0.875f, 0.01f);
    camera small = camera_look_at(vec3_make(0, 0, 0), vec3_make(0, 0, -1), vec3_make(0, 1, 0), 90.0f, 127, 128);
    job.cam = &small;
    pilot_calls = 0;
    assert_true(program_pilot_seconds(&job) == 0.0);
    assert_int_equal(pilot_calls, 0);
}

static vec3 sometimes_nan_radiance(const void *scene, ray r, pcg32 *rng, ray_counters *counters)
{
    (void)scene;
    (void)r;
    (void)counters;
    return pcg32_float(rng) < 0.25f ? vec3_make(NAN, 0, INFINITY) : vec3_splat(2.0f);
}

static void test_render_drops_and_counts_nan_samples(void **state)
{
    (void)state;
    camera cam = camera_look_at(vec3_make(0, 0, 0), vec3_make(0, 0, -1), vec3_make(0, 1, 0), 50.0f, 8, 8);
    render_job job = {.cam = &cam, .spp = 16, .seed = 1, .threads = 2, .quiet = true,
                      .radiance = sometimes_nan_radiance};
    image img = image_make(8, 8);
    render_stats stats;
    render_image(&job, &img, &stats);
    assert_true(stats.counters.nonfinite_samples > 0);
    for (int i = 0; i < 8 * 8 * 3; i++)
        assert_float_equal(img.rgb[i], 2.0f, 0.0f); /* the mean of the finite samples */
    image_free(&img);
}

static vec3 direction_radiance(const void *scene, ray r, pcg32 *rng, ray_counters *counters)
{
    (void)scene;
    (void)rng;
    (void)counters;
    return r.direction;
}

static void test_one_sample_goes_through_the_pixel_centre(void **state)
{
    (void)state;
    camera cam = camera_look_at(vec3_make(0, 0, 0), vec3_make(0, 0, -1), vec3_make(0, 1, 0), 50.0f, 10, 6);
    render_job job = {.cam = &cam, .spp = 1, .seed = 1, .threads = 1, .quiet = true,
                      .radiance = direction_radiance};
    ray_counters c = {0};
    vec3 d = render_pixel(&job, 3, 4, &c, NULL);
    vec3 expected = camera_ray(&cam, 3.5f, 4.5f).direction;
    assert_float_equal(d.x, expected.x, 0.0f);
    assert_float_equal(d.y, expected.y, 0.0f);
}

/* ---- estimates and progressive rendering --------------------------------- */

static vec3 constant_radiance(const void *scene, ray r, pcg32 *rng, ray_counters *counters)
{
    (void)scene;
    (void)r;
    (void)rng;
    (void)counters;
    return vec3_splat(0.5f);
}

/* Without noise there is no error to wait for: the render stops at the
 * first pass whose variance is trusted (16 samples per pixel). */
static void test_progressive_stops_at_once_without_noise(void **state)
{
    (void)state;
    camera cam = camera_look_at(vec3_make(0, 0, 0), vec3_make(0, 0, -1), vec3_make(0, 1, 0), 50.0f, 9, 7);
    estimate_image e = progressive_render(constant_radiance, NULL, &cam, 1, 2, 0.0, 1e-3, NULL);
    assert_int_equal(e.spp, 16);
    assert_float_equal(estimate_relative_error(&e), 0.0, 0.0);
    assert_float_equal(e.mean.rgb[0], 0.5f, 0.0f);
    estimate_image_free(&e);
}

/* Passes of 2, 2, 4, 8, ... samples until the error the variance predicts
 * is below the target; every pass's samples are counted. A noisy first
 * pass must not look converged (one sample per pixel has no variance). */
static void test_progressive_reaches_the_target_error(void **state)
{
    (void)state;
    camera cam = camera_look_at(vec3_make(0, 0, 0), vec3_make(0, 0, -1), vec3_make(0, 1, 0), 50.0f, 9, 7);
    estimate_image two = estimate_render(noisy_radiance, NULL, &cam, 2, 5, 2);
    double start_error = estimate_relative_error(&two);
    estimate_image_free(&two);
    assert_true(start_error > 0.05);
    double target = start_error / 4.0; /* about 16 times the samples */
    estimate_image e = progressive_render(noisy_radiance, NULL, &cam, 5, 2, 0.0, target, NULL);
    assert_true(estimate_relative_error(&e) <= target);
    assert_true(e.spp >= 16 && (e.spp & (e.spp - 1)) == 0);
    assert_int_equal(e.counters.camera_rays, (uint64_t)(9 * 7) * (uint64_t)e.spp);
    estimate_image_free(&e);
}

/* ---- command line --------------------------------------------------------- */

static cli_status parse(int argc, char **argv, cli_options *opts, char *err)
{
    static int max_depth = 5;
    static const cli_flag extras[] = {{"--max-depth", CLI_INT, &max_depth, "N", "recursion limit", 0, 64}};
    cli_spec spec = {"test", "a test", extras, 1, "the path of a pixel"};
    *opts = cli_defaults("/tmp/out.exr", 64, 32, 1);
    return cli_parse(argc, argv, &spec, opts, err, 512);
}

static void test_cli_reads_every_shared_flag(void **state)
{
    (void)state;
    char err[512];
    cli_options o;
    char *argv[] = {"p", "--width", "320", "--height=200", "--spp", "16", "--seed", "12345", "--threads", "2",
                    "--out", "/tmp/x.png", "--exposure", "-1.5", "--quiet", NULL};
    assert_int_equal(parse(15, argv, &o, err), CLI_OK);
    assert_int_equal(o.width, 320);
    assert_int_equal(o.height, 200);
    assert_int_equal(o.spp, 16);
    assert_int_equal(o.seed, 12345);
    assert_int_equal(o.threads, 2);
    assert_string_equal(o.out, "/tmp/x.png");
    assert_float_equal(o.exposure, -1.5f, 0.0f);
    assert_true(o.quiet);
}

static void expect_error(int argc, char **argv, const char *fragment)
{
    char err[512] = "";
    cli_options o;
    assert_int_equal(parse(argc, argv, &o, err), CLI_ERROR);
    if (strstr(err, fragment) == NULL)
        fail_msg("error '%s' does not mention '%s'", err, fragment);
}

static void test_cli_rejects_bad_flags_with_a_clear_message(void **state)
{
    (void)state;
    char *unknown[] = {"p", "--widht", "3"};
    expect_error(3, unknown, "unknown flag '--widht'");
    char *zero[] = {"p", "--width", "0"};
    expect_error(3, zero, "--width");
    char *negative[] = {"p", "--height", "-5"};
    expect_error(3, negative, "'-5'");
    char *junk[] = {"p", "--spp", "12abc"};
    expect_error(3, junk, "'12abc'");
    char *missing[] = {"p", "--spp"};
    expect_error(2, missing, "--spp needs a value");
    char *range[] = {"p", "--max-depth", "65"};
    expect_error(3, range, "--max-depth");
    char *no_dir[] = {"p", "--out", "/nonexistent-dir/x.exr"};
    expect_error(3, no_dir, "does not exist");
    char *suffix[] = {"p", "--out", "/tmp/x.jpg"};
    expect_error(3, suffix, ".exr or .png");
    char *file_as_dir[] = {"p", "--out", "/etc/passwd/x.exr"};
    expect_error(3, file_as_dir, "is not a directory");
    char *seed[] = {"p", "--seed", "-1"};
    expect_error(3, seed, "--seed");
}

static void test_cli_rejects_an_unwritable_directory(void **state)
{
    (void)state;
    if (geteuid() == 0)
        skip(); /* root may write anywhere */
    char *argv[] = {"p", "--out", "/proc/x.exr"};
    expect_error(3, argv, "not writable");
}

/* A float flag with no range has bounds -HUGE_VAL .. HUGE_VAL, which "inf"
 * meets: the parser must refuse non-finite values on their own, and NaN
 * (which compares false with everything) too. */
static void test_cli_rejects_nan_and_inf_for_an_unranged_float(void **state)
{
    (void)state;
    static float scale = 1.0f;
    static const cli_flag extras[] = {{"--scale", CLI_FLOAT, &scale, "X", "any finite number", 0, 0}};
    cli_spec spec = {"test", "a test", extras, 1, "the path of a pixel"};
    const char *bad[] = {"inf", "-inf", "infinity", "nan", "1e999", "0x1p2000", ""};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        char err[512] = "";
        cli_options o = cli_defaults("/tmp/out.exr", 64, 32, 1);
        char *argv[] = {"p", "--scale", (char *)bad[i]};
        assert_int_equal(cli_parse(3, argv, &spec, &o, err, sizeof err), CLI_ERROR);
        if (strstr(err, "--scale") == NULL)
            fail_msg("error '%s' does not name --scale", err);
    }
    char err[512] = "";
    cli_options o = cli_defaults("/tmp/out.exr", 64, 32, 1);
    char *argv[] = {"p", "--scale", "-1e30"};
    assert_int_equal(cli_parse(3, argv, &spec, &o, err, sizeof err), CLI_OK);
    assert_float_equal(scale, -1e30f, 0.0f);
}

/* A data directory is checked when the flags are read, not after the
 * experiment that fills it. */
static void test_cli_checks_a_directory_flag_at_once(void **state)
{
    (void)state;
    static const char *data = NULL;
    static const cli_flag extras[] = {{"--data", CLI_DIR, &data, "DIR", "where the CSV goes", 0, 0}};
    cli_spec spec = {"test", "a test", extras, 1, "the path of a pixel"};
    const char *bad[][2] = {{"/nonexistent-dir", "does not exist"}, {"/etc/passwd", "is not a directory"}, {"", "--data"}};
    for (int i = 0; i < 3; i++) {
        char err[512] = "";
        cli_options o = cli_defaults("/tmp/out.exr", 64, 32, 1);
        char *argv[] = {"p", "--data", (char *)bad[i][0]};
        assert_int_equal(cli_parse(3, argv, &spec, &o, err, sizeof err), CLI_ERROR);
        if (strstr(err, bad[i][1]) == NULL || strstr(err, "--data") == NULL)
            fail_msg("error '%s' does not say '%s' about --data", err, bad[i][1]);
    }
    char err[512] = "";
    cli_options o = cli_defaults("/tmp/out.exr", 64, 32, 1);
    char *argv[] = {"p", "--data", "/tmp"};
    assert_int_equal(cli_parse(3, argv, &spec, &o, err, sizeof err), CLI_OK);
    assert_string_equal(data, "/tmp");
}

static void test_cli_help_and_extras(void **state)
{
    (void)state;
    char err[512];
    cli_options o;
    char *help[] = {"p", "--help"};
    assert_int_equal(parse(2, help, &o, err), CLI_HELP);
    char *extra[] = {"p", "--max-depth", "9"};
    assert_int_equal(parse(3, extra, &o, err), CLI_OK);
}

/* ---- choice flags ---------------------------------------------------------- */

static const char *const RUNG_NAMES[] = {"lecture", "cosine", "mis", NULL};

static cli_status parse_choice(int argc, char **argv, cli_choice *choice, char *err, size_t err_size)
{
    const cli_flag extras[] = {{"--integrator", CLI_CHOICE, choice, NULL, "the rung", 0, 0}};
    cli_spec spec = {"test", "a test", extras, 1, "the path of a pixel"};
    cli_options o = cli_defaults("/tmp/out.exr", 64, 32, 1);
    return cli_parse(argc, argv, &spec, &o, err, err_size);
}

static void test_cli_choice_stores_the_index_of_the_name(void **state)
{
    (void)state;
    char err[512] = "";
    cli_choice rung = {RUNG_NAMES, NULL, 0};
    char *none[] = {"p"};
    assert_int_equal(parse_choice(1, none, &rung, err, sizeof err), CLI_OK);
    assert_int_equal(rung.index, 0); /* the default stays when the flag is not given */
    char *mis[] = {"p", "--integrator", "mis"};
    assert_int_equal(parse_choice(3, mis, &rung, err, sizeof err), CLI_OK);
    assert_int_equal(rung.index, 2);
    assert_string_equal(cli_choice_name(&rung), "mis");
    char *cosine[] = {"p", "--integrator=cosine"};
    assert_int_equal(parse_choice(2, cosine, &rung, err, sizeof err), CLI_OK);
    assert_int_equal(rung.index, 1);
    cli_choice unset = {RUNG_NAMES, NULL, -1};
    assert_null(cli_choice_name(&unset));
}

/* Every program's choice flags refuse a bad value with the same message,
 * naming the flag, the value and what it could have been. */
static void test_cli_choice_refuses_other_values_naming_the_choices(void **state)
{
    (void)state;
    const char *bad[] = {"fast", "", "MIS", "mis ", "lecture,mis"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        char err[512] = "", expected[512];
        cli_choice rung = {RUNG_NAMES, NULL, 0};
        char *argv[] = {"p", "--integrator", (char *)bad[i]};
        assert_int_equal(parse_choice(3, argv, &rung, err, sizeof err), CLI_ERROR);
        snprintf(expected, sizeof expected, "--integrator: unknown '%s' (lecture, cosine, mis)", bad[i]);
        assert_string_equal(err, expected);
        assert_int_equal(rung.index, 0);
    }
    /* A short err buffer gets a truncated message, never an overrun. */
    char small[20];
    cli_choice rung = {RUNG_NAMES, NULL, 0};
    char *argv[] = {"p", "--integrator", "fast"};
    assert_int_equal(parse_choice(3, argv, &rung, small, sizeof small), CLI_ERROR);
    assert_int_equal(strlen(small), sizeof small - 1);
}

/* cli_parse_or_exit: the message on stderr and exit status 2, as for any
 * bad flag. Run in a child, which exits. */
static void test_cli_choice_bad_value_exits_with_status_2(void **state)
{
    (void)state;
    int pipe_fds[2];
    assert_int_equal(pipe(pipe_fds), 0);
    fflush(stdout);
    fflush(stderr);
    pid_t child = fork();
    assert_true(child >= 0);
    if (child == 0) {
        dup2(pipe_fds[1], 2);
        cli_choice rung = {RUNG_NAMES, NULL, 0};
        const cli_flag extras[] = {{"--integrator", CLI_CHOICE, &rung, NULL, "the rung", 0, 0}};
        cli_spec spec = {"prog", "a test", extras, 1, "the path of a pixel"};
        cli_options o = cli_defaults("/tmp/out.exr", 64, 32, 1);
        char *argv[] = {"prog", "--integrator", "fast", NULL};
        cli_parse_or_exit(3, argv, &spec, &o);
        _exit(0);
    }
    close(pipe_fds[1]);
    char message[512] = "";
    ssize_t n = read(pipe_fds[0], message, sizeof message - 1);
    close(pipe_fds[0]);
    message[n > 0 ? n : 0] = '\0';
    int status = 0;
    assert_int_equal(waitpid(child, &status, 0), child);
    assert_true(WIFEXITED(status));
    assert_int_equal(WEXITSTATUS(status), 2);
    if (strstr(message, "prog: --integrator: unknown 'fast' (lecture, cosine, mis)\n") != message)
        fail_msg("stderr was '%s'", message);
}

/* What cli_print_help writes, caught from stdout. */
static void help_text(const cli_spec *spec, char *out, size_t size)
{
    cli_options d = cli_defaults("/tmp/out.exr", 64, 32, 1);
    FILE *caught = tmpfile();
    assert_non_null(caught);
    fflush(stdout);
    int saved = dup(1);
    dup2(fileno(caught), 1);
    cli_print_help(spec, &d);
    fflush(stdout);
    dup2(saved, 1);
    close(saved);
    rewind(caught);
    size_t n = fread(out, 1, size - 1, caught);
    out[n] = '\0';
    fclose(caught);
}

static void expect_in_help(const char *help, const char *line)
{
    if (strstr(help, line) == NULL)
        fail_msg("--help does not show '%s':\n%s", line, help);
}

/* --help lists the choices: as the value ("a|b|c"), with each name's note,
 * or after the help line when the flag has a metavar of its own. */
static void test_cli_choice_help_lists_the_choices(void **state)
{
    (void)state;
    static const char *const notes[] = {"uniform hemisphere", "cosine-weighted", "BSDF sampling and MIS"};
    cli_choice plain = {RUNG_NAMES, NULL, 0}, noted = {RUNG_NAMES, notes, 0}, named = {RUNG_NAMES, NULL, 0};
    const cli_flag extras[] = {
        {"--plain", CLI_CHOICE, &plain, NULL, "the rung", 0, 0},
        {"--noted", CLI_CHOICE, &noted, NULL, "the rung, noted", 0, 0},
        {"--named", CLI_CHOICE, &named, "RUNG", "the rung, named", 0, 0},
    };
    cli_spec spec = {"test", "a test", extras, 3, "the path of a pixel"};
    char help[8192];
    help_text(&spec, help, sizeof help);
    expect_in_help(help, "\n  --plain lecture|cosine|mis the rung\n");
    expect_in_help(help, "\n  --noted lecture|cosine|mis the rung, noted\n"
                         "                     lecture  uniform hemisphere\n"
                         "                     cosine   cosine-weighted\n"
                         "                     mis      BSDF sampling and MIS\n");
    expect_in_help(help, "\n  --named RUNG     the rung, named\n                   one of: lecture, cosine, mis\n");
}

/* ---- splat_film ---------------------------------------------------------- */

enum { SPLAT_SIDE = 8, SPLAT_COUNT = 200000 };

/* The k-th splat of a fixed random sequence: many land on the same pixel,
 * with values over six orders of magnitude, so float sums depend on order. */
static void splat_number(int k, float *x, float *y, vec3 *value)
{
    pcg32 rng = pcg32_for_pixel(test_seed(11), (uint64_t)k);
    *x = pcg32_float(&rng) * SPLAT_SIDE;
    *y = pcg32_float(&rng) * SPLAT_SIDE;
    float scale = powf(10.0f, 3.0f - 6.0f * pcg32_float(&rng));
    *value = vec3_make(scale * pcg32_float(&rng), scale * pcg32_float(&rng), scale * pcg32_float(&rng));
}

/* The same splats, added by 1 thread in order and by 2 threads in reverse
 * order, give the same film bit for bit; and the sum is the exact sum to
 * within the rounding of each splat (2^-25 each). */
static void test_splat_film_is_the_same_for_any_order_and_thread_count(void **state)
{
    (void)state;
    splat_film forward, backward;
    assert_true(splat_film_init(&forward, SPLAT_SIDE, SPLAT_SIDE));
    assert_true(splat_film_init(&backward, SPLAT_SIDE, SPLAT_SIDE));
    double exact[SPLAT_SIDE * SPLAT_SIDE] = {0};
    int count[SPLAT_SIDE * SPLAT_SIDE] = {0};
    for (int k = 0; k < SPLAT_COUNT; k++) {
        float x, y;
        vec3 v;
        splat_number(k, &x, &y, &v);
        splat_film_add(&forward, x, y, v, NULL);
        exact[(int)y * SPLAT_SIDE + (int)x] += v.x;
        count[(int)y * SPLAT_SIDE + (int)x]++;
    }
#pragma omp parallel for num_threads(2) schedule(dynamic, 64)
    for (int k = SPLAT_COUNT - 1; k >= 0; k--) {
        float x, y;
        vec3 v;
        splat_number(k, &x, &y, &v);
        splat_film_add(&backward, x, y, v, NULL);
    }
    assert_memory_equal(forward.sum, backward.sum, sizeof(int64_t) * SPLAT_SIDE * SPLAT_SIDE * 3);
    for (int p = 0; p < SPLAT_SIDE * SPLAT_SIDE; p++) {
        double got = (double)forward.sum[3 * p] / (double)(1LL << SPLAT_FILM_FRACTION_BITS);
        assert_true(fabs(got - exact[p]) <= count[p] * 0x1.0p-25 + 1e-9);
    }
    splat_film_free(&forward);
    splat_film_free(&backward);
}

/* Its twin: the same splats summed in float, forward and backward, do not
 * agree: the film's fixed point is what makes the order not matter. */
static void test_splat_float_sums_depend_on_order(void **state)
{
    (void)state;
    float forward[SPLAT_SIDE * SPLAT_SIDE] = {0}, backward[SPLAT_SIDE * SPLAT_SIDE] = {0};
    for (int k = 0; k < SPLAT_COUNT; k++) {
        float x, y;
        vec3 v;
        splat_number(k, &x, &y, &v);
        forward[(int)y * SPLAT_SIDE + (int)x] += v.x;
    }
    for (int k = SPLAT_COUNT - 1; k >= 0; k--) {
        float x, y;
        vec3 v;
        splat_number(k, &x, &y, &v);
        backward[(int)y * SPLAT_SIDE + (int)x] += v.x;
    }
    assert_true(memcmp(forward, backward, sizeof forward) != 0);
}

/* NaN, Inf and values too large for the sums are dropped and counted;
 * points off the film are ignored. */
static void test_splat_film_drops_nonfinite_and_ignores_points_outside(void **state)
{
    (void)state;
    splat_film film;
    assert_true(splat_film_init(&film, 2, 2));
    ray_counters counters = {0};
    splat_film_add(&film, 0.5f, 0.5f, vec3_make(NAN, 0.0f, 0.0f), &counters);
    splat_film_add(&film, 0.5f, 0.5f, vec3_make(0.0f, INFINITY, 0.0f), &counters);
    splat_film_add(&film, 0.5f, 0.5f, vec3_make(0.0f, 0.0f, 2.0f * SPLAT_FILM_MAX_VALUE), &counters);
    assert_int_equal(counters.nonfinite_samples, 3);
    splat_film_add(&film, -0.5f, 0.5f, vec3_make(1.0f, 1.0f, 1.0f), &counters);
    splat_film_add(&film, 2.0f, 0.5f, vec3_make(1.0f, 1.0f, 1.0f), &counters);
    splat_film_add(&film, 0.5f, NAN, vec3_make(1.0f, 1.0f, 1.0f), &counters);
    for (int i = 0; i < 12; i++)
        assert_int_equal(film.sum[i], 0);
    splat_film_add(&film, 1.999f, 1.0f, vec3_make(0.25f, -0.5f, 3.0f), &counters);
    vec3 v = splat_film_get(&film, 1, 1, 2.0);
    assert_true(v.x == 0.5f && v.y == -1.0f && v.z == 6.0f);
    splat_film_free(&film);
}

/* --eye, --target and --fov (CLI_CAMERA_FLAGS) read three numbers X,Y,Z
 * and a field of view, refuse anything else naming the flag, and replace
 * only the parts given: with none the camera is the scene's, bit for bit;
 * with an eye alone the view keeps its direction. */
static void test_camera_flags_override_the_scenes_camera(void **state)
{
    (void)state;
    camera_override view = CAMERA_NOT_OVERRIDDEN;
    const cli_flag extras[] = {CLI_CAMERA_FLAGS(view)};
    cli_spec spec = {"test", "camera flags", extras, 3, "the path of a pixel"};
    cli_options o = cli_defaults("out.exr", 8, 8, 1);
    char err[512];
    char *good[] = {"test", "--eye", "1,2,3", "--fov", "30"};
    assert_int_equal(cli_parse(5, good, &spec, &o, err, sizeof err), CLI_OK);
    assert_true(view.eye.x == 1.0f && view.eye.y == 2.0f && view.eye.z == 3.0f);
    assert_true(isnan(view.target.x) && view.vertical_fov_degrees == 30.0f);
    const char *bad[] = {"1,2", "1,2,3,4", "1,,3", "a,b,c", "1,2,nan", "", "1e9,0,0"};
    for (int k = 0; k < 7; k++) {
        char *argv[] = {"test", "--eye", (char *)bad[k]};
        assert_int_equal(cli_parse(3, argv, &spec, &o, err, sizeof err), CLI_ERROR);
        assert_non_null(strstr(err, "--eye"));
    }
    camera scene = camera_look_at(vec3_make(0, 1, 5), vec3_make(0, 1, 0), vec3_make(0, 1, 0), 40.0f, 8, 6);
    camera_override none = CAMERA_NOT_OVERRIDDEN;
    camera same = camera_overridden(&scene, &none);
    assert_memory_equal(&same, &scene, sizeof scene);
    camera_override eye_only = CAMERA_NOT_OVERRIDDEN;
    eye_only.eye = vec3_make(3, 1, 5);
    camera moved = camera_overridden(&scene, &eye_only);
    assert_true(moved.eye.x == 3.0f);
    assert_true(vec3_length(vec3_sub(moved.forward, scene.forward)) < 1e-6f);
    assert_true(fabsf(moved.half_height - scene.half_height) < 1e-6f); /* the field of view kept */
}

/* The record a counters file carries: the command line (an argument with a
 * space quoted, so the line pastes back), the version, the seed, the size
 * and the notes, as valid JSON strings (a quote in a note escaped). */
static void test_counters_file_records_the_run(void **state)
{
    (void)state;
    cli_options o = cli_defaults("out.exr", 16, 8, 4);
    o.seed = 42;
    char *argv[] = {"prog", "--seed", "42", "--scene", "my scene.scene"};
    o.scene = argv[4];
    run_record_command(5, argv, &o);
    run_record_note("integrator", "mis");
    run_record_note("odd", "say \"hi\"");
    char path[] = "/tmp/test_record.XXXXXX", json[256], err[256], text[8192];
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    close(fd);
    snprintf(json, sizeof json, "%s.json", path);
    ray_counters c = {0};
    assert_true(counters_write_json(json, &c, 1.0, NULL, err, sizeof err));
    FILE *f = fopen(json, "r");
    assert_non_null(f);
    size_t n = fread(text, 1, sizeof text - 1, f);
    text[n] = '\0';
    fclose(f);
    assert_non_null(strstr(text, "\"command\": \"prog --seed 42 --scene 'my scene.scene'\""));
    assert_non_null(strstr(text, "\"version\": \""));
    assert_non_null(strstr(text, "\"seed\": 42"));
    assert_non_null(strstr(text, "\"width\": 16"));
    assert_non_null(strstr(text, "\"scene\": \"my scene.scene\""));
    assert_non_null(strstr(text, "\"integrator\": \"mis\""));
    assert_non_null(strstr(text, "\"odd\": \"say \\\"hi\\\"\""));
    remove(json);
    remove(path);
}

/* A name on Linux is any bytes; JSON is Unicode text. A byte that is not
 * well-formed UTF-8 (Latin-1's e-acute, a sequence cut short, an overlong
 * '/', a surrogate) becomes \ufffd, one per byte, so the counters file
 * stays valid JSON; the twin: well-formed UTF-8 (e-acute, the euro sign,
 * an emoji) is written as it is. */
static void test_counters_file_is_valid_json_for_any_bytes(void **state)
{
    (void)state;
    cli_options o = cli_defaults("out.exr", 16, 8, 4);
    char *argv[] = {"prog", "--scene", "\xe9t\xe9 \xe2\x82.scene", "--obj", "\xc0\xaf\xed\xa0\x80\xff.obj", "--mesh",
                    "\xc3\xa9\xe2\x82\xac\xf0\x9f\x98\x80"};
    o.scene = argv[2];
    run_record_command(7, argv, &o);
    char json[8192];
    assert_true(run_record_json(json, sizeof json));
    assert_non_null(strstr(json, "\"command\": \"prog --scene '\\ufffdt\\ufffd \\ufffd\\ufffd.scene' --obj "
                                 "\\ufffd\\ufffd\\ufffd\\ufffd\\ufffd\\ufffd.obj --mesh \xc3\xa9\xe2\x82\xac\xf0\x9f\x98\x80\""));
    assert_non_null(strstr(json, "\"scene\": \"\\ufffdt\\ufffd \\ufffd\\ufffd.scene\""));
    for (const unsigned char *p = (const unsigned char *)json; *p != '\0'; p++)
        if (*p >= 0x80) /* only the twin's three well-formed characters */
            assert_true(p >= (const unsigned char *)strstr(json, "--mesh "));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pcg32_matches_reference_output),
        cmocka_unit_test(test_counters_file_records_the_run),
        cmocka_unit_test(test_counters_file_is_valid_json_for_any_bytes),
        cmocka_unit_test(test_camera_flags_override_the_scenes_camera),
        cmocka_unit_test(test_pcg32_float_is_in_unit_interval_and_uniform),
        cmocka_unit_test(test_pcg32_pixel_streams_differ),
        cmocka_unit_test(test_pcg32_bounded_stays_in_range),
        cmocka_unit_test(test_welford_matches_two_pass_formula),
        cmocka_unit_test(test_welford_is_stable_with_a_large_offset),
        cmocka_unit_test(test_welford_merge_equals_one_pass),
        cmocka_unit_test(test_loglog_slope_recovers_power_law),
        cmocka_unit_test(test_camera_centre_ray_looks_at_target),
        cmocka_unit_test(test_camera_edges_span_the_field_of_view),
        cmocka_unit_test(test_offset_origin_moves_to_the_normal_side_at_every_scale),
        cmocka_unit_test(test_spawn_offsets_towards_the_direction),
        cmocka_unit_test(test_render_is_bit_identical_for_any_thread_count),
        cmocka_unit_test(test_render_counts_every_camera_ray),
        cmocka_unit_test(test_pilot_samples_the_whole_image_at_full_spp),
        cmocka_unit_test(test_render_drops_and_counts_nan_samples),
        cmocka_unit_test(test_one_sample_goes_through_the_pixel_centre),
        cmocka_unit_test(test_progressive_stops_at_once_without_noise),
        cmocka_unit_test(test_progressive_reaches_the_target_error),
        cmocka_unit_test(test_cli_reads_every_shared_flag),
        cmocka_unit_test(test_cli_rejects_bad_flags_with_a_clear_message),
        cmocka_unit_test(test_cli_rejects_an_unwritable_directory),
        cmocka_unit_test(test_cli_help_and_extras),
        cmocka_unit_test(test_cli_rejects_nan_and_inf_for_an_unranged_float),
        cmocka_unit_test(test_cli_checks_a_directory_flag_at_once),
        cmocka_unit_test(test_cli_choice_stores_the_index_of_the_name),
        cmocka_unit_test(test_cli_choice_refuses_other_values_naming_the_choices),
        cmocka_unit_test(test_cli_choice_bad_value_exits_with_status_2),
        cmocka_unit_test(test_cli_choice_help_lists_the_choices),
        cmocka_unit_test(test_splat_film_is_the_same_for_any_order_and_thread_count),
        cmocka_unit_test(test_splat_float_sums_depend_on_order),
        cmocka_unit_test(test_splat_film_drops_nonfinite_and_ignores_points_outside),
    };
    return cmocka_run_group_tests_name("common", tests, NULL, NULL);
}
