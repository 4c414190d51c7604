/* quadrature.c -- how the integrals are computed: midpoint and
 * Gauss-Legendre rules, and the integrals over cones of directions,
 * triangles and disks built from them, each with its error estimate (see
 * quadrature.h). */
#include "07-radiometry/quadrature.h"

#include <float.h>
#include <stdlib.h>

#include "memory.h"
#include "vec3.h"

/* Newton's iteration for a Legendre root stops when a step moves the root by
 * at most this many units of DBL_EPSILON (the roots lie in (-1, 1), so this
 * is an absolute error of a few ulps); MAX_STEPS is a safety net that a
 * correct start never reaches (it converges quadratically in 3 to 6 steps). */
static const double LEGENDRE_ROOT_ULPS = 4.0;
static const int LEGENDRE_MAX_NEWTON_STEPS = 100;

/* Rounding: summing N terms in double errs by at most (N - 1) eps sum|term|
 * (recursive summation; Higham, Accuracy and Stability, section 4.2). Each
 * term also carries its own rounding: the node and weight (a few ulps from
 * Newton's iteration) and the integrand (a few dozen operations: a sine, a
 * square root, products). QUADRATURE_TERM_ULPS allows 64 ulps per term for
 * those, generously; the rounding bound added to every error estimate is
 * (N + QUADRATURE_TERM_ULPS) eps sum|w f|. */
static const double QUADRATURE_TERM_ULPS = 64.0;

/* ---- one-dimensional rules ------------------------------------------------ */

/* Gauss-Legendre on [-1, 1]: the nodes are the roots of the Legendre
 * polynomial P_n, found by Newton's method from the estimate
 * cos(pi (i + 3/4) / (n + 1/2)); the weights are 2 / ((1 - z^2) P_n'(z)^2). */
static void gauss_legendre_unit(int n, double *z_out, double *w_out)
{
    for (int i = 0; i < (n + 1) / 2; i++) {
        double z = cos(PI * ((double)i + 0.75) / ((double)n + 0.5));
        double derivative = 1.0;
        for (int step = 0; step < LEGENDRE_MAX_NEWTON_STEPS; step++) {
            /* P_n(z) by the three-term recurrence j P_j = (2j - 1) z P_{j-1} - (j - 1) P_{j-2}. */
            double p1 = 1.0, p2 = 0.0;
            for (int j = 1; j <= n; j++) {
                double p3 = p2;
                p2 = p1;
                p1 = ((2.0 * j - 1.0) * z * p2 - (j - 1.0) * p3) / j;
            }
            derivative = n * (z * p1 - p2) / (z * z - 1.0);
            double previous = z;
            z = previous - p1 / derivative;
            if (fabs(z - previous) <= LEGENDRE_ROOT_ULPS * DBL_EPSILON)
                break;
        }
        double w = 2.0 / ((1.0 - z * z) * derivative * derivative);
        /* Symmetric pairs: -z and +z share a weight. */
        z_out[i] = -z;
        z_out[n - 1 - i] = z;
        w_out[i] = w_out[n - 1 - i] = w;
    }
}

void quadrature_nodes(quadrature_rule rule, int n, double a, double b, double *x, double *w)
{
    double half = 0.5 * (b - a), mid = 0.5 * (a + b);
    if (rule == QUADRATURE_MIDPOINT) {
        double h = (b - a) / n;
        for (int i = 0; i < n; i++) {
            x[i] = a + ((double)i + 0.5) * h;
            w[i] = h;
        }
        return;
    }
    gauss_legendre_unit(n, x, w);
    for (int i = 0; i < n; i++) {
        x[i] = mid + half * x[i];
        w[i] *= half;
    }
}

const char *quadrature_rule_name(quadrature_rule rule)
{
    return rule == QUADRATURE_MIDPOINT ? "midpoint" : "Gauss-Legendre";
}

/* One grid's sum, and the sum of |terms| for its rounding bound. */
typedef struct {
    double sum, abs_sum;
    long evaluations;
} grid_sum;

