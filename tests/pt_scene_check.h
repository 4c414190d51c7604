/* pt_scene_check.h -- a scene file against the built-in scene it claims to
 * be: the same triangles bit for bit, in the same order, with the same
 * materials, the same spheres, lights, environment and camera. Then every
 * render of the two is the same, bit for bit, whatever the method.
 *
 *   assert_same_pt_scene(&from_file, &built_in);
 */
#ifndef PT_SCENE_CHECK_H
#define PT_SCENE_CHECK_H

#include <string.h>

#include "09-path-tracing/scene_pt.h"

static void assert_same_material(const pt_material *a, const pt_material *b)
{
    assert_int_equal(a->kind, b->kind);
    assert_memory_equal(&a->albedo, &b->albedo, sizeof a->albedo);
    assert_memory_equal(&a->emission, &b->emission, sizeof a->emission);
    assert_true(a->roughness == b->roughness && a->ior == b->ior);
}

static void assert_same_pt_scene(const pt_scene *a, const pt_scene *b)
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

/* The scene of a scene file, as the chapter programs load it. */
static void load_pt_scene_file(pt_scene *sc, const char *path)
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
