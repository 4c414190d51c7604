/* test_ch13.c -- what production renderers do, held to the lecture's
 * answers: the 4-wide BVH, its streams and the flat packets against brute
 * force; the walls against the test of every triangle; offsets eight lanes
 * at a time against ray.h; eight paths at a time against chapter 09's
 * lecture rung, statistically. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <unistd.h>

#include <omp.h>

#include "01-ray-casting/scene.h"
#include "04-uniform-grid/grid.h"
#include "05-kd-tree/kdtree.h"
#include "06-bvh/bvh.h"
#include "08-monte-carlo/estimators.h"
#include "08-monte-carlo/sampling.h"
#include "09-path-tracing/bsdf.h"
#include "09-path-tracing/experiments.h"
#include "09-path-tracing/light_transport.h"
#include "09-path-tracing/path_tracer.h"
#include "10-distribution/motion_scene.h"
#include "13-production/bench_scenes.h"
#include "13-production/wide_bvh.h"
#include "13-production/fast_sincos.h"
#include "13-production/flat.h"
#include "13-production/light_tree.h"
#include "13-production/path_tracer_wide.h"
#include "13-production/sobol_pixel.h"
#include "13-production/spawn_avx.h"
#include "13-production/speed.h"
#include "13-production/walls.h"
#include "13-production/wide_trace.h"
#include "obj.h"
#include "render.h"
#include "explain.h"
#include "scene_file.h"
#include "stats.h"
#include "accel_check.h"
#include "chi2.h"
#include "image_check.h"
#include "pt_scene_check.h"
#include "leak_check.h"
#include "test_support.h"

static bool box_contains(aabb outer, aabb inner)
{
    return outer.lo.x <= inner.lo.x && outer.lo.y <= inner.lo.y && outer.lo.z <= inner.lo.z &&
           inner.hi.x <= outer.hi.x && inner.hi.y <= outer.hi.y && inner.hi.z <= outer.hi.z;
}

static ray ray_from(float ox, float oy, float oz, float dx, float dy, float dz)
{
    return ray_make(vec3_make(ox, oy, oz), vec3_make(dx, dy, dz));
}

static path_tracer tracer(const pt_scene *sc, pt_integrator integrator, pt_russian_roulette rr)
{
    path_tracer pt = path_tracer_defaults(sc);
    pt.integrator = integrator;
    pt.russian_roulette = rr;
    return pt;
}

/* Chapter 09's scene traced through the production structure, walls on or off. */
static void use_production(pt_scene *sc, bool walls)
{
    pt_scene_use_accel(sc, walls ? production_scene_accel : production_scene_accel_no_walls, sc);
}

/* The walls of a scene (its structure a walls_accel). */
static bool walls_segment_inside_of(const pt_scene *sc, const ray *r) { return walls_segment_inside(sc->bvh, r); }
static int walls_segments8_inside_of(const pt_scene *sc, const rays8 *rays, int active)
{
    return walls_segments8_inside(sc->bvh, rays, active);
}

static image render_mean(const path_tracer *pt, int size, int spp, uint64_t seed, ray_counters *counters)
{
    camera cam = pt_scene_camera(pt->scene, size, size);
    image mean = image_make(size, size);
    render_stats stats;
    render_job job = {.cam = &cam, .spp = spp, .seed = test_seed(seed), .threads = 2, .quiet = true,
                      .radiance = path_trace_radiance, .scene = pt, .jitter = true};
    render_image(&job, &mean, &stats);
    if (counters != NULL)
        *counters = stats.counters;
    return mean;
}

/* The same image, bit for bit, with the same counters. */
static void assert_same_render(const path_tracer *a, const path_tracer *b, ray_counters *ca, ray_counters *cb)
{
    image ra = render_mean(a, 48, 2, 7, ca), rb = render_mean(b, 48, 2, 7, cb);
    assert_memory_equal(ra.rgb, rb.rgb, 48 * 48 * 3 * sizeof(float));
    image_free(&ra);
    image_free(&rb);
}

/* A uniform point on triangle t (as a hit computes it, P0 + (b1 E1 + b2 E2)),
 * and the triangle's unit normal. */
/* The answer without the walls shortcut: every triangle, every sphere. */
static bool occluded_by_everything(const pt_scene *sc, ray r)
{
    ray_counters ignored = {0};
    return (sc->triangles.count > 0 && accel_any_hit(walls_all(sc->bvh), r, &ignored)) || spheres_block(sc, r);
}

/* The Cornell box (scene 0), or the box with a glass sphere (1), on the
 * production structure with its walls. */
static void build_box_scene(pt_scene *sc, int scene)
{
    if (scene == 0)
        pt_scene_build_cornell_box(sc);
    else
        pt_scene_build_cornell_box_materials(sc);
    use_production(sc, true);
}

/* ==== the 4-wide BVH, streams and flat packets (from chapter 06's structures) ==== */
/* ---- the 4-wide BVH ------------------------------------------------------------ */

/* Every kernel, the plain C loop first: the tests below run each that this
 * processor runs (wide_bvh_kernel_runs). */
static const wide_bvh_kernel wide_bvh_kernels[] = {WIDE_BVH_KERNEL_SCALAR, WIDE_BVH_KERNEL_SSE, WIDE_BVH_KERNEL_AVX};
enum { WIDE_BVH_KERNELS = sizeof wide_bvh_kernels / sizeof wide_bvh_kernels[0] };

static accel *build_wide_bvh_sah(const triangle_set *set) { return wide_bvh_build(set, BVH_SPLIT_SAH); }
static accel *build_wide_bvh_median(const triangle_set *set) { return wide_bvh_build(set, BVH_SPLIT_MEDIAN); }
static accel *build_wide_bvh_quantized(const triangle_set *set)
{
    return wide_bvh_build_layout(set, BVH_SPLIT_SAH, WIDE_BVH_QUANTIZED);
}
static accel *build_wide_bvh_sah_scalar(const triangle_set *set)
{
    accel *a = wide_bvh_build(set, BVH_SPLIT_SAH);
    assert_true(wide_bvh_set_kernel(a, WIDE_BVH_KERNEL_SCALAR));
    return a;
}

static void test_wide_bvh_agrees_with_brute_force(void **state)
{
    (void)state;
    accel_check_all(build_wide_bvh_sah, 15000, "wide bvh sah");
    accel_check_all(build_wide_bvh_quantized, 15000, "wide bvh sah, quantized nodes");
    accel_check_all(build_wide_bvh_median, 3000, "wide bvh median");
}

/* The plain C loops, the path a machine without SSE takes. */
static void test_wide_bvh_scalar_kernel_agrees_with_brute_force(void **state)
{
    (void)state;
    accel_check_all(build_wide_bvh_sah_scalar, 5000, "wide bvh sah, scalar kernel");
}

/* Walks the wide tree: each child box contains its triangles' boxes (and,
 * exact, the boxes below it), empty slots come last and have the empty box,
 * each triangle is in exactly one lane, with its own P0 and edges. Returns
 * the union of the subtree's triangle boxes. */
static aabb check_wide_bvh_subtree(const wide_bvh *b, uint32_t ref, aabb box, int depth, int *seen, int *leaves,
                                   int *nodes_seen)
{
    aabb below = {vec3_make(INFINITY, INFINITY, INFINITY), vec3_make(-INFINITY, -INFINITY, -INFINITY)};
    assert_true(depth < WIDE_BVH_STACK_SIZE / (WIDE_BVH_WIDTH - 1));
    if (wide_bvh_is_leaf(ref)) {
        int count = wide_bvh_leaf_triangles(ref), first = wide_bvh_leaf_first_packet(ref);
        assert_true(count >= 1);
        (*leaves)++;
        for (int i = 0; i < 4 * ((count + 3) / 4); i++) {
            int lane = 4 * first + i;
            assert_true(lane < 4 * b->packet_count);
            const wide_bvh_packet *p = &b->packets[first + i / 4];
            int t = wide_bvh_lane_triangle(p->index[i % 4]);
            bool moller_trumbore = b->base.triangle_test == TRIANGLE_TEST_MOLLER_TRUMBORE;
            if (i >= count) { /* empty: zeros for Moller-Trumbore, NaN for the watertight test */
                assert_int_equal(t, -1);
                if (moller_trumbore)
                    assert_true(p->e1[0][i % 4] == 0.0f && p->e2[2][i % 4] == 0.0f);
                else
                    assert_true(isnan(p->p0[0][i % 4]) && isnan(p->p1[1][i % 4]) && isnan(p->p2[2][i % 4]));
                continue;
            }
            assert_true(t >= 0 && t < b->triangle_count);
            seen[t]++;
            assert_true(box_contains(box, b->base.set->boxes[t]));
            below = aabb_union(below, b->base.set->boxes[t]);
            const triangle *tri = &b->base.set->triangles[t];
            if (!moller_trumbore) { /* the corners, or NaN for a degenerate triangle */
                bool degenerate = triangle_is_degenerate(tri);
                assert_true(degenerate ? isnan(p->p0[0][i % 4]) && isnan(p->p2[2][i % 4])
                                       : p->p0[0][i % 4] == tri->p0.x && p->p1[1][i % 4] == tri->p1.y &&
                                             p->p2[2][i % 4] == tri->p2.z);
                assert_true((p->index[i % 4] & WIDE_BVH_LANE_EXACT) != 0);
                continue;
            }
            assert_true(p->p0[0][i % 4] == tri->p0.x && p->e1[1][i % 4] == tri->p1.y - tri->p0.y &&
                        p->e2[2][i % 4] == tri->p2.z - tri->p0.z);
            if (p->index[i % 4] & WIDE_BVH_LANE_EXACT) { /* P0 + E1 and P0 + E2 are P1 and P2, bit for bit */
                vec3 p0 = vec3_make(p->p0[0][i % 4], p->p0[1][i % 4], p->p0[2][i % 4]);
                vec3 p1 = vec3_add(p0, vec3_make(p->e1[0][i % 4], p->e1[1][i % 4], p->e1[2][i % 4]));
                vec3 p2 = vec3_add(p0, vec3_make(p->e2[0][i % 4], p->e2[1][i % 4], p->e2[2][i % 4]));
                assert_memory_equal(&p1, &tri->p1, sizeof p1);
                assert_memory_equal(&p2, &tri->p2, sizeof p2);
            }
        }
        return below;
    }
    assert_true(ref < (uint32_t)b->node_count);
    (*nodes_seen)++;
    bool empty_seen = false;
    for (int k = 0; k < WIDE_BVH_WIDTH; k++) {
        aabb child = wide_bvh_child_box(b, (int)ref, k);
        if (wide_bvh_child(b, (int)ref, k) == WIDE_BVH_EMPTY) {
            assert_true(k > 0);
            assert_true(k >= wide_bvh_children(b, (int)ref));
            if (b->layout == WIDE_BVH_EXACT) /* (quantized: lo 255, hi 0, and masked) */
                assert_true(child.lo.x == INFINITY && child.hi.x == -INFINITY);
            empty_seen = true;
            continue;
        }
        assert_false(empty_seen); /* children first, empty slots last */
        if (b->layout == WIDE_BVH_EXACT)
            assert_true(box_contains(box, child));
        aabb sub = check_wide_bvh_subtree(b, wide_bvh_child(b, (int)ref, k), child, depth + 1, seen, leaves, nodes_seen);
        assert_true(box_contains(child, sub));
        below = aabb_union(below, sub);
    }
    return below;
}

static void check_wide_bvh_structure(const accel *a)
{
    const wide_bvh *b = (const wide_bvh *)a;
    int n = a->set->count;
    int *seen = calloc((size_t)n + 1, sizeof *seen);
    int leaves = 0, nodes_seen = 0;
    if (b->node_count > 0)
        check_wide_bvh_subtree(b, 0, a->set->bounds, 0, seen, &leaves, &nodes_seen);
    for (int t = 0; t < n; t++)
        assert_int_equal(seen[t], 1);
    assert_int_equal(leaves, a->stats.leaves);
    assert_int_equal(nodes_seen, b->node_count);
    free(seen);
}

static void test_wide_bvh_every_triangle_in_exactly_one_lane_and_boxes_nest(void **state)
{
    (void)state;
    for (int kind = 0; kind < MESH_KIND_COUNT; kind++) {
        mesh m;
        accel_check_make_mesh(&m, (accel_check_mesh)kind);
        triangle_set set;
        triangle_set_from_mesh(&set, &m);
        for (int split = 0; split < 4; split++) { /* median, SAH; exact, quantized */
            accel *a = wide_bvh_build_layout(&set, split % 2 ? BVH_SPLIT_SAH : BVH_SPLIT_MEDIAN,
                                             split < 2 ? WIDE_BVH_EXACT : WIDE_BVH_QUANTIZED);
            assert_int_equal(((const wide_bvh *)a)->layout, split < 2 ? WIDE_BVH_EXACT : WIDE_BVH_QUANTIZED);
            check_wide_bvh_structure(a);
            /* the lanes rewritten for Moller-Trumbore, and back */
            assert_true(accel_use_triangle_test(a, TRIANGLE_TEST_MOLLER_TRUMBORE));
            check_wide_bvh_structure(a);
            assert_true(accel_use_triangle_test(a, TRIANGLE_TEST_WATERTIGHT));
            check_wide_bvh_structure(a);
            accel_destroy(a);
        }
        triangle_set_free(&set);
        mesh_free(&m);
    }
}

/* More coincident triangles than a leaf reference can count (255): the
 * leaf is split into a node over smaller leaves with the same box, and the
 * closest hit is still found, at the same t as brute force's. */
static void test_wide_bvh_more_coincident_triangles_than_a_leaf_holds(void **state)
{
    (void)state;
    mesh m;
    mesh_init(&m);
    mesh_coincident(&m, 1000);
    triangle_set set;
    triangle_set_from_mesh(&set, &m);
    accel *a = wide_bvh_build(&set, BVH_SPLIT_SAH), *brute = brute_force_build(&set);
    check_wide_bvh_structure(a);
    assert_true(((const wide_bvh *)a)->node_count >= 2); /* the root, and the node splitting the leaf */
    for (int kernel = 0; kernel < WIDE_BVH_KERNELS; kernel++) {
        if (!wide_bvh_set_kernel(a, wide_bvh_kernels[kernel]))
            continue;
        pcg32 rng = pcg32_for_pixel(6, 4);
        int hits = 0;
        for (int i = 0; i < 2000; i++) {
            ray r = accel_check_ray(&m, set.bounds.lo, set.bounds.hi, &rng, i);
            hit_record want, got;
            ray_counters counters = {0};
            bool want_hit = accel_closest_hit(brute, r, &want, &counters);
            assert_int_equal(accel_closest_hit(a, r, &got, &counters), want_hit);
            assert_int_equal(accel_any_hit(a, r, &counters), want_hit);
            if (want_hit) {
                assert_true(got.t == want.t); /* any of the coincident triangles: they tie */
                hits++;
            }
        }
        assert_true(hits > 100);
    }
    accel_destroy(brute);
    accel_destroy(a);
    triangle_set_free(&set);
    mesh_free(&m);
}

/* A mesh of the differential test, its triangle set and its 4-wide SAH BVH. */
static accel *wide_bvh_of_mesh_kind(accel_check_mesh kind, mesh *m, triangle_set *set)
{
    accel_check_make_mesh(m, kind);
    triangle_set_from_mesh(set, m);
    return wide_bvh_build(set, BVH_SPLIT_SAH);
}

static void check_wide_bvh_hit_records(triangle_test test);

/* The hit record of a lane marked WIDE_BVH_LANE_EXACT is made from the packet's
 * corners (watertight test) or P0, E1, E2 (Moller-Trumbore) instead of the
 * set's triangle: it must be the very record the set's triangle gives
 * (point, normals, material, bit for bit), on every mesh. With
 * Moller-Trumbore both kinds of lane must occur, so that both paths are
 * checked; the watertight test's lanes are all exact. */
static void test_wide_bvh_hit_records_equal_the_sets(void **state)
{
    (void)state;
    for (int test = 0; test < 2; test++)
        check_wide_bvh_hit_records((triangle_test)test);
}

static void check_wide_bvh_hit_records(triangle_test test)
{
    long exact_hits = 0, other_hits = 0;
    for (int kind = 0; kind < MESH_KIND_COUNT; kind++) {
        mesh m;
        triangle_set set;
        accel *a = wide_bvh_of_mesh_kind((accel_check_mesh)kind, &m, &set);
        assert_true(accel_use_triangle_test(a, test));
        const wide_bvh *b = (const wide_bvh *)a;
        bool *exact = calloc((size_t)set.count + 1, sizeof *exact);
        for (int lane = 0; lane < 4 * b->packet_count; lane++) {
            int32_t index = b->packets[lane / 4].index[lane % 4];
            if (index >= 0)
                exact[wide_bvh_lane_triangle(index)] = (index & WIDE_BVH_LANE_EXACT) != 0;
        }
        pcg32 rng = pcg32_for_pixel(6, 45 + kind);
        for (int i = 0; i < 4000; i++) {
            ray r = accel_check_ray(&m, set.bounds.lo, set.bounds.hi, &rng, i);
            hit_record got, want;
            ray_counters counters = {0};
            if (!accel_closest_hit(a, r, &got, &counters))
                continue;
            triangle_set_fill_hit(&set, got.shape_id, r, got.t, got.u, got.v, &want);
            if (exact[got.shape_id])
                exact_hits++;
            else
                other_hits++;
            assert_memory_equal(&got.point, &want.point, sizeof want.point);
            assert_memory_equal(&got.normal_geometric, &want.normal_geometric, sizeof want.normal_geometric);
            assert_memory_equal(&got.normal_shading, &want.normal_shading, sizeof want.normal_shading);
            assert_int_equal(got.material_id, want.material_id);
            assert_int_equal(got.front_face, want.front_face);
        }
        free(exact);
        accel_destroy(a);
        triangle_set_free(&set);
        mesh_free(&m);
    }
    print_message("wide BVH hit records, %s: %ld from exact lanes, %ld from the set's triangles\n",
                  triangle_test_name(test), exact_hits, other_hits);
    if (test == TRIANGLE_TEST_MOLLER_TRUMBORE)
        assert_true(exact_hits > 0 && other_hits > 0);
    else
        assert_true(exact_hits > 0 && other_hits == 0);
}

/* The SSE and the scalar kernel: the same hits, the same floats, the same
 * counters, ray by ray, on the tori field, with either triangle test. */
static void test_wide_bvh_kernels_give_identical_answers(void **state)
{
    (void)state;
    if (!WIDE_BVH_HAVE_SSE)
        skip();
    mesh m;
    accel_check_make_mesh(&m, MESH_TORI_FIELD);
    triangle_set set;
    triangle_set_from_mesh(&set, &m);
    accel *a = wide_bvh_build(&set, BVH_SPLIT_SAH);
    pcg32 rng = pcg32_for_pixel(6, 44);
    int hits = 0;
    for (int i = 0; i < 20000; i++) {
        /* the watertight test on three rays in four, Moller-Trumbore on the fourth */
        assert_true(accel_use_triangle_test(a, i % 4 == 3 ? TRIANGLE_TEST_MOLLER_TRUMBORE : TRIANGLE_TEST_WATERTIGHT));
        ray r = accel_check_ray(&m, set.bounds.lo, set.bounds.hi, &rng, i);
        hit_record scalar_hit;
        ray_counters scalar = {0};
        wide_bvh_set_kernel(a, WIDE_BVH_KERNEL_SCALAR);
        bool scalar_found = accel_closest_hit(a, r, &scalar_hit, &scalar);
        bool scalar_any = accel_any_hit(a, r, &scalar);
        hits += scalar_found;
        for (int kernel = 1; kernel < WIDE_BVH_KERNELS; kernel++) { /* SSE, AVX */
            hit_record simd_hit;
            ray_counters simd = {0};
            if (!wide_bvh_set_kernel(a, wide_bvh_kernels[kernel]))
                continue;
            bool simd_found = accel_closest_hit(a, r, &simd_hit, &simd);
            bool simd_any = accel_any_hit(a, r, &simd);
            assert_int_equal(simd_found, scalar_found);
            assert_int_equal(simd_any, scalar_any);
            assert_int_equal(simd.box_tests, scalar.box_tests);
            assert_int_equal(simd.primitive_tests, scalar.primitive_tests);
            if (simd_found) {
                assert_true(simd_hit.t == scalar_hit.t && simd_hit.u == scalar_hit.u && simd_hit.v == scalar_hit.v);
                assert_int_equal(simd_hit.shape_id, scalar_hit.shape_id);
            }
        }
    }
    assert_true(hits > 5000);
    accel_destroy(a);
    triangle_set_free(&set);
    mesh_free(&m);
}

/* The slab test of chapter 03, four boxes at once, both kernels: the IEEE
 * cases of test_slab_test_matches_chapter_03 (zero direction components of
 * both signs, origins exactly on a plane: 0 * inf = NaN, flat boxes), each
 * lane the same answer and t_enter as aabb_slab_test(), bit for bit. */
static void test_wide_bvh_slab_test_matches_chapter_03(void **state)
{
    (void)state;
    pcg32 rng = pcg32_for_pixel(606, 4);
    int nan_cases = 0, hits = 0;
    for (int i = 0; i < 50000; i++) {
        wide_bvh_node node;
        memset(&node, 0, sizeof node);
        aabb boxes[WIDE_BVH_WIDTH];
        for (int k = 0; k < WIDE_BVH_WIDTH; k++) {
            vec3 a = vec3_make(pcg32_float(&rng) * 4 - 2, pcg32_float(&rng) * 4 - 2, pcg32_float(&rng) * 4 - 2);
            vec3 b = vec3_make(pcg32_float(&rng) * 4 - 2, pcg32_float(&rng) * 4 - 2, pcg32_float(&rng) * 4 - 2);
            boxes[k] = (aabb){vec3_min(a, b), vec3_max(a, b)};
            if (pcg32_bounded(&rng, 5) == 0)
                boxes[k].hi.y = boxes[k].lo.y; /* flat */
            for (int axis = 0; axis < 3; axis++) {
                node.bounds[axis][k] = vec3_axis(boxes[k].lo, axis);
                node.bounds[3 + axis][k] = vec3_axis(boxes[k].hi, axis);
            }
        }
        /* the origin on a plane of box 0 or 1 (alternately), direction
         * components zero of both signs */
        const aabb *on_box = &boxes[i % 2];
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
                o[k] = vec3_axis(on_box->lo, k);
            else if (on == 1)
                o[k] = vec3_axis(on_box->hi, k);
            nan_cases += d[k] == 0.0f && on < 2;
        }
        ray r = ray_from(o[0], o[1], o[2], d[0], d[1], d[2]);
        r.t_max = (i % 3 == 0) ? INFINITY : 5.0f;
        slab_ray sr = slab_ray_make(r);
        for (int kernel = 0; kernel < WIDE_BVH_KERNELS; kernel++) {
            float enter4[WIDE_BVH_WIDTH];
            if (!wide_bvh_kernel_runs(wide_bvh_kernels[kernel]))
                continue;
            int mask = wide_bvh_slab_test(&node, r, r.t_min, r.t_max, enter4, wide_bvh_kernels[kernel]);
            for (int k = 0; k < WIDE_BVH_WIDTH; k++) {
                float enter03 = 0.0f, exit03 = 0.0f;
                bool hit03 = aabb_slab_test(&boxes[k], &sr, r.t_min, r.t_max, &enter03, &exit03);
                bool hit4 = mask >> k & 1;
                if (hit03 != hit4 || (hit03 && enter03 != enter4[k]))
                    fail_msg("ray %d box %d kernel %d: chapter 03 %d t_enter %g, wide BVH %d t_enter %g", i, k, kernel,
                             hit03, (double)enter03, hit4, (double)enter4[k]);
                hits += hit03 && kernel == 0;
            }
        }
        /* an empty slot's box is missed by every ray */
        wide_bvh_node empty;
        for (int k = 0; k < WIDE_BVH_WIDTH; k++)
            for (int axis = 0; axis < 3; axis++) {
                empty.bounds[axis][k] = INFINITY;
                empty.bounds[3 + axis][k] = -INFINITY;
            }
        float enter4[WIDE_BVH_WIDTH];
        for (int kernel = 0; kernel < WIDE_BVH_KERNELS; kernel++)
            if (wide_bvh_kernel_runs(wide_bvh_kernels[kernel]))
                assert_int_equal(wide_bvh_slab_test(&empty, r, r.t_min, r.t_max, enter4, wide_bvh_kernels[kernel]), 0);
    }
    print_message("wide BVH slab tests: %d boxes, %d hit, %d axes with 0 * inf\n", 50000 * WIDE_BVH_WIDTH, hits, nan_cases);
    assert_true(hits > 10000 && nan_cases > 3000);
}

