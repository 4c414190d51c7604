/* ray.h -- the ray r(t) = o + t d, the hit record, and how to leave a surface.
 *
 * A ray is valid for t in the open interval (t_min, t_max). Shapes fill a
 * hit_record with everything shading needs, including a bound on the hit
 * point's error; ray_spawn() starts a new ray that far off the surface so
 * that it cannot hit the surface it is leaving (see below).
 */
#ifndef RAY_H
#define RAY_H

#include <stdbool.h>
#include "vec3.h"

typedef struct {
    vec3 origin;
    /* Need not be unit length. Camera rays and the rays that leave a surface
     * in a sampled or reflected direction are unit; a shadow ray from
     * ray_spawn_to() is the segment itself, from t = 0 to t = 1. */
    vec3 direction;
    float t_min, t_max;
} ray;

typedef struct {
    float t;                /* distance along the ray (in units of |d|) */
    vec3 point;             /* the hit point, computed from the surface, not o + t d */
    /* How far `point` may lie off the surface, along the normal, as the
     * intersection tests see it (its rounding, and theirs from an origin
     * that close): ray_point_error(). A ray leaving the surface starts this
     * far off it (ray_spawn). */
    float point_error;
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
 * What we do instead (after pbrt-v4, "Robust Spawned Ray Origins", and
 * Waechter and Binder, Ray Tracing Gems ch. 6): each hit carries a bound on
 * how far its point may be off the surface, and the new ray starts that far
 * along the normal, to the side it leaves to. The bound has two parts, each
 * a multiple of u = 2^-24, float's unit roundoff (one rounding moves a value
 * by at most u times its magnitude):
 *
 *   - the point's own coordinates: the hit point is rounded once at the end
 *     (shapes.h computes it as P0 + (b1 E1 + b2 E2), so for a small triangle
 *     far out that is all), and the offset origin once more. Only the
 *     rounding across the surface matters: |p_x| |n_x| + |p_y| |n_y| +
 *     |p_z| |n_z|, so a floor in the plane y = 0 is exact however far out
 *     it lies in x and z;
 *   - the primitive's size s (a triangle's longest edge component, a
 *     sphere's radius): the arithmetic inside the hit point (the edges and
 *     their weights), and the intersection tests' own arithmetic from an
 *     origin this close, which works in differences of nearby points and
 *     so errs by multiples of u s.
 *
 * A point on an edge lies on two surfaces, and the offset moves it off
 * only the one it was found on: from an origin that still lies in the
 * other's plane, an intersection test finds that plane at a t of pure
 * rounding, either sign (a floor point whose x rounded to the wall's
 * x = 0: of the rays leaving such points in tests/test_ch01.c, 21 % stop
 * on the wall). So a spawned ray also ignores hits within the error bound of its
 * origin (t_min), and a shadow ray within the far end's of its end (t_max):
 * nothing that near can be told from the surfaces the ends lie on.
 *
 * Both are relative to the geometry itself, so the offset scales with it,
 * from 1e-7 to 1e6, and grows with the distance from the origin only as
 * much as one rounding there does: a sphere of radius 1 at 1e5 is left
 * about 2 u |p| = 0.012 off its surface (256 ulps of every coordinate
 * would be 2 there, beyond its far side), a box 1e-4 across near 0 about
 * 4e-10 (a fixed 2^-16 would be 15 % of it).
 *
 * These are static inline: every path vertex spawns one or two rays, and a
 * call into another file per ray cost more than the offset itself. */

/* u: a rounding to nearest moves a float by at most this times its magnitude. */
static const float RAY_FLOAT_ROUNDING = 0x1.0p-24f;
/* Roundings of the point's own coordinates the offset covers: the hit
 * point's last rounding and the offset origin's, each at most u |x| (half a
 * float step, and u |x| is between half a step and a whole one). A bound,
 * so no margin on top (measured on random triangles and spheres as in
 * tests/test_ch01.c: with 1, 735 of 2.3 million spawned rays re-hit their
 * surface; with 1.5, none). Far out a margin shows: at 1e5 a step is
 * 0.0078, and 4 roundings, 3 steps, were 4 % of the Cornell box scaled to
 * 0.55 there; rays from its walls ignored the floor within t_min, and its
 * corners darkened (tests/test_ch09.c: chi-square 414 on 256 pixels
 * against the box moved back to 0, 302 with 2). */
static const float OFFSET_POINT_ROUNDINGS = 2.0f;
/* Roundings of the primitive's size the offset covers: the hit point's
 * inner arithmetic (about 3) and the intersection tests' from a nearby
 * origin. Measured on random triangles, Moller-Trumbore and the watertight
 * test, no sliver thinner than 2 area / longest edge^2 = 0.01, and on
 * spheres: 16 suffices; 64 is four times that. The tests' arithmetic at
 * the far end of a shadow ray is in units of its whole length: the far end
 * moves back by the same multiple of the length (ray_offset_far_end). */
static const float OFFSET_SIZE_ROUNDINGS = 64.0f;

/* The bound for a point computed on a primitive of size `size` whose unit
 * normal is n (either orientation): what a hit record's point_error holds. */
