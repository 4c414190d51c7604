/* test_ch06.c -- bounding volume hierarchies: both builds agree with brute
 * force; the hard cases of the chapter text, each with its answer worked out
 * by hand; and twins that show the naive step failing on them. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <omp.h>

#include "03-aabb-slabs/accel_program.h"
#include "03-aabb-slabs/accel_view.h"
#include "06-bvh/bvh.h"
#include "06-bvh/bvh_internal.h" /* the tuned slab test, checked against chapter 03's */
#include "render.h"
#include "scene_file.h"
#include "accel_check.h"
#include "test_support.h"

static accel *build_median(const triangle_set *set) { return bvh_build(set, BVH_SPLIT_MEDIAN); }
static accel *build_sah(const triangle_set *set) { return bvh_build(set, BVH_SPLIT_SAH); }
static accel *build_sah_distance_order(const triangle_set *set)
{
    accel *a = bvh_build(set, BVH_SPLIT_SAH);
    bvh_set_order(a, BVH_ORDER_DISTANCE);
    return a;
}

static ray ray_from(float ox, float oy, float oz, float dx, float dy, float dz)
{
    return ray_make(vec3_make(ox, oy, oz), vec3_make(dx, dy, dz));
}

/* ---- the structure invariants ---------------------------------------------- */

static bool box_contains(aabb outer, aabb inner)
{
    return outer.lo.x <= inner.lo.x && outer.lo.y <= inner.lo.y && outer.lo.z <= inner.lo.z &&
           inner.hi.x <= outer.hi.x && inner.hi.y <= outer.hi.y && inner.hi.z <= outer.hi.z;
}

/* Walks the tree from node n: every node's box contains its children's boxes
 * and its triangles' boxes; marks each leaf position it sees. */
static void check_subtree(const bvh *b, int n, int depth, int *seen_positions, int *leaves, int *max_depth)
{
    assert_true(n >= 0 && n < b->node_count);
    assert_true(depth < BVH_STACK_SIZE);
    if (depth > *max_depth)
        *max_depth = depth;
    const bvh_node *node = &b->nodes[n];
    if (bvh_node_is_leaf(node)) {
        (*leaves)++;
        for (int i = node->first; i < node->first + bvh_node_triangles(node); i++) {
            assert_true(i >= 0 && i < b->triangle_count);
            seen_positions[i]++;
            int t = b->triangle_index[i];
            assert_true(box_contains(node->box, b->base.set->boxes[t]));
            /* the stored corners (watertight test) or edges (Moller-Trumbore)
             * are the triangle's own; a degenerate one is stored as NaN */
            const triangle *tri = &b->base.set->triangles[t];
            const bvh_triangle *stored = &b->triangles[i];
            if (b->base.triangle_test == TRIANGLE_TEST_MOLLER_TRUMBORE)
                assert_true(stored->p0.x == tri->p0.x && stored->e1.y == tri->p1.y - tri->p0.y &&
                            stored->e2.z == tri->p2.z - tri->p0.z);
            else if (triangle_is_degenerate(tri))
                assert_true(isnan(stored->p0.x) && isnan(stored->p1.y) && isnan(stored->p2.z));
            else
                assert_memory_equal(stored, tri, sizeof *tri);
        }
        return;
    }
    assert_true(node->first > n && node->first + 1 < b->node_count);
    assert_true(box_contains(node->box, b->nodes[node->first].box));
    assert_true(box_contains(node->box, b->nodes[node->first + 1].box));
    check_subtree(b, node->first, depth + 1, seen_positions, leaves, max_depth);
    check_subtree(b, node->first + 1, depth + 1, seen_positions, leaves, max_depth);
}

/* Every triangle in exactly one leaf, boxes nested, the counts consistent. */
static void check_structure(const accel *a)
{
    const bvh *b = (const bvh *)a;
    int n = a->set->count;
    assert_int_equal(b->triangle_count, n);
    int *seen_positions = calloc((size_t)n + 1, sizeof *seen_positions);
    int *seen_triangles = calloc((size_t)n + 1, sizeof *seen_triangles);
    int leaves = 0, max_depth = 0;
    check_subtree(b, 0, 0, seen_positions, &leaves, &max_depth);
    for (int i = 0; i < n; i++) {
        assert_int_equal(seen_positions[i], 1); /* each leaf position in exactly one leaf */
        seen_triangles[b->triangle_index[i]]++;
    }
    for (int t = 0; t < n; t++)
        assert_int_equal(seen_triangles[t], 1); /* each triangle at exactly one position */
    assert_int_equal(leaves, a->stats.leaves);
    assert_int_equal(b->node_count, 2 * leaves - 1); /* every interior node has two children */
    assert_int_equal(a->stats.nodes, b->node_count);
    assert_int_equal(max_depth, a->stats.max_depth);
    free(seen_positions);
    free(seen_triangles);
}

/* ---- the differential test -------------------------------------------------- */

static void test_median_bvh_agrees_with_brute_force(void **state)
{
    (void)state;
    accel_check_all(build_median, 7500, "bvh median");
}

static void test_sah_bvh_agrees_with_brute_force(void **state)
{
    (void)state;
    exercise_checks("sah_split");
    accel_check_all(build_sah, 15000, "bvh sah");
}

static void test_distance_order_agrees_with_brute_force(void **state)
{
    (void)state;
    accel_check_all(build_sah_distance_order, 3000, "bvh sah, distance order");
}

/* ---- the structure --------------------------------------------------------- */

static void test_every_triangle_in_exactly_one_leaf_and_boxes_nest(void **state)
{
    (void)state;
    for (int kind = 0; kind < MESH_KIND_COUNT; kind++) {
        mesh m;
        accel_check_make_mesh(&m, (accel_check_mesh)kind);
        triangle_set set;
        triangle_set_from_mesh(&set, &m);
        for (int split = 0; split < 2; split++) {
            accel *a = bvh_build(&set, split ? BVH_SPLIT_SAH : BVH_SPLIT_MEDIAN);
            check_structure(a);
            accel_destroy(a);
        }
        triangle_set_free(&set);
        mesh_free(&m);
    }
}

