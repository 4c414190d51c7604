/* scene_file.h -- the plain-text scene format every chapter program reads
 * with --scene FILE (the grammar is in docs/scene-format.md).
 *
 * Usage:
 *   scene_desc d;
 *   char err[SCENE_ERROR_SIZE];
 *   if (!scene_desc_load(&d, "chapters/01-ray-casting/scenes/default.scene", err, sizeof err)) {
 *       fprintf(stderr, "%s\n", err);           "file:line:col: what is wrong"
 *       ...
 *   }
 *   for (int i = 0; i < d.shape_count; i++) ... d.shapes[i].kind
 *   scene_desc_free(&d);
 *
 * The parser produces a plain description: what the file says, checked
 * (names resolved, numbers finite and in range, no unknown keys), with no
 * renderer's types in it. Each chapter converts the description into its own
 * scene and says what it cannot show. The parser opens no file but the scene
 * itself: mesh files are loaded by scene_desc_load_mesh(), which names the
 * scene line that asked for them when they fail.
 */
#ifndef SCENE_FILE_H
#define SCENE_FILE_H

#include <stdbool.h>
#include <stddef.h>

#include "mesh.h"
#include "vec3.h"

enum {
    SCENE_ERROR_SIZE = 1024,
    SCENE_NAME_SIZE = 64,
    SCENE_PATH_SIZE = 1024,
    /* Bounds that keep a mistyped or hostile file from taking the machine. */
    SCENE_MAX_FILE_BYTES = 16 << 20,
    SCENE_MAX_LINE = 4096,
    SCENE_MAX_MATERIALS = 4096,
    SCENE_MAX_LIGHTS = 4096,
    SCENE_MAX_SHAPES = 1 << 20,
    SCENE_MAX_GENERATED_TRIANGLES = 1 << 22,
};

/* The keys a material statement may have (scene_file.c parses them; each
 * kind takes some of them, below). SCENE_KEY(NAME) is the key's bit. */
enum {
    SCENE_KEY_ALBEDO, SCENE_KEY_DIFFUSE, SCENE_KEY_SPECULAR, SCENE_KEY_SHININESS, SCENE_KEY_CHECKER,
    SCENE_KEY_SIZE, SCENE_KEY_IOR, SCENE_KEY_ROUGHNESS, SCENE_KEY_EMISSION, SCENE_KEY_COUNT
};
#define SCENE_KEY(name) (1u << SCENE_KEY_##name)

/* The material kinds, the one list: X(ID, keyword, effects, keys, needs)
 * for each, in the enum's order. SCENE_MATERIAL_ID is the kind, `keyword`
 * its name in a scene file (and everywhere a kind is named), `effects` the
 * light it can pass on (effects.h's bits, read by effects_analyse(): a
 * scene with the kind may need them), `keys` the keys it takes and `needs`
 * those it must have (a glass with "roughness" is an error, not a wish
 * silently ignored). The enum below, the kinds' names, the scene file's
 * parser and effects_analyse() are made from it; chapter 09's BSDF kinds
 * (bsdf_kinds.h) name the rows of it that are BSDFs. A new kind: a row
 * here; a program that has no way of its own for it says what it shows
 * instead (chapter 01: its albedo, as diffuse; chapter 13: refused). A
 * user of the list takes `...` for the columns after those it reads, so
 * that a column added at the end changes none of them. */
