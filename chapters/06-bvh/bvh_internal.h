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

#endif
