/* bvh.h -- bounding volume hierarchies (GAMES101 lecture 14): partition the
 * objects, not space.
 *
 * Find the bounding box of all triangles, split the set of triangles in two
 * subsets, recompute the bounding box of each, and recurse; stop when a set
 * is small, and store its triangles in a leaf. A ray that misses a node's box
 * misses everything below it. Two ways to split:
 *
 *   BVH_SPLIT_MEDIAN  the lecture's heuristics: along the longest axis, at
 *                     the median object
 *   BVH_SPLIT_SAH     the surface area heuristic with binning (Wald 2007):
 *                     the split that minimises the expected cost of a ray
 *
 * Usage:
 *   accel *a = bvh_build(&set, BVH_SPLIT_SAH);
 *   if (accel_closest_hit(a, r, &hit, &counters)) ...
 *   printf("%d nodes, SAH cost %.1f\n", a->stats.nodes, bvh_sah_cost((const bvh *)a));
 *   accel_destroy(a);
 *
 * The tree is one flat array of 32-byte nodes, children side by side (the
 * second child of node n is nodes[n.first + 1]); the triangles are copied in
 * leaf order, so a leaf's triangles are contiguous.
 */
#ifndef BVH_H
#define BVH_H

#include <stdbool.h>
#include <stdint.h>

#include "03-aabb-slabs/accel.h"

typedef enum { BVH_SPLIT_MEDIAN, BVH_SPLIT_SAH } bvh_split;

/* Which child a ray visits first (both are correct; see bvh_traverse.c):
 *   BVH_ORDER_AXIS_SIGN  the child on the side the ray comes from along the
 *                        node's split axis (the sign of d on that axis)
 *   BVH_ORDER_DISTANCE   test both children's boxes, visit the one the ray
 *                        enters first; skip the other if it starts beyond
 *                        the closest hit found by then */
typedef enum { BVH_ORDER_AXIS_SIGN, BVH_ORDER_DISTANCE } bvh_order;

/* One node, 32 bytes: its box (6 floats) and two ints.
 *   interior: first = index of the first child (the second is first + 1),
 *             count_axis = 0 << 2 | split axis
 *   leaf:     first = index of its first triangle in bvh.triangles,
 *             count_axis = triangle count << 2 (count >= 1) */
typedef struct {
    union {
        aabb box;
        float bounds[6]; /* lo.x, lo.y, lo.z, hi.x, hi.y, hi.z: the same floats, by index */
    };
    int32_t first;
    uint32_t count_axis;
} bvh_node;

_Static_assert(sizeof(aabb) == 6 * sizeof(float), "bounds[] must be the box's six floats");
_Static_assert(sizeof(bvh_node) == 32, "a node is 32 bytes: two share a 64-byte cache line");

static inline int bvh_node_triangles(const bvh_node *n) { return (int)(n->count_axis >> 2); }
static inline int bvh_node_axis(const bvh_node *n) { return (int)(n->count_axis & 3u); }
static inline bool bvh_node_is_leaf(const bvh_node *n) { return n->count_axis >> 2 != 0; }

/* ---- the slab test, as the traversal runs it ---------------------------------
 * Chapter 03's slab test, aabb_slab_test(), made cheap enough to run for
 * every node: the same arithmetic and the same answer, bit for bit
 * (test_slab_test_matches_chapter_03), but inline (a call into another file
 * per node cost more than the test itself) and without a branch. Chapter 03
 * swaps t_min and t_max of an axis where 1/d < 0; here that choice is made
 * once per ray and kept as an index into the node's bounds[]: the plane met
 * first is lo where 1/d >= 0 and hi where 1/d < 0 (1/(-0) = -inf included),
 * as in Williams et al., "An Efficient and Robust Ray-Box Intersection
 * Algorithm" (2005). */
typedef struct {
    vec3 origin;
    vec3 inverse_direction; /* 1/d per axis */
    int near_x, near_y, near_z; /* index in bvh_node.bounds of the plane met first */
} bvh_ray;

/* aabb.c's SLAB_ROUNDING_PAD: 1 + 2 gamma(3), which covers the rounding of
 * t = (p - o) (1/d) in both t_enter and t_exit (see aabb.c). */
static const float BVH_SLAB_ROUNDING_PAD = 1.0f + 2.0f * (3.0f * 0x1.0p-24f) / (1.0f - 3.0f * 0x1.0p-24f);

