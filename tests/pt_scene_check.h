/* pt_scene_check.h -- a scene file against the built-in scene it claims to
 * be: the same triangles bit for bit, in the same order, with the same
 * materials, the same spheres, lights, environment and camera. Then every
 * render of the two is the same, bit for bit, whatever the method.
 *
 *   assert_same_pt_scene(&from_file, &built_in);
 *
 * And the small pieces the suites of chapters 09-13 share: a point on a
 * triangle, its normal, whether a sphere blocks a ray.
 */
#ifndef PT_SCENE_CHECK_H
#define PT_SCENE_CHECK_H

#include <math.h>
#include <string.h>

#include "09-path-tracing/scene_pt.h"

static inline void assert_same_material(const pt_material *a, const pt_material *b)
{
    assert_int_equal(a->kind, b->kind);
    assert_memory_equal(&a->albedo, &b->albedo, sizeof a->albedo);
    assert_memory_equal(&a->emission, &b->emission, sizeof a->emission);
    assert_true(a->roughness == b->roughness && a->ior == b->ior);
}

static inline void assert_same_pt_scene(const pt_scene *a, const pt_scene *b)
{
    assert_int_equal(a->triangles.count, b->triangles.count);
    assert_memory_equal(a->triangles.triangles, b->triangles.triangles,
                        (size_t)a->triangles.count * sizeof a->triangles.triangles[0]);
    for (int i = 0; i < a->geometry.face_count; i++)
        assert_same_material(&a->materials[a->geometry.faces[i].material], &b->materials[b->geometry.faces[i].material]);
    assert_int_equal(a->sphere_count, b->sphere_count);
    assert_int_equal(a->point_light_count, b->point_light_count);
    assert_int_equal(a->emitter_count, b->emitter_count);
    assert_true(a->emitter_power == b->emitter_power);
    assert_memory_equal(&a->environment, &b->environment, sizeof a->environment);
    assert_memory_equal(&a->eye, &b->eye, sizeof a->eye);
    assert_memory_equal(&a->target, &b->target, sizeof a->target);
    assert_memory_equal(&a->up, &b->up, sizeof a->up);
    assert_true(a->vertical_fov_degrees == b->vertical_fov_degrees);
}

/* A uniform point on triangle t. */
static inline vec3 point_on_triangle(const triangle *t, pcg32 *rng)
{
    float s = sqrtf(pcg32_float(rng)), u = pcg32_float(rng);
    float b1 = (1.0f - u) * s, b2 = u * s;
    return vec3_add(vec3_add(vec3_scale(t->p0, 1.0f - b1 - b2), vec3_scale(t->p1, b1)), vec3_scale(t->p2, b2));
}

/* The triangle's unit normal, from its winding. */
static inline vec3 triangle_normal(const triangle *t)
{
    return vec3_normalize(vec3_cross(vec3_sub(t->p1, t->p0), vec3_sub(t->p2, t->p0)));
}

/* Does any of the scene's spheres block r? */
static inline bool spheres_block(const pt_scene *sc, ray r)
{
    hit_record hit;
    for (int i = 0; i < sc->sphere_count; i++) {
        sphere shape = {sc->spheres[i].center, sc->spheres[i].radius};
        if (sphere_intersect(&shape, r, &hit))
            return true;
    }
    return false;
}

/* The scene of a scene file, as the chapter programs load it. */
static inline void load_pt_scene_file(pt_scene *sc, const char *path)
{
    scene_desc d;
    char err[SCENE_ERROR_SIZE];
    if (!scene_desc_load(&d, path, err, sizeof err))
        fail_msg("%s", err);
    if (!pt_scene_from_desc(sc, &d, "test", err, sizeof err))
        fail_msg("%s", err);
    scene_desc_free(&d);
}

#endif
