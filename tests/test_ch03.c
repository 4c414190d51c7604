/* test_ch03.c -- the slab test's IEEE cases, each beside the lecture's naive
 * version where it fails, and brute force through the interface. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>

#include "03-aabb-slabs/aabb.h"
#include "03-aabb-slabs/accel.h"
#include "03-aabb-slabs/accel_view.h"
#include "accel_check.h"
#include "mesh.h"
#include "test_support.h"

static const aabb unit_box = {{0, 0, 0}, {1, 1, 1}};

static bool slab(const aabb *b, ray r, float *t_enter, float *t_exit)
{
    slab_ray sr = slab_ray_make(r);
    return aabb_slab_test(b, &sr, r.t_min, r.t_max, t_enter, t_exit);
}

static ray ray_from(float ox, float oy, float oz, float dx, float dy, float dz)
{
    return ray_make(vec3_make(ox, oy, oz), vec3_make(dx, dy, dz));
}

static void test_slab_hit_from_outside_gives_enter_and_exit(void **state)
{
    (void)state;
    exercise_checks("slab_test");
    float t0, t1;
    /* From (-1, 0.5, 0.5) along +x: enters at x = 0 (t = 1), leaves at x = 1 (t = 2). */
    assert_true(slab(&unit_box, ray_from(-1, 0.5f, 0.5f, 1, 0, 0), &t0, &t1));
    assert_close(t0, 1.0, 0.0);
    assert_close(t1, 2.0, 2e-6); /* padded by the rounding bound, 2 gamma(3) */
    /* Diagonal: t_enter = max of the three t_min, t_exit = min of the t_max. */
    assert_true(slab(&unit_box, ray_from(-1, -0.5f, 0.25f, 2, 2, 0.5f), &t0, &t1));
    assert_close(t0, 0.5, 1e-6);  /* x enters last, at t = 0.5 */
    assert_close(t1, 0.75, 1e-6); /* y leaves first, at t = 0.75 */
}

static void test_slab_miss_and_box_behind(void **state)
{
    (void)state;
    exercise_checks("slab_test");
    float t0, t1;
    assert_false(slab(&unit_box, ray_from(-1, 2, 0.5f, 1, 0, 0), &t0, &t1));
    /* The box behind the origin: t_exit < 0. */
    assert_false(slab(&unit_box, ray_from(3, 0.5f, 0.5f, 1, 0, 0), &t0, &t1));
    /* A segment that ends before the box. */
    ray r = ray_from(-1, 0.5f, 0.5f, 1, 0, 0);
    r.t_max = 0.9f;
    assert_false(slab(&unit_box, r, &t0, &t1));
}

static void test_slab_origin_inside_enters_at_t_min(void **state)
{
    (void)state;
    exercise_checks("slab_test");
    float t0, t1;
    assert_true(slab(&unit_box, ray_from(0.5f, 0.5f, 0.5f, 0, 0, -1), &t0, &t1));
    assert_close(t0, 0.0, 0.0);
    assert_close(t1, 0.5, 1e-6);
}

/* Direction components of +0 and -0: 1/d is +inf or -inf, and the ray is
 * parallel to that pair of planes. Inside the slab: hit; outside: miss. */
static void test_slab_signed_zero_directions(void **state)
{
    (void)state;
    exercise_checks("slab_test");
    float t0, t1;
    const float zeros[2] = {0.0f, -0.0f};
    for (int i = 0; i < 2; i++) {
        float z = zeros[i];
        assert_true(slab(&unit_box, ray_from(-1, 0.5f, 0.5f, 1, z, z), &t0, &t1));
        assert_close(t0, 1.0, 0.0);
        assert_false(slab(&unit_box, ray_from(-1, 1.5f, 0.5f, 1, z, z), &t0, &t1));
        assert_false(slab(&unit_box, ray_from(-1, -0.5f, 0.5f, 1, z, z), &t0, &t1));
        /* -0 (and +0) directions with the origin inside the box. */
        assert_true(slab(&unit_box, ray_from(0.5f, 0.5f, 0.5f, z, z, -1), &t0, &t1));
        assert_close(t1, 0.5, 1e-6);
    }
}

/* The origin exactly on a slab plane, moving parallel to it: (lo - o) * inf
 * is 0 * inf = NaN. The ray runs along the box's face: it touches the box. */
