/* test_ch01.c -- ray casting: each shape against its closed form, the hard
 * cases the chapter text names, and Blinn-Phong against the formula. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "01-ray-casting/ray_casting.h"
#include "01-ray-casting/scene.h"
#include "01-ray-casting/shapes.h"
#include "effects.h"
#include "mesh.h"
#include "render.h"
#include "scene_file.h"
#include "test_support.h"

static ray ray_from(float ox, float oy, float oz, float dx, float dy, float dz)
{
    return ray_make(vec3_make(ox, oy, oz), vec3_make(dx, dy, dz));
}

/* ---- eye rays ---------------------------------------------------------------
 * A camera at the origin looking down -z with a 90 degree field of view
 * (tan 45 = 1) and a 4x2 image: the plane at distance 1 spans x in [-2, 2],
 * y in [-1, 1]. The centre of pixel (0, 0), at (0.5, 0.5), is the point
 * (-1.5, 0.5, -1) of that plane; the image's centre, (2, 1), is straight
 * ahead. */
/* A float direction normalized by vec3_normalize is within a few ulps of
 * the exact one: 1e-6 holds that, and a ray through the wrong point of the
 * pixel (its corner instead of its centre: more than 0.01 off) fails it. */
static const double EYE_RAY_DIRECTION_TOLERANCE = 1e-6;

static void test_eye_ray_goes_through_the_pixel_centre(void **state)
{
    (void)state;
    exercise_checks("eye_ray");
    camera cam = camera_look_at(vec3_make(0, 0, 0), vec3_make(0, 0, -1), vec3_make(0, 1, 0), 90.0f, 4, 2);
    ray corner = camera_ray(&cam, 0.5f, 0.5f);
    float length = sqrtf(1.5f * 1.5f + 0.5f * 0.5f + 1.0f);
    assert_close(corner.origin.x, 0.0, 0.0);
    assert_close(corner.direction.x, -1.5 / length, EYE_RAY_DIRECTION_TOLERANCE);
    assert_close(corner.direction.y, 0.5 / length, EYE_RAY_DIRECTION_TOLERANCE);
    assert_close(corner.direction.z, -1.0 / length, EYE_RAY_DIRECTION_TOLERANCE);
    ray centre = camera_ray(&cam, 2.0f, 1.0f);
    assert_close(centre.direction.x, 0.0, EYE_RAY_DIRECTION_TOLERANCE);
    assert_close(centre.direction.y, 0.0, EYE_RAY_DIRECTION_TOLERANCE);
    assert_close(centre.direction.z, -1.0, EYE_RAY_DIRECTION_TOLERANCE);
    /* The bottom-right pixel's centre, (3.5, 1.5): right and down. */
    ray bottom_right = camera_ray(&cam, 3.5f, 1.5f);
    assert_close(bottom_right.direction.x, 1.5 / length, EYE_RAY_DIRECTION_TOLERANCE);
    assert_close(bottom_right.direction.y, -0.5 / length, EYE_RAY_DIRECTION_TOLERANCE);
}

/* ---- ray-sphere ----------------------------------------------------------- */

static void test_sphere_hit_from_outside(void **state)
{
    (void)state;
    exercise_checks("ray_sphere");
    sphere s = {vec3_make(0, 0, 0), 1.0f};
    hit_record hit;
    assert_true(sphere_intersect(&s, ray_from(0, 0, -5, 0, 0, 1), &hit));
    assert_close(hit.t, 4.0, 1e-6);
    assert_true(hit.front_face);
    assert_close(hit.normal_geometric.z, -1.0, 1e-6);
    assert_close(hit.point.z, -1.0, 1e-6);
}

static void test_sphere_hit_from_inside_returns_the_exit(void **state)
{
    (void)state;
    exercise_checks("ray_sphere");
    sphere s = {vec3_make(0, 0, 0), 2.0f};
    hit_record hit;
    assert_true(sphere_intersect(&s, ray_from(0, 0, 0, 1, 0, 0), &hit));
    assert_close(hit.t, 2.0, 1e-6);
    assert_false(hit.front_face);
    assert_close(hit.normal_geometric.x, -1.0, 1e-6); /* faces the ray: inwards */
}

static void test_sphere_tangent_and_miss(void **state)
{
    (void)state;
    exercise_checks("ray_sphere");
    sphere s = {vec3_make(0, 0, 0), 1.0f};
    hit_record hit;
    /* Tangent: the ray grazes the sphere at (1, 0, 0). */
    assert_true(sphere_intersect(&s, ray_from(1, 0, -5, 0, 0, 1), &hit));
    assert_close(hit.t, 5.0, 1e-3);
    assert_false(sphere_intersect(&s, ray_from(1.001f, 0, -5, 0, 0, 1), &hit));
    /* Behind the origin: no hit for t > 0. */
    assert_false(sphere_intersect(&s, ray_from(0, 0, 5, 0, 0, 1), &hit));
    /* A direction that is not unit length: t is in units of |d|. */
    assert_true(sphere_intersect(&s, ray_from(0, 0, -5, 0, 0, 2), &hit));
    assert_close(hit.t, 2.0, 1e-6);
}

/* A radius-1 sphere 1e4 away: t = 9999. In float, the lecture's b^2 - 4ac
 * cancels to nothing (see shapes.c); the robust form keeps it. */
static void test_far_small_sphere_is_hit_at_the_right_distance(void **state)
{
    (void)state;
    exercise_checks("ray_sphere");
    sphere s = {vec3_make(0, 0, 1e4f), 1.0f};
    hit_record hit;
    assert_true(sphere_intersect(&s, ray_from(0, 0, 0, 0, 0, 1), &hit));
    assert_close(hit.t, 9999.0, 1e-3);
    /* Slightly off-centre too: the hit is at 1e4 - sqrt(1 - 0.6^2) = 9999.2. */
    assert_true(sphere_intersect(&s, ray_from(0.6f, 0, 0, 0, 0, 1), &hit));
    assert_close(hit.t, 9999.2, 2e-3);
}

/* The twin: the same case through the lecture's formula is wrong, which is
 * what the test above guards against. */
static void test_naive_quadratic_fails_on_the_far_small_sphere(void **state)
{
    (void)state;
    sphere s = {vec3_make(0, 0, 1e4f), 1.0f};
    hit_record hit;
    bool found = sphere_intersect_naive(&s, ray_from(0, 0, 0, 0, 0, 1), &hit);
    assert_true(!found || fabsf(hit.t - 9999.0f) > 0.5f);
}

/* ---- ray-plane ------------------------------------------------------------ */

static void test_plane_hit_and_parallel_miss(void **state)
{
    (void)state;
    plane p = {vec3_make(0, 1, 0), vec3_make(0, 1, 0)};
    hit_record hit;
    assert_true(plane_intersect(&p, ray_from(0, 3, 0, 0, -1, 0), &hit));
    assert_close(hit.t, 2.0, 1e-6);
    assert_true(hit.front_face);
    assert_true(plane_intersect(&p, ray_from(0, -3, 0, 0, 1, 0), &hit)); /* from below */
    assert_false(hit.front_face);
    assert_false(plane_intersect(&p, ray_from(0, 3, 0, 1, 0, 0), &hit));
    assert_false(plane_intersect(&p, ray_from(0, 1, 0, 1, 0, 0), &hit)); /* in the plane */
}

/* ---- ray-triangle (Moller-Trumbore) --------------------------------------- */

static const triangle unit_triangle = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};

static void test_triangle_hit_point_is_the_barycentric_combination(void **state)
{
    (void)state;
    exercise_checks("moller_trumbore");
    triangle tri = {{1, 2, 3}, {4, 2.5f, 3}, {2, 5, 4}};
    pcg32 rng = pcg32_for_pixel(1, 1);
    for (int i = 0; i < 1000; i++) {
        /* A point inside by its barycentrics, and a ray aimed at it. */
        float b1 = pcg32_float(&rng), b2 = pcg32_float(&rng);
        if (b1 + b2 > 1) {
            b1 = 1 - b1;
            b2 = 1 - b2;
        }
        vec3 target = vec3_add(vec3_add(vec3_scale(tri.p0, 1 - b1 - b2), vec3_scale(tri.p1, b1)),
                               vec3_scale(tri.p2, b2));
        vec3 origin = vec3_make(pcg32_float(&rng) * 4 - 2, pcg32_float(&rng) * 4 - 2, -5);
        ray r = ray_make(origin, vec3_sub(target, origin));
        hit_record hit;
        assert_true(triangle_intersect(&tri, r, &hit));
        assert_close(hit.t, 1.0, 1e-5);
        assert_close(hit.u, b1, 1e-5);
        assert_close(hit.v, b2, 1e-5);
        vec3 along_ray = ray_at(r, hit.t);
        assert_close(vec3_length(vec3_sub(hit.point, along_ray)), 0.0, 1e-5);
        assert_close(vec3_length(vec3_sub(hit.point, target)), 0.0, 1e-5);
    }
}

static void test_triangle_ray_in_its_plane_gives_no_hit_and_no_nan(void **state)
{
    (void)state;
    hit_record hit;
    memset(&hit, 0, sizeof hit);
    /* In the plane z = 0, straight through the triangle: the lecture's test
     * and the watertight one. */
    assert_false(triangle_intersect(&unit_triangle, ray_from(-1, 0.25f, 0, 1, 0, 0), &hit));
    assert_false(triangle_intersect(&unit_triangle, ray_from(0.2f, 0.2f, 0, 1, 1, 0), &hit));
    assert_false(triangle_intersect_watertight_hit(&unit_triangle, ray_from(-1, 0.25f, 0, 1, 0, 0), &hit));
    assert_false(triangle_intersect_watertight_hit(&unit_triangle, ray_from(0.2f, 0.2f, 0, 1, 1, 0), &hit));
    assert_false(isnan(hit.t)); /* the record was not touched */
}

