/* accel_check.h -- the differential test every acceleration structure takes:
 * on several meshes, for many seeded rays, its closest hit must be brute
 * force's (same t, bit for bit, and the same triangle unless two triangles
 * tie at that t), and its any-hit must agree with its closest hit. The
 * reference is brute force with the watertight triangle test (chapter 01),
 * the test every structure runs: a reference on Moller-Trumbore would leak
 * through the same shared edges as a structure on it, and could not see
 * that (tests/test_ch13.c's leak test does). Include after <cmocka.h>.
 *
 * Usage in a suite:
 *   static accel *build_grid(const triangle_set *s) { return grid_build(s, 27.0f); }
 *   static void test_grid_agrees_with_brute_force(void **state) { accel_check_all(build_grid, 100000); }
 */
#ifndef ACCEL_CHECK_H
#define ACCEL_CHECK_H

#include <stdio.h>

#include "03-aabb-slabs/accel.h"
#include "mesh.h"
#include "rng.h"

typedef accel *(*accel_builder)(const triangle_set *set);

/* 8 float ulps: two arrangements of a triangle test (a structure's stored
 * corners or edges, its SIMD lanes) may round differently by a few ulps; a
 * wrong traversal finds a hit farther away by far more. */
static const float ACCEL_CHECK_T_TOLERANCE = 8.0f * 0x1.0p-24f;

typedef enum {
    MESH_ICOSPHERE,      /* closed: every ray from outside towards it hits */
    MESH_TORI_FIELD,     /* the benchmark mesh (10240 triangles) */
    MESH_SOUP,           /* random small triangles */
    MESH_STADIUM,        /* teapot in a stadium */
    MESH_COINCIDENT,     /* 64 copies of one triangle plus a sphere */
    MESH_DEGENERATE,     /* collinear and zero-area triangles among good ones */
    MESH_FLAT,           /* a planar grid of triangles lying in z = 0.5: flat boxes */
    MESH_KIND_COUNT
} accel_check_mesh;

static const char *const accel_check_mesh_names[MESH_KIND_COUNT] = {
    "icosphere", "tori field", "soup", "teapot in stadium", "coincident", "degenerate", "flat"};

static inline void accel_check_make_mesh(mesh *m, accel_check_mesh kind)
{
    mesh_init(m);
    switch (kind) {
    case MESH_ICOSPHERE:
        mesh_icosphere(m, vec3_make(0.1f, -0.2f, 0.3f), 1.0f, 3, -1);
        break;
    case MESH_TORI_FIELD:
        mesh_tori_field(m, 10240);
        break;
    case MESH_SOUP:
        mesh_random_soup(m, 3000, vec3_make(-2, -1, -1), vec3_make(2, 1, 1), 0.2f, 42);
        break;
    case MESH_STADIUM:
        mesh_teapot_in_stadium(m, 3, 200.0f);
        break;
    case MESH_COINCIDENT:
        mesh_coincident(m, 64);
        mesh_icosphere(m, vec3_make(0, 0, 2), 0.5f, 1, -1);
        break;
    case MESH_DEGENERATE: {
        mesh_random_soup(m, 500, vec3_make(-1, -1, -1), vec3_make(1, 1, 1), 0.3f, 7);
        for (int i = 0; i < 50; i++) {
            float x = -1.0f + 0.04f * (float)i;
            int a = mesh_add_position(m, vec3_make(x, -1, 0));
            int b = mesh_add_position(m, vec3_make(x, 0, 0));
            int c = mesh_add_position(m, vec3_make(x, 1, 0)); /* collinear */
            mesh_add_triangle(m, a, b, c, -1);
            mesh_add_triangle(m, a, a, a, -1); /* a point */
        }
        break;
    }
    case MESH_FLAT: {
        int n = 20;
        for (int i = 0; i <= n; i++)
            for (int j = 0; j <= n; j++)
                mesh_add_position(m, vec3_make(-1.0f + 2.0f * (float)i / (float)n, -1.0f + 2.0f * (float)j / (float)n, 0.5f));
        for (int i = 0; i < n; i++)
            for (int j = 0; j < n; j++) {
                int a = i * (n + 1) + j, b = (i + 1) * (n + 1) + j, c = (i + 1) * (n + 1) + j + 1, d = i * (n + 1) + j + 1;
                mesh_add_triangle(m, a, b, c, -1);
                mesh_add_triangle(m, a, c, d, -1);
            }
        break;
    }
    case MESH_KIND_COUNT:
        break;
    }
}

static inline vec3 accel_check_random_unit(pcg32 *rng)
{
    float z = 2.0f * pcg32_float(rng) - 1.0f, phi = 2.0f * (float)PI * pcg32_float(rng);
    float s = sqrtf(fmaxf(0.0f, 1.0f - z * z));
    return vec3_make(s * cosf(phi), s * sinf(phi), z);
}

