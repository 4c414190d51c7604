/* test_ch11.c -- bidirectional path tracing: against chapter 09's path
 * tracer on the Cornell box, each strategy alone against it, the MIS
 * weights of every strategy summing to one, the same image on any number
 * of threads, NaN and Inf dropped. Each statistical check has a twin on a
 * deliberately wrong variant (bdpt.fault) that it catches. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "09-path-tracing/bsdf.h"
#include "11-bidirectional/bdpt.h"
#include "render.h"
#include "stats.h"
#include "image_check.h"
#include "pt_scene_check.h"
#include "test_support.h"

/* The statistical comparisons are those of chapter 09's tests
 * (tests/image_check.h): per channel, the image means' z-score and the
 * chi-square of the pixels' differences, each pixel's difference divided
 * by its own standard errors, with a false-alarm budget of 1e-6 per test.
 * They treat the standard errors as known, so BDPT's come from RENDERS
 * independent renders (the splats of light tracing land on any pixel, so
 * one render's per-pixel sample variance misses them): with 64, a pixel's
 * studentized difference is nearly normal (Student's t with 63 degrees of
 * freedom, whose square has mean 63 / 61 = 1.03, not 1). Chapter 09's
 * reference has REFERENCE_SPP samples per pixel. */
enum { RENDERS = 64, REFERENCE_SPP = 2048 };

/* A sum of weights may differ from 1 by float rounding: a few ulps per
 * strategy, over at most a dozen strategies. */
static const double WEIGHT_SUM_TOLERANCE = 1e-4;

enum { SIZE = 16 };

/* Chapter 09's best rung, spp samples per pixel: mean and standard error. */
static estimate_image path_traced(const pt_scene *sc, const camera *cam, int spp, uint64_t seed)
{
    path_tracer pt = path_tracer_defaults(sc);
    pt.integrator = PT_MIS;
    pt.russian_roulette = RR_THROUGHPUT;
    return render_estimate(&pt, cam, spp, test_seed(seed), 2);
}

/* `renders` independent BDPT images of spp samples, averaged: the standard
 * error per pixel from their spread (the splats of light tracing land on
 * any pixel, so the per-pixel sample variance of one render misses them). */
static estimate_image bidirectional(const bdpt *b, int spp, int renders, uint64_t seed)
{
    const camera *cam = b->cam;
    size_t n = (size_t)cam->width * (size_t)cam->height * 3;
    welford *w = calloc(n, sizeof *w);
    assert_non_null(w);
    estimate_image total;
    memset(&total, 0, sizeof total);
    for (int k = 0; k < renders; k++) {
        estimate_image e;
        assert_true(bdpt_render(b, spp, test_seed(seed) + (uint64_t)k * 7919u, 2, true, &e));
        for (size_t i = 0; i < n; i++)
            welford_add(&w[i], e.mean.rgb[i]);
        counters_add(&total.counters, &e.counters);
        estimate_image_free(&e);
    }
    total.mean = image_make(cam->width, cam->height);
    total.standard_error = image_make(cam->width, cam->height);
    for (size_t i = 0; i < n; i++) {
        total.mean.rgb[i] = (float)welford_mean(&w[i]);
        total.standard_error.rgb[i] = (float)welford_standard_error(&w[i]);
    }
    total.spp = (long)spp * renders;
    free(w);
    return total;
}

/* BDPT (a) against chapter 09 (b). */
static image_check bdpt_check(const estimate_image *a, const estimate_image *b)
{
    return check_agree(&a->mean, &a->standard_error, &b->mean, &b->standard_error);
}

/* ---- against chapter 09 -------------------------------------------------------- */