/* The SAH is built to minimise this sum; the median split ignores it. */
static void test_sah_tree_is_cheaper_than_median_tree_on_the_tori_field(void **state)
{
    (void)state;
    exercise_checks("sah_split");
    mesh m;
    mesh_init(&m);
    mesh_tori_field(&m, 10240);
    triangle_set set;
    triangle_set_from_mesh(&set, &m);
    accel *median = bvh_build(&set, BVH_SPLIT_MEDIAN), *sah = bvh_build(&set, BVH_SPLIT_SAH);
    double cost_median = bvh_sah_cost((const bvh *)median), cost_sah = bvh_sah_cost((const bvh *)sah);
    print_message("SAH cost: median tree %.2f, SAH tree %.2f\n", cost_median, cost_sah);
    assert_true(cost_sah < cost_median);
    accel_destroy(median);
    accel_destroy(sah);
    triangle_set_free(&set);
    mesh_free(&m);
}

/* ---- all centroids equal ------------------------------------------------------ */

/* 64 copies of the triangle (-1,-1,0), (1,-1,0), (0,1,0): no plane separates
 * them, so both builds make one leaf. The ray from (0,0,-1) along +z meets
 * it at t = 1, at (0,0,0) = (1 - b1 - b2) P0 + b1 P1 + b2 P2: from y,
 * -1 + 2 b2 = 0, b2 = 1/2; from x, -1 + 2 b1 + b2 = 0, b1 = 1/4. Any-hit
 * stops at the first triangle; closest-hit tests all 64. */
static void test_coincident_triangles_make_one_leaf(void **state)
{
    (void)state;
    mesh m;
    mesh_init(&m);
    mesh_coincident(&m, 64);
    triangle_set set;
    triangle_set_from_mesh(&set, &m);
    for (int split = 0; split < 2; split++) {
        accel *a = bvh_build(&set, split ? BVH_SPLIT_SAH : BVH_SPLIT_MEDIAN);
        assert_int_equal(a->stats.nodes, 1);
        assert_int_equal(a->stats.leaves, 1);
        check_structure(a);
        ray r = ray_from(0, 0, -1, 0, 0, 1);
        hit_record hit;
        ray_counters closest = {0}, any = {0};
        assert_true(accel_closest_hit(a, r, &hit, &closest));
        assert_close(hit.t, 1.0, 0.0);
        assert_close(hit.u, 0.25, 1e-7);
        assert_close(hit.v, 0.5, 1e-7);
        assert_int_equal(closest.primitive_tests, 64);
        assert_true(accel_any_hit(a, r, &any));
        assert_int_equal(any.primitive_tests, 1);
        accel_destroy(a);
    }
    triangle_set_free(&set);
    mesh_free(&m);
}

/* 1000 tiny triangles at the same point.
 * First: sizes s around p = (0.1, 0.2, 0.3), corners p + s (-1,-1,0),
 * p + s (1,-1,0), p + s (0,1,0): the boxes' centroids (p - s + p + s) / 2
 * differ from p only by rounding, a few ulps, so the bins are a few ulps
 * wide. A ray from p - (0,0,1) along +z must hit at t = 1.
 * Second: corners 0, (s,0,0), (0,s,0) with subnormal s ~ 1e-40: the
 * centroids s/2 differ, but bins / extent overflows to inf, so no axis can
 * be binned (the median split takes over). Such triangles are too small
 * for any float ray test; the hit must agree with brute force.
 * Both builds must terminate with at most 2 N - 1 nodes and a valid tree. */
static void test_tiny_triangles_at_one_point(void **state)
{
    (void)state;
    const vec3 p = vec3_make(0.1f, 0.2f, 0.3f);
    for (int c = 0; c < 2; c++) {
        mesh m;
        mesh_init(&m);
        for (int i = 0; i < 1000; i++) {
            float s = (c == 0 ? 1e-5f : 1e-40f) * (1.0f + (float)i / 1000.0f);
            vec3 corners[2][3] = {{vec3_add(p, vec3_make(-s, -s, 0)), vec3_add(p, vec3_make(s, -s, 0)),
                                   vec3_add(p, vec3_make(0, s, 0))},
                                  {vec3_make(0, 0, 0), vec3_make(s, 0, 0), vec3_make(0, s, 0)}};
            int a = mesh_add_position(&m, corners[c][0]);
            int b = mesh_add_position(&m, corners[c][1]);
            int d = mesh_add_position(&m, corners[c][2]);
            mesh_add_triangle(&m, a, b, d, -1);
        }
        triangle_set set;
        triangle_set_from_mesh(&set, &m);
        accel *brute = brute_force_build(&set);
        for (int split = 0; split < 2; split++) {
            accel *a = bvh_build(&set, split ? BVH_SPLIT_SAH : BVH_SPLIT_MEDIAN);
            assert_true(a->stats.nodes <= 2 * 1000 - 1);
            check_structure(a);
            ray r = c == 0 ? ray_from(p.x, p.y, p.z - 1.0f, 0, 0, 1) : ray_from(2e-41f, 2e-41f, -1, 0, 0, 1);
            hit_record hit, want;
            ray_counters counters = {0};
            bool want_hit = accel_closest_hit(brute, r, &want, &counters);
            assert_int_equal(accel_closest_hit(a, r, &hit, &counters), want_hit);
            if (c == 0) {
                assert_true(want_hit);
                assert_close(hit.t, 1.0, 1e-6);
                assert_true(hit.t == want.t);
            }
            accel_destroy(a);
        }
        accel_destroy(brute);
        triangle_set_free(&set);
        mesh_free(&m);
    }
}

/* ---- a centroid on the bounds' maximum -------------------------------------- */

/* The lecture-style bin index, floor((c - lo) * bins / extent), as usually
 * written: the twin of bvh_bin_index(). */
static int naive_bin_index(float c, float lo, float scale) { return (int)((c - lo) * scale); }

/* Bins over centroids in [0, 1], 16 of them: scale 16. The centroid on the
 * maximum, c = 1, gives (1 - 0) * 16 = 16, one past the last bin, 15. Every
 * set has a centroid on its maximum, so without the clamp every build would
 * write past its bins. And one ulp below the maximum can round up too: with
 * lo = 0x1.205bcp-6, hi = 0x1.10abb4p+0, the centroid 0x1.10abb2p+0 < hi
 * also gives exactly 16.0 (found by search, checked in float). */
static void test_centroid_on_the_bounds_maximum_goes_to_the_last_bin(void **state)
{
    (void)state;
    assert_int_equal(bvh_bin_index(1.0f, 0.0f, 16.0f, 16), 15);
    assert_int_equal(bvh_bin_index(0.0f, 0.0f, 16.0f, 16), 0);
    assert_int_equal(bvh_bin_index(0.5f, 0.0f, 16.0f, 16), 8);
    assert_int_equal(bvh_bin_index(NAN, 0.0f, 16.0f, 16), 0);
    float lo = 0x1.205bcp-6f, hi = 0x1.10abb4p+0f, c = 0x1.10abb2p+0f;
    float scale = 16.0f / (hi - lo);
    assert_true(c < hi);
    assert_int_equal(bvh_bin_index(c, lo, scale, 16), 15);
    /* the twin: without the clamp, both land in bin 16, past the end */
    assert_int_equal(naive_bin_index(1.0f, 0.0f, 16.0f), 16);
    assert_int_equal(naive_bin_index(c, lo, scale), 16);
}