/* The 4-lane tests, both kernels, against chapter 01's: the watertight
 * test against triangle_intersect_watertight(), Moller-Trumbore against
 * triangle_intersect_barycentric(). The same hit or miss, and the same t,
 * b1, b2 bit for bit, on rays aimed at vertices and edges (the near-ties,
 * and the watertight test's double-precision path) and with degenerate
 * lanes (zero area, and the empty lane). */
static void test_wide_bvh_triangle_test_matches_chapter_01(void **state)
{
    (void)state;
    pcg32 rng = pcg32_for_pixel(607, 4);
    int hits = 0;
    for (int i = 0; i < 50000; i++) {
        triangle_test test = i % 2 ? TRIANGLE_TEST_MOLLER_TRUMBORE : TRIANGLE_TEST_WATERTIGHT;
        triangle tris[4];
        wide_bvh_packet packet;
        memset(&packet, 0, sizeof packet);
        bool empty_lane = i % 8 < 2; /* lane 3 left as an empty lane */
        for (int k = 0; k < 4; k++) {
            vec3 p[3];
            for (int j = 0; j < 3; j++)
                p[j] = vec3_make(pcg32_float(&rng) * 2 - 1, pcg32_float(&rng) * 2 - 1, pcg32_float(&rng) * 2 - 1);
            if (k == 3 && i % 8 == 4)
                p[2] = p[1]; /* zero area */
            tris[k] = (triangle){p[0], p[1], p[2]};
            if (k == 3 && empty_lane)
                wide_bvh_packet_set_lane(&packet, k, NULL, -1, test);
            else
                wide_bvh_packet_set_lane(&packet, k, &tris[k], k, test);
        }
        /* aim at a vertex or an edge midpoint of lane i % 3's triangle */
        const triangle *aim = &tris[i % 3];
        vec3 target = i % 2 ? aim->p1 : vec3_scale(vec3_add(aim->p0, aim->p2), 0.5f);
        vec3 o = vec3_make(pcg32_float(&rng) * 6 - 3, pcg32_float(&rng) * 6 - 3, pcg32_float(&rng) * 6 - 3);
        ray r = ray_make(o, vec3_sub(target, o));
        float t_max = i % 5 == 0 ? 0.9f : INFINITY;
        for (int kernel = 0; kernel < WIDE_BVH_KERNELS; kernel++) {
            float t[4] = {0}, b1[4] = {0}, b2[4] = {0};
            if (!wide_bvh_kernel_runs(wide_bvh_kernels[kernel]))
                continue;
            int mask = wide_bvh_triangle_test(&packet, r, t_max, t, b1, b2, wide_bvh_kernels[kernel], test);
            for (int k = 0; k < 4; k++) {
                float want_t = 0.0f, want_b1 = 0.0f, want_b2 = 0.0f;
                bool want = !(k == 3 && empty_lane) &&
                            (test == TRIANGLE_TEST_WATERTIGHT
                                 ? triangle_intersect_watertight(&tris[k], &r, &want_t, &want_b1, &want_b2)
                                 : triangle_intersect_barycentric(&tris[k], &r, &want_t, &want_b1, &want_b2)) &&
                            want_t < t_max;
                bool got = mask >> k & 1;
                if (want != got || (want && (t[k] != want_t || b1[k] != want_b1 || b2[k] != want_b2)))
                    fail_msg("case %d lane %d kernel %d: chapter 01 %d t %a, wide BVH %d t %a", i, k, kernel, want,
                             (double)want_t, got, (double)t[k]);
                hits += want && kernel == 0;
            }
        }
    }
    print_message("wide BVH triangle tests: 200000 lanes, %d hit\n", hits);
    assert_true(hits > 20000);
}

/* The largest share of the root box's surface area that a leaf's box has:
 * the share of rays through the tree that test that leaf's triangles. */
static double wide_bvh_largest_leaf_share(const accel *a)
{
    const wide_bvh *b = (const wide_bvh *)a;
    aabb root = {vec3_make(INFINITY, INFINITY, INFINITY), vec3_make(-INFINITY, -INFINITY, -INFINITY)};
    double largest = 0.0;
    for (int pass = 0; pass < 2; pass++)
        for (int n = 0; n < (pass == 0 ? 1 : b->node_count); n++)
            for (int k = 0; k < wide_bvh_children(b, n); k++) {
                aabb box = wide_bvh_child_box(b, n, k);
                if (pass == 0)
                    root = aabb_union(root, box);
                else if (wide_bvh_is_leaf(wide_bvh_child(b, n, k)))
                    largest = fmax(largest, aabb_surface_area(box) / aabb_surface_area(root));
            }
    return largest;
}

/* A room's walls get leaves of their own. Any two walls that meet span the
 * whole room, so a leaf holding both has the room's box, and every ray in
 * the room tests it; the SAH with C_t = 1 keeps such a leaf (splitting off
 * one wall leaves the other's box as big). A wall alone has a box with at
 * most 1/3 of the room's area (a face of the box, both sides), so with the
 * lower C_t near the root no leaf should reach 1/2 of the root's area. And
 * a ray from inside the room tests only the wall it leaves through: fewer
 * triangle tests than with one leaf of walls, the same hits. The twin is
 * the same tree without the lower C_t: the room-sized leaf, found. */
static void test_wide_bvh_room_walls_get_leaves_of_their_own(void **state)
{
    (void)state;
    pt_scene sc;
    assert_true(bench_scene_build(&sc, "cornell-10k"));
    accel *tree = wide_bvh_build(&sc.triangles, BVH_SPLIT_SAH);
    accel *twin = wide_bvh_build_with_top(&sc.triangles, BVH_SPLIT_SAH, 0.0f);
    assert_true(wide_bvh_largest_leaf_share(tree) < 0.5);
    assert_true(wide_bvh_largest_leaf_share(twin) > 0.9);
    pcg32 rng = pcg32_for_pixel(13, 24);
    ray_counters counters[2] = {{0}, {0}};
    int rays = 0;
    for (int i = 0; i < 4096; i++) {
        vec3 origin = vec3_make(20.0f + 510.0f * pcg32_float(&rng), 20.0f + 500.0f * pcg32_float(&rng),
                                20.0f + 520.0f * pcg32_float(&rng));
        vec3 direction = vec3_make(2 * pcg32_float(&rng) - 1, 2 * pcg32_float(&rng) - 1, 2 * pcg32_float(&rng) - 1);
        /* inside the unit ball (directions uniform over the sphere), and not
         * so short that its normalising amplifies float rounding */
        const float shortest_squared = 1e-4f;
        if (vec3_dot(direction, direction) > 1.0f || vec3_dot(direction, direction) < shortest_squared)
            continue;
        ray r = ray_make(origin, direction);
        rays++;
        hit_record h[2];
        bool found[2] = {accel_closest_hit(tree, r, &h[0], &counters[0]), accel_closest_hit(twin, r, &h[1], &counters[1])};
        assert_int_equal(found[0], found[1]);
        if (found[0]) {
            assert_int_equal(h[0].shape_id, h[1].shape_id);
            assert_true(h[0].t == h[1].t);
        }
    }
    /* the twin: every ray starts in the room leaf's box and tests its 8
     * triangles; the tree: 0.39 times as many tests */
    assert_true(counters[1].primitive_tests >= 8 * (uint64_t)rays);
    assert_true((double)counters[0].primitive_tests < 0.75 * (double)counters[1].primitive_tests);
    accel_destroy(tree);
    accel_destroy(twin);
    pt_scene_free(&sc);
}

static void test_wide_bvh_empty_set_builds_and_misses(void **state)
{
    (void)state;
    mesh m;
    mesh_init(&m);
    triangle_set set;
    triangle_set_from_mesh(&set, &m);
    accel *a = wide_bvh_build(&set, BVH_SPLIT_SAH);
    hit_record hit;
    ray_counters counters = {0};
    assert_false(accel_closest_hit(a, ray_from(0, 0, 0, 0, 0, 1), &hit, &counters));
    assert_false(accel_any_hit(a, ray_from(0, 0, 0, 0, 0, 1), &counters));
    /* and a stream of rays: every one misses, none is left unanswered */
    ray rays[3] = {ray_from(0, 0, 0, 0, 0, 1), ray_from(1, 2, 3, -1, 0, 0), ray_from(0, 0, 0, 1, 1, 1)};
    hit_record hits[3];
    bool found[3] = {true, true, true}, any[3] = {true, true, true};
    wide_bvh_closest_hit_stream(a, rays, 3, hits, found, &counters);
    wide_bvh_any_hit_stream(a, rays, 3, any, &counters);
    for (int i = 0; i < 3; i++)
        assert_false(found[i] || any[i]);
    accel_destroy(a);
    triangle_set_free(&set);
    mesh_free(&m);
}

/* The wide tree on 1, 2 and 3 threads (its binary tree's halves built as
 * OpenMP tasks, its packets filled by every thread): the same nodes and
 * packets, byte for byte, in both layouts. */
static void test_wide_bvh_is_the_same_on_any_number_of_threads(void **state)
{
    (void)state;
    int threads = omp_get_max_threads();
    mesh m;
    mesh_init(&m);
    mesh_tori_field(&m, 40960);
    triangle_set set;
    triangle_set_from_mesh(&set, &m);
    for (int layout = 0; layout < 2; layout++) {
        wide_bvh *trees[3];
        for (int t = 0; t < 3; t++) {
            omp_set_num_threads(t + 1);
            trees[t] = (wide_bvh *)wide_bvh_build_layout(&set, BVH_SPLIT_SAH, (wide_bvh_layout)layout);
        }
        for (int t = 1; t < 3; t++) {
            assert_int_equal(trees[t]->node_count, trees[0]->node_count);
            assert_int_equal(trees[t]->packet_count, trees[0]->packet_count);
            if (layout == WIDE_BVH_QUANTIZED)
                assert_memory_equal(trees[t]->qnodes, trees[0]->qnodes,
                                    (size_t)trees[0]->node_count * sizeof(wide_bvh_qnode));
            else
                assert_memory_equal(trees[t]->nodes, trees[0]->nodes,
                                    (size_t)trees[0]->node_count * sizeof(wide_bvh_node));
            assert_memory_equal(trees[t]->packets, trees[0]->packets,
                                (size_t)trees[0]->packet_count * sizeof(wide_bvh_packet));
        }
        for (int t = 0; t < 3; t++)
            accel_destroy(&trees[t]->base);
    }
    omp_set_num_threads(threads);
    triangle_set_free(&set);
    mesh_free(&m);
}

/* ---- no tree: every triangle, eight at a time (flat.h) -------------------------- */

/* Rays on which `a` answers differently from chapter 03's brute force,
 * which tests the triangles one by one in order: found or not, and the hit
 * record bit for bit (t, barycentrics, point, normal, triangle, material;
 * of equal t the lower index wins in both), the triangles tested, and any
 * hit. Flat runs the same arithmetic, so nothing may differ, not even on
 * the coincident and degenerate meshes where ties are everywhere. */
static long flat_mismatches(const accel *a, const accel *brute, const mesh *m, const triangle_set *set, int rays,
                            uint64_t seed, long *hits)
{
    pcg32 rng = pcg32_for_pixel(seed, 606);
    long wrong = 0;
    for (int i = 0; i < rays; i++) {
        ray r = accel_check_ray(m, set->bounds.lo, set->bounds.hi, &rng, i);
        hit_record want, got;
        memset(&want, 0, sizeof want);
        memset(&got, 0, sizeof got);
        ray_counters c_want = {0}, c_got = {0};
        bool want_hit = accel_closest_hit(brute, r, &want, &c_want);
        bool got_hit = accel_closest_hit(a, r, &got, &c_got);
        bool same = want_hit == got_hit && c_want.primitive_tests == c_got.primitive_tests &&
                    accel_any_hit(a, r, &c_got) == want_hit;
        if (same && want_hit)
            same = memcmp(&want, &got, sizeof want) == 0;
        *hits += want_hit;
        wrong += !same;
    }
    return wrong;
}

static void test_flat_equals_brute_force_bit_for_bit(void **state)
{
    (void)state;
    const flat_kernel kernels[] = {FLAT_KERNEL_AVX512, FLAT_KERNEL_AVX, FLAT_KERNEL_SSE, FLAT_KERNEL_SCALAR};
    const char *names[] = {"avx with avx-512 registers", "avx", "sse", "scalar"};
    int kernels_run = 0;
    for (int k = 0; k < 4; k++) {
        long hits = 0, wrong = 0;
        bool available = flat_kernel_runs(kernels[k]);
        for (int kind = 0; kind < MESH_KIND_COUNT && available; kind++) {
            mesh m;
            triangle_set set;
            accel_check_make_mesh(&m, (accel_check_mesh)kind);
            triangle_set_from_mesh(&set, &m);
            accel *brute = brute_force_build(&set), *a = flat_build(&set);
            assert_true(flat_set_kernel(a, kernels[k]));
            /* the big meshes cost brute force's time twice: fewer rays */
            if (available)
                wrong += flat_mismatches(a, brute, &m, &set, set.count > 2000 ? 300 : 3000, 60 + (uint64_t)kind, &hits);
            accel_destroy(a);
            accel_destroy(brute);
            triangle_set_free(&set);
            mesh_free(&m);
        }
        if (!available) {
            print_message("flat: the %s kernel does not run here\n", names[k]);
            continue;
        }
        kernels_run++;
        print_message("flat, %s kernel: %ld rays hit, %ld answers differ from brute force\n", names[k], hits, wrong);
        assert_true(hits > 2000);
        assert_int_equal(wrong, 0);
    }
    assert_true(kernels_run >= 1);
}

/* The twins: two ways to get a flat set wrong, each caught. The last block
 * dropped (the count of blocks rounded down, a classic), and the triangle
 * numbers of lanes 0 and 1 swapped in every block (a hit reported for the
 * wrong triangle). */
static void test_flat_twins_are_caught(void **state)
{
    (void)state;
    mesh m;
    triangle_set set;
    /* the first mesh with a partial last block to drop */
    for (int kind = 0;; kind++) {
        assert_true(kind < MESH_KIND_COUNT);
        accel_check_make_mesh(&m, (accel_check_mesh)kind);
        triangle_set_from_mesh(&set, &m);
        if (set.count % FLAT_LANES != 0 && set.count < 2000)
            break;
        triangle_set_free(&set);
        mesh_free(&m);
    }
    accel *brute = brute_force_build(&set), *a = flat_build(&set);
    flat *f = (flat *)a;
    long hits = 0;
    assert_int_equal(flat_mismatches(a, brute, &m, &set, 3000, 61, &hits), 0);
    f->block_count--;
    long dropped = flat_mismatches(a, brute, &m, &set, 3000, 61, &hits);
    f->block_count++;
    for (int i = 0; i < f->block_count; i++) {
        int32_t first = f->blocks[i].index[0];
        f->blocks[i].index[0] = f->blocks[i].index[1];
        f->blocks[i].index[1] = first;
    }
    long swapped = flat_mismatches(a, brute, &m, &set, 3000, 61, &hits);
    print_message("flat twins: last block dropped %ld, two lanes swapped %ld of 3000 rays wrong\n", dropped, swapped);
    assert_true(dropped > 0 && swapped > 0);
    accel_destroy(a);
    accel_destroy(brute);
    triangle_set_free(&set);
    mesh_free(&m);
}

/* Eight rays at once (flat_closest_hit8, flat_any_hit8): each active lane
 * gets the single ray's answer, bit for bit, and idle lanes are left alone.
 * `shift` > 0 is the twin: lane k is handed ray k + shift's answer. */
static long packet_mismatches(flat_kernel kernel, int shift, long *compared)
{
    long wrong = 0;
    for (int kind = 0; kind < MESH_KIND_COUNT; kind++) {
        mesh m;
        triangle_set set;
        accel_check_make_mesh(&m, (accel_check_mesh)kind);
        triangle_set_from_mesh(&set, &m);
        if (set.count > 2000) { /* brute force on a big mesh: slow, and nothing new */
            triangle_set_free(&set);
            mesh_free(&m);
            continue;
        }
        accel *a = flat_build(&set);
        assert_true(flat_set_kernel(a, kernel));
        pcg32 rng = pcg32_for_pixel(62, (uint64_t)kind);
        for (int packet = 0; packet < 300; packet++) {
            ray rays[FLAT_LANES];
            for (int k = 0; k < FLAT_LANES; k++)
                rays[k] = accel_check_ray(&m, set.bounds.lo, set.bounds.hi, &rng, packet * FLAT_LANES + k);
            int active = packet % 3 == 0 ? (int)(pcg32_next(&rng) & 0xFF) : 0xFF;
            hit_record hits[FLAT_LANES];
            bool found[FLAT_LANES], any[FLAT_LANES];
            memset(hits, 0, sizeof hits);
            for (int k = 0; k < FLAT_LANES; k++)
                found[k] = any[k] = true; /* idle lanes must keep these */
            ray_counters c = {0};
            flat_closest_hit8(a, rays, active, hits, found, &c);
            flat_any_hit8(a, rays, active, any, &c);
            for (int k = 0; k < FLAT_LANES; k++) {
                if (!((active >> k) & 1)) {
                    wrong += !(found[k] && any[k]);
                    continue;
                }
                const ray *r = &rays[(k + shift) % FLAT_LANES];
                hit_record want;
                memset(&want, 0, sizeof want);
                bool want_hit = accel_closest_hit(a, *r, &want, &c);
                bool same = found[k] == want_hit && any[k] == accel_any_hit(a, *r, &c);
                if (same && want_hit)
                    same = memcmp(&hits[k], &want, sizeof want) == 0;
                wrong += !same;
                (*compared)++;
            }
        }
        accel_destroy(a);
        triangle_set_free(&set);
        mesh_free(&m);
    }
    return wrong;
}

static void test_flat_packets_give_each_ray_its_own_answer(void **state)
{
    (void)state;
    const flat_kernel kernels[] = {FLAT_KERNEL_AVX512, FLAT_KERNEL_AVX, FLAT_KERNEL_SSE};
    const char *names[] = {"avx with avx-512 registers", "avx", "sse: one ray at a time"};
    int run = 0;
    for (int k = 0; k < 3; k++) {
        if (!flat_kernel_runs(kernels[k])) {
            print_message("flat packets: the %s kernel does not run here\n", names[k]);
            continue;
        }
        long compared = 0, twin_compared = 0;
        long wrong = packet_mismatches(kernels[k], 0, &compared);
        long twin = packet_mismatches(kernels[k], 1, &twin_compared);
        print_message("flat packets (%s): %ld rays, %ld wrong; each lane given its neighbour's answer: %ld wrong\n",
                      names[k], compared, wrong, twin);
        assert_true(compared > 5000);
        assert_int_equal(wrong, 0);
        assert_true(twin > compared / 4);
        run++;
    }
    assert_true(run >= 1);
}

static void test_flat_empty_set_builds_and_misses(void **state)
{
    (void)state;
    mesh m;
    mesh_init(&m);
    triangle_set set;
    triangle_set_from_mesh(&set, &m);
    accel *a = flat_build(&set);
    hit_record hit;
    ray_counters counters = {0};
    const flat_kernel kernels[] = {FLAT_KERNEL_AVX512, FLAT_KERNEL_AVX, FLAT_KERNEL_SSE, FLAT_KERNEL_SCALAR};
    for (int k = 0; k < 4; k++) {
        if (!flat_set_kernel(a, kernels[k]))
            continue;
        assert_false(accel_closest_hit(a, ray_from(0, 0, 0, 0, 0, 1), &hit, &counters));
        assert_false(accel_any_hit(a, ray_from(0, 0, 0, 0, 0, 1), &counters));
    }
    assert_int_equal(counters.primitive_tests, 0);
    accel_destroy(a);
    triangle_set_free(&set);
    mesh_free(&m);
}

/* ---- streams: rays taking turns ------------------------------------------------- */

/* Rays of one stream whose answers differ from what the same rays get one
 * at a time: found or not, and the whole hit record (t, barycentrics, point,
 * normals, triangle, material) bit for bit; any hit the same. */
static long stream_mismatches(const accel *a, const ray *rays, int count, const hit_record *hits,
                              const bool *found, const bool *any)
{
    long mismatches = 0;
    for (int i = 0; i < count; i++) {
        hit_record want;
        ray_counters c = {0};
        bool want_found = accel_closest_hit(a, rays[i], &want, &c);
        bool same = want_found == found[i] && accel_any_hit(a, rays[i], &c) == any[i];
        if (same && want_found)
            same = want.t == hits[i].t && want.u == hits[i].u && want.v == hits[i].v &&
                   want.shape_id == hits[i].shape_id && want.material_id == hits[i].material_id &&
                   memcmp(&want.point, &hits[i].point, sizeof want.point) == 0 &&
                   memcmp(&want.normal_shading, &hits[i].normal_shading, sizeof want.normal_shading) == 0;
        mismatches += !same;
    }
    return mismatches;
}

/* A stream hands each ray what it would get alone, whatever the stream's
 * length (0, fewer rays than lanes, not a multiple of them, thousands), on
 * every mesh of the differential test and with both kernels. Half the rays
 * are cut short before their hit, so neighbours in the stream have
 * different answers, and a lane that kept the previous ray's closest hit
 * (or its t_max) would be caught. The counters are those of the rays one at
 * a time, summed. Twin: the same answers handed on to the next ray, the
 * mistake a stream can make that a single ray cannot, are caught. */
