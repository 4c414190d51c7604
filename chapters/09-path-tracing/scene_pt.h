/* scene_pt.h -- what the path tracer renders: triangles (in chapter 06's BVH)
 * and spheres, each with a material that may also emit; point lights; and
 * an environment: the radiance of rays that leave the scene.
 *
 * Usage:
 *   pt_scene sc; pt_scene_build_cornell_box(&sc);      (or pt_scene_init + pt_scene_add_*)
 *   pt_scene_finish(&sc);       builds the BVH and the table of emitters
 *   if (pt_scene_intersect(&sc, r, &hit, &counters)) ... hit.material_id
 *   pt_scene_free(&sc);
 *
 * Emitters are one-sided: a triangle emits from its front face (counter-
 * clockwise seen from outside), a sphere outwards. The lights the path
 * tracer samples are the emitting triangles, chosen in proportion to their
 * area, and the point lights; emitting spheres and the environment are
 * reached only by rays that happen to hit them.
 */
#ifndef SCENE_PT_H
#define SCENE_PT_H

#include <stdbool.h>
#include <stdio.h>

#include "01-ray-casting/shapes.h"
#include "03-aabb-slabs/accel.h"
#include "09-path-tracing/bsdf_kinds.h"
#include "camera.h"
#include "cli.h"
#include "counters.h"
#include "mesh.h"
#include "scene_file.h"

/* The scene file's kind of a BSDF, and its name ("diffuse", ...; "?" for
 * a value that is no kind). */
scene_material_kind bsdf_kind_scene_kind(bsdf_kind k);
const char *bsdf_kind_name(bsdf_kind k);

typedef struct {
    bsdf_kind kind;
    vec3 albedo;     /* rho for diffuse, F0 for glossy, the tint of mirror and glass */
    vec3 emission;   /* L_e, from the front side only */
    float roughness; /* GGX alpha (glossy) */
    float ior;       /* index of refraction (glass) */
} pt_material;

typedef struct {
    vec3 center;
    float radius;
    int material;
    bool inside_out; /* the outward normal points to the centre: a room seen from inside */
} pt_sphere;

typedef struct {
    vec3 position;
    vec3 intensity; /* I: irradiance I cos(theta) / r^2 at distance r */
} pt_point_light;

/* How the scene's triangles are traced: a builder of an acceleration
 * structure (chapter 03's interface) over them. `context` is what the
 * builder needs besides the triangles (may be NULL). */
typedef accel *(*pt_accel_builder)(const triangle_set *set, const void *context);

typedef struct {
    mesh geometry;          /* triangles; face material = index into materials */
    triangle_set triangles; /* built by pt_scene_finish */
    /* Every closest hit and every shadow ray of the scene's triangles goes
     * through this one structure: chapter 06's BVH unless
     * pt_scene_use_accel() chose another. */
    accel *bvh;
    pt_sphere *spheres;
    int sphere_count, sphere_capacity;
    pt_material *materials;
    int material_count, material_capacity;
    pt_point_light *point_lights;
    int point_light_count, point_light_capacity;
    /* The emitting triangles, for sampling a point on a light: a triangle
     * is picked in proportion to its power (area x mean of L_e's channels),
     * then a point on it uniformly by area. */
    int *emitters;          /* triangle indices */
    vec3 *emitter_normals;  /* their front normals */
    double *emitter_cdf;    /* running sum of powers, emitter_cdf[emitter_count - 1] = emitter_power */
    int emitter_count;
    double emitter_area;    /* of all emitting triangles */
    double emitter_power;   /* sum of area x mean(L_e) */
    vec3 environment; /* radiance arriving from every direction that escapes */
    vec3 eye, target, up;
    float vertical_fov_degrees;
} pt_scene;