static void test_tiny_triangle_is_hit(void **state)
{
    (void)state;
    exercise_checks("moller_trumbore");
    /* Side 2e-4: its determinant is ~1e-8, which a "|det| < 1e-8" cut-off
     * would refuse. */
    const float side = 2e-4f;
    triangle tiny = {{0, 0, 0}, {side, 0, 0}, {0, side, 0}};
    hit_record hit;
    assert_true(triangle_intersect(&tiny, ray_from(side / 4, side / 4, -1, 0, 0, 1), &hit));
    assert_close(hit.t, 1.0, 1e-6);
    assert_false(triangle_intersect(&tiny, ray_from(side, side, -1, 0, 0, 1), &hit));
    /* the watertight test has no cut-off either */
    assert_true(triangle_intersect_watertight_hit(&tiny, ray_from(side / 4, side / 4, -1, 0, 0, 1), &hit));
    assert_close(hit.t, 1.0, 1e-6);
    assert_false(triangle_intersect_watertight_hit(&tiny, ray_from(side, side, -1, 0, 0, 1), &hit));
}

static void test_triangle_back_face_and_outside(void **state)
{
    (void)state;
    exercise_checks("moller_trumbore");
    hit_record hit;
    assert_true(triangle_intersect(&unit_triangle, ray_from(0.25f, 0.25f, 1, 0, 0, -1), &hit));
    assert_true(hit.front_face); /* counter-clockwise seen from +z */
    assert_true(triangle_intersect(&unit_triangle, ray_from(0.25f, 0.25f, -1, 0, 0, 1), &hit));
    assert_false(hit.front_face);
    assert_close(hit.normal_geometric.z, -1.0, 1e-6);
    assert_false(triangle_intersect(&unit_triangle, ray_from(0.6f, 0.6f, 1, 0, 0, -1), &hit));
    /* the same with the watertight test, which accepts both windings */
    assert_true(triangle_intersect_watertight_hit(&unit_triangle, ray_from(0.25f, 0.25f, 1, 0, 0, -1), &hit));
    assert_true(hit.front_face);
    assert_true(triangle_intersect_watertight_hit(&unit_triangle, ray_from(0.25f, 0.25f, -1, 0, 0, 1), &hit));
    assert_false(hit.front_face);
    assert_false(triangle_intersect_watertight_hit(&unit_triangle, ray_from(0.6f, 0.6f, 1, 0, 0, -1), &hit));
}

/* ---- watertightness: rays through shared edges and vertices --------------- */

typedef bool (*triangle_test_fn)(const triangle *, const ray *, float *, float *, float *);

/* Shoots `count` rays from outside a closed icosphere at its vertices and at
 * points on its edges, and counts the rays that none of the triangles around
 * that vertex or edge reports as hit: leaks through a closed surface. */
static long count_leaks(triangle_test_fn test, int count)
{
    mesh m;
    mesh_init(&m);
    mesh_icosphere(&m, vec3_make(0.3f, -0.2f, 0.1f), 1.0f, 3, -1);
    pcg32 rng = pcg32_for_pixel(test_seed(1313), 0);
    long leaks = 0;
    for (int i = 0; i < count; i++) {
        int face = (int)pcg32_bounded(&rng, (uint32_t)m.face_count);
        int k = (int)pcg32_bounded(&rng, 3);
        int a = m.faces[face].position[k], b = m.faces[face].position[(k + 1) % 3];
        vec3 target = m.positions[a];
        bool on_edge = i % 2 == 1;
        if (on_edge) { /* a point along the edge a-b, as exactly as floats allow */
            float s = pcg32_float(&rng);
            target = vec3_add(vec3_scale(m.positions[a], 1.0f - s), vec3_scale(m.positions[b], s));
        }
        /* From outside, above the surface there, slightly tilted. */
        vec3 outward = vec3_normalize(vec3_sub(target, vec3_make(0.3f, -0.2f, 0.1f)));
        vec3 tilt = vec3_scale(vec3_make(pcg32_float(&rng) - 0.5f, pcg32_float(&rng) - 0.5f, pcg32_float(&rng) - 0.5f),
                               0.8f);
        vec3 origin = vec3_add(target, vec3_scale(vec3_add(outward, tilt), 3.0f));
        if (vec3_dot(vec3_sub(origin, target), outward) <= 0.1f)
            continue;
        ray r = ray_make(origin, vec3_sub(target, origin));
        bool hit = false;
        for (int f = 0; f < m.face_count && !hit; f++) {
            const int *p = m.faces[f].position;
            bool has_a = p[0] == a || p[1] == a || p[2] == a;
            bool has_b = p[0] == b || p[1] == b || p[2] == b;
            /* A point on the edge within an ulp of a (s ~ 1e-7) is a point
             * of a's fan: the ray may cross a triangle that has a but not b.
             * Requiring both flagged such rays as leaks (seed sweep: 1 ray in
             * 10^6 for 24 of 200 seeds); any triangle touching the edge's
             * ends is a hit within rounding of the target. */
            if (!(on_edge ? has_a || has_b : has_a))
                continue;
            triangle tri = {m.positions[p[0]], m.positions[p[1]], m.positions[p[2]]};
            float t, b1, b2;
            hit = test(&tri, &r, &t, &b1, &b2);
        }
        leaks += !hit;
    }
    mesh_free(&m);
    return leaks;
}

static void test_watertight_triangles_do_not_leak_at_shared_edges(void **state)
{
    (void)state;
    const int rays = 1000000;
    long watertight = count_leaks(triangle_intersect_watertight, rays);
    long moller_trumbore = count_leaks(triangle_intersect_barycentric, rays);
    print_message("rays through shared edges and vertices of a closed mesh: %ld of %d leak with "
                  "Moller-Trumbore, %ld with the watertight test\n", moller_trumbore, rays, watertight);
    assert_int_equal(watertight, 0);
    /* The twin: the lecture's test does leak, which is what makes this a test. */
    assert_true(moller_trumbore > 0);
}

static void test_watertight_agrees_with_moller_trumbore_inside(void **state)
{
    (void)state;
    exercise_checks("moller_trumbore");
    triangle tri = {{1, 2, 3}, {4, 2.5f, 3}, {2, 5, 4}};
    pcg32 rng = pcg32_for_pixel(test_seed(4), 4);
    for (int i = 0; i < 10000; i++) {
        float b1 = 0.05f + 0.4f * pcg32_float(&rng), b2 = 0.05f + 0.4f * pcg32_float(&rng);
        vec3 target = vec3_add(vec3_add(vec3_scale(tri.p0, 1 - b1 - b2), vec3_scale(tri.p1, b1)), vec3_scale(tri.p2, b2));
        vec3 origin = vec3_make(pcg32_float(&rng) * 8 - 4, pcg32_float(&rng) * 8 - 4, pcg32_float(&rng) * 8 - 4);
        ray r = ray_make(origin, vec3_sub(target, origin));
        /* Not grazing: there both tests lose digits, differently. */
        vec3 normal = vec3_normalize(vec3_cross(vec3_sub(tri.p1, tri.p0), vec3_sub(tri.p2, tri.p0)));
        if (fabsf(vec3_dot(vec3_normalize(r.direction), normal)) < 0.2f)
            continue;
        float t1, u1, v1, t2, u2, v2;
        bool a = triangle_intersect_barycentric(&tri, &r, &t1, &u1, &v1);
        bool b = triangle_intersect_watertight(&tri, &r, &t2, &u2, &v2);
        assert_true(a == b);
        if (a) {
            /* Each test rounds to a few ulps of coordinates up to ~8 in size,
             * divided by a cosine of at least 0.2: 5e-5 covers both. */
            const double agreement = 5e-5;
            assert_close(t2, t1, agreement);
            assert_close(u2, u1, agreement);
            assert_close(v2, v1, agreement);
        }
    }
    /* In the plane: no hit, no NaN. */
    float t, u, v;
    ray in_plane = ray_make(vec3_make(-1, 0.25f, 0), vec3_make(1, 0, 0));
    assert_false(triangle_intersect_watertight(&unit_triangle, &in_plane, &t, &u, &v));
}

/* ---- degenerate triangles -------------------------------------------------- */

/* Three collinear points (and three equal ones) bound no area: no ray may
 * hit them, from any direction, and no test may divide by the zero
 * determinant and produce NaN. */
static void test_degenerate_collinear_triangles_are_never_hit(void **state)
{
    (void)state;
    const triangle degenerate[] = {
        {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}},             /* collinear, evenly spaced */
        {{0.1f, 0.2f, 0.3f}, {0.1f, 0.2f, 0.3f}, {1, 0, 0}}, /* two equal points */
        {{0.5f, 0.5f, 0.5f}, {0.5f, 0.5f, 0.5f}, {0.5f, 0.5f, 0.5f}}, /* one point */
        {{-1, 0, 0}, {3, 0, 0}, {1, 0, 0}},             /* collinear, middle point last */
    };
    pcg32 rng = pcg32_for_pixel(test_seed(77), 7);
    for (size_t k = 0; k < sizeof degenerate / sizeof degenerate[0]; k++) {
        const triangle *tri = &degenerate[k];
        for (int i = 0; i < 20000; i++) {
            /* Aimed at a point of the segment, from anywhere. */
            float s = pcg32_float(&rng);
            vec3 target = vec3_add(vec3_scale(tri->p0, 1 - s), vec3_scale(tri->p2, s));
            vec3 origin = vec3_make(8 * pcg32_float(&rng) - 4, 8 * pcg32_float(&rng) - 4, 8 * pcg32_float(&rng) - 4);
            ray r = ray_make(origin, vec3_sub(target, origin));
            hit_record hit;
            float t = NAN, b1 = NAN, b2 = NAN;
            if (triangle_intersect(tri, r, &hit))
                fail_msg("triangle %zu hit (t = %g)", k, (double)hit.t);
            if (triangle_intersect_barycentric(tri, &r, &t, &b1, &b2))
                fail_msg("triangle %zu hit by Moller-Trumbore (t = %g)", k, (double)t);
            if (triangle_intersect_watertight(tri, &r, &t, &b1, &b2))
                fail_msg("triangle %zu hit by the watertight test (t = %g)", k, (double)t);
        }
    }
}

/* The zero-area check must not swallow thin triangles that are not
 * degenerate: a sliver one float step (2^-23 at size 1) high is a real
 * triangle. Rays along -z and +z through points inside it (x anywhere in the
 * middle half, y a quarter of the height: exact floats, and the shear of an
 * axis-aligned ray is exact) must all hit it, from above and from below. A
 * tilted ray aimed at it would not do: its rounded direction wanders by more
 * than 2^-23 before it gets there. */
