/* accel.c -- the triangle set every structure is built over, and brute force. */
#include "accel.h"

#include <stdlib.h>

#include "explain.h"
#include "memory.h"
#include "timer.h"

void triangle_set_from_mesh(triangle_set *set, const mesh *m)
{
    set->count = m->face_count;
    set->triangles = memory_allocate((size_t)m->face_count, sizeof *set->triangles);
    set->boxes = memory_allocate((size_t)m->face_count, sizeof *set->boxes);
    /* every closest hit may read a triangle, at random: 2 MB pages (memory.h) */
    memory_advise_huge(set->triangles, (size_t)m->face_count * sizeof *set->triangles);
    set->surfaces = memory_allocate((size_t)m->face_count, sizeof *set->surfaces);
    memory_advise_huge(set->surfaces, (size_t)m->face_count * sizeof *set->surfaces); /* read at every hit too */
    set->bounds = aabb_empty();
    set->source = m;
    set->vertex_normals = false;
    for (int i = 0; i < m->face_count; i++) {
        triangle t = {mesh_vertex(m, i, 0), mesh_vertex(m, i, 1), mesh_vertex(m, i, 2)};
        const mesh_face *f = &m->faces[i];
        set->triangles[i] = t;
        set->surfaces[i] = (triangle_surface){triangle_unit_normal(&t), f->material};
        set->vertex_normals |= f->normal[0] >= 0 && f->normal[1] >= 0 && f->normal[2] >= 0;
        set->boxes[i] = aabb_add_point(aabb_add_point(aabb_add_point(aabb_empty(), t.p0), t.p1), t.p2);
        set->bounds = aabb_union(set->bounds, set->boxes[i]);
    }
}

void triangle_set_subset(triangle_set *out, const triangle_set *from, const bool *keep)
{
    int count = 0;
    for (int i = 0; i < from->count; i++)
        count += keep[i];
    out->count = count;
    /* at least one of each, so that an empty set still frees cleanly */
    out->triangles = memory_allocate((size_t)(count > 0 ? count : 1), sizeof *out->triangles);
    out->boxes = memory_allocate((size_t)(count > 0 ? count : 1), sizeof *out->boxes);
    out->surfaces = memory_allocate((size_t)(count > 0 ? count : 1), sizeof *out->surfaces);
    out->bounds = aabb_empty();
    out->source = NULL;
    out->vertex_normals = false;
    for (int i = 0, k = 0; i < from->count; i++) {
        if (!keep[i])
            continue;
        out->triangles[k] = from->triangles[i];
        out->boxes[k] = from->boxes[i];
        out->surfaces[k] = from->surfaces[i];
        out->bounds = aabb_union(out->bounds, out->boxes[k]);
        k++;
    }
}

void triangle_set_free(triangle_set *set)
{
    free(set->triangles);
    free(set->boxes);
    free(set->surfaces);
    set->triangles = NULL;
    set->boxes = NULL;
    set->surfaces = NULL;
    set->count = 0;
}

void triangle_set_shade_vertex_normal(const triangle_set *set, int index, float b1, float b2, hit_record *hit)
{
    const mesh *m = set->source;
    const mesh_face *f = &m->faces[index];
    if (f->normal[0] >= 0 && f->normal[1] >= 0 && f->normal[2] >= 0) {
        /* Interpolated vertex normal, turned to the side of the geometric
         * normal (a shading normal on the far side would light the back). */
        vec3 n = vec3_add(vec3_add(vec3_scale(m->normals[f->normal[0]], 1.0f - b1 - b2),
                                   vec3_scale(m->normals[f->normal[1]], b1)),
                          vec3_scale(m->normals[f->normal[2]], b2));
        if (vec3_length_squared(n) > 0.0f) {
            n = vec3_normalize(n);
            hit->normal_shading = vec3_dot(n, hit->normal_geometric) < 0.0f ? vec3_neg(n) : n;
        }
    }
}

/* ---- brute force ----------------------------------------------------------
 * Every triangle, in order; a later one must be strictly nearer to replace
 * the closest so far, so of equal t the lower index wins. With the
 * watertight test the ray's part of it is computed once, here. */

static inline int brute_force_walk(const accel *a, ray *r, bool any, triangle_test test, float *b1_out,
                                   float *b2_out, ray_counters *counters)
{
    const triangle_set *set = a->set;
    watertight_ray wr = watertight_ray_make(r);
    int best = -1;
    for (int i = 0; i < set->count; i++) {
        float t, b1, b2;
        if (triangle_intersect_with(test, &wr, &set->triangles[i], r, r->t_max, &t, &b1, &b2)) {
            best = i;
            r->t_max = t; /* only closer hits from now on */
            *b1_out = b1;
            *b2_out = b2;
            if (any) {
                counters->primitive_tests += (uint64_t)i + 1;
                return best;
            }
        }
    }
    counters->primitive_tests += (uint64_t)set->count;
    return best;
}