static quadrature_result combine(grid_sum coarse, grid_sum fine)
{
    quadrature_result q;
    q.value = fine.sum;
    q.coarse = coarse.sum;
    double rounding = ((double)fine.evaluations + QUADRATURE_TERM_ULPS) * DBL_EPSILON * fine.abs_sum;
    q.error_estimate = fabs(fine.sum - coarse.sum) + rounding;
    q.evaluations = coarse.evaluations + fine.evaluations;
    return q;
}

static void check_points(int n)
{
    if (n < 1 || 4 * n > QUADRATURE_MAX_NODES) {
        /* A programming error, not an input error: the callers pass constants. */
        abort();
    }
}

/* ---- integrals over directions -------------------------------------------- */

/* Differential solid angle: d omega = sin theta d theta d phi. */
static grid_sum cone_grid(direction_fn f, const void *ctx, dvec3 axis, double alpha, quadrature_rule rule,
                          int n_theta, int n_phi)
{
    /* exercise: solid_angle_integral */
    double *theta = memory_allocate((size_t)n_theta, sizeof *theta);
    double *w_theta = memory_allocate((size_t)n_theta, sizeof *w_theta);
    double *phi = memory_allocate((size_t)n_phi, sizeof *phi);
    double *w_phi = memory_allocate((size_t)n_phi, sizeof *w_phi);
    quadrature_nodes(rule, n_theta, 0.0, alpha, theta, w_theta);
    quadrature_nodes(QUADRATURE_MIDPOINT, n_phi, 0.0, 2.0 * PI, phi, w_phi);
    dvec3 t, b;
    dvec3_basis(axis, &t, &b);
    grid_sum g = {0.0, 0.0, 0};
    for (int i = 0; i < n_theta; i++) {
        double s = sin(theta[i]), c = cos(theta[i]);
        for (int j = 0; j < n_phi; j++) {
            dvec3 w = dvec3_add(dvec3_add(dvec3_scale(t, s * cos(phi[j])), dvec3_scale(b, s * sin(phi[j]))),
                                dvec3_scale(axis, c));
            double term = w_theta[i] * w_phi[j] * s * f(ctx, w);
            g.sum += term;
            g.abs_sum += fabs(term);
            g.evaluations++;
        }
    }
    free(theta);
    free(w_theta);
    free(phi);
    free(w_phi);
    return g;
    /* end of exercise solid_angle_integral */
}

quadrature_result integrate_over_cone(direction_fn f, const void *ctx, dvec3 axis, double alpha,
                                      quadrature_rule rule, int n)
{
    check_points(n);
    grid_sum coarse = cone_grid(f, ctx, axis, alpha, rule, n, 2 * n);
    grid_sum fine = cone_grid(f, ctx, axis, alpha, rule, 2 * n, 4 * n);
    return combine(coarse, fine);
}

quadrature_result integrate_over_hemisphere(direction_fn f, const void *ctx, dvec3 normal, quadrature_rule rule,
                                            int n)
{
    return integrate_over_cone(f, ctx, normal, 0.5 * PI, rule, n);
}

quadrature_result integrate_over_sphere(direction_fn f, const void *ctx, quadrature_rule rule, int n)
{
    return integrate_over_cone(f, ctx, dvec3_make(0, 0, 1), PI, rule, n);
}

/* ---- integrals over a triangle -------------------------------------------- */

typedef struct {
    point_fn f;
    const void *ctx;
    int n;
    const double *u, *w; /* Gauss-Legendre on [0, 1] */
} triangle_rule;

/* One piece: x = a + u (b - a) + u v (c - b), dA = 2 area u du dv. */
static void triangle_piece(const triangle_rule *r, dvec3 a, dvec3 b, dvec3 c, grid_sum *g)
{
    dvec3 ab = dvec3_sub(b, a), bc = dvec3_sub(c, b);
    double twice_area = dvec3_length(dvec3_cross(ab, bc));
    for (int i = 0; i < r->n; i++) {
        double u = r->u[i];
        for (int j = 0; j < r->n; j++) {
            double v = r->u[j];
            dvec3 x = dvec3_add(a, dvec3_add(dvec3_scale(ab, u), dvec3_scale(bc, u * v)));
            double term = r->w[i] * r->w[j] * twice_area * u * r->f(r->ctx, x);
            g->sum += term;
            g->abs_sum += fabs(term);
            g->evaluations++;
        }
    }
}

