/* test_ch10.c -- distribution ray tracing against the path tracer, the thin
 * lens against its formula, motion blur and soft shadows against closed
 * forms, and the ray counts against N_glossy^depth. Statistical checks use
 * fixed seeds (test_seed) and 5 standard errors (in quadrature when both
 * sides are noisy); each has a twin on a deliberately wrong setting. */
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

#include "09-path-tracing/path_tracer.h"
#include "10-distribution/distribution.h"
#include "effects.h"
#include "render.h"
#include "scene_file.h"
#include "stats.h"
#include "test_support.h"
#include "chi2.h"
#include "chi2_sobol.h"

static const double STANDARD_ERRORS = 5.0;
/* Below this a standard error is float rounding, not noise. */
static const double ROUNDING_FLOOR = 1e-5;

typedef struct {
    image mean, standard_error;
    render_stats stats;
} render_result;

static render_result render_radiance(radiance_fn radiance, const void *ctx, const camera *cam, int spp, uint64_t seed,
                                     int threads)
{
    render_result r;
    r.mean = image_make(cam->width, cam->height);
    r.standard_error = image_make(cam->width, cam->height);
    render_job job = {.cam = cam, .spp = spp, .seed = seed, .threads = threads, .quiet = true, .radiance = radiance,
                      .scene = ctx, .standard_error = &r.standard_error, .jitter = true,
                      .stratify = radiance == distribution_radiance};
    render_image(&job, &r.mean, &r.stats);
    return r;
}

static void render_result_free(render_result *r)
{
    image_free(&r->mean);
    image_free(&r->standard_error);
}

/* Pixel channels where |a - b| > 5 sqrt(se_a^2 + se_b^2) (or, with no
 * noise on either side, more than ROUNDING_FLOOR). */
static int count_disagreements(const render_result *a, const render_result *b)
{
    int bad = 0, n = a->mean.width * a->mean.height * 3;
    for (int i = 0; i < n; i++) {
        double sa = a->standard_error.rgb[i], sb = b->standard_error.rgb[i];
        double tolerance = STANDARD_ERRORS * sqrt(sa * sa + sb * sb) + ROUNDING_FLOOR;
        bad += !(fabs((double)a->mean.rgb[i] - b->mean.rgb[i]) <= tolerance);
    }
    return bad;
}

/* ---- the path tracer's estimator, restricted ------------------------------------
 * Distribution ray tracing computes all the light the path tracer finds
 * except what bounces off a diffuse surface and goes on. Chapter 09 with
 * `effects` lacking EFFECT_INDIRECT ends its paths at diffuse vertices
 * after their direct light: the same light transport, so both estimate the
 * same image; MIS, RR off, one depth limit on both sides. The scene: the
 * still part of the built-in scene (a GGX plate, a mirror and a glass
 * sphere in the Cornell room: glossy reflections of the light and the
 * walls). */
static void test_equals_path_tracer_without_indirect_diffuse(void **state)
{
    (void)state;
    motion_scene ms;
    motion_scene_init(&ms);
    motion_scene_build_showcase_still(&ms.base);
    camera cam = pt_scene_camera(&ms.base, 12, 12);

    path_tracer pt = path_tracer_defaults(&ms.base);
    pt.integrator = PT_MIS;
    pt.russian_roulette = RR_OFF;
    pt.max_depth = 5;
    pt.effects = EFFECT_ALL & ~(unsigned)EFFECT_INDIRECT;
    render_result reference = render_radiance(path_trace_radiance, &pt, &cam, 1024, test_seed(1001), 2);

    distribution_tracer dt = distribution_tracer_defaults(&ms, &cam);
    dt.lens.aperture_radius = 0.0f;
    dt.light_samples = 2;
    dt.glossy_samples = 2;
    dt.max_depth = 5;
    render_result r = render_radiance(distribution_radiance, &dt, &cam, 256, test_seed(1002), 2);
    int bad = count_disagreements(&r, &reference);
    print_message("distribution vs path tracer: %d of %d pixel channels beyond 5 standard errors\n", bad,
                  12 * 12 * 3);
    /* 432 channels x 5.7e-7 (the normal tail at 5 sigma): expect none. */
    assert_int_equal(bad, 0);
    assert_int_equal(r.stats.counters.nonfinite_samples, 0);

    /* The twin: the area light's soft shadows replaced by shadow rays to a
     * point at its centre, of the same intensity straight down (L_e A):
     * the light as Whitted's renderer saw it. The emitting quad itself is
     * still seen, so the light pixels agree; the rest does not. */
    motion_scene twin = ms;
    pt_point_light point = {{278.0f, 548.0f, 279.5f}, vec3_scale(ms.base.materials[3].emission, 130.0f * 105.0f)};
    twin.base.emitter_count = 0; /* nothing left to sample by area (a shallow copy: freed with ms) */
    twin.base.point_lights = &point;
    twin.base.point_light_count = 1;
    distribution_tracer wrong = dt;
    wrong.scene = &twin;
    render_result w = render_radiance(distribution_radiance, &wrong, &cam, 256, test_seed(1002), 2);
    int twin_bad = count_disagreements(&w, &reference);
    print_message("twin, point light: %d of %d pixel channels beyond 5 standard errors\n", twin_bad, 12 * 12 * 3);
    assert_true(twin_bad > 12 * 12 * 3 / 4);
    render_result_free(&w);
    render_result_free(&r);
    render_result_free(&reference);
    motion_scene_free(&ms);
}

/* ---- the thin lens -------------------------------------------------------------- */

/* Aperture 0 is the pinhole camera: the same ray, bit for bit, whatever
 * the focus distance, and so the same image. */