void pt_scene_init(pt_scene *sc);
void pt_scene_free(pt_scene *sc);
int pt_scene_add_material(pt_scene *sc, pt_material m);
/* A quad p0 p1 p2 p3 (counter-clockwise from its front) as two triangles. */
void pt_scene_add_quad(pt_scene *sc, vec3 p0, vec3 p1, vec3 p2, vec3 p3, int material);
void pt_scene_add_triangle(pt_scene *sc, vec3 p0, vec3 p1, vec3 p2, int material);
void pt_scene_add_sphere(pt_scene *sc, vec3 center, float radius, int material, bool inside_out);
void pt_scene_add_point_light(pt_scene *sc, vec3 position, vec3 intensity);
/* Builds the BVH over the triangles (chapter 06's, binned SAH) and the
 * emitter table. */
void pt_scene_finish(pt_scene *sc);
/* What pt_scene_finish() builds over the triangles from now on: chapter
 * 06's BVH (the default), or nothing (NULL: the scene traces no triangles
 * until pt_scene_use_accel()). A program that puts its own structure in
 * place at once (chapter 13) asks for nothing: a BVH over a million
 * triangles is a second's work to throw away. */
void pt_scene_finish_builds(pt_accel_builder build);
/* Trace the triangles through another structure: build(set, context)
 * replaces the BVH (after pt_scene_finish). */
void pt_scene_use_accel(pt_scene *sc, pt_accel_builder build, const void *context);
/* Every point of a finished scene p -> scale p + offset (vertices, spheres'
 * centres and radii, point lights, the camera's eye and target), point
 * lights' intensities times scale^2 (so that the irradiance I / r^2 stays),
 * then rebuilt as pt_scene_finish builds it (chapter 06's BVH). The same
 * picture at another scale and place, as far as float can hold it: how the
 * tests put the Cornell box at 1e-7 or far from the origin. */
void pt_scene_transform(pt_scene *sc, float scale, vec3 offset);
/* Objects too small for where they are (ray.h's ray_too_small_for_position:
 * fewer than RAY_MIN_STEPS_ACROSS float steps across at the magnitude of
 * their coordinates), which no ray offset can render right: each sphere,
 * and each connected part of the triangles (joined by a shared corner,
 * by index or by place: a mesh's piece, a box of quads, a lone quad),
 * whatever its material. Writes one warning per object to `out` (the
 * first few; then how many more),
 * "label: warning: <the object> is only N float steps across at that
 * distance from the origin ...; move the scene near the origin", and
 * returns how many. The programs of chapters 09-13 call it before
 * rendering. */
int pt_scene_check_scale(const pt_scene *sc, const char *label, FILE *out);
/* Lights that face away from the scene: for each emitting material, 256
 * rays leave its triangles from the front and 256 from the back (cosine
 * distributed, a fixed seed); where less than a quarter of the front's
 * meet another material's surface and at least half of the back's would,
 * it writes "label: warning: the light of material #M ... faces away from
 * the scene ... flip it" to `out`. Returns how many. An emitter here
 * emits from its front only (Blender's emit from both, so a lamp plane
 * that lights a Blender scene may light nothing here). The programs of
 * chapters 09-13 call it before rendering. */
int pt_scene_check_lights(const pt_scene *sc, const char *label, FILE *out);
/* The structures of chapters 03-06 as builders: --accel's brute, grid,
 * kdtree and bvh (the default), by name; NULL for an unknown name. The
 * names, NULL-terminated, for --help and messages. */
pt_accel_builder pt_accel_builder_named(const char *name);
extern const char *const PT_ACCEL_NAMES[];

pt_material pt_diffuse(vec3 albedo);
pt_material pt_emitter(vec3 albedo, vec3 emission);
pt_material pt_glossy(vec3 f0, float roughness);
pt_material pt_glass(float ior);
pt_material pt_mirror(vec3 albedo);

bool pt_scene_intersect(const pt_scene *sc, ray r, hit_record *hit, ray_counters *counters);
/* The spheres' part of pt_scene_intersect(): the nearest sphere in
 * (r.t_min, r.t_max) into *hit (shape_id -1 - i), each test counted. For
 * tracers that find the triangles their own way (chapter 13's lanes). */