/* Midpoint subdivision: four congruent triangles, each a quarter of the area. */
static void triangle_pieces(const triangle_rule *r, dvec3 a, dvec3 b, dvec3 c, int level, grid_sum *g)
{
    if (level == 0) {
        triangle_piece(r, a, b, c, g);
        return;
    }
    dvec3 ab = dvec3_scale(dvec3_add(a, b), 0.5);
    dvec3 bc = dvec3_scale(dvec3_add(b, c), 0.5);
    dvec3 ca = dvec3_scale(dvec3_add(c, a), 0.5);
    triangle_pieces(r, a, ab, ca, level - 1, g);
    triangle_pieces(r, ab, b, bc, level - 1, g);
    triangle_pieces(r, ca, bc, c, level - 1, g);
    triangle_pieces(r, ab, bc, ca, level - 1, g);
}

quadrature_result integrate_over_triangle(point_fn f, const void *ctx, dvec3 p0, dvec3 p1, dvec3 p2, int level,
                                          int n)
{
    check_points(n);
    double *u = memory_allocate((size_t)n, sizeof *u);
    double *w = memory_allocate((size_t)n, sizeof *w);
    quadrature_nodes(QUADRATURE_GAUSS_LEGENDRE, n, 0.0, 1.0, u, w);
    triangle_rule r = {f, ctx, n, u, w};
    grid_sum coarse = {0.0, 0.0, 0}, fine = {0.0, 0.0, 0};
    triangle_pieces(&r, p0, p1, p2, level, &coarse);
    triangle_pieces(&r, p0, p1, p2, level + 1, &fine);
    free(u);
    free(w);
    return combine(coarse, fine);
}

/* ---- integrals over a disk ------------------------------------------------ */

static grid_sum disk_grid(point_fn f, const void *ctx, dvec3 centre, dvec3 normal, double radius,
                          quadrature_rule rule, int n_r, int n_phi)
{
    double *r = memory_allocate((size_t)n_r, sizeof *r);
    double *w_r = memory_allocate((size_t)n_r, sizeof *w_r);
    double *phi = memory_allocate((size_t)n_phi, sizeof *phi);
    double *w_phi = memory_allocate((size_t)n_phi, sizeof *w_phi);
    quadrature_nodes(rule, n_r, 0.0, radius, r, w_r);
    quadrature_nodes(QUADRATURE_MIDPOINT, n_phi, 0.0, 2.0 * PI, phi, w_phi);
    dvec3 t, b;
    dvec3_basis(normal, &t, &b);
    grid_sum g = {0.0, 0.0, 0};
    for (int i = 0; i < n_r; i++) {
        for (int j = 0; j < n_phi; j++) {
            dvec3 offset = dvec3_add(dvec3_scale(t, r[i] * cos(phi[j])), dvec3_scale(b, r[i] * sin(phi[j])));
            double term = w_r[i] * w_phi[j] * r[i] * f(ctx, dvec3_add(centre, offset));
            g.sum += term;
            g.abs_sum += fabs(term);
            g.evaluations++;
        }
    }
    free(r);
    free(w_r);
    free(phi);
    free(w_phi);
    return g;
}

quadrature_result integrate_over_disk(point_fn f, const void *ctx, dvec3 centre, dvec3 normal, double radius,
                                      quadrature_rule rule, int n)
{
    check_points(n);
    grid_sum coarse = disk_grid(f, ctx, centre, normal, radius, rule, n, 2 * n);
    grid_sum fine = disk_grid(f, ctx, centre, normal, radius, rule, 2 * n, 4 * n);
    return combine(coarse, fine);
}

double relative_error(double numeric, double exact)
{
    double difference = fabs(numeric - exact);
    return exact == 0.0 ? difference : difference / fabs(exact);
}