static void test_aperture_zero_is_the_pinhole(void **state)
{
    (void)state;
    exercise_checks("thin_lens");
    motion_scene ms;
    motion_scene_build_showcase(&ms);
    camera cam = pt_scene_camera(&ms.base, 16, 16);
    thin_lens lens = thin_lens_make(&cam, 0.0f, 700.0f);
    /* 50 pixel positions along a diagonal, each with a different lens
     * sample in [0, 1)^2: with aperture 0 none of them may move the ray */
    for (int i = 0; i < 50; i++) {
        ray pinhole = camera_ray(&cam, 0.3f * (float)i, 16.0f - 0.25f * (float)i);
        ray r = thin_lens_ray(&lens, pinhole, vec2_make(0.02f * (float)i, 0.9f - 0.017f * (float)i));
        if (memcmp(&r, &pinhole, sizeof r) != 0) {
            print_error("aperture 0: thin_lens_ray gave the ray from (%g, %g, %g) along (%g, %g, %g), expected the "
                        "pinhole ray itself, from (%g, %g, %g) along (%g, %g, %g)\n", (double)r.origin.x,
                        (double)r.origin.y, (double)r.origin.z, (double)r.direction.x, (double)r.direction.y,
                        (double)r.direction.z, (double)pinhole.origin.x, (double)pinhole.origin.y,
                        (double)pinhole.origin.z, (double)pinhole.direction.x, (double)pinhole.direction.y,
                        (double)pinhole.direction.z);
            fail();
        }
    }
    distribution_tracer a = distribution_tracer_defaults(&ms, &cam), b = a;
    a.lens.aperture_radius = b.lens.aperture_radius = 0.0f;
    b.lens.focus_distance = 300.0f;
    render_result ra = render_radiance(distribution_radiance, &a, &cam, 4, 5, 2);
    render_result rb = render_radiance(distribution_radiance, &b, &cam, 4, 5, 2);
    assert_memory_equal(ra.mean.rgb, rb.mean.rgb, 16 * 16 * 3 * sizeof(float));
    /* and a lens that is open does change it */
    b.lens.aperture_radius = 25.0f;
    render_result rc = render_radiance(distribution_radiance, &b, &cam, 4, 5, 2);
    assert_true(memcmp(ra.mean.rgb, rc.mean.rgb, 16 * 16 * 3 * sizeof(float)) != 0);
    render_result_free(&ra);
    render_result_free(&rb);
    render_result_free(&rc);
    motion_scene_free(&ms);
}

/* ---- chi-square: the lens samples its disk (tests/chi2.h) --------------------------
 * thin_lens_ray puts the ray's origin at a point of the aperture, a disk
 * of radius a about the eye in the film's plane, uniformly: density
 * 1 / (pi a^2) per unit area. The origins, in the camera's (right, up)
 * coordinates, are counted in bins of equal probability over the disk and
 * compared by Pearson's test (chi2.h) with N times the density's integral
 * per bin; and every ray must pass through the point of the plane of focus
 * its pinhole ray meets. Two cameras (the showcase's, far from the origin
 * with a 25 mm aperture, and one of aperture 0.2 at the origin), two
 * pixels (the centre and a corner), random and Sobol points: a family of
 * 8, Holm-corrected to CHI2_FAMILY_ALPHA. */
enum { LENS_ATTEMPTS = 100000, LENS_FAMILY = 8 };

typedef struct {
    thin_lens lens;
    ray pinhole;
    double right[3], up[3], eye[3];
    double claimed_radius; /* the disk the pdf claims: the aperture, or the twin's */
    double rim_slack;      /* relative: how far past the rim rounding may put a point */
    bool unit_disk_pdf;    /* the twin: 1 / pi, the unit disk's density, not the aperture's */
    double worst_focus_miss;
} lens_chi2;

static bool lens_chi2_sample(const void *ctx, const float *u, double point[3])
{
    lens_chi2 *l = (lens_chi2 *)ctx; /* keeps the worst miss of the focus point */
    ray r = thin_lens_ray(&l->lens, l->pinhole, vec2_make(u[0], u[1]));
    double o[3] = {(double)r.origin.x - l->eye[0], (double)r.origin.y - l->eye[1], (double)r.origin.z - l->eye[2]};
    point[0] = o[0] * l->right[0] + o[1] * l->right[1] + o[2] * l->right[2];
    point[1] = o[0] * l->up[0] + o[1] * l->up[1] + o[2] * l->up[2];
    point[2] = 0.0;
    /* the distance from the focus point to the ray's line */
    vec3 focus = ray_at(l->pinhole, l->lens.focus_distance / vec3_dot(l->pinhole.direction, l->lens.forward));
    vec3 to_focus = vec3_sub(focus, r.origin);
    double miss = vec3_length(vec3_cross(to_focus, r.direction)) / vec3_length(to_focus);
    l->worst_focus_miss = fmax(l->worst_focus_miss, miss);
    return true;
}

static double lens_chi2_pdf(const void *ctx, const double point[3])
{
    const lens_chi2 *l = ctx;
    double a = l->claimed_radius;
    if (!(hypot(point[0], point[1]) <= a * (1.0 + l->rim_slack)))
        return 0.0;
    return l->unit_disk_pdf ? 1.0 / PI : 1.0 / (PI * a * a);
}

static lens_chi2 lens_chi2_make(const camera *cam, float aperture, float focus, float px, float py)
{
    lens_chi2 l = {.lens = thin_lens_make(cam, aperture, focus), .pinhole = camera_ray(cam, px, py),
                   .claimed_radius = aperture};
    vec3 v[3] = {cam->right, cam->up, cam->eye};
    double *out[3] = {l.right, l.up, l.eye};
    for (int k = 0; k < 3; k++)
        out[k][0] = v[k].x, out[k][1] = v[k].y, out[k][2] = v[k].z;
    /* The origin eye + a (x right + y up) is summed in float at the eye's
     * magnitude: a few float steps there, relative to a. */
    float magnitude = fmaxf(fabsf(cam->eye.x), fmaxf(fabsf(cam->eye.y), fabsf(cam->eye.z))) + aperture;
    l.rim_slack = 8.0 * FLT_EPSILON * magnitude / aperture;
    return l;
}

