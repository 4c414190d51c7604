/* scene_mesh.c -- what chapters 03-06 take from a scene file: triangles and
 * the camera (see accel_program.h). */
#include <stdio.h>
#include <stdlib.h>

#include "03-aabb-slabs/accel_program.h"
#include "03-aabb-slabs/accel_view.h"
#include "memory.h"
#include "program.h"

/* The tori field is built torus after torus, each with the same number of
 * triangles (mesh.h). */
enum { TORI_IN_FIELD = 16 };

bool accel_mesh_from_desc(mesh *m, const scene_desc *d, const char *label, int **object_first, int *object_count,
                          char *err, size_t err_size)
{
    mesh out;
    mesh_init(&out);
    int *first = NULL, capacity = 0, count = 0;
    for (int i = 0; i < d->shape_count; i++) {
        const scene_shape *s = &d->shapes[i];
        int before = out.face_count;
        switch (s->kind) {
        case SCENE_SHAPE_TRIANGLE:
        case SCENE_SHAPE_QUAD: {
            int a = mesh_add_position(&out, s->p[0]), b = mesh_add_position(&out, s->p[1]);
            int c = mesh_add_position(&out, s->p[2]);
            mesh_add_triangle(&out, a, b, c, -1);
            if (s->kind == SCENE_SHAPE_QUAD)
                mesh_add_triangle(&out, a, c, mesh_add_position(&out, s->p[3]), -1);
            break;
        }
        case SCENE_SHAPE_MESH_OBJ:
        case SCENE_SHAPE_MESH_TORI:
            if (!scene_desc_load_mesh(d, i, &out, err, err_size)) {
                mesh_free(&out);
                free(first);
                return false;
            }
            break;
        case SCENE_SHAPE_SPHERE:
        case SCENE_SHAPE_PLANE:
        case SCENE_SHAPE_TORUS:
            program_warn(label, d, s->line, s->column,
                         "%s ignored: this chapter's acceleration structures hold triangles only",
                         scene_shape_kind_name(s->kind));
            continue;
        }
        /* One object per statement; the tori field, one per torus. */
        int pieces = s->kind == SCENE_SHAPE_MESH_TORI && (out.face_count - before) % TORI_IN_FIELD == 0 ? TORI_IN_FIELD : 1;
        for (int k = 0; k < pieces; k++) {
            first = memory_grow(first, &capacity, count + 2, sizeof *first);
            first[count++] = before + k * ((out.face_count - before) / pieces);
        }
    }
    if (out.face_count == 0) {
        snprintf(err, err_size, "%s: no triangles (this chapter renders triangle, quad and mesh shapes)", d->source);
        mesh_free(&out);
        free(first);
        return false;
    }
    if (d->light_count > 0 || d->material_count > 0)
        program_warn(label, d, 0, 0, "lights and materials ignored: this chapter shows the triangles lit by a "
                     "headlight (or, with --heatmap, what each ray cost)");
    if (d->effects_allowed != EFFECT_ALL || d->integrator[0] != '\0')
        program_warn(label, d, 0, 0, "effects and integrator ignored: this chapter casts camera rays only");

    /* Append to m: positions, vertex normals (the headlight shades with
     * them, as with --obj) and faces, with indices shifted. */
    int base_position = m->position_count, base_normal = m->normal_count, base_face = m->face_count;
    for (int i = 0; i < out.position_count; i++)
        mesh_add_position(m, out.positions[i]);
    for (int i = 0; i < out.normal_count; i++)
        mesh_add_normal(m, out.normals[i]);
    for (int i = 0; i < out.face_count; i++) {
        const mesh_face *f = &out.faces[i];
        mesh_add_triangle(m, base_position + f->position[0], base_position + f->position[1],
                          base_position + f->position[2], -1);
        for (int k = 0; k < 3; k++)
            m->faces[m->face_count - 1].normal[k] = f->normal[k] >= 0 ? base_normal + f->normal[k] : -1;
    }
    mesh_free(&out);
    first[count] = m->face_count;
    for (int k = 0; k < count; k++)
        first[k] += base_face;
    if (object_first != NULL)
        *object_first = first;
    else
        free(first);
    if (object_count != NULL)
        *object_count = count;
    return true;
}

camera accel_scene_camera(const scene_desc *d, aabb bounds, int width, int height)
{
    if (d->has_camera)
        return camera_look_at(d->eye, d->target, d->up, d->fov_degrees, width, height);
    return accel_view_camera(bounds, width, height);
}