static void test_converges_to_path_tracing_on_the_cornell_box(void **state)
{
    (void)state;
    exercise_checks("bdpt_connect");
    pt_scene sc;
    pt_scene_build_cornell_box(&sc);
    camera cam = pt_scene_camera(&sc, SIZE, SIZE);
    estimate_image reference = path_traced(&sc, &cam, REFERENCE_SPP, 11);
    bdpt b = bdpt_defaults(&sc, &cam);
    estimate_image e = bidirectional(&b, 4, RENDERS, 12);
    image_check c = bdpt_check(&e, &reference);
    print_message("BDPT against chapter 09: p = %.3g (image mean z = %.2f, chi-square %.1f on %d)\n", c.p, c.z, c.chi2,
                  c.dof);
    assert_image_check(c, 1, "BDPT against chapter 09");
    assert_int_equal(e.counters.nonfinite_samples, 0);
    /* The twin: the cosine at the light left out of the joins (s = 1, t = 1) */
    b.fault = BDPT_FAULT_NO_LIGHT_COSINE;
    estimate_image twin = bidirectional(&b, 4, RENDERS, 12);
    image_check t = bdpt_check(&twin, &reference);
    print_message("twin, no cosine at the light: p = %.3g (z = %.2f)\n", t.p, t.z);
    assert_true(t.p < image_check_alpha(1));
    estimate_image_free(&twin);
    estimate_image_free(&e);
    estimate_image_free(&reference);
    pt_scene_free(&sc);
}

/* The Cornell room whose floor, ceiling and back wall glow as well (a
 * little: L_e = 0.5 against the lamp's 17), with a white cube in the middle
 * to cast shadows. Camera paths alone reach an emitter only by hitting one;
 * in the Cornell box itself its small lamp makes that so rare in the
 * shadows that 64 renders often see none there (a mean and a standard
 * error of 0: no statistic is fair to that). Here a third of every
 * bounce's directions end on an emitter, and both families' estimates are
 * well-behaved. */
static void build_glowing_room(pt_scene *sc)
{
    pt_scene_init(sc);
    int white = pt_scene_add_material(sc, pt_emitter(PT_CORNELL_WHITE, vec3_splat(0.5f)));
    int red = pt_scene_add_material(sc, pt_diffuse(PT_CORNELL_RED));
    int green = pt_scene_add_material(sc, pt_diffuse(PT_CORNELL_GREEN));
    int light = pt_scene_add_material(sc, pt_emitter(vec3_splat(0.65f), PT_CORNELL_LIGHT));
    int cube = pt_scene_add_material(sc, pt_diffuse(vec3_splat(0.7f)));
    pt_scene_add_cornell_room(sc, white, red, green, light);
    /* a cube from (180, 0, 180) to (380, 200, 380): four sides and the top,
     * counter-clockwise seen from outside */
    vec3 p[8];
    for (int k = 0; k < 8; k++)
        p[k] = vec3_make(k & 1 ? 380.0f : 180.0f, k & 2 ? 200.0f : 0.0f, k & 4 ? 380.0f : 180.0f);
    pt_scene_add_quad(sc, p[2], p[6], p[7], p[3], cube); /* top, +y */
    pt_scene_add_quad(sc, p[0], p[2], p[3], p[1], cube); /* front, -z */
    pt_scene_add_quad(sc, p[5], p[7], p[6], p[4], cube); /* back, +z */
    pt_scene_add_quad(sc, p[4], p[6], p[2], p[0], cube); /* left, -x */
    pt_scene_add_quad(sc, p[1], p[3], p[7], p[5], cube); /* right, +x */
    pt_scene_finish(sc);
}

/* Each strategy family alone, unweighted, is an unbiased estimator of the
 * paths it can make: light tracing (t = 1, every s) and camera paths that
 * hit the light (s = 0, every t) each make every path of a diffuse scene,
 * so each alone converges to the whole image. */
