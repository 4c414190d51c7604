/* accel.c -- the triangle set every structure is built over, and brute force. */
#include "03-aabb-slabs/accel.h"

#include <stdlib.h>

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
    int best = ACCEL_WALK(a, brute_force_walk, a, &r, false, &b1, &b2, counters);
    return accel_walk_hit(a, best, r, b1, b2, hit);
}

static bool brute_force_any_hit(const accel *a, ray r, ray_counters *counters)
{
    float b1, b2;
    return ACCEL_WALK(a, brute_force_walk, a, &r, true, &b1, &b2, counters) >= 0;
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