static void test_wide_bvh_stream_gives_each_ray_its_own_answer(void **state)
{
    (void)state;
    enum { RAYS = 3001 };
    static const int lengths[] = {0, 1, WIDE_BVH_STREAM_LANES - 1, WIDE_BVH_STREAM_LANES + 3, RAYS};
    ray *rays = calloc(RAYS, sizeof *rays);
    hit_record *hits = calloc(RAYS, sizeof *hits);
    bool *found = calloc(RAYS, sizeof *found), *any = calloc(RAYS, sizeof *any);
    long shifted_mismatches = 0, hit_count = 0;
    for (int kind = 0; kind < MESH_KIND_COUNT; kind++) {
        mesh m;
        triangle_set set;
        accel *a = wide_bvh_of_mesh_kind((accel_check_mesh)kind, &m, &set);
        pcg32 rng = pcg32_for_pixel(6, 60 + kind);
        for (int i = 0; i < RAYS; i++) {
            rays[i] = accel_check_ray(&m, set.bounds.lo, set.bounds.hi, &rng, i);
            hit_record h;
            ray_counters c = {0};
            if (i % 2 == 1 && accel_closest_hit(a, rays[i], &h, &c))
                rays[i].t_max = h.t * 0.5f;
        }
        for (int kernel = 0; kernel < WIDE_BVH_KERNELS; kernel++) {
            if (!wide_bvh_set_kernel(a, wide_bvh_kernels[kernel]))
                continue;
            for (size_t l = 0; l < sizeof lengths / sizeof lengths[0]; l++) {
                int n = lengths[l];
                ray_counters stream = {0}, alone = {0};
                wide_bvh_closest_hit_stream(a, rays, n, hits, found, &stream);
                wide_bvh_any_hit_stream(a, rays, n, any, &stream);
                for (int i = 0; i < n; i++) {
                    hit_record h;
                    accel_closest_hit(a, rays[i], &h, &alone);
                    accel_any_hit(a, rays[i], &alone);
                    hit_count += found[i];
                }
                if (stream_mismatches(a, rays, n, hits, found, any) != 0)
                    fail_msg("%s, kernel %d, stream of %d: answers differ from single rays",
                             accel_check_mesh_names[kind], kernel, n);
                assert_int_equal(stream.box_tests, alone.box_tests);
                assert_int_equal(stream.primitive_tests, alone.primitive_tests);
            }
            /* the twin: every answer handed to the next ray */
            shifted_mismatches += stream_mismatches(a, rays + 1, RAYS - 1, hits, found, any);
        }
        accel_destroy(a);
        triangle_set_free(&set);
        mesh_free(&m);
    }
    print_message("streams: %ld hits; answers handed to the next ray: %ld wrong\n", hit_count, shifted_mismatches);
    assert_true(hit_count > 1000);
    assert_true(shifted_mismatches > 1000);
    free(rays);
    free(hits);
    free(found);
    free(any);
}


/* ==== walls, offsets and eight paths at a time (from chapter 09) ==== */
static ray random_segment(const pt_scene *sc, bool on_surfaces, pcg32 *rng)
{
    if (on_surfaces) {
        const triangle *a = &sc->triangles.triangles[pcg32_bounded(rng, (uint32_t)sc->triangles.count)];
        const triangle *b = &sc->triangles.triangles[pcg32_bounded(rng, (uint32_t)sc->triangles.count)];
        vec3 from = point_on_triangle(a, rng), to = point_on_triangle(b, rng);
        vec3 from_normal = triangle_normal(a), to_normal = triangle_normal(b);
        return ray_spawn_to(from, triangle_point_error(a, from, from_normal), from_normal, to,
                            triangle_point_error(b, to, to_normal), to_normal);
    }
    vec3 lo = sc->triangles.bounds.lo, hi = sc->triangles.bounds.hi, size = vec3_sub(hi, lo);
    vec3 p[2];
    for (int k = 0; k < 2; k++)
        p[k] = vec3_make(lo.x - 0.5f * size.x + 2.0f * size.x * pcg32_float(rng),
                         lo.y - 0.5f * size.y + 2.0f * size.y * pcg32_float(rng),
                         lo.z - 0.5f * size.z + 2.0f * size.z * pcg32_float(rng));
    ray r = ray_make(p[0], vec3_sub(p[1], p[0]));
    r.t_max = 1.0f;
    return r;
}

/* The Cornell box's room is five faces with the whole box in front of
 * them: walls. The light (the ceiling is behind it) and the blocks (each
 * has the room behind its faces) are not. Four faces are flat and axis-
 * aligned, one plane each; the red wall's published corners are not in
 * one plane, so its two triangles have a plane each. Rendered with the
 * walls and without them, the image is the same bit for bit. */
static void test_the_cornell_box_has_ten_walls_that_change_no_image(void **state)
{
    (void)state;
    pt_scene sc;
    pt_scene_build_cornell_box(&sc);
    use_production(&sc, true);
    /* The red wall's quad: is its fourth corner off the plane of the
     * first three? */
    vec3 a = {552.8f, 0, 0}, b = {549.6f, 0, 559.2f}, c = {556, 548.8f, 559.2f}, d = {556, 548.8f, 0};
    double volume = (double)vec3_dot(vec3_cross(vec3_sub(b, a), vec3_sub(c, a)), vec3_sub(d, a));
    int expected_planes = 4 + (volume != 0.0 ? 2 : 1);
    assert_int_equal(walls_triangle_count(sc.bvh), 10);
    assert_int_equal(walls_plane_count(sc.bvh), expected_planes);
    const triangle_set *occluders = walls_occluders(sc.bvh)->set;
    assert_int_equal(occluders->count, sc.triangles.count - 10);
    /* The room's quads are added first (pt_scene_add_cornell_room): the
     * occluders are exactly the triangles after them, in order. */
    for (int i = 0; i < occluders->count; i++)
        assert_memory_equal(&occluders->triangles[i], &sc.triangles.triangles[10 + i], sizeof(triangle));

    /* The walls change no answer: the render with them and without them
     * is the same, bit for bit; with them nearly every shadow ray skips
     * them, without them none does. */
    {
        path_tracer with = tracer(&sc, PT_LECTURE, RR_FIXED);
        pt_scene without_walls;
        pt_scene_build_cornell_box(&without_walls);
        use_production(&without_walls, false);
        path_tracer without = tracer(&without_walls, PT_LECTURE, RR_FIXED);
        ray_counters c_with, c_without;
        assert_same_render(&with, &without, &c_with, &c_without);
        assert_true(c_with.shadow_rays_inside_walls >= c_with.shadow_rays * 99 / 100);
        assert_int_equal(c_without.shadow_rays_inside_walls, 0);
        assert_true(c_without.primitive_tests > c_with.primitive_tests);
        pt_scene_free(&without_walls);
    }
    pt_scene_free(&sc);

    /* A closed sphere of triangles has every face a wall, but hundreds of
     * small ones do not pay (scene_pt.c): none are used. */
    pt_scene_build_furnace(&sc, 0.5f, 0.5f);
    use_production(&sc, true);
    assert_int_equal(walls_triangle_count(sc.bvh), 0);
    assert_false(walls_found(sc.bvh));
    pt_scene_free(&sc);
}

/* The Cornell box (scene 0), or the box with a glass sphere (1). */
static void test_walls_skipped_only_where_they_cannot_block(void **state)
{
    (void)state;
    enum { SEGMENTS = 20000 };
    for (int scene = 0; scene < 2; scene++) {
        pt_scene sc;
        build_box_scene(&sc, scene);
        pcg32 rng = pcg32_for_pixel(test_seed(91), (uint64_t)scene);
        for (int kind = 0; kind < 2; kind++) {
            bool on_surfaces = kind == 0;
            ray_counters c = {0};
            int wrong = 0, wrong_twin = 0, blocked = 0;
            for (int i = 0; i < SEGMENTS; i++) {
                ray r = random_segment(&sc, on_surfaces, &rng);
                bool truth = occluded_by_everything(&sc, r);
                blocked += truth;
                wrong += pt_scene_occluded(&sc, r, &c) != truth;
                /* the twin: is the start alone in front of every wall? */
                ray start_only = r;
                start_only.t_max = r.t_min;
                ray_counters ignored = {0};
                bool twin = walls_segment_inside(sc.bvh, &start_only)
                                ? accel_any_hit(walls_occluders(sc.bvh), r, &ignored) || spheres_block(&sc, r)
                                : truth;
                wrong_twin += twin != truth;
            }
            assert_int_equal(wrong, 0);
            assert_true(blocked > 0 && blocked < SEGMENTS);
            if (on_surfaces) {
                /* every surface point, moved off its surface into the room,
                 * is in front of every wall: nearly all rays skip them */
                assert_true(c.shadow_rays_inside_walls >= (uint64_t)(0.99 * SEGMENTS));
            } else {
                assert_true(c.shadow_rays_inside_walls > 0 && c.shadow_rays_inside_walls < SEGMENTS);
                assert_true(wrong_twin > 0);
            }
        }
        pt_scene_free(&sc);
    }
}

/* pt_scene_visible() is the shadow ray ray_spawn_to() builds, tested: from
 * random surface points to random points on other surfaces (as light
 * samples) and to points in the room (as point lights, normal 0), it
 * answers as the whole tree and every sphere do on that ray, and counts
 * one shadow ray per call. The twin, a shadow ray that ends exactly on the
 * target's surface instead of just before it (the far end not offset),
 * is often blocked by that surface itself (2,337 and 2,851 of the 15,000
 * pairs on surfaces answer wrongly), and the same comparison catches it. */