static void test_light_tracing_alone_and_camera_paths_alone(void **state)
{
    (void)state;
    pt_scene sc;
    build_glowing_room(&sc);
    camera cam = pt_scene_camera(&sc, SIZE, SIZE);
    estimate_image reference = path_traced(&sc, &cam, REFERENCE_SPP, 21);
    bdpt b = bdpt_defaults(&sc, &cam);
    b.unweighted = true;
    b.only_t = 1;
    estimate_image light = bidirectional(&b, 4, RENDERS, 22);
    image_check c_light = bdpt_check(&light, &reference);
    b.only_t = -1;
    b.only_s = 0;
    estimate_image eye = bidirectional(&b, 64, RENDERS, 23);
    image_check c_eye = bdpt_check(&eye, &reference);
    print_message("light tracing alone: p = %.3g, camera paths alone: p = %.3g\n", c_light.p, c_eye.p);
    /* two image checks in this test */
    assert_image_check(c_light, 2, "light tracing alone");
    assert_image_check(c_eye, 2, "camera paths alone");
    /* The twins: light tracing without the cosine at the light vertex, and
     * camera paths cut after one bounce, are caught. */
    b.only_s = -1;
    b.only_t = 1;
    b.fault = BDPT_FAULT_NO_LIGHT_COSINE;
    estimate_image light_twin = bidirectional(&b, 4, RENDERS, 22);
    image_check t_light = bdpt_check(&light_twin, &reference);
    b.fault = BDPT_FAULT_NONE;
    b.only_t = -1;
    b.only_s = 0;
    b.max_depth = 1;
    estimate_image eye_twin = bidirectional(&b, 64, RENDERS, 23);
    image_check t_eye = bdpt_check(&eye_twin, &reference);
    print_message("twins: light tracing without the light's cosine p = %.3g, camera paths of one bounce p = %.3g\n",
                  t_light.p, t_eye.p);
    assert_true(t_light.p < image_check_alpha(2));
    assert_true(t_eye.p < image_check_alpha(2));
    estimate_image_free(&light);
    estimate_image_free(&eye);
    estimate_image_free(&light_twin);
    estimate_image_free(&eye_twin);
    estimate_image_free(&reference);
    pt_scene_free(&sc);
}

/* ---- the weights ------------------------------------------------------------------
 * A path of n vertices can be made by n strategies; their MIS weights must
 * sum to one, or the estimate counts the path too much or too little. The
 * paths here are built by hand: an eye path through a random pixel, a few
 * cosine-sampled bounces, then a random point on the light (visibility does
 * not enter the weights). Each strategy then sees the path as its own two
 * subpaths, with the densities its random walks would have stored. */

static bdpt_vertex surface_vertex(const hit_record *h)
{
    bdpt_vertex v;
    memset(&v, 0, sizeof v);
    v.kind = BDPT_VERTEX_SURFACE;
    v.point = h->point;
    v.point_error = h->point_error;
    v.normal = h->normal_shading;
    v.normal_geometric = h->normal_geometric;
    v.material = h->material_id;
    v.front_face = h->front_face;
    return v;
}

/* Builds x_0 (light) .. x_{n-1} (eye) into path; false if the walk missed
 * or some density is zero (the path is then of no strategy). */
static bool random_path(const bdpt *b, int n, pcg32 *rng, bdpt_vertex *path)
{
    const pt_scene *sc = b->scene;
    ray_counters counters;
    memset(&counters, 0, sizeof counters);
    bdpt_vertex eye_side[BDPT_MAX_VERTICES];
    memset(&eye_side[0], 0, sizeof eye_side[0]);
    eye_side[0].kind = BDPT_VERTEX_CAMERA;
    eye_side[0].point = b->cam->eye;
    eye_side[0].normal = b->cam->forward;
    ray r = camera_ray(b->cam, pcg32_float(rng) * (float)b->cam->width, pcg32_float(rng) * (float)b->cam->height);
    for (int k = 1; k < n - 1; k++) {
        hit_record h;
        if (!pt_scene_intersect(sc, r, &h, &counters))
            return false;
        eye_side[k] = surface_vertex(&h);
        vec3 w = frame_to_world(h.normal_shading, sample_cosine_hemisphere(vec2_make(pcg32_float(rng), pcg32_float(rng))));
        r = ray_spawn(h.point, h.point_error, h.normal_geometric, w);
    }
    bdpt_vertex light;
    memset(&light, 0, sizeof light);
    light.kind = BDPT_VERTEX_LIGHT;
    if (!pt_scene_sample_emitter(sc, pcg32_float(rng), pcg32_float(rng), pcg32_float(rng), &light.point,
                                 &light.point_error, &light.normal, &light.material))
        return false;
    light.normal_geometric = light.normal;
    light.front_face = true;
    path[0] = light;
    for (int k = 0; k < n - 1; k++)
        path[n - 1 - k] = eye_side[k];
    /* every density along the path, both ways, must be positive */
    bdpt_vertex forward[2 * BDPT_MAX_VERTICES], backward[2 * BDPT_MAX_VERTICES];
    for (int i = 0; i < n; i++) {
        forward[i] = path[i];
        backward[i] = path[n - 1 - i];
    }
    bdpt_subpath_fill_pdfs(b, forward, n);
    bdpt_subpath_fill_pdfs(b, backward, n);
    for (int i = 0; i < n; i++)
        if (!(forward[i].pdf_fwd > 0.0f) || !(backward[i].pdf_fwd > 0.0f))
            return false;
    return true;
}

