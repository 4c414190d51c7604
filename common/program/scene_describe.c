/* scene_describe.c -- a scene description made in code (scene_file.h): a
 * chapter's built-in scene as a scene file would give it, so that it can be
 * written out, hashed or read back the way a file is. Chapter 01's
 * scene_describe() and chapter 09's pt_scene_describe() build theirs with
 * these; each says only how its own materials and shapes map. */
#include <stdio.h>
#include <string.h>

#include "memory.h"
#include "scene_file.h"

void scene_desc_init_built_in(scene_desc *d, vec3 eye, vec3 target, vec3 up, float fov_degrees, vec3 background)
{
    scene_desc_init(d);
    snprintf(d->source, sizeof d->source, "built-in scene");
    d->has_camera = true;
    d->eye = eye;
    d->target = target;
    d->up = up;
    d->fov_degrees = fov_degrees;
    d->background = background;
}

void scene_desc_add_material(scene_desc *d, scene_material m)
{
    snprintf(m.name, sizeof m.name, "material%d", d->material_count);
    d->materials = memory_grow(d->materials, &d->material_capacity, d->material_count + 1, sizeof m);
    d->materials[d->material_count++] = m;
}

void scene_desc_add_shape(scene_desc *d, scene_shape s)
{
    d->shapes = memory_grow(d->shapes, &d->shape_capacity, d->shape_count + 1, sizeof s);
    d->shapes[d->shape_count++] = s;
}

void scene_desc_add_point_light(scene_desc *d, vec3 position, vec3 intensity)
{
    scene_light l;
    memset(&l, 0, sizeof l);
    l.kind = SCENE_LIGHT_POINT;
    l.position = position;
    l.intensity = intensity;
    d->lights = memory_grow(d->lights, &d->light_capacity, d->light_count + 1, sizeof l);
    d->lights[d->light_count++] = l;
}
