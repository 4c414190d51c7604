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
    /* exercise: moller_trumbore */
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
    /* end of exercise moller_trumbore */
}

/* The same test returning only t and the barycentrics (b1, b2), the way an
 * acceleration structure's inner loop wants it (filling the hit record once,
 * for the closest hit only, with triangle_fill_hit()). Kept as the lecture's
 * derivation and as the counterexample: rays through the shared edges of a
 * closed mesh leak through it (docs/hard-cases.md). Nothing renders with it;
 * every accelerator can be switched to it to measure that
 * (accel_use_triangle_test, chapter 03). */
bool triangle_intersect_barycentric(const triangle *tri, const ray *r, float *t, float *b1, float *b2);

/* ---- Ray-triangle, watertight: what every renderer uses ----------------------
 * The test of Woop, Benthin and Wald (2013), as pbrt-v4 writes it: a ray
 * through an edge or a vertex shared by triangles of a closed mesh hits at
 * least one of them, which Moller-Trumbore does not promise (shapes.c says
 * why). Same outputs as triangle_intersect_barycentric(): t in
 * (r->t_min, r->t_max), b1 and b2 the weights of p1 and p2. */
bool triangle_intersect_watertight(const triangle *tri, const ray *r, float *t, float *b1, float *b2);
/* Both tests by name, for whoever offers a choice (accelerators, benchmarks). */
typedef enum {
    TRIANGLE_TEST_WATERTIGHT,      /* the default: zero in every accelerator's struct */
    TRIANGLE_TEST_MOLLER_TRUMBORE, /* the lecture's, kept to measure against */
} triangle_test;
static inline const char *triangle_test_name(triangle_test test)
{
    return test == TRIANGLE_TEST_WATERTIGHT ? "watertight" : "Moller-Trumbore";
}

/* The watertight test in two parts, so that an accelerator pays for the
 * ray's part once per ray instead of once per triangle. The ray's part: its
 * axes renamed so that z is the one along which |d| is largest (kz; kx and
 * ky follow it cyclically), and the shear along it that takes the ray's
 * line to the z axis: x' = x - (d_kx / d_kz) z,  y' = y - (d_ky / d_kz) z.
 * The SIMD kernels of chapter 13 (the wide BVH, flat) hold the same numbers in
 * registers and do the triangle's part lane by lane with exactly the
 * operations of watertight_intersect() below, so every lane's answer is
 * this function's, bit for bit. */
typedef struct {
    int kx, ky, kz;
    float shear_x, shear_y; /* d_kx / d_kz, d_ky / d_kz */
    vec3 origin, direction;
    float t_min;
} watertight_ray;

/* The triangle's part below is inlined into every accelerator's loop
 * whatever the compiler's size heuristics say: GCC 12 left
 * watertight_intersect() out of line in brute force's loop, and a call per
 * triangle (its arguments through memory) cost more than the test. */
#if defined(__GNUC__)
#define WATERTIGHT_INLINE static inline __attribute__((always_inline))
#else
#define WATERTIGHT_INLINE static inline
#endif

/* A triangle's nine coordinates are nine floats in a row (p0.x .. p2.z), so
 * the kernels can read coordinate kx of a corner by index. */
_Static_assert(sizeof(vec3) == 3 * sizeof(float), "a vec3 is three floats in a row");
_Static_assert(sizeof(triangle) == 9 * sizeof(float), "a triangle is its nine coordinates");

static inline watertight_ray watertight_ray_make(const ray *r)
{
    vec3 abs_d = vec3_abs(r->direction);
    int kz = abs_d.x > abs_d.y ? (abs_d.x > abs_d.z ? 0 : 2) : (abs_d.y > abs_d.z ? 1 : 2);
    int kx = kz == 2 ? 0 : kz + 1, ky = kx == 2 ? 0 : kx + 1;
    /* vec3_axis() selects, where indexing the ray's floats in memory would
     * make the processor wait for the stores that wrote them (measured: a
     * tenth of chapter 13's one-ray any hit, on the Cornell box) */
    float dz = vec3_axis(r->direction, kz);
    float shear_x = vec3_axis(r->direction, kx) / dz, shear_y = vec3_axis(r->direction, ky) / dz;
    return (watertight_ray){kx, ky, kz, shear_x, shear_y, r->origin, r->direction, r->t_min};
}

/* The edge functions of a lane recomputed in double, where the products of
 * floats are exact (watertight_intersect() calls it when one is exactly 0). */