static bool brute_force_closest_hit(const accel *a, ray r, hit_record *hit, ray_counters *counters)
{
    float b1 = 0.0f, b2 = 0.0f;
    int best = a->triangle_test == TRIANGLE_TEST_WATERTIGHT
                   ? brute_force_walk(a, &r, false, TRIANGLE_TEST_WATERTIGHT, &b1, &b2, counters)
                   : brute_force_walk(a, &r, false, TRIANGLE_TEST_MOLLER_TRUMBORE, &b1, &b2, counters);
    if (best < 0)
        return false;
    triangle_set_fill_hit(a->set, best, r, r.t_max, b1, b2, hit);
    return true;
}

static bool brute_force_any_hit(const accel *a, ray r, ray_counters *counters)
{
    float b1, b2;
    if (a->triangle_test == TRIANGLE_TEST_WATERTIGHT)
        return brute_force_walk(a, &r, true, TRIANGLE_TEST_WATERTIGHT, &b1, &b2, counters) >= 0;
    return brute_force_walk(a, &r, true, TRIANGLE_TEST_MOLLER_TRUMBORE, &b1, &b2, counters) >= 0;
}

static void brute_force_destroy(accel *a) { free(a); }

/* The structures that test the set's own triangles (brute force, the grid,
 * the kd-tree) store nothing per test: switching is the field alone. */
bool accel_use_triangle_test_of_set(accel *a, triangle_test test)
{
    a->triangle_test = test;
    return true;
}

static const accel_ops brute_force_ops = {brute_force_closest_hit, brute_force_any_hit, brute_force_destroy,
                                          accel_use_triangle_test_of_set};

accel *brute_force_build(const triangle_set *set)
{
    double start = timer_seconds();
    accel *a = memory_allocate(1, sizeof *a);
    a->ops = &brute_force_ops;
    a->set = set;
    a->stats.name = "brute";
    a->stats.bytes = sizeof *a;
    a->stats.nodes = 1;
    a->stats.leaves = 1;
    a->stats.references = set->count;
    a->stats.build_seconds = timer_seconds() - start;
    return a;
}

/* ---- looking at a mesh ---------------------------------------------------- */

vec3 accel_heat_colour(float fraction)
{
    /* dark blue -> magenta -> orange -> yellow -> white, in linear RGB */
    static const vec3 ramp[5] = {{0.0f, 0.0f, 0.08f}, {0.45f, 0.02f, 0.45f}, {0.95f, 0.3f, 0.02f},
                                 {1.0f, 0.9f, 0.05f}, {1.0f, 1.0f, 1.0f}};
    float x = fminf(fmaxf(fraction, 0.0f), 1.0f) * 4.0f;
    int i = (int)fminf(x, 3.0f);
    return vec3_lerp(ramp[i], ramp[i + 1], x - (float)i);
}

vec3 accel_view_radiance(const void *view_ptr, ray r, pcg32 *rng, ray_counters *counters)
{
    (void)rng;
    const accel_view *view = view_ptr;
    uint64_t cost_before = counters->box_tests + counters->primitive_tests;
    hit_record hit;
    uint64_t boxes_before = counters->box_tests, triangles_before = counters->primitive_tests;
    bool found = accel_closest_hit(view->structure, r, &hit, counters);
    if (explain_on()) {
        explain_line(1, "%s: %llu nodes or cells visited, %llu triangles tested", view->structure->stats.name,
                     (unsigned long long)(counters->box_tests - boxes_before),
                     (unsigned long long)(counters->primitive_tests - triangles_before));
        if (found)
            explain_line(1, "closest hit: triangle #%d at t = %.6g; headlight shading |n . d| = %.4g", hit.shape_id,
                         (double)hit.t, (double)fabsf(vec3_dot(hit.normal_shading, vec3_normalize(r.direction))));
        else
            explain_line(1, "no triangle hit: the background");
    }
    if (view->heatmap) {
        float cost = (float)(counters->box_tests + counters->primitive_tests - cost_before);
        return accel_heat_colour(cost / view->heatmap_max_cost);
    }
    if (!found)
        return vec3_make(0.02f, 0.02f, 0.03f);
    float facing = fabsf(vec3_dot(hit.normal_shading, vec3_normalize(r.direction)));
    return vec3_scale(vec3_make(0.8f, 0.75f, 0.7f), 0.1f + 0.9f * facing);
}