#define SCENE_MATERIAL_KINDS(X)                                                                               \
    /* Lambertian: albedo */                                                                                  \
    X(DIFFUSE, "diffuse", EFFECT_INDIRECT, SCENE_KEY(ALBEDO), SCENE_KEY(ALBEDO))                              \
    /* k_d (maybe a checkerboard), k_s, p */                                                                  \
    X(BLINN_PHONG, "blinn_phong", EFFECT_INDIRECT,                                                            \
      SCENE_KEY(DIFFUSE) | SCENE_KEY(SPECULAR) | SCENE_KEY(SHININESS) | SCENE_KEY(CHECKER) | SCENE_KEY(SIZE), \
      SCENE_KEY(DIFFUSE))                                                                                     \
    /* perfect reflection, tinted by albedo */                                                                \
    X(MIRROR, "mirror", EFFECT_REFLECTION, SCENE_KEY(ALBEDO), 0)                                              \
    /* smooth dielectric with index ior */                                                                    \
    X(GLASS, "glass", EFFECT_REFLECTION | EFFECT_REFRACTION, SCENE_KEY(IOR) | SCENE_KEY(ALBEDO), SCENE_KEY(IOR)) \
    /* GGX microfacet: F0 = albedo, alpha = roughness */                                                      \
    X(GLOSSY, "glossy", EFFECT_GLOSSY | EFFECT_INDIRECT, SCENE_KEY(ALBEDO) | SCENE_KEY(ROUGHNESS),            \
      SCENE_KEY(ALBEDO) | SCENE_KEY(ROUGHNESS))                                                               \
    /* diffuse albedo that also emits L_e from its front */                                                   \
    X(EMISSIVE, "emissive", EFFECT_INDIRECT, SCENE_KEY(EMISSION) | SCENE_KEY(ALBEDO), SCENE_KEY(EMISSION))

typedef enum {
#define SCENE_MATERIAL_ENUM(id, ...) SCENE_MATERIAL_##id,
    SCENE_MATERIAL_KINDS(SCENE_MATERIAL_ENUM)
#undef SCENE_MATERIAL_ENUM
} scene_material_kind;
/* How many (apart from the enum, so that a switch over the kinds names
 * only kinds). */
#define SCENE_MATERIAL_ONE(id, ...) +1
enum { SCENE_MATERIAL_KIND_COUNT = 0 SCENE_MATERIAL_KINDS(SCENE_MATERIAL_ONE) };
#undef SCENE_MATERIAL_ONE

typedef struct {
    char name[SCENE_NAME_SIZE];
    scene_material_kind kind;
    vec3 albedo;          /* diffuse/emissive albedo, Blinn-Phong k_d, mirror/glass tint, glossy F0 */
    vec3 specular;        /* Blinn-Phong k_s */
    float shininess;      /* Blinn-Phong p */
    vec3 checker;         /* the other k_d of a checkerboard ... */
    float checker_size;   /* ... of squares this wide in x and z (0: none) */
    float ior;            /* glass */
    float roughness;      /* glossy */
    vec3 emission;        /* emissive: L_e */
    int line, column;
} scene_material;

typedef enum { SCENE_LIGHT_POINT, SCENE_LIGHT_AREA } scene_light_kind;

typedef struct {
    scene_light_kind kind;
    vec3 position, intensity; /* point: irradiance I / r^2 */
    vec3 corners[4];          /* area: a quad, counter-clockwise seen from the lit side */
    vec3 emission;            /* area: radiance L_e from its front */
    int line, column;
} scene_light;

typedef enum {
    SCENE_SHAPE_SPHERE,
    SCENE_SHAPE_PLANE,
    SCENE_SHAPE_TRIANGLE,
    SCENE_SHAPE_QUAD,      /* two triangles p0 p1 p2 and p0 p2 p3 */
    SCENE_SHAPE_TORUS,     /* the implicit torus of chapter 01, around the y axis */
    SCENE_SHAPE_MESH_OBJ,  /* an OBJ file (with its MTL) */
    SCENE_SHAPE_MESH_TORI, /* the benchmark's procedural tori field (mesh.h) */
} scene_shape_kind;

typedef struct {
    scene_shape_kind kind;
    int material;    /* index into materials; -1: a mesh keeps its MTL colours */
    vec3 center;     /* sphere, torus */
    float radius;    /* sphere */
    bool inside_out; /* sphere: its front is the inside (a room seen from within) */
    vec3 point, normal; /* plane (normal unit) */
    vec3 p[4];          /* triangle p[0..2], quad p[0..3] */
    float major, minor; /* torus */
    /* mesh: resolved against the scene file's directory; the description's
     * own copy (scene_desc_free frees it), NULL for every other shape, so
     * that a description of a million triangles is not a gigabyte of room
     * for paths */
    char *path;
    int triangles;              /* tori field size */
    int line, column;
} scene_shape;

