/* scene_pt.c -- the path tracer's scenes. */
#include "09-path-tracing/scene_pt.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "04-uniform-grid/grid.h"
#include "05-kd-tree/kdtree.h"
#include "06-bvh/bvh.h"
#include "09-path-tracing/bsdf.h"
#include "memory.h"
#include "obj.h"

void pt_scene_init(pt_scene *sc)
{
    memset(sc, 0, sizeof *sc);
    mesh_init(&sc->geometry);
    sc->up = vec3_make(0, 1, 0);
    sc->vertical_fov_degrees = 40.0f;
}

void pt_scene_free(pt_scene *sc)
{
    accel_destroy(sc->bvh);
    triangle_set_free(&sc->triangles);
    mesh_free(&sc->geometry);
    free(sc->spheres);
    free(sc->materials);
    free(sc->point_lights);
    free(sc->emitters);
    free(sc->emitter_normals);
    free(sc->emitter_cdf);
    memset(sc, 0, sizeof *sc);
}

pt_material pt_diffuse(vec3 albedo) { return (pt_material){BSDF_DIFFUSE, albedo, vec3_splat(0.0f), 1.0f, 1.0f}; }

pt_material pt_emitter(vec3 albedo, vec3 emission)
{
    pt_material m = pt_diffuse(albedo);
    m.emission = emission;
    return m;
}

pt_material pt_glossy(vec3 f0, float roughness) { return (pt_material){BSDF_GLOSSY, f0, vec3_splat(0.0f), roughness, 1.0f}; }

pt_material pt_glass(float ior) { return (pt_material){BSDF_GLASS, vec3_splat(1.0f), vec3_splat(0.0f), 0.0f, ior}; }

pt_material pt_mirror(vec3 albedo) { return (pt_material){BSDF_MIRROR, albedo, vec3_splat(0.0f), 0.0f, 1.0f}; }

int pt_scene_add_material(pt_scene *sc, pt_material m)
{
    sc->materials = memory_grow(sc->materials, &sc->material_capacity, sc->material_count + 1, sizeof m);
    sc->materials[sc->material_count] = m;
    return sc->material_count++;
}

void pt_scene_add_triangle(pt_scene *sc, vec3 p0, vec3 p1, vec3 p2, int material)
{
    int a = mesh_add_position(&sc->geometry, p0), b = mesh_add_position(&sc->geometry, p1);
    int c = mesh_add_position(&sc->geometry, p2);
    mesh_add_triangle(&sc->geometry, a, b, c, material);
}

void pt_scene_add_quad(pt_scene *sc, vec3 p0, vec3 p1, vec3 p2, vec3 p3, int material)
{
    pt_scene_add_triangle(sc, p0, p1, p2, material);
    pt_scene_add_triangle(sc, p0, p2, p3, material);
}

void pt_scene_add_sphere(pt_scene *sc, vec3 center, float radius, int material, bool inside_out)
{
    sc->spheres = memory_grow(sc->spheres, &sc->sphere_capacity, sc->sphere_count + 1, sizeof(pt_sphere));
    sc->spheres[sc->sphere_count++] = (pt_sphere){center, radius, material, inside_out};
}

void pt_scene_add_point_light(pt_scene *sc, vec3 position, vec3 intensity)
{
    sc->point_lights = memory_grow(sc->point_lights, &sc->point_light_capacity, sc->point_light_count + 1,
                                   sizeof(pt_point_light));
    sc->point_lights[sc->point_light_count++] = (pt_point_light){position, intensity};
}

/* ---- the acceleration structure ---------------------------------------------
 * pt_scene_intersect() and pt_scene_occluded() are the only places that
 * trace the triangles, and they do it through chapter 03's interface, so
 * any structure of chapters 03-06 can stand here. The default is chapter
 * 06's BVH with the binned SAH: change it, and chapter 09's counters move. */
static accel *build_brute(const triangle_set *set, const void *context)
{
    (void)context;
    return brute_force_build(set);
}

static accel *build_grid(const triangle_set *set, const void *context)
{
    (void)context;
    return grid_build(set, GRID_DEFAULT_DENSITY);
}

static accel *build_kdtree(const triangle_set *set, const void *context)
{
    (void)context;
    return kdtree_build(set);
}