static void test_sliver_one_float_step_thick_is_still_hit(void **state)
{
    (void)state;
    const float height = 0x1p-23f;
    const triangle sliver = {{0, 0, 0}, {2, 0, 0}, {1, height, 0}};
    pcg32 rng = pcg32_for_pixel(test_seed(78), 8);
    long missed = 0;
    for (int i = 0; i < 20000; i++) {
        float x = 0.5f + pcg32_float(&rng);
        float side = (i % 2) ? 1.0f : -1.0f;
        ray r = ray_make(vec3_make(x, 0.25f * height, side * (0.5f + 4 * pcg32_float(&rng))), vec3_make(0, 0, -side));
        float t = NAN, b1 = NAN, b2 = NAN;
        if (!triangle_intersect_watertight(&sliver, &r, &t, &b1, &b2))
            missed++;
    }
    assert_int_equal(missed, 0);
}

/* ---- implicit surface (sphere-traced torus) ------------------------------- */

static void test_torus_hit_along_its_plane(void **state)
{
    (void)state;
    implicit_torus torus = {vec3_make(0, 0, 0), 1.0f, 0.25f};
    hit_record hit;
    /* From x = -3 along +x: the outer edge of the tube is at x = -1.25. */
    assert_true(implicit_intersect(&torus, ray_from(-3, 0, 0, 1, 0, 0), &hit));
    assert_close(hit.t, 1.75, 1e-5);
    assert_close(hit.normal_geometric.x, -1.0, 1e-4);
    assert_close(implicit_torus_value(&torus, hit.point), 0.0, 1e-5);
    /* Down the hole: the axis never meets the tube. */
    assert_false(implicit_intersect(&torus, ray_from(0, 5, 0, 0, -1, 0), &hit));
    /* From above onto the tube's top at (1, 0.25, 0). */
    assert_true(implicit_intersect(&torus, ray_from(1, 5, 0, 0, -1, 0), &hit));
    assert_close(hit.t, 4.75, 1e-5);
}

/* A naive root finder for comparison: fixed steps of `step`, a hit where f
 * changes sign. */
static bool fixed_step_march(const implicit_torus *torus, ray r, float step, float t_end)
{
    float previous = implicit_torus_value(torus, r.origin);
    for (float t = step; t < t_end; t += step) {
        float f = implicit_torus_value(torus, ray_at(r, t));
        if ((f < 0) != (previous < 0))
            return true;
        previous = f;
    }
    return false;
}

static void test_sphere_tracing_does_not_skip_a_thin_torus(void **state)
{
    (void)state;
    /* A tube 2e-3 thick, crossed straight through its middle. */
    implicit_torus thin = {vec3_make(0, 0, 0), 1.0f, 1e-3f};
    /* Start at y = 3.0037 so that steps of 0.01 land at y = +0.0037 and
     * -0.0063, either side of the tube. */
    ray r = ray_from(1.0f, 3.0037f, 0.0001f, 0, -1, 0);
    hit_record hit;
    assert_true(implicit_intersect(&thin, r, &hit));
    assert_close(hit.t, 3.0037 - 1e-3, 1e-5);
    /* The twin: a fixed step of 0.01 jumps over the tube. */
    assert_false(fixed_step_march(&thin, r, 0.01f, 6.0f));
}

static void test_sphere_tracing_grazing_ray(void **state)
{
    (void)state;
    implicit_torus torus = {vec3_make(0, 0, 0), 1.0f, 0.25f};
    hit_record hit;
    /* Just above the top of the tube (y = 0.25) along x: misses ... */
    assert_false(implicit_intersect(&torus, ray_from(-3, 0.2502f, 0, 1, 0, 0), &hit));
    /* ... just below it: hits the outer side near x = -1. */
    assert_true(implicit_intersect(&torus, ray_from(-3, 0.2490f, 0, 1, 0, 0), &hit));
    assert_true(hit.point.x > -1.03f && hit.point.x < -0.97f);
}

/* ---- leaving a surface: offsets at every scale and distance ----------------
 * ray.h moves a spawned ray off its surface by the hit point's error bound
 * (ray_point_error: 2 roundings of its coordinates across the surface, 64
 * of the primitive's size). The tests below place objects 1e-7 to 1e6
 * across, from the origin out to 1e5 from it, wherever float can still
 * place them (ray_too_small_for_position); their twins keep the offsets
 * ray.h had before, to show what these tests catch. */

static vec3 random_unit(pcg32 *rng)
{
    for (;;) {
        vec3 v = vec3_make(2 * pcg32_float(rng) - 1, 2 * pcg32_float(rng) - 1, 2 * pcg32_float(rng) - 1);
        float l2 = vec3_length_squared(v);
        if (l2 > 1e-4f && l2 <= 1.0f)
            return vec3_scale(v, 1.0f / sqrtf(l2));
    }
}

/* ---- inside or outside: counting crossings ---------------------------------
 * Points inside an icosphere of radius 1 (its faces lie within 2 % of the
 * sphere: below 0.9 is inside) and outside it (1.05 to 1.55), each with a
 * random direction: the parity of the crossings must say which, every time.
 * The twin, "inside iff the ray hits the mesh at all", calls an outside
 * point inside whenever its ray points at the mesh. */
static void test_counting_crossings_tells_inside_from_outside(void **state)
{
    (void)state;
    mesh m;
    mesh_init(&m);
    mesh_icosphere(&m, vec3_make(0, 0, 0), 1.0f, 2, -1);
    triangle *tris = malloc((size_t)m.face_count * sizeof *tris);
    assert_non_null(tris);
    for (int i = 0; i < m.face_count; i++) {
        const int *v = m.faces[i].position;
        tris[i] = (triangle){m.positions[v[0]], m.positions[v[1]], m.positions[v[2]]};
    }
    pcg32 rng;
    pcg32_seed(&rng, test_seed(77), 1);
    int wrong = 0, twin_wrong = 0, points = 2000;
    for (int k = 0; k < points; k++) {
        vec3 p = random_unit(&rng);
        bool inside = k % 2 == 0;
        p = vec3_scale(p, inside ? 0.9f * pcg32_float(&rng) : 1.05f + 0.5f * pcg32_float(&rng));
        vec3 d = random_unit(&rng);
        wrong += closed_mesh_contains(tris, m.face_count, p, d) != inside;
        ray r = ray_make(p, d);
        bool any = false;
        for (int i = 0; i < m.face_count && !any; i++) {
            float t, b1, b2;
            any = triangle_intersect_watertight(&tris[i], &r, &t, &b1, &b2);
        }
        twin_wrong += any != inside;
    }
    print_message("inside by parity: %d of %d points wrong; twin (any hit = inside): %d wrong\n", wrong, points,
                  twin_wrong);
    assert_int_equal(wrong, 0);
    assert_true(twin_wrong > points / 20); /* about a fifth of the outside points aim at the mesh */
    free(tris);
    mesh_free(&m);
}

/* A point on triangle tri at barycentrics (b1, b2), as a hit computes it. */
static vec3 triangle_point(const triangle *tri, float b1, float b2)
{
    vec3 e1 = vec3_sub(tri->p1, tri->p0), e2 = vec3_sub(tri->p2, tri->p0);
    return vec3_add(tri->p0, vec3_add(vec3_scale(e1, b1), vec3_scale(e2, b2)));
}

/* Uniform barycentrics (b1, b2) inside a triangle. */
static void random_barycentrics(pcg32 *rng, float *b1, float *b2)
{
    *b1 = pcg32_float(rng);
    *b2 = pcg32_float(rng);
    if (*b1 + *b2 > 1) {
        *b1 = 1 - *b1;
        *b2 = 1 - *b2;
    }
}

/* Does either triangle test (Moller-Trumbore, the accelerators'; the
 * watertight one) see a hit of r on tri in (t_min, t_max)? */
static bool either_test_hits(const triangle *tri, ray r)
{
    float t, b1, b2;
    return triangle_intersect_barycentric(tri, &r, &t, &b1, &b2) ||
           triangle_intersect_watertight(tri, &r, &t, &b1, &b2);
}

/* ---- the offsets ray.h had before: the twins' wrong implementation ---------
 * 256 float steps of each coordinate along the normal; below |x| = 1/32,
 * where a step is tiny, a fixed 2^-16 instead; the far end of a shadow ray
 * moved at least 256 steps of the segment's length. Right at the scale of
 * the Cornell box, wrong for small objects (2^-16 is 15 % of an object 1e-4
 * across) and for small objects far out (256 steps of 1e5 are 2 units). */
static const float FIXED_OFFSET_ULPS = 256.0f, FIXED_NEAR_ZERO = 1.0f / 32.0f, FIXED_OFFSET = 1.0f / 65536.0f;

static float fixed_offset_coordinate(float p, float n)
{
    if (fabsf(p) < FIXED_NEAR_ZERO)
        return p + FIXED_OFFSET * n;
    int32_t bits, ulps = (int32_t)(FIXED_OFFSET_ULPS * n);
    memcpy(&bits, &p, sizeof bits);
    bits += p < 0.0f ? -ulps : ulps;
    memcpy(&p, &bits, sizeof p);
    return p;
}

static vec3 fixed_offset_origin(vec3 p, vec3 n)
{
    return vec3_make(fixed_offset_coordinate(p.x, n.x), fixed_offset_coordinate(p.y, n.y),
                     fixed_offset_coordinate(p.z, n.z));
}

static ray fixed_spawn(vec3 point, vec3 n, vec3 direction)
{
    vec3 side = vec3_dot(direction, n) < 0.0f ? vec3_neg(n) : n;
    return ray_make(fixed_offset_origin(point, side), direction);
}

/* The old far end; with by_length false, moved by its coordinates alone
 * (as before chapter 11 found the wall through zero). */
static ray fixed_spawn_to(vec3 point, vec3 n, vec3 target, vec3 target_normal, bool by_length)
{
    vec3 to_target = vec3_sub(target, point);
    vec3 side = vec3_dot(to_target, n) < 0.0f ? vec3_neg(n) : n;
    vec3 origin = fixed_offset_origin(point, side);
    vec3 target_side = target_normal;
    if (vec3_dot(vec3_sub(origin, target), target_normal) < 0.0f)
        target_side = vec3_neg(target_normal);
    vec3 end = fixed_offset_origin(target, target_side);
    float minimum = vec3_length(to_target) * (FIXED_OFFSET_ULPS * 0x1.0p-24f);
    if (by_length && vec3_dot(vec3_sub(end, target), target_side) < minimum)
        end = vec3_add(target, vec3_scale(target_side, minimum));
    ray r = ray_make(origin, vec3_sub(end, origin));
    r.t_max = 1.0f;
    return r;
}