bool pt_scene_intersect_spheres(const pt_scene *sc, ray r, hit_record *hit, ray_counters *counters);
/* Is anything hit in (r.t_min, r.t_max)? An any-hit query of the BVH,
 * then the spheres. */
bool pt_scene_occluded(const pt_scene *sc, ray r, ray_counters *counters);
/* Can the hit point `from` see `target` (a point on a light, with its error
 * bound target_error and its normal *target_normal, or a point light: error
 * and normal 0)? One shadow ray, ray_spawn_to(from->point,
 * from->point_error, from->normal_geometric, *target, target_error,
 * *target_normal) (ray.h), counted in counters->shadow_rays. */
bool pt_scene_visible(const pt_scene *sc, const hit_record *from, const vec3 *target, float target_error,
                      const vec3 *target_normal, ray_counters *counters);
/* Does a shadow ray get through: is nothing hit on its segment (a ray of
 * ray_spawn_to(), light_transport.h's `shadow`)? Counted in
 * counters->shadow_rays. */
bool pt_scene_segment_clear(const pt_scene *sc, ray shadow, ray_counters *counters);

/* A uniform point on emitter `slot` (the triangle sc->emitters[slot]), with
 * its error bound, front normal and material: the second half of a light
 * sample, whichever way the emitter was picked (by power below; by chapter
 * 13's light tree). */
static inline void pt_scene_emitter_point(const pt_scene *sc, int slot, float u1, float u2, vec3 *point,
                                          float *point_error, vec3 *normal, int *material)
{
    int index = sc->emitters[slot];
    const triangle *t = &sc->triangles.triangles[index];
    /* A uniform point on a triangle: b0 = 1 - sqrt(u1), b1 = u2 sqrt(u1);
     * the point as a hit's (triangle_fill_hit_normal), P0 + (b1 E1 + b2 E2). */
    float s = sqrtf(u1);
    float b1 = (1.0f - u2) * s, b2 = u2 * s;
    vec3 e1 = vec3_sub(t->p1, t->p0), e2 = vec3_sub(t->p2, t->p0);
    *point = vec3_add(t->p0, vec3_add(vec3_scale(e1, b1), vec3_scale(e2, b2)));
    *normal = sc->emitter_normals[slot];
    *point_error = ray_point_error(*point, *normal, triangle_edge_size(e1, e2));
    *material = sc->geometry.faces[index].material;
}

/* A point on the emitting triangles, with its error bound (ray.h's
 * ray_point_error, as a hit there would have), the emitter's front normal
 * and material. Picked by power: the density per unit area at a point of an
 * emitter of radiance L_e is pt_scene_emitter_pdf_area(), mean(L_e) /
 * emitter_power -- for lights that all have the same L_e (the Cornell box)
 * that is the lecture's 1 / A. False if there are none. Inline: chapter
 * 13's renderer calls it for eight paths at every step. */
static inline bool pt_scene_sample_emitter(const pt_scene *sc, float u_pick, float u1, float u2, vec3 *point,
                                           float *point_error, vec3 *normal, int *material)
{
    if (sc->emitter_count == 0)
        return false;
    /* Pick a triangle with probability power / total power, then a uniform
     * point on it. The pick is a binary search in the running sum for the
     * first entry above u_pick x power (the last, if rounding leaves none),
     * written without a branch on the comparison (GCC turns the obvious
     * `? :` into one): the way it goes is random, so a branch would be
     * guessed wrong half the time (the Cornell box's light is two
     * triangles of equal power). */
    double target = (double)u_pick * sc->emitter_power;
    int lo = 0; /* the answer is in [lo, lo + n) */
    for (int n = sc->emitter_count; n > 1;) {
        int half = n / 2;
        lo += half & -(int)(sc->emitter_cdf[lo + half - 1] <= target);
        n -= half;
    }
    pt_scene_emitter_point(sc, lo, u1, u2, point, point_error, normal, material);
    return true;
}

