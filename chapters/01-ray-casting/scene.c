#include "01-ray-casting/scene.h"

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
        m = material_blinn_phong(sm->albedo, vec3_splat(0.0f), 1.0f);
        program_warn(label, d, sm->line, sm->column, "emissive '%s': shaded by its albedo; its triangles and quads "
                     "light the scene as point lights (below), its spheres do not", sm->name);
        break;
    default:
        /* A kind of the scene format's list that came after these chapters
         * (a BSDF of chapter 09's): shown by its albedo, and said, so that
         * a new kind is one row in the list and its BSDF, not a case here. */
        m = material_blinn_phong(sm->albedo, vec3_splat(0.0f), 1.0f);
        program_warn(label, d, sm->line, sm->column, "%s '%s': shown as diffuse with its albedo (chapter 09 renders it)",
                     scene_material_kind_name(sm->kind), sm->name);
        break;
    }
    snprintf(m.name, sizeof m.name, "%s", sm->name);
    return m;
}

/* Where add_mesh says what each MTL material became (NULL: nowhere). */
static FILE *material_report;
static bool material_report_set;

void scene_report_materials(FILE *out)
{
    material_report = out;
    material_report_set = true;
}

/* An emitter as chapters 01-02 light a scene: as they treat an area light, a
 * point light at its centre with intensity L_e x area, lifted off the
 * emitting surface along its front normal by this fraction of its size, so
 * that a shadow ray towards it does not end on the emitter's own triangles
 * (which would block it about half the time, by rounding). */
static const float EMITTER_LIGHT_LIFT = 1e-3f;

typedef struct {
    vec3 weighted_centre, normal; /* sums over the emitting triangles, weighted by area */
    float area;
} emitter_sum;

static void emitter_add(emitter_sum *e, vec3 p0, vec3 p1, vec3 p2)
{
    vec3 cross = vec3_cross(vec3_sub(p1, p0), vec3_sub(p2, p0));
    float area = 0.5f * vec3_length(cross);
    vec3 centre = vec3_scale(vec3_add(vec3_add(p0, p1), p2), 1.0f / 3.0f);
    e->weighted_centre = vec3_add(e->weighted_centre, vec3_scale(centre, area));
    e->normal = vec3_add(e->normal, vec3_scale(cross, 0.5f));
    e->area += area;
}

/* The point light of the emitter summed in e, if it has an area. */
static bool emitter_light(scene *sc, const emitter_sum *e, vec3 emission)
{
    if (!(e->area > 0.0f))
        return false;
    vec3 centre = vec3_scale(e->weighted_centre, 1.0f / e->area);
    vec3 lift = vec3_length(e->normal) > 0.0f ? vec3_normalize(e->normal) : vec3_splat(0.0f);
    scene_add_point_light(sc, vec3_add(centre, vec3_scale(lift, EMITTER_LIGHT_LIFT * sqrtf(e->area))),
                          vec3_scale(emission, e->area));
    return true;
}

/* An MTL material as chapters 01-02 shade it: glass where the MTL says light
 * passes through (illum 4, 6, 7, 9 or d < 1), else Blinn-Phong with k_d = Kd,
 * k_s = Ks, p = Ns. */
static material material_from_mtl(const mesh_material *mm, char *note, size_t note_size)
{
    material mat;
    if (mesh_material_transparent(mm)) {
        float ior = mm->ior > 1.0f ? mm->ior : 1.5f;
        mat = material_glass(ior);
        snprintf(note, note_size, "glass, ior %g", (double)ior);
    } else {
        mat = material_blinn_phong(mm->diffuse, mm->specular, fmaxf(1.0f, mm->shininess));
        snprintf(note, note_size, "Blinn-Phong, k_d %g %g %g, k_s %g %g %g, p %g%s", (double)mm->diffuse.x,
                 (double)mm->diffuse.y, (double)mm->diffuse.z, (double)mm->specular.x, (double)mm->specular.y,
                 (double)mm->specular.z, (double)mat.shininess, mm->ior > 1.0f ? "; Ni ignored (opaque)" : "");
    }
    snprintf(mat.name, sizeof mat.name, "%s", mm->name);
    return mat;
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
    FILE *out = material_report_set ? material_report : stdout;
    /* The MTL's materials; faces with none get a grey. */
    int first = sc->material_count;
    for (int i = 0; material_id < 0 && i < m.material_count; i++) {
        char note[256];
        scene_add_material(sc, material_from_mtl(&m.materials[i], note, sizeof note));
        if (out != NULL)
            fprintf(out, "%s: material '%s': %s\n", d->shapes[index].path, m.materials[i].name, note);
    }
    int grey = material_id;
    if (material_id < 0) {
        material mat = material_blinn_phong(vec3_splat(0.7f), vec3_splat(0.0f), 1.0f);
        snprintf(mat.name, sizeof mat.name, "mesh default grey");
        grey = scene_add_material(sc, mat);
    }
    emitter_sum *emitters = calloc((size_t)(m.material_count > 0 ? m.material_count : 1), sizeof *emitters);
    if (emitters == NULL) {
        snprintf(err, err_size, "out of memory");
        mesh_free(&m);
        return false;
    }
    for (int i = 0; i < m.face_count; i++) {
        int face_material = m.faces[i].material;
        int id = material_id >= 0 ? material_id : face_material >= 0 ? first + face_material : grey;
        vec3 p0 = mesh_vertex(&m, i, 0), p1 = mesh_vertex(&m, i, 1), p2 = mesh_vertex(&m, i, 2);
        scene_add_triangle(sc, p0, p1, p2, id);
        if (material_id < 0 && face_material >= 0 && mesh_material_emits(&m.materials[face_material]))
            emitter_add(&emitters[face_material], p0, p1, p2);
    }
    /* Each emitting material (Ke) of the mesh lights the scene. */
    for (int i = 0; i < m.material_count; i++)
        if (emitter_light(sc, &emitters[i], m.materials[i].emission) && out != NULL)
            fprintf(out, "%s: material '%s' emits (Ke): a point light of intensity Ke x area %g at its centre "
                    "(hard shadows; soft shadows are chapter 09)\n", d->shapes[index].path, m.materials[i].name,
                    (double)emitters[i].area);
    free(emitters);
    mesh_free(&m);
    return true;
}

