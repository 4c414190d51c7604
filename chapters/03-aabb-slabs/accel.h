/* accel.h -- one interface for every acceleration structure, so that one
 * render loop, one test and one benchmark run them all side by side.
 *
 *   chapter 03: brute force (test every triangle)   brute_force_build()
 *   chapter 04: uniform grid                        grid_build()
 *   chapter 05: kd-tree                             kdtree_build()
 *   chapter 06: BVH                                 bvh_build()
 *
 * Usage:
 *   triangle_set tris; triangle_set_from_mesh(&tris, &m);
 *   accel *a = brute_force_build(&tris);
 *   if (accel_closest_hit(a, r, &hit, &counters)) ...   hit.shape_id = triangle index
 *   if (accel_any_hit(a, shadow_ray, &counters)) ...     occluded
 *   printf("%s: %.1f ms, %.1f bytes/triangle\n", a->stats.name, ...);
 *   accel_destroy(a); triangle_set_free(&tris);
 *
 * Every structure counts, per ray, the nodes or cells it visits
 * (counters->box_tests) and the triangles it tests (primitive_tests).
 */
#ifndef ACCEL_H
#define ACCEL_H

#include <stdbool.h>
#include <stddef.h>

#include "01-ray-casting/shapes.h"
#include "03-aabb-slabs/aabb.h"
#include "counters.h"
#include "camera.h"
#include "cli.h"
#include "mesh.h"
#include "rng.h"
#include "scene_file.h"

/* A triangle's unit normal and material, what its hit record needs
 * besides the corners (see triangle_set). */
typedef struct {
    vec3 normal;
    int material;
} triangle_surface;

/* The triangles an accelerator is built over, with their corners copied out
 * of the mesh (the inner loop then reads 36 contiguous bytes per triangle),
 * and each one's bounding box, which every builder needs. */
typedef struct {
    triangle *triangles;
    aabb *boxes;
    int count;
    aabb bounds;        /* of all triangles */
    const mesh *source; /* for vertex normals; may be NULL */
    /* What a hit needs of each triangle besides its corners, copied out of
     * the mesh or computed once here (16 bytes, which calloc's 16-byte
     * alignment keeps within one cache line):
     *   - its material (its face's, or -1): a hit then reads this array
     *     instead of the mesh's 40-byte face. On a mesh of a million
     *     triangles the faces (40 MB) are far outside the caches and this
     *     array (16 MB) less so. The face is read only for meshes with
     *     vertex normals.
     *   - its unit normal, triangle_unit_normal() of its corners: normalising
     *     at every hit is a square root and then a division, one waiting
     *     for the other, and the shading at the hit waits for both (chapter
     *     09's README, "Speed"). Beside the material it costs no cache line
     *     more per hit. */
    triangle_surface *surfaces;
    bool vertex_normals; /* does any face have vertex normals? */
} triangle_set;

void triangle_set_from_mesh(triangle_set *set, const mesh *m);
void triangle_set_free(triangle_set *set);
/* The triangles of `from` with keep[i] set, in order, as a set of their
 * own (triangle i of `out` is the i-th one kept). It has no source mesh:
 * for structures asked only whether something is hit (any hit). */
void triangle_set_subset(triangle_set *out, const triangle_set *from, const bool *keep);
/* The interpolated vertex normal of triangle `index` at (b1, b2) as the
 * hit's shading normal, if its face has vertex normals. */
void triangle_set_shade_vertex_normal(const triangle_set *set, int index, float b1, float b2, hit_record *hit);

/* Fill a hit record for triangle `index` of the set, hit at (t, b1, b2),
 * from a copy of the triangle the caller already holds (equal to
 * set->triangles[index], bit for bit: a structure that stores the vertices
 * in its leaves saves the read of the set's copy): the point, the
 * geometric normal, the interpolated vertex normal where the mesh has
 * them, and the material. Inline: every closest hit of every structure
 * ends here, and a call would copy the ray and the triangle through
 * memory once more. */