static accel *build_bvh(const triangle_set *set, const void *context)
{
    (void)context;
    return bvh_build(set, BVH_SPLIT_SAH);
}

const char *const PT_ACCEL_NAMES[] = {"bvh", "kdtree", "grid", "brute", NULL};
static const pt_accel_builder accel_builders[] = {build_bvh, build_kdtree, build_grid, build_brute};

pt_accel_builder pt_accel_builder_named(const char *name)
{
    for (int i = 0; PT_ACCEL_NAMES[i] != NULL; i++)
        if (strcmp(name, PT_ACCEL_NAMES[i]) == 0)
            return accel_builders[i];
    return NULL;
}

void pt_scene_use_accel(pt_scene *sc, pt_accel_builder build, const void *context)
{
    accel_destroy(sc->bvh);
    sc->bvh = build(&sc->triangles, context);
}

/* How bright an emitter is, for choosing which light to sample: the mean of
 * L_e's channels (positive whenever any channel is). */
static double emitter_weight(vec3 le) { return ((double)le.x + (double)le.y + (double)le.z) / 3.0; }

static pt_accel_builder finish_builder = build_bvh;
void pt_scene_finish_builds(pt_accel_builder build) { finish_builder = build; }

void pt_scene_finish(pt_scene *sc)
{
    triangle_set_from_mesh(&sc->triangles, &sc->geometry);
    sc->bvh = finish_builder != NULL ? finish_builder(&sc->triangles, NULL) : NULL;
    /* The emitter table: every triangle whose material emits, with the
     * running sum of powers, to pick one in proportion to its power. */
    int n = 0;
    for (int i = 0; i < sc->geometry.face_count; i++)
        n += vec3_max_component(sc->materials[sc->geometry.faces[i].material].emission) > 0.0f;
    sc->emitters = memory_allocate((size_t)(n > 0 ? n : 1), sizeof(int));
    sc->emitter_normals = memory_allocate((size_t)(n > 0 ? n : 1), sizeof(vec3));
    sc->emitter_cdf = memory_allocate((size_t)(n > 0 ? n : 1), sizeof(double));
    sc->emitter_count = 0;
    sc->emitter_area = 0.0;
    sc->emitter_power = 0.0;
    for (int i = 0; i < sc->geometry.face_count; i++) {
        vec3 le = sc->materials[sc->geometry.faces[i].material].emission;
        if (vec3_max_component(le) <= 0.0f)
            continue;
        const triangle *t = &sc->triangles.triangles[i];
        vec3 cross = vec3_cross(vec3_sub(t->p1, t->p0), vec3_sub(t->p2, t->p0));
        double area = 0.5 * (double)vec3_length(cross);
        sc->emitter_area += area;
        sc->emitter_power += area * emitter_weight(le);
        sc->emitters[sc->emitter_count] = i;
        sc->emitter_normals[sc->emitter_count] = vec3_normalize(cross);
        sc->emitter_cdf[sc->emitter_count] = sc->emitter_power;
        sc->emitter_count++;
    }
}

static vec3 transformed(vec3 p, float scale, vec3 offset) { return vec3_add(vec3_scale(p, scale), offset); }

void pt_scene_transform(pt_scene *sc, float scale, vec3 offset)
{
    for (int i = 0; i < sc->geometry.position_count; i++)
        sc->geometry.positions[i] = transformed(sc->geometry.positions[i], scale, offset);
    for (int i = 0; i < sc->sphere_count; i++) {
        sc->spheres[i].center = transformed(sc->spheres[i].center, scale, offset);
        sc->spheres[i].radius *= scale;
    }
    for (int i = 0; i < sc->point_light_count; i++) {
        sc->point_lights[i].position = transformed(sc->point_lights[i].position, scale, offset);
        sc->point_lights[i].intensity = vec3_scale(sc->point_lights[i].intensity, scale * scale);
    }
    sc->eye = transformed(sc->eye, scale, offset);
    sc->target = transformed(sc->target, scale, offset);
    /* what pt_scene_finish builds, built again from the moved points */
    accel_destroy(sc->bvh);
    sc->bvh = NULL;
    triangle_set_free(&sc->triangles);
    free(sc->emitters);
    free(sc->emitter_normals);
    free(sc->emitter_cdf);
    pt_scene_finish(sc);
}