static chi2_result lens_chi2_run(lens_chi2 *l, chi2_points points)
{
    chi2_case c = {.measure = CHI2_DISK, .s_max = l->claimed_radius * (1.0 + l->rim_slack), .dimensions = 2,
                   .sample = lens_chi2_sample, .pdf = lens_chi2_pdf, .ctx = l};
    chi2_table tab = chi2_tabulate(&c, 64, 256);
    chi2_result r = chi2_run(&c, &tab, points, LENS_ATTEMPTS);
    chi2_table_free(&tab);
    return r;
}

/* The ray through the focus point: float directions from origins a few
 * float steps off, over focus distances of up to 1000: 1e-6 relative of
 * the distance (~10 float steps). */
static const double LENS_FOCUS_TOLERANCE = 1e-6;

static void lens_cameras(motion_scene *ms, camera cams[2], float apertures[2], float focus[2])
{
    motion_scene_build_showcase(ms);
    cams[0] = pt_scene_camera(&ms->base, 64, 48);
    apertures[0] = 25.0f, focus[0] = 700.0f;
    cams[1] = camera_look_at(vec3_make(0, 0, 0), vec3_make(0.3f, -0.2f, -1.0f), vec3_make(0, 1, 0), 50.0f, 64, 48);
    apertures[1] = 0.2f, focus[1] = 3.0f;
}

static void test_chi2_thin_lens_samples_its_disk(void **state)
{
    (void)state;
    exercise_checks("thin_lens");
    motion_scene ms;
    camera cams[2];
    float apertures[2], focus[2];
    lens_cameras(&ms, cams, apertures, focus);
    chi2_family family = {.count = 0};
    for (int k = 0; k < 2; k++)
        for (int pixel = 0; pixel < 2; pixel++)
            for (int which = 0; which < 2; which++) {
                lens_chi2 l = lens_chi2_make(&cams[k], apertures[k], focus[k], pixel == 0 ? 32.0f : 0.5f,
                                             pixel == 0 ? 24.0f : 47.5f);
                chi2_sources src;
                chi2_points points = chi2_source(&src, 500 + 4 * (uint64_t)k + 2 * (uint64_t)pixel, which);
                chi2_result r = lens_chi2_run(&l, points);
                char name[CHI2_NAME_SIZE];
                snprintf(name, sizeof name, "lens of aperture %g, %s pixel, %s", (double)apertures[k],
                         pixel == 0 ? "centre" : "corner", points.name);
                chi2_family_add(&family, name, &r);
                if (!(l.worst_focus_miss <= LENS_FOCUS_TOLERANCE * focus[k])) {
                    print_error("%s: a ray passes %.3g from its point of the plane of focus, expected at most %.3g "
                                "(every ray from the lens goes through the point its pinhole ray meets there)\n",
                                name, l.worst_focus_miss, LENS_FOCUS_TOLERANCE * focus[k]);
                    fail();
                }
            }
    assert_int_equal(family.count, LENS_FAMILY);
    int rejected = chi2_family_holm(&family, CHI2_FAMILY_ALPHA);
    if (rejected != 0) {
        print_error("%d of %d sets of ray origins are not uniform on the aperture, a disk of radius a about the eye "
                    "spanned by right and up (density 1 / (pi a^2)), expected none\n", rejected, LENS_FAMILY);
        fail();
    }
    motion_scene_free(&ms);
}

/* The twins: a density claiming an aperture 10 % wider than the one
 * sampled, and the unit disk's 1 / pi with the aperture's scale a^2 (the
 * map's Jacobian) dropped. */
static void test_chi2_thin_lens_twins_fail(void **state)
{
    (void)state;
    motion_scene ms;
    camera cams[2];
    float apertures[2], focus[2];
    lens_cameras(&ms, cams, apertures, focus);
    chi2_sources src;
    lens_chi2 l = lens_chi2_make(&cams[0], apertures[0], focus[0], 32.0f, 24.0f);
    l.claimed_radius *= 1.1;
    chi2_result r = lens_chi2_run(&l, chi2_source(&src, 510, 0));
    chi2_assert_twin_fails("lens, pdf of an aperture 10 % wider", &r, LENS_FAMILY);
    l = lens_chi2_make(&cams[1], apertures[1], focus[1], 32.0f, 24.0f);
    l.unit_disk_pdf = true;
    r = lens_chi2_run(&l, chi2_source(&src, 511, 1));
    chi2_assert_twin_fails("lens of aperture 0.2, Jacobian a^2 dropped, Sobol", &r, LENS_FAMILY);
    motion_scene_free(&ms);
}

/* The mean squared distance from the image's centroid, in pixels^2,
 * weighted by brightness (the green channel). */
static double image_spread2(const image *img)
{
    double sum = 0, sx = 0, sy = 0, sxx = 0;
    for (int y = 0; y < img->height; y++)
        for (int x = 0; x < img->width; x++) {
            double w = img->rgb[(y * img->width + x) * 3 + 1];
            double cx = x + 0.5, cy = y + 0.5;
            sum += w;
            sx += w * cx;
            sy += w * cy;
            sxx += w * (cx * cx + cy * cy);
        }
    double mx = sx / sum, my = sy / sum;
    return sxx / sum - mx * mx - my * my;
}