/* Chapters 01-02 test every shape for every ray: beyond this many
 * triangles a render takes minutes where chapter 06's BVH takes seconds. */
enum { BRUTE_FORCE_TRIANGLES_WARN = 4096 };

/* What would make the picture wrong or slow, said before it is rendered:
 * no light at all (only the ambient term and the background remain), and
 * a mesh too large to test triangle by triangle. */
static void warn_before_rendering(const scene *sc, const scene_desc *d, const char *label)
{
    int triangles = 0, emissive_spheres = 0;
    for (int i = 0; i < sc->shape_count; i++)
        triangles += sc->shapes[i].kind == SHAPE_TRIANGLE;
    for (int i = 0; i < d->shape_count; i++)
        emissive_spheres += d->shapes[i].kind == SCENE_SHAPE_SPHERE && d->shapes[i].material >= 0 &&
                            d->materials[d->shapes[i].material].kind == SCENE_MATERIAL_EMISSIVE;
    if (sc->light_count == 0)
        program_warn(label, d, 0, 0, "no light: the picture shows only the ambient term and the background%s",
                     emissive_spheres > 0 ? " (emissive spheres do not light the scene here; chapter 09 samples them "
                                            "by the rays that hit them)"
                                          : "; add a point or area light, or an emissive quad");
    if (triangles > BRUTE_FORCE_TRIANGLES_WARN)
        program_warn(label, d, 0, 0, "%d triangles: this chapter tests every one for every ray (no acceleration "
                     "structure yet), which takes minutes; chapter 06 (06-bvh --scene ...) and chapter 09 trace them "
                     "through a BVH", triangles);
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
        case SCENE_SHAPE_QUAD: {
            emitter_sum e = {{0, 0, 0}, {0, 0, 0}, 0.0f};
            scene_add_triangle(sc, s->p[0], s->p[1], s->p[2], s->material);
            emitter_add(&e, s->p[0], s->p[1], s->p[2]);
            if (s->kind == SCENE_SHAPE_QUAD) {
                scene_add_triangle(sc, s->p[0], s->p[2], s->p[3], s->material);
                emitter_add(&e, s->p[0], s->p[2], s->p[3]);
            }
            const scene_material *sm = &d->materials[s->material];
            if (sm->kind == SCENE_MATERIAL_EMISSIVE && emitter_light(sc, &e, sm->emission))
                program_warn(label, d, s->line, s->column, "an emitting %s: lights the scene as a point light at its "
                             "centre with intensity L_e x area (hard shadows; soft shadows are chapter 09)",
                             s->kind == SCENE_SHAPE_QUAD ? "quad" : "triangle");
            break;
        }
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
    warn_before_rendering(sc, d, label);
    if (d->integrator[0] != '\0' && strcmp(d->integrator, "ray_casting") != 0 && strcmp(d->integrator, "whitted") != 0)
        program_warn(label, d, d->integrator_line, d->integrator_column,
                     "integrator '%s' is not one of chapters 01-02 (ray_casting, whitted): ignored", d->integrator);
    return true;
}

void scene_describe(const scene *sc, scene_desc *d)
{
    scene_desc_init_built_in(d, sc->camera.eye, sc->camera.target, sc->camera.up, sc->camera.vertical_fov_degrees,
                             sc->background);
    d->ambient = sc->ambient;
    for (int i = 0; i < sc->material_count; i++) {
        const material *m = &sc->materials[i];
        scene_material sm;
        memset(&sm, 0, sizeof sm);
        sm.kind = m->kind == MATERIAL_MIRROR  ? SCENE_MATERIAL_MIRROR
                  : m->kind == MATERIAL_GLASS ? SCENE_MATERIAL_GLASS
                                              : SCENE_MATERIAL_BLINN_PHONG;
        sm.albedo = m->diffuse;
        sm.specular = m->specular;
        sm.shininess = m->shininess;
        sm.ior = m->ior;
        scene_desc_add_material(d, sm);
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
        scene_desc_add_shape(d, ss);
    }
    for (int i = 0; i < sc->light_count; i++)
        scene_desc_add_point_light(d, sc->lights[i].position, sc->lights[i].intensity);
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
