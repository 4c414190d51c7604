/* small_bvh.h -- chapter 06's BVH, built for a small scene.
 *
 * Usage: accel *a = small_bvh_build(&set);   (then accel_closest_hit etc.)
 *
 * The same nodes and traversal as bvh_build(), but the tree is chosen by the
 * surface area heuristic at every split position (a sweep over the sorted
 * centroids, O(n log^2 n)), with the traversal cost measured for the path
 * tracer's rays. Meant for scenes of up to a few thousand triangles, where
 * the build takes microseconds to milliseconds.
 */
#ifndef SMALL_BVH_H
#define SMALL_BVH_H

#include "03-aabb-slabs/accel.h"

accel *small_bvh_build(const triangle_set *set);

#endif
