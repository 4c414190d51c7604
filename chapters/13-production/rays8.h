/* rays8.h -- eight rays as one bundle, and their nearest hits.
 *
 * What every eight-ray kernel of this chapter takes and gives: the flat
 * set's (flat.h, flat_closest_hit8_raw), the wide BVH's walk of eight rays
 * (wide_trace.h), the walls' test of eight shadow rays (walls.h), and the
 * eight-path renderer (path_tracer_wide.h), which keeps its lanes' rays
 * this way from bounce to bounce. Structure of arrays: coordinate c of
 * lane k's origin is origin[c][k], so an AVX instruction reads one
 * coordinate of all eight rays.
 *
 * Usage:
 *   rays8 rays;
 *   rays8_set(&rays, k, r);        lane k holds ray r
 *   ray r = rays8_get(&rays, k);   and gives it back, bit for bit
 */
#ifndef RAYS8_H
#define RAYS8_H

#include <stdint.h>

#include "ray.h"

enum { RAYS8_LANES = 8 };

/* The eight rays: by coordinate, then by lane. */
typedef struct {
    _Alignas(32) float origin[3][RAYS8_LANES], direction[3][RAYS8_LANES];
    float t_min[RAYS8_LANES], t_max[RAYS8_LANES];
} rays8;

static inline void rays8_set(rays8 *rays, int k, ray r)
{
    const float o[3] = {r.origin.x, r.origin.y, r.origin.z}, d[3] = {r.direction.x, r.direction.y, r.direction.z};
    for (int c = 0; c < 3; c++) {
        rays->origin[c][k] = o[c];
        rays->direction[c][k] = d[c];
    }
    rays->t_min[k] = r.t_min;
    rays->t_max[k] = r.t_max;
}

static inline ray rays8_get(const rays8 *rays, int k)
{
    ray r = ray_make(vec3_make(rays->origin[0][k], rays->origin[1][k], rays->origin[2][k]),
                     vec3_make(rays->direction[0][k], rays->direction[1][k], rays->direction[2][k]));
    r.t_min = rays->t_min[k];
    r.t_max = rays->t_max[k];
    return r;
}

/* The nearest hits of eight rays before their hit records are made: lane
 * k's nearest t, the index of its triangle in the set and the barycentrics
 * b1, b2, what triangle_set_fill_hit() makes lane k's record from. For a
 * caller that makes its own records, eight at a time (path_tracer_wide.c).
 * The entries of lanes that did not hit mean nothing. */
typedef struct {
    _Alignas(32) float t[RAYS8_LANES];
    int32_t index[RAYS8_LANES];
    float b1[RAYS8_LANES], b2[RAYS8_LANES];
} hits8;

#endif