/* Ray i of a mesh's test set: a third start inside the bounds and go
 * anywhere; a third start outside and aim at a random vertex exactly; a third
 * aim at the midpoint of a random edge (shared edges and vertices are where
 * hits are easiest to lose). A few have axis-aligned directions with zero
 * components, the slab test's +0/-0 cases. */
static inline ray accel_check_ray(const mesh *m, vec3 lo, vec3 hi, pcg32 *rng, int i)
{
    vec3 extent = vec3_sub(hi, lo);
    vec3 centre = vec3_scale(vec3_add(lo, hi), 0.5f);
    float size = fmaxf(vec3_length(extent), 1e-3f);
    ray r;
    if (i % 3 == 0) {
        vec3 o = vec3_make(lo.x + extent.x * pcg32_float(rng), lo.y + extent.y * pcg32_float(rng),
                           lo.z + extent.z * pcg32_float(rng));
        vec3 d = accel_check_random_unit(rng);
        if (i % 17 == 0) /* axis-aligned, with signed zeros */
            d = (i / 17) % 2 ? vec3_make(0.0f, -0.0f, 1.0f) : vec3_make(-0.0f, -1.0f, 0.0f);
        r = ray_make(o, d);
    } else {
        int face = (int)pcg32_bounded(rng, (uint32_t)m->face_count);
        int k = (int)pcg32_bounded(rng, 3);
        vec3 target = mesh_vertex(m, face, k);
        if (i % 3 == 2)
            target = vec3_scale(vec3_add(target, mesh_vertex(m, face, (k + 1) % 3)), 0.5f);
        vec3 o = vec3_add(centre, vec3_scale(accel_check_random_unit(rng), size));
        r = ray_make(o, vec3_sub(target, o));
    }
    return r;
}

/* Returns the number of mismatches (0 when the structure is right) and
 * prints the first few. */
static inline long accel_check_mesh_kind(accel_builder build, accel_check_mesh kind, int ray_count, const char *name)
{
    mesh m;
    accel_check_make_mesh(&m, kind);
    triangle_set set;
    triangle_set_from_mesh(&set, &m);
    accel *reference = brute_force_build(&set);
    assert_int_equal(reference->triangle_test, TRIANGLE_TEST_WATERTIGHT);
    accel *tested = build(&set);
    pcg32 rng = pcg32_for_pixel(20261123, (uint64_t)kind);
    long mismatches = 0, hits = 0;
    for (int i = 0; i < ray_count; i++) {
        ray r = accel_check_ray(&m, set.bounds.lo, set.bounds.hi, &rng, i);
        ray_counters c = {0};
        hit_record want, got;
        bool want_hit = accel_closest_hit(reference, r, &want, &c);
        bool got_hit = accel_closest_hit(tested, r, &got, &c);
        hits += want_hit;
        bool same = want_hit == got_hit;
        /* The same t within ACCEL_CHECK_T_TOLERANCE (relative): a structure
         * may run a differently arranged triangle test; a different
         * triangle is fine only when it ties at that t (a shared edge). */
        if (same && want_hit)
            same = fabsf(want.t - got.t) <= ACCEL_CHECK_T_TOLERANCE * want.t;
        /* any-hit: over the whole ray, and over a segment ending before the
         * closest hit (must then find nothing) */
        bool any = accel_any_hit(tested, r, &c);
        if (any != want_hit)
            same = false;
        if (want_hit) {
            ray shorter = r;
            shorter.t_max = want.t * 0.999f;
            if (accel_any_hit(tested, shorter, &c))
                same = false;
        }
        if (!same) {
            if (mismatches < 5)
                print_message("%s on %s: ray %d (o=%g,%g,%g d=%g,%g,%g): brute %s t=%.9g tri %d, got %s t=%.9g tri %d, any %d\n",
                              name, accel_check_mesh_names[kind], i, (double)r.origin.x, (double)r.origin.y,
                              (double)r.origin.z, (double)r.direction.x, (double)r.direction.y, (double)r.direction.z,
                              want_hit ? "hit" : "miss", want_hit ? (double)want.t : 0.0, want_hit ? want.shape_id : -1,
                              got_hit ? "hit" : "miss", got_hit ? (double)got.t : 0.0, got_hit ? got.shape_id : -1, any);
            mismatches++;
        }
    }
    /* A test set that never hits proves nothing. */
    if (hits < ray_count / 20) {
        print_message("%s on %s: only %ld of %d rays hit\n", name, accel_check_mesh_names[kind], hits, ray_count);
        mismatches++;
    }
    accel_destroy(tested);
    accel_destroy(reference);
    triangle_set_free(&set);
    mesh_free(&m);
    return mismatches;
}

/* Every mesh kind, ray_count rays each. */
static inline void accel_check_all(accel_builder build, int ray_count, const char *name)
{
    long total = 0;
    for (int kind = 0; kind < MESH_KIND_COUNT; kind++)
        total += accel_check_mesh_kind(build, (accel_check_mesh)kind, ray_count, name);
    if (total != 0)
        fail_msg("%s disagrees with brute force on %ld rays", name, total);
}

#endif