/* ---- intersection ---------------------------------------------------------- */

bool pt_scene_intersect_spheres(const pt_scene *sc, ray r, hit_record *hit, ray_counters *counters)
{
    bool found = false;
    for (int i = 0; i < sc->sphere_count; i++) {
        const pt_sphere *s = &sc->spheres[i];
        sphere shape = {s->center, s->radius};
        counters->primitive_tests++;
        if (sphere_intersect(&shape, r, hit)) {
            found = true;
            r.t_max = hit->t;
            hit->shape_id = -1 - i; /* spheres count down from -1; triangles up from 0 */
            hit->material_id = s->material;
            if (s->inside_out) /* the front is the inside */
                hit->front_face = !hit->front_face;
        }
    }
    return found;
}

bool pt_scene_intersect(const pt_scene *sc, ray r, hit_record *hit, ray_counters *counters)
{
    bool found = false;
    if (sc->bvh != NULL && sc->triangles.count > 0 && accel_closest_hit(sc->bvh, r, hit, counters)) {
        found = true;
        r.t_max = hit->t;
    }
    return pt_scene_intersect_spheres(sc, r, hit, counters) || found;
}

/* A shadow ray asks only whether anything is in the way (any hit). */
static bool occluded(const pt_scene *sc, const ray *r, ray_counters *counters)
{
    if (sc->bvh != NULL && sc->triangles.count > 0 && accel_any_hit(sc->bvh, *r, counters))
        return true;
    hit_record ignored;
    for (int i = 0; i < sc->sphere_count; i++) {
        sphere shape = {sc->spheres[i].center, sc->spheres[i].radius};
        counters->primitive_tests++;
        if (sphere_intersect(&shape, *r, &ignored))
            return true;
    }
    return false;
}

bool pt_scene_occluded(const pt_scene *sc, ray r, ray_counters *counters) { return occluded(sc, &r, counters); }

bool pt_scene_segment_clear(const pt_scene *sc, ray shadow, ray_counters *counters)
{
    counters->shadow_rays++;
    return !occluded(sc, &shadow, counters);
}

bool pt_scene_visible(const pt_scene *sc, const hit_record *from, const vec3 *target, float target_error,
                      const vec3 *target_normal, ray_counters *counters)
{
    return pt_scene_segment_clear(sc,
                                  ray_spawn_to(from->point, from->point_error, from->normal_geometric, *target,
                                               target_error, *target_normal),
                                  counters);
}

float pt_scene_emitter_pdf_area(const pt_scene *sc, int material)
{
    /* P(triangle) / its area = area x weight / power / area */
    return (float)(emitter_weight(sc->materials[material].emission) / sc->emitter_power);
}

camera pt_scene_camera(const pt_scene *sc, int width, int height)
{
    return camera_look_at(sc->eye, sc->target, sc->up, sc->vertical_fov_degrees, width, height);
}

/* ---- scenes ------------------------------------------------------------------ */

static vec3 v(float x, float y, float z) { return vec3_make(x, y, z); }

/* Reflectances of the box's paints as RGB (the values GAMES101's assignment 7
 * uses), and the light's emission. */
const vec3 PT_CORNELL_WHITE = {0.725f, 0.71f, 0.68f};
const vec3 PT_CORNELL_RED = {0.63f, 0.065f, 0.05f};
const vec3 PT_CORNELL_GREEN = {0.14f, 0.45f, 0.091f};
const vec3 PT_CORNELL_LIGHT = {17.0f, 12.0f, 4.0f};

int pt_scene_add_painted_cornell_room(pt_scene *sc)
{
    int white = pt_scene_add_material(sc, pt_diffuse(PT_CORNELL_WHITE));
    int red = pt_scene_add_material(sc, pt_diffuse(PT_CORNELL_RED));
    int green = pt_scene_add_material(sc, pt_diffuse(PT_CORNELL_GREEN));
    int light = pt_scene_add_material(sc, pt_emitter(vec3_splat(0.65f), PT_CORNELL_LIGHT));
    pt_scene_add_cornell_room(sc, white, red, green, light);
    return white;
}