/* Three triangles with centroids x = 0, 1, 2: the last is on the maximum.
 * The SAH build must place all three, and find each. */
static void test_sah_build_with_a_centroid_on_the_maximum(void **state)
{
    (void)state;
    exercise_checks("sah_split");
    mesh m;
    mesh_init(&m);
    for (int i = 0; i < 3; i++) {
        float x = (float)i;
        int a = mesh_add_position(&m, vec3_make(x, -1, -1));
        int b = mesh_add_position(&m, vec3_make(x, 3, -1));
        int c = mesh_add_position(&m, vec3_make(x, -1, 3));
        mesh_add_triangle(&m, a, b, c, -1);
    }
    triangle_set set;
    triangle_set_from_mesh(&set, &m);
    accel *a = bvh_build(&set, BVH_SPLIT_SAH);
    check_structure(a);
    for (int i = 0; i < 3; i++) {
        /* from x = -0.5 + i along +x: the first triangle ahead is i, at t = 0.5 */
        hit_record hit;
        ray_counters counters = {0};
        assert_true(accel_closest_hit(a, ray_from(-0.5f + (float)i, 0, 0, 1, 0, 0), &hit, &counters));
        assert_int_equal(hit.shape_id, i);
        assert_close(hit.t, 0.5, 0.0);
    }
    accel_destroy(a);
    triangle_set_free(&set);
    mesh_free(&m);
}

/* ---- overlapping children: the closer hit in the far child ------------------ */

/* Triangles, each covering the z axis except D:
 *   A in z = 9, B in z = 2.5, D in z = 1 but off at x = 5..6.
 * Built by hand: the root splits along z; its first child holds A and D, so
 * its box is z = 1..9; its second holds B, z = 2.5. The ray from the origin
 * along +z enters the first child first on both orders (it comes first on
 * +z, and its t_enter = 1 < 2.5): there it finds A at t = 9. The closest
 * hit is B at t = 2.5, in the child visited second: its box overlaps the
 * first's. */
enum { TRI_A, TRI_B, TRI_D };

static void make_overlap_scene(mesh *m, triangle_set *set)
{
    mesh_init(m);
    const float z[3] = {9.0f, 2.5f, 1.0f}, x0[3] = {-1.0f, -1.0f, 5.0f};
    for (int i = 0; i < 3; i++) {
        int a = mesh_add_position(m, vec3_make(x0[i], -1, z[i]));
        int b = mesh_add_position(m, vec3_make(x0[i] + 2.0f, -1, z[i]));
        int c = mesh_add_position(m, vec3_make(x0[i] + 1.0f, 1, z[i]));
        mesh_add_triangle(m, a, b, c, -1);
    }
    triangle_set_from_mesh(set, m);
}

static accel *overlap_tree(const triangle_set *set, int first_child_triangles[2], int second_child_triangle)
{
    int order[3] = {first_child_triangles[0], first_child_triangles[1], second_child_triangle};
    bvh_node nodes[3];
    memset(nodes, 0, sizeof nodes);
    nodes[1].box = aabb_union(set->boxes[order[0]], set->boxes[order[1]]);
    nodes[1].first = 0;
    nodes[1].count_axis = 2u << 2;
    nodes[2].box = set->boxes[order[2]];
    nodes[2].first = 2;
    nodes[2].count_axis = 1u << 2;
    nodes[0].box = aabb_union(nodes[1].box, nodes[2].box);
    nodes[0].first = 1;
    nodes[0].count_axis = 2; /* interior, split axis z */
    return bvh_from_nodes(set, nodes, 3, order, 3);
}

/* The naive traversal the twin uses: near child first (by the sign of d on
 * the split axis, as BVH_ORDER_AXIS_SIGN) and return the first hit found. */
static bool naive_first_hit(const bvh *b, ray r, float *t_out, int *triangle_out)
{
    int stack[BVH_STACK_SIZE], top = 0, current = 0;
    bvh_ray br = bvh_ray_make(&r);
    for (;;) {
        const bvh_node *node = &b->nodes[current];
        float t_enter;
        if (bvh_slab_test(node, &br, r.t_min, r.t_max, &t_enter)) {
            if (!bvh_node_is_leaf(node)) {
                int negative = vec3_axis(r.direction, bvh_node_axis(node)) < 0.0f;
                stack[top++] = node->first + 1 - negative;
                current = node->first + negative;
                continue;
            }
            for (int i = node->first; i < node->first + bvh_node_triangles(node); i++) {
                float t, b1, b2;
                if (triangle_intersect_watertight(&b->base.set->triangles[b->triangle_index[i]], &r, &t, &b1, &b2)) {
                    *t_out = t;
                    *triangle_out = b->triangle_index[i];
                    return true; /* the mistake: a closer hit may wait in a child not visited yet */
                }
            }
        }
        if (top == 0)
            return false;
        current = stack[--top];
    }
}

static void test_far_child_holds_the_closer_hit(void **state)
{
    (void)state;
    mesh m;
    triangle_set set;
    make_overlap_scene(&m, &set);
    accel *a = overlap_tree(&set, (int[2]){TRI_A, TRI_D}, TRI_B);
    assert_non_null(a);
    check_structure(a);
    ray r = ray_from(0, 0, 0, 0, 0, 1);
    for (int order = 0; order < 2; order++) {
        bvh_set_order(a, order ? BVH_ORDER_DISTANCE : BVH_ORDER_AXIS_SIGN);
        hit_record hit;
        ray_counters counters = {0};
        assert_true(accel_closest_hit(a, r, &hit, &counters));
        assert_int_equal(hit.shape_id, TRI_B);
        assert_close(hit.t, 2.5, 0.0);
        assert_int_equal(counters.primitive_tests, 3); /* A and D, then B */
    }
    /* the twin: stopping at the first hit found returns A at t = 9 */
    float t = 0.0f;
    int tri = -1;
    assert_true(naive_first_hit((const bvh *)a, r, &t, &tri));
    assert_int_equal(tri, TRI_A);
    assert_close(t, 9.0, 0.0);
    accel_destroy(a);
    triangle_set_free(&set);
    mesh_free(&m);
}