static void test_slab_origin_on_a_plane_with_zero_direction(void **state)
{
    (void)state;
    exercise_checks("slab_test");
    float t0, t1;
    const float zeros[2] = {0.0f, -0.0f};
    for (int i = 0; i < 2; i++) {
        /* On the plane x = 0 (lo) and on x = 1 (hi), moving along +z. */
        assert_true(slab(&unit_box, ray_from(0, 0.5f, -1, zeros[i], 0.25f, 1), &t0, &t1));
        assert_close(t0, 1.0, 0.0);
        assert_true(slab(&unit_box, ray_from(1, 0.5f, -1, zeros[i], 0.25f, 1), &t0, &t1));
    }
    /* The twin: the lecture's test, min and max written the usual way, lets
     * the NaN through and misses. */
    assert_false(aabb_slab_test_naive(&unit_box, ray_from(0, 0.5f, -1, 0, 0.25f, 1), &t0, &t1));
}

/* A flat box: the bounds of a triangle lying in the plane y = 0.3. The ray
 * crosses that plane at a single t, so t_enter = t_exit exactly; the
 * lecture's strict t_enter < t_exit misses, and rounding can put t_enter one
 * ulp above t_exit. */
static void test_slab_flat_box_is_hit(void **state)
{
    (void)state;
    exercise_checks("slab_test");
    const aabb flat = {{-1, 0.3f, -1}, {1, 0.3f, 1}};
    float t0, t1;
    ray r = ray_from(0.1f, 1.3f, 0.2f, 0, -1, 0);
    assert_true(slab(&flat, r, &t0, &t1));
    assert_close(t0, 1.0, 1e-6);
    /* The twin: the lecture's strict comparison misses the flat box. */
    assert_false(aabb_slab_test_naive(&flat, r, &t0, &t1));

    /* Many oblique rays through random points of flat boxes at awkward
     * coordinates: every one must hit. */
    pcg32 rng = pcg32_for_pixel(3, 3);
    int misses = 0, naive_misses = 0;
    for (int i = 0; i < 100000; i++) {
        float y = (pcg32_float(&rng) - 0.5f) * 2000.0f;
        aabb box = {{-3.3f, y, -1.7f}, {2.9f, y, 4.1f}};
        vec3 target = vec3_make(-3.3f + 6.2f * pcg32_float(&rng), y, -1.7f + 5.8f * pcg32_float(&rng));
        vec3 origin = vec3_make(pcg32_float(&rng) * 50 - 25, y + 1 + pcg32_float(&rng) * 100,
                                pcg32_float(&rng) * 50 - 25);
        ray oblique = ray_make(origin, vec3_sub(target, origin));
        misses += !slab(&box, oblique, &t0, &t1);
        naive_misses += !aabb_slab_test_naive(&box, oblique, &t0, &t1);
    }
    assert_int_equal(misses, 0);
    assert_true(naive_misses > 1000);
}

static void test_slab_touching_an_edge_counts_as_hit(void **state)
{
    (void)state;
    exercise_checks("slab_test");
    float t0, t1;
    /* Along the edge x = 1, y = 1 of the box. */
    assert_true(slab(&unit_box, ray_from(1, 1, -1, 0, 0, 1), &t0, &t1));
    /* Through the corner (1, 1, 1) diagonally from outside. */
    assert_true(slab(&unit_box, ray_from(2, 2, 2, -1, -1, -1), &t0, &t1));
    assert_close(t0, 1.0, 1e-6);
}

static void test_surface_area_and_longest_axis(void **state)
{
    (void)state;
    aabb b = {{0, 0, 0}, {1, 2, 3}};
    assert_close(aabb_surface_area(b), 2.0 * (2 + 6 + 3), 0.0);
    assert_int_equal(aabb_longest_axis(b), 2);
    assert_close(aabb_surface_area(aabb_empty()), 0.0, 0.0);
}

/* ---- brute force through the interface ------------------------------------ */

