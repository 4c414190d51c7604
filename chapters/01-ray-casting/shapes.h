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
/* The same test returning only t and the barycentrics (b1, b2): what an
 * acceleration structure calls in its inner loop, filling the hit record
 * once, for the closest hit only, with triangle_fill_hit(). */
bool triangle_intersect_barycentric(const triangle *tri, const ray *r, float *t, float *b1, float *b2);
/* The watertight test of Woop, Benthin and Wald (2013): a ray through an edge
 * or vertex shared by triangles of a closed mesh hits at least one of them,
 * which Moller-Trumbore does not promise. Same outputs as above. */
bool triangle_intersect_watertight(const triangle *tri, const ray *r, float *t, float *b1, float *b2);
void triangle_fill_hit(const triangle *tri, ray r, float t, float b1, float b2, hit_record *hit);

float implicit_torus_value(const implicit_torus *torus, vec3 p);
bool implicit_intersect(const implicit_torus *torus, ray r, hit_record *hit);

#endif