/* A small bright sphere (a "point") on a black ground, seen through a thin
 * lens of radius a focused at f. On the plane of focus it spreads over the
 * disk of confusion of diameter 2 a |z - f| / z (thin_lens.c); on the
 * image plane (distance 1) that is divided by f. The image is that disk
 * (mean squared radius R^2 / 2) blurred by the sphere's own disk (rho^2 / 2)
 * and the pixel's box (1/6 pixel^2 in two axes): the three variances add. */
static double predicted_spread2(const thin_lens *lens, float z, float radius, double pixel)
{
    double coc_radius = 0.5 * thin_lens_confusion_diameter(lens, z) / lens->focus_distance / pixel;
    double rho = radius / z / pixel;
    return coc_radius * coc_radius / 2.0 + rho * rho / 2.0 + 1.0 / 6.0;
}

/* The spread of the point's image: measured on BATCHES renders of
 * independent seeds, whose spreads give the estimate's standard error. */
enum { BATCHES = 16 };

static double render_point_spread2(float z, float radius, float aperture, float focus, thin_lens *lens_out,
                                   double *pixel_out, double *standard_error)
{
    motion_scene ms;
    motion_scene_init(&ms);
    int glow = pt_scene_add_material(&ms.base, pt_emitter(vec3_splat(0.0f), vec3_splat(1.0f)));
    pt_scene_add_sphere(&ms.base, vec3_make(0, 0, -z), radius, glow, false);
    pt_scene_finish(&ms.base);
    camera cam = camera_look_at(vec3_make(0, 0, 0), vec3_make(0, 0, -1), vec3_make(0, 1, 0), 10.0f, 48, 48);
    distribution_tracer dt = distribution_tracer_defaults(&ms, &cam);
    dt.lens = thin_lens_make(&cam, aperture, focus);
    welford spread = {0};
    for (int b = 0; b < BATCHES; b++) {
        render_result r = render_radiance(distribution_radiance, &dt, &cam, 64, test_seed(77 + (uint64_t)b), 2);
        welford_add(&spread, image_spread2(&r.mean));
        render_result_free(&r);
    }
    *lens_out = dt.lens;
    *pixel_out = 2.0 * cam.half_height / cam.height;
    *standard_error = welford_standard_error(&spread);
    motion_scene_free(&ms);
    return welford_mean(&spread);
}

static void test_thin_lens_focus_and_circle_of_confusion(void **state)
{
    (void)state;
    exercise_checks("thin_lens");
    thin_lens lens;
    double pixel, se;
    /* At the focus distance: sharp. The "point" is a sphere of radius
     * SHARP_RADIUS at SHARP_DISTANCE, on the plane of focus. */
    const double SHARP_RADIUS = 0.01, SHARP_DISTANCE = 10.0;
    double sharp = render_point_spread2((float)SHARP_DISTANCE, (float)SHARP_RADIUS, 0.2f, (float)SHARP_DISTANCE, &lens,
                                        &pixel, &se);
    print_message("in focus: rms spread %.3f pixels\n", sqrt(sharp));
    /* A point's image discretised at pixel centres spreads at most over the
     * 2 x 2 pixels around it: sqrt(2)/2 pixel rms (at their common corner,
     * as here), widened by the sphere's own disk (rho_sharp pixels in
     * radius). SHARP_SLACK (pixels) covers the rms estimate's own noise
     * over the samples; a lens left open at the focus spreads the point
     * over many pixels, far beyond it. */
    const double SHARP_SLACK = 0.01;
    double rho_sharp = SHARP_RADIUS / SHARP_DISTANCE / pixel;
    double sharp_bound = sqrt(0.5 + rho_sharp * rho_sharp / 2.0) + SHARP_SLACK;
    if (!(sqrt(sharp) <= sharp_bound)) {
        if (isnan(sharp))
            print_error("a point on the plane of focus is not in the image at all (it is black), expected within %.3g "
                        "pixels rms of its pinhole image (sharp)\n", sharp_bound);
        else
            print_error("a point on the plane of focus spreads over %.3g pixels rms, expected at most %.3g (sharp)\n",
                        sqrt(sharp), sharp_bound);
        fail();
    }
    /* Half as far: the disk of confusion, 2 a (f - z) / z = 0.4 on the
     * plane of focus, 5.5 pixels in radius (the "point" is now a sphere
     * 2.2 pixels in radius: a smaller one is hit by too few samples for a
     * stable spread, whose ratio estimate is then biased low). Tolerance: 5 standard errors of
     * the measured spread^2, plus 1 % for the model (the pixel box's 1/6
     * holds on average over sub-pixel positions). */
    double blurred = render_point_spread2(5.0f, 0.04f, 0.2f, 10.0f, &lens, &pixel, &se);
    double predicted = predicted_spread2(&lens, 5.0f, 0.04f, pixel);
    print_message("out of focus: spread^2 %.3f +- %.3f pixels^2 (predicted %.3f)\n", blurred, se, predicted);
    assert_close(blurred, predicted, STANDARD_ERRORS * se + 0.01 * predicted);
    /* The twin: the circle divided by the focus distance instead of the
     * point's (2 a |z - f| / f, half the true size here) is caught. */
    double wrong_radius = lens.aperture_radius * fabs(5.0 - 10.0) / 10.0 / 10.0 / pixel;
    double rho = 0.04 / 5.0 / pixel;
    double wrong = wrong_radius * wrong_radius / 2.0 + rho * rho / 2.0 + 1.0 / 6.0;
    print_message("twin, circle 2 a |z - f| / f: predicted %.3f pixels^2\n", wrong);
    assert_false(fabs(blurred - wrong) <= STANDARD_ERRORS * se + 0.01 * wrong);
}