/* The sum over s of strategy (s, n - s)'s weight for this path. */
static double weight_sum(const bdpt *b, const bdpt_vertex *path, int n)
{
    double sum = 0.0;
    for (int s = 0; s <= n - 1; s++) {
        int t = n - s;
        bdpt_vertex light[BDPT_MAX_VERTICES], camera[BDPT_MAX_VERTICES];
        for (int i = 0; i < s; i++)
            light[i] = path[i];
        for (int j = 0; j < t; j++)
            camera[j] = path[n - 1 - j];
        if (s == 0)
            camera[t - 1].kind = BDPT_VERTEX_SURFACE; /* the eye path hit the light */
        bdpt_subpath_fill_pdfs(b, light, s);
        bdpt_subpath_fill_pdfs(b, camera, t);
        sum += bdpt_mis_weight(b, light, s, camera, t);
    }
    return sum;
}

static void test_weights_of_all_strategies_sum_to_one(void **state)
{
    (void)state;
    pt_scene sc;
    pt_scene_build_veach(&sc); /* glossy plates: pdfs that are not symmetric */
    pt_scene sc2;
    pt_scene_build_cornell_box(&sc2);
    const pt_scene *scenes[2] = {&sc2, &sc};
    for (int k = 0; k < 2; k++) {
        camera cam = pt_scene_camera(scenes[k], SIZE, SIZE);
        bdpt b = bdpt_defaults(scenes[k], &cam);
        pcg32 rng = pcg32_for_pixel(test_seed(31), (uint64_t)k);
        for (int heuristic = 0; heuristic < 2; heuristic++) {
            b.heuristic = heuristic == 0 ? BDPT_POWER : BDPT_BALANCE;
            /* the Veach scene is open to a black world: long paths are rare */
            int longest = k == 0 ? 7 : 4;
            for (int n = 2; n <= longest; n++) {
                int tested = 0;
                double worst = 0.0, worst_twin = 0.0;
                for (int attempt = 0; attempt < 20000 && tested < 50; attempt++) {
                    bdpt_vertex path[2 * BDPT_MAX_VERTICES];
                    if (!random_path(&b, n, &rng, path))
                        continue;
                    tested++;
                    b.fault = BDPT_FAULT_NONE;
                    worst = fmax(worst, fabs(weight_sum(&b, path, n) - 1.0));
                    /* The twin: one join's pdf left per unit solid angle */
                    b.fault = BDPT_FAULT_SOLID_ANGLE_PDF;
                    worst_twin = fmax(worst_twin, fabs(weight_sum(&b, path, n) - 1.0));
                    b.fault = BDPT_FAULT_NONE;
                }
                print_message("%s, %s, n = %d: %d paths, largest |sum - 1| %.2g (twin %.2g)\n",
                              k == 0 ? "cornell" : "veach", heuristic == 0 ? "power" : "balance", n, tested, worst,
                              worst_twin);
                assert_true(tested >= 10);
                assert_true(worst <= WEIGHT_SUM_TOLERANCE);
                assert_true(worst_twin > 0.01);
            }
        }
    }
    pt_scene_free(&sc);
    pt_scene_free(&sc2);
}