static inline float ray_point_error(vec3 point, vec3 n, float size)
{
    vec3 p = vec3_abs(point), m = vec3_abs(n);
    float across = p.x * m.x + p.y * m.y + p.z * m.z;
    return RAY_FLOAT_ROUNDING * (OFFSET_POINT_ROUNDINGS * across + OFFSET_SIZE_ROUNDINGS * size);
}

/* A hit point moved off its surface by its error bound, to the side that
 * the unit normal `side` points to. */
static inline vec3 ray_offset_origin(vec3 point, float point_error, vec3 side)
{
    return vec3_add(point, vec3_scale(side, point_error));
}

/* A new ray leaving the surface at `point` (error bound point_error,
 * geometric normal n, either orientation) in `direction`: the origin is
 * offset to the side direction goes to, so the ray cannot re-hit the
 * surface it leaves, and hits within point_error of it are not counted. */
static inline ray ray_spawn(vec3 point, float point_error, vec3 n, vec3 direction)
{
    vec3 side = vec3_dot(direction, n) < 0.0f ? vec3_neg(n) : n;
    ray r = ray_make(ray_offset_origin(point, point_error, side), direction);
    r.t_min = point_error / vec3_length(direction);
    return r;
}

/* The far end of a segment of length `length`, on a surface with unit
 * normal `side` (facing the segment's start), pulled off that surface
 * (ray_offset_far_end) by ray_far_end_pull().
 * Its own error bound is not enough: the intersection test's arithmetic for
 * the far end's surface works from the segment's start, in units of the
 * whole segment, and errs by multiples of u times the length (a wall in the
 * plane x = 0 and a light 500 units away: measured, 4 % of the shadow rays
 * from the light stopped on the wall when the far end moved by its
 * coordinates' rounding alone). So it moves back by OFFSET_SIZE_ROUNDINGS
 * roundings of the length as well. */
static inline float ray_far_end_pull(float target_error, float length)
{
    return target_error + OFFSET_SIZE_ROUNDINGS * RAY_FLOAT_ROUNDING * length;
}

static inline vec3 ray_offset_far_end(vec3 target, float target_error, vec3 side, float length)
{
    return ray_offset_origin(target, ray_far_end_pull(target_error, length), side);
}

/* A shadow ray from `point` (error bound point_error, geometric normal n)
 * towards `target`, ending just short of it. A target on a surface (an
 * area light sample: target_normal non-zero, error bound target_error) is
 * pulled off that surface to the side facing the origin, so the shadow ray
 * stops before it; a target with target_normal zero (a point light) is
 * kept. t runs along direction = end - origin, which is not unit length,
 * from the origin's error bound (t_min) to the far end's short of 1
 * (t_max), in units of the segment's length. */
static inline ray ray_spawn_to(vec3 point, float point_error, vec3 n, vec3 target, float target_error,
                               vec3 target_normal)
{
    vec3 to_target = vec3_sub(target, point);
    float length = vec3_length(to_target);
    vec3 side = vec3_dot(to_target, n) < 0.0f ? vec3_neg(n) : n;
    vec3 origin = ray_offset_origin(point, point_error, side);
    float pull = 0.0f;
    if (vec3_length_squared(target_normal) > 0.0f) {
        vec3 target_side = vec3_dot(vec3_sub(origin, target), target_normal) < 0.0f ? vec3_neg(target_normal) : target_normal;
        pull = ray_far_end_pull(target_error, length);
        target = ray_offset_origin(target, pull, target_side);
    }
    ray r = ray_make(origin, vec3_sub(target, origin));
    /* in units of the segment (one division: they are on every shadow ray's
     * way); a segment of length 0 is empty, t_min = 0 > t_max = -inf */
    float per_length = 1.0f / length;
    r.t_min = length > 0.0f ? point_error * per_length : 0.0f;
    r.t_max = length > 0.0f ? 1.0f - pull * per_length : -INFINITY;
    return r;
}

/* ---- what float can place: objects too small for where they are ---------
 * Floats are spaced in proportion to their magnitude: at 1e5 one step is
 * 2^-7 = 0.0078. An object only a few steps across there has its corners
 * rounded by a good part of its size, and the offsets above (2 roundings of
 * its coordinates: up to 3.5 steps, 2 for a face along an axis) are a good
 * part of it too. No offset fixes that; moving the scene near the origin
 * does. The programs say so before rendering (pt_scene_check_scale). */

/* The gap between the float `magnitude` (>= 0) and the next one up. */
static inline float ray_float_step(float magnitude) { return nextafterf(magnitude, INFINITY) - magnitude; }

/* An object must be at least this many float steps (at the magnitude of
 * its coordinates) across: its corners are then placed within 1/128 of
 * its size, and rays leave it at most about a twentieth of its size off
 * its surface. Fewer, and its shading and shadows visibly change. */
static const float RAY_MIN_STEPS_ACROSS = 64.0f;

/* Is an object `extent` across (its largest dimension), whose coordinates
 * reach `magnitude` (the largest |x|, |y|, |z| of its bounds), too small
 * for float to place it and its rays? */
static inline bool ray_too_small_for_position(float extent, float magnitude)
{
    return extent < RAY_MIN_STEPS_ACROSS * ray_float_step(magnitude);
}

#endif
