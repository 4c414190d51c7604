/* aabb.c -- boxes and the slab test. */
#include "03-aabb-slabs/aabb.h"

float aabb_surface_area(aabb b)
{
    if (aabb_is_empty(b))
        return 0.0f;
    vec3 e = aabb_extent(b);
    return 2.0f * (e.x * e.y + e.y * e.z + e.z * e.x);
}

int aabb_longest_axis(aabb b)
{
    vec3 e = aabb_extent(b);
    if (e.x >= e.y && e.x >= e.z)
        return 0;
    return e.y >= e.z ? 1 : 2;
}

slab_ray slab_ray_make(ray r)
{
    /* 1/d: a zero component gives +inf or -inf by the sign of the zero,
     * which is exactly the slope of a ray parallel to those planes. */
    return (slab_ray){r.origin, vec3_make(1.0f / r.direction.x, 1.0f / r.direction.y, 1.0f / r.direction.z)};
}

/* Every float operation rounds by at most half an ulp, a relative 2^-24. The
 * plane distances (p - o) * (1/d) take three roundings (subtraction, the
 * reciprocal, the product), so a computed t is within gamma(3) = 3u / (1 - 3u)
 * of the exact one. Growing t_exit by 2 gamma(3) covers the error of both
 * t_enter and t_exit (Ize, "Robust BVH Ray Traversal", 2013; pbrt's
 * Bounds3::IntersectP does the same). Without it, a ray through a flat box
 * (the box of a triangle lying in a plane x = c) can compute t_enter one ulp
 * above t_exit and miss the triangle inside. */
static const float SLAB_ROUNDING_PAD = 1.0f + 2.0f * (3.0f * 0x1.0p-24f) / (1.0f - 3.0f * 0x1.0p-24f);

bool aabb_slab_test(const aabb *box, const slab_ray *r, float ray_t_min, float ray_t_max, float *t_enter,
                    float *t_exit)
{
    /* exercise: slab_test */
    float enter = ray_t_min, exit = ray_t_max;
    for (int axis = 0; axis < 3; axis++) {
        float inverse = vec3_axis(r->inverse_direction, axis);
        float origin = vec3_axis(r->origin, axis);
        /* t_min and t_max for this pair of planes */
        float t_near = (vec3_axis(box->lo, axis) - origin) * inverse;
        float t_far = (vec3_axis(box->hi, axis) - origin) * inverse;
        /* A negative direction meets the hi plane first. Decided by the
         * sign of 1/d, not by comparing the two t: one of them may be NaN
         * (below), and a comparison with NaN is always false. */
        if (inverse < 0.0f) {
            float swap = t_near;
            t_near = t_far;
            t_far = swap;
        }
        t_far *= SLAB_ROUNDING_PAD;
        /* t_enter = max t_min, t_exit = min t_max. Written as comparisons
         * that are false for NaN: a ray parallel to a slab with its origin
         * exactly on one of the planes gives 0 * inf = NaN, and then this
         * axis leaves the interval as it is (the ray runs along the plane,
         * which counts as touching the box). */
        enter = t_near > enter ? t_near : enter;
        exit = t_far < exit ? t_far : exit;
        /* The box is missed as soon as the interval is empty. A box the ray
         * only touches (t_enter == t_exit: an edge, a corner, a flat box)
         * counts as hit: a box that is too large costs a little time; one
         * that is too small loses the triangle inside. */
        if (enter > exit)
            return false;
    }
    *t_enter = enter;
    *t_exit = exit;
    return true;
    /* end of exercise slab_test */
}

bool aabb_slab_test_naive(const aabb *box, ray r, float *t_enter, float *t_exit)
{
    float enter = -INFINITY, exit = INFINITY;
    for (int axis = 0; axis < 3; axis++) {
        float d = vec3_axis(r.direction, axis), o = vec3_axis(r.origin, axis);
        float t1 = (vec3_axis(box->lo, axis) - o) / d;
        float t2 = (vec3_axis(box->hi, axis) - o) / d;
        float t_min = t1 < t2 ? t1 : t2, t_max = t1 < t2 ? t2 : t1;
        /* max and min as they are often written; with t_min = NaN (0/0 for
         * an origin on a plane it runs parallel to) they return NaN, and
         * every comparison after that is false. */
        enter = enter > t_min ? enter : t_min;
        exit = exit < t_max ? exit : t_max;
    }
    *t_enter = enter;
    *t_exit = exit;
    /* The lecture's condition, exactly: t_enter < t_exit and t_exit >= 0. */
    return enter < exit && exit >= 0.0f;
}