/* The same scene the other way round: B in the first child (z = 1..2.5, with
 * D), A alone in the second (z = 9). The hit B at t = 2.5 is found first;
 * the second child begins at t = 9 > 2.5 and is skipped: its triangle is
 * never tested. Axis-sign order tests its box and rejects it (3 box tests);
 * distance order tested both boxes at the root and drops it from the stack
 * (also 3: the root, then both children). */
static void test_far_child_beyond_the_closest_hit_is_skipped(void **state)
{
    (void)state;
    mesh m;
    triangle_set set;
    make_overlap_scene(&m, &set);
    accel *a = overlap_tree(&set, (int[2]){TRI_B, TRI_D}, TRI_A);
    assert_non_null(a);
    ray r = ray_from(0, 0, 0, 0, 0, 1);
    for (int order = 0; order < 2; order++) {
        bvh_set_order(a, order ? BVH_ORDER_DISTANCE : BVH_ORDER_AXIS_SIGN);
        hit_record hit;
        ray_counters counters = {0};
        assert_true(accel_closest_hit(a, r, &hit, &counters));
        assert_int_equal(hit.shape_id, TRI_B);
        assert_int_equal(counters.primitive_tests, 2); /* B and D, never A */
        assert_int_equal(counters.box_tests, 3);
    }
    accel_destroy(a);
    triangle_set_free(&set);
    mesh_free(&m);
}

/* A near-tie at a shared vertex, from the differential test (icosphere, ray
 * 4243): the ray is aimed at the vertex V that triangles X and Y share, so
 * the exact t is 1 for both. Moller-Trumbore computes t_X = 0x1.fffffcp-1
 * and t_Y = 0x1.fffeeep-1, 134 ulps earlier. But Y's box begins at V, after
 * t_X: a traversal that finds X first and then culls boxes beginning beyond
 * the closest hit exactly skips Y, and returns X, while brute force returns
 * Y. The cull therefore has a slack (BVH_CULL_SLACK in bvh_traverse.c).
 * Found with Moller-Trumbore, so run with it (accel_use_triangle_test): the
 * watertight test every structure now runs errs too (here it misses X and
 * gives t_Y = 0x1.00007ap+0, 122 ulps late), and the slack covers either. */
static void test_shared_vertex_near_tie_is_not_culled(void **state)
{
    (void)state;
    const triangle x = {{0x1.672b22p-1f, 0x1.5fbd6ap-3f, 0x1.01d1cp+0f},
                        {0x1.541922p-1f, 0x1.40e57cp-2f, 0x1.e4a5d6p-1f},
                        {0x1.23093cp-1f, 0x1.041618p-2f, 0x1.0ed4dcp+0f}};
    const triangle y = {{0x1.333332p-1f, 0x1.be8894p-4f, 0x1.1be888p+0f},
                        {0x1.69e4fep-1f, 0x1.2fcfa8p-5f, 0x1.0f03d6p+0f},
                        {0x1.672b22p-1f, 0x1.5fbd6ap-3f, 0x1.01d1cp+0f}};
    ray r = ray_from(0x1.3ae826p+0f, 0x1.7bfe2ap+1f, -0x1.0d4ceep-1f, -0x1.0ea52ap-1f, -0x1.660254p+1f,
                     0x1.887838p+0f);
    mesh m;
    mesh_init(&m);
    const triangle *tris[2] = {&x, &y};
    for (int i = 0; i < 2; i++)
        mesh_add_triangle(&m, mesh_add_position(&m, tris[i]->p0), mesh_add_position(&m, tris[i]->p1),
                          mesh_add_position(&m, tris[i]->p2), -1);
    triangle_set set;
    triangle_set_from_mesh(&set, &m);
    /* the root splits along z, on which d > 0: X's leaf (the first child) is
     * visited first in axis-sign order; its box is also entered first */
    bvh_node nodes[3];
    memset(nodes, 0, sizeof nodes);
    nodes[1].box = set.boxes[0];
    nodes[1].count_axis = 1u << 2;
    nodes[2].box = set.boxes[1];
    nodes[2].first = 1;
    nodes[2].count_axis = 1u << 2;
    nodes[0].box = aabb_union(nodes[1].box, nodes[2].box);
    nodes[0].first = 1;
    nodes[0].count_axis = 2;
    accel *a = bvh_from_nodes(&set, nodes, 3, (int[2]){0, 1}, 2);
    accel *brute = brute_force_build(&set);
    assert_true(accel_use_triangle_test(a, TRIANGLE_TEST_MOLLER_TRUMBORE));
    assert_true(accel_use_triangle_test(brute, TRIANGLE_TEST_MOLLER_TRUMBORE));
    hit_record hit, want;
    ray_counters counters = {0};
    assert_true(accel_closest_hit(brute, r, &want, &counters));
    assert_int_equal(want.shape_id, 1);
    assert_true(want.t == 0x1.fffeeep-1f);
    for (int order = 0; order < 2; order++) {
        bvh_set_order(a, order ? BVH_ORDER_DISTANCE : BVH_ORDER_AXIS_SIGN);
        assert_true(accel_closest_hit(a, r, &hit, &counters));
        assert_int_equal(hit.shape_id, 1);
        assert_true(hit.t == want.t);
    }
    /* the twin: X's hit, and Y's box tested against it without the slack */
    float t_x, b1, b2, t_enter;
    assert_true(triangle_intersect_barycentric(&x, &r, &t_x, &b1, &b2));
    assert_true(t_x == 0x1.fffffcp-1f);
    bvh_ray br = bvh_ray_make(&r);
    assert_false(bvh_slab_test(&nodes[2], &br, r.t_min, t_x, &t_enter));
    accel_destroy(brute);
    accel_destroy(a);
    triangle_set_free(&set);
    mesh_free(&m);
}

static void test_hand_built_tree_is_checked(void **state)
{
    (void)state;
    mesh m;
    triangle_set set;
    make_overlap_scene(&m, &set);
    bvh_node nodes[3];
    memset(nodes, 0, sizeof nodes);
    nodes[0].first = 1;
    nodes[0].count_axis = 2;
    nodes[1].count_axis = 1u << 2;
    nodes[2].first = 1;
    nodes[2].count_axis = 5u << 2; /* a leaf past the end */
    int order[3] = {0, 1, 2};
    assert_null(bvh_from_nodes(&set, nodes, 3, order, 3));
    nodes[2].count_axis = 2u << 2;
    accel *a = bvh_from_nodes(&set, nodes, 3, order, 3);
    assert_non_null(a);
    accel_destroy(a);
    nodes[0].first = 2; /* the second child would be nodes[3] */
    assert_null(bvh_from_nodes(&set, nodes, 3, order, 3));
    triangle_set_free(&set);
    mesh_free(&m);
}