/* ---- where objects are placed -------------------------------------------------
 * Sizes 1e-7 to 1e6; distances of the centre from the origin 0, one size,
 * 30 and 1000 sizes, and 1e5; each pair kept if `thinnest` of the size
 * (the object's smallest dimension) is still RAY_MIN_STEPS_ACROSS float
 * steps there, as the programs' check asks of a scene. */
static const float PLACE_SIZES[] = {1e-7f, 1e-4f, 1.0f, 1e3f, 1e6f};
static const float PLACE_DISTANCES[] = {0.0f, 1.0f, 30.0f, 1e3f}; /* in sizes; then 1e5 itself */
enum { PLACE_SIZE_COUNT = 5, PLACE_DISTANCE_COUNT = 5 };

static bool place(int size_index, int distance_index, float thinnest, float *size, float *distance)
{
    *size = PLACE_SIZES[size_index];
    *distance = distance_index < 4 ? PLACE_DISTANCES[distance_index] * *size : 1e5f;
    return *distance <= 1e5f && !ray_too_small_for_position(thinnest * *size, *distance + *size);
}

/* Where the k-th object's centre goes, `distance` from the origin: in a
 * random direction, or every other time at (+-1, +-1, +-1) times the
 * distance, where every coordinate is that large (and a float step is
 * largest). */
static vec3 random_centre(pcg32 *rng, float distance, int k)
{
    if (k % 2 == 0)
        return vec3_scale(random_unit(rng), distance);
    vec3 signs = vec3_make(pcg32_float(rng) < 0.5f ? -1.0f : 1.0f, pcg32_float(rng) < 0.5f ? -1.0f : 1.0f,
                           pcg32_float(rng) < 0.5f ? -1.0f : 1.0f);
    return vec3_scale(signs, distance);
}

/* ---- no re-hit of the surface just left ---------------------------------------- */

typedef enum {
    OFFSET_BOUND,      /* ray_spawn: the hit's error bound */
    OFFSET_NONE,       /* the twin: the bare hit point */
    OFFSET_POINT_ONLY, /* the twin: the bound without its size term */
    OFFSET_SIZE_ONLY,  /* the twin: the bound without its coordinate term */
} offset_kind;

typedef struct {
    long self_hits; /* spawned rays that hit the surface they left */
    long trials;
} self_hit_count;

/* A random triangle around c, corners within `size` of it, not a sliver:
 * twice its area at least MIN_TRIANGLE_QUALITY of its longest edge squared
 * (what ray.h's OFFSET_SIZE_ROUNDINGS was measured for). Every fourth one
 * lies in a plane along an axis through c, and every eighth in the plane
 * through 0, however far c is: coordinates that are exactly zero. */
static const float MIN_TRIANGLE_QUALITY = 0.01f;

static vec3 with_axis(vec3 p, int axis, float value)
{
    if (axis == 0)
        p.x = value;
    else if (axis == 1)
        p.y = value;
    else
        p.z = value;
    return p;
}

static triangle random_triangle(pcg32 *rng, vec3 c, float size, int k)
{
    for (;;) {
        vec3 p[3];
        for (int i = 0; i < 3; i++)
            p[i] = vec3_add(c, vec3_scale(random_unit(rng), size));
        if (k % 4 == 0) {
            int axis = (k / 4) % 3;
            float level = (k / 4) % 2 == 0 ? 0.0f : vec3_axis(c, axis);
            for (int i = 0; i < 3; i++)
                p[i] = with_axis(p[i], axis, level);
        }
        triangle tri = {p[0], p[1], p[2]};
        vec3 e1 = vec3_sub(tri.p1, tri.p0), e2 = vec3_sub(tri.p2, tri.p0), e3 = vec3_sub(tri.p2, tri.p1);
        float longest = fmaxf(vec3_length(e1), fmaxf(vec3_length(e2), vec3_length(e3)));
        if (vec3_length(vec3_cross(e1, e2)) >= MIN_TRIANGLE_QUALITY * longest * longest)
            return tri;
    }
}

/* From each hit, rays leave into an open half-space, which a flat or
 * convex surface can never meet again: for a triangle either side (a
 * reflection or a transmission), for a sphere the outside; a quarter of
 * them grazing, 1e-6 to 0.1 radians off the surface. Hits by
 * Moller-Trumbore and by the watertight test alike, re-hits seen by either. */
static vec3 leaving_direction(pcg32 *rng, vec3 side, int i)
{
    for (;;) {
        vec3 d = random_unit(rng);
        if (vec3_dot(d, side) < 0)
            d = vec3_neg(d);
        if (i % 4 == 3) {
            vec3 along = vec3_normalize(vec3_sub(d, vec3_scale(side, vec3_dot(d, side))));
            d = vec3_normalize(vec3_add(along, vec3_scale(side, powf(10.0f, -6.0f + 5.0f * pcg32_float(rng)))));
        }
        /* ray_spawn decides the side by this sign: a grazing direction
         * that rounds into the surface is not leaving it */
        if (vec3_dot(d, side) > 0.0f)
            return d;
    }
}

static ray leave(const hit_record *hit, vec3 direction, offset_kind kind)
{
    if (kind == OFFSET_NONE)
        return ray_make(hit->point, direction);
    float error = hit->point_error;
    if (kind == OFFSET_POINT_ONLY)
        error = ray_point_error(hit->point, hit->normal_geometric, 0.0f);
    if (kind == OFFSET_SIZE_ONLY)
        error = hit->point_error - ray_point_error(hit->point, hit->normal_geometric, 0.0f);
    return ray_spawn(hit->point, error, hit->normal_geometric, direction);
}

static self_hit_count count_self_hits(int size_index, int distance_index, offset_kind kind, int shapes)
{
    self_hit_count count = {0, 0};
    float size, distance;
    if (!place(size_index, distance_index, 1.0f, &size, &distance))
        return count;
    pcg32 rng = pcg32_for_pixel(test_seed(2024), (uint64_t)(size_index * 8 + distance_index));
    for (int k = 0; k < shapes; k++) {
        vec3 c = random_centre(&rng, distance, k);
        bool use_sphere = k % 3 == 2;
        sphere s = {c, size};
        triangle tri = random_triangle(&rng, c, size, k);
        for (int i = 0; i < 64; i++) {
            /* A ray from a random point 2 to 2000 sizes away, aimed at a
             * random point of the shape. */
            vec3 target;
            if (use_sphere) {
                target = vec3_add(s.center, vec3_scale(random_unit(&rng), s.radius * 0.99f));
            } else {
                float b1, b2;
                random_barycentrics(&rng, &b1, &b2);
                target = triangle_point(&tri, b1, b2);
            }
            float away = size * powf(10.0f, 0.3f + 3.0f * pcg32_float(&rng));
            vec3 origin = vec3_add(target, vec3_scale(random_unit(&rng), away));
            ray in = ray_make(origin, vec3_normalize(vec3_sub(target, origin)));
            hit_record hit;
            float t, b1, b2;
            bool found;
            if (use_sphere)
                found = sphere_intersect(&s, in, &hit);
            else if (i % 2 == 0)
                found = triangle_intersect(&tri, in, &hit);
            else if ((found = triangle_intersect_watertight(&tri, &in, &t, &b1, &b2)))
                triangle_fill_hit(&tri, in, t, b1, b2, &hit);
            if (!found)
                continue;
            vec3 side = hit.normal_geometric; /* the side the ray came from */
            if (!use_sphere && pcg32_float(&rng) < 0.5f)
                side = vec3_neg(side);
            ray leaving = leave(&hit, leaving_direction(&rng, side, i), kind);
            hit_record again;
            count.trials++;
            count.self_hits += use_sphere ? sphere_intersect(&s, leaving, &again) : either_test_hits(&tri, leaving);
        }
    }
    return count;
}

static void test_spawned_rays_never_rehit_their_surface(void **state)
{
    (void)state;
    long trials = 0;
    for (int s = 0; s < PLACE_SIZE_COUNT; s++)
        for (int d = 0; d < PLACE_DISTANCE_COUNT; d++) {
            self_hit_count c = count_self_hits(s, d, OFFSET_BOUND, 600);
            trials += c.trials;
            if (c.self_hits != 0)
                fail_msg("size %g at %d: %ld of %ld spawned rays hit their own surface", PLACE_SIZES[s], d,
                         c.self_hits, c.trials);
        }
    print_message("%ld spawned rays, none hit its own surface\n", trials);
    assert_true(trials > 400000);
}

static void test_unoffset_rays_do_rehit_their_surface(void **state)
{
    (void)state;
    /* The twin: without the offset, rounding puts about half the hit points
     * just behind the surface, and many rays find it again. */
    long total = 0;
    for (int s = 0; s < PLACE_SIZE_COUNT; s++)
        total += count_self_hits(s, 0, OFFSET_NONE, 200).self_hits;
    print_message("bare hit points: %ld rays hit their own surface\n", total);
    assert_true(total > 1000);
}

static void test_offset_without_the_size_term_rehits(void **state)
{
    (void)state;
    /* The twin: the bound's coordinate term alone covers the hit point's
     * last rounding, not the intersection tests' arithmetic from a nearby
     * origin, which errs by roundings of the triangle's size. Near 0,
     * where the coordinates are no bigger than the size, rays re-hit. */
    long total = 0;
    for (int s = 0; s < PLACE_SIZE_COUNT; s++)
        total += count_self_hits(s, 0, OFFSET_POINT_ONLY, 200).self_hits;
    print_message("offset without its size term: %ld rays hit their own surface\n", total);
    assert_true(total > 100);
}

static void test_offset_without_the_coordinate_term_rehits(void **state)
{
    (void)state;
    /* The twin: the size term alone does not cover the hit point's own
     * rounding, which grows with its distance from the origin: objects
     * 1000 of their sizes out re-hit. */
    long total = 0;
    for (int s = 0; s < PLACE_SIZE_COUNT; s++)
        total += count_self_hits(s, 3, OFFSET_SIZE_ONLY, 200).self_hits;
    print_message("offset without its coordinate term: %ld rays hit their own surface\n", total);
    assert_true(total > 100);
}

