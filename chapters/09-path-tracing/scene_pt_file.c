/* scene_pt_file.c -- a scene file's description as the path tracer's scene. */
#include <stdio.h>
#include <string.h>

#include "09-path-tracing/bsdf.h"
#include "09-path-tracing/scene_pt.h"
#include "memory.h"
#include "program.h"

cli_choice pt_builtin_scene_choice(const pt_builtin_scene *table, int count, const char **names, const char **notes)
{
    for (int k = 0; k < count; k++) {
        names[k] = table[k].name;
        notes[k] = table[k].description;
    }
    names[count] = NULL;
    return (cli_choice){names, notes, 0};
}

/* A scene file's material as the path tracer's: Blinn-Phong as diffuse
 * (with a word), emissive as a diffuse emitter, and every other kind as the
 * BSDF it is (bsdf.c's table says how). */
static pt_material material_from_desc(const scene_desc *d, const scene_material *sm, const char *label)
{
    bsdf_kind k;
    if (sm->kind == SCENE_MATERIAL_BLINN_PHONG) {
        program_warn(label, d, sm->line, sm->column,
                     "blinn_phong '%s': rendered as diffuse with albedo k_d%s; Blinn-Phong is not energy-conserving, "
                     "use glossy for a highlight", sm->name, sm->checker_size > 0 ? " (the checkerboard is not shown)" : "");
        return pt_diffuse(sm->albedo);
    }
    if (sm->kind == SCENE_MATERIAL_EMISSIVE)
        return pt_emitter(sm->albedo, sm->emission);
    if (bsdf_kind_of_scene_kind(sm->kind, &k))
        return bsdf_material_from_scene(k, sm);
    /* not reached: a kind of the list that is neither of the two above nor a
     * BSDF (bsdf_kinds.h) would need a way here; test_ch09 holds every kind */
    program_warn(label, d, sm->line, sm->column, "%s '%s': not a BSDF of this chapter's, rendered as diffuse",
                 scene_material_kind_name(sm->kind), sm->name);
    return pt_diffuse(sm->albedo);
}

static bool add_mesh(pt_scene *sc, const scene_desc *d, int index, char *err, size_t err_size)
{
    mesh m;
    mesh_init(&m);
    if (!scene_desc_load_mesh(d, index, &m, err, err_size)) {
        mesh_free(&m);
        return false;
    }
    int material_id = d->shapes[index].material;
    /* The MTL's materials as pt_scene_load_obj reads them. */
    int first = sc->material_count;
    if (material_id < 0)
        pt_scene_add_mtl_materials(sc, &m, d->shapes[index].path);
    int grey = material_id >= 0 ? material_id : pt_scene_add_material(sc, pt_diffuse(vec3_splat(0.7f)));
    for (int i = 0; i < m.face_count; i++) {
        int face_material = m.faces[i].material;
        int id = material_id >= 0 ? material_id : face_material >= 0 ? first + face_material : grey;
        pt_scene_add_triangle(sc, mesh_vertex(&m, i, 0), mesh_vertex(&m, i, 1), mesh_vertex(&m, i, 2), id);
    }
    mesh_free(&m);
    return true;
}