static long double exact_distance(const triangle *t, vec3 p)
{
    long double e1[3] = {(long double)t->p1.x - t->p0.x, (long double)t->p1.y - t->p0.y, (long double)t->p1.z - t->p0.z};
    long double e2[3] = {(long double)t->p2.x - t->p0.x, (long double)t->p2.y - t->p0.y, (long double)t->p2.z - t->p0.z};
    long double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    long double q[3] = {(long double)p.x - t->p0.x, (long double)p.y - t->p0.y, (long double)p.z - t->p0.z};
    return (n[0] * q[0] + n[1] * q[1] + n[2] * q[2]) / sqrtl(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

/* How many points near the walls does the float test call "in front of
 * every wall" when, exactly, one is on or behind a wall? */
static int points_misjudged(const pt_scene *sc, int points, uint64_t seed, int *judged_inside)
{
    pcg32 rng = pcg32_for_pixel(seed, 0);
    int misjudged = 0;
    *judged_inside = 0;
    for (int i = 0; i < points; i++) {
        /* a point on a random wall, moved along its normal by +-2^-k of
         * the room's size, k from 6 to 40 (log-uniform): from well inside
         * to far below a float's resolution, both sides */
        const triangle *wall = &sc->triangles.triangles[pcg32_bounded(&rng, 10)];
        float step = ldexpf(560.0f, -6 - (int)pcg32_bounded(&rng, 35)) * (pcg32_float(&rng) < 0.5f ? -1.0f : 1.0f);
        vec3 p = vec3_add(point_on_triangle(wall, &rng), vec3_scale(triangle_normal(wall), step));
        ray at_p = ray_make(p, vec3_make(0, 1, 0));
        at_p.t_max = 0.0f; /* both ends at p */
        if (!walls_segment_inside_of(sc, &at_p))
            continue;
        (*judged_inside)++;
        bool behind = false;
        for (int w = 0; w < 10; w++)
            behind |= exact_distance(&sc->triangles.triangles[w], p) <= 0.0L;
        misjudged += behind;
    }
    return misjudged;
}

/* The float test of a point against the walls never says "in front" of a
 * point that is exactly on or behind one: its slack bounds the rounding
 * (scene_pt.c). Points at every distance from 2^-6 to 2^-40 of the room's
 * size, on both sides of every wall. And it is not so cautious that it
 * refuses the rays it is for: a point 2^-16 in front of the wall x = 0 (far
 * less than ray.h moves a ray's end off that wall: 64 roundings of its
 * 559.2 mm edge, 2e-3) is in front. The twin: with
 * no slack, points just behind the red wall, whose normal was rounded to
 * float, are called in front. */
static void test_wall_test_is_never_fooled_by_rounding(void **state)
{
    (void)state;
    enum { POINTS = 200000 };
    pt_scene sc;
    pt_scene_build_cornell_box(&sc);
    use_production(&sc, true);
    int inside = 0;
    assert_int_equal(points_misjudged(&sc, POINTS, test_seed(92), &inside), 0);
    assert_true(inside > POINTS / 4); /* about half the points are in front of all walls */

    ray near_green = ray_make(vec3_make(0x1.0p-16f, 274.0f, 280.0f), vec3_make(0, 1, 0));
    near_green.t_max = 0.0f;
    assert_true(walls_segment_inside_of(&sc, &near_green));
    near_green.origin.x = 0.0f; /* on the wall: not in front */
    assert_false(walls_segment_inside_of(&sc, &near_green));

    /* the twin */
    walls_drop_slack(sc.bvh);
    assert_true(points_misjudged(&sc, POINTS, test_seed(92), &inside) > 0);
    pt_scene_free(&sc);
}

/* A point on a random wall of the Cornell box, moved along its normal by
 * +-2^-k of the room's size, k from 6 to 40: where the wall test's answer
 * turns on its rounding. */
static vec3 point_near_a_wall(const pt_scene *sc, pcg32 *rng)
{
    const triangle *wall = &sc->triangles.triangles[pcg32_bounded(rng, 10)];
    float step = ldexpf(560.0f, -6 - (int)pcg32_bounded(rng, 35)) * (pcg32_float(rng) < 0.5f ? -1.0f : 1.0f);
    return vec3_add(point_on_triangle(wall, rng), vec3_scale(triangle_normal(wall), step));
}

/* Lanes of eight-ray packets whose answer from
 * walls_segments8_inside_of() is not walls_segment_inside_of()
 * of `truth` for the same ray alone: segments between two points near the
 * walls (as a shadow ray runs), some of them infinite or starting past
 * their origin, in packets with random lanes on. Counts the lanes found
 * inside. */
static long wall_lanes_misjudged(const pt_scene *sc, const pt_scene *truth, uint64_t seed, long *inside)
{
    pcg32 rng = pcg32_for_pixel(seed, 0);
    long wrong = 0;
    *inside = 0;
    for (int packet = 0; packet < 20000; packet++) {
        rays8 rays;
        ray alone[FLAT_LANES];
        for (int k = 0; k < FLAT_LANES; k++) {
            vec3 from = point_near_a_wall(sc, &rng), to = point_near_a_wall(sc, &rng);
            alone[k] = ray_make(from, vec3_sub(to, from));
            alone[k].t_max = 1.0f;
            uint32_t kind = pcg32_bounded(&rng, 8);
            if (kind == 0)
                alone[k].t_max = INFINITY;
            else if (kind == 1)
                alone[k].t_min = pcg32_float(&rng);
            rays8_set(&rays, k, alone[k]);
        }
        int active = (int)pcg32_bounded(&rng, 256);
        int got = walls_segments8_inside_of(sc, &rays, active);
        for (int k = 0; k < FLAT_LANES; k++) {
            bool expected = ((active >> k) & 1) && walls_segment_inside_of(truth, &alone[k]);
            wrong += ((got >> k) & 1) != expected;
            *inside += expected;
        }
    }
    return wrong;
}

/* Eight rays' wall test (the wide renderer's shadow packets) gives each
 * lane the answer of the one-ray test, bit for bit: the same operations
 * in the same order. Its twin, the eight-ray test without the slack that
 * bounds the rounding, differs on these segments. */
static void test_eight_rays_wall_test_is_the_one_ray_test(void **state)
{
    (void)state;
    pt_scene sc, sloppy;
    pt_scene_build_cornell_box(&sc);
    use_production(&sc, true);
    pt_scene_build_cornell_box(&sloppy);
    use_production(&sloppy, true);
    long inside = 0;
    long wrong = wall_lanes_misjudged(&sc, &sc, test_seed(93), &inside);
    print_message("eight rays' wall test: %ld of %d lanes differ from the one-ray test, %ld inside\n", wrong,
                  20000 * FLAT_LANES, inside);
    assert_int_equal(wrong, 0);
    /* both answers are common: each end is in front of all walls about
     * half the time, a lane is on half the time (5 946 inside seen) */
    assert_true(inside > 2000);
    assert_true(inside < 20000 * FLAT_LANES / 4);
    walls_drop_slack(sloppy.bvh);
    long twin = wall_lanes_misjudged(&sloppy, &sc, test_seed(93), &inside);
    print_message("twin, without the slack: %ld lanes differ\n", twin);
    assert_true(twin > 0);
    pt_scene_free(&sc);
    pt_scene_free(&sloppy);
}

/* ---- eight rays past the boxes of flat.c's groups ---------------------------------- */

/* How far outside its triangle's box a hit point o + t d may lie and still
 * be a true hit: rounding puts it a few ulps of the room (about 1e-4 mm)
 * away, unless the ray nearly lies in the triangle's plane, where t itself
 * means little; a meaningless "hit" of a ray in the plane lies hundreds of
 * millimetres away. A thousandth of the scene's size is far from both. */
static const float TRUE_HIT_REACH = 1e-3f;
/* The lanes that may differ from the ray alone are the rays in a
 * triangle's plane within rounding: rare (3 of 28 079 seen). A box test
 * that went wrong on more than that share would be hiding behind them. */
static const double IN_PLANE_SHARE_MAX = 1e-3;
/* The boxes must skip something: at most this share of the triangle tests
 * a packet would make with no boxes (74 % seen). */
static const double TESTED_SHARE_MAX = 0.9;
/* The twin must be caught plainly: more lanes than this lose a true hit
 * (1 113 seen). */
static const long TWIN_LANES_MIN = 100;

/* Is point p inside triangle `index`'s box, grown by TRUE_HIT_REACH of the
 * scene's size? */
static bool inside_triangle_box(const triangle_set *set, int index, vec3 p)
{
    aabb box = set->boxes[index];
    float grow = TRUE_HIT_REACH * vec3_max_component(aabb_extent(set->bounds));
    const float at[3] = {p.x, p.y, p.z}, lo[3] = {box.lo.x, box.lo.y, box.lo.z}, hi[3] = {box.hi.x, box.hi.y, box.hi.z};
    for (int axis = 0; axis < 3; axis++)
        if (!(at[axis] >= lo[axis] - grow && at[axis] <= hi[axis] + grow))
            return false;
    return true;
}

/* Packets whose rays run along the Cornell box's triangles, where a box
 * test and the triangle test are likeliest to disagree: each ray passes
 * through a random point of a triangle, in the triangle's plane or tilted
 * out of it by 10^-7 to 10^-2 radians, starting on the triangle or up to
 * two room sizes back along its line, its origin on the plane or 2^-16 off
 * it. Each lane is compared with the ray alone (flat.c, "Groups").
 *
 * A ray in a triangle's plane, within rounding, is where a triangle test
 * means nothing: the watertight test's determinant is rounding noise, and
 * its t (where the ray meets a plane it nearly lies in) may put the "hit"
 * hundreds of units from the triangle. A packet whose rays all miss
 * that triangle's box skips it and gives the true nearest hit instead. So
 * a lane may differ from the ray alone only there: where the lone ray's
 * hit point o + t d lies outside its triangle's box. Returns
 * the lanes that differ otherwise (*differ counts all that differ); counts
 * the hits and the triangles the packets tested. */
static long wall_packets_mismatched(const pt_scene *sc, uint64_t seed, long *differ, long *hits, uint64_t *tested,
                                    long *lanes)
{
    static const float tilts[] = {0.0f, 1e-7f, 1e-6f, 1e-5f, 1e-4f, 1e-3f, 1e-2f};
    static const float backs[] = {0.0f, 1.0f, 10.0f, 100.0f, 1000.0f};
    pcg32 rng = pcg32_for_pixel(seed, 0);
    const triangle_set *set = &sc->triangles;
    long wrong = 0;
    for (int packet = 0; packet < 4000; packet++) {
        ray rays[FLAT_LANES];
        for (int k = 0; k < FLAT_LANES; k++) {
            const triangle *tri = &set->triangles[pcg32_bounded(&rng, (uint32_t)set->count)];
            float a = pcg32_float(&rng), b = pcg32_float(&rng);
            if (a + b > 1.0f) {
                a = 1.0f - a;
                b = 1.0f - b;
            }
            vec3 e1 = vec3_sub(tri->p1, tri->p0), e2 = vec3_sub(tri->p2, tri->p0);
            vec3 point = vec3_add(tri->p0, vec3_add(vec3_scale(e1, a), vec3_scale(e2, b)));
            vec3 normal = triangle_unit_normal(tri);
            float angle = 6.2831853f * pcg32_float(&rng);
            vec3 along = vec3_normalize(vec3_add(vec3_scale(vec3_normalize(e1), cosf(angle)),
                                                 vec3_scale(vec3_normalize(vec3_cross(normal, e1)), sinf(angle))));
            float tilt = tilts[pcg32_bounded(&rng, 7)] * (pcg32_next(&rng) & 1 ? 1.0f : -1.0f);
            vec3 direction = vec3_normalize(vec3_add(along, vec3_scale(normal, tilt)));
            vec3 origin = vec3_sub(point, vec3_scale(direction, backs[pcg32_bounded(&rng, 5)]));
            uint32_t off = pcg32_bounded(&rng, 3);
            if (off > 0)
                origin = vec3_add(origin, vec3_scale(normal, off == 1 ? 0x1.0p-16f : -0x1.0p-16f));
            rays[k] = ray_make(origin, direction);
        }
        int active = packet % 4 == 0 ? (int)(pcg32_next(&rng) & 0xFF) : 0xFF;
        hit_record got[FLAT_LANES];
        bool found[FLAT_LANES], any[FLAT_LANES];
        memset(got, 0, sizeof got);
        ray_counters c = {0};
        flat_closest_hit8(walls_all(sc->bvh), rays, active, got, found, &c);
        flat_any_hit8(walls_all(sc->bvh), rays, active, any, &c);
        *tested += c.primitive_tests;
        for (int k = 0; k < FLAT_LANES; k++) {
            if (!((active >> k) & 1))
                continue;
            hit_record want;
            memset(&want, 0, sizeof want);
            ray_counters alone = {0};
            bool want_hit = accel_closest_hit(walls_all(sc->bvh), rays[k], &want, &alone);
            bool want_any = accel_any_hit(walls_all(sc->bvh), rays[k], &alone);
            bool same = found[k] == want_hit && any[k] == want_any;
            if (same && want_hit)
                same = memcmp(&got[k], &want, sizeof want) == 0;
            *differ += !same;
            *hits += want_hit;
            (*lanes)++;
            /* differing is allowed only where the lone ray's hit is outside its box */
            if (!same && !(want_hit && !inside_triangle_box(set, want.shape_id, ray_at(rays[k], want.t))))
                wrong++;
        }
    }
    return wrong;
}

/* The packets skip the groups none of their rays meet, and still give each
 * ray its own answer wherever that answer is a point of its triangle's box.
 * They test fewer than all 32 triangles per ray (the boxes do skip). The
 * twin: boxes shrunk by twice their padding, so that they no longer hold
 * their triangles, lose true hits. */
static void test_packets_along_the_walls_match_single_rays(void **state)
{
    (void)state;
    pt_scene sc;
    pt_scene_build_cornell_box(&sc);
    use_production(&sc, true);
    assert_true(flat_is(walls_all(sc.bvh)));
    flat *f = (flat *)walls_all(sc.bvh);
    if (!flat_kernel_runs(FLAT_KERNEL_AVX)) {
        pt_scene_free(&sc);
        skip(); /* the packets are rays one at a time: nothing to compare */
    }
    long hits = 0, lanes = 0, differ = 0;
    uint64_t tested = 0;
    long wrong = wall_packets_mismatched(&sc, test_seed(94), &differ, &hits, &tested, &lanes);
    /* closest and any hit per lane: 2 * 32 triangles per lane if nothing were skipped */
    double share = (double)tested / (2.0 * (double)lanes * (double)sc.triangles.count);
    print_message("packets along the walls: %ld lanes, %ld hits; %ld differ from one ray alone, %ld of them where "
                  "the lone ray's hit is inside its box; %d groups, %.0f %% of the triangles tested\n",
                  lanes, hits, differ, wrong, f->group_count, 100.0 * share);
    assert_int_equal(wrong, 0);
    assert_true(differ < IN_PLANE_SHARE_MAX * (double)lanes);
    assert_true(hits > lanes / 2); /* most rays are aimed at a triangle: the test is not about misses */
    assert_true(f->group_count > 1 && share < TESTED_SHARE_MAX);

    /* the twin: each box shrunk by twice GROUP_PAD of the scene's size */
    aabb s = sc.triangles.bounds;
    vec3 extent = aabb_extent(s), far = vec3_max(vec3_abs(s.lo), vec3_abs(s.hi));
    float shrink = 0x1.0p-9f * (vec3_max_component(extent) + vec3_max_component(far));
    for (int g = 0; g < f->group_count; g++)
        for (int axis = 0; axis < 3; axis++) {
            f->groups[g].lo[axis] += shrink;
            f->groups[g].hi[axis] -= shrink;
        }
    long twin_differ = 0, twin = wall_packets_mismatched(&sc, test_seed(94), &twin_differ, &hits, &tested, &lanes);
    print_message("boxes shrunk inside their triangles: %ld lanes differ where the lone ray's hit is inside its box\n",
                  twin);
    assert_true(twin > TWIN_LANES_MIN);
    pt_scene_free(&sc);
}

/* ---- eight paths at a time (path_tracer_wide.c) ----------------------------------- */

/* Eight paths at a time is the lecture rung by another route: its image
 * must agree with chapter 09's (the lecture rung, on chapter 06's BVH) in
 * distribution, for the lecture's roulette and the three deeper ones the
 * speed table compares (pbrt's, smallpt's, none), by the image-level
 * statistics of tests/image_check.h. Its own guarantees hold bit for bit:
 * the same image at 1 and 2 threads, and with the lanes' arithmetic in AVX
 * or lane by lane. The twin: the wide renderer with every albedo 10 % low
 * is caught by the same comparison. */
enum { WIDE_SIZE = 12, WIDE_SPP = 512, WIDE_IMAGES = 5 };

static image_check wide_against_chapter_09(const path_tracer *wide_pt, const path_tracer *lecture_pt, uint64_t seed)
{
    camera cam = pt_scene_camera(wide_pt->scene, WIDE_SIZE, WIDE_SIZE);
    estimate_image wide, lecture = render_estimate(lecture_pt, &cam, WIDE_SPP, test_seed(seed), 2);
    assert_true(render_estimate_wide(wide_pt, &cam, WIDE_SPP, test_seed(seed + 1), 2, &wide));
    image_check c = check_agree(&wide.mean, &wide.standard_error, &lecture.mean, &lecture.standard_error);
    estimate_image_free(&wide);
    estimate_image_free(&lecture);
    return c;
}

static void test_eight_paths_agree_with_chapter_09(void **state)
{
    (void)state;
    pt_scene prod, lecture;
    pt_scene_build_cornell_box(&prod);
    use_production(&prod, true);
    pt_scene_build_cornell_box(&lecture); /* chapter 06's BVH, as chapter 09 renders */
    static const struct {
        pt_russian_roulette rr;
        int start, max_depth;
        const char *label;
    } roulettes[] = {{RR_FIXED, 0, 64, "P_RR 0.8"},
                     {RR_THROUGHPUT, RR_START_PBRT, 64, "throughput from 5"},
                     {RR_ALBEDO, RR_START_SMALLPT, 64, "albedo from 6"},
                     {RR_OFF, 0, 50, "none, depth 50"}};
    for (int k = 0; k < 4; k++) {
        path_tracer w = tracer(&prod, PT_LECTURE, roulettes[k].rr), l = tracer(&lecture, PT_LECTURE, roulettes[k].rr);
        w.max_depth = l.max_depth = roulettes[k].max_depth;
        if (roulettes[k].start > 0)
            w.rr_start_depth = l.rr_start_depth = roulettes[k].start;
        assert_image_check(wide_against_chapter_09(&w, &l, 131 + 2 * (uint64_t)k), WIDE_IMAGES, roulettes[k].label);
    }
    /* the twin: every albedo 10 % low, eight paths at a time */
    for (int m = 0; m < prod.material_count; m++)
        prod.materials[m].albedo = vec3_scale(prod.materials[m].albedo, 0.90f);
    path_tracer w = tracer(&prod, PT_LECTURE, RR_FIXED), l = tracer(&lecture, PT_LECTURE, RR_FIXED);
    image_check twin = wide_against_chapter_09(&w, &l, 141);
    print_message("twin, albedo 10 %% low: p = %.3g (image mean z = %.1f, chi-square %.0f on %d)\n", twin.p, twin.z,
                  twin.chi2, twin.dof);
    assert_true(twin.p < image_check_alpha(WIDE_IMAGES));
    pt_scene_free(&prod);
    pt_scene_free(&lecture);
}

static void test_eight_paths_same_bits_for_threads_and_lanes(void **state)
{
    (void)state;
    pt_scene sc;
    pt_scene_build_cornell_box(&sc);
    use_production(&sc, true);
    camera cam = pt_scene_camera(&sc, 24, 24);
    for (int rung = 0; rung < 3; rung++) {
        path_tracer pt = tracer(&sc, (pt_integrator)rung, RR_FIXED);
        estimate_image one, two, lanes;
        assert_true(render_estimate_wide(&pt, &cam, 8, test_seed(91), 1, &one));
        assert_true(render_estimate_wide(&pt, &cam, 8, test_seed(91), 2, &two));
        path_tracer_wide_use_avx(false); /* the lanes' arithmetic one lane at a time */
        assert_true(render_estimate_wide(&pt, &cam, 8, test_seed(91), 1, &lanes));
        path_tracer_wide_use_avx(true);
        assert_memory_equal(one.mean.rgb, two.mean.rgb, sizeof(float) * 3 * 24 * 24);
        assert_memory_equal(one.standard_error.rgb, two.standard_error.rgb, sizeof(float) * 3 * 24 * 24);
        assert_memory_equal(one.mean.rgb, lanes.mean.rgb, sizeof(float) * 3 * 24 * 24);
        estimate_image_free(&one);
        estimate_image_free(&two);
        estimate_image_free(&lanes);
    }
    /* what it refuses: --explain, which follows one path; what it takes:
     * every rung, and a scene on chapter 06's BVH (traced one ray at a
     * time, wide_trace.h) */
    path_tracer pt = tracer(&sc, PT_MIS, RR_FIXED);
    assert_true(path_tracer_wide_supported(&pt, NULL, 0));
    explain_begin(stderr);
    char why[64] = "";
    assert_false(path_tracer_wide_supported(&pt, why, sizeof why));
    explain_end();
    assert_non_null(strstr(why, "explain"));
    /* A material kind the lanes do not render (here a value past chapter
     * 09's kinds, standing for one added after them) is refused by its
     * name, so the scene is rendered one path at a time, never with black
     * lanes. */
    pt_material kept = sc.materials[1];
    sc.materials[1].kind = (bsdf_kind)BSDF_KIND_COUNT;
    char kind_why[160] = "";
    assert_false(path_tracer_wide_supported(&pt, kind_why, sizeof kind_why));
    assert_non_null(strstr(kind_why, "material 1 is of kind '?'"));
    estimate_image refused;
    assert_false(render_estimate_wide(&pt, &cam, 1, test_seed(92), 1, &refused));
    sc.materials[1] = kept;
    assert_true(path_tracer_wide_supported(&pt, NULL, 0));
    pt_scene lecture;
    pt_scene_build_cornell_box(&lecture);
    path_tracer on_bvh = tracer(&lecture, PT_LECTURE, RR_FIXED);
    assert_true(path_tracer_wide_supported(&on_bvh, NULL, 0));
    assert_string_equal(wide_scene_tracers_for(&lecture).all.name, "one ray at a time");
    pt_scene_free(&lecture);
    pt_scene_free(&sc);
}


/* ---- every scene chapter 09 renders ---------------------------------------------
 * The same comparison on what the renderer once refused: a mesh larger than
 * the flat set (the 4-wide BVH's streams), spheres of glass and a GGX
 * metal, a mirror, a point light and the environment, and the Sobol
 * sampler. Each scene's twins change one thing in the eight-path render
 * only -- an albedo, a light's intensity, a term dropped -- and each must
 * be caught. */
enum { EVERY_SCENE_CHECKS = 5, MESH_TRIANGLES = 2000 };

/* The box's room, a mirror sphere and a glossy one, a point light, and an
 * environment that comes in through the open front. */
static void build_feature_scene(pt_scene *sc)
{
    pt_scene_init(sc);
    pt_scene_add_painted_cornell_room(sc);
    pt_scene_add_sphere(sc, vec3_make(370, 120, 350), 120, pt_scene_add_material(sc, pt_mirror(vec3_splat(0.9f))),
                        false);
    pt_scene_add_sphere(sc, vec3_make(170, 90, 200), 90,
                        pt_scene_add_material(sc, pt_glossy(vec3_make(0.9f, 0.6f, 0.3f), 0.2f)), false);
    pt_scene_add_point_light(sc, vec3_make(278, 400, 150), vec3_splat(8e4f));
    sc->environment = vec3_splat(2.0f);
    pt_scene_finish(sc);
}

/* The box's room whose white walls glow, with its light and a GGX sphere:
 * emitters large and near every surface, where light sampling and BSDF
 * sampling each find much of the light, and the MIS weights matter. */
static void build_glowing_room(pt_scene *sc)
{
    pt_scene_init(sc);
    int white = pt_scene_add_material(sc, pt_emitter(PT_CORNELL_WHITE, vec3_splat(1.0f)));
    int red = pt_scene_add_material(sc, pt_diffuse(PT_CORNELL_RED));
    int green = pt_scene_add_material(sc, pt_diffuse(PT_CORNELL_GREEN));
    int light = pt_scene_add_material(sc, pt_emitter(vec3_splat(0.65f), PT_CORNELL_LIGHT));
    pt_scene_add_cornell_room(sc, white, red, green, light);
    pt_scene_add_sphere(sc, vec3_make(278, 150, 280), 150,
                        pt_scene_add_material(sc, pt_glossy(vec3_make(0.9f, 0.6f, 0.3f), 0.15f)), false);
    pt_scene_finish(sc);
}

/* Scene `scene` (0: the box with a torus, 1: chapter 09's materials, 2:
 * the feature scene, 3: the glowing room), with its twin `twin` (0: none). */
static void build_every_scene(pt_scene *sc, int scene, int twin)
{
    if (scene == 0)
        production_scene_box_with_torus(sc, MESH_TRIANGLES);
    else if (scene == 1)
        pt_scene_build_cornell_box_materials(sc);
    else if (scene == 2)
        build_feature_scene(sc);
    else
        build_glowing_room(sc);
    for (int m = 0; m < sc->material_count; m++) {
        pt_material *mat = &sc->materials[m];
        bool wrong = (scene == 0 && twin == 1) || (scene == 1 && twin == 1 && mat->kind == BSDF_GLASS) ||
                     (scene == 1 && twin == 2 && mat->kind == BSDF_GLOSSY) ||
                     (scene == 2 && twin == 3 && mat->kind == BSDF_MIRROR);
        if (wrong) /* the spheres and the metal block cover a few of the 144 pixels: a larger error */
            mat->albedo = vec3_scale(mat->albedo, scene == 0 ? 0.85f : 0.5f);
    }
    if (scene == 2 && twin == 1)
        sc->point_lights[0].intensity = vec3_scale(sc->point_lights[0].intensity, 0.5f);
    if (scene == 2 && twin == 2)
        sc->environment = vec3_splat(0.0f);
}

static const char *const EVERY_SCENE_NAMES[] = {"box with a 2000-triangle torus", "glass and GGX metal",
                                                 "mirror, glossy sphere, point light, environment",
                                                 "glowing walls and a GGX sphere"};
static const char *const EVERY_SCENE_TWINS[3][4] = {{NULL, "every albedo 15 % low"},
                                                    {NULL, "glass tint halved", "GGX F0 halved"},
                                                    {NULL, "point light halved", "environment dropped",
                                                     "mirror albedo halved"}};

/* The eight-path render of scene `scene` (twin `twin`) on the production
 * structures against chapter 09's own render of the same rung on chapter
 * 06's BVH. */
static image_check rung_scene_check(pt_integrator rung, int scene, int twin, pt_russian_roulette rr, pt_sampler sampler,
                                    uint64_t seed)
{
    pt_scene wide_sc, lecture_sc;
    build_every_scene(&wide_sc, scene, twin);
    use_production(&wide_sc, true);
    build_every_scene(&lecture_sc, scene, 0);
    path_tracer w = tracer(&wide_sc, rung, rr), l = tracer(&lecture_sc, rung, rr);
    w.sampler = l.sampler = sampler;
    if (rr == RR_THROUGHPUT)
        w.rr_start_depth = l.rr_start_depth = RR_START_PBRT;
    image_check c = wide_against_chapter_09(&w, &l, seed);
    pt_scene_free(&wide_sc);
    pt_scene_free(&lecture_sc);
    return c;
}

static image_check every_scene_check(int scene, int twin, pt_russian_roulette rr, pt_sampler sampler, uint64_t seed)
{
    return rung_scene_check(PT_LECTURE, scene, twin, rr, sampler, seed);
}

static void test_eight_paths_agree_with_chapter_09_on_every_scene(void **state)
{
    (void)state;
    pt_scene mesh;
    build_every_scene(&mesh, 0, 0);
    use_production(&mesh, true);
    assert_true(mesh.triangles.count > 64 && wide_bvh_is(walls_all(mesh.bvh)));
    assert_string_equal(wide_scene_tracers_for(&mesh).all.name, "the " WIDE_BVH_NAME ", each lane's ray walking it alone");
    pt_scene_free(&mesh);
    for (int scene = 0; scene < 3; scene++)
        assert_image_check(every_scene_check(scene, 0, RR_FIXED, PT_SAMPLER_RANDOM, 171 + 2 * (uint64_t)scene),
                           EVERY_SCENE_CHECKS, EVERY_SCENE_NAMES[scene]);
    assert_image_check(every_scene_check(0, 0, RR_THROUGHPUT, PT_SAMPLER_RANDOM, 181), EVERY_SCENE_CHECKS,
                       "box with a torus, --rr throughput");
    assert_image_check(every_scene_check(2, 0, RR_FIXED, PT_SAMPLER_SOBOL, 183), EVERY_SCENE_CHECKS,
                       "feature scene, --sampler sobol");
    /* the twins, each caught */
    for (int scene = 0; scene < 3; scene++)
        for (int twin = 1; twin < 4 && EVERY_SCENE_TWINS[scene][twin] != NULL; twin++) {
            image_check c = every_scene_check(scene, twin, RR_FIXED, PT_SAMPLER_RANDOM, 191 + 8 * (uint64_t)scene);
            print_message("twin, %s, %s: p = %.3g (image mean z = %.1f)\n", EVERY_SCENE_NAMES[scene],
                          EVERY_SCENE_TWINS[scene][twin], c.p, c.z);
            assert_true(c.p < image_check_alpha(EVERY_SCENE_CHECKS));
        }
}

/* What the program and make bench run (production_path_tracer_defaults:
 * the MIS rung, Sobol points, roulette on throughput), eight paths at a
 * time on the production structures, against chapter 09's own render with
 * the same settings, on the benchmark scenes themselves (bench_scenes.h).
 * The million-triangle one is left out of the sanitizer build only: its
 * two builds would take most of that suite's time, and it is the 100k's
 * shape. The twin: the production render of the glossy and glass box with
 * the metal block's F0 halved. */
#if defined(__SANITIZE_ADDRESS__)
enum { BENCHMARK_SCENE_CHECKS = 5 }; /* the Sidak family: one image check per scene */
#else
enum { BENCHMARK_SCENE_CHECKS = 6 };
#endif
enum { BENCHMARK_GLOSSY_GLASS = 3 };

static void test_production_defaults_agree_with_chapter_09_on_the_benchmark_scenes(void **state)
{
    (void)state;
    static const char *const names[] = {"cornell",      "cornell-10k", "cornell-100k",
                                        "glossy-glass", "open-100k",   "cornell-1m"};
    for (int twin = 0; twin < 2; twin++)
        for (int i = twin ? BENCHMARK_GLOSSY_GLASS : 0; i < (twin ? BENCHMARK_GLOSSY_GLASS + 1 : BENCHMARK_SCENE_CHECKS);
             i++) {
            pt_scene wide_sc, lecture_sc;
            assert_true(bench_scene_build(&wide_sc, names[i]) && bench_scene_build(&lecture_sc, names[i]));
            use_production(&wide_sc, true);
            for (int m = 0; twin && m < wide_sc.material_count; m++)
                if (wide_sc.materials[m].kind == BSDF_GLOSSY)
                    wide_sc.materials[m].albedo = vec3_scale(wide_sc.materials[m].albedo, 0.5f);
            path_tracer w = production_path_tracer_defaults(&wide_sc), l = production_path_tracer_defaults(&lecture_sc);
            image_check c = wide_against_chapter_09(&w, &l, 301 + 2 * (uint64_t)i);
            pt_scene_free(&wide_sc);
            pt_scene_free(&lecture_sc);
            if (twin) {
                print_message("twin, %s, the metal's F0 halved: p = %.3g (image mean z = %.1f)\n", names[i], c.p, c.z);
                assert_true(c.p < image_check_alpha(BENCHMARK_SCENE_CHECKS));
            } else {
                print_message("production defaults, %s: p = %.3g (image mean z = %.1f)\n", names[i], c.p, c.z);
                assert_image_check(c, BENCHMARK_SCENE_CHECKS, names[i]);
            }
        }
}

/* The cosine and MIS rungs, eight paths at a time, against chapter 09's
 * trace_iterative() on the same scenes and the glowing room: with the
 * lecture's numbers and roulette (random, P_RR 0.8), and with the
 * production's (Sobol, on throughput from bounce 5). The twins leave one
 * of the MIS rung's two weights off, in the glowing room: the emission a
 * BSDF sample finds counted in full, and the light sample counted in full.
 * Each then counts the light both samples find once and a part (the other
 * weight), too bright; each must be caught. (In the box with its small
 * light the light sample's weight is within a few thousandths of 1 on the
 * walls: that twin would hide there.) */
enum { RUNG_SCENES = 4, RUNG_SCENE_CHECKS = 2 * RUNG_SCENES * 2 };

static void test_eight_paths_cosine_and_mis_agree_with_chapter_09(void **state)
{
    (void)state;
    static const pt_integrator rungs[] = {PT_COSINE, PT_MIS};
    for (int r = 0; r < 2; r++)
        for (int scene = 0; scene < RUNG_SCENES; scene++)
            for (int sampler = 0; sampler < 2; sampler++) {
                char what[128];
                snprintf(what, sizeof what, "%s rung, %s, %s", pt_integrator_name(rungs[r]), EVERY_SCENE_NAMES[scene],
                         sampler ? "Sobol, roulette on throughput" : "random, P_RR 0.8");
                uint64_t seed = 211 + 20 * (uint64_t)r + 4 * (uint64_t)scene + 2 * (uint64_t)sampler;
                image_check c = rung_scene_check(rungs[r], scene, 0, sampler ? RR_THROUGHPUT : RR_FIXED,
                                                 (pt_sampler)sampler, seed);
                print_message("%s: p = %.3g (image mean z = %.1f)\n", what, c.p, c.z);
                assert_image_check(c, RUNG_SCENE_CHECKS, what);
            }
    static const struct {
        wide_twin twin;
        const char *name;
    } twins[] = {{WIDE_TWIN_EMISSION_UNWEIGHTED, "emission found by the BSDF sample unweighted"},
                 {WIDE_TWIN_LIGHT_UNWEIGHTED, "light sample unweighted"}};
    for (int t = 0; t < 2; t++) {
        path_tracer_wide_twin(twins[t].twin);
        image_check c = rung_scene_check(PT_MIS, 3, 0, RR_FIXED, PT_SAMPLER_RANDOM, 251 + 2 * (uint64_t)t);
        path_tracer_wide_twin(WIDE_TWIN_NONE);
        print_message("twin, MIS rung, %s: p = %.3g (image mean z = %.1f)\n", twins[t].name, c.p, c.z);
        assert_true(c.p < image_check_alpha(RUNG_SCENE_CHECKS));
    }
}

/* The same image, bit for bit, on 1 and 2 threads and with the lanes'
 * arithmetic in AVX or lane by lane, on the scenes above, on every rung,
 * with either sampler; and with the walls off (walls.h: exact). */
static void test_eight_paths_same_bits_for_threads_on_every_scene(void **state)
{
    (void)state;
    for (int rung = 0; rung < 3; rung++)
    for (int scene = 0; scene < 3; scene++)
        for (int sampler = 0; sampler < 2; sampler++) {
            pt_scene sc;
            build_every_scene(&sc, scene, 0);
            use_production(&sc, true);
            camera cam = pt_scene_camera(&sc, 20, 20);
            path_tracer pt = tracer(&sc, (pt_integrator)rung, sampler ? RR_THROUGHPUT : RR_FIXED);
            pt.sampler = (pt_sampler)sampler;
            estimate_image one, two, lanes;
            assert_true(render_estimate_wide(&pt, &cam, 4, test_seed(97), 1, &one));
            assert_true(render_estimate_wide(&pt, &cam, 4, test_seed(97), 2, &two));
            assert_memory_equal(one.mean.rgb, two.mean.rgb, sizeof(float) * 3 * 20 * 20);
            assert_memory_equal(one.standard_error.rgb, two.standard_error.rgb, sizeof(float) * 3 * 20 * 20);
            assert_true(counters_total_rays(&one.counters) == counters_total_rays(&two.counters));
            path_tracer_wide_use_avx(false); /* the lanes' arithmetic one lane at a time: the same bits */
            assert_true(render_estimate_wide(&pt, &cam, 4, test_seed(97), 2, &lanes));
            path_tracer_wide_use_avx(true);
            assert_memory_equal(one.mean.rgb, lanes.mean.rgb, sizeof(float) * 3 * 20 * 20);
            estimate_image_free(&lanes);
            /* the walls answer every shadow ray as all the triangles would:
             * without them, the same image */
            assert_true(walls_found(sc.bvh));
            use_production(&sc, false);
            estimate_image no_walls;
            assert_true(render_estimate_wide(&pt, &cam, 4, test_seed(97), 2, &no_walls));
            assert_null(wide_scene_tracers_for(&sc).walls);
            assert_memory_equal(one.mean.rgb, no_walls.mean.rgb, sizeof(float) * 3 * 20 * 20);
            estimate_image_free(&no_walls);
            estimate_image_free(&one);
            estimate_image_free(&two);
            pt_scene_free(&sc);
        }
}

/* ---- spawn_avx.h: ray.h's offsets, eight lanes at a time -----------------
 * spawn_point_error8(), ray_spawn8() and ray_spawn_to8() against
 * ray_point_error(), ray_spawn() and ray_spawn_to(), bit for bit, on points
 * whose coordinates are hard cases for the arithmetic: exactly 0 and -0,
 * tiny and huge, of either sign; primitive sizes from 0 to 1e6; normals
 * facing either way. The twin is a reference that forgets to pull the
 * shadow ray's far end off the light: the same comparison must see it. */
#if SPAWN_HAVE_AVX2
/* Coordinates the offsets must get right (inputs, not tolerances): zero of
 * both signs, where the point's own rounding vanishes; tiny and unit values
 * of each sign; the Cornell box's middle and its ceiling's height; 1e5,
 * whose float step is 2^-7; and 5e6, whose step is 0.5. */
static const float SPAWN_HARD_COORDINATES[] = {0.0f,   -0.0f, 1e-7f,  -1e-7f,  1e-3f, -1e-3f, 1.0f,  -1.0f,
                                               278.0f, -278.0f, 548.8f, 1e5f, -1e5f, 5e6f,  -5e6f};
enum { SPAWN_HARD_COUNT = sizeof SPAWN_HARD_COORDINATES / sizeof SPAWN_HARD_COORDINATES[0] };
/* Primitive sizes: none (an infinite plane's point), a 1e-7 object, a unit
 * one, the Cornell box's walls, a million. */
static const float SPAWN_SIZES[] = {0.0f, 1e-7f, 1.0f, 559.2f, 1e6f};

/* One of the hard coordinates three times in four, else anywhere in the
 * Cornell box's span around 0. */
static float hard_coordinate(pcg32 *rng)
{
    uint32_t pick = pcg32_next(rng) % 20;
    if (pick < SPAWN_HARD_COUNT)
        return SPAWN_HARD_COORDINATES[pick];
    return (pcg32_float(rng) - 0.5f) * 1200.0f;
}

static vec3 hard_point(pcg32 *rng) { return vec3_make(hard_coordinate(rng), hard_coordinate(rng), hard_coordinate(rng)); }

static vec3 random_direction(pcg32 *rng)
{
    return sample_uniform_sphere(vec2_make(pcg32_float(rng), pcg32_float(rng)));
}

static float hard_size(pcg32 *rng)
{
    return SPAWN_SIZES[pcg32_bounded(rng, sizeof SPAWN_SIZES / sizeof SPAWN_SIZES[0])];
}

static bool same_bits(vec3 a, vec3 b) { return memcmp(&a, &b, sizeof a) == 0; }

static ray spawn_to_without_far_end(vec3 point, float point_error, vec3 n, vec3 target, float target_error,
                                    vec3 target_normal)
{
    (void)target_error;
    ray r = ray_spawn_to(point, point_error, n, target, 0.0f, vec3_splat(0.0f));
    r.t_max = ray_spawn_to(point, point_error, n, target, target_error, target_normal).t_max;
    return r;
}

typedef ray (*spawn_to_fn)(vec3 point, float point_error, vec3 n, vec3 target, float target_error,
                           vec3 target_normal);

/* Rays whose error bound, spawned origin or shadow ray differs from the
 * reference's in any bit, of `batches` batches of eight. */
SPAWN_TARGET static long spawns_apart(spawn_to_fn reference, int batches, uint64_t seed)
{
    pcg32 rng = pcg32_for_pixel(seed, 0);
    long apart = 0;
    for (int b = 0; b < batches; b++) {
        _Alignas(32) float in[5][3][8], sizes[2][8];
        vec3 v[5][8];
        for (int k = 0; k < 8; k++) {
            v[0][k] = hard_point(&rng);       /* point */
            v[1][k] = random_direction(&rng); /* its normal */
            v[2][k] = random_direction(&rng); /* a direction to leave in */
            v[3][k] = hard_point(&rng);       /* a target */
            v[4][k] = random_direction(&rng); /* its normal */
            for (int a = 0; a < 5; a++) {
                in[a][0][k] = v[a][k].x;
                in[a][1][k] = v[a][k].y;
                in[a][2][k] = v[a][k].z;
            }
            sizes[0][k] = hard_size(&rng);
            sizes[1][k] = hard_size(&rng);
        }
        __m256 m[5][3], origin[3], shadow_origin[3], shadow_direction[3], t_min, shadow_t_min, shadow_t_max;
        for (int a = 0; a < 5; a++)
            for (int c = 0; c < 3; c++)
                m[a][c] = _mm256_load_ps(in[a][c]);
        __m256 error = spawn_point_error8(m[0], m[1], _mm256_load_ps(sizes[0]));
        __m256 target_error = spawn_point_error8(m[3], m[4], _mm256_load_ps(sizes[1]));
        ray_spawn8(m[0], error, m[1], m[2], origin, &t_min);
        ray_spawn_to8(m[0], error, m[1], m[3], target_error, m[4], shadow_origin, shadow_direction, &shadow_t_min,
                      &shadow_t_max);
        _Alignas(32) float out[3][3][8], errors[2][8], ts[3][8];
        for (int c = 0; c < 3; c++) {
            _mm256_store_ps(out[0][c], origin[c]);
            _mm256_store_ps(out[1][c], shadow_origin[c]);
            _mm256_store_ps(out[2][c], shadow_direction[c]);
        }
        _mm256_store_ps(errors[0], error);
        _mm256_store_ps(errors[1], target_error);
        _mm256_store_ps(ts[0], t_min);
        _mm256_store_ps(ts[1], shadow_t_min);
        _mm256_store_ps(ts[2], shadow_t_max);
        for (int k = 0; k < 8; k++) {
            float e = ray_point_error(v[0][k], v[1][k], sizes[0][k]);
            float e_target = ray_point_error(v[3][k], v[4][k], sizes[1][k]);
            ray spawned = ray_spawn(v[0][k], e, v[1][k], v[2][k]);
            ray shadow = reference(v[0][k], e, v[1][k], v[3][k], e_target, v[4][k]);
            float t[3] = {spawned.t_min, shadow.t_min, shadow.t_max}, t_lanes[3] = {ts[0][k], ts[1][k], ts[2][k]};
            bool same = memcmp(&e, &errors[0][k], sizeof e) == 0 && memcmp(&e_target, &errors[1][k], sizeof e) == 0 &&
                        memcmp(t, t_lanes, sizeof t) == 0 &&
                        same_bits(spawned.origin, vec3_make(out[0][0][k], out[0][1][k], out[0][2][k])) &&
                        same_bits(shadow.origin, vec3_make(out[1][0][k], out[1][1][k], out[1][2][k])) &&
                        same_bits(shadow.direction, vec3_make(out[2][0][k], out[2][1][k], out[2][2][k]));
            apart += !same;
        }
    }
    _mm256_zeroupper();
    return apart;
}
#endif

static void test_spawn_avx_is_ray_h_bit_for_bit(void **state)
{
    (void)state;
#if SPAWN_HAVE_AVX2
    if (!__builtin_cpu_supports("avx2")) {
        print_message("no AVX2 here: the vector code never runs, so nothing to compare\n");
        skip();
    }
    enum { BATCHES = 20000 };
    long apart = spawns_apart(ray_spawn_to, BATCHES, test_seed(93));
    print_message("spawn_avx.h: %ld of %d rays differ from ray.h's in any bit\n", apart, 8 * BATCHES);
    assert_int_equal(apart, 0);
    long twin = spawns_apart(spawn_to_without_far_end, BATCHES, test_seed(93));
    print_message("twin (the far end not pulled off the light): %ld of %d differ\n", twin, 8 * BATCHES);
    assert_true(twin > 8 * BATCHES / 2);
#else
    print_message("not an x86-64 build: the vector code is not compiled, so nothing to compare\n");
    skip();
#endif
}


/* ---- sin and cos of an angle in turns ----------------------------------------
 * fast_sincos_turns(u) against sin and cos of 2 pi u in double: within
 * FAST_SINCOS_TURNS_ULPS units in the last place (the fit's 2.1, measured
 * over every float in [0, 1), plus rounding headroom), on every 101st float
 * in [0, 1], and exactly 0 and +-1 at the quarter turns. The twin negates
 * the cosine in the third quarter and must fail the same check. */
enum { FAST_SINCOS_TURNS_ULPS = 3 };

typedef void (*sincos_fn)(float u, float *s, float *c);

static void sincos_quarter_two_wrong(float u, float *s, float *c)
{
    fast_sincos_turns(u, s, c);
    if (u > 0.375f && u < 0.625f)
        *c = -*c;
}

/* in units of the float spacing at the exact value */
static double ulps_from(float got, double exact)
{
    double spacing = nextafterf(fabsf((float)exact), INFINITY) - fabsf((float)exact);
    return fabs((double)got - exact) / spacing;
}

/* The largest error in ulps over the floats checked; 1e30 for a wrong
 * quarter turn. */
static double sincos_worst_ulps(sincos_fn f)
{
    double worst = 0.0;
    for (uint32_t bits = 0; bits <= 0x3f800000u; bits += 101) {
        float u;
        memcpy(&u, &bits, sizeof u);
        float s, c;
        f(u, &s, &c);
        double turns = 4.0 * u;
        if (turns == floor(turns)) { /* a quarter turn: exact values */
            int q = (int)turns;
            float want_s = q == 1 ? 1.0f : q == 3 ? -1.0f : 0.0f;
            float want_c = q == 0 || q == 4 ? 1.0f : q == 2 ? -1.0f : 0.0f;
            if (s != want_s || c != want_c)
                return 1e30;
            continue;
        }
        worst = fmax(worst, fmax(ulps_from(s, sin(2.0 * PI * u)), ulps_from(c, cos(2.0 * PI * u))));
    }
    return worst;
}

/* ==== leaks: rays through the shared edges and vertices of closed meshes ====
 * The system-level watertightness test (docs/hard-cases.md, section 1): closed
 * meshes -- jittered icospheres of 20 to 5120 triangles, a jittered torus of
 * 64, and a jittered torus of 2304 written as an OBJ file of quads and loaded
 * back through mesh_load_obj() -- each at scales 1e-4 to 1e4 and offset from
 * the origin by up to 3000 of its sizes (at most 1e5: a mesh of size 1e-4
 * at 1e5 would be one float point), with rays from outside aimed at float
 * points of shared edges and at vertices (tests/leak_check.h). Every ray
 * crosses the surface at its target, so each entry point must report a
 * triangle there or before it: every accelerator's closest and any hit, the
 * lecture's recursive BVH traversal, the 4-wide BVH's streams, the flat set's
 * eight-ray packets, and what the renderers call: chapter 01's scene,
 * chapter 09's scene on each --accel structure and on chapter 13's, the
 * eight-path renderer's packet calls, chapter 10's moving mesh. For the
 * renderers the first hit must also be a front face: a camera inside
 * nothing sees the outside of every closed mesh. The watertight test leaks
 * nowhere; its twin, every switchable entry point on Moller-Trumbore,
 * leaks everywhere, and reports how often. */

/* What one entry point saw, over every case: rays, and the rays that leaked. */
enum { LEAK_ENTRIES_MAX = 96, LEAK_NAME_SIZE = 72 };
typedef struct {
    char name[LEAK_ENTRIES_MAX][LEAK_NAME_SIZE];
    long rays[LEAK_ENTRIES_MAX], leaks[LEAK_ENTRIES_MAX];
    bool switchable[LEAK_ENTRIES_MAX]; /* runs Moller-Trumbore when asked (the twin's entry points) */
    int count;
} leak_tally;

static void leak_add(leak_tally *t, const char *name, bool switchable, long rays, long leaks)
{
    int e = 0;
    while (e < t->count && strcmp(t->name[e], name) != 0)
        e++;
    if (e == t->count) {
        assert_true(t->count < LEAK_ENTRIES_MAX);
        snprintf(t->name[e], LEAK_NAME_SIZE, "%s", name);
        t->count++;
    }
    t->switchable[e] = switchable;
    t->rays[e] += rays;
    t->leaks[e] += leaks;
}

/* The rays of one case, and the test the switchable entry points run. */
typedef struct {
    const mesh *m;
    const ray *rays;
    int n;
    triangle_test test;
} leak_case;

/* A renderer's first hit: a triangle at the target or before, its front. */
static bool leak_front_ok(bool found, const hit_record *hit) { return leak_closest_ok(found, hit) && hit->front_face; }

/* Closest and any hit through an accel_ops structure. */
static void leak_through_accel(leak_tally *t, const char *name, const accel *a, const leak_case *c)
{
    long closest = 0, any = 0;
    ray_counters counters = {0};
    for (int i = 0; i < c->n; i++) {
        hit_record hit;
        closest += !leak_closest_ok(accel_closest_hit(a, c->rays[i], &hit, &counters), &hit);
        any += !accel_any_hit(a, leak_segment(c->rays[i]), &counters);
    }
    char entry[LEAK_NAME_SIZE];
    snprintf(entry, sizeof entry, "%.40s: closest hit", name);
    leak_add(t, entry, true, c->n, closest);
    snprintf(entry, sizeof entry, "%.40s: any hit", name);
    leak_add(t, entry, true, c->n, any);
}

/* The 4-wide BVH's streams (wide_bvh_closest_hit_stream, wide_bvh_any_hit_stream). */
static void leak_through_streams(leak_tally *t, const char *name, const accel *a, const leak_case *c)
{
    hit_record *hits = calloc((size_t)c->n, sizeof *hits);
    bool *found = calloc((size_t)c->n, sizeof *found);
    ray *segments = calloc((size_t)c->n, sizeof *segments);
    ray_counters counters = {0};
    long closest = 0, any = 0;
    wide_bvh_closest_hit_stream(a, c->rays, c->n, hits, found, &counters);
    for (int i = 0; i < c->n; i++) {
        closest += !leak_closest_ok(found[i], &hits[i]);
        segments[i] = leak_segment(c->rays[i]);
    }
    wide_bvh_any_hit_stream(a, segments, c->n, found, &counters);
    for (int i = 0; i < c->n; i++)
        any += !found[i];
    char entry[LEAK_NAME_SIZE];
    snprintf(entry, sizeof entry, "%.40s stream: closest hit", name);
    leak_add(t, entry, true, c->n, closest);
    snprintf(entry, sizeof entry, "%.40s stream: any hit", name);
    leak_add(t, entry, true, c->n, any);
    free(hits);
    free(found);
    free(segments);
}

/* The flat set's eight-ray packets (flat_closest_hit8, flat_any_hit8). */
static void leak_through_packets(leak_tally *t, const char *name, const accel *a, const leak_case *c)
{
    long closest = 0, any = 0;
    ray_counters counters = {0};
    for (int i = 0; i < c->n; i += FLAT_LANES) {
        int lanes = c->n - i < FLAT_LANES ? c->n - i : FLAT_LANES, active = (1 << lanes) - 1;
        ray rays[FLAT_LANES], segments[FLAT_LANES];
        hit_record hits[FLAT_LANES];
        bool found[FLAT_LANES] = {false}, blocked[FLAT_LANES] = {false};
        for (int k = 0; k < lanes; k++) {
            rays[k] = c->rays[i + k];
            segments[k] = leak_segment(rays[k]);
        }
        flat_closest_hit8(a, rays, active, hits, found, &counters);
        flat_any_hit8(a, segments, active, blocked, &counters);
        for (int k = 0; k < lanes; k++) {
            closest += !leak_closest_ok(found[k], &hits[k]);
            any += !blocked[k];
        }
    }
    char entry[LEAK_NAME_SIZE];
    snprintf(entry, sizeof entry, "%.40s packets: closest hit", name);
    leak_add(t, entry, true, c->n, closest);
    snprintf(entry, sizeof entry, "%.40s packets: any hit", name);
    leak_add(t, entry, true, c->n, any);
}

/* Chapter 09's scene (pt_scene_intersect, pt_scene_occluded) on its
 * current structure, switched to the case's test. */
static void leak_through_pt_scene(leak_tally *t, const char *name, pt_scene *sc, const leak_case *c)
{
    assert_true(accel_use_triangle_test(sc->bvh, c->test));
    long closest = 0, any = 0;
    ray_counters counters = {0};
    for (int i = 0; i < c->n; i++) {
        hit_record hit;
        closest += !leak_front_ok(pt_scene_intersect(sc, c->rays[i], &hit, &counters), &hit);
        any += !pt_scene_occluded(sc, leak_segment(c->rays[i]), &counters);
    }
    char entry[LEAK_NAME_SIZE];
    snprintf(entry, sizeof entry, "%.40s: first hit a front face", name);
    leak_add(t, entry, true, c->n, closest);
    snprintf(entry, sizeof entry, "%.40s: shadow ray blocked", name);
    leak_add(t, entry, true, c->n, any);
}

/* The eight-path renderer's two calls (path_tracer_wide.c, through
 * wide_trace.h): the closest hits of eight rays on the scene's flat set or
 * 4-wide BVH, made into hit records as its hit_record_lane() does, and
 * eight shadow rays (no walls in a closed mesh seen from outside: every
 * one goes to all the triangles). */
static void leak_through_tracer(leak_tally *t, const char *name, const pt_scene *sc, const wide_tracer *all,
                                const leak_case *c)
{
    long closest = 0, any = 0;
    ray_counters counters = {0};
    for (int i = 0; i < c->n; i += FLAT_LANES) {
        int lanes = c->n - i < FLAT_LANES ? c->n - i : FLAT_LANES, active = (1 << lanes) - 1;
        rays8 rays = {0}, segments = {0};
        for (int k = 0; k < lanes; k++) {
            rays8_set(&rays, k, c->rays[i + k]);
            rays8_set(&segments, k, leak_segment(c->rays[i + k]));
        }
        hits8 hits;
        int hit = all->closest_hit8(all->context, &rays, active, &hits, &counters);
        int blocked = all->any_hit8(all->context, &segments, active, &counters);
        for (int k = 0; k < lanes; k++) {
            hit_record record;
            bool found = (hit >> k) & 1;
            if (found)
                triangle_set_fill_hit(&sc->triangles, hits.index[k], c->rays[i + k], hits.t[k], hits.b1[k],
                                      hits.b2[k], &record);
            closest += !leak_front_ok(found, &record);
            any += !((blocked >> k) & 1);
        }
    }
    char entry[LEAK_NAME_SIZE];
    snprintf(entry, sizeof entry, "ch13 eight paths, %.24s: first hit a front face", name);
    leak_add(t, entry, true, c->n, closest);
    snprintf(entry, sizeof entry, "ch13 eight paths, %.24s: shadow ray blocked", name);
    leak_add(t, entry, true, c->n, any);
}

/* The renderer's trace step (wide_trace.h): the flat set's kernels or the
 * 4-wide BVH's walks, whichever the scene's size picks, and the BVH's
 * streams, which it may be asked for. */
static void leak_through_eight_paths(leak_tally *t, const pt_scene *sc, const leak_case *c)
{
    wide_scene_tracers trace = wide_scene_tracers_for(sc);
    assert_false(walls_found(sc->bvh));
    assert_null(trace.walls);
    const accel *all = walls_all(sc->bvh);
    leak_through_tracer(t, flat_is(all) ? "flat set" : WIDE_BVH_NAME, sc, &trace.all, c);
    if (wide_bvh_is(all)) {
        wide_tracer streams = wide_tracer_streams(all);
        leak_through_tracer(t, "4-wide BVH streams", sc, &streams, c);
    }
}

/* Every entry point on one case. */
static void leak_trace_case(const leak_case *c, leak_tally *t)
{
    triangle_set set;
    triangle_set_from_mesh(&set, c->m);
    /* the structures, each switched to the case's test */
    enum { STRUCTURES = 16 };
    struct {
        char name[48];
        accel *a;
    } s[STRUCTURES];
    int n = 0;
    snprintf(s[n].name, sizeof s[n].name, "ch03 brute force"), s[n++].a = brute_force_build(&set);
    snprintf(s[n].name, sizeof s[n].name, "ch04 grid"), s[n++].a = grid_build(&set, GRID_DEFAULT_DENSITY);
    snprintf(s[n].name, sizeof s[n].name, "ch05 kd-tree"), s[n++].a = kdtree_build(&set);
    snprintf(s[n].name, sizeof s[n].name, "ch06 bvh sah"), s[n++].a = bvh_build(&set, BVH_SPLIT_SAH);
    const int bvh_sah = n - 1;
    snprintf(s[n].name, sizeof s[n].name, "ch06 bvh sah, distance order"), s[n].a = bvh_build(&set, BVH_SPLIT_SAH);
    bvh_set_order(s[n++].a, BVH_ORDER_DISTANCE);
    snprintf(s[n].name, sizeof s[n].name, "ch06 bvh median"), s[n++].a = bvh_build(&set, BVH_SPLIT_MEDIAN);
    /* the wide BVH in every kernel, with exact and with quantized nodes */
    const int wide_bvh_first = n;
    const char *kernel_names_wide[] = {"scalar", "sse", "avx"};
    for (int layout = 0; layout < 2; layout++)
        for (int k = 0; k < WIDE_BVH_KERNELS; k++) {
            accel *a = wide_bvh_build_layout(&set, BVH_SPLIT_SAH, (wide_bvh_layout)layout);
            if (!wide_bvh_set_kernel(a, wide_bvh_kernels[k])) {
                accel_destroy(a);
                continue;
            }
            snprintf(s[n].name, sizeof s[n].name, "ch13 wide bvh%s (%s)", layout ? " quantized" : "",
                     kernel_names_wide[k]);
            s[n++].a = a;
        }
    const int flat_first = n;
    const flat_kernel kernels[] = {FLAT_KERNEL_AVX512, FLAT_KERNEL_AVX, FLAT_KERNEL_SSE, FLAT_KERNEL_SCALAR};
    const char *kernel_names[] = {"avx-512 registers", "avx", "sse", "scalar"};
    for (int k = 0; k < 4; k++)
        if (flat_kernel_runs(kernels[k])) {
            snprintf(s[n].name, sizeof s[n].name, "ch13 flat (%s)", kernel_names[k]);
            s[n].a = flat_build(&set);
            assert_true(flat_set_kernel(s[n++].a, kernels[k]));
        }
    for (int k = 0; k < n; k++) {
        assert_true(accel_use_triangle_test(s[k].a, c->test));
        leak_through_accel(t, s[k].name, s[k].a, c);
        if (k >= wide_bvh_first && k < flat_first)
            leak_through_streams(t, s[k].name, s[k].a, c);
        if (k >= flat_first)
            leak_through_packets(t, s[k].name, s[k].a, c);
    }
    long recursive = 0;
    for (int i = 0; i < c->n; i++) {
        hit_record hit;
        ray_counters counters = {0};
        recursive += !leak_closest_ok(bvh_closest_hit_recursive((const bvh *)s[bvh_sah].a, c->rays[i], &hit, &counters),
                                      &hit);
    }
    leak_add(t, "ch06 bvh sah, the lecture's recursion: closest hit", true, c->n, recursive);
    for (int k = 0; k < n; k++)
        accel_destroy(s[k].a);
    triangle_set_free(&set);

    /* The renderers. Chapter 09's scene (so chapters 10-12's, which trace
     * through it), on each --accel structure and on chapter 13's. */
    pt_scene sc;
    pt_scene_init(&sc);
    int material = pt_scene_add_material(&sc, pt_diffuse(vec3_splat(0.5f)));
    for (int f = 0; f < c->m->face_count; f++)
        pt_scene_add_triangle(&sc, mesh_vertex(c->m, f, 0), mesh_vertex(c->m, f, 1), mesh_vertex(c->m, f, 2), material);
    pt_scene_finish(&sc);
    for (int k = 0; PT_ACCEL_NAMES[k] != NULL; k++) {
        char entry[LEAK_NAME_SIZE];
        snprintf(entry, sizeof entry, "ch09 scene, --accel %s", PT_ACCEL_NAMES[k]);
        pt_scene_use_accel(&sc, pt_accel_builder_named(PT_ACCEL_NAMES[k]), NULL);
        leak_through_pt_scene(t, entry, &sc, c);
    }
    pt_scene_use_accel(&sc, production_scene_accel, &sc);
    leak_through_pt_scene(t, "ch13 scene, production structure", &sc, c);
    leak_through_eight_paths(t, &sc, c); /* the flat set (at most 64 triangles) or the 4-wide BVH's streams */
    pt_scene_free(&sc);

    /* Chapter 10's moving mesh (through chapter 06's BVH, the ray moved into
     * the mesh's frame), here at rest. */
    motion_scene ms;
    motion_scene_init(&ms);
    pt_scene_finish(&ms.base);
    mesh copy;
    mesh_init(&copy);
    for (int i = 0; i < c->m->position_count; i++)
        mesh_add_position(&copy, c->m->positions[i]);
    for (int f = 0; f < c->m->face_count; f++)
        mesh_add_triangle(&copy, c->m->faces[f].position[0], c->m->faces[f].position[1], c->m->faces[f].position[2],
                          -1);
    motion_scene_add_mesh(&ms, &copy, vec3_splat(0.0f));
    assert_true(accel_use_triangle_test(ms.meshes[0]->bvh, c->test));
    long moving = 0, moving_any = 0;
    for (int i = 0; i < c->n; i++) {
        hit_record hit;
        ray_counters counters = {0};
        moving += !leak_front_ok(motion_scene_intersect(&ms, (timed_ray){c->rays[i], 0.5f}, &hit, &counters), &hit);
        moving_any += !motion_scene_occluded(&ms, (timed_ray){leak_segment(c->rays[i]), 0.5f}, &counters);
    }
    leak_add(t, "ch10 moving mesh: first hit a front face", true, c->n, moving);
    leak_add(t, "ch10 moving mesh: shadow ray blocked", true, c->n, moving_any);
    motion_scene_free(&ms);

    /* Chapter 01's scene of shapes (chapter 02 renders it too): the
     * watertight test, with no other to switch to. */
    if (c->test == TRIANGLE_TEST_WATERTIGHT) {
        scene s01;
        scene_init(&s01);
        int m01 = scene_add_material(&s01, material_blinn_phong(vec3_splat(0.5f), vec3_splat(0.0f), 1.0f));
        for (int f = 0; f < c->m->face_count; f++)
            scene_add_triangle(&s01, mesh_vertex(c->m, f, 0), mesh_vertex(c->m, f, 1), mesh_vertex(c->m, f, 2), m01);
        long closest = 0, any = 0;
        for (int i = 0; i < c->n; i++) {
            hit_record hit;
            ray_counters counters = {0};
            closest += !leak_front_ok(scene_intersect(&s01, c->rays[i], &hit, &counters), &hit);
            any += !scene_occluded(&s01, leak_segment(c->rays[i]), &counters);
        }
        leak_add(t, "ch01 scene: first hit a front face", false, c->n, closest);
        leak_add(t, "ch01 scene: shadow ray blocked", false, c->n, any);
        scene_free(&s01);
    }
}

/* The 2304-triangle torus as an OBJ file of 48 x 24 quads, read back by
 * mesh_load_obj() (which splits each quad into two triangles). */
static void leak_mesh_from_obj(mesh *m, pcg32 *rng)
{
    enum { U = 48, V = 24 };
    mesh generated;
    leak_mesh_jittered_torus(&generated, 0.35f, U, V, rng);
    char dir[] = "/tmp/leak_obj.XXXXXX";
    assert_non_null(mkdtemp(dir));
    char path[64];
    snprintf(path, sizeof path, "%s/torus.obj", dir);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    for (int i = 0; i < generated.position_count; i++) /* %.9g: every float reads back as itself */
        fprintf(f, "v %.9g %.9g %.9g\n", (double)generated.positions[i].x, (double)generated.positions[i].y,
                (double)generated.positions[i].z);
    for (int i = 0; i < U; i++) /* mesh_torus's grid, as quads (1-based) */
        for (int j = 0; j < V; j++)
            fprintf(f, "f %d %d %d %d\n", 1 + i * V + j, 1 + ((i + 1) % U) * V + j, 1 + ((i + 1) % U) * V + (j + 1) % V,
                    1 + i * V + (j + 1) % V);
    assert_int_equal(fclose(f), 0);
    mesh_init(m);
    char err[MESH_ERROR_SIZE];
    if (!mesh_load_obj(m, path, err, sizeof err))
        fail_msg("%s", err);
    assert_int_equal(m->face_count, 2 * U * V);
    unlink(path);
    rmdir(dir);
    mesh_free(&generated);
}

/* The meshes, scales and offsets of the cases (see the section's comment). */
enum { LEAK_MESHES = 7, LEAK_SCALES = 5, LEAK_OFFSETS = 3 };
static const float leak_scales[LEAK_SCALES] = {1e-4f, 1e-2f, 1.0f, 1e2f, 1e4f};
/* Offsets in units of the mesh's size, each at most LEAK_OFFSET_MAX away. */
static const float leak_offset_sizes[LEAK_OFFSETS] = {0.0f, 30.0f, 3000.0f};
static const float LEAK_OFFSET_MAX = 1e5f;

static void leak_mesh_make(mesh *m, int which, pcg32 *rng)
{
    if (which < 5) /* 20, 80, 320, 1280, 5120 triangles */
        leak_mesh_jittered_icosphere(m, which, rng);
    else if (which == 5) /* 64 triangles: the eight-path renderer's flat set */
        leak_mesh_jittered_torus(m, 0.4f, 8, 4, rng);
    else
        leak_mesh_from_obj(m, rng);
}

/* Every case with rays_per_case rays, every entry point, one test. */
static void leak_run(triangle_test test, int rays_per_case, leak_tally *t)
{
    ray *rays = calloc((size_t)rays_per_case, sizeof *rays);
    for (int which = 0; which < LEAK_MESHES; which++) {
        pcg32 rng = pcg32_for_pixel(test_seed(2013), (uint64_t)which);
        mesh unit;
        leak_mesh_make(&unit, which, &rng);
        for (int s = 0; s < LEAK_SCALES; s++)
            for (int o = 0; o < LEAK_OFFSETS; o++) {
                mesh m;
                mesh_init(&m);
                for (int i = 0; i < unit.position_count; i++)
                    mesh_add_position(&m, unit.positions[i]);
                for (int f = 0; f < unit.face_count; f++)
                    mesh_add_triangle(&m, unit.faces[f].position[0], unit.faces[f].position[1],
                                      unit.faces[f].position[2], -1);
                float offset = fminf(LEAK_OFFSET_MAX, leak_offset_sizes[o] * leak_scales[s]);
                leak_mesh_transform(&m, leak_scales[s], vec3_scale(leak_random_unit(&rng), offset));
                int n = leak_rays_make(&m, rays_per_case, &rng, rays);
                assert_int_equal(n, rays_per_case);
                leak_case c = {&m, rays, n, test};
                leak_trace_case(&c, t);
                mesh_free(&m);
            }
        mesh_free(&unit);
    }
    free(rays);
}

/* make test: LEAK_RAYS rays through each entry point (about 50,000: 480
 * per case); make test-seeds runs it over 200 other seeds, 10^7 rays per
 * entry point. The twin needs few: Moller-Trumbore leaks a few percent. */
enum { LEAK_RAYS_PER_CASE = 480, LEAK_TWIN_RAYS_PER_CASE = 48 };

static void test_no_ray_leaks_through_a_closed_mesh_anywhere(void **state)
{
    (void)state;
    leak_tally t = {0};
    leak_run(TRIANGLE_TEST_WATERTIGHT, LEAK_RAYS_PER_CASE, &t);
    long total = 0;
    for (int e = 0; e < t.count; e++) {
        if (t.leaks[e] != 0)
            print_message("LEAK %s: %ld of %ld rays\n", t.name[e], t.leaks[e], t.rays[e]);
        total += t.leaks[e];
    }
    print_message("watertight: %d entry points, %ld rays each (%d meshes x %d scales x %d offsets), %ld leaks\n",
                  t.count, t.rays[0], LEAK_MESHES, LEAK_SCALES, LEAK_OFFSETS, total);
    assert_int_equal(total, 0);
}

/* The twin: the same cases with every switchable entry point on
 * Moller-Trumbore. Each must leak, and the rate is reported. */
static void test_moller_trumbore_leaks_through_every_entry_point(void **state)
{
    (void)state;
    leak_tally t = {0};
    leak_run(TRIANGLE_TEST_MOLLER_TRUMBORE, LEAK_TWIN_RAYS_PER_CASE, &t);
    int quiet = 0;
    for (int e = 0; e < t.count; e++) {
        if (!t.switchable[e])
            continue;
        print_message("Moller-Trumbore, %s: %ld of %ld rays leak (%.2f %%)\n", t.name[e], t.leaks[e], t.rays[e],
                      100.0 * (double)t.leaks[e] / (double)t.rays[e]);
        quiet += t.leaks[e] == 0;
    }
    assert_int_equal(quiet, 0);
}

/* ---- quantized nodes (wide_bvh_qnode) -------------------------------------------- */

/* One parent's children for the quantization tests, of a kind that has
 * broken quantizers: random boxes at sizes from 1e-30 to 1e30, far from
 * the origin relative to their size (1e7 with size 1e-3, where a float's
 * step is 1), flat and zero-size ones, children equal to each other or to
 * the parent, boxes reaching +-3e38, planes at -0 and +0, and sizes
 * below the smallest normal float. Returns the number of children. */
static int quantize_case(wide_bvh_node *node, int kind, pcg32 *rng)
{
    memset(node, 0, sizeof *node);
    int children = 1 + (int)pcg32_bounded(rng, WIDE_BVH_WIDTH);
    static const float sizes[] = {1e-30f, 1e-20f, 1e-3f, 1.0f, 1e3f, 1e20f, 1e30f, 1e-40f};
    float size = sizes[pcg32_bounded(rng, sizeof sizes / sizeof sizes[0])];
    float offset = 0.0f;
    /* far out: at FAR_OFFSET a float's step is 1, a thousand times
     * FAR_SIZE, so the box's planes are a float or two apart */
    const float FAR_OFFSET = 1e7f, FAR_SIZE = 1e-3f;
    if (kind % 4 == 1)
        offset = FAR_OFFSET, size = FAR_SIZE;
    else if (kind % 4 == 2)
        offset = size * powf(10.0f, 8.0f * pcg32_float(rng)); /* far relative to its size */
    float sign = pcg32_bounded(rng, 2) ? -1.0f : 1.0f;
    for (int k = 0; k < children; k++) {
        for (int axis = 0; axis < 3; axis++) {
            float lo = sign * offset + size * (2.0f * pcg32_float(rng) - 1.0f);
            float hi = lo + size * pcg32_float(rng);
            if (kind % 4 == 3) { /* +-3e38, or planes at -0 and +0 */
                lo = pcg32_bounded(rng, 2) ? -3e38f * pcg32_float(rng) : -0.0f;
                hi = pcg32_bounded(rng, 2) ? 3e38f * pcg32_float(rng) : 0.0f;
            }
            uint32_t shape = pcg32_bounded(rng, 6);
            if (shape == 0 || (shape == 1 && axis == 1))
                hi = lo; /* a point, or flat in y */
            node->bounds[axis][k] = lo;
            node->bounds[axis + 3][k] = hi;
        }
        if (k > 0 && pcg32_bounded(rng, 5) == 0) /* the same box as the one before */
            for (int p = 0; p < 6; p++)
                node->bounds[p][k] = node->bounds[p][k - 1];
        node->child[k] = (uint32_t)k;
    }
    for (int k = children; k < WIDE_BVH_WIDTH; k++) {
        for (int axis = 0; axis < 3; axis++) {
            node->bounds[axis][k] = INFINITY;
            node->bounds[axis + 3][k] = -INFINITY;
        }
        node->child[k] = WIDE_BVH_EMPTY;
    }
    node->children = (uint32_t)children;
    return children;
}

/* How many children of the cases' quantized nodes do not contain their
 * exact box, or have a NaN plane, with planes rounded `rounding`; and the
 * mean share of the parent's extent that quantizing added to a child's
 * (outward: at most 2 steps of 2^e, each below 1/127 of the extent). */
static long quantize_failures(wide_bvh_rounding rounding, int trials, double *growth)
{
    pcg32 rng = pcg32_for_pixel(2017, (uint64_t)rounding);
    long failures = 0, measured = 0;
    double grown = 0.0;
    for (int i = 0; i < trials; i++) {
        wide_bvh_node exact;
        int children = quantize_case(&exact, i, &rng);
        wide_bvh_qnode q;
        assert_true(wide_bvh_quantize_node(&exact, rounding, &q));
        assert_int_equal(q.children, children);
        for (int k = 0; k < WIDE_BVH_WIDTH; k++) {
            assert_int_equal(q.child[k], exact.child[k]);
            if (k >= children) { /* empty: lo above hi on every axis */
                for (int axis = 0; axis < 3; axis++)
                    assert_true(q.bounds[axis][k] == 255 && q.bounds[axis + 3][k] == 0);
                continue;
            }
            aabb box = wide_bvh_qnode_box(&q, k);
            for (int axis = 0; axis < 3; axis++) {
                float lo = vec3_axis(box.lo, axis), hi = vec3_axis(box.hi, axis);
                bool contains = lo <= exact.bounds[axis][k] && hi >= exact.bounds[axis + 3][k];
                failures += !contains || isnan(lo) || isnan(hi);
                double parent = (double)wide_bvh_dequantize(q.origin[axis], q.exponent[axis], 255) - q.origin[axis];
                if (contains && parent > 0.0 && isfinite(parent) && isfinite(hi - lo)) {
                    grown += ((double)hi - lo - ((double)exact.bounds[axis + 3][k] - exact.bounds[axis][k])) / parent;
                    measured++;
                }
            }
        }
    }
    *growth = measured > 0 ? grown / (double)measured : 0.0;
    return failures;
}

/* Every quantized box contains the exact box it stands for, on random and
 * adversarial parents (quantize_case), and no plane is NaN. The twin rounds
 * each plane to the nearest grid plane instead of outward: its boxes are as
 * tight on average, but some do not contain their exact box, so a ray
 * through the part cut off would miss a triangle: caught. */
static void test_quantized_boxes_contain_their_exact_boxes(void **state)
{
    (void)state;
    enum { TRIALS = 200000 };
    double outward_growth = 0.0, nearest_growth = 0.0;
    long outward = quantize_failures(WIDE_BVH_ROUND_OUTWARD, TRIALS, &outward_growth);
    long nearest = quantize_failures(WIDE_BVH_ROUND_NEAREST, TRIALS, &nearest_growth);
    print_message("quantized boxes, %d parents: rounded outward %ld not containing their box (each axis grew by "
                  "%.2f %% of the parent's on average); to nearest %ld\n",
                  TRIALS, outward, 100.0 * outward_growth, nearest);
    assert_int_equal(outward, 0);
    assert_true(nearest > 1000);
    /* a node whose box is not finite cannot go on a grid */
    wide_bvh_node infinite;
    pcg32 rng = pcg32_for_pixel(2017, 7);
    quantize_case(&infinite, 0, &rng);
    infinite.bounds[4][0] = INFINITY;
    wide_bvh_qnode q;
    assert_false(wide_bvh_quantize_node(&infinite, WIDE_BVH_ROUND_OUTWARD, &q));
}

/* The kernels dequantize in SIMD (bytes widened, converted, times the step,
 * plus the origin): each must test the boxes wide_bvh_qnode_box() gives,
 * bit for bit, as the exact node's test would test them, and never an empty
 * slot. */
static void test_quantized_slab_test_is_the_exact_test_of_its_boxes(void **state)
{
    (void)state;
    pcg32 rng = pcg32_for_pixel(2017, 11);
    long hits = 0;
    for (int i = 0; i < 20000; i++) {
        wide_bvh_node exact, dequantized;
        int children = quantize_case(&exact, i, &rng);
        wide_bvh_qnode q;
        assert_true(wide_bvh_quantize_node(&exact, WIDE_BVH_ROUND_OUTWARD, &q));
        dequantized = exact;
        for (int k = 0; k < children; k++) {
            aabb box = wide_bvh_qnode_box(&q, k);
            for (int axis = 0; axis < 3; axis++) {
                dequantized.bounds[axis][k] = vec3_axis(box.lo, axis);
                dequantized.bounds[axis + 3][k] = vec3_axis(box.hi, axis);
            }
        }
        /* a ray from near the boxes towards one of them, sometimes along an axis */
        aabb target = wide_bvh_qnode_box(&q, (int)pcg32_bounded(&rng, (uint32_t)children));
        vec3 centre = vec3_scale(vec3_add(target.lo, target.hi), 0.5f), extent = aabb_extent(target);
        if (!isfinite(centre.x + centre.y + centre.z)) /* a box reaching inf (the +-3e38 cases) */
            centre = vec3_make(0.0f, 0.0f, 0.0f);
        /* The ray starts 3 reach from the box: its size, plus a few float
         * steps at its place (REACH_RELATIVE of the coordinate) so that a
         * box of zero size far out is not started on, and REACH_TINY so
         * that a zero-size box at the origin is not either. */
        const float REACH_RELATIVE = 1e-6f, REACH_TINY = 1e-30f;
        float reach = fmaxf(fmaxf(extent.x, extent.y), extent.z) +
                      fmaxf(REACH_TINY, REACH_RELATIVE * fabsf(centre.x));
        reach = fminf(reach, 1e37f);
        vec3 o = vec3_add(centre, vec3_scale(accel_check_random_unit(&rng), 3.0f * reach));
        ray r = ray_make(o, vec3_sub(centre, o));
        if (i % 7 == 0)
            r.direction.y = i % 14 ? 0.0f : -0.0f;
        for (int kernel = 0; kernel < WIDE_BVH_KERNELS; kernel++) {
            if (!wide_bvh_kernel_runs(wide_bvh_kernels[kernel]))
                continue;
            float want[WIDE_BVH_WIDTH], got[WIDE_BVH_WIDTH];
            int want_mask = wide_bvh_slab_test(&dequantized, r, r.t_min, r.t_max, want, WIDE_BVH_KERNEL_SCALAR);
            int got_mask = wide_bvh_qslab_test(&q, r, r.t_min, r.t_max, got, wide_bvh_kernels[kernel]);
            assert_int_equal(got_mask, want_mask);
            assert_true(got_mask >> children == 0);
            for (int k = 0; k < children; k++)
                if (want_mask >> k & 1)
                    assert_memory_equal(&got[k], &want[k], sizeof got[k]);
            hits += kernel == 0 ? __builtin_popcount((unsigned)want_mask) : 0;
        }
    }
    print_message("quantized slab tests: 20000 nodes, %ld boxes hit\n", hits);
    assert_true(hits > 20000);
}

/* The quantized tree finds what the exact tree finds, bit for bit: the same
 * triangle, t and barycentrics for every ray (and so the same hit record),
 * the same any hit, on every mesh of the differential test and on the leak
 * test's closed meshes scaled from 1e-4 to 1e4 and moved far off, in every
 * kernel and through the streams. Rays aimed at shared edges and vertices
 * tie between triangles at the very same t: there the quantized tree, whose
 * larger boxes may let the walk meet them in another order, takes brute
 * force's lower index (checked against brute force), and the exact tree the
 * one its walk meets first (the differential tests accept either), so
 * there the two may name different triangles at the same t. */
static long quantized_mismatches(const triangle_set *set, const ray *rays, int count, const accel *brute)
{
    accel *trees[2] = {wide_bvh_build_layout(set, BVH_SPLIT_SAH, WIDE_BVH_EXACT),
                       wide_bvh_build_layout(set, BVH_SPLIT_SAH, WIDE_BVH_QUANTIZED)};
    assert_int_equal(((const wide_bvh *)trees[1])->layout, WIDE_BVH_QUANTIZED);
    wide_bvh_raw_hit *raw = calloc((size_t)count, sizeof *raw), *stream = calloc((size_t)count, sizeof *stream);
    bool *found = calloc((size_t)count, sizeof *found);
    long mismatches = 0;
    for (int kernel = 0; kernel < WIDE_BVH_KERNELS; kernel++) {
        if (!wide_bvh_set_kernel(trees[0], wide_bvh_kernels[kernel]) ||
            !wide_bvh_set_kernel(trees[1], wide_bvh_kernels[kernel]))
            continue;
        ray_counters counters = {0};
        for (int i = 0; i < count; i++) {
            wide_bvh_raw_hit want, got;
            wide_bvh_closest_hit_raw(trees[0], rays[i], &want, &counters);
            wide_bvh_closest_hit_raw(trees[1], rays[i], &got, &counters);
            raw[i] = got;
            /* The same hit, bit for bit, or (only) at a tie of equal t
             * another triangle: the exact tree keeps the one its walk meets
             * first, the quantized tree brute force's lower index (below). */
            bool tie = want.index != got.index && want.t == got.t;
            bool same = (memcmp(&want, &got, sizeof want) == 0 || tie) &&
                        accel_any_hit(trees[0], rays[i], &counters) == accel_any_hit(trees[1], rays[i], &counters);
            hit_record brute_hit;
            if (kernel == 0 && accel_closest_hit(brute, rays[i], &brute_hit, &counters))
                same = same && got.index == brute_hit.shape_id && got.t == brute_hit.t;
            mismatches += !same;
        }
        wide_bvh_closest_hit_stream_raw(trees[1], rays, count, stream, found, &counters);
        for (int i = 0; i < count; i++)
            mismatches += memcmp(&raw[i], &stream[i], sizeof raw[i]) != 0;
    }
    free(raw);
    free(stream);
    free(found);
    accel_destroy(trees[0]);
    accel_destroy(trees[1]);
    return mismatches;
}

static void test_quantized_tree_hits_are_the_exact_trees_bit_for_bit(void **state)
{
    (void)state;
    enum { RAYS = 3000 };
    ray *rays = calloc(RAYS, sizeof *rays);
    long mismatches = 0, cases = 0;
    for (int kind = 0; kind < MESH_KIND_COUNT; kind++) {
        mesh m;
        accel_check_make_mesh(&m, (accel_check_mesh)kind);
        triangle_set set;
        triangle_set_from_mesh(&set, &m);
        pcg32 rng = pcg32_for_pixel(2017, 100 + (uint64_t)kind);
        for (int i = 0; i < RAYS; i++)
            rays[i] = accel_check_ray(&m, set.bounds.lo, set.bounds.hi, &rng, i);
        accel *brute = brute_force_build(&set);
        mismatches += quantized_mismatches(&set, rays, RAYS, brute);
        cases++;
        accel_destroy(brute);
        triangle_set_free(&set);
        mesh_free(&m);
    }
    pcg32 rng = pcg32_for_pixel(2017, 200);
    for (int s = 0; s < LEAK_SCALES; s++) {
        mesh m;
        leak_mesh_jittered_icosphere(&m, 2, &rng);
        float offset = fminf(LEAK_OFFSET_MAX, leak_offset_sizes[LEAK_OFFSETS - 1] * leak_scales[s]);
        leak_mesh_transform(&m, leak_scales[s], vec3_scale(leak_random_unit(&rng), offset));
        int n = leak_rays_make(&m, RAYS, &rng, rays);
        triangle_set set;
        triangle_set_from_mesh(&set, &m);
        accel *brute = brute_force_build(&set);
        mismatches += quantized_mismatches(&set, rays, n, brute);
        cases++;
        accel_destroy(brute);
        triangle_set_free(&set);
        mesh_free(&m);
    }
    free(rays);
    print_message("quantized against exact trees: %ld meshes, %ld rays differ\n", cases, mismatches);
    assert_int_equal(mismatches, 0);
}

static void test_fast_sincos_turns_is_within_a_few_ulps(void **state)
{
    (void)state;
    double worst = sincos_worst_ulps(fast_sincos_turns);
    print_message("fast_sincos_turns: at most %.2f ulp from sin and cos of 2 pi u\n", worst);
    assert_true(worst <= FAST_SINCOS_TURNS_ULPS);
    double twin = sincos_worst_ulps(sincos_quarter_two_wrong);
    print_message("twin (cosine negated in the third quarter): %.3g ulp\n", twin);
    assert_true(twin > FAST_SINCOS_TURNS_ULPS);
}

/* ---- the physics once: the lanes' kernels against chapter 09's pieces ----------
 * The eight-path renderer computes each diffuse vertex's light sample and
 * bounce in AVX (or lane by lane), through chapter 09's pieces
 * (light_transport.h). On random vertices of the Cornell box with random
 * light samples and random numbers for the bounce, each kernel gives the
 * very bits of the scalar function it vectorises, value by value: the light
 * sample direct_light_solid_angle()'s contribution (times the throughput)
 * and shadow segment, with and without its MIS weight; the bounce the
 * direction of sample_uniform_hemisphere_fast() or
 * sample_cosine_hemisphere_fast() (fast_sincos.h), bounce_weight()'s
 * f cos / pdf (on the MIS rung bsdf_sample()'s rho) times the throughput
 * and 1 / P_RR, and the next ray from ray_spawn(). And the light sample
 * agrees with the lecture's, chapter 09's shade() in the slide's area form
 * (direct_light_area()), to rounding (the forms order their products
 * differently: a few ulps, LIGHT_MATH_TOLERANCE relative). The twins: the
 * area form without cos(theta'), the MIS rung's sample expected without its
 * weight (within a few thousandths of 1 in the box: still far outside the
 * tolerance), and the bounce's direction from chapter 08's libm sine and
 * cosine (a few ulps off), are caught. */
static const float LIGHT_MATH_TOLERANCE = 1e-5f;

static vec3 random_unit_in_hemisphere(vec3 n, pcg32 *rng)
{
    for (;;) {
        vec3 d = vec3_make(2.0f * pcg32_float(rng) - 1.0f, 2.0f * pcg32_float(rng) - 1.0f, 2.0f * pcg32_float(rng) - 1.0f);
        float l2 = vec3_length_squared(d);
        if (l2 > 1e-4f && l2 <= 1.0f)
            return vec3_dot(d, n) > 0.0f ? vec3_normalize(d) : vec3_normalize(vec3_neg(d));
    }
}

static bool same_vec3(vec3 a, vec3 b) { return memcmp(&a, &b, sizeof a) == 0; }

static bool same_ray(ray a, ray b)
{
    return same_vec3(a.origin, b.origin) && same_vec3(a.direction, b.direction) &&
           memcmp(&a.t_min, &b.t_min, sizeof a.t_min) == 0 && memcmp(&a.t_max, &b.t_max, sizeof a.t_max) == 0;
}

/* Eight random diffuse vertices of the box, each with a point on its light
 * (x[k]) and numbers for its bounce. */
static void random_wide_vertices(const pt_scene *sc, pcg32 *rng, wide_vertex v[8], pt_light_sample x[8])
{
    for (int k = 0; k < 8; k++) {
        int t;
        do
            t = (int)pcg32_bounded(rng, (uint32_t)sc->triangles.count);
        while (vec3_max_component(sc->materials[sc->geometry.faces[t].material].emission) > 0.0f);
        const triangle *tri = &sc->triangles.triangles[t];
        const pt_material *m = &sc->materials[sc->geometry.faces[t].material];
        float r1 = sqrtf(pcg32_float(rng)), r2 = pcg32_float(rng);
        v[k].p = vec3_add(vec3_add(vec3_scale(tri->p0, 1.0f - r1), vec3_scale(tri->p1, r1 * (1.0f - r2))),
                          vec3_scale(tri->p2, r1 * r2));
        v[k].n = v[k].ng = vec3_normalize(vec3_cross(vec3_sub(tri->p1, tri->p0), vec3_sub(tri->p2, tri->p0)));
        v[k].wo = random_unit_in_hemisphere(v[k].n, rng);
        if (pcg32_float(rng) < 0.125f) /* seen from below: f is 0, the light adds nothing, the path ends */
            v[k].wo = vec3_neg(v[k].wo);
        v[k].albedo = m->albedo;
        v[k].throughput = vec3_make(0.5f + 0.5f * pcg32_float(rng), 0.5f + 0.5f * pcg32_float(rng), 1.0f);
        v[k].p_error = 1e-4f * pcg32_float(rng);
        memset(&x[k], 0, sizeof x[k]); /* assert_true may return: the compiler cannot know it stops the test */
        float u_pick = pcg32_float(rng), u1 = pcg32_float(rng), u2 = pcg32_float(rng);
        assert_true(pt_scene_sample_light(sc, u_pick, u1, u2, &x[k]));
        v[k].x_light = x[k].point;
        v[k].n_light = x[k].normal;
        v[k].le = x[k].emission;
        v[k].x_error = x[k].point_error;
        v[k].pdf_area = x[k].pdf_light;
        v[k].u_x = pcg32_float(rng);
        v[k].u_y = pcg32_float(rng);
        v[k].rr_scale = pcg32_float(rng) < 0.5f ? 1.0f : 1.0f / 0.8f;
    }
}

static hit_record vertex_hit(const wide_vertex *v)
{
    hit_record hit = {.point = v->p, .point_error = v->p_error, .normal_geometric = v->ng, .normal_shading = v->n};
    return hit;
}

/* `vertices` random vertices of the box, eight at a time, each batch (with
 * its light samples) checked by `batch`: the number it finds wrong. */
typedef long (*wide_batch_check)(const wide_vertex v[8], const pt_light_sample x[8], void *how);

static long wide_mismatches(const pt_scene *sc, int vertices, uint64_t seed, wide_batch_check batch, void *how)
{
    pcg32 rng = pcg32_for_pixel(seed, 0);
    long wrong = 0;
    for (int start = 0; start < vertices; start += 8) {
        wide_vertex v[8];
        pt_light_sample x[8];
        random_wide_vertices(sc, &rng, v, x);
        wrong += batch(v, x, how);
    }
    return wrong;
}

/* `mis`: the MIS rung's light sample, weighted by the power heuristic
 * against bsdf_pdf() (sample_direct_light()); `expect_mis`: the weight in
 * the value expected from the area form; `with_cos_light` false: the twin
 * without cos(theta'). Counts the samples that add light (lit) and those
 * whose bits are not direct_light_solid_angle()'s (not_exact). */
typedef struct {
    bool with_cos_light, mis, expect_mis;
    long lit, not_exact;
} light_check;

/* The vertices whose light sample is not the area form's to rounding. */
static long light_batch_mismatches(const wide_vertex v[8], const pt_light_sample x[8], void *how)
{
    light_check *c = how;
    bool with_cos_light = c->with_cos_light, mis = c->mis, expect_mis = c->expect_mis;
    long wrong = 0;
    wide_light_result got[8];
    int mask = path_tracer_wide_light_math(v, 8, mis, got);
    for (int k = 0; k < 8; k++) {
        pt_material m = pt_diffuse(v[k].albedo);
        hit_record p = vertex_hit(&v[k]);
        /* chapter 09's shade(), the area form, and the later rungs' solid-angle form */
        light_contribution area = direct_light_area(&m, &p, v[k].wo, &x[k]);
        light_contribution solid = direct_light_solid_angle(&m, &p, v[k].wo, &x[k], 1, mis ? 1 : 0);
        bool wide_adds = (mask >> k) & 1, adds = area.adds && solid.adds;
        c->lit += adds;
        c->not_exact += wide_adds != solid.adds ||
                        (solid.adds && !(same_vec3(got[k].contribution, vec3_mul(v[k].throughput, solid.radiance)) &&
                                         same_ray(got[k].shadow, solid.shadow)));
        if (wide_adds != adds) {
            wrong++;
            continue;
        }
        if (!adds)
            continue;
        float weight = 1.0f;
        if (expect_mis) {
            vec3 wi = vec3_normalize(vec3_sub(x[k].point, v[k].p));
            weight = power_heuristic(solid.pdf_light, bsdf_pdf(&m, v[k].n, v[k].wo, wi));
        }
        float cos_light = with_cos_light ? 1.0f : area.cos_theta_light;
        vec3 expected = vec3_mul(v[k].throughput, vec3_scale(area.radiance, weight / cos_light));
        float scale = fmaxf(vec3_max_component(expected), vec3_max_component(got[k].contribution));
        wrong += vec3_max_component(vec3_abs(vec3_sub(got[k].contribution, expected))) > LIGHT_MATH_TOLERANCE * scale;
    }
    return wrong;
}

static long light_math_mismatches(const pt_scene *sc, int vertices, bool with_cos_light, bool mis, bool expect_mis,
                                  uint64_t seed, long *lit, long *not_exact)
{
    light_check c = {with_cos_light, mis, expect_mis, 0, 0};
    long wrong = wide_mismatches(sc, vertices, seed, light_batch_mismatches, &c);
    *lit += c.lit;
    *not_exact += c.not_exact;
    return wrong;
}

static void test_lanes_light_sample_is_chapter_09s(void **state)
{
    (void)state;
    pt_scene sc;
    pt_scene_build_cornell_box(&sc);
    enum { VERTICES = 8000 };
    for (int avx = 1; avx >= 0; avx--)
        for (int mis = 0; mis < 2; mis++) {
            path_tracer_wide_use_avx(avx);
            long lit = 0, not_exact = 0;
            long wrong = light_math_mismatches(&sc, VERTICES, true, mis, mis, test_seed(151), &lit, &not_exact);
            print_message("light sample%s, %s: %ld of %d vertices not direct_light_solid_angle()'s bits, %ld not "
                          "the area form's to rounding (%ld add light)\n",
                          mis ? " with its MIS weight" : "", avx ? "AVX" : "lane by lane", not_exact, VERTICES, wrong,
                          lit);
            assert_int_equal(not_exact, 0);
            assert_int_equal(wrong, 0);
            assert_true(lit > VERTICES / 4);
        }
    path_tracer_wide_use_avx(true);
    long lit = 0, ignored = 0;
    long twin = light_math_mismatches(&sc, VERTICES, false, false, false, test_seed(151), &lit, &ignored);
    lit = 0;
    long unweighted = light_math_mismatches(&sc, VERTICES, true, false, true, test_seed(151), &lit, &ignored);
    print_message("twins: without cos(theta'): %ld differ; without the MIS weight: %ld differ\n", twin, unweighted);
    assert_true(twin > lit / 2);
    assert_true(unweighted > lit / 2);
    pt_scene_free(&sc);
}

/* The bounce chapter 09's pieces give vertex v on `rung` (the direction
 * from `sample`), written as the lanes write it: false if its path ends. */
static bool expected_bounce(const wide_vertex *v, pt_integrator rung, vec3 (*sample)(float, float),
                            wide_bounce_result *out)
{
    pt_material m = pt_diffuse(v->albedo);
    vec3 local = sample(v->u_x, v->u_y);
    vec3 wi = frame_to_world(v->n, local);
    vec3 weight;
    out->pdf = 0.0f;
    if (rung == PT_LECTURE) {
        weight = bounce_weight(&m, v->n, v->wo, wi, local.z, uniform_hemisphere_pdf());
    } else {
        out->pdf = cosine_hemisphere_pdf(local.z);
        if (rung == PT_MIS ? !(local.z > 0.0f) : !(out->pdf > 0.0f))
            return false;
        weight = rung == PT_MIS ? m.albedo : bounce_weight(&m, v->n, v->wo, wi, local.z, out->pdf);
    }
    if (vec3_is_black(weight))
        return false;
    out->next = ray_spawn(v->p, v->p_error, v->ng, wi);
    out->wo = vec3_neg(wi);
    out->throughput = vec3_scale(vec3_mul(v->throughput, weight), v->rr_scale);
    return true;
}

static vec3 uniform_hemisphere_libm(float u_x, float u_y) { return sample_uniform_hemisphere(vec2_make(u_x, u_y)); }
static vec3 cosine_hemisphere_libm(float u_x, float u_y) { return sample_cosine_hemisphere(vec2_make(u_x, u_y)); }

/* The bounce on `rung`, expected with the direction from libm's sine and
 * cosine if `libm` (the twin); counts the paths that go on. */
typedef struct {
    pt_integrator rung;
    bool libm;
    long goes_on;
} bounce_check;

/* The vertices whose bounce is not the expected one, bit for bit (t_max
 * aside: the lanes keep the next ray's as it was). */
static long bounce_batch_mismatches(const wide_vertex v[8], const pt_light_sample x[8], void *how)
{
    (void)x;
    bounce_check *c = how;
    pt_integrator rung = c->rung;
    bool libm = c->libm;
    long wrong = 0;
    wide_bounce_result got[8];
    int mask = path_tracer_wide_bounce_math(v, 8, rung, got);
    for (int k = 0; k < 8; k++) {
        vec3 (*sample)(float, float) =
            rung == PT_LECTURE ? (libm ? uniform_hemisphere_libm : sample_uniform_hemisphere_fast)
                               : (libm ? cosine_hemisphere_libm : sample_cosine_hemisphere_fast);
        wide_bounce_result want = {.pdf = 0.0f};
        bool on = expected_bounce(&v[k], rung, sample, &want);
        c->goes_on += on;
        if (on != ((mask >> k) & 1)) {
            wrong++;
            continue;
        }
        got[k].next.t_max = want.next.t_max;
        wrong += on && !(same_ray(got[k].next, want.next) && same_vec3(got[k].wo, want.wo) &&
                         same_vec3(got[k].throughput, want.throughput) &&
                         memcmp(&got[k].pdf, &want.pdf, sizeof want.pdf) == 0);
    }
    return wrong;
}

static long bounce_mismatches(const pt_scene *sc, int vertices, pt_integrator rung, bool libm, uint64_t seed,
                              long *goes_on)
{
    bounce_check c = {rung, libm, 0};
    long wrong = wide_mismatches(sc, vertices, seed, bounce_batch_mismatches, &c);
    *goes_on += c.goes_on;
    return wrong;
}

static void test_lanes_bounce_is_chapter_09s(void **state)
{
    (void)state;
    pt_scene sc;
    pt_scene_build_cornell_box(&sc);
    enum { VERTICES = 8000 };
    for (int rung = 0; rung < 3; rung++) {
        for (int avx = 1; avx >= 0; avx--) {
            path_tracer_wide_use_avx(avx);
            long on = 0, wrong = bounce_mismatches(&sc, VERTICES, (pt_integrator)rung, false, test_seed(153), &on);
            print_message("bounce, %s rung, %s: %ld of %d vertices not chapter 09's bits (%ld go on)\n",
                          pt_integrator_name((pt_integrator)rung), avx ? "AVX" : "lane by lane", wrong, VERTICES, on);
            assert_int_equal(wrong, 0);
            assert_true(on > VERTICES / 2);
        }
        long on = 0, twin = bounce_mismatches(&sc, VERTICES, (pt_integrator)rung, true, test_seed(153), &on);
        print_message("twin, the direction from libm's sine and cosine: %ld of %d differ\n", twin, VERTICES);
        assert_true(twin > VERTICES / 10);
    }
    path_tracer_wide_use_avx(true);
    pt_scene_free(&sc);
}

/* ---- the benchmark scenes (bench_scenes.h) ------------------------------------- */

static int compare_longs(const void *a, const void *b)
{
    long x = *(const long *)a, y = *(const long *)b;
    return (x > y) - (x < y);
}

/* Is the mesh's part from face `first` on closed and consistently turned:
 * every directed edge (a, b) met once, and (b, a) once (so a ray that
 * enters the surface must leave it)? */
static bool faces_closed(const mesh *m, int first)
{
    int n = m->face_count - first;
    long *edges = malloc(sizeof(long) * 3 * (size_t)n);
    long vertices = m->position_count;
    for (int i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            edges[3 * i + k] = (long)m->faces[first + i].position[k] * vertices +
                               m->faces[first + i].position[(k + 1) % 3];
    qsort(edges, 3 * (size_t)n, sizeof(long), compare_longs);
    bool closed = true;
    for (long e = 0; e < 3L * n && closed; e++) {
        long reverse = edges[e] % vertices * vertices + edges[e] / vertices;
        closed = (e == 0 || edges[e - 1] != edges[e]) &&
                 bsearch(&reverse, edges, 3 * (size_t)n, sizeof(long), compare_longs) != NULL;
    }
    free(edges);
    return closed;
}

/* ---- a pixel's Sobol points, one after another -------------------------------- */

/* The twin's step: the Gray-code step chapter 08 uses for its points
 * (xor the one direction number of the lowest set bit of i + 1). It gives
 * the same sets of 2^m points but in another order, so a pixel's sample i
 * would not be chapter 09's point i. */
static void gray_code_step(sobol_pixel *s)
{
    uint32_t next = s->index + 1;
    int lowest = next == 0 ? 31 : __builtin_ctz(next);
    for (int d = 0; d < SOBOL_DIMENSIONS; d++)
        s->point_reversed[d] ^= reverse_bits(sobol_direction_numbers(d)[lowest]);
    s->index++;
    s->ready = 0;
    s->dimension = 0;
}

/* How many numbers of `samples` samples from `first` on differ from
 * chapter 09's sobol_sampler_next, when sobol_pixel steps from one sample
 * to the next with `step`. The samples draw 1 to 80 numbers each, as paths
 * of different lengths do (past SOBOL_DIMENSIONS, the pixel's stream). */
static long sobol_pixel_mismatches(void (*step)(sobol_pixel *), uint64_t seed, uint64_t pixel, uint32_t first,
                                   int samples)
{
    pcg32 rng_fast = pcg32_for_pixel(seed, pixel), rng_lecture = pcg32_for_pixel(seed, pixel);
    sobol_pixel fast;
    sobol_pixel_start(&fast, seed, pixel, first, &rng_fast);
    long wrong = 0;
    for (int i = 0; i < samples; i++) {
        if (i > 0)
            step(&fast);
        sobol_sampler lecture = sobol_sampler_start(seed, pixel, first + (uint32_t)i, &rng_lecture);
        int draws = 1 + (i * 37 + 79) % 80;
        for (int k = 0; k < draws; k++) {
            float a = sobol_pixel_next(&fast), b = sobol_sampler_next(&lecture);
            wrong += memcmp(&a, &b, sizeof a) != 0;
        }
    }
    return wrong;
}

/* Chapter 13's lanes draw chapter 09's numbers, bit for bit, however many
 * samples a pixel takes and wherever its first one is: from sample 0, from
 * a sample in the middle (a resumed or split render), and across index
 * 2^32 - 1 to 0, where every bit of the index flips; eight dimensions
 * at a time and one at a time. Up to 80 draws a sample, so the pixel's
 * stream past the 64th is compared too. */
static void test_sobol_pixel_draws_chapter_09s_numbers(void **state)
{
    (void)state;
    const struct {
        uint64_t seed, pixel;
        uint32_t first;
        int samples;
    } cases[] = {{1, 0, 0, 1100}, {test_seed(7), 123456, 0, 300}, {test_seed(8), 99, 1000, 300},
                 {test_seed(9), 5, 0xFFFFFF00u, 300}, {2, 77, 0xFFFFFFFFu, 2}};
    for (int simd = 1; simd >= 0; simd--) {
        sobol_pixel_use_simd(simd);
        long wrong = 0, twin = 0;
        for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
            wrong += sobol_pixel_mismatches(sobol_pixel_next_sample, cases[c].seed, cases[c].pixel, cases[c].first,
                                            cases[c].samples);
            twin += sobol_pixel_mismatches(gray_code_step, cases[c].seed, cases[c].pixel, cases[c].first,
                                           cases[c].samples);
        }
        print_message("sobol_pixel (%s) against chapter 09's sampler: %ld numbers differ; Gray-code steps (twin): %ld\n",
                      simd ? "eight dimensions at once" : "one at a time", wrong, twin);
        assert_int_equal(wrong, 0);
        assert_true(twin > 1000);
    }
    sobol_pixel_use_simd(true);
}

/* bench_scene_write() of `name` into dir, loaded back through the scene
 * file: the same corners, materials, camera, lights and environment. */
static void written_scene_loads_back(const char *dir, const char *name)
{
    pt_scene sc, back;
    assert_true(bench_scene_build(&sc, name));
    char path[256], err[1024];
    assert_true(bench_scene_write(dir, name, err, sizeof err));
    snprintf(path, sizeof path, "%s/%s.scene", dir, name);
    scene_desc desc;
    scene_desc_init(&desc);
    pt_scene_report_materials(NULL);
    assert_true(scene_desc_load(&desc, path, err, sizeof err));
    assert_true(pt_scene_from_desc(&back, &desc, "test", err, sizeof err));
    assert_int_equal(back.triangles.count, sc.triangles.count);
    for (int i = 0; i < sc.geometry.face_count; i++) {
        for (int c = 0; c < 3; c++) {
            vec3 p = mesh_vertex(&sc.geometry, i, c), q = mesh_vertex(&back.geometry, i, c);
            assert_true(p.x == q.x && p.y == q.y && p.z == q.z);
        }
        const pt_material *a = &sc.materials[sc.geometry.faces[i].material];
        const pt_material *b = &back.materials[back.geometry.faces[i].material];
        assert_int_equal(a->kind, b->kind);
        assert_true(a->albedo.x == b->albedo.x && a->albedo.y == b->albedo.y && a->albedo.z == b->albedo.z);
        assert_true(a->emission.x == b->emission.x && a->emission.z == b->emission.z);
    }
    assert_true(back.eye.z == sc.eye.z && back.vertical_fov_degrees == sc.vertical_fov_degrees);
    assert_int_equal(back.emitter_count, sc.emitter_count);
    assert_true(back.environment.x == sc.environment.x && back.environment.y == sc.environment.y &&
                back.environment.z == sc.environment.z);
    scene_desc_free(&desc);
    pt_scene_free(&back);
    pt_scene_free(&sc);
    const char *suffixes[] = {".scene", ".obj", ".mtl"};
    for (int k = 0; k < 3; k++) {
        snprintf(path, sizeof path, "%s/%s%s", dir, name, suffixes[k]);
        unlink(path);
    }
}

static void test_the_benchmark_scenes_are_what_they_say(void **state)
{
    (void)state;
    const char *names[] = {"cornell", "cornell-10k", "cornell-100k", "glossy-glass", "open-100k"};
    const int triangles[] = {32, 32 + 10240, 32 + 102400, 22 + 5120, 4 + 102400};
    for (int k = 0; k < 5; k++) {
        pt_scene sc;
        assert_true(bench_scene_build(&sc, names[k]));
        assert_int_equal(sc.triangles.count, triangles[k]);
        assert_int_equal(sc.sphere_count, 0);
        /* only the open scene has a sky, and every scene a light */
        assert_true((sc.environment.x > 0.0f) == (k == 4));
        assert_true(sc.emitter_count > 0);
        if (k == 1 || k == 2) {
            /* the torus (faces 32 on) is closed and above the short block's top, y = 165 */
            assert_true(faces_closed(&sc.geometry, 32));
            float lowest = INFINITY;
            for (int i = 32; i < sc.geometry.face_count; i++)
                for (int c = 0; c < 3; c++)
                    lowest = fminf(lowest, mesh_vertex(&sc.geometry, i, c).y);
            assert_true(lowest > 165.0f);
        }
        pt_scene_free(&sc);
    }
    /* the twin of the closedness check: one triangle gone opens the torus */
    pt_scene sc;
    assert_true(bench_scene_build(&sc, "cornell-10k"));
    sc.geometry.face_count--;
    assert_false(faces_closed(&sc.geometry, 32));
    sc.geometry.face_count++;
    assert_false(bench_scene_build(&sc, "no-such-scene")); /* sc untouched */
    pt_scene_free(&sc);

    /* What make bench writes loads back as the same triangles, paints and
     * sky: the room with a mesh, and the open scene, whose sky the scene
     * file carries (OBJ has none). */
    char dir[] = "/tmp/test_ch13_bench.XXXXXX";
    assert_non_null(mkdtemp(dir));
    written_scene_loads_back(dir, "cornell-10k");
    written_scene_loads_back(dir, "open-100k");
    rmdir(dir);
}

/* ==== the light tree (light_tree.c) ==== */

/* A scene of LIGHT_TEST_EMITTERS emitting triangles strewn in [-1, 1]^3,
 * each facing its own random way, of eight powers over a range of 2^7
 * (one material per power): what the tree must choose among by place,
 * facing and power at once. */
enum { LIGHT_TEST_EMITTERS = 48, LIGHT_TEST_POWERS = 8 };
/* Each emitter's two edges, in a cube of side 2: small beside the gaps
 * between them, so that the tree's bounds separate them. */
static const float LIGHT_TEST_EDGE = 0.08f;

static void build_strewn_lights(pt_scene *sc, uint64_t seed)
{
    pt_scene_init(sc);
    int material[LIGHT_TEST_POWERS];
    for (int k = 0; k < LIGHT_TEST_POWERS; k++)
        material[k] = pt_scene_add_material(sc, pt_emitter(vec3_splat(0.0f), vec3_splat(exp2f((float)k))));
    pcg32 rng = pcg32_for_pixel(test_seed(seed), 0);
    for (int i = 0; i < LIGHT_TEST_EMITTERS; i++) {
        vec3 c = vec3_make(2.0f * pcg32_float(&rng) - 1.0f, 2.0f * pcg32_float(&rng) - 1.0f, 2.0f * pcg32_float(&rng) - 1.0f);
        vec3 a = vec3_scale(random_direction(&rng), LIGHT_TEST_EDGE);
        vec3 b = vec3_scale(random_direction(&rng), LIGHT_TEST_EDGE);
        pt_scene_add_triangle(sc, c, vec3_add(c, a), vec3_add(c, b), material[pcg32_bounded(&rng, LIGHT_TEST_POWERS)]);
    }
    pt_scene_finish(sc);
}

/* A shading point and its normal, named. */
typedef struct {
    const char *name;
    vec3 p, n;
} light_test_point;

/* The points the tree is tested at in the strewn scene: among the lights,
 * on the back of one emitter (just behind it, facing away), far away (the
 * whole scene one small cone), and a point in space (no surface). */
static int light_test_points(const pt_scene *sc, light_test_point out[4])
{
    const triangle *t = &sc->triangles.triangles[sc->emitters[0]];
    vec3 centre = vec3_scale(vec3_add(t->p0, vec3_add(t->p1, t->p2)), 1.0f / 3.0f), n0 = sc->emitter_normals[0];
    out[0] = (light_test_point){"among the lights", vec3_make(0.1f, -0.2f, 0.05f), vec3_make(0.0f, 1.0f, 0.0f)};
    out[1] = (light_test_point){"behind an emitter", vec3_sub(centre, vec3_scale(n0, 0.01f)), vec3_neg(n0)};
    out[2] = (light_test_point){"far away", vec3_make(60.0f, 40.0f, -80.0f), vec3_normalize(vec3_make(-0.6f, -0.4f, 0.8f))};
    out[3] = (light_test_point){"in space", vec3_make(1.5f, 0.0f, 0.0f), vec3_splat(0.0f)};
    return 4;
}

/* A pmf for the twins: what light_tree_pmf() computes, with one mistake. */
typedef float (*light_pmf_fn)(const light_tree *t, vec3 p, vec3 n, int slot);

/* The sum of a group's importances at p, each by `importance`. */
static float group_sum(const light_tree *t, int first, vec3 p, vec3 n,
                       float (*importance)(const light_tree_node *, vec3, vec3))
{
    float sum = 0.0f;
    for (int k = 0; k < LIGHT_TREE_WIDTH; k++) {
        light_tree_node node = light_tree_node_at(t, first + k);
        sum += importance(&node, p, n);
    }
    return sum;
}

/* The twin that forgets to renormalize: each choice I_child / I_parent
 * instead of I_child over the sum of its group's (at the top, the sum). */
static float pmf_not_renormalized(const light_tree *t, vec3 p, vec3 n, int slot)
{
    float product = 1.0f;
    for (int node = t->leaf_of_light[slot]; node >= 0; node = t->parent[node]) {
        light_tree_node here = light_tree_node_at(t, node), parent = light_tree_node_at(t, t->parent[node] >= 0 ? t->parent[node] : 0);
        float below = t->parent[node] >= 0 ? light_node_importance(&parent, p, n) : group_sum(t, 0, p, n, light_node_importance);
        product *= below > 0.0f ? light_node_importance(&here, p, n) / below : 0.0f;
    }
    return product;
}

/* The twin that drops the orientation term from the pmf (every cone the
 * whole sphere) while the sampler keeps it. */
static float importance_without_orientation(const light_tree_node *node, vec3 p, vec3 n)
{
    light_tree_node wide = *node;
    wide.cos_theta_o = -32767;
    return light_node_importance(&wide, p, n);
}

static float pmf_without_orientation(const light_tree *t, vec3 p, vec3 n, int slot)
{
    float product = 1.0f;
    for (int node = t->leaf_of_light[slot]; node >= 0; node = t->parent[node]) {
        float sum = group_sum(t, node - node % LIGHT_TREE_WIDTH, p, n, importance_without_orientation);
        light_tree_node here = light_tree_node_at(t, node);
        product *= sum > 0.0f ? importance_without_orientation(&here, p, n) / sum : 0.0f;
    }
    return product;
}

/* The tree's picks at (p, n), N of them from a fixed seed, counted per
 * emitter (the last cell: no pick), against a pmf: Pearson's X^2 on
 * chapter 09's chi-square machinery (tests/chi2.h), the emitters the
 * cells. Each pick's own pmf must be light_tree_pmf()'s, bit for bit. */
static chi2_result light_tree_chi2(const light_tree *t, vec3 p, vec3 n, light_pmf_fn pmf, long attempts, uint64_t seed)
{
    int cells = t->light_count + 1;
    double *observed = calloc((size_t)cells, sizeof *observed), *probability = calloc((size_t)cells, sizeof *probability);
    pcg32 rng = pcg32_for_pixel(test_seed(seed), 1);
    long mismatched = 0;
    for (long i = 0; i < attempts; i++) {
        float picked_pmf;
        int slot = light_tree_sample(t, p, n, pcg32_float(&rng), &picked_pmf);
        observed[slot >= 0 ? slot : cells - 1] += 1.0;
        mismatched += slot >= 0 && picked_pmf != light_tree_pmf(t, p, n, slot);
    }
    assert_int_equal(mismatched, 0);
    double total = 0.0;
    for (int k = 0; k < t->light_count; k++)
        total += probability[k] = pmf(t, p, n, k);
    probability[cells - 1] = fmax(0.0, 1.0 - total);
    chi2_result r = chi2_verdict(observed, probability, cells, attempts);
    r.samples = attempts - (long)observed[cells - 1];
    r.refused = (long)observed[cells - 1];
    r.total = total;
    if (total > 1.0 + CHI2_TOTAL_ROUNDING)
        r.p_value = 0.0;
    free(observed);
    free(probability);
    return r;
}

/* The pmf of every emitter at a point sums to 1 (where every emitter may
 * be picked: a choice between two halves that can both give nothing
 * refuses, and then the sum is 1 less the refusals, at most 1). Float
 * products along a way of ~16 choices: a few ulps each. */
static const double LIGHT_PMF_SUM_TOLERANCE = 1e-5;

static void assert_pmf_sums_to_one(const light_tree *t, vec3 p, vec3 n, const char *where)
{
    double sum = 0.0;
    int zero = 0;
    for (int k = 0; k < t->light_count; k++) {
        float pmf = light_tree_pmf(t, p, n, k);
        sum += pmf;
        zero += pmf == 0.0f;
    }
    print_message("light tree, %s: pmf sums to %.8f over %d emitters (%d of pmf 0)\n", where, sum, t->light_count, zero);
    if (zero == 0)
        assert_true(fabs(sum - 1.0) <= LIGHT_PMF_SUM_TOLERANCE);
    else
        assert_true(sum <= 1.0 + LIGHT_PMF_SUM_TOLERANCE);
}

enum { LIGHT_CHI2_ATTEMPTS = 400000, LIGHT_CHI2_MANY_ATTEMPTS = 1000000 };

static void test_light_tree_picks_with_its_pmf(void **state)
{
    (void)state;
    pt_scene sc, many;
    build_strewn_lights(&sc, 401);
    assert_true(bench_scene_build(&many, "many-lights"));
    light_tree t, tm;
    light_tree_build(&t, &sc);
    light_tree_build(&tm, &many);
    assert_true(t.node_count <= LIGHT_TREE_WIDTH * (sc.emitter_count + 1));
    assert_true(many.emitter_count >= 10000);
    light_test_point points[4];
    int count = light_test_points(&sc, points);
    chi2_family family = {.count = 0};
    char name[CHI2_NAME_SIZE];
    for (int i = 0; i < count; i++) {
        assert_pmf_sums_to_one(&t, points[i].p, points[i].n, points[i].name);
        chi2_result r = light_tree_chi2(&t, points[i].p, points[i].n, light_tree_pmf, LIGHT_CHI2_ATTEMPTS, 411 + (uint64_t)i);
        snprintf(name, sizeof name, "light tree, %d emitters, %s", t.light_count, points[i].name);
        chi2_family_add(&family, name, &r);
    }
    /* the benchmark's room of 10,208 lamps, from the floor and from the
     * back of a ceiling lamp */
    const light_test_point in_room[] = {{"floor of the many-lights box", vec3_make(300.0f, 0.0f, 200.0f), vec3_make(0.0f, 1.0f, 0.0f)},
                                        {"above a ceiling lamp", vec3_make(20.0f, 548.5f, 20.0f), vec3_make(0.0f, -1.0f, 0.0f)}};
    for (int i = 0; i < 2; i++) {
        assert_pmf_sums_to_one(&tm, in_room[i].p, in_room[i].n, in_room[i].name);
        chi2_result r = light_tree_chi2(&tm, in_room[i].p, in_room[i].n, light_tree_pmf, LIGHT_CHI2_MANY_ATTEMPTS,
                                        421 + (uint64_t)i);
        snprintf(name, sizeof name, "light tree, %d emitters, %s", tm.light_count, in_room[i].name);
        chi2_family_add(&family, name, &r);
    }
    assert_int_equal(chi2_family_holm(&family, CHI2_FAMILY_ALPHA), 0);
    /* The twins, among the lights: each pmf wrong one way, the picks the
     * tree's; each must fail. */
    static const struct {
        light_pmf_fn pmf;
        const char *name;
    } twins[] = {{pmf_not_renormalized, "a choice not renormalized"},
                 {pmf_without_orientation, "the orientation term left out of the pmf"}};
    for (int k = 0; k < 2; k++) {
        chi2_result r = light_tree_chi2(&t, points[0].p, points[0].n, twins[k].pmf, LIGHT_CHI2_ATTEMPTS, 431 + (uint64_t)k);
        chi2_assert_twin_fails(twins[k].name, &r, family.count);
    }
    light_tree_free(&t);
    light_tree_free(&tm);
    pt_scene_free(&sc);
    pt_scene_free(&many);
}

/* The walk's four importances at once (SSE) are light_node_importance()
 * of each node, bit for bit, for every group of the many-lights tree at
 * random points in and around the box with random normals (and none):
 * the readable function is the one the walk computes. */
static void test_light_tree_group_is_its_nodes_importance(void **state)
{
    (void)state;
    pt_scene many;
    assert_true(bench_scene_build(&many, "many-lights"));
    light_tree t;
    light_tree_build(&t, &many);
    pcg32 rng = pcg32_for_pixel(test_seed(461), 0);
    long compared = 0, differ = 0;
    for (int trial = 0; trial < 64; trial++) {
        vec3 p = vec3_make(800.0f * pcg32_float(&rng) - 100.0f, 800.0f * pcg32_float(&rng) - 100.0f,
                           800.0f * pcg32_float(&rng) - 100.0f);
        vec3 n = trial % 8 == 0 ? vec3_splat(0.0f) : random_direction(&rng);
        for (int first = 0; first < t.node_count; first += LIGHT_TREE_WIDTH) {
            float group[LIGHT_TREE_WIDTH];
            light_tree_group_importances(&t, first, p, n, group);
            for (int k = 0; k < LIGHT_TREE_WIDTH; k++) {
                light_tree_node node = light_tree_node_at(&t, first + k);
                float one = light_node_importance(&node, p, n);
                differ += memcmp(&one, &group[k], sizeof one) != 0;
                compared++;
            }
        }
    }
    print_message("light tree: %ld importances four at a time, %ld differ from one at a time\n", compared, differ);
    assert_int_equal(differ, 0);
    light_tree_free(&t);
    pt_scene_free(&many);
}

/* Chapter 13 with the light tree against chapter 09's pick by power, on
 * the benchmark's many-lights box: the same image in distribution, by
 * the image-level statistics of tests/image_check.h (as chapter 13 is
 * held to chapter 09 above), on the production defaults (MIS, Sobol,
 * roulette on throughput) and on the lecture rung (light samples alone,
 * so a pmf the picks do not follow would show as bias). The twin, on the
 * lecture rung, picks by the tree but divides by chapter 09's density of
 * the pick by power. (A twin that weighs the emission a BSDF sample finds
 * against the wrong pmf hides here: the lamps are small, and the light
 * samples carry nearly all the light.) */
enum { LIGHT_TREE_IMAGE_CHECKS = 2 };

static image_check light_tree_against_power(pt_integrator rung, uint64_t seed)
{
    pt_scene wide_sc, lecture_sc;
    assert_true(bench_scene_build(&wide_sc, "many-lights") && bench_scene_build(&lecture_sc, "many-lights"));
    use_production(&wide_sc, true);
    assert_true(path_tracer_wide_uses_light_tree(&wide_sc)); /* 10,210 emitters: the tree, by default */
    path_tracer w = production_path_tracer_defaults(&wide_sc), l = production_path_tracer_defaults(&lecture_sc);
    if (rung != PRODUCTION_INTEGRATOR) {
        w = tracer(&wide_sc, rung, RR_FIXED);
        l = tracer(&lecture_sc, rung, RR_FIXED);
    }
    image_check c = wide_against_chapter_09(&w, &l, seed);
    pt_scene_free(&wide_sc);
    pt_scene_free(&lecture_sc);
    return c;
}

static void test_light_tree_image_agrees_with_power_picking(void **state)
{
    (void)state;
    static const pt_integrator rungs[LIGHT_TREE_IMAGE_CHECKS] = {PRODUCTION_INTEGRATOR, PT_LECTURE};
    for (int r = 0; r < LIGHT_TREE_IMAGE_CHECKS; r++) {
        image_check c = light_tree_against_power(rungs[r], 441 + 2 * (uint64_t)r);
        print_message("light tree against power picking, %s rung: p = %.3g (image mean z = %.2f, chi-square %.1f on %d)\n",
                      pt_integrator_name(rungs[r]), c.p, c.z, c.chi2, c.dof);
        assert_image_check(c, LIGHT_TREE_IMAGE_CHECKS, pt_integrator_name(rungs[r]));
    }
    path_tracer_wide_twin(WIDE_TWIN_TREE_PDF_OF_POWER);
    image_check twin = light_tree_against_power(PT_LECTURE, 451);
    path_tracer_wide_twin(WIDE_TWIN_NONE);
    print_message("twin, the tree's pick divided by the pick by power's density: p = %.3g (image mean z = %.2f, chi-square %.1f on %d)\n",
                  twin.p, twin.z, twin.chi2, twin.dof);
    assert_true(twin.p < image_check_alpha(LIGHT_TREE_IMAGE_CHECKS));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_wide_bvh_agrees_with_brute_force),
        cmocka_unit_test(test_wide_bvh_scalar_kernel_agrees_with_brute_force),
        cmocka_unit_test(test_wide_bvh_every_triangle_in_exactly_one_lane_and_boxes_nest),
        cmocka_unit_test(test_wide_bvh_more_coincident_triangles_than_a_leaf_holds),
        cmocka_unit_test(test_wide_bvh_hit_records_equal_the_sets),
        cmocka_unit_test(test_wide_bvh_kernels_give_identical_answers),
        cmocka_unit_test(test_wide_bvh_slab_test_matches_chapter_03),
        cmocka_unit_test(test_wide_bvh_triangle_test_matches_chapter_01),
        cmocka_unit_test(test_wide_bvh_room_walls_get_leaves_of_their_own),
        cmocka_unit_test(test_wide_bvh_empty_set_builds_and_misses),
        cmocka_unit_test(test_wide_bvh_is_the_same_on_any_number_of_threads),
        cmocka_unit_test(test_flat_equals_brute_force_bit_for_bit),
        cmocka_unit_test(test_flat_twins_are_caught),
        cmocka_unit_test(test_flat_packets_give_each_ray_its_own_answer),
        cmocka_unit_test(test_flat_empty_set_builds_and_misses),
        cmocka_unit_test(test_wide_bvh_stream_gives_each_ray_its_own_answer),
        cmocka_unit_test(test_the_cornell_box_has_ten_walls_that_change_no_image),
        cmocka_unit_test(test_walls_skipped_only_where_they_cannot_block),
        cmocka_unit_test(test_wall_test_is_never_fooled_by_rounding),
        cmocka_unit_test(test_eight_rays_wall_test_is_the_one_ray_test),
        cmocka_unit_test(test_packets_along_the_walls_match_single_rays),
        cmocka_unit_test(test_eight_paths_agree_with_chapter_09),
        cmocka_unit_test(test_eight_paths_same_bits_for_threads_and_lanes),
        cmocka_unit_test(test_eight_paths_agree_with_chapter_09_on_every_scene),
        cmocka_unit_test(test_production_defaults_agree_with_chapter_09_on_the_benchmark_scenes),
        cmocka_unit_test(test_eight_paths_cosine_and_mis_agree_with_chapter_09),
        cmocka_unit_test(test_eight_paths_same_bits_for_threads_on_every_scene),
        cmocka_unit_test(test_spawn_avx_is_ray_h_bit_for_bit),
        cmocka_unit_test(test_fast_sincos_turns_is_within_a_few_ulps),
        cmocka_unit_test(test_lanes_light_sample_is_chapter_09s),
        cmocka_unit_test(test_lanes_bounce_is_chapter_09s),
        cmocka_unit_test(test_no_ray_leaks_through_a_closed_mesh_anywhere),
        cmocka_unit_test(test_moller_trumbore_leaks_through_every_entry_point),
        cmocka_unit_test(test_quantized_boxes_contain_their_exact_boxes),
        cmocka_unit_test(test_quantized_slab_test_is_the_exact_test_of_its_boxes),
        cmocka_unit_test(test_quantized_tree_hits_are_the_exact_trees_bit_for_bit),
        cmocka_unit_test(test_sobol_pixel_draws_chapter_09s_numbers),
        cmocka_unit_test(test_the_benchmark_scenes_are_what_they_say),
        cmocka_unit_test(test_light_tree_picks_with_its_pmf),
        cmocka_unit_test(test_light_tree_group_is_its_nodes_importance),
        cmocka_unit_test(test_light_tree_image_agrees_with_power_picking),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