/* ---- no false block between mutually visible points ------------------------------
 * A closed box, every face's inside seen from every other's: the box is
 * convex, so every two points on its inside see each other. Boxes of size
 * 1e-7 to 1e6, placed out to 1e5, turned at random (a third of them along
 * the axes), flattened to a tenth in one direction, so that its two big
 * faces face each other a tenth of the size apart. From random points on
 * the faces: shadow rays (ray_spawn_to) to random points on the faces must
 * not be blocked by any of its triangles (Moller-Trumbore or watertight),
 * and a ray spawned towards a point on another face must meet the box
 * first at that point (the nearest real hit is not skipped). The points
 * are computed as hits are, but not within rounding of an edge (below). */
typedef struct {
    long blocked; /* shadow rays between points on the box blocked by the box */
    long missed;  /* rays towards a point on another face that met the box elsewhere, or not at all */
    long pairs;
    long aimed;   /* of them checked for their nearest hit */
} box_count;

static const float BOX_THICKNESS = 0.1f; /* of the box's size */
/* "Right beside" p[1]: a thousandth of the box, far above the rounding of
 * its corners and far below the distance between its faces, and what the
 * offsets move the hit (below). */
static const float BOX_HIT_TOLERANCE = 1e-3f;
/* Segments meeting a face at a sine below this (1/20: about 3 degrees) are
 * left out of the nearest-hit check, and in turned boxes altogether (below). */
static const float BOX_MIN_SINE = 0.05f;
/* Points are drawn at least this many of their error bounds from every
 * other face's plane. A point within rounding of an edge lies on two
 * faces, and may lie just outside the other one: a ray leaving it at an
 * angle theta to that face crosses it up to (the rounding) / sin(theta)
 * away, beyond t_min (measured without this margin: 2 to 6 of the 460,800
 * pairs blocked, over four seeds, each by the face beside an end that lay
 * within rounding of their common edge). What ray.h cannot tell from a
 * point alone; see docs/hard-cases.md. */
static const float BOX_EDGE_MARGIN = 4.0f;

/* Is p, on face `face` of the box, within BOX_EDGE_MARGIN error bounds of
 * the plane of another face (in double: the plane's distance is exact
 * enough there)? */