void pt_scene_add_cornell_room(pt_scene *sc, int white, int red, int green, int light)
{
    /* Floor, ceiling, back wall, right (green) and left (red) walls: the
     * published coordinates, each face counter-clockwise seen from inside. */
    pt_scene_add_quad(sc, v(552.8f, 0, 0), v(0, 0, 0), v(0, 0, 559.2f), v(549.6f, 0, 559.2f), white);
    pt_scene_add_quad(sc, v(556, 548.8f, 0), v(556, 548.8f, 559.2f), v(0, 548.8f, 559.2f), v(0, 548.8f, 0), white);
    pt_scene_add_quad(sc, v(549.6f, 0, 559.2f), v(0, 0, 559.2f), v(0, 548.8f, 559.2f), v(556, 548.8f, 559.2f), white);
    pt_scene_add_quad(sc, v(0, 0, 559.2f), v(0, 0, 0), v(0, 548.8f, 0), v(0, 548.8f, 559.2f), green);
    pt_scene_add_quad(sc, v(552.8f, 0, 0), v(549.6f, 0, 559.2f), v(556, 548.8f, 559.2f), v(556, 548.8f, 0), red);
    /* The light, 0.1 mm below the ceiling so the two never coincide, facing down. */
    pt_scene_add_quad(sc, v(343, 548.7f, 227), v(343, 548.7f, 332), v(213, 548.7f, 332), v(213, 548.7f, 227), light);
    sc->eye = v(278, 273, -800);
    sc->target = v(278, 273, 0);
    /* A 35 mm lens on a 25 mm film: 2 atan(12.5 / 35) = 39.3 degrees. */
    sc->vertical_fov_degrees = 2.0f * atanf(12.5f / 35.0f) * 180.0f / (float)PI;
}

static void cornell_short_block(pt_scene *sc, int m)
{
    pt_scene_add_quad(sc, v(130, 165, 65), v(82, 165, 225), v(240, 165, 272), v(290, 165, 114), m);
    pt_scene_add_quad(sc, v(290, 0, 114), v(290, 165, 114), v(240, 165, 272), v(240, 0, 272), m);
    pt_scene_add_quad(sc, v(130, 0, 65), v(130, 165, 65), v(290, 165, 114), v(290, 0, 114), m);
    pt_scene_add_quad(sc, v(82, 0, 225), v(82, 165, 225), v(130, 165, 65), v(130, 0, 65), m);
    pt_scene_add_quad(sc, v(240, 0, 272), v(240, 165, 272), v(82, 165, 225), v(82, 0, 225), m);
}

static void cornell_tall_block(pt_scene *sc, int m)
{
    pt_scene_add_quad(sc, v(423, 330, 247), v(265, 330, 296), v(314, 330, 456), v(472, 330, 406), m);
    pt_scene_add_quad(sc, v(423, 0, 247), v(423, 330, 247), v(472, 330, 406), v(472, 0, 406), m);
    pt_scene_add_quad(sc, v(472, 0, 406), v(472, 330, 406), v(314, 330, 456), v(314, 0, 456), m);
    pt_scene_add_quad(sc, v(314, 0, 456), v(314, 330, 456), v(265, 330, 296), v(265, 0, 296), m);
    pt_scene_add_quad(sc, v(265, 0, 296), v(265, 330, 296), v(423, 330, 247), v(423, 0, 247), m);
}

void pt_scene_build_cornell_box(pt_scene *sc)
{
    pt_scene_init(sc);
    int white = pt_scene_add_painted_cornell_room(sc);
    cornell_short_block(sc, white);
    cornell_tall_block(sc, white);
    pt_scene_finish(sc);
}

void pt_scene_build_cornell_box_materials(pt_scene *sc)
{
    pt_scene_init(sc);
    int white = pt_scene_add_material(sc, pt_diffuse(PT_CORNELL_WHITE));
    int red = pt_scene_add_material(sc, pt_diffuse(PT_CORNELL_RED));
    int green = pt_scene_add_material(sc, pt_diffuse(PT_CORNELL_GREEN));
    int light = pt_scene_add_material(sc, pt_emitter(vec3_splat(0.65f), PT_CORNELL_LIGHT));
    int metal = pt_scene_add_material(sc, pt_glossy(vec3_make(0.95f, 0.64f, 0.54f), 0.15f)); /* copper-like */
    int glass = pt_scene_add_material(sc, pt_glass(1.5f));
    pt_scene_add_cornell_room(sc, white, red, green, light);
    cornell_tall_block(sc, metal);
    pt_scene_add_sphere(sc, v(185, 90, 170), 90, glass, false);
    pt_scene_finish(sc);
}

