/* scene.h -- what a ray can hit: shapes with materials, point lights, a
 * camera and a background. Chapter 01 builds the list and finds the closest
 * hit by testing every shape (the brute force that chapters 03-06 speed up).
 *
 * Usage:
 *   scene sc; scene_init(&sc);
 *   int red = scene_add_material(&sc, material_blinn_phong(vec3_make(0.7f, 0.1f, 0.1f), ...));
 *   scene_add_sphere(&sc, vec3_make(0, 1, 0), 1.0f, red);
 *   scene_add_point_light(&sc, vec3_make(0, 5, 0), vec3_splat(20.0f));
 *   if (scene_intersect(&sc, r, &hit, &counters)) ...
 *   scene_free(&sc);
 */
#ifndef SCENE_H
#define SCENE_H

#include <stdbool.h>
#include <stdio.h>

#include "01-ray-casting/shapes.h"
#include "camera.h"
#include "cli.h"
#include "counters.h"
#include "ray.h"
#include "scene_file.h"

typedef enum {
    MATERIAL_BLINN_PHONG, /* diffuse + specular highlight (chapter 01) */
    MATERIAL_MIRROR,      /* perfect reflection (chapter 02) */
    MATERIAL_GLASS,       /* reflection + refraction, Fresnel-weighted (chapter 02) */
} material_kind;

typedef struct {
    material_kind kind;
    vec3 diffuse;         /* k_d */
    vec3 specular;        /* k_s */
    float shininess;      /* the Blinn-Phong exponent p */
    vec3 checker_diffuse; /* the other k_d of a checkerboard ... */
    float checker_size;   /* ... with squares this wide in x and z (0: no checkerboard) */
    float ior;            /* index of refraction of glass */
    char name[SCENE_NAME_SIZE]; /* from the scene file, for --explain ("" for built-ins) */
} material;

/* A point light of intensity I: irradiance I / r^2 at distance r. */
typedef struct {
    vec3 position;
    vec3 intensity;
} point_light;

typedef enum { SHAPE_SPHERE, SHAPE_PLANE, SHAPE_TRIANGLE, SHAPE_IMPLICIT } shape_kind;

typedef struct {
    shape_kind kind;
    int material_id;
    union {
        sphere sphere;
        plane plane;
        triangle triangle;
        implicit_torus torus;
    } as;
} shape;

typedef struct {
    vec3 eye, target, up;
    float vertical_fov_degrees;
} scene_camera;

typedef struct {
    shape *shapes;
    int shape_count, shape_capacity;
    material *materials;
    int material_count, material_capacity;
    point_light *lights;
    int light_count, light_capacity;
    vec3 background; /* radiance of rays that hit nothing */
    vec3 ambient;    /* k_a I_a of Blinn-Phong: light that "comes from everywhere" */
    scene_camera camera;
    /* The effects the integrators simulate (EFFECT_* of scene_file.h):
     * EFFECT_ALL unless the effects analysis of a scene file narrowed them.
     * Without EFFECT_SHADOWS every light counts as visible and no shadow ray
     * is traced; without reflection or refraction (chapter 02) those rays
     * are not traced and bring nothing. */
    unsigned effects;
} scene;

void scene_init(scene *sc);
void scene_free(scene *sc);

material material_blinn_phong(vec3 diffuse, vec3 specular, float shininess);
material material_mirror(void);
material material_glass(float ior);

int scene_add_material(scene *sc, material m);
int scene_add_sphere(scene *sc, vec3 center, float radius, int material_id);
int scene_add_plane(scene *sc, vec3 point, vec3 normal, int material_id);
int scene_add_triangle(scene *sc, vec3 p0, vec3 p1, vec3 p2, int material_id);
int scene_add_torus(scene *sc, vec3 center, float major, float minor, int material_id);
void scene_add_point_light(scene *sc, vec3 position, vec3 intensity);
/* Where loading a mesh says what each MTL material became (stdout by
 * default; NULL: nowhere, for --quiet and the tests). */
void scene_report_materials(FILE *out);

/* One shape, whatever its kind. */
bool shape_intersect(const shape *s, ray r, hit_record *hit);

/* The closest hit over all shapes, by testing every one (counts a primitive
 * test per shape). Fills shape_id and material_id. */
bool scene_intersect(const scene *sc, ray r, hit_record *hit, ray_counters *counters);
/* Is anything hit in (r.t_min, r.t_max)? Stops at the first hit: a shadow ray
 * needs to know whether, not where. */
bool scene_occluded(const scene *sc, ray r, ray_counters *counters);

/* k_d at a point: the checkerboard's colour there, or the plain diffuse. */
vec3 material_diffuse_at(const material *m, vec3 point);

/* The scene of a scene file (scene_file.h): materials, point lights,
 * spheres, planes, triangles, quads, tori and meshes (OBJ + MTL Kd/Ks/Ns, or
 * generated), camera, background, ambient. What chapters 01-02 cannot show
 * is converted with a warning naming the line: a diffuse material becomes
 * Blinn-Phong without highlight, a glossy one Blinn-Phong with
 * p = 2 / alpha^2 - 2, an emissive one is shaded but does not glow, and an
 * area light becomes a point light at its centre with intensity L_e A. The
 * effects are left at EFFECT_ALL (the caller narrows them). False with err
 * ("file:line:col: ...") if a mesh cannot be loaded; sc is then empty. */
bool scene_from_desc(scene *sc, const scene_desc *d, const char *label, char *err, size_t err_size);
/* The reverse: a built-in scene as a description, so that the effects
 * analysis runs on it as on a file (d->source is "built-in scene"). */
void scene_describe(const scene *sc, scene_desc *d);
/* What the programs of chapters 01 and 02 do first: the scene of --scene
 * FILE, or else the built-in one (build_built_in) described as if it were a
 * file; then the effects analysis on it, narrowed to what the chapter can
 * simulate (supported), printed unless --quiet and noted for the counters
 * file. desc is left for the caller to read (max_depth, say) and free.
 * Returns 0, or the exit status after printing the error. */
int scene_load_for_program(scene *sc, scene_desc *desc, cli_options *opts, const char *program,
                           void (*build_built_in)(scene *), unsigned supported);
/* Does the scene trace shadow rays (the effects analysis did not prove them
 * useless, or narrow them away)? */
static inline bool scene_traces_shadows(const scene *sc) { return (sc->effects & EFFECT_SHADOWS) != 0; }

/* "sphere #2" and "material 'red' (blinn_phong)", for --explain. */
const char *shape_kind_name(shape_kind k);
const char *material_kind_name(material_kind k);

/* The scene's camera for an image of this size. */
camera scene_make_camera(const scene *sc, int width, int height);

#endif