static bool near_another_face(const triangle tris[12], int face, vec3 p, float error)
{
    for (int t = 0; t < 12; t += 2) {
        if (t / 2 == face)
            continue;
        const triangle *q = &tris[t];
        double e1[3] = {(double)q->p1.x - q->p0.x, (double)q->p1.y - q->p0.y, (double)q->p1.z - q->p0.z};
        double e2[3] = {(double)q->p2.x - q->p0.x, (double)q->p2.y - q->p0.y, (double)q->p2.z - q->p0.z};
        double m[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        double d[3] = {(double)p.x - q->p0.x, (double)p.y - q->p0.y, (double)p.z - q->p0.z};
        double distance = (m[0] * d[0] + m[1] * d[1] + m[2] * d[2]) / sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
        if (fabs(distance) < BOX_EDGE_MARGIN * error)
            return true;
    }
    return false;
}

static void build_box(pcg32 *rng, vec3 centre, float size, int k, triangle tris[12])
{
    vec3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    if (k % 3 != 0) {
        axes[2] = random_unit(rng);
        vec3_basis(axes[2], &axes[0], &axes[1]);
    }
    float half[3] = {0.5f * size, 0.5f * size, 0.5f * BOX_THICKNESS * size};
    vec3 corner[8];
    for (int i = 0; i < 8; i++) {
        vec3 p = centre;
        for (int a = 0; a < 3; a++)
            p = vec3_add(p, vec3_scale(axes[a], (i >> a) & 1 ? half[a] : -half[a]));
        corner[i] = p;
    }
    /* Each face as two triangles, by the corners' bits: the face where bit
     * a is `high`. */
    int t = 0;
    for (int a = 0; a < 3; a++)
        for (int high = 0; high < 2; high++) {
            int b = (a + 1) % 3, c = (a + 2) % 3, base = high << a;
            int q[4] = {base, base | 1 << b, base | 1 << b | 1 << c, base | 1 << c};
            tris[t++] = (triangle){corner[q[0]], corner[q[1]], corner[q[2]]};
            tris[t++] = (triangle){corner[q[0]], corner[q[2]], corner[q[3]]};
        }
}

typedef ray (*spawn_to_fn)(vec3 point, float point_error, vec3 n, vec3 target, float target_error, vec3 target_normal);

static ray fixed_spawn_to_as_ray_h(vec3 point, float point_error, vec3 n, vec3 target, float target_error,
                                   vec3 target_normal)
{
    (void)point_error;
    (void)target_error;
    return fixed_spawn_to(point, n, target, target_normal, true);
}

static box_count count_box_blocks(int size_index, int distance_index, bool fixed, int boxes)
{
    box_count count = {0, 0, 0, 0};
    float size, distance;
    if (!place(size_index, distance_index, BOX_THICKNESS, &size, &distance))
        return count;
    spawn_to_fn spawn_to = fixed ? fixed_spawn_to_as_ray_h : ray_spawn_to;
    pcg32 rng = pcg32_for_pixel(test_seed(2025), (uint64_t)(size_index * 8 + distance_index));
    for (int k = 0; k < boxes; k++) {
        triangle tris[12];
        build_box(&rng, random_centre(&rng, distance, k), size, k, tris);
        for (int i = 0; i < 64; i++) {
            vec3 p[2], n[2];
            float error[2];
            int face[2];
            for (int e = 0; e < 2; e++) {
                int index;
                do { /* the big faces (4 and 5) half the time */
                    index = pcg32_float(&rng) < 0.5f ? 8 + (int)pcg32_bounded(&rng, 4) : (int)pcg32_bounded(&rng, 12);
                    float b1, b2;
                    random_barycentrics(&rng, &b1, &b2);
                    p[e] = triangle_point(&tris[index], b1, b2);
                    n[e] = triangle_unit_normal(&tris[index]);
                    error[e] = triangle_point_error(&tris[index], p[e], n[e]);
                } while (near_another_face(tris, index / 2, p[e], error[e]));
                face[e] = index / 2;
            }
            /* In a turned box, segments that graze a face are left out:
             * its two triangles, whose corners were rounded apart, are not
             * quite flat (by up to a few roundings of the corners, as much
             * as the offsets), and a segment that runs along the face one
             * offset off it can meet the other triangle (measured: 6 of
             * 40 seeds blocked one such pair, all between points of one
             * face 1000 sizes out). A box along the axes has flat faces. */
            vec3 v = vec3_sub(p[1], p[0]);
            float along = vec3_length(v);
            bool grazing = fabsf(vec3_dot(v, n[0])) < BOX_MIN_SINE * along ||
                           fabsf(vec3_dot(v, n[1])) < BOX_MIN_SINE * along;
            if (k % 3 != 0 && grazing)
                continue;
            count.pairs++;
            ray shadow = spawn_to(p[0], error[0], n[0], p[1], error[1], n[1]);
            bool blocked = false;
            for (int t = 0; t < 12; t++)
                blocked |= either_test_hits(&tris[t], shadow);
            count.blocked += blocked;
            /* The nearest-hit check, from a point towards one on another
             * face, where the segment meets both at an angle (a ray that
             * grazes a face moves its hit along it by a lot). */
            if (face[0] == face[1] || grazing)
                continue;
            count.aimed++;
            ray towards = fixed ? fixed_spawn(p[0], n[0], vec3_sub(p[1], p[0]))
                                : ray_spawn(p[0], error[0], n[0], vec3_sub(p[1], p[0]));
            hit_record nearest = {0};
            int nearest_face = -1;
            for (int t = 0; t < 12; t++) {
                float th, b1, b2;
                if (triangle_intersect_watertight(&tris[t], &towards, &th, &b1, &b2)) {
                    triangle_fill_hit(&tris[t], towards, th, b1, b2, &nearest);
                    nearest_face = t / 2;
                    towards.t_max = th;
                }
            }
            bool found = nearest_face >= 0;
            /* The ray aims at p[1], so the box's first surface along it is
             * p[1]'s face, or, where p[1] lies within rounding of an edge,
             * the neighbouring face right beside p[1]: the ray runs e0 off
             * p[1] (the offset of its origin), which a face met at sine s
             * turns into e0 / s along the face. */
            float beside = BOX_HIT_TOLERANCE * size + (error[0] + error[1]) / BOX_MIN_SINE;
            count.missed += !found || (nearest_face != face[1] && vec3_length(vec3_sub(nearest.point, p[1])) > beside);
        }
    }
    return count;
}

static void test_points_inside_a_closed_box_see_each_other(void **state)
{
    (void)state;
    long pairs = 0, aimed = 0;
    for (int s = 0; s < PLACE_SIZE_COUNT; s++)
        for (int d = 0; d < PLACE_DISTANCE_COUNT; d++) {
            box_count c = count_box_blocks(s, d, false, 400);
            pairs += c.pairs;
            aimed += c.aimed;
            if (c.blocked != 0 || c.missed != 0)
                fail_msg("box %g across at %d: %ld of %ld shadow rays blocked, %ld rays missed the point they aim at",
                         PLACE_SIZES[s], d, c.blocked, c.pairs, c.missed);
        }
    print_message("%ld pairs of points inside boxes: none blocked; %ld rays aimed from one to the other: no nearest "
                  "hit skipped\n", pairs, aimed);
    assert_true(pairs > 200000 && aimed > pairs / 3);
}

static void test_fixed_offset_near_zero_blocks_points_inside_a_small_box(void **state)
{
    (void)state;
    /* The twin: the old fixed 2^-16 near 0 moves points of a box 1e-4
     * across (its big faces 1e-5 apart) through the opposite face. */
    box_count c = count_box_blocks(1, 0, true, 400);
    print_message("fixed offset, box 1e-4 across at 0: %ld of %ld shadow rays blocked, "
                  "%ld of %ld nearest hits skipped\n",
                  c.blocked, c.pairs, c.missed, c.aimed);
    assert_true(c.blocked > c.pairs / 100);
    assert_true(c.missed > c.aimed / 100);
}

/* ---- a point on an edge ------------------------------------------------------
 * A room's corner: a floor in the plane y = 0 and a wall in x = 0, and
 * points of the floor exactly on their common edge (x = 0), where a hit on
 * the floor can round to. The offset moves such a point off the floor only:
 * it still lies in the wall's plane, where an intersection test finds the
 * wall at a t of pure rounding, of either sign. ray_spawn and ray_spawn_to
 * count no hit within the point's error bound of the origin (t_min). */
static long count_edge_hits(float size, bool with_t_min, int count)
{
    pcg32 rng = pcg32_for_pixel(test_seed(2027), (uint64_t)(size * 1e7f));
    triangle wall = {{0, 0, 0}, {0, size, 0}, {0, 0, size}}, floor_tri = {{0, 0, 0}, {0, 0, size}, {size, 0, 0}};
    vec3 n = triangle_unit_normal(&floor_tri);
    long hits = 0;
    for (int i = 0; i < count; i++) {
        vec3 p = vec3_make(0.0f, 0.0f, size * (0.01f + 0.98f * pcg32_float(&rng)));
        float error = triangle_point_error(&floor_tri, p, n);
        vec3 target = vec3_scale(vec3_make(pcg32_float(&rng), pcg32_float(&rng), pcg32_float(&rng)), size);
        ray rays[2] = {ray_spawn_to(p, error, n, target, 0.0f, vec3_splat(0.0f)),
                       ray_spawn(p, error, n, vec3_normalize(vec3_sub(target, p)))};
        for (int k = 0; k < 2; k++) {
            if (!with_t_min)
                rays[k].t_min = 0.0f;
            hits += either_test_hits(&wall, rays[k]);
        }
    }
    return hits;
}

static void test_rays_from_a_point_on_an_edge_do_not_stop_on_the_other_face(void **state)
{
    (void)state;
    const float sizes[] = {1e-7f, 1e-3f, 1.0f, 550.0f, 1e5f};
    for (int s = 0; s < 5; s++) {
        long n = count_edge_hits(sizes[s], true, 20000);
        if (n != 0)
            fail_msg("room %g across: %ld of 40000 rays from the edge stop on the wall", sizes[s], n);
    }
}

/* ---- shadow rays to a point on a light ----------------------------------- */

/* A floor triangle and a light triangle facing it, at a given scale and far
 * from the origin: from random floor points, shadow rays to random light
 * points (ray_spawn_to, as the path tracer builds them). Nothing lies
 * between them, so any hit is a hit on the floor the ray leaves or the light
 * it aims at: a false shadow. Returns how many of `count` rays had one;
 * `offset` false is the twin with bare end points and t_max = 1. */
static int count_false_shadows(float scale, bool offset, int count)
{
    pcg32 rng = pcg32_for_pixel(test_seed(4242), (uint64_t)(scale * 1e7f));
    vec3 base = vec3_scale(vec3_make(0.7f, 0.3f, -0.55f), scale);
    triangle floor_tri = {vec3_add(base, vec3_scale(vec3_make(-1, 0, -1), scale)),
                          vec3_add(base, vec3_scale(vec3_make(1.2f, 0.01f, -0.9f), scale)),
                          vec3_add(base, vec3_scale(vec3_make(0.1f, -0.02f, 1.1f), scale))};
    triangle light_tri = {vec3_add(base, vec3_scale(vec3_make(-0.3f, 0.8f, -0.2f), scale)),
                          vec3_add(base, vec3_scale(vec3_make(0.1f, 0.83f, 0.35f), scale)),
                          vec3_add(base, vec3_scale(vec3_make(0.4f, 0.79f, -0.3f), scale))};
    vec3 n_floor = triangle_unit_normal(&floor_tri), n_light = triangle_unit_normal(&light_tri);
    int false_shadows = 0;
    for (int i = 0; i < count; i++) {
        vec3 ends[2];
        float errors[2];
        const triangle *tris[2] = {&floor_tri, &light_tri};
        for (int k = 0; k < 2; k++) {
            float b1, b2;
            random_barycentrics(&rng, &b1, &b2);
            ends[k] = triangle_point(tris[k], b1, b2);
            errors[k] = triangle_point_error(tris[k], ends[k], k == 0 ? n_floor : n_light);
        }
        ray shadow;
        if (offset) {
            shadow = ray_spawn_to(ends[0], errors[0], n_floor, ends[1], errors[1], n_light);
        } else {
            shadow = ray_make(ends[0], vec3_sub(ends[1], ends[0]));
            shadow.t_max = 1.0f;
        }
        false_shadows += either_test_hits(&floor_tri, shadow) || either_test_hits(&light_tri, shadow);
    }
    return false_shadows;
}

static void test_shadow_rays_do_not_hit_the_light_they_aim_at(void **state)
{
    (void)state;
    const float scales[] = {1e-7f, 1e-4f, 1.0f, 1e2f, 1e4f, 1e6f};
    for (int s = 0; s < 6; s++) {
        int n = count_false_shadows(scales[s], true, 20000);
        if (n != 0)
            fail_msg("scale %g: %d of 20000 shadow rays hit their own floor or the light they aim at", scales[s], n);
    }
}

static void test_unoffset_shadow_rays_hit_the_light_they_aim_at(void **state)
{
    (void)state;
    /* The twin: from the bare hit point to the bare light point with
     * t_max = 1, rounding lands many end points a little beyond the light
     * or the start a little below the floor. */
    int total = 0;
    const float scales[] = {1.0f, 1e2f, 1e4f};
    for (int s = 0; s < 3; s++)
        total += count_false_shadows(scales[s], false, 20000);
    print_message("unoffset shadow rays: %d of 60000 hit the floor or the light\n", total);
    assert_true(total > 100);
}

/* A wall in the plane x = 0, `wall` across (the Cornell box's green wall
 * lies there), and a light `far` from it: shadow rays between random wall
 * points and random light points, built with ray_spawn_to from either end,
 * and rays spawned from the wall towards the light. The test's arithmetic
 * for the far end's surface errs by roundings of the whole segment, so the
 * far end must move back by more than the wall's own error bound where the
 * light is far compared to the wall. Returns how many of `count` rays
 * (each way, and spawned from the wall) hit the wall they leave or aim at.
 * The twins: `far_end` FAR_END_COORDINATES, the far end moved by the old
 * offset of its coordinates alone (a fixed 2^-16 at x = 0), and
 * FAR_END_OWN_ERROR, by the wall point's error bound alone (no length). */
typedef enum { FAR_END_RAY_H, FAR_END_COORDINATES, FAR_END_OWN_ERROR } far_end_kind;

static int count_false_shadows_at_zero(float wall, float far, far_end_kind far_end, int count)
{
    pcg32 rng = pcg32_for_pixel(test_seed(4343), (uint64_t)(wall * 1e7f) ^ (uint64_t)far);
    triangle wall_tri = {vec3_make(0, 0, 0), vec3_make(0, wall, 0), vec3_make(0, 0, wall)};
    vec3 n_wall = vec3_make(1, 0, 0), n_light = vec3_make(0, -1, 0);
    int false_shadows = 0;
    for (int i = 0; i < count; i++) {
        float b1, b2;
        random_barycentrics(&rng, &b1, &b2);
        vec3 on_wall = triangle_point(&wall_tri, b1, b2);
        float wall_error = triangle_point_error(&wall_tri, on_wall, n_wall);
        float lx = 0.4f + 0.2f * pcg32_float(&rng), lz = 0.4f + 0.2f * pcg32_float(&rng);
        vec3 on_light = vec3_make(far * lx, far * 0.99f, far * lz);
        float light_error = ray_point_error(on_light, n_light, 0.1f * far); /* a light a tenth of `far` across */
        ray to_wall;
        if (far_end == FAR_END_COORDINATES) {
            to_wall = fixed_spawn_to(on_light, n_light, on_wall, n_wall, false);
        } else {
            to_wall = ray_spawn_to(on_light, light_error, n_light, on_wall, wall_error, n_wall);
            if (far_end == FAR_END_OWN_ERROR) { /* the end and t_max by the wall point's bound alone */
                to_wall.direction = vec3_sub(ray_offset_origin(on_wall, wall_error, n_wall), to_wall.origin);
                to_wall.t_max = 1.0f - wall_error / vec3_length(vec3_sub(on_wall, on_light));
            }
        }
        false_shadows += either_test_hits(&wall_tri, to_wall);
        if (far_end != FAR_END_RAY_H)
            continue;
        ray from_wall = ray_spawn_to(on_wall, wall_error, n_wall, on_light, light_error, n_light);
        ray leaving = ray_spawn(on_wall, wall_error, n_wall, vec3_sub(on_light, on_wall));
        false_shadows += either_test_hits(&wall_tri, from_wall) + either_test_hits(&wall_tri, leaving);
    }
    return false_shadows;
}

static void test_shadow_rays_to_a_wall_through_zero_stop_short_of_it(void **state)
{
    (void)state;
    /* Walls as big as their distance to the light, and walls a thousandth
     * of it. */
    const float scales[] = {1e-7f, 1e-3f, 1.0f, 550.0f, 1e4f, 1e6f};
    for (int s = 0; s < 6; s++)
        for (int small = 0; small < 2; small++) {
            float wall = small ? 1e-3f * scales[s] : scales[s];
            int n = count_false_shadows_at_zero(wall, scales[s], FAR_END_RAY_H, 20000);
            if (n != 0)
                fail_msg("wall %g, light %g away: %d of 60000 shadow rays hit the wall at x = 0 they leave or aim at",
                         wall, scales[s], n);
        }
}

static void test_far_end_offset_in_coordinate_ulps_hits_a_wall_through_zero(void **state)
{
    (void)state;
    /* The twin: the far end moved only by ulps of its own coordinates (a
     * fixed 2^-16 at x = 0), as ray_spawn_to did once. At the Cornell
     * box's scale a shadow ray from the light to the green wall then stops
     * on the wall in about 4 % of cases: chapter 11 saw 0.6 % of the box's
     * direct light vanish when it joined paths from the light's side. */
    int n = count_false_shadows_at_zero(550.0f, 550.0f, FAR_END_COORDINATES, 20000);
    print_message("far end offset in coordinate ulps: %d of 20000 rays stop on the wall\n", n);
    assert_true(n > 100);
}

static void test_far_end_moved_by_its_own_error_alone_stops_on_a_small_far_wall(void **state)
{
    (void)state;
    /* The twin: the far end moved back by the wall point's error bound
     * alone, without the roundings of the segment's length. A wall a
     * thousandth of the distance across has a bound a thousandth of the
     * test's error there. */
    int n = count_false_shadows_at_zero(0.55f, 550.0f, FAR_END_OWN_ERROR, 20000);
    print_message("far end moved by its own error bound alone: %d of 20000 rays stop on the small wall\n", n);
    assert_true(n > 100);
}

/* ---- refraction into a small sphere far out ------------------------------------
 * Rays from outside enter a glass sphere (Snell's law, ior 1.5): the
 * refracted ray, spawned from the hit, must start inside the sphere
 * (checked in double) and meet its far side, the chord 2 R cos(theta_t)
 * away, not the entry point again nor nothing. Spheres 1e-7 to 1e6 in
 * radius, out to 1e5: among them the radius 1 at 1e5, where 256
 * steps of each coordinate are 2 units. */
typedef struct {
    long outside; /* refracted rays whose origin is not inside the sphere */
    long wrong;   /* ... that do not meet the far side at the chord's length */
    long rays;
} refraction_count;

static bool refract_into(vec3 d, vec3 n, float eta, vec3 *t)
{
    float cos_i = -vec3_dot(d, n);
    float k = 1.0f - eta * eta * (1.0f - cos_i * cos_i);
    if (k < 0.0f)
        return false;
    *t = vec3_normalize(vec3_add(vec3_scale(d, eta), vec3_scale(n, eta * cos_i - sqrtf(k))));
    return true;
}

static refraction_count count_refraction(int size_index, int distance_index, bool fixed, int spheres)
{
    refraction_count count = {0, 0, 0};
    float size, distance;
    if (!place(size_index, distance_index, 2.0f, &size, &distance))
        return count;
    pcg32 rng = pcg32_for_pixel(test_seed(2026), (uint64_t)(size_index * 8 + distance_index));
    for (int k = 0; k < spheres; k++) {
        sphere s = {random_centre(&rng, distance, k), size};
        for (int i = 0; i < 64; i++) {
            vec3 target = vec3_add(s.center, vec3_scale(random_unit(&rng), 0.99f * size));
            float away = size * powf(10.0f, 0.3f + 3.0f * pcg32_float(&rng));
            vec3 origin = vec3_add(target, vec3_scale(random_unit(&rng), away));
            ray in = ray_make(origin, vec3_normalize(vec3_sub(target, origin)));
            hit_record hit, far_side;
            vec3 t;
            if (!sphere_intersect(&s, in, &hit) || !hit.front_face ||
                !refract_into(in.direction, hit.normal_geometric, 1.0f / 1.5f, &t))
                continue;
            ray r = fixed ? fixed_spawn(hit.point, hit.normal_geometric, t)
                          : ray_spawn(hit.point, hit.point_error, hit.normal_geometric, t);
            double dx = (double)r.origin.x - s.center.x, dy = (double)r.origin.y - s.center.y,
                   dz = (double)r.origin.z - s.center.z;
            bool inside = sqrt(dx * dx + dy * dy + dz * dz) < size;
            /* 2 R cos(theta_t) is at least 1.49 R (theta_t <= asin(1 / 1.5)):
             * within a tenth of it, far above the rounding of the sphere's
             * surface (at most a 64th of its size, by the placement). */
            float chord = 2.0f * size * -vec3_dot(t, hit.normal_geometric);
            bool far = sphere_intersect(&s, r, &far_side) &&
                       fabsf(vec3_length(vec3_sub(far_side.point, hit.point)) - chord) < 0.1f * chord;
            count.rays++;
            count.outside += !inside;
            count.wrong += !inside || !far;
        }
    }
    return count;
}

static void test_refracted_ray_into_a_sphere_finds_the_far_side(void **state)
{
    (void)state;
    long rays = 0;
    for (int s = 0; s < PLACE_SIZE_COUNT; s++)
        for (int d = 0; d < PLACE_DISTANCE_COUNT; d++) {
            refraction_count c = count_refraction(s, d, false, 200);
            rays += c.rays;
            if (c.wrong != 0)
                fail_msg("radius %g at %d: %ld of %ld refracted rays start outside, %ld miss the far side",
                         PLACE_SIZES[s], d, c.outside, c.rays, c.wrong);
        }
    /* the sphere: radius 1 at 1e5 */
    refraction_count far_out = count_refraction(2, 4, false, 200);
    assert_true(far_out.rays > 5000);
    assert_int_equal(far_out.wrong, 0);
    print_message("%ld refracted rays, all start inside and meet the far side\n", rays);
}

static void test_fixed_ulp_offset_starts_refracted_rays_beyond_a_far_sphere(void **state)
{
    (void)state;
    /* The twin: 256 float steps of each coordinate at 1e5 are 2 units, the
     * sphere's diameter: the origin lands about where the ray through the
     * centre leaves, not on the refracted ray's way. */
    refraction_count c = count_refraction(2, 4, true, 200);
    print_message("fixed offset, radius 1 at 1e5: of %ld refracted rays %ld start outside the sphere, "
                  "%ld miss its far side\n",
                  c.rays, c.outside, c.wrong);
    assert_true(c.wrong > c.rays / 10);
}

/* ---- Blinn-Phong, by hand ------------------------------------------------- */

static void build_one_sphere_scene(scene *sc, bool with_blocker)
{
    scene_init(sc);
    sc->camera = (scene_camera){vec3_make(0, 0, 5), vec3_make(0, 0, 0), vec3_make(0, 1, 0), 30.0f};
    sc->ambient = vec3_splat(0.1f);
    sc->background = vec3_splat(0.0f);
    int m = scene_add_material(sc, material_blinn_phong(vec3_make(0.5f, 0.25f, 0.125f), vec3_splat(0.4f), 10.0f));
    scene_add_sphere(sc, vec3_make(0, 0, 0), 1.0f, m);
    scene_add_point_light(sc, vec3_make(3, 0, 5), vec3_splat(50.0f));
    if (with_blocker) /* a small sphere on the segment from (0,0,1) to the light */
        scene_add_sphere(sc, vec3_make(1.5f, 0, 3), 0.2f, m);
}

static void test_blinn_phong_pixel_equals_the_formula(void **state)
{
    (void)state;
    scene sc;
    build_one_sphere_scene(&sc, false);
    camera cam = scene_make_camera(&sc, 9, 9);
    render_job job = {.cam = &cam, .spp = 1, .seed = 1, .threads = 1, .radiance = ray_cast_radiance, .scene = &sc};
    ray_counters counters = {0};
    vec3 c = render_pixel(&job, 4, 4, &counters, NULL); /* the centre pixel: hit (0,0,1) */

    /* By hand: p = (0,0,1), n = v = (0,0,1), to the light (3,0,4): r^2 = 25,
     * l = (0.6, 0, 0.8), n.l = 0.8; h = unit(l + v) = unit(0.6, 0, 1.8),
     * n.h = 1.8 / sqrt(0.36 + 3.24) = 3 / sqrt(10). */
    double irradiance = 50.0 / 25.0;
    double n_dot_h = 3.0 / sqrt(10.0);
    double specular = 0.4 * irradiance * pow(n_dot_h, 10.0);
    const double k_d[3] = {0.5, 0.25, 0.125};
    const float got[3] = {c.x, c.y, c.z};
    for (int i = 0; i < 3; i++)
        assert_close(got[i], 0.1 * k_d[i] + k_d[i] * irradiance * 0.8 + specular, 1e-5);
    assert_int_equal(counters.shadow_rays, 1);
    scene_free(&sc);
}

static void test_shadowed_point_gets_only_ambient(void **state)
{
    (void)state;
    scene sc;
    build_one_sphere_scene(&sc, true);
    camera cam = scene_make_camera(&sc, 9, 9);
    render_job job = {.cam = &cam, .spp = 1, .seed = 1, .threads = 1, .radiance = ray_cast_radiance, .scene = &sc};
    ray_counters counters = {0};
    vec3 c = render_pixel(&job, 4, 4, &counters, NULL);
    assert_close(c.x, 0.1 * 0.5, 1e-6);
    assert_close(c.z, 0.1 * 0.125, 1e-6);
    scene_free(&sc);
}

static void test_light_behind_the_surface_casts_no_shadow_ray(void **state)
{
    (void)state;
    scene sc;
    build_one_sphere_scene(&sc, false);
    sc.lights[0].position = vec3_make(0, 0, -5); /* behind the sphere */
    hit_record hit;
    ray_counters counters = {0};
    assert_true(scene_intersect(&sc, ray_from(0, 0, 5, 0, 0, -1), &hit, &counters));
    vec3 c = blinn_phong_shade(&sc, &hit, vec3_make(0, 0, 1), &counters);
    assert_int_equal(counters.shadow_rays, 0);
    assert_close(c.x, 0.05, 1e-6);
    scene_free(&sc);
}

/* ---- the whole picture ---------------------------------------------------- */

static image render_demo(int threads)
{
    scene sc;
    scene_build_ray_casting_demo(&sc);
    camera cam = scene_make_camera(&sc, 96, 54);
    render_job job = {.cam = &cam, .spp = 2, .seed = 5, .threads = threads, .quiet = true,
                      .radiance = ray_cast_radiance, .scene = &sc};
    image img = image_make(96, 54);
    render_stats stats;
    render_image(&job, &img, &stats);
    assert_int_equal(stats.counters.nonfinite_samples, 0);
    scene_free(&sc);
    return img;
}

static void test_demo_is_bit_identical_for_one_and_two_threads(void **state)
{
    (void)state;
    image one = render_demo(1), two = render_demo(2);
    assert_memory_equal(one.rgb, two.rgb, 96 * 54 * 3 * sizeof(float));
    for (int i = 0; i < 96 * 54 * 3; i++)
        assert_true(isfinite(one.rgb[i]) && one.rgb[i] >= 0.0f);
    image_free(&one);
    image_free(&two);
}


/* ---- scene files ------------------------------------------------------------ */

/* A scene from scene-file text, effects decided as the program decides them. */
static void scene_from_text(scene *sc, const char *text, unsigned supported)
{
    scene_desc d;
    char err[SCENE_ERROR_SIZE];
    if (!scene_desc_parse(&d, text, strlen(text), "test.scene", NULL, err, sizeof err))
        fail_msg("%s", err);
    assert_true(scene_from_desc(sc, &d, "test", err, sizeof err));
    effects_report e = effects_analyse(&d);
    sc->effects = effects_decide(&e, supported);
    scene_desc_free(&d);
}

static image render_scene(const scene *sc, int width, int height, ray_counters *counters)
{
    camera cam = scene_make_camera(sc, width, height);
    render_job job = {.cam = &cam, .spp = 1, .seed = 1, .threads = 2, .quiet = true, .radiance = ray_cast_radiance,
                      .scene = sc};
    image img = image_make(width, height);
    render_stats stats;
    render_image(&job, &img, &stats);
    *counters = stats.counters;
    return img;
}

static void test_default_scene_file_renders_the_built_in_image(void **state)
{
    (void)state;
    scene_desc d;
    char err[SCENE_ERROR_SIZE];
    if (!scene_desc_load(&d, "chapters/01-ray-casting/scenes/default.scene", err, sizeof err))
        fail_msg("%s", err);
    scene from_file, built_in;
    assert_true(scene_from_desc(&from_file, &d, "test", err, sizeof err));
    effects_report e = effects_analyse(&d);
    from_file.effects = effects_decide(&e, EFFECT_SHADOWS);
    assert_int_equal(d.width, 1280);
    scene_desc_free(&d);
    scene_build_ray_casting_demo(&built_in);
    ray_counters c1, c2;
    image a = render_scene(&from_file, 128, 72, &c1), b = render_scene(&built_in, 128, 72, &c2);
    assert_memory_equal(a.rgb, b.rgb, 128 * 72 * 3 * sizeof(float));
    assert_memory_equal(&c1, &c2, sizeof c1);
    image_free(&a);
    image_free(&b);
    scene_free(&from_file);
    scene_free(&built_in);
}

static const char *const ONE_SPHERE =
    "camera eye 0 0 5 target 0 0 0 fov 40\n"
    "material red blinn_phong diffuse 0.7 0.2 0.1 specular 0.5 0.5 0.5 shininess 32\n"
    "sphere center 0 0 0 radius 1 material red\n"
    "light point position 3 4 5 intensity 30 30 30\n";

/* One sphere seen from outside, one light outside it: the analysis proves no
 * light can be blocked, so no shadow ray is traced, and the image is the
 * same, bit for bit, as with a shadow ray to every light. */
static void test_one_unoccluded_light_needs_no_shadow_ray(void **state)
{
    (void)state;
    scene analysed, forced;
    scene_from_text(&analysed, ONE_SPHERE, EFFECT_SHADOWS);
    scene_from_text(&forced, ONE_SPHERE, EFFECT_SHADOWS);
    assert_false(scene_traces_shadows(&analysed));
    forced.effects = EFFECT_ALL;
    ray_counters c_analysed, c_forced;
    image a = render_scene(&analysed, 64, 48, &c_analysed), b = render_scene(&forced, 64, 48, &c_forced);
    assert_int_equal(c_analysed.shadow_rays, 0);
    assert_true(c_forced.shadow_rays > 100); /* the check would see shadow rays if they were traced */
    assert_memory_equal(a.rgb, b.rgb, 64 * 48 * 3 * sizeof(float));
    image_free(&a);
    image_free(&b);
    scene_free(&analysed);
    scene_free(&forced);
}

/* The twin: add a floor, and the sphere can shadow it; shadow rays are back
 * and they change the image. */
static void test_a_second_shape_brings_shadow_rays_back(void **state)
{
    (void)state;
    char text[1024];
    snprintf(text, sizeof text, "%smaterial grey diffuse albedo 0.5 0.5 0.5\nplane point 0 -1 0 normal 0 1 0 "
                                "material grey\n", ONE_SPHERE);
    scene sc;
    scene_from_text(&sc, text, EFFECT_SHADOWS);
    assert_true(scene_traces_shadows(&sc));
    ray_counters c;
    image a = render_scene(&sc, 64, 48, &c);
    assert_true(c.shadow_rays > 0);
    sc.effects = 0; /* no shadows: the floor under the sphere gets light it should not */
    ray_counters c_off;
    image b = render_scene(&sc, 64, 48, &c_off);
    assert_int_equal(c_off.shadow_rays, 0);
    assert_true(memcmp(a.rgb, b.rgb, 64 * 48 * 3 * sizeof(float)) != 0);
    image_free(&a);
    image_free(&b);
    scene_free(&sc);
}

/* The built-in scene, described, is analysed like its file: the same
 * effects, shadows included (a sphere and a torus over a floor). */
static void test_built_in_scene_description_matches_its_file(void **state)
{
    (void)state;
    scene sc;
    scene_build_ray_casting_demo(&sc);
    scene_desc built_in, file;
    scene_describe(&sc, &built_in);
    char err[SCENE_ERROR_SIZE];
    if (!scene_desc_load(&file, "chapters/01-ray-casting/scenes/default.scene", err, sizeof err))
        fail_msg("%s", err);
    assert_int_equal(built_in.shape_count, file.shape_count);
    assert_int_equal(built_in.light_count, file.light_count);
    effects_report a = effects_analyse(&built_in), b = effects_analyse(&file);
    assert_int_equal(a.needed, b.needed);
    assert_int_equal(a.needed, EFFECT_SHADOWS | EFFECT_INDIRECT);
    scene_desc_free(&built_in);
    scene_desc_free(&file);
    scene_free(&sc);
}

/* A mesh shape brings the OBJ's triangles with their MTL colours; an area
 * light becomes a point light (with a warning). */
static void test_scene_file_mesh_and_area_light_convert(void **state)
{
    (void)state;
    const char *text = "material m diffuse albedo 0.5 0.5 0.5\n"
                       "mesh generator tori_field triangles 1024\n"
                       "light area p0 0 5 0 p1 1 5 0 p2 1 5 1 p3 0 5 1 emission 2 2 2\n";
    scene sc;
    scene_from_text(&sc, text, EFFECT_SHADOWS);
    assert_int_equal(sc.shape_count, 1024);
    assert_int_equal(sc.light_count, 1);
    assert_close(sc.lights[0].intensity.x, 2.0, 1e-6); /* L_e x area 1 */
    assert_close(sc.lights[0].position.x, 0.5, 1e-6);
    scene_free(&sc);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_eye_ray_goes_through_the_pixel_centre),
        cmocka_unit_test(test_sphere_hit_from_outside),
        cmocka_unit_test(test_counting_crossings_tells_inside_from_outside),
        cmocka_unit_test(test_sphere_hit_from_inside_returns_the_exit),
        cmocka_unit_test(test_sphere_tangent_and_miss),
        cmocka_unit_test(test_far_small_sphere_is_hit_at_the_right_distance),
        cmocka_unit_test(test_naive_quadratic_fails_on_the_far_small_sphere),
        cmocka_unit_test(test_plane_hit_and_parallel_miss),
        cmocka_unit_test(test_triangle_hit_point_is_the_barycentric_combination),
        cmocka_unit_test(test_triangle_ray_in_its_plane_gives_no_hit_and_no_nan),
        cmocka_unit_test(test_tiny_triangle_is_hit),
        cmocka_unit_test(test_triangle_back_face_and_outside),
        cmocka_unit_test(test_watertight_triangles_do_not_leak_at_shared_edges),
        cmocka_unit_test(test_watertight_agrees_with_moller_trumbore_inside),
        cmocka_unit_test(test_torus_hit_along_its_plane),
        cmocka_unit_test(test_sphere_tracing_does_not_skip_a_thin_torus),
        cmocka_unit_test(test_sphere_tracing_grazing_ray),
        cmocka_unit_test(test_spawned_rays_never_rehit_their_surface),
        cmocka_unit_test(test_unoffset_rays_do_rehit_their_surface),
        cmocka_unit_test(test_offset_without_the_size_term_rehits),
        cmocka_unit_test(test_offset_without_the_coordinate_term_rehits),
        cmocka_unit_test(test_points_inside_a_closed_box_see_each_other),
        cmocka_unit_test(test_fixed_offset_near_zero_blocks_points_inside_a_small_box),
        cmocka_unit_test(test_rays_from_a_point_on_an_edge_do_not_stop_on_the_other_face),
        cmocka_unit_test(test_refracted_ray_into_a_sphere_finds_the_far_side),
        cmocka_unit_test(test_fixed_ulp_offset_starts_refracted_rays_beyond_a_far_sphere),
        cmocka_unit_test(test_blinn_phong_pixel_equals_the_formula),
        cmocka_unit_test(test_shadowed_point_gets_only_ambient),
        cmocka_unit_test(test_light_behind_the_surface_casts_no_shadow_ray),
        cmocka_unit_test(test_shadow_rays_do_not_hit_the_light_they_aim_at),
        cmocka_unit_test(test_unoffset_shadow_rays_hit_the_light_they_aim_at),
        cmocka_unit_test(test_shadow_rays_to_a_wall_through_zero_stop_short_of_it),
        cmocka_unit_test(test_far_end_offset_in_coordinate_ulps_hits_a_wall_through_zero),
        cmocka_unit_test(test_far_end_moved_by_its_own_error_alone_stops_on_a_small_far_wall),
        cmocka_unit_test(test_degenerate_collinear_triangles_are_never_hit),
        cmocka_unit_test(test_sliver_one_float_step_thick_is_still_hit),
        cmocka_unit_test(test_demo_is_bit_identical_for_one_and_two_threads),
        cmocka_unit_test(test_default_scene_file_renders_the_built_in_image),
        cmocka_unit_test(test_one_unoccluded_light_needs_no_shadow_ray),
        cmocka_unit_test(test_a_second_shape_brings_shadow_rays_back),
        cmocka_unit_test(test_scene_file_mesh_and_area_light_convert),
        cmocka_unit_test(test_built_in_scene_description_matches_its_file),
    };
    return cmocka_run_group_tests_name("ch01 ray casting", tests, NULL, NULL);
}