/* ---- the lecture's recursive traversal ------------------------------------------ */

typedef bool (*bvh_closest_fn)(const bvh *b, ray r, hit_record *hit, ray_counters *counters);

/* The twin: the slide's recursion with its last line wrong, "return hit1 if
 * there is one, else hit2": the first hit in tree order, not the closer. */
typedef struct {
    int triangle; /* in the set; -1: none */
    float t, b1, b2;
} twin_hit;

static twin_hit first_hit_recursive(const bvh *b, const ray *r, const slab_ray *sr, int n)
{
    const bvh_node *node = &b->nodes[n];
    twin_hit none = {-1, 0.0f, 0.0f, 0.0f};
    float t_enter, t_exit;
    if (!aabb_slab_test(&node->box, sr, r->t_min, r->t_max, &t_enter, &t_exit))
        return none;
    if (bvh_node_is_leaf(node)) {
        twin_hit closest = none;
        ray shorter = *r;
        for (int i = node->first; i < node->first + bvh_node_triangles(node); i++) {
            twin_hit h = {b->triangle_index[i], 0.0f, 0.0f, 0.0f};
            if (triangle_intersect_watertight(&b->base.set->triangles[h.triangle], &shorter, &h.t, &h.b1, &h.b2)) {
                closest = h;
                shorter.t_max = h.t;
            }
        }
        return closest;
    }
    twin_hit hit1 = first_hit_recursive(b, r, sr, node->first);
    if (hit1.triangle >= 0)
        return hit1; /* the mistake: child2 may hold a closer hit */
    return first_hit_recursive(b, r, sr, node->first + 1);
}

static bool first_hit_recursive_closest(const bvh *b, ray r, hit_record *hit, ray_counters *counters)
{
    (void)counters;
    slab_ray sr = slab_ray_make(r);
    twin_hit h = first_hit_recursive(b, &r, &sr, 0);
    if (h.triangle < 0)
        return false;
    triangle_set_fill_hit(b->base.set, h.triangle, r, h.t, h.b1, h.b2, hit);
    return true;
}

/* Over the differential test's meshes and rays (accel_check.h), on trees of
 * both splits: how many rays get an answer other than brute force's (hit or
 * miss, t bit for bit, the same triangle), and how many hit at all. */
static long recursive_mismatches(bvh_closest_fn closest, int ray_count, long *hits)
{
    long mismatches = 0;
    *hits = 0;
    for (int kind = 0; kind < MESH_KIND_COUNT; kind++) {
        mesh m;
        accel_check_make_mesh(&m, (accel_check_mesh)kind);
        triangle_set set;
        triangle_set_from_mesh(&set, &m);
        accel *brute = brute_force_build(&set);
        for (int split = 0; split < 2; split++) {
            accel *a = bvh_build(&set, split ? BVH_SPLIT_SAH : BVH_SPLIT_MEDIAN);
            pcg32 rng = pcg32_for_pixel(20261123, (uint64_t)kind);
            for (int i = 0; i < ray_count; i++) {
                ray r = accel_check_ray(&m, set.bounds.lo, set.bounds.hi, &rng, i);
                hit_record want, got;
                ray_counters counters = {0};
                bool want_hit = accel_closest_hit(brute, r, &want, &counters);
                bool got_hit = closest((const bvh *)a, r, &got, &counters);
                *hits += want_hit;
                if (want_hit != got_hit || (want_hit && (got.t != want.t || got.shape_id != want.shape_id))) {
                    if (mismatches < 3)
                        print_message("%s, %s split, ray %d: brute %s t=%a tri %d, recursive %s t=%a tri %d\n",
                                      accel_check_mesh_names[kind], split ? "sah" : "median", i,
                                      want_hit ? "hit" : "miss", want_hit ? (double)want.t : 0.0,
                                      want_hit ? want.shape_id : -1, got_hit ? "hit" : "miss",
                                      got_hit ? (double)got.t : 0.0, got_hit ? got.shape_id : -1);
                    mismatches++;
                }
            }
            accel_destroy(a);
        }
        accel_destroy(brute);
        triangle_set_free(&set);
        mesh_free(&m);
    }
    return mismatches;
}

enum { RECURSIVE_CHECK_RAYS = 2000 };

/* The slide's recursion returns brute force's closest hit: the same t, bit
 * for bit (the same Moller-Trumbore on the same triangle), and the same
 * triangle (ties at equal t go to the lower index, as in brute force). It
 * tests every leaf whose box the ray crosses, and brute force's triangle
 * lies in one of them. */
static void test_recursive_traversal_equals_brute_force(void **state)
{
    (void)state;
    exercise_checks("bvh_intersect");
    long hits;
    long mismatches = recursive_mismatches(bvh_closest_hit_recursive, RECURSIVE_CHECK_RAYS, &hits);
    print_message("recursive traversal: %ld of %d rays differ from brute force (%ld hits)\n", mismatches,
                  2 * MESH_KIND_COUNT * RECURSIVE_CHECK_RAYS, hits);
    assert_int_equal(mismatches, 0);
    assert_true(hits > MESH_KIND_COUNT * RECURSIVE_CHECK_RAYS); /* more than a quarter of the rays hit */
}

/* Its twin returns the first hit in tree order and must fail the same check
 * (on a closed mesh a ray through it crosses at least two triangles, and
 * child1 holds the farther one about half the time). */
static void test_recursive_twin_returning_the_first_hit_is_caught(void **state)
{
    (void)state;
    long hits;
    long mismatches = recursive_mismatches(first_hit_recursive_closest, RECURSIVE_CHECK_RAYS, &hits);
    print_message("twin (first hit, not the closer): %ld of %d rays differ from brute force\n", mismatches,
                  2 * MESH_KIND_COUNT * RECURSIVE_CHECK_RAYS);
    assert_true(mismatches > hits / 10);
}

/* The iterative traversals test a node's box against [t_min, closest hit
 * so far]; the recursion against the whole ray [t_min, t_max]. With
 * t_max = inf, whatever box passes the first passes the second (the slab
 * test is the same float arithmetic, and its answer only grows with t_max),
 * so every node the iterative traversals reach, the recursion reaches too:
 * per ray, at least as many box tests and triangle tests, in either order.
 * And fewer is the point of the pruning: over all rays, strictly more,
 * except on the flat mesh, where every box lies in the one plane z = 0.5
 * and so begins where the hit is: nothing lies beyond it to skip. On the
 * overlap scene with B found first, the recursion tests A as well (the
 * worked example of test_far_child_beyond_the_closest_hit_is_skipped). */
