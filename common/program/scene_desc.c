/* scene_desc.c -- a scene description once read (scene_file.h): made
 * empty and freed, its meshes loaded, where a statement was, the names of
 * its kinds. The parser that fills it is scene_file.c. */
#include "obj.h"
#include "scene_file.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void scene_desc_init(scene_desc *d)
{
    memset(d, 0, sizeof *d);
    d->up = vec3_make(0, 1, 0);
    d->fov_degrees = 40.0f;
    d->max_depth = -1;
    d->effects_allowed = EFFECT_ALL;
}

void scene_desc_free(scene_desc *d)
{
    free(d->materials);
    free(d->lights);
    for (int i = 0; i < d->shape_count; i++)
        free(d->shapes[i].path);
    free(d->shapes);
    scene_desc_init(d);
}

bool scene_desc_load_mesh(const scene_desc *d, int index, mesh *m, char *err, size_t err_size)
{
    const scene_shape *s = &d->shapes[index];
    if (s->kind == SCENE_SHAPE_MESH_TORI) {
        mesh_tori_field(m, s->triangles);
        return true;
    }
    if (s->kind != SCENE_SHAPE_MESH_OBJ) {
        snprintf(err, err_size, "%s:%d:%d: not a mesh", d->source, s->line, s->column);
        return false;
    }
    char why[MESH_ERROR_SIZE];
    int first_face = m->face_count, first_position = m->position_count, first_material = m->material_count;
    int first_normal = m->normal_count, first_texcoord = m->texcoord_count;
    if (!mesh_load_obj(m, s->path, why, sizeof why)) {
        snprintf(err, err_size, "%s:%d:%d: mesh: %s", d->source, s->line, s->column, why);
        return false;
    }
    /* A mesh given an emitting material is a light: like an emitting quad,
     * it must have area somewhere (a triangle without area among others
     * with area is harmless: it is never sampled). */
    if (s->material >= 0 && scene_material_emits(&d->materials[s->material])) {
        bool has_area = false;
        for (int i = first_face; i < m->face_count && !has_area; i++) {
            vec3 p[3] = {mesh_vertex(m, i, 0), mesh_vertex(m, i, 1), mesh_vertex(m, i, 2)};
            has_area = scene_corners_have_area(p);
        }
        if (!has_area) {
            snprintf(err, err_size, "%s:%d:%d: mesh: %s: emits light (material '%s') but no triangle of it has area",
                     d->source, s->line, s->column, s->path, d->materials[s->material].name);
            /* m as it was before the call, as on any other failure. */
            m->face_count = first_face;
            m->position_count = first_position;
            m->material_count = first_material;
            m->normal_count = first_normal;
            m->texcoord_count = first_texcoord;
            return false;
        }
    }
    return true;
}

void scene_desc_where(const scene_desc *d, int line, int column, char *out, size_t out_size)
{
    snprintf(out, out_size, "%s:%d:%d", d->source, line, column);
}

const char *scene_material_kind_name(scene_material_kind k)
{
    static const char *const names[] = {
#define SCENE_MATERIAL_NAME(id, keyword, ...) keyword,
        SCENE_MATERIAL_KINDS(SCENE_MATERIAL_NAME)
#undef SCENE_MATERIAL_NAME
    };
    return (unsigned)k < SCENE_MATERIAL_KIND_COUNT ? names[k] : "?";
}

const char *scene_shape_kind_name(scene_shape_kind k)
{
    static const char *const names[] = {"sphere", "plane", "triangle", "quad", "implicit torus", "mesh", "mesh"};
    return (unsigned)k < 7 ? names[k] : "?";
}