/* ---- motion blur ----------------------------------------------------------------
 * An emitting square (L_e = 1) facing the camera, moving sideways by d over
 * the shutter: a pixel of a row it spans from top to bottom sees it for
 * the fraction of (time x pixel width) when they overlap:
 *   E_i = integral over t in [0,1) of |[i, i+1] n [a + t d, a + t d + w]| dt
 * (in pixels; the square's image is a square, moving uniformly, since it
 * lies parallel to the image plane). Integrated here by the midpoint rule. */
static double overlap(double lo0, double hi0, double lo1, double hi1)
{
    return fmax(0.0, fmin(hi0, hi1) - fmax(lo0, lo1));
}

static double expected_coverage(int i, double a, double w, double d)
{
    const int steps = 20000;
    double sum = 0.0;
    for (int k = 0; k < steps; k++) {
        double t = (k + 0.5) / steps;
        sum += overlap(i, i + 1, a + t * d, a + t * d + w);
    }
    return sum / steps;
}

static void test_motion_blur_of_a_moving_square(void **state)
{
    (void)state;
    const float z = 10.0f, x0 = -0.9f, width = 0.5f, move = 0.8f;
    motion_scene ms;
    motion_scene_init(&ms);
    int glow = pt_scene_add_material(&ms.base, pt_emitter(vec3_splat(0.0f), vec3_splat(1.0f)));
    pt_scene_finish(&ms.base);
    mesh square;
    mesh_init(&square);
    int p0 = mesh_add_position(&square, vec3_make(x0, -1, -z)), p1 = mesh_add_position(&square, vec3_make(x0 + width, -1, -z));
    int p2 = mesh_add_position(&square, vec3_make(x0 + width, 1, -z)), p3 = mesh_add_position(&square, vec3_make(x0, 1, -z));
    mesh_add_triangle(&square, p0, p1, p2, glow);
    mesh_add_triangle(&square, p0, p2, p3, glow);
    motion_scene_add_mesh(&ms, &square, vec3_make(move, 0, 0));
    const int w = 40, h = 8;
    camera cam = camera_look_at(vec3_make(0, 0, 0), vec3_make(0, 0, -1), vec3_make(0, 1, 0), 4.0f, w, h);
    distribution_tracer dt = distribution_tracer_defaults(&ms, &cam);
    render_result r = render_radiance(distribution_radiance, &dt, &cam, 256, test_seed(303), 2);
    /* world x at depth z -> pixel: (x / z / half_width + 1) w / 2 */
    double scale = w / 2.0 / z / cam.half_width;
    double a = (x0 / z / cam.half_width + 1.0) * w / 2.0, wp = width * scale, dp = move * scale;
    int bad = 0, bad_twin = 0, y = h / 2;
    for (int i = 0; i < w; i++) {
        double m = r.mean.rgb[(y * w + i) * 3 + 1], se = r.standard_error.rgb[(y * w + i) * 3 + 1];
        /* Each sample is 1 (the square) or 0: a Bernoulli of mean E, whose
         * standard error sqrt(E (1 - E) / n) stands in where the 256
         * samples happened to agree (a measured se of 0 at E = 0.004). */
        double e = expected_coverage(i, a, wp, dp), e_twin = expected_coverage(i, a, wp, dp / 2);
        double se_e = fmax(se, sqrt(e * (1 - e) / 256)), se_twin = fmax(se, sqrt(e_twin * (1 - e_twin) / 256));
        bad += !(fabs(m - e) <= STANDARD_ERRORS * se_e + ROUNDING_FLOOR);
        /* the twin: a shutter open half as long (the square moving d/2) */
        bad_twin += !(fabs(m - e_twin) <= STANDARD_ERRORS * se_twin + ROUNDING_FLOOR);
    }
    print_message("moving square: %d of %d pixels beyond 5 standard errors; twin (d/2): %d\n", bad, w, bad_twin);
    assert_int_equal(bad, 0);
    assert_true(bad_twin >= 4);
    render_result_free(&r);
    motion_scene_free(&ms);
}

/* With the shutter closed (every sample at time 0) the scene is the still
 * of its first instant: the same image, bit for bit, as the scene whose
 * objects do not move at all. And a ray at any instant that hits a moving
 * object also meets that object's swept bounds. */
static void test_time_zero_is_the_still(void **state)
{
    (void)state;
    motion_scene moving, still;
    motion_scene_build_showcase(&moving);
    motion_scene_build_showcase(&still);
    for (int i = 0; i < still.sphere_count; i++)
        still.spheres[i].motion = vec3_splat(0.0f);
    for (int i = 0; i < still.mesh_count; i++)
        still.meshes[i]->motion = vec3_splat(0.0f);
    camera cam = pt_scene_camera(&moving.base, 24, 24);
    distribution_tracer closed = distribution_tracer_defaults(&moving, &cam), fixed = distribution_tracer_defaults(&still, &cam);
    closed.motion = false;
    render_result a = render_radiance(distribution_radiance, &closed, &cam, 4, 9, 2);
    render_result b = render_radiance(distribution_radiance, &fixed, &cam, 4, 9, 2);
    assert_memory_equal(a.mean.rgb, b.mean.rgb, 24 * 24 * 3 * sizeof(float));
    /* the twin: the shutter open, the moving scene differs */
    closed.motion = true;
    render_result c = render_radiance(distribution_radiance, &closed, &cam, 4, 9, 2);
    assert_true(memcmp(a.mean.rgb, c.mean.rgb, 24 * 24 * 3 * sizeof(float)) != 0);

    /* swept bounds: points of the moving sphere and cube at random
     * instants lie inside the bounds over the whole shutter */
    pcg32 rng = pcg32_for_pixel(5, 5);
    const moving_sphere *s = &moving.spheres[0];
    const moving_mesh *m = moving.meshes[0];
    aabb swept = moving_sphere_swept_bounds(s);
    for (int k = 0; k < 1000; k++) {
        float t = pcg32_float(&rng);
        vec3 on_sphere = vec3_add(moving_sphere_center(s, t),
                                  vec3_scale(sample_uniform_sphere(vec2_make(pcg32_float(&rng), pcg32_float(&rng))),
                                             s->radius));
        vec3 on_mesh = vec3_add(m->triangles.triangles[k % m->triangles.count].p1, moving_mesh_offset(m, t));
        for (int axis = 0; axis < 3; axis++) {
            assert_true(vec3_axis(on_sphere, axis) >= vec3_axis(swept.lo, axis) - 1e-3f &&
                        vec3_axis(on_sphere, axis) <= vec3_axis(swept.hi, axis) + 1e-3f);
            assert_true(vec3_axis(on_mesh, axis) >= vec3_axis(m->swept.lo, axis) &&
                        vec3_axis(on_mesh, axis) <= vec3_axis(m->swept.hi, axis));
        }
    }
    render_result_free(&a);
    render_result_free(&b);
    render_result_free(&c);
    motion_scene_free(&moving);
    motion_scene_free(&still);
}