static void test_recursive_traversal_visits_at_least_as_many_nodes(void **state)
{
    (void)state;
    exercise_checks("bvh_intersect");
    mesh m;
    triangle_set set;
    make_overlap_scene(&m, &set);
    accel *a = overlap_tree(&set, (int[2]){TRI_B, TRI_D}, TRI_A);
    hit_record hit;
    ray_counters counters = {0};
    assert_true(bvh_closest_hit_recursive((const bvh *)a, ray_from(0, 0, 0, 0, 0, 1), &hit, &counters));
    assert_int_equal(hit.shape_id, TRI_B);
    assert_int_equal(counters.box_tests, 3);       /* the root and both children */
    assert_int_equal(counters.primitive_tests, 3); /* B and D, then A: the iterative ones skip A */
    accel_destroy(a);
    triangle_set_free(&set);
    mesh_free(&m);

    for (int kind = 0; kind < MESH_KIND_COUNT; kind++) {
        accel_check_make_mesh(&m, (accel_check_mesh)kind);
        triangle_set_from_mesh(&set, &m);
        a = bvh_build(&set, BVH_SPLIT_SAH);
        const bvh *b = (const bvh *)a;
        pcg32 rng = pcg32_for_pixel(20261123, (uint64_t)kind);
        ray_counters total[3] = {{0}, {0}, {0}}; /* recursive, axis sign, distance */
        for (int i = 0; i < 4 * RECURSIVE_CHECK_RAYS; i++) {
            ray r = accel_check_ray(&m, set.bounds.lo, set.bounds.hi, &rng, i);
            ray_counters c[3] = {{0}, {0}, {0}};
            bvh_closest_hit_recursive(b, r, &hit, &c[0]);
            bvh_set_order(a, BVH_ORDER_AXIS_SIGN);
            accel_closest_hit(a, r, &hit, &c[1]);
            bvh_set_order(a, BVH_ORDER_DISTANCE);
            accel_closest_hit(a, r, &hit, &c[2]);
            for (int k = 1; k < 3; k++)
                if (c[0].box_tests < c[k].box_tests || c[0].primitive_tests < c[k].primitive_tests)
                    fail_msg("%s, ray %d: recursive %llu boxes %llu triangles, %s order %llu boxes %llu triangles",
                             accel_check_mesh_names[kind], i, (unsigned long long)c[0].box_tests,
                             (unsigned long long)c[0].primitive_tests, k == 1 ? "axis-sign" : "distance",
                             (unsigned long long)c[k].box_tests, (unsigned long long)c[k].primitive_tests);
            for (int k = 0; k < 3; k++) {
                total[k].box_tests += c[k].box_tests;
                total[k].primitive_tests += c[k].primitive_tests;
            }
        }
        print_message("%-17s boxes, triangles per ray: recursive %6.1f %6.1f, axis-sign %6.1f %6.1f, distance "
                      "%6.1f %6.1f\n",
                      accel_check_mesh_names[kind], (double)total[0].box_tests / (4 * RECURSIVE_CHECK_RAYS),
                      (double)total[0].primitive_tests / (4 * RECURSIVE_CHECK_RAYS),
                      (double)total[1].box_tests / (4 * RECURSIVE_CHECK_RAYS),
                      (double)total[1].primitive_tests / (4 * RECURSIVE_CHECK_RAYS),
                      (double)total[2].box_tests / (4 * RECURSIVE_CHECK_RAYS),
                      (double)total[2].primitive_tests / (4 * RECURSIVE_CHECK_RAYS));
        if (kind != MESH_FLAT)
            assert_true(total[0].box_tests > total[1].box_tests &&
                        total[0].primitive_tests > total[1].primitive_tests);
        accel_destroy(a);
        triangle_set_free(&set);
        mesh_free(&m);
    }
}

/* ---- a chain: triangles growing exponentially -------------------------------- */

/* 65 triangles in the planes x = 17^i, i = -36 .. 28 (17^-36 is subnormal;
 * 17^28 still leaves the SAH's areas finite). Each x is less than a
 * sixteenth of the next, so in every node all centroids but the largest
 * fall in the first of the 16 bins: the only plane the SAH can choose cuts
 * off one triangle per level, a chain 57 deep where the median split makes
 * a tree 5 deep. Traversal must still be right, within its fixed stack.
 * (Past BVH_STACK_SIZE - 33 levels the build would switch to median splits;
 * float's range allows no longer chain of this kind.) */
static void test_exponentially_spaced_triangles_make_a_chain(void **state)
{
    (void)state;
    mesh m;
    mesh_init(&m);
    for (int i = -36; i <= 28; i++) {
        float x = powf(17.0f, (float)i);
        int a = mesh_add_position(&m, vec3_make(x, -1, -1));
        int b = mesh_add_position(&m, vec3_make(x, 3, -1));
        int c = mesh_add_position(&m, vec3_make(x, -1, 3));
        mesh_add_triangle(&m, a, b, c, -1);
    }
    triangle_set set;
    triangle_set_from_mesh(&set, &m);
    accel *a = bvh_build(&set, BVH_SPLIT_SAH), *brute = brute_force_build(&set);
    check_structure(a);
    print_message("chain: depth %d\n", a->stats.max_depth);
    assert_true(a->stats.max_depth >= 50); /* the chain did form */
    assert_true(a->stats.max_depth < BVH_STACK_SIZE);
    /* from the origin along +x, the first triangle is at t = 1; from the far
     * end back along -x, the last one; and between any two */
    hit_record hit, want;
    ray_counters counters = {0};
    assert_true(accel_closest_hit(a, ray_from(0, 0, 0, 1, 0, 0), &hit, &counters));
    assert_int_equal(hit.shape_id, 0);
    assert_true(hit.t == set.triangles[0].p0.x);
    for (int i = 0; i < set.count; i += 3) {
        ray r = ray_from(set.triangles[i].p0.x * 1.25f, 0.5f, 0.5f, (i % 2) ? 1.0f : -1.0f, 0.0f, 0.0f);
        bool want_hit = accel_closest_hit(brute, r, &want, &counters);
        assert_int_equal(accel_closest_hit(a, r, &hit, &counters), want_hit);
        if (want_hit) {
            assert_int_equal(hit.shape_id, want.shape_id);
            assert_true(hit.t == want.t);
        }
        assert_int_equal(accel_any_hit(a, r, &counters), want_hit);
    }
    accel_destroy(brute);
    accel_destroy(a);
    triangle_set_free(&set);
    mesh_free(&m);
}

