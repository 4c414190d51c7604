/* bvh_internal.h -- what bvh_build.c and bvh_traverse.c share, and nothing
 * else includes. */
#ifndef BVH_INTERNAL_H
#define BVH_INTERNAL_H

#include "bvh.h"

extern const accel_ops bvh_ops_axis_sign; /* BVH_ORDER_AXIS_SIGN */
extern const accel_ops bvh_ops_distance;  /* BVH_ORDER_DISTANCE */

/* The node array, placed so that each pair of children shares a cache line
 * (see bvh_build.c); free it with bvh_nodes_free(). */
bvh_node *bvh_nodes_allocate(int count);
void bvh_nodes_free(bvh_node *nodes);

/* bvh4_traverse.c's accel_ops for the default kernel (bvh4_build.c sets it). */
const accel_ops *bvh4_default_ops(void);

/* The SAH's constants, which the 4-wide BVH (bvh4.c) sets differently:
 * bvh_build() uses C_t = BVH_SAH_TRAVERSAL_COST, blocks of 1 and leaves of
 * at most BVH_SAH_MAX_LEAF_SIZE. */
typedef struct {
    float traversal_cost; /* C_t, with C_i = 1 */
    int leaf_block;       /* a leaf costs C_i per started block of this many triangles */
    int max_leaf_size;    /* split larger sets even when the SAH prefers a leaf */
} bvh_sah_params;

accel *bvh_build_with(const triangle_set *set, bvh_split split, const bvh_sah_params *sah);

/* Boxes are culled against the closest hit times this: see bvh_traverse.c
 * for why and how much. */
static const float BVH_CULL_SLACK = 1.0f + 0x1.0p-9f;

#endif