/* ---- soft shadows ----------------------------------------------------------------
 * A square light of side 2s at height h, facing down, radiance L_e, over a
 * diffuse floor of albedo rho. Straight below its centre the irradiance is
 * E = L_e pi F, F the form factor to the square: four rectangles a x b = s x s
 * with a corner above the point (the standard result),
 *   F_corner = 1/(2 pi) [X/sqrt(1+X^2) atan(Y/sqrt(1+X^2)) + Y/sqrt(1+Y^2) atan(X/sqrt(1+Y^2))],
 * X = a/h, Y = b/h; and the floor's radiance is rho E / pi. A thin blocker
 * at height h/2 over the half-space x > 0 hides exactly half of the light
 * from that point: the penumbra's value E/2. */
static double square_light_irradiance(double le, double s, double h)
{
    double x = s / h, y = s / h;
    double corner = (x / sqrt(1 + x * x) * atan(y / sqrt(1 + x * x)) + y / sqrt(1 + y * y) * atan(x / sqrt(1 + y * y))) /
                    (2.0 * PI);
    return le * PI * 4.0 * corner;
}

static void build_light_over_floor(motion_scene *ms, bool blocked)
{
    motion_scene_init(ms);
    pt_scene *sc = &ms->base;
    int floor = pt_scene_add_material(sc, pt_diffuse(vec3_splat(0.5f)));
    int light = pt_scene_add_material(sc, pt_emitter(vec3_splat(0.0f), vec3_splat(2.0f)));
    int black = pt_scene_add_material(sc, pt_diffuse(vec3_splat(0.0f)));
    pt_scene_add_quad(sc, vec3_make(-5, 0, -5), vec3_make(-5, 0, 5), vec3_make(5, 0, 5), vec3_make(5, 0, -5), floor);
    /* side 1 (s = 0.5) at h = 1, counter-clockwise seen from below */
    pt_scene_add_quad(sc, vec3_make(-0.5f, 1, -0.5f), vec3_make(0.5f, 1, -0.5f), vec3_make(0.5f, 1, 0.5f),
                      vec3_make(-0.5f, 1, 0.5f), light);
    if (blocked)
        pt_scene_add_quad(sc, vec3_make(0, 0.5f, -3), vec3_make(3, 0.5f, -3), vec3_make(3, 0.5f, 3), vec3_make(0, 0.5f, 3),
                          black);
    pt_scene_finish(sc);
}

/* The floor's radiance straight below the light's centre, from n camera
 * samples of a ray looking down from 0.2 above it (1e-3 off the floor's
 * diagonal, z, where the irradiance changes only to second order): mean
 * and standard error. */
static void floor_radiance(const distribution_tracer *dt, int n, uint64_t seed, double *mean, double *se,
                           ray_counters *counters)
{
    pcg32 rng = pcg32_for_pixel(seed, 0);
    welford w = {0};
    for (int i = 0; i < n; i++) {
        ray down = ray_make(vec3_make(0, 0.2f, 1e-3f), vec3_make(0, -1, 0));
        counters->camera_rays++;
        welford_add(&w, distribution_radiance(dt, down, &rng, counters).y);
    }
    *mean = welford_mean(&w);
    *se = welford_standard_error(&w);
}

static void test_soft_shadow_irradiance(void **state)
{
    (void)state;
    double expected = 0.5 / PI * square_light_irradiance(2.0, 0.5, 1.0);
    camera cam = camera_look_at(vec3_make(0, 0.2f, 0), vec3_make(0, 0, 0), vec3_make(0, 0, 1), 10, 1, 1);
    for (int blocked = 0; blocked < 2; blocked++) {
        motion_scene ms;
        build_light_over_floor(&ms, blocked);
        distribution_tracer dt = distribution_tracer_defaults(&ms, &cam);
        dt.light_samples = 4;
        ray_counters counters = {0};
        double mean, se;
        floor_radiance(&dt, 20000, test_seed(41 + (uint64_t)blocked), &mean, &se, &counters);
        double truth = blocked ? expected / 2 : expected;
        print_message("%s: %.5f +- %.5f, closed form %.5f\n", blocked ? "half blocked" : "unblocked", mean, se, truth);
        assert_close(mean, truth, STANDARD_ERRORS * se);
        if (blocked) {
            /* the twin: no visibility test (no shadow rays) sees the whole light */
            dt.effects &= ~(unsigned)EFFECT_SHADOWS;
            floor_radiance(&dt, 20000, test_seed(43), &mean, &se, &counters);
            print_message("twin, no shadow rays: %.5f +- %.5f against %.5f\n", mean, se, truth);
            assert_false(fabs(mean - truth) <= STANDARD_ERRORS * se);
        }
        motion_scene_free(&ms);
    }
}

