#include "scene.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "effects.h"
#include "memory.h"
#include "program.h"

void scene_init(scene *sc)
{
    memset(sc, 0, sizeof *sc);
    sc->camera = (scene_camera){vec3_make(0, 0, 5), vec3_make(0, 0, 0), vec3_make(0, 1, 0), 40.0f};
    sc->effects = EFFECT_ALL;
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
        /* The watertight test, not the lecture's Moller-Trumbore
         * (triangle_intersect()): triangles that share an edge must not let
         * a ray through between them (shapes.h). */
        return triangle_intersect_watertight_hit(&s->as.triangle, r, hit);
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

const char *shape_kind_name(shape_kind k)
{
    static const char *const names[] = {"sphere", "plane", "triangle", "implicit torus"};
    return (unsigned)k < 4 ? names[k] : "?";
}

const char *material_kind_name(material_kind k)
{
    static const char *const names[] = {"blinn_phong", "mirror", "glass"};
    return (unsigned)k < 3 ? names[k] : "?";
}

/* ---- from a scene file ---------------------------------------------------- */

static material material_from_desc(const scene_desc *d, const scene_material *sm, const char *label)
{
    material m;
    switch (sm->kind) {
    case SCENE_MATERIAL_BLINN_PHONG:
        m = material_blinn_phong(sm->albedo, sm->specular, sm->shininess);
        m.checker_diffuse = sm->checker;
        m.checker_size = sm->checker_size;
        break;
    case SCENE_MATERIAL_DIFFUSE:
        /* Lambert's term is Blinn-Phong's diffuse term: k_d = albedo. */
        m = material_blinn_phong(sm->albedo, vec3_splat(0.0f), 1.0f);
        break;
    case SCENE_MATERIAL_MIRROR:
        m = material_mirror();
        if (sm->albedo.x != 1.0f || sm->albedo.y != 1.0f || sm->albedo.z != 1.0f)
            program_warn(label, d, sm->line, sm->column, "mirror '%s': the tint (albedo) is not shown, mirrors here "
                         "reflect everything", sm->name);
        break;
    case SCENE_MATERIAL_GLASS:
        m = material_glass(sm->ior);
        if (sm->albedo.x != 1.0f || sm->albedo.y != 1.0f || sm->albedo.z != 1.0f)
            program_warn(label, d, sm->line, sm->column, "glass '%s': the tint (albedo) is not shown", sm->name);
        break;
    case SCENE_MATERIAL_GLOSSY: {
        /* Blinn-Phong's lobe is close to a Beckmann microfacet lobe with
         * p = 2 / alpha^2 - 2 (Walter et al. 2007): the nearest thing here. */
        float a = sm->roughness;
        m = material_blinn_phong(vec3_splat(0.0f), sm->albedo, fmaxf(1.0f, 2.0f / (a * a) - 2.0f));
        program_warn(label, d, sm->line, sm->column, "glossy '%s': shown as a Blinn-Phong highlight (k_s = albedo, "
                     "p = %.0f); it does not reflect other surfaces here", sm->name, (double)m.shininess);
        break;
    }
    case SCENE_MATERIAL_EMISSIVE:
    default:
        m = material_blinn_phong(sm->albedo, vec3_splat(0.0f), 1.0f);
        program_warn(label, d, sm->line, sm->column, "emissive '%s': shaded by its albedo, but it does not glow: "
                     "only point lights give light here", sm->name);
        break;
    }
    snprintf(m.name, sizeof m.name, "%s", sm->name);
    return m;
}

static bool add_mesh(scene *sc, const scene_desc *d, int index, char *err, size_t err_size)
{
    mesh m;
    mesh_init(&m);
    if (!scene_desc_load_mesh(d, index, &m, err, err_size)) {
        mesh_free(&m);
        return false;
    }
    int material_id = d->shapes[index].material;
    /* The MTL's colours as Blinn-Phong materials (Kd, Ks, Ns); faces with
     * none get a grey. */
    int first = sc->material_count;
    for (int i = 0; material_id < 0 && i < m.material_count; i++) {
        const mesh_material *mm = &m.materials[i];
        material mat = material_blinn_phong(mm->diffuse, mm->specular, fmaxf(1.0f, mm->shininess));
        snprintf(mat.name, sizeof mat.name, "%s", mm->name);
        scene_add_material(sc, mat);
    }
    int grey = material_id;
    if (material_id < 0) {
        material mat = material_blinn_phong(vec3_splat(0.7f), vec3_splat(0.0f), 1.0f);
        snprintf(mat.name, sizeof mat.name, "mesh default grey");
        grey = scene_add_material(sc, mat);
    }
    for (int i = 0; i < m.face_count; i++) {
        int face_material = m.faces[i].material;
        int id = material_id >= 0 ? material_id : face_material >= 0 ? first + face_material : grey;
        scene_add_triangle(sc, mesh_vertex(&m, i, 0), mesh_vertex(&m, i, 1), mesh_vertex(&m, i, 2), id);
    }
    mesh_free(&m);
    return true;
}

bool scene_from_desc(scene *sc, const scene_desc *d, const char *label, char *err, size_t err_size)
{
    scene_init(sc);
    if (d->has_camera)
        sc->camera = (scene_camera){d->eye, d->target, d->up, d->fov_degrees};
    sc->background = d->background;
    sc->ambient = d->ambient;
    /* Scene materials first, in order, so a shape's index is the same here. */
    for (int i = 0; i < d->material_count; i++)
        scene_add_material(sc, material_from_desc(d, &d->materials[i], label));
    for (int i = 0; i < d->light_count; i++) {
        const scene_light *l = &d->lights[i];
        if (l->kind == SCENE_LIGHT_POINT) {
            scene_add_point_light(sc, l->position, l->intensity);
            continue;
        }
        vec3 e1 = vec3_sub(l->corners[1], l->corners[0]), e2 = vec3_sub(l->corners[2], l->corners[0]);
        vec3 e3 = vec3_sub(l->corners[3], l->corners[0]);
        float area = 0.5f * (vec3_length(vec3_cross(e1, e2)) + vec3_length(vec3_cross(e2, e3)));
        vec3 centre = vec3_scale(vec3_add(vec3_add(l->corners[0], l->corners[1]), vec3_add(l->corners[2], l->corners[3])),
                                 0.25f);
        program_warn(label, d, l->line, l->column, "area light: replaced by a point light at its centre with "
                     "intensity L_e x area (hard shadows; soft shadows are chapter 09)");
        scene_add_point_light(sc, centre, vec3_scale(l->emission, area));
    }
    for (int i = 0; i < d->shape_count; i++) {
        const scene_shape *s = &d->shapes[i];
        switch (s->kind) {
        case SCENE_SHAPE_SPHERE:
            scene_add_sphere(sc, s->center, s->radius, s->material);
            break;
        case SCENE_SHAPE_PLANE:
            scene_add_plane(sc, s->point, s->normal, s->material);
            break;
        case SCENE_SHAPE_TRIANGLE:
            scene_add_triangle(sc, s->p[0], s->p[1], s->p[2], s->material);
            break;
        case SCENE_SHAPE_QUAD:
            scene_add_triangle(sc, s->p[0], s->p[1], s->p[2], s->material);
            scene_add_triangle(sc, s->p[0], s->p[2], s->p[3], s->material);
            break;
        case SCENE_SHAPE_TORUS:
            scene_add_torus(sc, s->center, s->major, s->minor, s->material);
            break;
        case SCENE_SHAPE_MESH_OBJ:
        case SCENE_SHAPE_MESH_TORI:
            if (!add_mesh(sc, d, i, err, err_size)) {
                scene_free(sc);
                return false;
            }
            break;
        }
    }
    if (d->integrator[0] != '\0' && strcmp(d->integrator, "ray_casting") != 0 && strcmp(d->integrator, "whitted") != 0)
        program_warn(label, d, d->integrator_line, d->integrator_column,
                     "integrator '%s' is not one of chapters 01-02 (ray_casting, whitted): ignored", d->integrator);
    return true;
}

void scene_describe(const scene *sc, scene_desc *d)
{
    scene_desc_init(d);
    snprintf(d->source, sizeof d->source, "built-in scene");
    d->has_camera = true;
    d->eye = sc->camera.eye;
    d->target = sc->camera.target;
    d->up = sc->camera.up;
    d->fov_degrees = sc->camera.vertical_fov_degrees;
    d->background = sc->background;
    d->ambient = sc->ambient;
    for (int i = 0; i < sc->material_count; i++) {
        const material *m = &sc->materials[i];
        scene_material sm;
        memset(&sm, 0, sizeof sm);
        snprintf(sm.name, sizeof sm.name, "material%d", i);
        sm.kind = m->kind == MATERIAL_MIRROR  ? SCENE_MATERIAL_MIRROR
                  : m->kind == MATERIAL_GLASS ? SCENE_MATERIAL_GLASS
                                              : SCENE_MATERIAL_BLINN_PHONG;
        sm.albedo = m->diffuse;
        sm.specular = m->specular;
        sm.shininess = m->shininess;
        sm.ior = m->ior;
        d->materials = memory_grow(d->materials, &d->material_capacity, d->material_count + 1, sizeof sm);
        d->materials[d->material_count++] = sm;
    }
    for (int i = 0; i < sc->shape_count; i++) {
        const shape *s = &sc->shapes[i];
        scene_shape ss;
        memset(&ss, 0, sizeof ss);
        ss.material = s->material_id;
        switch (s->kind) {
        case SHAPE_SPHERE:
            ss.kind = SCENE_SHAPE_SPHERE;
            ss.center = s->as.sphere.center;
            ss.radius = s->as.sphere.radius;
            break;
        case SHAPE_PLANE:
            ss.kind = SCENE_SHAPE_PLANE;
            ss.point = s->as.plane.point;
            ss.normal = s->as.plane.normal;
            break;
        case SHAPE_TRIANGLE:
            ss.kind = SCENE_SHAPE_TRIANGLE;
            ss.p[0] = s->as.triangle.p0;
            ss.p[1] = s->as.triangle.p1;
            ss.p[2] = s->as.triangle.p2;
            break;
        case SHAPE_IMPLICIT:
            ss.kind = SCENE_SHAPE_TORUS;
            ss.center = s->as.torus.center;
            ss.major = s->as.torus.major;
            ss.minor = s->as.torus.minor;
            break;
        }
        d->shapes = memory_grow(d->shapes, &d->shape_capacity, d->shape_count + 1, sizeof ss);
        d->shapes[d->shape_count++] = ss;
    }
    for (int i = 0; i < sc->light_count; i++) {
        scene_light l;
        memset(&l, 0, sizeof l);
        l.kind = SCENE_LIGHT_POINT;
        l.position = sc->lights[i].position;
        l.intensity = sc->lights[i].intensity;
        d->lights = memory_grow(d->lights, &d->light_capacity, d->light_count + 1, sizeof l);
        d->lights[d->light_count++] = l;
    }
}

int scene_load_for_program(scene *sc, scene_desc *desc, cli_options *opts, const char *program,
                           void (*build_built_in)(scene *), unsigned supported)
{
    if (program_load_scene(opts, program, desc)) {
        char err[SCENE_ERROR_SIZE];
        if (!scene_from_desc(sc, desc, program, err, sizeof err)) {
            fprintf(stderr, "%s: %s\n", program, err);
            scene_desc_free(desc);
            return 1;
        }
    } else {
        build_built_in(sc);
        scene_describe(sc, desc);
    }
    /* The effects analysis, on the file or on the built-in scene alike. */
    effects_report e = effects_analyse(desc);
    sc->effects = effects_decide(&e, supported);
    if (!opts->quiet)
        effects_print(stdout, &e, program);
    program_note_effects(&e);
    return 0;
}