/* ---- the join ----------------------------------------------------------------------
 * bdpt_connect on vertices of the Cornell box built by hand, against the
 * formula written out in double: a light vertex y_0 (beta = L_e / p_A, the
 * light's factor 1 in front), a point of the back wall reached from it,
 * a point of the floor seen from the eye; every surface is diffuse, so
 * each BSDF is rho / pi:
 *   y_0 -> floor:  beta(y_0) 1 G f_floor beta(z)
 *   wall -> floor: beta(w) f_wall G f_floor beta(z)
 *   y_0 -> a point behind the light: 0 (it emits from its front only)
 * Float rounding of a dozen operations, each at most 6e-8 relative: 1e-5
 * relative leaves room and still catches any missing factor. */
static bdpt_vertex vertex_hit_by(const pt_scene *sc, ray r, vec3 beta)
{
    hit_record h;
    ray_counters counters;
    memset(&counters, 0, sizeof counters);
    assert_true(pt_scene_intersect(sc, r, &h, &counters));
    bdpt_vertex v = surface_vertex(&h);
    v.beta = beta;
    return v;
}

static double geometry_term(const bdpt_vertex *a, const bdpt_vertex *c)
{
    double d[3] = {(double)c->point.x - a->point.x, (double)c->point.y - a->point.y, (double)c->point.z - a->point.z};
    double d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    double cos_a = fabs(d[0] * a->normal.x + d[1] * a->normal.y + d[2] * a->normal.z) / sqrt(d2);
    double cos_c = fabs(d[0] * c->normal.x + d[1] * c->normal.y + d[2] * c->normal.z) / sqrt(d2);
    return cos_a * cos_c / d2;
}

/* bdpt_connect() computes in float what the test computes in double:
 * JOIN_RELATIVE covers a few float roundings of each factor (2^-24 each,
 * a few dozen operations); JOIN_ABSOLUTE only lets an expected 0 be met
 * by a float 0 or denormal. A term left out or doubled (a cosine, G, a
 * beta) is off by far more. */
static const double JOIN_RELATIVE = 1e-5, JOIN_ABSOLUTE = 1e-30;

static void assert_join(const char *what, vec3 got, const double expected[3])
{
    double g[3] = {got.x, got.y, got.z};
    for (int k = 0; k < 3; k++)
        if (!(fabs(g[k] - expected[k]) <= JOIN_RELATIVE * fabs(expected[k]) + JOIN_ABSOLUTE)) {
            print_error("%s: bdpt_connect gave (%.6g, %.6g, %.6g), expected beta f G f beta = (%.6g, %.6g, %.6g)\n",
                        what, g[0], g[1], g[2], expected[0], expected[1], expected[2]);
            fail();
        }
}

