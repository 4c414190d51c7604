/* shapes.h -- ray-surface intersection for lecture 13's shapes.
 *
 * Each *_intersect(shape, ray, &hit) returns true and fills hit when the ray
 * meets the shape at some t in (r.t_min, r.t_max), the closest such t.
 * hit.normal_geometric faces the incoming ray; hit.front_face says whether
 * that is the outward side. shape_id and material_id are left to the caller.
 */
#ifndef SHAPES_H
#define SHAPES_H

#include <stdbool.h>
#include "ray.h"

typedef struct {
    vec3 center;
    float radius;
} sphere;

/* The plane (p - point) . normal = 0; normal is unit. */
typedef struct {
    vec3 point;
    vec3 normal;
} plane;

/* Counter-clockwise p0, p1, p2 seen from the front (outward) side. */
typedef struct {
    vec3 p0, p1, p2;
} triangle;

/* A torus around the y axis: tube radius `minor` swept along a circle of
 * radius `major`, as the implicit surface f(p) = 0 with
 *   f(p) = sqrt( (sqrt(x^2 + z^2) - R)^2 + y^2 ) - r.
 * f is the signed distance to the surface, so |grad f| = 1: see
 * implicit_intersect() for why that matters. */
typedef struct {
    vec3 center;
    float major, minor;
} implicit_torus;

bool sphere_intersect(const sphere *s, ray r, hit_record *hit);
/* The lecture's quadratic formula as written, t = (-b +- sqrt(b^2 - 4ac)) / 2a,
 * kept to show where it fails (a small sphere far away): see shapes.c. */
bool sphere_intersect_naive(const sphere *s, ray r, hit_record *hit);

bool plane_intersect(const plane *p, ray r, hit_record *hit);

/* Moller-Trumbore, exactly as the lecture writes it. */
bool triangle_intersect(const triangle *tri, ray r, hit_record *hit);
/* Ray-triangle: Moller-Trumbore, on the triangle's first corner P0 and its
 * edges E1 = P1 - P0, E2 = P2 - P0, for a hit in (r->t_min, t_max).
 * Solve o + t d = (1 - b1 - b2) P0 + b1 P1 + b2 P2 for (t, b1, b2) by
 * Cramer's rule:
 *   E1 = P1 - P0, E2 = P2 - P0, S = O - P0, S1 = D x E2, S2 = S x E1
 *   [t, b1, b2] = 1 / (S1 . E1) * [S2 . E2, S1 . S, S2 . D]
 * Cost: 1 division, 27 multiplications, 17 additions. The hit is inside the
 * triangle iff b1 >= 0, b2 >= 0, b1 + b2 <= 1. */
static inline bool triangle_intersect_edges(vec3 p0, vec3 e1, vec3 e2, const ray *r, float t_max, float *t_out,
                                            float *b1_out, float *b2_out)
{
    vec3 s1 = vec3_cross(r->direction, e2);
    float determinant = vec3_dot(s1, e1);
    /* Only an exactly zero determinant (the ray lies parallel to the plane)
     * is refused. The usual "|det| < 1e-8" cut-off would also refuse every
     * triangle smaller than about 1e-4 on a side, whatever the ray. A tiny
     * non-zero determinant can give t = inf or NaN; the comparisons below are
     * all false for NaN, so such a ray simply misses. */
    if (determinant == 0.0f)
        return false;
    float inverse = 1.0f / determinant;
    vec3 s = vec3_sub(r->origin, p0);
    /* The same three products as the formula, computed in an order that
     * lets most misses leave early: b1 needs only S1 and S. */
    float b1 = vec3_dot(s1, s) * inverse;
    if (!(b1 >= 0.0f && b1 <= 1.0f))
        return false;
    vec3 s2 = vec3_cross(s, e1);
    float b2 = vec3_dot(s2, r->direction) * inverse;
    if (!(b2 >= 0.0f && b1 + b2 <= 1.0f))
        return false;
    float t = vec3_dot(s2, e2) * inverse;
    if (!(t > r->t_min && t < t_max))
        return false;
    *t_out = t;
    *b1_out = b1;
    *b2_out = b2;
    return true;
}

