/* ray.h -- the ray r(t) = o + t d, the hit record, and how to leave a surface.
 *
 * A ray is valid for t in the open interval (t_min, t_max). Shapes fill a
 * hit_record with everything shading needs; ray_spawn() starts a new ray at a
 * hit point so that it cannot hit the surface it is leaving (see ray.c).
 */
#ifndef RAY_H
#define RAY_H

#include <stdbool.h>
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

/* Offset a hit point off its surface, to the side that normal n points to.
 * Robust at every scale: see the comment in ray.c. */
vec3 ray_offset_origin(vec3 point, vec3 n);

/* A new ray leaving the surface at `point` (with geometric normal n, either
 * orientation) in `direction`: the origin is offset to the side direction
 * goes to, so the ray cannot re-hit the surface it leaves. */
ray ray_spawn(vec3 point, vec3 n, vec3 direction);

/* A shadow ray from `point` towards `target`, ending just short of it (the
 * end is offset the same way, so a ray to a light sample on a surface does
 * not hit that surface). t runs from 0 to 1 along direction = target - origin. */
ray ray_spawn_to(vec3 point, vec3 n, vec3 target, vec3 target_normal);

#endif