/* ---- the inlined slab test --------------------------------------------------- */

/* bvh_slab_test() against chapter 03's aabb_slab_test() on random boxes
 * (a fifth of them flat) and rays with zero direction components of both
 * signs and origins exactly on the slab planes (0 * inf = NaN): the same
 * answer and the same t_enter, bit for bit. */
static void test_slab_test_matches_chapter_03(void **state)
{
    (void)state;
    pcg32 rng = pcg32_for_pixel(606, 1);
    int nan_cases = 0, hits = 0;
    for (int i = 0; i < 200000; i++) {
        vec3 a = vec3_make(pcg32_float(&rng) * 4 - 2, pcg32_float(&rng) * 4 - 2, pcg32_float(&rng) * 4 - 2);
        vec3 b = vec3_make(pcg32_float(&rng) * 4 - 2, pcg32_float(&rng) * 4 - 2, pcg32_float(&rng) * 4 - 2);
        bvh_node node;
        memset(&node, 0, sizeof node);
        node.box = (aabb){vec3_min(a, b), vec3_max(a, b)};
        if (i % 5 == 0)
            node.box.hi.y = node.box.lo.y; /* flat */
        float o[3], d[3];
        for (int k = 0; k < 3; k++) {
            o[k] = pcg32_float(&rng) * 6 - 3;
            d[k] = pcg32_float(&rng) * 2 - 1;
            uint32_t pick = pcg32_bounded(&rng, 8);
            if (pick == 0)
                d[k] = 0.0f;
            else if (pick == 1)
                d[k] = -0.0f;
            uint32_t on = pcg32_bounded(&rng, 6);
            if (on == 0)
                o[k] = vec3_axis(node.box.lo, k);
            else if (on == 1)
                o[k] = vec3_axis(node.box.hi, k);
            nan_cases += d[k] == 0.0f && on < 2;
        }
        ray r = ray_from(o[0], o[1], o[2], d[0], d[1], d[2]);
        r.t_max = (i % 3 == 0) ? INFINITY : 5.0f;
        slab_ray sr = slab_ray_make(r);
        bvh_ray br = bvh_ray_make(&r);
        float enter03 = 0.0f, exit03 = 0.0f, enter06 = 0.0f;
        bool hit03 = aabb_slab_test(&node.box, &sr, r.t_min, r.t_max, &enter03, &exit03);
        bool hit06 = bvh_slab_test(&node, &br, r.t_min, r.t_max, &enter06);
        if (hit03 != hit06 || (hit03 && enter03 != enter06))
            fail_msg("ray %d: chapter 03 %d t_enter %g, bvh %d t_enter %g", i, hit03, (double)enter03, hit06,
                     (double)enter06);
        hits += hit03;
    }
    print_message("slab tests: 200000 rays, %d hit, %d axes with 0 * inf\n", hits, nan_cases);
    assert_true(hits > 10000 && nan_cases > 10000);
}

/* ---- an empty set --------------------------------------------------------------- */

static void test_empty_set_builds_and_misses(void **state)
{
    (void)state;
    exercise_checks("bvh_intersect");
    mesh m;
    mesh_init(&m);
    triangle_set set;
    triangle_set_from_mesh(&set, &m);
    for (int split = 0; split < 2; split++) {
        accel *a = bvh_build(&set, split ? BVH_SPLIT_SAH : BVH_SPLIT_MEDIAN);
        hit_record hit;
        ray_counters counters = {0};
        assert_false(accel_closest_hit(a, ray_from(0, 0, 0, 0, 0, 1), &hit, &counters));
        assert_false(accel_any_hit(a, ray_from(0, 0, 0, 0, 0, 1), &counters));
        assert_false(bvh_closest_hit_recursive((const bvh *)a, ray_from(0, 0, 0, 0, 0, 1), &hit, &counters));
        accel_destroy(a);
    }
    triangle_set_free(&set);
    mesh_free(&m);
}

/* ---- scene files (chapters 03-06) ---------------------------------------------- */

static image render_view(const accel *a, const camera *cam)
{
    accel_view view = {a, false, 100.0f};
    render_job job = {.cam = cam, .spp = 1, .seed = 1, .threads = 2, .quiet = true, .radiance = accel_view_radiance,
                      .scene = &view};
    image img = image_make(cam->width, cam->height);
    render_stats stats;
    render_image(&job, &img, &stats);
    return img;
}

/* Each accelerator chapter's default.scene holds the built-in mesh, face for
 * face, and no camera (so the harness view): the BVH renders the same image
 * from it as from the built-in mesh, bit for bit. */
static void test_default_scene_files_hold_the_built_in_meshes(void **state)
{
    (void)state;
    const char *chapters[4] = {"03-aabb-slabs", "04-uniform-grid", "05-kd-tree", "06-bvh"};
    const long sizes[4] = {10240, 102400, 102400, 102400};
    for (int c = 0; c < 4; c++) {
        char path[256], err[SCENE_ERROR_SIZE];
        snprintf(path, sizeof path, "chapters/%s/scenes/default.scene", chapters[c]);
        scene_desc d;
        if (!scene_desc_load(&d, path, err, sizeof err))
            fail_msg("%s", err);
        assert_false(d.has_camera);
        mesh from_file, built_in;
        mesh_init(&from_file);
        mesh_init(&built_in);
        int *first = NULL, objects = 0;
        if (!accel_mesh_from_desc(&from_file, &d, "test", &first, &objects, err, sizeof err))
            fail_msg("%s", err);
        mesh_tori_field(&built_in, sizes[c]);
        assert_int_equal(from_file.face_count, built_in.face_count);
        assert_int_equal(objects, 16); /* one object per torus */
        assert_int_equal(first[16], built_in.face_count);
        for (int i = 0; i < built_in.face_count; i++)
            for (int k = 0; k < 3; k++) {
                vec3 a = mesh_vertex(&from_file, i, k), b = mesh_vertex(&built_in, i, k);
                assert_memory_equal(&a, &b, sizeof a);
            }
        if (c == 3) {
            triangle_set s1, s2;
            triangle_set_from_mesh(&s1, &from_file);
            triangle_set_from_mesh(&s2, &built_in);
            accel *a1 = bvh_build(&s1, BVH_SPLIT_SAH), *a2 = bvh_build(&s2, BVH_SPLIT_SAH);
            camera c1 = accel_scene_camera(&d, s1.bounds, 64, 48), c2 = accel_view_camera(s2.bounds, 64, 48);
            image i1 = render_view(a1, &c1), i2 = render_view(a2, &c2);
            assert_memory_equal(i1.rgb, i2.rgb, 64 * 48 * 3 * sizeof(float));
            image_free(&i1);
            image_free(&i2);
            accel_destroy(a1);
            accel_destroy(a2);
            triangle_set_free(&s1);
            triangle_set_free(&s2);
        }
        free(first);
        mesh_free(&from_file);
        mesh_free(&built_in);
        scene_desc_free(&d);
    }
}