/* ---- counters --------------------------------------------------------------------- */

/* Under the light every hit sees all of it: N_light shadow rays per camera
 * ray exactly, and nothing else (no glossy, mirror or glass). */
static void test_counts_shadow_rays_per_light_sample(void **state)
{
    (void)state;
    motion_scene ms;
    build_light_over_floor(&ms, false);
    camera cam = camera_look_at(vec3_make(0, 0.2f, 0), vec3_make(0, 0, 0), vec3_make(0, 0, 1), 10, 1, 1);
    for (int n = 1; n <= 8; n *= 2) {
        distribution_tracer dt = distribution_tracer_defaults(&ms, &cam);
        dt.light_samples = n;
        ray_counters c = {0};
        double mean, se;
        floor_radiance(&dt, 100, 3, &mean, &se, &c);
        assert_int_equal(c.shadow_rays, 100 * (uint64_t)n);
        assert_int_equal(c.indirect_rays + c.reflection_rays + c.refraction_rays, 0);
    }
    motion_scene_free(&ms);
}

/* The ray-count explosion, exactly: inside a glossy sphere (nearly a
 * mirror, so no lobe sample falls below the surface) with a point light at
 * its centre, every hit is glossy. A camera ray then spawns N_glossy rays
 * at each hit up to the depth limit: sum_{d=1}^{D} N^d glossy rays, and a
 * shadow ray at each of the sum_{d=0}^{D-1} N^d hits that may still add
 * light. No glass: no refraction rays. */
static void test_counts_glossy_rays_explode(void **state)
{
    (void)state;
    motion_scene ms;
    motion_scene_init(&ms);
    int shiny = pt_scene_add_material(&ms.base, pt_glossy(vec3_splat(0.9f), 0.01f));
    pt_scene_add_sphere(&ms.base, vec3_make(0, 0, 0), 1.0f, shiny, true);
    pt_scene_add_point_light(&ms.base, vec3_make(0, 0, 0), vec3_splat(1.0f));
    pt_scene_finish(&ms.base);
    camera cam = camera_look_at(vec3_make(0, 0, 0), vec3_make(0, 0, -1), vec3_make(0, 1, 0), 20.0f, 2, 2);
    for (int n = 1; n <= 3; n++)
        for (int depth = 1; depth <= 4; depth++) {
            distribution_tracer dt = distribution_tracer_defaults(&ms, &cam);
            dt.glossy_samples = n;
            dt.max_depth = depth;
            render_result r = render_radiance(distribution_radiance, &dt, &cam, 3, 17, 1);
            const ray_counters *c = &r.stats.counters;
            double hits = distribution_glossy_rays_per_camera_ray(n, depth - 1) + 1.0;
            assert_int_equal(c->camera_rays, 12);
            assert_int_equal(c->indirect_rays, (uint64_t)(12 * distribution_glossy_rays_per_camera_ray(n, depth)));
            assert_int_equal(c->shadow_rays, (uint64_t)(12 * hits));
            assert_int_equal(c->refraction_rays + c->reflection_rays, 0);
            render_result_free(&r);
        }
    assert_close(distribution_glossy_rays_per_camera_ray(4, 3), 4 + 16 + 64, 0);
    motion_scene_free(&ms);
}

/* The Cornell box, all diffuse: no glossy, mirror or refraction rays, and
 * the showcase (glossy plate, mirror, glass) spawns all three. */
static void test_counts_only_what_the_scene_needs(void **state)
{
    (void)state;
    motion_scene ms;
    motion_scene_init(&ms);
    pt_scene_build_cornell_box(&ms.base);
    camera cam = pt_scene_camera(&ms.base, 16, 16);
    distribution_tracer dt = distribution_tracer_defaults(&ms, &cam);
    dt.glossy_samples = 4;
    render_result r = render_radiance(distribution_radiance, &dt, &cam, 2, 3, 2);
    assert_int_equal(r.stats.counters.indirect_rays + r.stats.counters.reflection_rays + r.stats.counters.refraction_rays, 0);
    assert_true(r.stats.counters.shadow_rays > 0);
    render_result_free(&r);
    motion_scene_free(&ms);

    motion_scene_build_showcase(&ms);
    cam = pt_scene_camera(&ms.base, 16, 16);
    dt = distribution_tracer_defaults(&ms, &cam);
    r = render_radiance(distribution_radiance, &dt, &cam, 2, 3, 2);
    assert_true(r.stats.counters.indirect_rays > 0);
    assert_true(r.stats.counters.reflection_rays > 0);
    assert_true(r.stats.counters.refraction_rays > 0);
    render_result_free(&r);
    motion_scene_free(&ms);
}

/* Same seed, same image, for 1 and 2 threads: every pixel its own stream. */
static void test_same_image_for_any_thread_count(void **state)
{
    (void)state;
    motion_scene ms;
    motion_scene_build_showcase(&ms);
    camera cam = pt_scene_camera(&ms.base, 20, 20);
    distribution_tracer dt = distribution_tracer_defaults(&ms, &cam);
    dt.glossy_samples = dt.light_samples = 2;
    render_result a = render_radiance(distribution_radiance, &dt, &cam, 4, 21, 1);
    render_result b = render_radiance(distribution_radiance, &dt, &cam, 4, 21, 2);
    assert_memory_equal(a.mean.rgb, b.mean.rgb, 20 * 20 * 3 * sizeof(float));
    assert_memory_equal(&a.stats.counters, &b.stats.counters, sizeof a.stats.counters);
    render_result_free(&a);
    render_result_free(&b);
    motion_scene_free(&ms);
}

/* The shipped scene file is the built-in scene's still part: the same
 * image, bit for bit, and the same counters. */