camera accel_view_camera(aabb bounds, int width, int height)
{
    vec3 centre = aabb_centroid(bounds);
    float half_diagonal = 0.5f * vec3_length(aabb_extent(bounds));
    vec3 eye = vec3_add(centre, vec3_scale(vec3_normalize(vec3_make(0.3f, 0.4f, 1.0f)), 2.5f * half_diagonal));
    return camera_look_at(eye, centre, vec3_make(0, 1, 0), 2.0f * atanf(0.3f) * 180.0f / (float)PI, width, height);
}

/* ---- the Embree harness's ray sets ------------------------------------------ */

static double harness_uniform(uint64_t *state)
{
    uint64_t z = (*state += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    z ^= z >> 31;
    return (double)(z >> 11) * (1.0 / 9007199254740992.0);
}

static vec3 harness_unit(vec3 a) { return vec3_scale(a, 1.0f / sqrtf(vec3_dot(a, a))); }

ray *accel_harness_rays(aabb bounds, bool coherent, int *count)
{
    enum { SIDE = 1024, INCOHERENT = 1 << 20 };
    if (coherent) {
        *count = SIDE * SIDE;
        ray *rays = memory_allocate((size_t)*count, sizeof *rays);
        vec3 c = vec3_scale(vec3_add(bounds.lo, bounds.hi), 0.5f);
        vec3 diagonal = vec3_sub(bounds.hi, bounds.lo);
        float rb = 0.5f * sqrtf(vec3_dot(diagonal, diagonal));
        vec3 eye = vec3_add(c, vec3_scale(harness_unit(vec3_make(0.3f, 0.4f, 1.0f)), 2.5f * rb));
        vec3 forward = harness_unit(vec3_sub(c, eye));
        vec3 right = harness_unit(vec3_cross(forward, vec3_make(0, 1, 0)));
        vec3 up = vec3_cross(right, forward);
        float th = 0.3f, tw = th * (float)SIDE / (float)SIDE;
        for (int y = 0; y < SIDE; y++)
            for (int x = 0; x < SIDE; x++) {
                float u = (2 * (x + 0.5f) / (float)SIDE - 1) * tw, v = (1 - 2 * (y + 0.5f) / (float)SIDE) * th;
                vec3 d = harness_unit(vec3_add(forward, vec3_add(vec3_scale(right, u), vec3_scale(up, v))));
                rays[(size_t)y * SIDE + (size_t)x] = ray_make(eye, d);
            }
        return rays;
    }
    *count = INCOHERENT;
    ray *rays = memory_allocate((size_t)*count, sizeof *rays);
    uint64_t state = 0xBADC0DE;
    for (int k = 0; k < *count; k++) {
        vec3 o;
        o.x = (float)(bounds.lo.x + (bounds.hi.x - bounds.lo.x) * harness_uniform(&state));
        o.y = (float)(bounds.lo.y + (bounds.hi.y - bounds.lo.y) * harness_uniform(&state));
        o.z = (float)(bounds.lo.z + (bounds.hi.z - bounds.lo.z) * harness_uniform(&state));
        float z = (float)(2 * harness_uniform(&state) - 1);
        float phi = (float)(2 * PI * harness_uniform(&state));
        float s = sqrtf(1 - z * z);
        rays[k] = ray_make(o, vec3_make(s * cosf(phi), s * sinf(phi), z));
    }
    return rays;
}

ray *accel_aimed_rays(const triangle_set *set, int count, uint64_t seed)
{
    ray *rays = memory_allocate((size_t)count, sizeof *rays);
    pcg32 rng = pcg32_for_pixel(seed, 0x9120);
    vec3 lo = set->bounds.lo, e = aabb_extent(set->bounds);
    for (int i = 0; i < count; i++) {
        /* in a written order (C leaves a call's argument order open): GCC's */
        float u_z = pcg32_float(&rng), u_y = pcg32_float(&rng), u_x = pcg32_float(&rng);
        vec3 o = vec3_make(lo.x + e.x * u_x, lo.y + e.y * u_y, lo.z + e.z * u_z);
        const triangle *t = &set->triangles[pcg32_bounded(&rng, (uint32_t)set->count)];
        vec3 target = vec3_scale(vec3_add(vec3_add(t->p0, t->p1), t->p2), 1.0f / 3.0f);
        rays[i] = ray_make(o, vec3_normalize(vec3_sub(target, o)));
    }
    return rays;
}