/* The same test returning only t and the barycentrics (b1, b2): what an
 * acceleration structure calls in its inner loop, filling the hit record
 * once, for the closest hit only, with triangle_fill_hit(). */
bool triangle_intersect_barycentric(const triangle *tri, const ray *r, float *t, float *b1, float *b2);
/* The watertight test of Woop, Benthin and Wald (2013): a ray through an edge
 * or vertex shared by triangles of a closed mesh hits at least one of them,
 * which Moller-Trumbore does not promise. Same outputs as above. */
bool triangle_intersect_watertight(const triangle *tri, const ray *r, float *t, float *b1, float *b2);
void triangle_fill_hit(const triangle *tri, ray r, float t, float b1, float b2, hit_record *hit);

/* Fill the parts of a hit record every shape fills the same way: orient the
 * geometric normal towards the ray, and remember which side was hit. */
static inline void hit_set_normal(hit_record *hit, ray r, vec3 outward_normal)
{
    hit->front_face = vec3_dot(r.direction, outward_normal) < 0.0f;
    hit->normal_geometric = hit->front_face ? outward_normal : vec3_neg(outward_normal);
    hit->normal_shading = hit->normal_geometric;
}

/* A triangle's outward unit normal: (P1 - P0) x (P2 - P0), normalised (the
 * side from which P0, P1, P2 turn counter-clockwise). */
static inline vec3 triangle_unit_normal(const triangle *tri)
{
    vec3 e1 = vec3_sub(tri->p1, tri->p0), e2 = vec3_sub(tri->p2, tri->p0);
    return vec3_normalize(vec3_cross(e1, e2));
}

/* A triangle's size for ray_point_error(): the largest coordinate of its
 * edges E1 = P1 - P0 and E2 = P2 - P0 (at least half its extent). */
static inline float triangle_edge_size(vec3 e1, vec3 e2)
{
    return fmaxf(vec3_max_component(vec3_abs(e1)), vec3_max_component(vec3_abs(e2)));
}

/* The error bound (ray.h) of a point computed on triangle tri, with unit
 * normal n, as P0 + (b1 E1 + b2 E2): what its hit record would carry. */
static inline float triangle_point_error(const triangle *tri, vec3 point, vec3 n)
{
    return ray_point_error(point, n, triangle_edge_size(vec3_sub(tri->p1, tri->p0), vec3_sub(tri->p2, tri->p0)));
}

/* triangle_fill_hit() with the triangle's unit normal already at hand
 * (triangle_unit_normal(), computed once per triangle ahead of time: the
 * same bits). Normalising costs a square root and a division, one after
 * the other, for every hit; a structure that stores the normals saves both
 * (accel.h). Inline, so that an accelerator's hit does not copy the ray
 * into one more call. */
static inline void triangle_fill_hit_normal(const triangle *tri, vec3 unit_normal, const ray *r, float t, float b1,
                                            float b2, hit_record *hit)
{
    hit->t = t;
    hit->u = b1;
    hit->v = b2;
    /* The point from the barycentrics, not o + t d, whose error grows with
     * the distance travelled: (1 - b1 - b2) P0 + b1 P1 + b2 P2, written as
     * P0 + (b1 E1 + b2 E2). The same point, but for a small triangle far
     * from the origin the edges are exact differences of nearby floats and
     * their weighted sum is small, so the point is rounded once, at the
     * end, where the first form rounds several terms of the coordinates'
     * size (ray.h's offsets rely on it). */
    vec3 e1 = vec3_sub(tri->p1, tri->p0), e2 = vec3_sub(tri->p2, tri->p0);
    hit->point = vec3_add(tri->p0, vec3_add(vec3_scale(e1, b1), vec3_scale(e2, b2)));
    hit->point_error = ray_point_error(hit->point, unit_normal, triangle_edge_size(e1, e2));
    hit_set_normal(hit, *r, unit_normal);
}

float implicit_torus_value(const implicit_torus *torus, vec3 p);
bool implicit_intersect(const implicit_torus *torus, ray r, hit_record *hit);

#endif