void watertight_edges_in_double(float ax, float ay, float bx, float by, float cx, float cy, float *u, float *v,
                                float *w);

/* t where the ray meets the triangle's plane, ((P0 - O) . N) / (D . N)
 * with N = (P1 - P0) x (P2 - P0), as Embree's watertight kernel computes
 * it; pbrt computes (u z_a + v z_b + w z_c) / det from the sheared
 * corners instead. Why not pbrt's: the shear mixes the three coordinates
 * of every corner, so that t's error is a few ulps of the corners'
 * distances from the origin, whatever the ray's own offset from the
 * plane. With the offsets ray.h had then (a fixed 2^-16 near 0), a ray
 * spawned from the Cornell box's floor (y = 0) started 2^-16 above it while
 * the floor's corners are 550 away, a quarter of their ulp: pbrt's t found
 * the floor again at t = +3e-8 (5 of 20,000 shadow rays, test_walls_
 * skipped_only_where_they_cannot_block). ray.h's offsets now also cover the
 * intersection tests' own arithmetic (a multiple of the primitive's size),
 * measured with both tests; the plane's t is kept for being the more
 * accurate: P0 - O along an axis-aligned normal is exact, and in general t
 * is as accurate as Moller-Trumbore's. pbrt guards its t with an error bound instead
 * (refusing t below it), which refuses every hit on a sliver one float
 * step thick (test_sliver_one_float_step_thick_is_still_hit). Only rays
 * that passed the edge test get here. Written out (not vec3_cross and
 * vec3_dot) so that the SIMD kernels' copies (watertight_simd.h) visibly
 * do the same operations in the same order. */
WATERTIGHT_INLINE float watertight_plane_t(const float *p0, const float *p1, const float *p2,
                                           const watertight_ray *wr)
{
    float e1x = p1[0] - p0[0], e1y = p1[1] - p0[1], e1z = p1[2] - p0[2];
    float e2x = p2[0] - p0[0], e2y = p2[1] - p0[1], e2z = p2[2] - p0[2];
    float nx = e1y * e2z - e1z * e2y, ny = e1z * e2x - e1x * e2z, nz = e1x * e2y - e1y * e2x;
    float sx = p0[0] - wr->origin.x, sy = p0[1] - wr->origin.y, sz = p0[2] - wr->origin.z;
    float numerator = sx * nx + sy * ny + sz * nz;
    float denominator = wr->direction.x * nx + wr->direction.y * ny + wr->direction.z * nz;
    return numerator / denominator;
}

/* The triangle's part: corners p0, p1, p2 given as pointers to their three
 * coordinates. A hit in (t_min, t_max) gives t, b1 (p1's weight) and b2
 * (p2's). Degenerate triangles (triangle_is_degenerate()) are not refused
 * here: a structure leaves them out at build time (they cannot be hit), or
 * calls watertight_intersect_triangle(), which asks after a hit.
 *
 *  1. Translate the corners by -o and shear them: the ray is now the +z axis
 *     from (0, 0), and only the corners' x and y decide whether it hits.
 *  2. The three edge functions of the projected corners, twice the signed
 *     areas of the triangles the origin makes with each edge:
 *       u = c_x b_y - c_y b_x (edge p1 p2), v = a_x c_y - a_y c_x (p2 p0),
 *       w = b_x a_y - b_y a_x (p0 p1).
 *     An edge shared by two triangles of a closed mesh, consistently
 *     oriented, is p -> q in one and q -> p in the other: its edge function
 *     is q_x p_y - q_y p_x in one and p_x q_y - p_y q_x in the other, the
 *     same two products subtracted the other way round, so the same float
 *     negated. The ray cannot be "just outside" both triangles: at least one
 *     sees it inside or on its edge. (Only if a*b - c*d is rounded the same
 *     way everywhere: no fused multiply-add, -ffp-contract=off.)
 *  3. An edge function of exactly 0 may be the rounding of a tiny value of
 *     either sign: recompute in double (exact there), rare.
 *  4. Inside iff u, v, w are all >= 0 or all <= 0 (either winding).
 *     pbrt swaps kx and ky when d_kz < 0 to keep the winding; that negates
 *     u, v, w and their sum exactly, and changes no decision, b1 or b2, so
 *     we do not.
 *  5. det = u + v + w (0: the ray lies in the triangle's plane: no hit;
 *     NaN, from NaN coordinates: no hit either).
 *  6. t from the triangle's plane, for the rays that passed: see
 *     watertight_plane_t(). The barycentrics are the edge functions over
 *     det. */
