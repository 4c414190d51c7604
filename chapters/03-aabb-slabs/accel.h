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
 *
 * What is built on the interface has headers of its own: accel_view.h (a
 * mesh rendered through any structure, or the cost of each ray) and
 * accel_program.h (what the programs of chapters 03-06 share: the mesh
 * their flags ask for, the Embree harness's ray sets and their timing).
 */
#ifndef ACCEL_H
#define ACCEL_H

#include <stdbool.h>
#include <stddef.h>

#include "01-ray-casting/shapes.h"
#include "03-aabb-slabs/aabb.h"
#include "counters.h"
#include "mesh.h"

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

/* ---- a structure's walk behind accel_ops -------------------------------------------
 * Brute force, the grid and the kd-tree each walk their cells or nodes in a
 * function of one shape: walk(structure, ray *r, mode, triangle_test,
 * float *b1, float *b2, ray_counters *), which returns the index of the
 * triangle found (-1: none; mode says closest or any), r->t_max cut to its
 * t, and its barycentrics. ACCEL_WALK calls it with the structure's test
 * as a constant, so that the walk is compiled once per test (the test
 * inlined into its loop); accel_walk_hit() makes closest_hit's record of
 * what it found. */
#define ACCEL_WALK(a, walk, structure, r, mode, b1, b2, counters)                                             \
    ((a)->triangle_test == TRIANGLE_TEST_WATERTIGHT                                                          \
         ? walk(structure, r, mode, TRIANGLE_TEST_WATERTIGHT, b1, b2, counters)                              \
         : walk(structure, r, mode, TRIANGLE_TEST_MOLLER_TRUMBORE, b1, b2, counters))

static inline bool accel_walk_hit(const accel *a, int found, ray r, float b1, float b2, hit_record *hit)
{
    if (found < 0)
        return false;
    triangle_set_fill_hit(a->set, found, r, r.t_max, b1, b2, hit);
    return true;
}

/* Brute force: every ray tests every triangle. The baseline every structure
 * must agree with, and beat. */
accel *brute_force_build(const triangle_set *set);
/* An accel_ops.use_triangle_test for structures that read the set's
 * triangles as they are (brute force, grid, kd-tree): sets the field. */
bool accel_use_triangle_test_of_set(accel *a, triangle_test test);

#endif
