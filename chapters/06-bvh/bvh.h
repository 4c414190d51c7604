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
 *                        the closest hit found by then
 *   BVH_ORDER_RECURSIVE  the slide's Intersect(ray, node): both children,
 *                        recursively, the closer of their hits (any hit
 *                        too: a shadow ray asks for the closest) */
typedef enum { BVH_ORDER_AXIS_SIGN, BVH_ORDER_DISTANCE, BVH_ORDER_RECURSIVE } bvh_order;

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

/* A triangle as the traversal's triangle test reads it (accel.triangle_test):
 *   watertight (the default)  its three corners; a degenerate triangle
 *                             (triangle_is_degenerate) as NaN corners, which
 *                             no ray hits, so the test need not ask
 *   Moller-Trumbore           P0 and the edges E1 = P1 - P0, E2 = P2 - P0,
 *                             computed once at build time instead of once
 *                             per test
 * accel_use_triangle_test() rewrites them from the set. */
typedef struct {
    vec3 p0;
    union {
        struct {
            vec3 p1, p2;
        };
        struct {
            vec3 e1, e2;
        };
    };
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

/* The lecture's traversal (lecture 14's pseudocode, in bvh_traverse.c):
 * recursive; if the ray misses a node's box, nothing; a leaf returns its
 * closest hit; an interior node visits both children and returns the closer
 * of their hits. Brute force's answer, bit for bit (at equal t, the lower
 * triangle index, as brute force), found by visiting more nodes than
 * accel_closest_hit() does, which skips boxes beyond the closest hit so far.
 * Counts its box and triangle tests in counters, as every traversal does. */
bool bvh_closest_hit_recursive(const bvh *b, ray r, hit_record *hit, ray_counters *counters);

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