WATERTIGHT_INLINE bool watertight_intersect(const watertight_ray *wr, const float *p0, const float *p1,
                                            const float *p2, float t_max, float *t_out, float *b1_out, float *b2_out)
{
    const float *o = &wr->origin.x;
    const int kx = wr->kx, ky = wr->ky, kz = wr->kz;
    float a_z = p0[kz] - o[kz], b_z = p1[kz] - o[kz], c_z = p2[kz] - o[kz];
    float ax = (p0[kx] - o[kx]) - wr->shear_x * a_z, ay = (p0[ky] - o[ky]) - wr->shear_y * a_z;
    float bx = (p1[kx] - o[kx]) - wr->shear_x * b_z, by = (p1[ky] - o[ky]) - wr->shear_y * b_z;
    float cx = (p2[kx] - o[kx]) - wr->shear_x * c_z, cy = (p2[ky] - o[ky]) - wr->shear_y * c_z;
    float u = cx * by - cy * bx;
    float v = ax * cy - ay * cx;
    /* Most rays pass beside the triangle, and two of its edge functions
     * already disagree in sign: leave before the third. (Rounding is
     * monotonic, so an edge function that is not exactly 0 has the sign of
     * its exact value, which step 3 would recompute: the answer is the
     * same as the full test's, and the SIMD kernels, which run every lane
     * to the end, agree with it.) */
    if (((u < 0.0f) & (v > 0.0f)) | ((u > 0.0f) & (v < 0.0f)))
        return false;
    float w = bx * ay - by * ax;
    if (u == 0.0f || v == 0.0f || w == 0.0f)
        watertight_edges_in_double(ax, ay, bx, by, cx, cy, &u, &v, &w);
    if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f))
        return false;
    float determinant = u + v + w;
    if (!(fabsf(determinant) > 0.0f)) /* 0, or NaN from a NaN edge function */
        return false;
    float t = watertight_plane_t(p0, p1, p2, wr);
    if (!(t > wr->t_min && t < t_max))
        return false;
    float inverse = 1.0f / determinant;
    *t_out = t;
    *b1_out = v * inverse;
    *b2_out = w * inverse;
    return true;
}

/* Is the triangle's area exactly zero (its corners on one line, or equal)?
 * Such a triangle has no plane and no normal; no ray may hit it (shapes.c). */
bool triangle_is_degenerate(const triangle *tri);

/* watertight_intersect() on a triangle that may be degenerate (a set's,
 * chapter 03): the area is asked only after a hit, which is rare beside the
 * tests that miss. */
WATERTIGHT_INLINE bool watertight_intersect_triangle(const watertight_ray *wr, const triangle *tri, float t_max,
                                                     float *t_out, float *b1_out, float *b2_out)
{
    float t, b1, b2;
    if (!watertight_intersect(wr, &tri->p0.x, &tri->p1.x, &tri->p2.x, t_max, &t, &b1, &b2) ||
        triangle_is_degenerate(tri))
        return false;
    *t_out = t;
    *b1_out = b1;
    *b2_out = b2;
    return true;
}

/* Either test by name on a set's triangle, the ray prepared for both: what
 * the structures of chapters 03-06 call in their inner loops. Inline, and
 * called with `test` a constant, so each loop is compiled for one test. */
WATERTIGHT_INLINE bool triangle_intersect_with(triangle_test test, const watertight_ray *wr, const triangle *tri,
                                               const ray *r, float t_max, float *t, float *b1, float *b2)
{
    if (test == TRIANGLE_TEST_WATERTIGHT)
        return watertight_intersect_triangle(wr, tri, t_max, t, b1, b2);
    return triangle_intersect_edges(tri->p0, vec3_sub(tri->p1, tri->p0), vec3_sub(tri->p2, tri->p0), r, t_max, t, b1,
                                    b2);
}

/* The watertight test filling a hit record: what chapter 01's scenes render
 * with (triangle_intersect() above is the lecture's, beside it). */
bool triangle_intersect_watertight_hit(const triangle *tri, ray r, hit_record *hit);

/* Is p inside the closed mesh of `count` triangles? The parity of the
 * crossings of the ray from p along `direction` (which must not run through
 * an edge or a vertex: a random one, see shapes.c). */
bool closed_mesh_contains(const triangle *triangles, int count, vec3 p, vec3 direction);
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