float pt_scene_emitter_pdf_area(const pt_scene *sc, int material);

/* Sampling the light, as the lecture writes it: a point x' on the lights
 * with its normal n', the radiance L_e it emits, and pdf_light per unit
 * area (1 / A for one light of area A). Every integrator that samples
 * lights draws them here, from three uniform numbers. */
typedef struct {
    vec3 point, normal, emission;
    float point_error; /* for the shadow ray's far end (ray_spawn_to) */
    float pdf_light;
} pt_light_sample;

static inline bool pt_scene_sample_light(const pt_scene *sc, float u_pick, float u1, float u2, pt_light_sample *x)
{
    int material;
    if (!pt_scene_sample_emitter(sc, u_pick, u1, u2, &x->point, &x->point_error, &x->normal, &material))
        return false;
    x->emission = sc->materials[material].emission;
    x->pdf_light = pt_scene_emitter_pdf_area(sc, material);
    return true;
}

camera pt_scene_camera(const pt_scene *sc, int width, int height);

/* The scenes. */
/* The Cornell box's paints as RGB albedos (the values of GAMES101's
 * assignment 7) and its light's emitted radiance: every room built on
 * pt_scene_add_cornell_room() uses them. */
extern const vec3 PT_CORNELL_WHITE, PT_CORNELL_RED, PT_CORNELL_GREEN, PT_CORNELL_LIGHT;
/* The Cornell box's room alone: floor, ceiling and back wall (white), the
 * green and red walls, the light in the ceiling, and the original camera;
 * millimetres. The rooms of pt_scene_build_cornell_box and of chapter 10. */
void pt_scene_add_cornell_room(pt_scene *sc, int white, int red, int green, int light);
/* The same room in its own paints, added as materials first (white, red,
 * green, the light, in that order); returns the white's index. */
int pt_scene_add_painted_cornell_room(pt_scene *sc);
/* The Cornell box as measured (Cornell University Program of Computer
 * Graphics): white, red and green walls, a square light in the ceiling, a
 * short and a tall block; millimetres; the original camera. */
void pt_scene_build_cornell_box(pt_scene *sc);
/* The Cornell box with the tall block made a GGX metal and the short block
 * replaced by a glass sphere: the materials of the later rungs. */
void pt_scene_build_cornell_box_materials(pt_scene *sc);
/* Where multiple importance sampling wins (after Veach's thesis, fig. 9.2):
 * four glossy GGX plates, from rough (alpha 0.3, in front) to nearly a
 * mirror (alpha 0.015, at the back), reflecting four lights of the same
 * power whose sizes grow by 3 in each direction. Light sampling is best for
 * small lights on rough plates, BSDF sampling for large lights on sharp
 * plates; MIS keeps the better of both everywhere. */
void pt_scene_build_veach(pt_scene *sc);
/* The camera inside a closed sphere (an icosphere of triangles, normals
 * inwards) that reflects albedo and emits `emission` everywhere: radiance is
 * emission / (1 - albedo) in every direction. */
void pt_scene_build_furnace(pt_scene *sc, float albedo, float emission);
/* A sphere of the given material at the origin under a uniform environment
 * of radiance `environment`, seen from +z. */
void pt_scene_build_white_furnace(pt_scene *sc, pt_material sphere_material, vec3 environment);
/* A unit sphere of albedo rho, seen from inside, with a point light of
 * intensity I at its centre: direct irradiance I everywhere. */
