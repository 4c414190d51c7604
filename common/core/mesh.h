/* mesh.h -- triangle meshes: made by procedures so that nothing needs a
 * download, or loaded from Wavefront OBJ (+ MTL colours) by obj.h.
 *
 * Usage:
 *   mesh m; mesh_init(&m);
 *   char err[MESH_ERROR_SIZE];
 *   if (!mesh_load_obj(&m, "bunny.obj", err, sizeof err)) { puts(err); ... }   obj.h; "bunny.obj:12: ..."
 *   mesh_icosphere(&m, vec3_make(0, 0, 0), 1.0f, 3, -1);    appends to m
 *   for (int i = 0; i < m.face_count; i++) { vec3 a = mesh_vertex(&m, i, 0); ... }
 *   mesh_free(&m);
 *
 * A mesh is a list of triangles (faces) over shared vertex arrays; polygons
 * from OBJ files are fan-triangulated on loading. Generators append, so
 * several can be combined into one mesh.
 */
#ifndef MESH_H
#define MESH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "vec3.h"

enum { MESH_ERROR_SIZE = 512, MESH_NAME_SIZE = 64 };

typedef struct {
    int position[3]; /* indices into positions */
    int normal[3];   /* indices into normals, or -1 */
    int texcoord[3]; /* indices into texcoords, or -1 */
    int material;    /* index into materials, or -1 */
} mesh_face;

/* What an MTL file gives a material: the colours (Kd, Ks, Ke), shininess
 * (Ns), index of refraction (Ni), and whether light passes through it
 * (d, the dissolve; Tr = 1 - d, its other spelling; illum, the illumination
 * model: 4, 6, 7 and 9 are the transparent ones; 3 is "reflection on",
 * Blender's mark of a metal), and the PBR extension's metallic (Pm) and
 * roughness (Pr). */
typedef struct {
    char name[MESH_NAME_SIZE];
    vec3 diffuse, specular, emission;
    float shininess, ior;
    float dissolve;  /* d: 1 opaque (the default), 0 fully transparent */
    int illum;       /* -1 if not given */
    float metallic;  /* Pm, 0 to 1; -1 if not given */
    float roughness; /* Pr, 0 to 1 (alpha = Pr^2, as Blender and glTF mean it); -1 if not given */
} mesh_material;

/* Does the MTL say light passes through (illum 4, 6, 7 or 9, or d < 1)?
 * An index of refraction alone does not: exporters write one for every
 * material (Blender: Ni 1.45 on opaque ones). */
bool mesh_material_transparent(const mesh_material *m);
/* Does it emit (a positive Ke)? */
bool mesh_material_emits(const mesh_material *m);

typedef struct {
    vec3 *positions;
    int position_count, position_capacity;
    vec3 *normals;
    int normal_count, normal_capacity;
    float *texcoords; /* 2 floats each */
    int texcoord_count, texcoord_capacity;
    mesh_face *faces;
    int face_count, face_capacity;
    mesh_material *materials;
    int material_count, material_capacity;
} mesh;

void mesh_init(mesh *m);
void mesh_free(mesh *m);

int mesh_add_position(mesh *m, vec3 p);
int mesh_add_normal(mesh *m, vec3 n);
int mesh_add_texcoord(mesh *m, float u, float v);
/* A triangle of three position indices, no normals or texcoords. */
int mesh_add_triangle(mesh *m, int a, int b, int c, int material);
int mesh_add_material(mesh *m, const mesh_material *material);

/* Corner k (0, 1, 2) of face i. */
static inline vec3 mesh_vertex(const mesh *m, int face, int k)
{
    return m->positions[m->faces[face].position[k]];
}

/* Axis-aligned bounds of all face vertices; false for an empty mesh. */
bool mesh_bounds(const mesh *m, vec3 *lo, vec3 *hi);

/* ---- procedural meshes (each appends to m; material may be -1) ------------- */

/* A closed icosphere: an icosahedron subdivided `subdivisions` times, with
 * vertices on the sphere. Every edge is shared by exactly two triangles, so a
 * ray that enters must hit (the watertightness test mesh). 20 * 4^s triangles. */
void mesh_icosphere(mesh *m, vec3 center, float radius, int subdivisions, int material);

/* A torus as a U x V grid of quads (2 triangles each) around unit `axis`. */
void mesh_torus(mesh *m, vec3 center, vec3 axis, float major, float minor, int u_segments, int v_segments,
                int material);

/* The "tori field" of shared/anchors/embree_bench.c, vertex for vertex: 16
 * tori placed by splitmix64 from seed 0x5EED, with the U x V grid the harness
 * picks for `target_triangles` (1024, 10240, 102400, 1048576). */
void mesh_tori_field(mesh *m, long target_triangles);

/* n triangles with vertices uniform in [lo, hi], small (edge about `size`). */
void mesh_random_soup(mesh *m, int n, vec3 lo, vec3 hi, float size, uint64_t seed);

/* "Teapot in a stadium": a small dense icosphere (radius 1, `subdivisions`)
 * at the centre of a huge, sparse stadium of large ground and wall quads
 * `stadium_size` across: the case that defeats a uniform grid. */
void mesh_teapot_in_stadium(mesh *m, int subdivisions, float stadium_size);

/* n copies of the same triangle: a build must still terminate. */
void mesh_coincident(mesh *m, int n);

#endif