static void test_connection_is_beta_f_g_f_beta(void **state)
{
    (void)state;
    exercise_checks("bdpt_connect");
    pt_scene sc;
    pt_scene_build_cornell_box(&sc);
    camera cam = pt_scene_camera(&sc, SIZE, SIZE);
    bdpt b = bdpt_defaults(&sc, &cam);
    /* y_0 on the lamp */
    bdpt_vertex y0;
    memset(&y0, 0, sizeof y0);
    y0.kind = BDPT_VERTEX_LIGHT;
    assert_true(pt_scene_sample_emitter(&sc, 0.3f, 0.4f, 0.6f, &y0.point, &y0.point_error, &y0.normal, &y0.material));
    y0.normal_geometric = y0.normal;
    y0.front_face = true;
    vec3 emission = sc.materials[y0.material].emission;
    y0.beta = vec3_scale(emission, 1.0f / pt_scene_emitter_pdf_area(&sc, y0.material));
    /* the eye, and the floor it sees at the bottom of the image */
    bdpt_vertex eye;
    memset(&eye, 0, sizeof eye);
    eye.kind = BDPT_VERTEX_CAMERA;
    eye.point = cam.eye;
    eye.normal = eye.normal_geometric = cam.forward;
    eye.beta = vec3_splat(1.0f);
    bdpt_vertex floor = vertex_hit_by(&sc, camera_ray(&cam, 0.5f * SIZE, SIZE - 0.5f), vec3_make(0.25f, 0.5f, 0.75f));
    assert_true(floor.normal.y > 0.99f);
    /* the back wall, reached from y_0 */
    vec3 towards_wall = vec3_normalize(vec3_sub(vec3_make(278.0f, 450.0f, 559.2f), y0.point));
    bdpt_vertex wall = vertex_hit_by(&sc, ray_spawn(y0.point, y0.point_error, y0.normal_geometric, towards_wall),
                                     vec3_make(0.9f, 0.6f, 0.3f));
    assert_true(wall.normal.z < -0.99f);
    vec3 rho_floor = sc.materials[floor.material].albedo, rho_wall = sc.materials[wall.material].albedo;
    double expected[3];
    /* y_0 -> floor */
    double g = geometry_term(&y0, &floor);
    expected[0] = (double)y0.beta.x * g * rho_floor.x / PI * floor.beta.x;
    expected[1] = (double)y0.beta.y * g * rho_floor.y / PI * floor.beta.y;
    expected[2] = (double)y0.beta.z * g * rho_floor.z / PI * floor.beta.z;
    assert_join("the light's point joined to the floor (s = 1)", bdpt_connect(&b, &y0, NULL, &floor, &eye), expected);
    /* wall -> floor */
    g = geometry_term(&wall, &floor);
    expected[0] = (double)wall.beta.x * rho_wall.x / PI * g * rho_floor.x / PI * floor.beta.x;
    expected[1] = (double)wall.beta.y * rho_wall.y / PI * g * rho_floor.y / PI * floor.beta.y;
    expected[2] = (double)wall.beta.z * rho_wall.z / PI * g * rho_floor.z / PI * floor.beta.z;
    assert_join("the back wall joined to the floor (s = 2)", bdpt_connect(&b, &wall, &y0, &floor, &eye), expected);
    /* behind the light: above it, facing it, reached from the floor */
    bdpt_vertex above = floor;
    above.point = vec3_add(y0.point, vec3_make(10.0f, 5.0f, -10.0f));
    above.normal = above.normal_geometric = vec3_make(0.0f, -1.0f, 0.0f);
    expected[0] = expected[1] = expected[2] = 0.0;
    assert_join("the light's point joined to a point behind the light", bdpt_connect(&b, &y0, NULL, &above, &floor),
                expected);
    pt_scene_free(&sc);
}

/* ---- threads, NaN, refusals ------------------------------------------------------ */

static void test_same_image_for_one_and_two_threads(void **state)
{
    (void)state;
    pt_scene sc;
    pt_scene_build_cornell_box(&sc);
    camera cam = pt_scene_camera(&sc, SIZE, SIZE);
    bdpt b = bdpt_defaults(&sc, &cam);
    estimate_image one, two;
    assert_true(bdpt_render(&b, 4, 41, 1, true, &one));
    assert_true(bdpt_render(&b, 4, 41, 2, true, &two));
    assert_memory_equal(one.mean.rgb, two.mean.rgb, SIZE * SIZE * 3 * sizeof(float));
    estimate_image_free(&one);
    estimate_image_free(&two);
    pt_scene_free(&sc);
}

/* A light whose emission is infinite makes every path through it Inf or
 * NaN: they are counted and dropped, and the image stays finite. */
static void test_nonfinite_samples_are_counted_and_dropped(void **state)
{
    (void)state;
    pt_scene sc;
    pt_scene_build_cornell_box(&sc);
    for (int i = 0; i < sc.material_count; i++)
        if (sc.materials[i].emission.x > 0.0f)
            sc.materials[i].emission.x = INFINITY;
    camera cam = pt_scene_camera(&sc, 8, 8);
    bdpt b = bdpt_defaults(&sc, &cam);
    estimate_image e;
    assert_true(bdpt_render(&b, 4, 51, 2, true, &e));
    print_message("non-finite samples dropped: %llu\n", (unsigned long long)e.counters.nonfinite_samples);
    assert_true(e.counters.nonfinite_samples > 0);
    for (int i = 0; i < 8 * 8 * 3; i++)
        assert_true(isfinite(e.mean.rgb[i]));
    estimate_image_free(&e);
    pt_scene_free(&sc);
}