/* The effects a scene may ask for or forbid (bit flags; see effects.h). */
typedef enum {
    EFFECT_SHADOWS = 1 << 0,    /* shadow rays decide whether a light is seen */
    EFFECT_REFLECTION = 1 << 1, /* mirror (and the mirror part of glass) */
    EFFECT_REFRACTION = 1 << 2, /* light through glass */
    EFFECT_GLOSSY = 1 << 3,     /* glossy surfaces reflecting other surfaces */
    EFFECT_INDIRECT = 1 << 4,   /* diffuse interreflection */
    EFFECT_ALL = (1 << 5) - 1,
} effect_flag;

typedef struct {
    char source[SCENE_PATH_SIZE]; /* the file name used in messages */
    bool has_camera;
    vec3 eye, target, up;
    float fov_degrees;   /* vertical */
    bool has_width, has_height, has_spp;
    int width, height, spp;
    vec3 background;     /* radiance of rays that leave the scene */
    vec3 ambient;        /* Blinn-Phong k_a I_a */
    char integrator[SCENE_NAME_SIZE]; /* "" when not given */
    int integrator_line, integrator_column;
    int max_depth;       /* -1 when not given */
    unsigned effects_allowed; /* EFFECT_* the scene lets the renderer simulate */
    scene_material *materials;
    int material_count, material_capacity;
    scene_light *lights;
    int light_count, light_capacity;
    scene_shape *shapes;
    int shape_count, shape_capacity;
} scene_desc;

void scene_desc_init(scene_desc *d);
void scene_desc_free(scene_desc *d);

/* Reads and parses a scene file. On failure: false, err = "file:line:col:
 * message" (or "file: message" when the file cannot be read: missing, not a
 * regular file, over SCENE_MAX_FILE_BYTES), and d is left empty (nothing
 * half-built). */
bool scene_desc_load(scene_desc *d, const char *path, char *err, size_t err_size);
/* The same from text in memory; `name` is used in messages, mesh paths are
 * resolved against base_dir (NULL: kept as written). */
bool scene_desc_parse(scene_desc *d, const char *text, size_t length, const char *name, const char *base_dir,
                      char *err, size_t err_size);

/* Appends the triangles of mesh shape `index` (OBJ file or generator) to m.
 * The OBJ's MTL materials are appended to m's materials. A mesh given an
 * emitting material must have a triangle with area. On failure: false,
 * err = "scene:line:col: mesh: reason", m unchanged. */
bool scene_desc_load_mesh(const scene_desc *d, int index, mesh *m, char *err, size_t err_size);

/* Where a statement is, for a chapter's warnings: "file:line:col". */
/* A description made in code (scene_describe.c): a chapter's built-in
 * scene, named "built-in scene", with its camera and background; then its
 * materials (each named material<N>, N its index), shapes and point lights
 * added one by one, each copied in. */
void scene_desc_init_built_in(scene_desc *d, vec3 eye, vec3 target, vec3 up, float fov_degrees, vec3 background);
void scene_desc_add_material(scene_desc *d, scene_material m);
void scene_desc_add_shape(scene_desc *d, scene_shape s);
void scene_desc_add_point_light(scene_desc *d, vec3 position, vec3 intensity);

void scene_desc_where(const scene_desc *d, int line, int column, char *out, size_t out_size);

/* A kind's keyword ("diffuse", ...; "?" for a value that is no kind). */
const char *scene_material_kind_name(scene_material_kind k);
const char *scene_shape_kind_name(scene_shape_kind k);

/* Whether the parallelogram or triangle on corners p0, p1, p2 has area:
 * false when they are on a line (or the cross product underflows), the
 * same test for an area light and for an emitting triangle or quad. */
static inline bool scene_corners_have_area(const vec3 *p)
{
    vec3 normal = vec3_cross(vec3_sub(p[1], p[0]), vec3_sub(p[2], p[0]));
    return vec3_length_squared(normal) > 0.0f;
}

/* Does the material give light (an emissive kind with some emission)? */
static inline bool scene_material_emits(const scene_material *m)
{
    return m->kind == SCENE_MATERIAL_EMISSIVE && vec3_max_component(m->emission) > 0.0f;
}

#endif
