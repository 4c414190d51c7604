/* aabb.h -- axis-aligned bounding boxes and the slab test (lecture 13).
 *
 * A box is the intersection of three slabs, each the space between two
 * parallel planes: lo.x <= x <= hi.x, and the same for y and z. A ray meets
 * the box in the interval where it is inside all three slabs at once.
 *
 * Usage:
 *   aabb box = aabb_empty(); box = aabb_add_point(box, p); ...
 *   slab_ray sr = slab_ray_make(r);          once per ray: 1/d per axis
 *   float t_enter, t_exit;
 *   if (aabb_slab_test(&box, &sr, r.t_min, r.t_max, &t_enter, &t_exit)) ...
 */
#ifndef AABB_H
#define AABB_H

#include <stdbool.h>

#include "ray.h"

typedef struct {
    vec3 lo, hi;
} aabb;

/* A box containing nothing (lo = +inf, hi = -inf): the identity of union. */
static inline aabb aabb_empty(void) { return (aabb){vec3_splat(INFINITY), vec3_splat(-INFINITY)}; }
static inline aabb aabb_add_point(aabb b, vec3 p) { return (aabb){vec3_min(b.lo, p), vec3_max(b.hi, p)}; }
static inline aabb aabb_union(aabb a, aabb b) { return (aabb){vec3_min(a.lo, b.lo), vec3_max(a.hi, b.hi)}; }
static inline vec3 aabb_centroid(aabb b) { return vec3_scale(vec3_add(b.lo, b.hi), 0.5f); }
static inline vec3 aabb_extent(aabb b) { return vec3_sub(b.hi, b.lo); }
static inline bool aabb_is_empty(aabb b) { return !(b.lo.x <= b.hi.x && b.lo.y <= b.hi.y && b.lo.z <= b.hi.z); }
/* Surface area, the SAH's measure of how likely a random ray is to hit. */
float aabb_surface_area(aabb b);
/* 0, 1 or 2: the axis along which the box is longest. */
int aabb_longest_axis(aabb b);

/* What the slab test needs of a ray, computed once per ray and reused for
 * every box: the origin and 1/d per axis. 1/(+0) = +inf and 1/(-0) = -inf,
 * both meaningful here (see aabb.c). */
typedef struct {
    vec3 origin;
    vec3 inverse_direction;
} slab_ray;

slab_ray slab_ray_make(ray r);

/* The slab test. For each axis, the ray is between the two planes for t in
 * [t_min, t_max] of that pair; t_enter = max of the t_min, t_exit = min of
 * the t_max, both clipped to the ray's [ray_t_min, ray_t_max]. The ray meets
 * the box iff t_enter <= t_exit. Returns that, and the interval. */
bool aabb_slab_test(const aabb *box, const slab_ray *r, float ray_t_min, float ray_t_max, float *t_enter,
                    float *t_exit);

/* The lecture's slab test without the robustness (no padding; NaN from
 * 0 * inf goes where it may; strict t_enter < t_exit). Kept to show, in the
 * tests and the text, what each fix in aabb_slab_test() prevents. */
bool aabb_slab_test_naive(const aabb *box, ray r, float *t_enter, float *t_exit);

#endif