static void test_delta_materials_are_refused(void **state)
{
    (void)state;
    pt_scene sc;
    char err[256];
    pt_scene_build_cornell_box_materials(&sc);
    assert_false(bdpt_supports(&sc, err, sizeof err));
    assert_non_null(strstr(err, "glass"));
    pt_scene_free(&sc);
    pt_scene_build_cornell_box(&sc);
    assert_true(bdpt_supports(&sc, err, sizeof err));
    pt_scene_free(&sc);
    bdpt_scene_build_ceiling_lamp(&sc);
    assert_true(bdpt_supports(&sc, err, sizeof err));
    pt_scene_free(&sc);
}

/* The camera's sampling density and its projection agree: a ray through
 * pixel position (px, py) projects back there, and the density integrates
 * to one over the image (a Monte Carlo sum over uniform directions). */
static void test_camera_projection_and_density(void **state)
{
    (void)state;
    pt_scene sc;
    pt_scene_build_cornell_box(&sc);
    camera cam = pt_scene_camera(&sc, 20, 10);
    pcg32 rng = pcg32_for_pixel(test_seed(61), 0);
    for (int i = 0; i < 1000; i++) {
        float px = pcg32_float(&rng) * 20.0f, py = pcg32_float(&rng) * 10.0f, qx, qy;
        ray r = camera_ray(&cam, px, py);
        assert_true(bdpt_camera_project(&cam, ray_at(r, 100.0f), &qx, &qy));
        assert_close(qx, px, 1e-3);
        assert_close(qy, py, 1e-3);
    }
    /* integral of pdf over the sphere = 1: uniform sphere directions, 4 pi / N sum */
    welford w = {0};
    for (int i = 0; i < 200000; i++) {
        float z = 1.0f - 2.0f * pcg32_float(&rng), phi = 2.0f * (float)PI * pcg32_float(&rng);
        float rxy = sqrtf(fmaxf(0.0f, 1.0f - z * z));
        vec3 d = vec3_make(rxy * cosf(phi), rxy * sinf(phi), z);
        welford_add(&w, 4.0 * PI * bdpt_camera_pdf_direction(&cam, d));
    }
    print_message("integral of the camera's density: %.4f +- %.4f\n", welford_mean(&w), welford_standard_error(&w));
    assert_close(welford_mean(&w), 1.0, 5.0 * welford_standard_error(&w));
    pt_scene_free(&sc);
}

/* The shipped scene file is the built-in scene: the same triangles, bit for
 * bit, materials, lights and camera (tests/pt_scene_check.h), so every
 * render of it is the built-in scene's. */
static void test_scene_file_is_the_built_in_scene(void **state)
{
    (void)state;
    pt_scene from_file, built_in;
    load_pt_scene_file(&from_file, "chapters/11-bidirectional/scenes/ceiling-lamp.scene");
    bdpt_scene_build_ceiling_lamp(&built_in);
    assert_same_pt_scene(&from_file, &built_in);
    pt_scene_free(&from_file);
    pt_scene_free(&built_in);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_scene_file_is_the_built_in_scene),
        cmocka_unit_test(test_weights_of_all_strategies_sum_to_one),
        cmocka_unit_test(test_connection_is_beta_f_g_f_beta),
        cmocka_unit_test(test_camera_projection_and_density),
        cmocka_unit_test(test_converges_to_path_tracing_on_the_cornell_box),
        cmocka_unit_test(test_light_tracing_alone_and_camera_paths_alone),
        cmocka_unit_test(test_same_image_for_one_and_two_threads),
        cmocka_unit_test(test_nonfinite_samples_are_counted_and_dropped),
        cmocka_unit_test(test_delta_materials_are_refused),
    };
    return cmocka_run_group_tests_name("ch11 bidirectional path tracing", tests, NULL, NULL);
}