/* A rectangle centred at c with unit axes a and b (half-sizes ha, hb),
 * counter-clockwise seen from the side a x b points to. */
static void add_rectangle(pt_scene *sc, vec3 c, vec3 a, float ha, vec3 b, float hb, int material)
{
    vec3 da = vec3_scale(a, ha), db = vec3_scale(b, hb);
    pt_scene_add_quad(sc, vec3_sub(vec3_sub(c, da), db), vec3_sub(vec3_add(c, da), db),
                      vec3_add(vec3_add(c, da), db), vec3_add(vec3_sub(c, da), db), material);
}

void pt_scene_build_veach(pt_scene *sc)
{
    pt_scene_init(sc);
    sc->eye = v(0, 2.2f, 7.5f);
    sc->target = v(0, 0.7f, 0);
    sc->vertical_fov_degrees = 38.0f;
    /* Nothing else: a black world, so that all the light in the image is
     * the lights' own, reflected once (the estimators differ only there). */

    /* Four lights in a row behind the plates, each 9 times the area of the
     * last and emitting 1/9 as much per unit area: the same power. */
    const vec3 light_row = v(0, 2.6f, -1.8f);
    const float half_size[4] = {0.03f, 0.09f, 0.27f, 0.81f};
    const float light_x[4] = {-2.1f, -1.05f, 0.15f, 1.9f};
    const vec3 colour[4] = {{1.0f, 0.35f, 0.2f}, {1.0f, 0.9f, 0.3f}, {0.3f, 1.0f, 0.4f}, {0.3f, 0.5f, 1.0f}};
    for (int i = 0; i < 4; i++) {
        float le = 0.6f / (half_size[i] * half_size[i]); /* power 2.4 per colour unit */
        int m = pt_scene_add_material(sc, pt_emitter(vec3_splat(0.0f), vec3_scale(colour[i], le)));
        vec3 c = v(light_x[i], light_row.y, light_row.z);
        /* facing the plates: its normal points at the middle of them */
        vec3 n = vec3_normalize(vec3_sub(v(light_x[i], 0.3f, 1.0f), c));
        vec3 a = v(1, 0, 0), b = vec3_normalize(vec3_cross(n, a));
        add_rectangle(sc, c, a, half_size[i], b, half_size[i], m);
    }

    /* Four plates, the sharpest at the back, each tilted so that the eye
     * sees the row of lights reflected in it: its normal halves the angle
     * between the directions to the eye and to the lights. */
    const float roughness[4] = {0.3f, 0.12f, 0.05f, 0.015f};
    const vec3 plate_centre[4] = {{0, 0.0f, 2.2f}, {0, 0.3f, 1.2f}, {0, 0.62f, 0.25f}, {0, 0.98f, -0.65f}};
    for (int i = 0; i < 4; i++) {
        int m = pt_scene_add_material(sc, pt_glossy(vec3_splat(0.8f), roughness[i]));
        vec3 c = plate_centre[i];
        vec3 to_eye = vec3_normalize(vec3_sub(sc->eye, c)), to_light = vec3_normalize(vec3_sub(light_row, c));
        vec3 n = vec3_normalize(vec3_add(to_eye, to_light));
        vec3 a = v(1, 0, 0), b = vec3_normalize(vec3_cross(n, a));
        add_rectangle(sc, c, a, 2.6f, b, 0.42f, m);
    }
    pt_scene_finish(sc);
}