void pt_scene_build_point_in_sphere(pt_scene *sc, float albedo, float intensity);
/* The built-in scenes by name (--builtin), NULL-terminated. */
typedef struct {
    const char *name;
    void (*build)(pt_scene *sc);
    const char *description; /* the line --help shows (a program's own table, chapters 11 and 12) */
} pt_builtin_scene;
extern const pt_builtin_scene PT_BUILTIN_SCENES[];
/* The same names, NULL-terminated, and a line on each (--builtin). */
extern const char *const PT_BUILTIN_SCENE_NAMES[];
extern const char *const PT_BUILTIN_SCENE_NOTES[];
/* Builds the scene named `name`; false if there is none of that name. */
bool pt_scene_build_builtin(pt_scene *sc, const char *name);
/* The --builtin choice of a program's own table of `count` scenes (chapters
 * 11 and 12), the first the default: their names and descriptions written
 * into names[count + 1] and notes[count], the caller's, which the choice
 * keeps pointing to. */
cli_choice pt_builtin_scene_choice(const pt_builtin_scene *table, int count, const char **names, const char **notes);

/* An MTL material as the path tracer's, as the format means it: an
 * emitter where Ke > 0; glass where the MTL says light passes through
 * (illum 4, 6, 7, 9 or d < 1), with Ni (1.5 without one); a GGX metal with
 * F0 = Kd where the PBR extension says metallic (Pm >= 0.5, alpha = Pr^2);
 * GGX glossy with F0 = Ks where Ks outweighs Kd, its roughness from Ns; a
 * GGX metal with F0 = Kd for illum 3 without Pm (how Blender writes a
 * metal); else diffuse Kd.
 * An Ni alone makes nothing glass: exporters write one on every material.
 * *note receives a line saying what it became and what was dropped. */
pt_material pt_material_from_mtl(const mesh_material *mm, char *note, size_t note_size);
/* Adds m's materials in order, printing "SOURCE: material 'NAME': what it
 * became" for each (to stdout, or where pt_scene_report_materials() says). */
void pt_scene_add_mtl_materials(pt_scene *sc, const mesh *m, const char *source);
/* Where the lines go (NULL: nowhere, e.g. for --quiet and the tests). */
void pt_scene_report_materials(FILE *out);
/* An OBJ file's triangles with its MTL materials (pt_material_from_mtl),
 * and a camera from its bounds. False with err on failure. */
bool pt_scene_load_obj(pt_scene *sc, const char *path, char *err, size_t err_size);
/* The reverse: the scene's triangles as an OBJ file and its materials as
 * the MTL file beside it (the OBJ's name with .mtl), written so that
 * pt_scene_load_obj reads back the same triangles, bit for bit, and the
 * same materials (glossy: alpha within a float's rounding). For another
 * renderer to render the same scene (make bench-cycles). False with err,
 * and nothing written, for what OBJ cannot hold: spheres, point lights, an
 * environment, perfect mirrors, tinted glass. */
bool pt_scene_write_obj(const pt_scene *sc, const char *obj_path, char *err, size_t err_size);

/* The scene of a scene file (scene_file.h; scene_pt_file.c): diffuse,
 * glossy, mirror, glass and emissive materials, point and area lights (an
 * area light is a one-sided emitting quad), spheres, triangles, quads and
 * meshes (OBJ with MTL: Kd albedo, Ke emission, Ni > 1 glass), camera,
 * background (the environment). Blinn-Phong becomes diffuse k_d, with a
 * warning naming the line; planes and implicit tori are errors (the path
 * tracer intersects triangles and spheres only). Runs pt_scene_finish. False
 * with err ("file:line:col: ...") on failure, sc then empty. */
bool pt_scene_from_desc(pt_scene *sc, const scene_desc *d, const char *label, char *err, size_t err_size);
/* Would the render be black for want of light (no emitting triangle, point
 * light, emitting sphere or background)? Then true, and why says so. */
bool pt_scene_has_no_light(const pt_scene *sc, char *why, size_t why_size);

/* The reverse: a built-in scene as a description (every triangle a shape),
 * so that the effects analysis runs on it as on a file. */
void pt_scene_describe(const pt_scene *sc, scene_desc *d);

#endif