static inline void triangle_set_fill_hit_from(const triangle_set *set, const triangle *tri, int index, ray r,
                                              float t, float b1, float b2, hit_record *hit)
{
    const triangle_surface *surface = &set->surfaces[index];
    triangle_fill_hit_normal(tri, surface->normal, &r, t, b1, b2, hit);
    hit->shape_id = index;
    hit->material_id = surface->material;
    if (set->source != NULL && set->vertex_normals)
        triangle_set_shade_vertex_normal(set, index, b1, b2, hit);
}

/* The same, reading the set's own copy of triangle `index`. */
static inline void triangle_set_fill_hit(const triangle_set *set, int index, ray r, float t, float b1, float b2,
                                         hit_record *hit)
{
    triangle_set_fill_hit_from(set, &set->triangles[index], index, r, t, b1, b2, hit);
}

typedef struct {
    const char *name;
    double build_seconds;
    size_t bytes;     /* memory of the structure itself, not the triangles */
    int nodes;        /* nodes, or cells for a grid */
    int leaves;       /* leaves, or non-empty cells */
    int max_depth;
    long references;  /* triangle references stored in leaves or cells */
} accel_stats;

typedef struct accel accel;

typedef struct {
    /* The closest hit in (r.t_min, r.t_max); fills hit (shape_id = triangle). */
    bool (*closest_hit)(const accel *a, ray r, hit_record *hit, ray_counters *counters);
    /* Is there any hit in (r.t_min, r.t_max)? May stop at the first found. */
    bool (*any_hit)(const accel *a, ray r, ray_counters *counters);
    void (*destroy)(accel *a);
    /* Switch the triangle test (may be NULL: only the watertight one). */
    bool (*use_triangle_test)(accel *a, triangle_test test);
} accel_ops;

/* Each structure's own type starts with this, so a pointer to it is a
 * pointer to an accel. */
struct accel {
    const accel_ops *ops;
    const triangle_set *set;
    accel_stats stats;
    /* Which ray-triangle test its closest and any hit run: the watertight
     * one (0, what a zeroed allocation gives), or Moller-Trumbore, which
     * only tests and benchmarks ask for (accel_use_triangle_test). */
    triangle_test triangle_test;
};

static inline bool accel_closest_hit(const accel *a, ray r, hit_record *hit, ray_counters *counters)
{
    return a->ops->closest_hit(a, r, hit, counters);
}

static inline bool accel_any_hit(const accel *a, ray r, ray_counters *counters)
{
    return a->ops->any_hit(a, r, counters);
}

static inline void accel_destroy(accel *a)
{
    if (a != NULL)
        a->ops->destroy(a);
}

/* Trace with `test` from now on: every structure runs the watertight test
 * unless told otherwise. Moller-Trumbore is there to be measured against:
 * the leak tests' twins, and the benchmark's column beside the watertight
 * one. A structure that stores its triangles in the form its test reads
 * (chapter 06's P0, E1, E2 for Moller-Trumbore; the corners for the
 * watertight test) rewrites them from the set. False if the structure has
 * no such choice (it then keeps its test). Not while rays are in flight. */
static inline bool accel_use_triangle_test(accel *a, triangle_test test)
{
    return a->ops->use_triangle_test != NULL && a->ops->use_triangle_test(a, test);
}

/* Brute force: every ray tests every triangle. The baseline every structure
 * must agree with, and beat. */
accel *brute_force_build(const triangle_set *set);
/* An accel_ops.use_triangle_test for structures that read the set's
 * triangles as they are (brute force, grid, kd-tree): sets the field. */
bool accel_use_triangle_test_of_set(accel *a, triangle_test test);

/* ---- looking at a mesh through any structure ------------------------------
 * What every accelerator chapter's program renders: the mesh lit by a light
 * at the eye (brightest where it faces the camera), or, with heatmap set, the
 * cost of each ray: the nodes or cells it visited plus the triangles it
 * tested, as a colour from dark blue (cheap) to yellow and white (expensive),
 * so you can see where a structure works hard. */