void pt_scene_build_furnace(pt_scene *sc, float albedo, float emission)
{
    pt_scene_init(sc);
    int m = pt_scene_add_material(sc, pt_emitter(vec3_splat(albedo), vec3_splat(emission)));
    /* An icosphere's triangles face outwards; the furnace is seen from
     * inside, so each triangle is added with its winding reversed. */
    mesh ball;
    mesh_init(&ball);
    mesh_icosphere(&ball, v(0, 0, 0), 1.0f, 2, -1);
    for (int i = 0; i < ball.face_count; i++)
        pt_scene_add_triangle(sc, mesh_vertex(&ball, i, 0), mesh_vertex(&ball, i, 2), mesh_vertex(&ball, i, 1), m);
    mesh_free(&ball);
    sc->eye = v(0.1f, 0.2f, 0.3f);
    sc->target = v(0.5f, 0.1f, -1.0f);
    sc->vertical_fov_degrees = 90.0f;
    pt_scene_finish(sc);
}

void pt_scene_build_white_furnace(pt_scene *sc, pt_material sphere_material, vec3 environment)
{
    pt_scene_init(sc);
    int m = pt_scene_add_material(sc, sphere_material);
    pt_scene_add_sphere(sc, v(0, 0, 0), 1.0f, m, false);
    sc->environment = environment;
    sc->eye = v(0, 0, 4);
    sc->target = v(0, 0, 0);
    sc->vertical_fov_degrees = 40.0f;
    pt_scene_finish(sc);
}

void pt_scene_build_point_in_sphere(pt_scene *sc, float albedo, float intensity)
{
    pt_scene_init(sc);
    int m = pt_scene_add_material(sc, pt_diffuse(vec3_splat(albedo)));
    pt_scene_add_sphere(sc, v(0, 0, 0), 1.0f, m, true);
    pt_scene_add_point_light(sc, v(0, 0, 0), vec3_splat(intensity));
    sc->eye = v(0.2f, -0.1f, 0.3f);
    sc->target = v(0.4f, 0.3f, -1.0f);
    sc->vertical_fov_degrees = 70.0f;
    pt_scene_finish(sc);
}

/* ---- OBJ scenes ---------------------------------------------------------------- */

/* Where the loaders say what each MTL material became (NULL: nowhere). */
static FILE *material_report;
static bool material_report_set;

void pt_scene_report_materials(FILE *out)
{
    material_report = out;
    material_report_set = true;
}

/* The sharpest GGX lobe an MTL makes: at alpha 0, D(h) is 0 / 0 at its
 * peak; at 0.001 its peak 1 / (pi alpha^2), 3e5, is far inside float. */
static const float MTL_ALPHA_MIN = 0.001f;

/* The MTL's shininess Ns as GGX's alpha: a Blinn-Phong lobe of exponent p
 * is close to a microfacet lobe of alpha = sqrt(2 / (p + 2)) (Walter et al.
 * 2007), kept within what the glossy BSDF takes. */
static float alpha_from_shininess(float ns)
{
    float alpha = sqrtf(2.0f / (fmaxf(ns, 0.0f) + 2.0f));
    return fminf(1.0f, fmaxf(MTL_ALPHA_MIN, alpha));
}

/* A metal's alpha from Blender's Ns: its exporter writes a Principled
 * BSDF's roughness r as Ns = 1000 (1 - r)^2, and its GGX alpha is r^2. */
static float alpha_from_blender_shininess(float ns)
{
    float r = 1.0f - sqrtf(fminf(1.0f, fmaxf(ns, 0.0f) / 1000.0f));
    return fminf(1.0f, fmaxf(MTL_ALPHA_MIN, r * r));
}

/* A metal: GGX with F0 = Kd, the base colour a metallic workflow keeps
 * there. Said by the PBR extension (Pm at least 0.5, roughness Pr), or in
 * the way Blender's exporter writes a metal without it: illum 3
 * ("reflection on", its mark of a Principled BSDF with metallic above 0),
 * the base colour as Kd and the fixed 0.5 of its specular slider as Ks.
 * Read as the format means it, that would be a diffuse Kd, so every
 * exported metal rendered as coloured plaster. */