static void test_brute_force_hits_a_closed_sphere_from_every_side(void **state)
{
    (void)state;
    mesh m;
    mesh_init(&m);
    mesh_icosphere(&m, vec3_make(0, 0, 0), 1.0f, 3, -1);
    triangle_set set;
    triangle_set_from_mesh(&set, &m);
    accel *a = brute_force_build(&set);
    pcg32 rng = pcg32_for_pixel(9, 9);
    for (int i = 0; i < 2000; i++) {
        vec3 from = vec3_scale(accel_check_random_unit(&rng), 5.0f);
        ray r = ray_make(from, vec3_normalize(vec3_neg(from)));
        hit_record hit;
        ray_counters c = {0};
        assert_true(accel_closest_hit(a, r, &hit, &c));
        /* The icosphere's faces lie inside the unit sphere, by at most the
         * sagitta of a level-3 face: t in [4, 4.01]. */
        assert_true(hit.t >= 4.0f - 1e-5f && hit.t <= 4.01f);
        assert_true(hit.front_face);
        assert_int_equal(c.primitive_tests, (uint64_t)set.count);
        /* Shadow ray ending before the sphere: no hit. */
        r.t_max = 3.9f;
        assert_false(accel_any_hit(a, r, &c));
    }
    accel_destroy(a);
    triangle_set_free(&set);
    mesh_free(&m);
}

static void test_icosphere_is_closed(void **state)
{
    (void)state;
    /* Every edge shared by exactly two faces: 3F = 2E, and V - E + F = 2. */
    mesh m;
    mesh_init(&m);
    mesh_icosphere(&m, vec3_make(0, 0, 0), 1.0f, 2, -1);
    assert_int_equal(m.face_count, 320);
    int edges = 3 * m.face_count / 2;
    assert_int_equal(m.position_count - edges + m.face_count, 2);
    mesh_free(&m);
}

static void test_tori_field_matches_the_embree_harness(void **state)
{
    (void)state;
    /* First and last vertex of `embree_bench obj 1024 x.obj` (printed with
     * %.9g, which round-trips floats), and its triangle count. */
    mesh m;
    mesh_init(&m);
    mesh_tori_field(&m, 1024);
    assert_int_equal(m.face_count, 1024);
    assert_int_equal(m.position_count, 512);
    assert_float_equal(m.positions[0].x, -0.0395200104f, 0.0f);
    assert_float_equal(m.positions[0].y, -0.334397793f, 0.0f);
    assert_float_equal(m.positions[0].z, -0.470703751f, 0.0f);
    mesh_free(&m);
}

static void test_mesh_view_heat_map_counts_cost(void **state)
{
    (void)state;
    mesh m;
    mesh_init(&m);
    mesh_icosphere(&m, vec3_make(0, 0, 0), 1.0f, 1, -1);
    triangle_set set;
    triangle_set_from_mesh(&set, &m);
    accel *a = brute_force_build(&set);
    accel_view view = {a, true, 2.0f * (float)set.count};
    ray_counters c = {0};
    vec3 colour = accel_view_radiance(&view, ray_from(0, 0, 5, 0, 0, -1), NULL, &c);
    /* Brute force tests every triangle: cost = count, half of the maximum. */
    vec3 expected = accel_heat_colour(0.5f);
    assert_float_equal(colour.x, expected.x, 0.0f);
    assert_float_equal(colour.y, expected.y, 0.0f);
    accel_destroy(a);
    triangle_set_free(&set);
    mesh_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_slab_hit_from_outside_gives_enter_and_exit),
        cmocka_unit_test(test_slab_miss_and_box_behind),
        cmocka_unit_test(test_slab_origin_inside_enters_at_t_min),
        cmocka_unit_test(test_slab_signed_zero_directions),
        cmocka_unit_test(test_slab_origin_on_a_plane_with_zero_direction),
        cmocka_unit_test(test_slab_flat_box_is_hit),
        cmocka_unit_test(test_slab_touching_an_edge_counts_as_hit),
        cmocka_unit_test(test_surface_area_and_longest_axis),
        cmocka_unit_test(test_brute_force_hits_a_closed_sphere_from_every_side),
        cmocka_unit_test(test_icosphere_is_closed),
        cmocka_unit_test(test_tori_field_matches_the_embree_harness),
        cmocka_unit_test(test_mesh_view_heat_map_counts_cost),
    };
    return cmocka_run_group_tests_name("ch03 bounding boxes", tests, NULL, NULL);
}