typedef struct {
    const accel *structure;
    bool heatmap;
    float heatmap_max_cost; /* the cost shown as white */
} accel_view;

vec3 accel_view_radiance(const void *view, ray r, pcg32 *rng, ray_counters *counters);
/* The view of the Embree harness's coherent ray set: from
 * c + unit(0.3, 0.4, 1) * 2.5 * half-diagonal, looking at the centre c of
 * the bounds, tan(vertical fov / 2) = 0.3. */
camera accel_view_camera(aabb bounds, int width, int height);
/* The ray sets of the Embree harness (../shared/anchors/embree_bench.c),
 * generated operation for operation as it does, for timing on the same work:
 * coherent, a 1024 x 1024 pinhole image of the bounds in scanline order;
 * incoherent, 2^20 rays with origins uniform in the bounds and directions
 * uniform on the sphere (splitmix64 from seed 0xBADC0DE). The caller frees. */
ray *accel_harness_rays(aabb bounds, bool coherent, int *count);

/* Rays aimed at the mesh itself, whatever a camera sees: origins uniform in
 * the bounds, each aimed at the centroid of a triangle picked uniformly, so
 * a mesh's dense parts get their share of the rays (the teapot, not the
 * empty stadium). Seeded PCG32; the caller frees. */
ray *accel_aimed_rays(const triangle_set *set, int count, uint64_t seed);
/* ---- scene files (scene_mesh.c) ---------------------------------------------
 * Chapters 03-06 trace triangles only, lit by a headlight: from a scene file
 * they take the triangle, quad and mesh shapes, appended to m in order, and
 * the camera. Each shape statement is one object (the tori field generator
 * gives one per torus): *object_first (allocated, may be NULL to skip) gets
 * object_count + 1 entries, object k owning faces [first[k], first[k+1]).
 * Everything else -- spheres, planes, tori, lights, materials, effects -- is
 * named in one warning each, not silently dropped. False with err
 * ("file:line:col: ...") if a mesh fails to load or there are no
 * triangles; m is then unchanged. */
bool accel_mesh_from_desc(mesh *m, const scene_desc *d, const char *label, int **object_first, int *object_count,
                          char *err, size_t err_size);
/* The scene file's camera if it has one, else accel_view_camera(bounds). */
camera accel_scene_camera(const scene_desc *d, aabb bounds, int width, int height);

/* ---- what the programs of chapters 04-06 share (accel_program.c) -------------
 * The mesh their flags ask for: --scene FILE (its triangles and camera),
 * else --obj FILE, else the procedural --mesh NAME: "tori" (the harness's
 * field of tori_triangles), "stadium" (the teapot in a stadium) or
 * "icosphere". On bad input prints "program: message" and returns the exit
 * status (1: a bad or empty file, 2: a bad flag), with nothing left to free;
 * 0 on success, and then accel_input_free releases it. */
typedef struct {
    mesh m;
    scene_desc desc;  /* --scene's description (empty without --scene) */
    const char *name; /* what was loaded, for messages */
    bool stadium;     /* the teapot in a stadium: seen by a spectator */
} accel_input;

int accel_input_load(accel_input *in, cli_options *opts, const char *program, const char *mesh_name,
                     const char *obj_path, int tori_triangles, int icosphere_subdivisions);
/* The scene file's camera, a spectator's in the stadium, else the harness's
 * view of the bounds. */
camera accel_input_camera(const accel_input *in, aabb bounds, int width, int height);
void accel_input_free(accel_input *in);
/* Times the harness's coherent or incoherent ray set (accel_harness_rays)
 * on one thread: the median of 3 runs of closest hit and of any hit, by the
 * wall clock and by this thread's CPU time, with the hit fraction, the sum of
 * t (to compare with Embree's) and the tests per ray. */
void accel_bench_harness(const accel *a, bool coherent);

/* The heat map's colour for cost / max_cost. */
vec3 accel_heat_colour(float fraction);

#endif