static bool mtl_metal(const mesh_material *mm, char *note, size_t note_size, pt_material *out)
{
    const vec3 kd = mm->diffuse;
    float alpha;
    if (mm->metallic >= 0.5f) {
        bool pr = mm->roughness >= 0.0f;
        alpha = pr ? fmaxf(MTL_ALPHA_MIN, mm->roughness * mm->roughness) : alpha_from_shininess(mm->shininess);
        snprintf(note, note_size, "glossy GGX, a metal (Pm %g), F0 = Kd %g %g %g, alpha %.3g from %s",
                 (double)mm->metallic, (double)kd.x, (double)kd.y, (double)kd.z, (double)alpha, pr ? "Pr" : "Ns");
    } else if (mm->metallic < 0.0f && mm->illum == 3) {
        alpha = alpha_from_blender_shininess(mm->shininess);
        snprintf(note, note_size,
                 "glossy GGX, a metal (illum 3, as Blender writes one), F0 = Kd %g %g %g, alpha %.3g from Ns %g "
                 "(Blender's Ns = 1000 (1 - roughness)^2); Ks dropped",
                 (double)kd.x, (double)kd.y, (double)kd.z, (double)alpha, (double)mm->shininess);
    } else {
        return false;
    }
    *out = pt_glossy(kd, alpha);
    return true;
}

pt_material pt_material_from_mtl(const mesh_material *mm, char *note, size_t note_size)
{
    float kd = vec3_max_component(mm->diffuse), ks = vec3_max_component(mm->specular);
    if (mesh_material_emits(mm)) {
        snprintf(note, note_size, "emitter, Ke %g %g %g (Kd %g %g %g as its albedo)", (double)mm->emission.x,
                 (double)mm->emission.y, (double)mm->emission.z, (double)mm->diffuse.x, (double)mm->diffuse.y,
                 (double)mm->diffuse.z);
        return pt_emitter(mm->diffuse, mm->emission);
    }
    if (mesh_material_transparent(mm)) {
        float ior = mm->ior > 1.0f ? mm->ior : 1.5f;
        snprintf(note, note_size, "glass, ior %g (%s)%s", (double)ior,
                 mm->dissolve < 1.0f ? "d < 1" : "a transparent illum", mm->ior > 1.0f ? "" : "; no Ni > 1: 1.5");
        return pt_glass(ior);
    }
    pt_material metal;
    if (mm->metallic >= 0.5f && mtl_metal(mm, note, note_size, &metal))
        return metal;
    if (ks > kd) {
        float alpha = alpha_from_shininess(mm->shininess);
        snprintf(note, note_size, "glossy GGX, F0 = Ks %g %g %g, alpha %.3g from Ns %g", (double)mm->specular.x,
                 (double)mm->specular.y, (double)mm->specular.z, (double)alpha, (double)mm->shininess);
        return pt_glossy(mm->specular, alpha);
    }
    if (mtl_metal(mm, note, note_size, &metal))
        return metal;
    snprintf(note, note_size, "diffuse, Kd %g %g %g%s%s", (double)mm->diffuse.x, (double)mm->diffuse.y,
             (double)mm->diffuse.z, ks > 0.0f ? "; Ks dropped (the diffuse part is larger: no layered material here)" : "",
             mm->ior > 1.0f ? "; Ni ignored (opaque)" : "");
    return pt_diffuse(mm->diffuse);
}

void pt_scene_add_mtl_materials(pt_scene *sc, const mesh *m, const char *source)
{
    FILE *out = material_report_set ? material_report : stdout;
    for (int i = 0; i < m->material_count; i++) {
        char note[256];
        pt_scene_add_material(sc, pt_material_from_mtl(&m->materials[i], note, sizeof note));
        if (out != NULL)
            fprintf(out, "%s: material '%s': %s\n", source, m->materials[i].name, note);
    }
}