static inline bvh_ray bvh_ray_make(const ray *r)
{
    bvh_ray b;
    b.origin = r->origin;
    b.inverse_direction = vec3_make(1.0f / r->direction.x, 1.0f / r->direction.y, 1.0f / r->direction.z);
    b.near_x = b.inverse_direction.x < 0.0f ? 3 : 0;
    b.near_y = b.inverse_direction.y < 0.0f ? 4 : 1;
    b.near_z = b.inverse_direction.z < 0.0f ? 5 : 2;
    return b;
}

/* Does the ray meet the node's box for some t in [t_min, t_max]? Returns
 * that, and t_enter (the first such t). The far plane of each axis is the
 * other one of its pair: 3 - near_x, 5 - near_y, 7 - near_z. */
static inline bool bvh_slab_test(const bvh_node *node, const bvh_ray *r, float t_min, float t_max, float *t_enter)
{
    const float *b = node->bounds;
    float near_x = (b[r->near_x] - r->origin.x) * r->inverse_direction.x;
    float far_x = (b[3 - r->near_x] - r->origin.x) * r->inverse_direction.x;
    float near_y = (b[r->near_y] - r->origin.y) * r->inverse_direction.y;
    float far_y = (b[5 - r->near_y] - r->origin.y) * r->inverse_direction.y;
    float near_z = (b[r->near_z] - r->origin.z) * r->inverse_direction.z;
    float far_z = (b[7 - r->near_z] - r->origin.z) * r->inverse_direction.z;
    /* t_enter = max t_min, t_exit = min t_max; a NaN leaves them as they are */
    float enter = t_min, exit = INFINITY;
    enter = near_x > enter ? near_x : enter;
    enter = near_y > enter ? near_y : enter;
    enter = near_z > enter ? near_z : enter;
    exit = far_x < exit ? far_x : exit;
    exit = far_y < exit ? far_y : exit;
    exit = far_z < exit ? far_z : exit;
    /* aabb.c pads each axis's t_max before the minimum; padding the minimum
     * gives the same float (rounding is monotonic: min(a p, b p) = min(a, b) p)
     * for one multiplication instead of three. */
    exit *= BVH_SLAB_ROUNDING_PAD;
    exit = t_max < exit ? t_max : exit;
    *t_enter = enter;
    return enter <= exit;
}

/* A triangle as Moller-Trumbore uses it: P0 and the edges E1 = P1 - P0,
 * E2 = P2 - P0, computed once at build time instead of once per test. */
typedef struct {
    vec3 p0, e1, e2;
} bvh_triangle;

/* Traversal keeps the nodes still to visit in a fixed array of this many
 * entries; the build never makes a tree deeper than this. */
enum { BVH_STACK_SIZE = 128 };

typedef struct {
    accel base;
    bvh_node *nodes; /* nodes[0] is the root */
    int node_count;
    bvh_triangle *triangles; /* in leaf order */
    int *triangle_index;     /* triangles[i] is set->triangles[triangle_index[i]] */
    int triangle_count;
    bvh_split split;
    bvh_order order;
} bvh;

accel *bvh_build(const triangle_set *set, bvh_split split);
/* The SAH tree with leaves of at most max_leaf_size triangles (bvh_build's
 * is 8; the SAH may stop earlier). Larger leaves: fewer nodes visited and
 * more triangles tested per ray, which chapter 09's counters show. */
accel *bvh_build_max_leaf(const triangle_set *set, int max_leaf_size);

/* Switch the traversal order of a built BVH (default BVH_ORDER_AXIS_SIGN,
 * the faster one on our measurements: README). */
void bvh_set_order(accel *a, bvh_order order);

/* Wrap a tree built by hand (for tests and exercises): the nodes are
 * copied; triangle_index[i] says which triangle of the set is at leaf
 * position i. Returns NULL if the nodes do not describe a valid tree over
 * exactly those positions (a child out of range, a leaf past the end). */
accel *bvh_from_nodes(const triangle_set *set, const bvh_node *nodes, int node_count, const int *triangle_index,
                      int triangle_count);

/* The tree's expected cost of a random ray, by the SAH: the sum over
 * interior nodes of C_t A(n) / A(root), plus over leaves of
 * C_i N(n) A(n) / A(root). Lower is better. */
double bvh_sah_cost(const bvh *b);

/* The SAH's bin of a centroid coordinate c, for bins of width 1/scale
 * starting at lo: floor((c - lo) * scale), clamped to 0 .. bin_count - 1.
 * A centroid exactly on the bounds' maximum gives bin_count before the
 * clamp, and so may one just below it, by rounding; NaN goes to bin 0. */
int bvh_bin_index(float c, float lo, float scale, int bin_count);

#endif
