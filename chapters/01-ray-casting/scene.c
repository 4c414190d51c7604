#include "scene.h"

#include <stdlib.h>
#include <string.h>

#include "memory.h"

void scene_init(scene *sc)
{
    memset(sc, 0, sizeof *sc);
    sc->camera = (scene_camera){vec3_make(0, 0, 5), vec3_make(0, 0, 0), vec3_make(0, 1, 0), 40.0f};
}

void scene_free(scene *sc)
{
    free(sc->shapes);
    free(sc->materials);
    free(sc->lights);
    memset(sc, 0, sizeof *sc);
}

material material_blinn_phong(vec3 diffuse, vec3 specular, float shininess)
{
    material m = {0};
    m.kind = MATERIAL_BLINN_PHONG;
    m.diffuse = diffuse;
    m.specular = specular;
    m.shininess = shininess;
    m.ior = 1.0f;
    return m;
}

material material_mirror(void)
{
    material m = material_blinn_phong(vec3_splat(0.0f), vec3_splat(0.0f), 1.0f);
    m.kind = MATERIAL_MIRROR;
    return m;
}

material material_glass(float ior)
{
    material m = material_blinn_phong(vec3_splat(0.0f), vec3_splat(0.0f), 1.0f);
    m.kind = MATERIAL_GLASS;
    m.ior = ior;
    return m;
}

int scene_add_material(scene *sc, material m)
{
    sc->materials = memory_grow(sc->materials, &sc->material_capacity, sc->material_count + 1, sizeof m);
    sc->materials[sc->material_count] = m;
    return sc->material_count++;
}

static int scene_add_shape(scene *sc, shape s)
{
    sc->shapes = memory_grow(sc->shapes, &sc->shape_capacity, sc->shape_count + 1, sizeof s);
    sc->shapes[sc->shape_count] = s;
    return sc->shape_count++;
}

int scene_add_sphere(scene *sc, vec3 center, float radius, int material_id)
{
    shape s = {.kind = SHAPE_SPHERE, .material_id = material_id};
    s.as.sphere = (sphere){center, radius};
    return scene_add_shape(sc, s);
}

int scene_add_plane(scene *sc, vec3 point, vec3 normal, int material_id)
{
    shape s = {.kind = SHAPE_PLANE, .material_id = material_id};
    s.as.plane = (plane){point, vec3_normalize(normal)};
    return scene_add_shape(sc, s);
}

int scene_add_triangle(scene *sc, vec3 p0, vec3 p1, vec3 p2, int material_id)
{
    shape s = {.kind = SHAPE_TRIANGLE, .material_id = material_id};
    s.as.triangle = (triangle){p0, p1, p2};
    return scene_add_shape(sc, s);
}

int scene_add_torus(scene *sc, vec3 center, float major, float minor, int material_id)
{
    shape s = {.kind = SHAPE_IMPLICIT, .material_id = material_id};
    s.as.torus = (implicit_torus){center, major, minor};
    return scene_add_shape(sc, s);
}

void scene_add_point_light(scene *sc, vec3 position, vec3 intensity)
{
    sc->lights = memory_grow(sc->lights, &sc->light_capacity, sc->light_count + 1, sizeof(point_light));
    sc->lights[sc->light_count++] = (point_light){position, intensity};
}

bool shape_intersect(const shape *s, ray r, hit_record *hit)
{
    switch (s->kind) {
    case SHAPE_SPHERE:
        return sphere_intersect(&s->as.sphere, r, hit);
    case SHAPE_PLANE:
        return plane_intersect(&s->as.plane, r, hit);
    case SHAPE_TRIANGLE:
        return triangle_intersect(&s->as.triangle, r, hit);
    case SHAPE_IMPLICIT:
        return implicit_intersect(&s->as.torus, r, hit);
    }
    return false;
}

/* Closest hit: test every shape, and shrink the ray's t_max to each hit found,
 * so that later shapes only report hits closer than the best so far. */
bool scene_intersect(const scene *sc, ray r, hit_record *hit, ray_counters *counters)
{
    bool found = false;
    for (int i = 0; i < sc->shape_count; i++) {
        counters->primitive_tests++;
        if (shape_intersect(&sc->shapes[i], r, hit)) {
            found = true;
            r.t_max = hit->t;
            hit->shape_id = i;
            hit->material_id = sc->shapes[i].material_id;
        }
    }
    return found;
}

bool scene_occluded(const scene *sc, ray r, ray_counters *counters)
{
    hit_record ignored;
    for (int i = 0; i < sc->shape_count; i++) {
        counters->primitive_tests++;
        if (shape_intersect(&sc->shapes[i], r, &ignored))
            return true;
    }
    return false;
}

vec3 material_diffuse_at(const material *m, vec3 point)
{
    if (m->checker_size <= 0.0f)
        return m->diffuse;
    /* floor, not a cast to int: a cast truncates towards zero, which would
     * make the two squares either side of x = 0 the same colour. */
    long cell = (long)floorf(point.x / m->checker_size) + (long)floorf(point.z / m->checker_size);
    return (cell & 1) ? m->checker_diffuse : m->diffuse;
}

camera scene_make_camera(const scene *sc, int width, int height)
{
    return camera_look_at(sc->camera.eye, sc->camera.target, sc->camera.up, sc->camera.vertical_fov_degrees, width,
                          height);
}