bool pt_scene_load_obj(pt_scene *sc, const char *path, char *err, size_t err_size)
{
    pt_scene_init(sc);
    if (!mesh_load_obj(&sc->geometry, path, err, err_size)) {
        pt_scene_free(sc);
        return false;
    }
    /* Materials from the MTL; faces without one get a grey diffuse. */
    pt_scene_add_mtl_materials(sc, &sc->geometry, path);
    int grey = pt_scene_add_material(sc, pt_diffuse(vec3_splat(0.7f)));
    for (int i = 0; i < sc->geometry.face_count; i++)
        if (sc->geometry.faces[i].material < 0)
            sc->geometry.faces[i].material = grey;
    vec3 lo, hi;
    if (!mesh_bounds(&sc->geometry, &lo, &hi)) {
        snprintf(err, err_size, "%s: no triangles to render", path);
        pt_scene_free(sc);
        return false;
    }
    vec3 centre = vec3_scale(vec3_add(lo, hi), 0.5f);
    float radius = 0.5f * vec3_length(vec3_sub(hi, lo));
    sc->target = centre;
    sc->eye = vec3_add(centre, vec3_make(0, 0.3f * radius, 2.8f * radius));
    sc->vertical_fov_degrees = 45.0f;
    pt_scene_finish(sc);
    if (sc->emitter_count == 0 && sc->point_light_count == 0) {
        sc->environment = vec3_splat(1.0f); /* nothing emits: light it with a white sky */
        FILE *out = material_report_set ? material_report : stdout;
        if (out != NULL)
            fprintf(out,
                    "%s: no material emits (Ke): lit by a white sky of radiance 1 instead. Blender writes no lamp "
                    "to OBJ; to light it as you lit it, give a face an Emission material, or use a scene file "
                    "(docs/scene-format.md)\n",
                    path);
    }
    return true;
}

/* ---- the built-in scenes, by name ----------------------------------------- */

static void build_furnace(pt_scene *sc) { pt_scene_build_furnace(sc, 0.5f, 0.5f); }
static void build_white_furnace(pt_scene *sc)
{
    pt_scene_build_white_furnace(sc, pt_diffuse(vec3_splat(0.5f)), vec3_splat(1.0f));
}
static void build_glass_furnace(pt_scene *sc) { pt_scene_build_white_furnace(sc, pt_glass(1.5f), vec3_splat(1.0f)); }
static void build_point_in_sphere(pt_scene *sc) { pt_scene_build_point_in_sphere(sc, 0.5f, (float)PI); }

const char *const PT_BUILTIN_SCENE_NAMES[] = {"cornell",       "materials",     "veach", "furnace",
                                              "white-furnace", "glass-furnace", "point-in-sphere", NULL};
const char *const PT_BUILTIN_SCENE_NOTES[] = {
    "the Cornell box (the default)",
    "the box with a glossy metal block and a glass sphere",
    "glossy plates and lights of four sizes (where MIS wins)",
    "inside a closed sphere that emits and reflects 0.5: radiance 1 everywhere",
    "a diffuse sphere of albedo 0.5 under a uniform sky of radiance 1",
    "a glass sphere under a uniform sky of radiance 1",
    "a point light inside a sphere of albedo 0.5",
    NULL,
};
/* in the order of PT_BUILTIN_SCENE_NAMES (their lines are PT_BUILTIN_SCENE_NOTES) */
const pt_builtin_scene PT_BUILTIN_SCENES[] = {
    {"cornell", pt_scene_build_cornell_box, NULL},
    {"materials", pt_scene_build_cornell_box_materials, NULL},
    {"veach", pt_scene_build_veach, NULL},
    {"furnace", build_furnace, NULL},
    {"white-furnace", build_white_furnace, NULL},
    {"glass-furnace", build_glass_furnace, NULL},
    {"point-in-sphere", build_point_in_sphere, NULL},
    {NULL, NULL, NULL},
};

bool pt_scene_build_builtin(pt_scene *sc, const char *name)
{
    for (int i = 0; PT_BUILTIN_SCENES[i].name != NULL; i++)
        if (strcmp(name, PT_BUILTIN_SCENES[i].name) == 0) {
            PT_BUILTIN_SCENES[i].build(sc);
            return true;
        }
    return false;
}

/* ---- a warning before a render that cannot be right --------------------- */

bool pt_scene_has_no_light(const pt_scene *sc, char *why, size_t why_size)
{
    if (sc->emitter_count > 0 || sc->point_light_count > 0 || vec3_max_component(sc->environment) > 0.0f)
        return false;
    int emitting_spheres = 0;
    for (int i = 0; i < sc->sphere_count; i++)
        emitting_spheres += vec3_max_component(sc->materials[sc->spheres[i].material].emission) > 0.0f;
    snprintf(why, why_size, "no light: no emitting triangle, point light or background%s: the image will be black",
             emitting_spheres > 0 ? " (only emitting spheres, which light what happens to hit them)" : "");
    return emitting_spheres == 0;
}
