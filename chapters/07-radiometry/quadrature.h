/* quadrature.h -- deterministic numerical integration over directions and
 * over areas, each with an estimate of its own error. Chapter 07 checks every
 * radiometric closed form against one of these integrals; Monte Carlo comes
 * in chapter 08.
 *
 * Usage:
 *   static double integrand(const void *ctx, dvec3 w) { return w.z; }  // cos theta
 *   quadrature_result q = integrate_over_hemisphere(integrand, NULL, dvec3_make(0, 0, 1),
 *                                                   QUADRATURE_GAUSS_LEGENDRE, 16);
 *   q.value             the integral (pi here)
 *   q.error_estimate    |fine - coarse| plus a bound on rounding: trust q.value to this
 *   q.evaluations       integrand calls on both grids
 *
 * Every integrator runs twice, on a grid and on a grid twice as fine in each
 * direction, and returns the fine result. The difference of the two is the
 * error estimate: for the midpoint rule (error ~ h^2) the fine result's error
 * is about a third of the difference; for Gauss-Legendre (error falling
 * faster than any power of h on smooth integrands) it is far smaller than the
 * difference. Either way |value - exact| <= error_estimate once the grids
 * resolve the integrand, which is what the tests of chapter 07 check (and
 * they require the estimate itself to be small, so a useless integrator does
 * not pass by claiming a huge error).
 *
 * Everything is double: this chapter is about numbers, and the checks reach
 * twelve digits and more.
 */
#ifndef QUADRATURE_H
#define QUADRATURE_H

#include <math.h>

/* ---- a direction or a point in double ------------------------------------ */

typedef struct {
    double x, y, z;
} dvec3;

static inline dvec3 dvec3_make(double x, double y, double z) { return (dvec3){x, y, z}; }
static inline dvec3 dvec3_add(dvec3 a, dvec3 b) { return (dvec3){a.x + b.x, a.y + b.y, a.z + b.z}; }
static inline dvec3 dvec3_sub(dvec3 a, dvec3 b) { return (dvec3){a.x - b.x, a.y - b.y, a.z - b.z}; }
static inline dvec3 dvec3_scale(dvec3 a, double s) { return (dvec3){a.x * s, a.y * s, a.z * s}; }
static inline double dvec3_dot(dvec3 a, dvec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline dvec3 dvec3_cross(dvec3 a, dvec3 b)
{
    return (dvec3){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
static inline double dvec3_length(dvec3 a) { return sqrt(dvec3_dot(a, a)); }
static inline dvec3 dvec3_normalize(dvec3 a) { return dvec3_scale(a, 1.0 / dvec3_length(a)); }

/* An orthonormal basis (t, b, n) around unit n (Duff et al. 2017, as
 * vec3_basis in common/core/vec3.h, in double). */
static inline void dvec3_basis(dvec3 n, dvec3 *t, dvec3 *b)
{
    double sign = copysign(1.0, n.z);
    double a = -1.0 / (sign + n.z);
    double c = n.x * n.y * a;
    *t = (dvec3){1.0 + sign * n.x * n.x * a, sign * c, -sign * n.x};
    *b = (dvec3){c, sign + n.y * n.y * a, -n.y};
}

/* ---- one-dimensional rules ------------------------------------------------ */

typedef enum {
    QUADRATURE_MIDPOINT,       /* n equal cells, one point in the middle of each */
    QUADRATURE_GAUSS_LEGENDRE  /* n Gauss-Legendre nodes: exact for polynomials of degree 2n - 1 */
} quadrature_rule;

enum { QUADRATURE_MAX_NODES = 4096 };

/* The n nodes x[] and weights w[] of `rule` on [a, b]: sum w[i] f(x[i])
 * approximates the integral of f from a to b. 1 <= n <= QUADRATURE_MAX_NODES. */
void quadrature_nodes(quadrature_rule rule, int n, double a, double b, double *x, double *w);

const char *quadrature_rule_name(quadrature_rule rule);

typedef struct {
    double value;          /* on the fine grid */
    double coarse;         /* on the coarse grid (half as many points per dimension) */
    double error_estimate; /* |value - coarse| + rounding bound */
    long evaluations;      /* integrand calls, both grids */
} quadrature_result;

/* ---- integrals over directions: d omega = sin theta d theta d phi --------- */

typedef double (*direction_fn)(const void *ctx, dvec3 w);

/* The integral of f over the cone of directions within `alpha` of the unit
 * `axis` (alpha = pi/2: a hemisphere; alpha = pi: the whole sphere):
 *
 *     integral_0^{2 pi} integral_0^{alpha} f(theta, phi) sin theta d theta d phi
 *
 * theta on n nodes of `rule`, phi on 2n midpoints (for a smooth periodic
 * integrand the midpoint rule in phi converges faster than any power of n);
 * then again with 2n and 4n. */
quadrature_result integrate_over_cone(direction_fn f, const void *ctx, dvec3 axis, double alpha,
                                      quadrature_rule rule, int n);
quadrature_result integrate_over_hemisphere(direction_fn f, const void *ctx, dvec3 normal, quadrature_rule rule,
                                            int n);
quadrature_result integrate_over_sphere(direction_fn f, const void *ctx, quadrature_rule rule, int n);

/* ---- integrals over areas ------------------------------------------------- */

typedef double (*point_fn)(const void *ctx, dvec3 x);

/* The integral of f over the triangle (p0, p1, p2), dA: the triangle split
 * into 4^level congruent pieces (midpoint subdivision), each mapped from the
 * unit square by x = p0 + u (p1 - p0) + u v (p2 - p1), dA = 2 area u du dv,
 * with n x n Gauss-Legendre nodes; then again with 4^(level+1) pieces. Raise
 * `level` until a piece is smaller than the distance at which f changes (a
 * point close to the triangle makes 1/r^3 change on the scale of that
 * distance). */
quadrature_result integrate_over_triangle(point_fn f, const void *ctx, dvec3 p0, dvec3 p1, dvec3 p2, int level,
                                          int n);

/* The integral of f over the disk of `radius` around `centre` with unit
 * `normal`, dA = r dr d phi: r on n nodes of `rule`, phi on 2n midpoints; then
 * again with 2n and 4n. */
quadrature_result integrate_over_disk(point_fn f, const void *ctx, dvec3 centre, dvec3 normal, double radius,
                                      quadrature_rule rule, int n);

/* |numeric - exact| / |exact| (or the absolute error when exact is 0). */
double relative_error(double numeric, double exact);

#endif