/* Only triangles are taken; a scene of spheres alone is an error naming the
 * file, and m is left as it was. */
static void test_scene_without_triangles_is_an_error(void **state)
{
    (void)state;
    const char *text = "material w diffuse albedo 1 1 1\nsphere center 0 0 0 radius 1 material w\n"
                       "quad p0 0 0 0 p1 1 0 0 p2 1 1 0 p3 0 1 0 material w\n";
    scene_desc d;
    char err[SCENE_ERROR_SIZE];
    assert_true(scene_desc_parse(&d, text, strlen(text), "t.scene", NULL, err, sizeof err));
    mesh m;
    mesh_init(&m);
    int *first = NULL, objects = 0;
    assert_true(accel_mesh_from_desc(&m, &d, "test", &first, &objects, err, sizeof err));
    assert_int_equal(m.face_count, 2); /* the quad; the sphere is ignored with a warning */
    assert_int_equal(objects, 1);
    free(first);
    d.shape_count = 1; /* the sphere alone */
    assert_false(accel_mesh_from_desc(&m, &d, "test", NULL, NULL, err, sizeof err));
    assert_non_null(strstr(err, "t.scene: no triangles"));
    assert_int_equal(m.face_count, 2);
    mesh_free(&m);
    scene_desc_free(&d);
}

/* The build shares a set's two halves out among threads (OpenMP tasks),
 * and must make the same tree whatever the count: node for node, the same
 * leaf order, so the same hits and images on 1 thread or 16. On meshes
 * large enough to be shared out (BVH_TASK_MIN = 4096 triangles), both
 * splits, 1 to 3 threads (3 on a machine with 2 cores: the halves finish
 * in other orders). The nodes are numbered as the serial recursion numbers
 * them: a node's children get the next two numbers when a depth-first walk
 * reaches it, first child's subtree first. */
static int serial_numbering_mismatches(const bvh *b, int n, int *next)
{
    const bvh_node *node = &b->nodes[n];
    if (bvh_node_is_leaf(node))
        return 0;
    int first = *next, wrong = node->first != first;
    *next += 2;
    wrong += serial_numbering_mismatches(b, first, next);
    return wrong + serial_numbering_mismatches(b, first + 1, next);
}

static void test_the_tree_is_the_same_on_any_number_of_threads(void **state)
{
    (void)state;
    int threads = omp_get_max_threads();
    for (int which = 0; which < 2; which++) {
        mesh m;
        mesh_init(&m);
        if (which == 0)
            mesh_tori_field(&m, 40960);
        else
            mesh_random_soup(&m, 30000, vec3_make(-2, -1, -1), vec3_make(2, 1, 1), 0.2f, 9);
        triangle_set set;
        triangle_set_from_mesh(&set, &m);
        for (int split = 0; split < 2; split++) {
            bvh *trees[3];
            for (int t = 0; t < 3; t++) {
                omp_set_num_threads(t + 1);
                trees[t] = (bvh *)bvh_build(&set, split ? BVH_SPLIT_SAH : BVH_SPLIT_MEDIAN);
            }
            int next = 1;
            assert_int_equal(serial_numbering_mismatches(trees[0], 0, &next), 0);
            assert_int_equal(next, trees[0]->node_count);
            for (int t = 1; t < 3; t++) {
                assert_int_equal(trees[t]->node_count, trees[0]->node_count);
                assert_memory_equal(trees[t]->nodes, trees[0]->nodes, (size_t)trees[0]->node_count * sizeof(bvh_node));
                assert_memory_equal(trees[t]->triangle_index, trees[0]->triangle_index, (size_t)set.count * sizeof(int));
                assert_memory_equal(trees[t]->triangles, trees[0]->triangles, (size_t)set.count * sizeof(bvh_triangle));
                assert_int_equal(trees[t]->base.stats.leaves, trees[0]->base.stats.leaves);
                assert_int_equal(trees[t]->base.stats.max_depth, trees[0]->base.stats.max_depth);
            }
            for (int t = 0; t < 3; t++)
                accel_destroy(&trees[t]->base);
        }
        omp_set_num_threads(threads);
        triangle_set_free(&set);
        mesh_free(&m);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_default_scene_files_hold_the_built_in_meshes),
        cmocka_unit_test(test_scene_without_triangles_is_an_error),
        cmocka_unit_test(test_median_bvh_agrees_with_brute_force),
        cmocka_unit_test(test_sah_bvh_agrees_with_brute_force),
        cmocka_unit_test(test_distance_order_agrees_with_brute_force),
        cmocka_unit_test(test_every_triangle_in_exactly_one_leaf_and_boxes_nest),
        cmocka_unit_test(test_sah_tree_is_cheaper_than_median_tree_on_the_tori_field),
        cmocka_unit_test(test_coincident_triangles_make_one_leaf),
        cmocka_unit_test(test_tiny_triangles_at_one_point),
        cmocka_unit_test(test_centroid_on_the_bounds_maximum_goes_to_the_last_bin),
        cmocka_unit_test(test_sah_build_with_a_centroid_on_the_maximum),
        cmocka_unit_test(test_far_child_holds_the_closer_hit),
        cmocka_unit_test(test_far_child_beyond_the_closest_hit_is_skipped),
        cmocka_unit_test(test_shared_vertex_near_tie_is_not_culled),
        cmocka_unit_test(test_hand_built_tree_is_checked),
        cmocka_unit_test(test_recursive_traversal_equals_brute_force),
        cmocka_unit_test(test_recursive_twin_returning_the_first_hit_is_caught),
        cmocka_unit_test(test_recursive_traversal_visits_at_least_as_many_nodes),
        cmocka_unit_test(test_exponentially_spaced_triangles_make_a_chain),
        cmocka_unit_test(test_slab_test_matches_chapter_03),
        cmocka_unit_test(test_empty_set_builds_and_misses),
        cmocka_unit_test(test_the_tree_is_the_same_on_any_number_of_threads),
    };
    return cmocka_run_group_tests_name("ch06 bvh", tests, NULL, NULL);
}
