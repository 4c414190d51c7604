/* ray.h -- the ray r(t) = o + t d, the hit record, and how to leave a surface.
 *
 * A ray is valid for t in the open interval (t_min, t_max). Shapes fill a
 * hit_record with everything shading needs; ray_spawn() starts a new ray at a
 * hit point so that it cannot hit the surface it is leaving (see below).
 */
#ifndef RAY_H
#define RAY_H

#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "vec3.h"

typedef struct {
    vec3 origin;
    vec3 direction; /* need not be unit length, but every chapter keeps it so */
    float t_min, t_max;
} ray;

typedef struct {
    float t;                /* distance along the ray (in units of |d|) */
    vec3 point;             /* the hit point, computed from the surface, not o + t d */
    vec3 normal_geometric;  /* unit, faces the side the ray came from */
    vec3 normal_shading;    /* unit, interpolated where the shape has vertex normals */
    float u, v;             /* barycentrics (triangles) or surface parameters */
    int shape_id;           /* which shape or triangle was hit */
    int material_id;
    bool front_face;        /* true if the ray hit the outside (against the outward normal) */
} hit_record;

static inline ray ray_make(vec3 origin, vec3 direction)
{
    return (ray){origin, direction, 0.0f, INFINITY};
}

static inline vec3 ray_at(ray r, float t) { return vec3_add(r.origin, vec3_scale(r.direction, t)); }

/* ---- leaving a surface without hitting it again ("shadow acne") ----------
 *
 * A hit point is rounded to the nearest float, so it lies a little in front
 * of or behind the true surface. A ray started exactly there may hit the
 * surface it leaves at a tiny t: black speckles on lit surfaces (shadow acne)
 * and rays that refract twice. The common fix, "ignore hits with t < 0.001",
 * fails both ways: at large scales 0.001 is below the rounding error of the
 * coordinates, and at small scales it skips real hits (a contact shadow, a
 * thin sheet of glass).
 *
 * What we do instead (Waechter and Binder, "A Fast and Robust Method for
 * Avoiding Self-Intersection", Ray Tracing Gems, 2019): move the origin along
 * the normal by a fixed number of units in the last place of each coordinate.
 * Rounding error of a hit point computed from the surface (barycentric
 * combination, or re-projection onto a sphere) is a few ulps of the
 * coordinates' magnitude, so an offset of ORIGIN_OFFSET_ULPS ulps is safely
 * larger at every scale, yet is still a relative 1.5e-5 of the coordinate.
 * Near zero the ulp becomes tiny (denormals), so below ORIGIN_NEAR_ZERO we add
 * a small fixed offset instead.
  *
 * These are static inline: every path vertex spawns one or two rays, and a
 * call into another file per ray cost more than the offset itself. */

/* How many float ulps to move along the normal. The hit-point error of our
 * shapes is at most about 8 ulps of the largest coordinate involved; 256 gives
 * a 32x margin and stays invisible (1.5e-5 relative). */
static const float ORIGIN_OFFSET_ULPS = 256.0f;
/* Below this magnitude a coordinate's ulp is too small to be a useful offset. */
static const float ORIGIN_NEAR_ZERO = 1.0f / 32.0f;
/* The fixed offset used there: comfortably above the float error of values
 * near ORIGIN_NEAR_ZERO (whose ulp is 2^-28). */
static const float ORIGIN_FIXED_OFFSET = 1.0f / 65536.0f;

static inline float ray_float_from_bits(int32_t i)
{
    float f;
    memcpy(&f, &i, sizeof f);
    return f;
}

static inline int32_t ray_bits_from_float(float f)
{
    int32_t i;
    memcpy(&i, &f, sizeof i);
    return i;
}

static inline float ray_offset_coordinate(float p, float n)
{
    if (fabsf(p) < ORIGIN_NEAR_ZERO)
        return p + ORIGIN_FIXED_OFFSET * n;
    /* Moving away from zero adds to the bit pattern's magnitude, moving
     * towards zero subtracts; the sign bit makes negative floats count down. */
    int32_t ulps = (int32_t)(ORIGIN_OFFSET_ULPS * n);
    return ray_float_from_bits(ray_bits_from_float(p) + (p < 0.0f ? -ulps : ulps));
}

/* Offset a hit point off its surface, to the side that normal n points to.
 * Robust at every scale: see above. */
static inline vec3 ray_offset_origin(vec3 point, vec3 n)
{
    return vec3_make(ray_offset_coordinate(point.x, n.x), ray_offset_coordinate(point.y, n.y),
                     ray_offset_coordinate(point.z, n.z));
}

/* A new ray leaving the surface at `point` (with geometric normal n, either
 * orientation) in `direction`: the origin is offset to the side direction
 * goes to, so the ray cannot re-hit the surface it leaves. */
static inline ray ray_spawn(vec3 point, vec3 n, vec3 direction)
{
    /* Offset to the side the new ray goes to. */
    vec3 side = vec3_dot(direction, n) < 0.0f ? vec3_neg(n) : n;
    return ray_make(ray_offset_origin(point, side), direction);
}

/* The far end of a segment of length `length`, on a surface with normal
 * `side` (facing the segment's start), pulled off that surface. The
 * intersection test's t for the far end's own surface is rounded in units
 * of the whole segment: its error along the ray is a few ulps of `length`,
 * not of the end's coordinates. Far from zero ray_offset_origin's 256 ulps
 * of each coordinate cover that; near zero (a wall in the plane x = 0 and a
 * light 500 units away) its fixed 2^-16 does not, and a shadow ray would
 * stop on the wall it aims at. So the end moves at least ORIGIN_OFFSET_ULPS
 * ulps of the length along the normal, whichever is farther. */
static inline vec3 ray_offset_far_end(vec3 target, vec3 side, float length)
{
    vec3 by_coordinates = ray_offset_origin(target, side);
    float minimum = length * (ORIGIN_OFFSET_ULPS * 0x1.0p-24f);
    if (vec3_dot(vec3_sub(by_coordinates, target), side) >= minimum)
        return by_coordinates;
    return vec3_add(target, vec3_scale(side, minimum));
}

/* A shadow ray from `point` towards `target`, ending just short of it (the
 * end is offset too, so a ray to a light sample on a surface does not hit
 * that surface). t runs from 0 to 1 along direction = target - origin. */
static inline ray ray_spawn_to(vec3 point, vec3 n, vec3 target, vec3 target_normal)
{
    vec3 to_target = vec3_sub(target, point);
    vec3 side = vec3_dot(to_target, n) < 0.0f ? vec3_neg(n) : n;
    vec3 origin = ray_offset_origin(point, side);
    if (vec3_length_squared(target_normal) > 0.0f) {
        /* A target on a surface (an area light sample): pull it to the side
         * facing the origin, so the shadow ray stops before that surface. */
        vec3 target_side = vec3_dot(vec3_sub(origin, target), target_normal) < 0.0f ? vec3_neg(target_normal) : target_normal;
        target = ray_offset_far_end(target, target_side, vec3_length(to_target));
    }
    ray r = ray_make(origin, vec3_sub(target, origin));
    r.t_max = 1.0f;
    return r;
}

#endif