static void test_scene_file_renders_the_still_part(void **state)
{
    (void)state;
    scene_desc d;
    char err[SCENE_ERROR_SIZE];
    if (!scene_desc_load(&d, "chapters/10-distribution/scenes/showcase.scene", err, sizeof err))
        fail_msg("%s", err);
    motion_scene from_file, built_in;
    motion_scene_init(&from_file);
    pt_scene_free(&from_file.base);
    if (!pt_scene_from_desc(&from_file.base, &d, "test", err, sizeof err))
        fail_msg("%s", err);
    scene_desc_free(&d);
    motion_scene_init(&built_in);
    motion_scene_build_showcase_still(&built_in.base);
    camera cam = pt_scene_camera(&built_in.base, 24, 24);
    camera cam_file = pt_scene_camera(&from_file.base, 24, 24);
    assert_memory_equal(&cam, &cam_file, sizeof cam);
    distribution_tracer a = distribution_tracer_defaults(&from_file, &cam), b = distribution_tracer_defaults(&built_in, &cam);
    a.lens = b.lens = thin_lens_make(&cam, 25.0f, 1000.0f);
    render_result ra = render_radiance(distribution_radiance, &a, &cam, 2, 13, 2);
    render_result rb = render_radiance(distribution_radiance, &b, &cam, 2, 13, 2);
    assert_memory_equal(ra.mean.rgb, rb.mean.rgb, 24 * 24 * 3 * sizeof(float));
    assert_memory_equal(&ra.stats.counters, &rb.stats.counters, sizeof ra.stats.counters);
    render_result_free(&ra);
    render_result_free(&rb);
    motion_scene_free(&from_file);
    motion_scene_free(&built_in);
}

/* ---- stratified pixel samples ----------------------------------------------------
 * A radiance function that records where in the pixel each camera ray
 * went (from its direction, inverting camera_ray), for the test below. */
typedef struct {
    const camera *cam;
    float px[64], py[64];
    int count;
} sample_log;

static sample_log stratify_log;

static vec3 record_position(const void *ctx, ray r, pcg32 *rng, ray_counters *counters)
{
    (void)ctx;
    (void)rng;
    (void)counters;
    const camera *cam = stratify_log.cam;
    float along = vec3_dot(r.direction, cam->forward);
    float sx = vec3_dot(r.direction, cam->right) / along, sy = vec3_dot(r.direction, cam->up) / along;
    stratify_log.px[stratify_log.count] = (sx / cam->half_width + 1.0f) * 0.5f * (float)cam->width;
    stratify_log.py[stratify_log.count] = (1.0f - sy / cam->half_height) * 0.5f * (float)cam->height;
    stratify_log.count++;
    return vec3_splat(0.0f);
}

/* Cook's jittered samples: with spp = k^2 (+ a few) the first k^2 fall one
 * in each cell of a k x k grid over the pixel; the twin, independent
 * uniform positions, leaves cells empty. */
static void test_stratified_samples_fill_every_cell(void **state)
{
    (void)state;
    camera cam = camera_look_at(vec3_make(0, 0, 0), vec3_make(0, 0, -1), vec3_make(0, 1, 0), 30.0f, 8, 8);
    const int spps[3] = {16, 18, 49};
    for (int stratify = 1; stratify >= 0; stratify--)
        for (int k = 0; k < 3; k++) {
            int spp = spps[k], side = spp == 49 ? 7 : 4;
            stratify_log.cam = &cam;
            stratify_log.count = 0;
            render_job job = {.cam = &cam, .spp = spp, .seed = 3, .threads = 1, .quiet = true,
                              .radiance = record_position, .scene = NULL, .stratify = stratify};
            ray_counters c = {0};
            render_pixel(&job, 5, 2, &c, NULL);
            assert_int_equal(stratify_log.count, spp);
            int hits[49] = {0}, empty = 0;
            for (int i = 0; i < side * side; i++) {
                /* pixel (5, 2): positions in [5, 6) x [2, 3) */
                float fx = stratify_log.px[i] - 5.0f, fy = stratify_log.py[i] - 2.0f;
                assert_true(fx > -1e-4f && fx < 1.0001f && fy > -1e-4f && fy < 1.0001f);
                int cx = (int)fminf(fmaxf(fx * (float)side, 0.0f), (float)side - 1.0f);
                int cy = (int)fminf(fmaxf(fy * (float)side, 0.0f), (float)side - 1.0f);
                hits[cy * side + cx]++;
            }
            for (int i = 0; i < side * side; i++)
                empty += hits[i] == 0;
            if (stratify)
                assert_int_equal(empty, 0);
            else /* k^2 uniform points leave about k^2 / e cells empty */
                assert_true(empty > 0);
        }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_equals_path_tracer_without_indirect_diffuse),
        cmocka_unit_test(test_aperture_zero_is_the_pinhole),
        cmocka_unit_test(test_thin_lens_focus_and_circle_of_confusion),
        cmocka_unit_test(test_chi2_thin_lens_samples_its_disk),
        cmocka_unit_test(test_chi2_thin_lens_twins_fail),
        cmocka_unit_test(test_motion_blur_of_a_moving_square),
        cmocka_unit_test(test_time_zero_is_the_still),
        cmocka_unit_test(test_soft_shadow_irradiance),
        cmocka_unit_test(test_counts_shadow_rays_per_light_sample),
        cmocka_unit_test(test_counts_glossy_rays_explode),
        cmocka_unit_test(test_counts_only_what_the_scene_needs),
        cmocka_unit_test(test_same_image_for_any_thread_count),
        cmocka_unit_test(test_scene_file_renders_the_still_part),
        cmocka_unit_test(test_stratified_samples_fill_every_cell),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
