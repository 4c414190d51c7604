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

/* ---- ray-sphere ----------------------------------------------------------- */

static void test_sphere_hit_from_outside(void **state)
{
    (void)state;
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

/* ---- shadow rays to a point on a light ----------------------------------- */

/* The ray offsets of ray.h (the tests below) must hold for the triangle
 * test every renderer runs, the watertight one, and for the lecture's. */
typedef bool (*triangle_hit_fn)(const triangle *, ray, hit_record *);
static const triangle_hit_fn triangle_hits[2] = {triangle_intersect_watertight_hit, triangle_intersect};
static const char *const triangle_hit_names[2] = {"watertight", "Moller-Trumbore"};

/* A floor triangle and a light triangle facing it, at a given scale and far
 * from the origin: from random floor points, shadow rays to random light
 * points (ray_spawn_to, as the path tracer builds them). Nothing lies
 * between them, so any hit is a hit on the floor the ray leaves or the light
 * it aims at: a false shadow. Returns how many of `count` rays had one;
 * `offset` false is the twin with bare end points and t_max = 1. */
static int count_false_shadows(triangle_hit_fn triangle_hit, float scale, bool offset, int count)
{
    pcg32 rng = pcg32_for_pixel(test_seed(4242), (uint64_t)scale);
    vec3 base = vec3_scale(vec3_make(0.7f, 0.3f, -0.55f), scale);
    triangle floor_tri = {vec3_add(base, vec3_scale(vec3_make(-1, 0, -1), scale)),
                          vec3_add(base, vec3_scale(vec3_make(1.2f, 0.01f, -0.9f), scale)),
                          vec3_add(base, vec3_scale(vec3_make(0.1f, -0.02f, 1.1f), scale))};
    triangle light_tri = {vec3_add(base, vec3_scale(vec3_make(-0.3f, 0.8f, -0.2f), scale)),
                          vec3_add(base, vec3_scale(vec3_make(0.1f, 0.83f, 0.35f), scale)),
                          vec3_add(base, vec3_scale(vec3_make(0.4f, 0.79f, -0.3f), scale))};
    vec3 n_floor = vec3_normalize(vec3_cross(vec3_sub(floor_tri.p1, floor_tri.p0), vec3_sub(floor_tri.p2, floor_tri.p0)));
    vec3 n_light = vec3_normalize(vec3_cross(vec3_sub(light_tri.p1, light_tri.p0), vec3_sub(light_tri.p2, light_tri.p0)));
    int false_shadows = 0;
    for (int i = 0; i < count; i++) {
        vec3 ends[2];
        const triangle *tris[2] = {&floor_tri, &light_tri};
        for (int k = 0; k < 2; k++) {
            float b1 = pcg32_float(&rng), b2 = pcg32_float(&rng);
            if (b1 + b2 > 1) {
                b1 = 1 - b1;
                b2 = 1 - b2;
            }
            ends[k] = vec3_add(vec3_add(vec3_scale(tris[k]->p0, 1 - b1 - b2), vec3_scale(tris[k]->p1, b1)),
                               vec3_scale(tris[k]->p2, b2));
        }
        ray shadow;
        if (offset) {
            shadow = ray_spawn_to(ends[0], n_floor, ends[1], n_light);
        } else {
            shadow = ray_make(ends[0], vec3_sub(ends[1], ends[0]));
            shadow.t_max = 1.0f;
        }
        hit_record hit;
        bool blocked = triangle_hit(&floor_tri, shadow, &hit) || triangle_hit(&light_tri, shadow, &hit);
        false_shadows += blocked;
    }
    return false_shadows;
}

static void test_shadow_rays_do_not_hit_the_light_they_aim_at(void **state)
{
    (void)state;
    const float scales[] = {1.0f, 1e2f, 1e4f, 1e6f};
    for (int test = 0; test < 2; test++)
        for (int s = 0; s < 4; s++) {
            int n = count_false_shadows(triangle_hits[test], scales[s], true, 20000);
            if (n != 0)
                fail_msg("%s, scale %g: %d of 20000 shadow rays hit their own floor or the light they aim at",
                         triangle_hit_names[test], scales[s], n);
        }
}

static void test_unoffset_shadow_rays_hit_the_light_they_aim_at(void **state)
{
    (void)state;
    /* The twin: from the bare hit point to the bare light point with
     * t_max = 1, rounding lands many end points a little beyond the light
     * or the start a little below the floor. */
    const float scales[] = {1.0f, 1e2f, 1e4f};
    for (int test = 0; test < 2; test++) {
        int total = 0;
        for (int s = 0; s < 3; s++)
            total += count_false_shadows(triangle_hits[test], scales[s], false, 20000);
        print_message("unoffset shadow rays, %s: %d of 60000 hit the floor or the light\n", triangle_hit_names[test],
                      total);
        assert_true(total > 100);
    }
}

/* A wall in the plane x = 0 (the Cornell box's green wall lies there) and
 * a light far from it, at several scales: shadow rays between random wall
 * points and random light points, built with ray_spawn_to from either end.
 * Near zero a coordinate's ulp is tiny, so the offset along the wall's
 * normal cannot be counted in ulps of x; it must also cover the rounding of
 * t at the far end of the segment, which grows with the segment's length.
 * Returns how many of `count` rays (each way, and spawned from the wall)
 * hit the wall they leave or aim at; `far_end_by_length` false is the twin
 * whose far end moves only by ray_offset_origin (ulps of its coordinates). */
static int count_false_shadows_at_zero(triangle_hit_fn triangle_hit, float scale, bool far_end_by_length, int count)
{
    pcg32 rng = pcg32_for_pixel(test_seed(4343), (uint64_t)(scale * 1000.0f));
    triangle wall = {vec3_make(0, 0, 0), vec3_make(0, scale, 0), vec3_make(0, 0, scale)};
    vec3 n_wall = vec3_make(1, 0, 0), n_light = vec3_make(0, -1, 0);
    int false_shadows = 0;
    for (int i = 0; i < count; i++) {
        float b1 = pcg32_float(&rng), b2 = pcg32_float(&rng);
        if (b1 + b2 > 1) {
            b1 = 1 - b1;
            b2 = 1 - b2;
        }
        vec3 on_wall = vec3_make(0.0f, scale * b1, scale * b2);
        vec3 on_light = vec3_scale(vec3_make(0.4f + 0.2f * pcg32_float(&rng), 0.99f, 0.4f + 0.2f * pcg32_float(&rng)), scale);
        hit_record hit;
        ray to_wall = ray_spawn_to(on_light, n_light, on_wall, n_wall);
        if (!far_end_by_length) {
            to_wall = ray_make(to_wall.origin, vec3_sub(ray_offset_origin(on_wall, n_wall), to_wall.origin));
            to_wall.t_max = 1.0f;
        }
        false_shadows += triangle_hit(&wall, to_wall, &hit);
        if (!far_end_by_length)
            continue;
        false_shadows += triangle_hit(&wall, ray_spawn_to(on_wall, n_wall, on_light, n_light), &hit);
        false_shadows += triangle_hit(&wall, ray_spawn(on_wall, n_wall, vec3_sub(on_light, on_wall)), &hit);
    }
    return false_shadows;
}

static void test_shadow_rays_to_a_wall_through_zero_stop_short_of_it(void **state)
{
    (void)state;
    const float scales[] = {1e-3f, 1.0f, 550.0f, 1e4f, 1e6f};
    for (int test = 0; test < 2; test++)
        for (int s = 0; s < 5; s++) {
            int n = count_false_shadows_at_zero(triangle_hits[test], scales[s], true, 20000);
            if (n != 0)
                fail_msg("%s, scale %g: %d of 60000 shadow rays hit the wall at x = 0 they leave or aim at",
                         triangle_hit_names[test], scales[s], n);
        }
}

static void test_far_end_offset_in_coordinate_ulps_hits_a_wall_through_zero(void **state)
{
    (void)state;
    /* The twin: the far end moved only by ulps of its own coordinates (a
     * fixed 2^-16 at x = 0), as ray_spawn_to did before. At the Cornell
     * box's scale a shadow ray from the light to the green wall then stops
     * on the wall in about 4 % of cases with Moller-Trumbore, whose t at the
     * far end errs by ulps of the whole segment: chapter 11 saw 0.6 % of the
     * box's direct light vanish when it joined paths from the light's side.
     * The watertight test's t on this wall is -o_x / d_x (its plane is
     * x = 0: shapes.h, watertight_plane_t), exact to an ulp of t: it
     * stopped on the wall for none of the 20,000 (the count is printed).
     * The length-based offset is for both, and for walls less kind. */
    int n = count_false_shadows_at_zero(triangle_intersect, 550.0f, false, 20000);
    int watertight = count_false_shadows_at_zero(triangle_intersect_watertight_hit, 550.0f, false, 20000);
    print_message("far end offset in coordinate ulps: %d of 20000 rays stop on the wall with Moller-Trumbore, "
                  "%d with the watertight test\n", n, watertight);
    assert_true(n > 100);
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

/* ---- leaving a surface: no self-intersection at any scale ----------------- */

static vec3 random_unit(pcg32 *rng)
{
    for (;;) {
        vec3 v = vec3_make(2 * pcg32_float(rng) - 1, 2 * pcg32_float(rng) - 1, 2 * pcg32_float(rng) - 1);
        float l2 = vec3_length_squared(v);
        if (l2 > 1e-4f && l2 <= 1.0f)
            return vec3_scale(v, 1.0f / sqrtf(l2));
    }
}

typedef struct {
    int self_hits;  /* outgoing rays that hit the surface they left */
    int trials;
} self_hit_count;

/* 10^4 random hits per scale on a sphere and a triangle placed away from the
 * origin at that scale; from each, a ray leaves into the open half space. A
 * convex or flat surface can never be hit again by such a ray. With
 * `offset` false the origin is the bare hit point: the twin that shows the
 * test can fail. */
static self_hit_count count_self_hits(triangle_hit_fn triangle_hit, float scale, bool offset)
{
    self_hit_count count = {0, 0};
    pcg32 rng = pcg32_for_pixel(test_seed(2024), (uint64_t)scale);
    sphere s = {vec3_scale(vec3_make(0.3f, -0.7f, 0.5f), scale), 0.8f * scale};
    triangle tri = {vec3_scale(vec3_make(1.1f, 0.2f, -0.4f), scale), vec3_scale(vec3_make(-0.3f, 0.9f, 0.6f), scale),
                    vec3_scale(vec3_make(0.4f, -0.8f, 1.3f), scale)};
    for (int i = 0; i < 10000; i++) {
        bool use_sphere = i % 2 == 0;
        /* A ray from a random point outside aimed at a random point of the shape. */
        vec3 origin = vec3_scale(vec3_scale(random_unit(&rng), 4.0f), scale);
        vec3 target;
        if (use_sphere) {
            target = vec3_add(s.center, vec3_scale(random_unit(&rng), s.radius * 0.9f));
        } else {
            float b1 = pcg32_float(&rng), b2 = pcg32_float(&rng);
            if (b1 + b2 > 1) {
                b1 = 1 - b1;
                b2 = 1 - b2;
            }
            target = vec3_add(vec3_add(vec3_scale(tri.p0, 1 - b1 - b2), vec3_scale(tri.p1, b1)), vec3_scale(tri.p2, b2));
        }
        ray in = ray_make(origin, vec3_normalize(vec3_sub(target, origin)));
        hit_record hit, again;
        bool found = use_sphere ? sphere_intersect(&s, in, &hit) : triangle_hit(&tri, in, &hit);
        if (!found)
            continue;
        /* Leave into the side the ray came from (a reflection or shadow ray). */
        vec3 out = random_unit(&rng);
        if (vec3_dot(out, hit.normal_geometric) < 0)
            out = vec3_neg(out);
        ray leaving = offset ? ray_spawn(hit.point, hit.normal_geometric, out) : ray_make(hit.point, out);
        bool again_found = use_sphere ? sphere_intersect(&s, leaving, &again) : triangle_hit(&tri, leaving, &again);
        count.trials++;
        count.self_hits += again_found;
    }
    return count;
}

static void test_spawned_rays_never_rehit_their_surface(void **state)
{
    (void)state;
    const float scales[] = {1.0f, 1e2f, 1e4f, 1e6f};
    for (int test = 0; test < 2; test++)
        for (int s = 0; s < 4; s++) {
            self_hit_count c = count_self_hits(triangle_hits[test], scales[s], true);
            assert_true(c.trials > 9000);
            if (c.self_hits != 0)
                fail_msg("%s, scale %g: %d of %d spawned rays hit their own surface", triangle_hit_names[test],
                         scales[s], c.self_hits, c.trials);
        }
}

static void test_unoffset_rays_do_rehit_their_surface(void **state)
{
    (void)state;
    /* The twin: without the offset, rounding puts about half the hit points
     * just behind the surface, and many rays find it again. */
    const float scales[] = {1.0f, 1e2f, 1e4f};
    for (int test = 0; test < 2; test++) {
        int total = 0;
        for (int s = 0; s < 3; s++)
            total += count_self_hits(triangle_hits[test], scales[s], false).self_hits;
        assert_true(total > 100);
    }
}

static void test_refracted_ray_into_a_sphere_finds_the_far_side(void **state)
{
    (void)state;
    /* A ray entering a sphere must reach the far side, not the entry point. */
    const float scales[] = {1.0f, 1e2f, 1e4f};
    pcg32 rng = pcg32_for_pixel(77, 0);
    for (int s = 0; s < 3; s++) {
        sphere sp = {vec3_make(0.5f * scales[s], 0, 0), scales[s]};
        for (int i = 0; i < 2000; i++) {
            vec3 n = random_unit(&rng);
            vec3 p = vec3_add(sp.center, vec3_scale(n, sp.radius));
            vec3 inward = random_unit(&rng);
            if (vec3_dot(inward, n) > -0.05f)
                continue;
            hit_record hit;
            ray r = ray_spawn(p, n, inward);
            assert_true(sphere_intersect(&sp, r, &hit));
            /* The chord length is 2 R |cos|: at least 0.1 R here. */
            assert_true(hit.t > 0.09f * sp.radius);
        }
    }
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
        cmocka_unit_test(test_sphere_hit_from_outside),
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
        cmocka_unit_test(test_refracted_ray_into_a_sphere_finds_the_far_side),
        cmocka_unit_test(test_blinn_phong_pixel_equals_the_formula),
        cmocka_unit_test(test_shadowed_point_gets_only_ambient),
        cmocka_unit_test(test_light_behind_the_surface_casts_no_shadow_ray),
        cmocka_unit_test(test_shadow_rays_do_not_hit_the_light_they_aim_at),
        cmocka_unit_test(test_unoffset_shadow_rays_hit_the_light_they_aim_at),
        cmocka_unit_test(test_shadow_rays_to_a_wall_through_zero_stop_short_of_it),
        cmocka_unit_test(test_far_end_offset_in_coordinate_ulps_hits_a_wall_through_zero),
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