bool pt_scene_from_desc(pt_scene *sc, const scene_desc *d, const char *label, char *err, size_t err_size)
{
    pt_scene_init(sc);
    if (!d->has_camera) {
        snprintf(err, err_size, "%s: no camera statement (the path tracer needs one: camera eye .. target ..)",
                 d->source);
        pt_scene_free(sc);
        return false;
    }
    sc->eye = d->eye;
    sc->target = d->target;
    sc->up = d->up;
    sc->vertical_fov_degrees = d->fov_degrees;
    sc->environment = d->background;
    if (d->ambient.x > 0.0f || d->ambient.y > 0.0f || d->ambient.z > 0.0f)
        program_warn(label, d, 0, 0, "ambient is ignored: the path tracer computes indirect light itself");
    /* Scene materials first, in order, so a shape's index means the same here. */
    for (int i = 0; i < d->material_count; i++)
        pt_scene_add_material(sc, material_from_desc(d, &d->materials[i], label));
    for (int i = 0; i < d->shape_count; i++) {
        const scene_shape *s = &d->shapes[i];
        switch (s->kind) {
        case SCENE_SHAPE_SPHERE:
            pt_scene_add_sphere(sc, s->center, s->radius, s->material, s->inside_out);
            break;
        case SCENE_SHAPE_TRIANGLE:
            pt_scene_add_triangle(sc, s->p[0], s->p[1], s->p[2], s->material);
            break;
        case SCENE_SHAPE_QUAD:
            pt_scene_add_quad(sc, s->p[0], s->p[1], s->p[2], s->p[3], s->material);
            break;
        case SCENE_SHAPE_MESH_OBJ:
        case SCENE_SHAPE_MESH_TORI:
            if (!add_mesh(sc, d, i, err, err_size)) {
                pt_scene_free(sc);
                return false;
            }
            break;
        case SCENE_SHAPE_PLANE:
        case SCENE_SHAPE_TORUS:
            snprintf(err, err_size, "%s:%d:%d: the path tracer intersects triangles, quads, meshes and spheres "
                     "only, not %s (an infinite plane: use a large quad)", d->source, s->line, s->column,
                     scene_shape_kind_name(s->kind));
            pt_scene_free(sc);
            return false;
        }
    }
    /* Lights after the shapes: an area light is an emitting quad (black, so
     * it only emits), sampled by area like every emitting triangle. */
    for (int i = 0; i < d->light_count; i++) {
        const scene_light *l = &d->lights[i];
        if (l->kind == SCENE_LIGHT_POINT) {
            pt_scene_add_point_light(sc, l->position, l->intensity);
        } else {
            int m = pt_scene_add_material(sc, pt_emitter(vec3_splat(0.0f), l->emission));
            pt_scene_add_quad(sc, l->corners[0], l->corners[1], l->corners[2], l->corners[3], m);
        }
    }
    pt_scene_finish(sc);
    return true;
}

void pt_scene_describe(const pt_scene *sc, scene_desc *d)
{
    scene_desc_init_built_in(d, sc->eye, sc->target, sc->up, sc->vertical_fov_degrees, sc->environment);
    for (int i = 0; i < sc->material_count; i++) {
        const pt_material *m = &sc->materials[i];
        scene_material sm;
        memset(&sm, 0, sizeof sm);
        bool emits = m->emission.x > 0.0f || m->emission.y > 0.0f || m->emission.z > 0.0f;
        sm.kind = m->kind == BSDF_DIFFUSE && emits ? SCENE_MATERIAL_EMISSIVE : bsdf_kind_scene_kind(m->kind);
        sm.albedo = m->albedo;
        sm.emission = m->emission;
        sm.roughness = m->roughness;
        sm.ior = m->ior;
        scene_desc_add_material(d, sm);
    }
    /* One shape per triangle: for a mesh of a million, a gigabyte of
     * descriptions (each has room for a path), so the array is made once
     * at its size, not grown, and filled by every thread: most of the time
     * goes to the system clearing the new pages, which threads do side by
     * side. Each shape is its own, so the description does not depend on
     * the thread count. */
    int shapes = sc->geometry.face_count + sc->sphere_count, first = d->shape_count;
    d->shapes = memory_grow(d->shapes, &d->shape_capacity, first + shapes, sizeof *d->shapes);
    d->shape_count += shapes;
#pragma omp parallel for schedule(static) if (shapes >= 4096)
    for (int i = 0; i < shapes; i++) {
        scene_shape s;
        memset(&s, 0, sizeof s);
        if (i < sc->geometry.face_count) {
            s.kind = SCENE_SHAPE_TRIANGLE;
            for (int k = 0; k < 3; k++)
                s.p[k] = mesh_vertex(&sc->geometry, i, k);
            s.material = sc->geometry.faces[i].material;
        } else {
            const pt_sphere *sp = &sc->spheres[i - sc->geometry.face_count];
            s.kind = SCENE_SHAPE_SPHERE;
            s.center = sp->center;
            s.radius = sp->radius;
            s.inside_out = sp->inside_out;
            s.material = sp->material;
        }
        d->shapes[first + i] = s;
    }
    for (int i = 0; i < sc->point_light_count; i++)
        scene_desc_add_point_light(d, sc->point_lights[i].position, sc->point_lights[i].intensity);
}
