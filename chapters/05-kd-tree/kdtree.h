/* kdtree.h -- a kd-tree built by the surface area heuristic (GAMES101
 * lecture 14: spatial partitions).
 *
 * A kd-tree cuts space, not the list of objects: every interior node splits
 * its box by one axis-aligned plane into a "below" and an "above" child, and
 * a triangle that straddles the plane goes to both. A ray walks the cells it
 * crosses front to back and stops at the first cell whose triangles give a
 * hit inside that cell.
 *
 * Usage:
 *   accel *a = kdtree_build(&tris);                    the default costs
 *   kdtree_options o = kdtree_default_options();
 *   o.max_depth = 1; accel *one_split = kdtree_build_with(&tris, &o);
 *   accel_closest_hit(a, r, &hit, &counters); ... accel_destroy(a);
 *   const kd_tree *t = (const kd_tree *)a;            nodes, SAH cost, leaves
 *
 * Build: Wald and Havran's O(N log N) sweep over sorted "events" (where each
 * triangle's box starts, ends, or lies flat), see kdtree.c. Traversal: a
 * small stack, near child first, see kdtree_trace.c.
 */
#ifndef KDTREE_H
#define KDTREE_H

#include <stdbool.h>
#include <stdint.h>

#include "03-aabb-slabs/accel.h"

/* ---- one node: 8 bytes --------------------------------------------------
 * The low 2 bits of `bits` hold the split axis (0, 1, 2) or 3 for a leaf; the
 * other 30 bits hold, for an interior node, the index of its above child (the
 * below child is always the next node in the array), and for a leaf its
 * number of triangles. The first word is the split position, or for a leaf
 * the offset of its first triangle index in kd_tree.references. */
typedef struct {
    union {
        float split;
        uint32_t first_reference;
    };
    uint32_t bits;
} kd_node;

enum { KD_LEAF_TAG = 3, KD_MAX_DEPTH = 60 };

static inline bool kd_node_is_leaf(const kd_node *n) { return (n->bits & 3u) == KD_LEAF_TAG; }
static inline int kd_node_axis(const kd_node *n) { return (int)(n->bits & 3u); }
static inline uint32_t kd_node_above_child(const kd_node *n) { return n->bits >> 2; }
static inline uint32_t kd_node_triangle_count(const kd_node *n) { return n->bits >> 2; }

/* The SAH's constants and the depth limit (see kdtree.c for the values). */
typedef struct {
    float traversal_cost;    /* C_traverse: one step down the tree */
    float intersection_cost; /* C_isect: one ray-triangle test */
    float empty_bonus;       /* cost factor for a split with one empty side (< 1 favours cutting off empty space) */
    int max_depth;           /* 0: 8 + 1.3 log2 N */
} kdtree_options;

kdtree_options kdtree_default_options(void);

typedef struct {
    accel base;
    kd_node *nodes;           /* nodes[0] is the root */
    uint32_t *references;     /* leaf triangle indices, leaf by leaf */
    aabb bounds;              /* the root's box */
    kdtree_options options;
    int depth_limit;          /* the max depth actually used */
    int empty_leaves;
    double sah_cost;          /* the model's expected cost of a random ray, in C_isect units of the formula */
    float fixed_hit_margin;   /* 0: stop by the hit's error bound (kdtree_trace.c); > 0: the earlier
                                 fixed relative margin, kept for a test's twin */
} kd_tree;

accel *kdtree_build(const triangle_set *set);
accel *kdtree_build_with(const triangle_set *set, const kdtree_options *options);

/* The SAH cost of splitting `box` at `split` on `axis` with n_below and
 * n_above triangles on the two sides:
 *   C_traverse + (SA_below/SA) N_below C_isect + (SA_above/SA) N_above C_isect,
 * times empty_bonus when one side is empty. Against a leaf's N C_isect. */
float kdtree_split_cost(const kdtree_options *o, aabb box, int axis, float split, int n_below, int n_above);

/* A bound on |t - t*| for a hit at t on tri by `test` (t* the exact
 * distance to the triangle's plane): the walk goes on past a hit into every
 * cell that starts within it (kdtree_trace.c says why and derives it).
 * Infinite when the ray lies in the plane to within rounding. */
float kdtree_hit_t_error(triangle_test test, const triangle *tri, const ray *r, float t);

/* 8 + 1.3 log2 N, rounded down, at most KD_MAX_DEPTH. */
int kdtree_depth_limit(int triangle_count);

#endif
