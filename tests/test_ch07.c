/* test_ch07.c -- radiometry: every quantity's quadrature against its closed
 * form, within the quadrature's own error estimate, including the grazing
 * and degenerate cases; the BRDF energy check and its twins; the closed
 * furnace summed bounce by bounce and iterated as L = E + K L.
 *
 * No randomness anywhere: every integral is deterministic quadrature. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <float.h>
#include <math.h>
#include <stdlib.h>

#include "07-radiometry/radiometry.h"
#include "memory.h"
#include "test_support.h"
#include "vec3.h"

/* What "agrees" means.
 *
 * A quadrature agrees with a closed form when |numeric - exact| is within the
 * quadrature's error estimate (|I(2n) - I(n)| plus its rounding bound, see
 * quadrature.h) plus the closed form's own rounding. CLOSED_FORM_ULPS allows
 * 16 ulps of the exact value for that: the closed forms here are at most a
 * handful of operations (a cos, a sqrt, a pow, a division), each correct to
 * an ulp or so.
 *
 * An estimate can only be trusted where the grid resolves the integrand, and
 * a useless integrator could "agree" by claiming a huge error. So each check
 * also demands that the estimate be small: REQUIRED_ACCURACY, a relative 1e-8.
 * The grids below were chosen to resolve their integrands; their estimates
 * are 1e-12 to 3e-10 (the program prints them), so 1e-8 leaves room, while
 * any integrand that is not resolved (an estimate of 1e-4 or worse) fails. */
static const double CLOSED_FORM_ULPS = 16.0;
static const double REQUIRED_ACCURACY = 1e-8;

/* Quadrature sizes (coarse grid; the fine grid doubles them). */
enum { N_DIRECTIONS = 32, N_DISK = 32, N_TRIANGLE = 8, N_BRDF = 64 };

static void assert_agrees_at(quadrature_result q, double exact, const char *what, const char *file, int line)
{
    double tolerance = q.error_estimate + CLOSED_FORM_ULPS * DBL_EPSILON * fabs(exact);
    if (!(fabs(q.value - exact) <= tolerance)) {
        print_error("%s: numeric %.17g, closed form %.17g, off by %.3g > estimate %.3g\n", what, q.value, exact,
                    fabs(q.value - exact), tolerance);
        _fail(file, line);
    }
    if (!(q.error_estimate <= REQUIRED_ACCURACY * fabs(exact))) {
        print_error("%s: error estimate %.3g is not below %.3g of %.17g: the grid does not resolve the integrand\n",
                    what, q.error_estimate, REQUIRED_ACCURACY, exact);
        _fail(file, line);
    }
}
#define assert_agrees(q, exact) assert_agrees_at((q), (exact), #q, __FILE__, __LINE__)

static double constant(const void *ctx, dvec3 w)
{
    (void)w;
    return *(const double *)ctx;
}

static double deg(double degrees) { return degrees * PI / 180.0; }

static const dvec3 UP = {0, 0, 1};
static const dvec3 ORIGIN = {0, 0, 0};

/* ---- the quadrature rules themselves -------------------------------------- */

/* Gauss-Legendre with n nodes integrates every polynomial of degree up to
 * 2n - 1 exactly; for x^(2n) it misses by exactly its known remainder,
 * (b - a)^(2n+1) (n!)^4 / ((2n + 1) ((2n)!)^2) (Abramowitz and Stegun 25.4.30
 * with f^(2n) = (2n)!). */
static void test_gauss_legendre_is_exact_for_degree_2n_minus_1_and_not_2n(void **state)
{
    (void)state;
    const double a = -1.0, b = 2.0;
    for (int n = 1; n <= 12; n++) {
        double x[12], w[12];
        quadrature_nodes(QUADRATURE_GAUSS_LEGENDRE, n, a, b, x, w);
        for (int k = 0; k <= 2 * n; k++) {
            double sum = 0.0;
            for (int i = 0; i < n; i++)
                sum += w[i] * pow(x[i], k);
            double exact = (pow(b, k + 1) - pow(a, k + 1)) / (k + 1);
            /* Rounding: n terms, each at most (b - a) b^k; 64 ulps per term
             * for the node, the weight and the power. */
            double rounding = 64.0 * n * DBL_EPSILON * (b - a) * pow(b, k);
            double remainder = 0.0;
            if (k == 2 * n) {
                double n_factorial = tgamma(n + 1.0), two_n_factorial = tgamma(2.0 * n + 1.0);
                remainder = pow(b - a, 2 * n + 1) * pow(n_factorial, 4) / ((2 * n + 1) * two_n_factorial * two_n_factorial);
                assert_true(remainder > 10.0 * rounding); /* a miss the test can see */
            }
            assert_close(exact - sum, remainder, rounding);
        }
    }
}

static double cosine(const void *ctx, dvec3 w)
{
    (void)ctx;
    return w.z;
}

/* The midpoint rule's error falls as h^2: doubling n divides it by 4, and
 * the estimate |I(2n) - I(n)| is then about 3 times the fine grid's error. */
static void test_midpoint_error_falls_as_h_squared_and_the_estimate_covers_it(void **state)
{
    (void)state;
    double previous = 0.0;
    for (int n = 4; n <= 64; n *= 2) {
        quadrature_result q = integrate_over_hemisphere(cosine, NULL, UP, QUADRATURE_MIDPOINT, n);
        double error = fabs(q.value - PI);
        assert_true(error <= q.error_estimate);
        assert_true(q.error_estimate < 4.0 * error); /* the estimate is not wildly pessimistic either */
        if (previous > 0.0)
            assert_close(previous / error, 4.0, 0.05); /* h^2: ratio 4 to within 1% */
        previous = error;
    }
}

/* ---- Solid angle ----------------------------------------------------------- */

static void test_solid_angle_of_the_sphere_is_4pi(void **state)
{
    (void)state;
    exercise_checks("solid_angle_integral");
    double one = 1.0;
    assert_agrees(integrate_over_sphere(constant, &one, QUADRATURE_GAUSS_LEGENDRE, N_DIRECTIONS), 4.0 * PI);
}

static void test_solid_angle_of_cones_up_to_half_angle_pi(void **state)
{
    (void)state;
    exercise_checks("solid_angle_integral");
    double one = 1.0;
    const double alphas[] = {deg(1), deg(10), deg(45), deg(90), deg(135), deg(179), PI};
    for (int i = 0; i < 7; i++) {
        quadrature_result q =
            integrate_over_cone(constant, &one, dvec3_normalize(dvec3_make(1, 2, 3)), alphas[i],
                                QUADRATURE_GAUSS_LEGENDRE, N_DIRECTIONS);
        assert_agrees(q, solid_angle_cone(alphas[i]));
    }
    /* Half-angle pi is the whole sphere; pi/2 a hemisphere. */
    assert_close(solid_angle_cone(PI), 4.0 * PI, 4 * DBL_EPSILON * 4.0 * PI);
    assert_close(solid_angle_cone(0.5 * PI), 2.0 * PI, 4 * DBL_EPSILON * 2.0 * PI);
    assert_true(solid_angle_cone(0.0) == 0.0);
}

static void test_solid_angle_of_a_sphere_seen_from_outside(void **state)
{
    (void)state;
    double one = 1.0;
    const double distances[] = {1.001, 1.5, 3.0, 100.0};
    for (int i = 0; i < 4; i++) {
        double d = distances[i];
        assert_agrees(integrate_over_cone(constant, &one, UP, asin(1.0 / d), QUADRATURE_GAUSS_LEGENDRE, N_DIRECTIONS),
                      solid_angle_sphere(1.0, d));
    }
    /* Far away: Omega -> pi r^2 / d^2, the disk's area over d^2. */
    assert_close(solid_angle_sphere(1.0, 1e3) / (PI / 1e6), 1.0, 1e-6);
}

static void test_triangle_solid_angle_matches_the_area_integral(void **state)
{
    (void)state;
    const dvec3 tri[4][3] = {
        {{-1, -1, 2}, {2, -0.5, 2.5}, {0, 1.5, 1.5}},
        {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}},         /* one octant's corners: Omega = pi/2 */
        {{3, 1, -1}, {4, -2, 0.5}, {5, 0, 2}},
        {{-10, 0, 1}, {10, 0, 1}, {0, 0.1, 1}},   /* long and thin */
    };
    for (int i = 0; i < 4; i++) {
        quadrature_result q = solid_angle_triangle_numeric(ORIGIN, tri[i][0], tri[i][1], tri[i][2], 4, N_TRIANGLE);
        assert_agrees(q, solid_angle_triangle(ORIGIN, tri[i][0], tri[i][1], tri[i][2]));
    }
    /* The octant triangle (1,0,0), (0,1,0), (0,0,1) covers 1/8 of the sphere. */
    assert_close(solid_angle_triangle(ORIGIN, tri[1][0], tri[1][1], tri[1][2]), 0.5 * PI, 8 * DBL_EPSILON);
}

static void test_triangle_seen_edge_on_has_zero_solid_angle(void **state)
{
    (void)state;
    /* The point in the triangle's plane, outside it. */
    dvec3 a = {1, 0, 0}, b = {3, 0, 0}, c = {2, 2, 0};
    assert_true(solid_angle_triangle(ORIGIN, a, b, c) == 0.0);
    quadrature_result q = solid_angle_triangle_numeric(ORIGIN, a, b, c, 2, N_TRIANGLE);
    assert_true(q.value == 0.0);
    /* Just off the plane, the solid angle grows from 0 and the two still agree. */
    dvec3 above = {0, 0, 1e-3};
    double omega = solid_angle_triangle(above, a, b, c);
    assert_true(omega > 0.0 && omega < 1e-3);
    assert_agrees(solid_angle_triangle_numeric(above, a, b, c, 2, N_TRIANGLE), omega);
    /* A point on a vertex: no NaN. */
    assert_true(solid_angle_triangle(a, a, b, c) == 0.0);
}

/* A triangle 9 units across, 0.25 below the point: it fills most of the
 * lower hemisphere, Omega = 5.78 > pi, and the Van Oosterom-Strackee
 * denominator is negative. */
static const dvec3 BIG[3] = {{-4, -3, -0.25}, {5, -3, -0.25}, {0, 5, -0.25}};

static void test_large_close_triangle_covers_more_than_pi_and_atan2_keeps_it(void **state)
{
    (void)state;
    double omega = solid_angle_triangle(ORIGIN, BIG[0], BIG[1], BIG[2]);
    assert_true(omega > PI && omega < 2.0 * PI);
    /* The point is close: 1/r^3 changes on the scale 0.25, so the pieces must
     * be smaller than that: 4^6 pieces of side ~9/64 = 0.14. */
    assert_agrees(solid_angle_triangle_numeric(ORIGIN, BIG[0], BIG[1], BIG[2], 6, N_TRIANGLE), omega);
    /* Nearer still, Omega approaches the hemisphere's 2 pi. */
    dvec3 near = {0, 0, -0.25 + 1e-4};
    double omega_near = solid_angle_triangle(near, BIG[0], BIG[1], BIG[2]);
    assert_true(omega_near > 2.0 * PI - 1e-3 && omega_near <= 2.0 * PI);
}

/* The twin: 2 atan(num / den) puts the angle in the wrong quadrant when the
 * denominator is negative, giving Omega - 2 pi. */
static void test_naive_atan_gets_the_large_triangle_wrong(void **state)
{
    (void)state;
    double omega = solid_angle_triangle(ORIGIN, BIG[0], BIG[1], BIG[2]);
    double naive = solid_angle_triangle_naive(ORIGIN, BIG[0], BIG[1], BIG[2]);
    assert_true(naive < 0.0);
    assert_close(naive, omega - 2.0 * PI, 1e-12);
    /* On a small triangle the two agree: the failure is the quadrant only. */
    dvec3 a = {-1, -1, 2}, b = {2, -0.5, 2.5}, c = {0, 1.5, 1.5};
    assert_close(solid_angle_triangle_naive(ORIGIN, a, b, c), solid_angle_triangle(ORIGIN, a, b, c), 1e-14);
}

/* A closed cube [-1, 1]^3 of 12 triangles with outward normals: the signed
 * solid angles add to 4 pi from inside (even close to a face, where a
 * triangle covers more than pi) and to 0 from outside. */
static void cube_triangles(dvec3 tri[12][3])
{
    /* Each face: its normal axis, sign, and two corners' directions. */
    int t = 0;
    for (int axis = 0; axis < 3; axis++)
        for (int sign = -1; sign <= 1; sign += 2) {
            dvec3 c[4];
            for (int k = 0; k < 4; k++) {
                /* Corners in counter-clockwise order seen from outside. */
                double u = (k == 1 || k == 2) ? 1 : -1, v = (k >= 2) ? 1 : -1;
                if (sign < 0) {
                    double swap = u;
                    u = v;
                    v = swap;
                }
                double xyz[3];
                xyz[axis] = sign;
                xyz[(axis + 1) % 3] = u;
                xyz[(axis + 2) % 3] = v;
                c[k] = dvec3_make(xyz[0], xyz[1], xyz[2]);
            }
            tri[t][0] = c[0], tri[t][1] = c[1], tri[t][2] = c[2], t++;
            tri[t][0] = c[0], tri[t][1] = c[2], tri[t][2] = c[3], t++;
        }
}

static void test_closed_cube_solid_angles_sum_to_4pi_inside_and_0_outside(void **state)
{
    (void)state;
    dvec3 tri[12][3];
    cube_triangles(tri);
    /* Every triangle faces outwards. */
    for (int i = 0; i < 12; i++) {
        dvec3 n = dvec3_cross(dvec3_sub(tri[i][1], tri[i][0]), dvec3_sub(tri[i][2], tri[i][0]));
        assert_true(dvec3_dot(n, tri[i][0]) > 0.0);
    }
    const dvec3 inside[3] = {{0, 0, 0}, {0.3, -0.2, 0.5}, {0.1, 0.05, 0.999}};
    for (int p = 0; p < 3; p++) {
        double sum = 0.0, largest = 0.0;
        for (int i = 0; i < 12; i++) {
            double omega = solid_angle_triangle_signed(inside[p], tri[i][0], tri[i][1], tri[i][2]);
            sum += omega;
            largest = fmax(largest, omega);
        }
        assert_close(sum, 4.0 * PI, 64 * DBL_EPSILON * 4.0 * PI);
        if (p == 2)
            assert_true(largest > PI); /* the face 0.001 away: one of its triangles exceeds pi */
    }
    /* From the centre each face covers a sixth of the sphere. */
    assert_close(solid_angle_triangle(ORIGIN, tri[0][0], tri[0][1], tri[0][2]) +
                     solid_angle_triangle(ORIGIN, tri[1][0], tri[1][1], tri[1][2]),
                 4.0 * PI / 6.0, 16 * DBL_EPSILON);
    const dvec3 outside[2] = {{3, 0.5, -0.2}, {0, 0, 1.001}};
    for (int p = 0; p < 2; p++) {
        double sum = 0.0;
        for (int i = 0; i < 12; i++)
            sum += solid_angle_triangle_signed(outside[p], tri[i][0], tri[i][1], tri[i][2]);
        assert_close(sum, 0.0, 64 * DBL_EPSILON * 4.0 * PI);
    }
}

/* ---- Radiant flux and intensity -------------------------------------------- */

static void test_flux_is_the_integral_of_intensity(void **state)
{
    (void)state;
    exercise_checks("solid_angle_integral");
    double flux = 100.0, I = intensity_isotropic_point(flux);
    assert_agrees(integrate_over_sphere(constant, &I, QUADRATURE_GAUSS_LEGENDRE, N_DIRECTIONS), flux);
    assert_agrees(flux_lambertian_emitter_numeric(2.0, 3.0, N_DIRECTIONS), flux_lambertian_emitter(2.0, 3.0));
    /* Lambert's cosine law for emitters: I(theta) = L A cos theta, 0 behind. */
    assert_close(intensity_lambertian_emitter(2.0, 3.0, 0.5), 3.0, 4 * DBL_EPSILON);
    assert_true(intensity_lambertian_emitter(2.0, 3.0, -0.5) == 0.0);
    assert_agrees(intensity_sphere_emitter_numeric(2.0, 0.5, N_DIRECTIONS), intensity_sphere_emitter(2.0, 0.5));
}

/* ---- Irradiance ------------------------------------------------------------ */

static void test_uniform_sky_gives_pi_L(void **state)
{
    (void)state;
    exercise_checks("solid_angle_integral");
    for (double L = 0.5; L <= 8.0; L *= 2.0)
        assert_agrees(irradiance_from_cone(L, UP, UP, 0.5 * PI, QUADRATURE_GAUSS_LEGENDRE, N_DIRECTIONS),
                      irradiance_uniform_sky(L));
}

static void test_disk_light_on_axis_in_both_forms(void **state)
{
    (void)state;
    const double heights[] = {0.1, 1.0, 2.0, 10.0};
    for (int i = 0; i < 4; i++) {
        double h = heights[i], R = 1.0, L = 2.0;
        double exact = irradiance_disk_on_axis(L, R, h);
        assert_agrees(irradiance_from_cone(L, UP, UP, atan(R / h), QUADRATURE_GAUSS_LEGENDRE, N_DIRECTIONS), exact);
        assert_agrees(irradiance_from_disk_area(L, dvec3_make(0, 0, h), dvec3_make(0, 0, -1), R, ORIGIN, UP,
                                                QUADRATURE_GAUSS_LEGENDRE, N_DISK),
                      exact);
    }
    /* Far away the disk is a point light of intensity pi R^2 L. */
    assert_close(irradiance_disk_on_axis(1.0, 1.0, 1e3) / irradiance_point_light(PI, 1e3, 1.0), 1.0, 1e-6);
    /* Close up it is the whole sky: pi L. */
    assert_close(irradiance_disk_on_axis(1.0, 1.0, 1e-4), PI, 1e-7);
}

static void test_sphere_light_on_axis_and_tilted(void **state)
{
    (void)state;
    double L = 3.0, r = 0.5, d = 3.0, alpha = asin(r / d);
    /* On axis, tilted, and tilted until the sphere just touches the horizon. */
    const double tilts[] = {0.0, deg(40), 0.5 * PI - alpha};
    for (int i = 0; i < 3; i++) {
        quadrature_result q = irradiance_from_cone(L, UP, direction_at_polar_angle(tilts[i]), alpha,
                                                   QUADRATURE_GAUSS_LEGENDRE, N_DIRECTIONS);
        assert_agrees(q, irradiance_sphere_light(L, r, d, cos(tilts[i])));
    }
    assert_close(irradiance_sphere_light(L, r, d, 1.0), PI * L * (r / d) * (r / d), 4 * DBL_EPSILON);
}

/* Straddling the horizon there is no simple closed form (NaN), but the
 * integral is defined: with the centre on the horizon, half the sphere is
 * visible, E lies between 0 and the on-axis value. Wholly below: 0 both ways
 * (the cosine is clamped, not negative). */
static void test_sphere_light_across_and_below_the_horizon(void **state)
{
    (void)state;
    double r = 0.5, d = 3.0, alpha = asin(r / d);
    assert_true(isnan(irradiance_sphere_light(1.0, r, d, cos(0.5 * PI))));
    quadrature_result half = irradiance_from_cone(1.0, UP, direction_at_polar_angle(0.5 * PI), alpha,
                                                  QUADRATURE_GAUSS_LEGENDRE, N_DIRECTIONS);
    assert_true(half.value > 0.0 && half.value < irradiance_sphere_light(1.0, r, d, 1.0));
    double below = 0.5 * PI + alpha + deg(1);
    assert_true(irradiance_sphere_light(1.0, r, d, cos(below)) == 0.0);
    assert_true(irradiance_from_cone(1.0, UP, direction_at_polar_angle(below), alpha, QUADRATURE_GAUSS_LEGENDRE,
                                     N_DIRECTIONS)
                    .value == 0.0);
}

/* A point light is a sphere light shrunk at constant intensity I = pi r^2 L:
 * E = I cos theta / d^2, and 0 behind the surface (cos clamped). The small
 * sphere is exact (see test_sphere_light_on_axis_and_tilted); the shrinking
 * shows that the point law is its limit. */
static void test_point_light_is_the_limit_of_a_small_sphere(void **state)
{
    (void)state;
    double I = 2.0, d = 2.0, r = 1e-3, L = I / (PI * r * r);
    const double thetas[] = {0.0, deg(30), deg(60), deg(89)};
    for (int i = 0; i < 4; i++) {
        quadrature_result q = irradiance_from_cone(L, UP, direction_at_polar_angle(thetas[i]), asin(r / d),
                                                   QUADRATURE_GAUSS_LEGENDRE, N_DIRECTIONS);
        assert_agrees(q, irradiance_point_light(I, d, cos(thetas[i])));
    }
    /* Behind the surface: 0, not negative. */
    assert_true(irradiance_point_light(I, d, cos(deg(120))) == 0.0);
    assert_true(irradiance_point_light(I, d, -1.0) == 0.0);
    assert_true(irradiance_from_cone(L, UP, direction_at_polar_angle(deg(120)), asin(r / d),
                                     QUADRATURE_GAUSS_LEGENDRE, N_DIRECTIONS)
                    .value == 0.0);
    /* Inverse square: twice as far, a quarter of the irradiance. */
    assert_close(irradiance_point_light(I, 2 * d, 1.0) / irradiance_point_light(I, d, 1.0), 0.25, 4 * DBL_EPSILON);
}

static void test_polygon_irradiance_matches_the_area_integral(void **state)
{
    (void)state;
    /* A unit square at height 1, a tilted square, a triangle; seen from
     * points below, beside and far from them. */
    dvec3 square[4] = {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    double t = deg(30);
    dvec3 tilted[4] = {{-0.5, -0.5 * cos(t), 0.75 - 0.5 * sin(t)},
                       {0.5, -0.5 * cos(t), 0.75 - 0.5 * sin(t)},
                       {0.5, 0.5 * cos(t), 0.75 + 0.5 * sin(t)},
                       {-0.5, 0.5 * cos(t), 0.75 + 0.5 * sin(t)}};
    const dvec3 points[4] = {{0, 0, 0}, {0.5, 0.5, 0}, {2, -1, 0}, {-3, 0.2, 0}};
    for (int i = 0; i < 4; i++) {
        dvec3 *polys[2] = {square, tilted};
        for (int k = 0; k < 2; k++) {
            dvec3 *v = polys[k];
            quadrature_result a = irradiance_from_triangle_area(1.5, v[0], v[1], v[2], points[i], UP, 3, N_TRIANGLE);
            quadrature_result b = irradiance_from_triangle_area(1.5, v[0], v[2], v[3], points[i], UP, 3, N_TRIANGLE);
            quadrature_result both = {a.value + b.value, a.coarse + b.coarse, a.error_estimate + b.error_estimate,
                                      a.evaluations + b.evaluations};
            assert_agrees(both, irradiance_polygon(1.5, v, 4, points[i], UP));
        }
        /* Orientation does not matter: the square listed clockwise. */
        dvec3 reversed[4] = {square[3], square[2], square[1], square[0]};
        assert_close(irradiance_polygon(1.5, reversed, 4, points[i], UP),
                     irradiance_polygon(1.5, square, 4, points[i], UP), 64 * DBL_EPSILON);
    }
    /* A receiver tilted towards the light; triangle light. */
    dvec3 tri[3] = {{-1, 2, 1}, {1, 2, 1.5}, {0, 3, 2}};
    dvec3 n = dvec3_normalize(dvec3_make(0, 1, 1));
    quadrature_result q = irradiance_from_triangle_area(1.0, tri[0], tri[1], tri[2], ORIGIN, n, 3, N_TRIANGLE);
    assert_agrees(q, irradiance_polygon(1.0, tri, 3, ORIGIN, n));
}

/* ---- The BRDF ------------------------------------------------------------- */

static const double VIEW_ANGLES[] = {0.0, 30.0, 60.0, 85.0, 89.9};
enum { VIEWS = 5 };

static void test_lambertian_albedo_is_rho_at_every_angle(void **state)
{
    (void)state;
    exercise_checks("solid_angle_integral");
    const double rhos[] = {0.2, 0.8, 1.0};
    for (int r = 0; r < 3; r++) {
        brdf f = brdf_lambertian(rhos[r]);
        for (int i = 0; i < VIEWS; i++)
            assert_agrees(brdf_albedo(&f, deg(VIEW_ANGLES[i]), N_BRDF), rhos[r]);
        assert_true(brdf_check_energy(&f, 18, N_BRDF).conserves_energy);
    }
}

/* The twin: the albedo integral without cos theta_i gives 2 rho for a
 * Lambertian BRDF, and the same check must refuse it. */
static void test_albedo_without_cosine_fails_the_lambertian_check(void **state)
{
    (void)state;
    brdf f = brdf_lambertian(0.8);
    for (int i = 0; i < VIEWS; i++) {
        quadrature_result wrong = brdf_albedo_without_cosine(&f, deg(VIEW_ANGLES[i]), N_BRDF);
        assert_true(fabs(wrong.value - 0.8) > 1e3 * wrong.error_estimate);
        assert_close(wrong.value, 1.6, 1e3 * wrong.error_estimate); /* it is 2 rho */
    }
}

static void test_blinn_phong_albedo_matches_its_closed_form_at_normal_viewing(void **state)
{
    (void)state;
    const double p[] = {1.0, 8.0, 32.0, 128.0};
    for (int i = 0; i < 4; i++) {
        brdf f = brdf_blinn_phong(0.3, 0.7, p[i]);
        assert_agrees(brdf_albedo(&f, 0.0, N_BRDF), brdf_albedo_at_normal(&f));
        brdf g = brdf_blinn_phong_as_shaded(0.3, 0.7, p[i]);
        assert_agrees(brdf_albedo(&g, 0.0, N_BRDF), brdf_albedo_at_normal(&g));
    }
}

/* The lecture's Blinn-Phong is not energy conserving: with a big ks the
 * albedo exceeds 1 by far more than the quadrature's error, and the energy
 * check says so. A small ks passes the same check. */
static void test_blinn_phong_with_big_ks_gains_energy(void **state)
{
    (void)state;
    brdf big = brdf_blinn_phong(0.5, 2.0, 32.0);
    energy_check e = brdf_check_energy(&big, 18, N_BRDF);
    assert_false(e.conserves_energy);
    assert_true(e.worst_albedo > 1.5 && e.worst_albedo - 1.0 > 1e3 * e.worst_error);
    quadrature_result a = brdf_albedo(&big, 0.0, N_BRDF);
    assert_true(a.value > 1.0 + 1e3 * a.error_estimate);

    brdf modest = brdf_blinn_phong(0.5, 0.5, 32.0);
    assert_true(brdf_check_energy(&modest, 18, N_BRDF).conserves_energy);
    /* Chapter 01's formula read as a BRDF: its diffuse part alone has albedo
     * pi kd, 2.36 for the red sphere's kd = 0.75. */
    brdf shaded = brdf_blinn_phong_as_shaded(0.75, 0.5, 64.0);
    energy_check s = brdf_check_energy(&shaded, 18, N_BRDF);
    assert_false(s.conserves_energy);
    assert_true(s.worst_albedo > PI * 0.75);
}

static void test_glossy_mirror_albedo_is_rho_at_normal_and_at_most_rho(void **state)
{
    (void)state;
    const double p[] = {2.0, 20.0, 200.0};
    for (int i = 0; i < 3; i++) {
        brdf f = brdf_glossy_mirror(0.9, p[i]);
        assert_agrees(brdf_albedo(&f, 0.0, N_BRDF), 0.9);
        for (int k = 0; k < VIEWS; k++) {
            quadrature_result a = brdf_albedo(&f, deg(VIEW_ANGLES[k]), N_BRDF);
            assert_true(a.value <= 0.9 + a.error_estimate);
        }
        assert_true(brdf_check_energy(&f, 18, N_BRDF).conserves_energy);
    }
}

/* Helmholtz reciprocity, f(w_i -> w_o) = f(w_o -> w_i), holds for the
 * physically meant BRDFs; chapter 01's formula read as a BRDF breaks it
 * (its 1 / cos theta_i is not symmetric): the twin. */
static void test_brdfs_are_reciprocal_except_the_shading_formula(void **state)
{
    (void)state;
    brdf good[3] = {brdf_lambertian(0.7), brdf_blinn_phong(0.4, 0.6, 20.0), brdf_glossy_mirror(0.9, 10.0)};
    dvec3 dirs[4] = {dvec3_normalize(dvec3_make(0.3, 0.1, 0.9)), dvec3_normalize(dvec3_make(-0.5, 0.2, 0.6)),
                     dvec3_normalize(dvec3_make(0.1, -0.7, 0.3)), dvec3_normalize(dvec3_make(0.9, 0.0, 0.1))};
    for (int k = 0; k < 3; k++)
        for (int i = 0; i < 4; i++)
            for (int j = 0; j < 4; j++) {
                double fij = brdf_eval(&good[k], dirs[i], dirs[j]), fji = brdf_eval(&good[k], dirs[j], dirs[i]);
                assert_close(fij, fji, 8 * DBL_EPSILON * fabs(fij));
            }
    brdf shaded = brdf_blinn_phong_as_shaded(0.4, 0.6, 20.0);
    /* Near the mirror configuration, where the highlight matters. */
    dvec3 wi = dvec3_make(0.5, 0.0, sqrt(0.75)), wo = dvec3_make(-0.8, 0.0, 0.6);
    double fij = brdf_eval(&shaded, wi, wo), fji = brdf_eval(&shaded, wo, wi);
    assert_true(fabs(fij - fji) > 0.1 * fabs(fij));
}

static void test_brdf_is_zero_below_the_horizon(void **state)
{
    (void)state;
    brdf fs[3] = {brdf_lambertian(0.7), brdf_blinn_phong(0.4, 0.6, 20.0), brdf_glossy_mirror(0.9, 10.0)};
    dvec3 above = dvec3_normalize(dvec3_make(0.2, 0.1, 0.9)), below = dvec3_normalize(dvec3_make(0.2, 0.1, -0.9));
    dvec3 grazing = dvec3_make(1, 0, 0);
    for (int k = 0; k < 3; k++) {
        assert_true(brdf_eval(&fs[k], below, above) == 0.0);
        assert_true(brdf_eval(&fs[k], above, below) == 0.0);
        assert_true(brdf_eval(&fs[k], grazing, above) == 0.0);
        assert_true(brdf_eval(&fs[k], above, above) > 0.0);
    }
}

/* ---- The reflection equation ----------------------------------------------- */

static double graded_sky(const void *ctx, dvec3 w)
{
    return *(const double *)ctx * (1.0 + w.z);
}

static void test_reflection_equation_under_uniform_and_graded_skies(void **state)
{
    (void)state;
    double L0 = 2.0;
    brdf lambert = brdf_lambertian(0.6);
    for (int i = 0; i < VIEWS; i++) {
        dvec3 wr = direction_at_polar_angle(deg(VIEW_ANGLES[i]));
        /* Lambertian: L_r = rho/pi * E, E = pi L0 (uniform) or pi L0 + 2 pi L0 / 3 (graded). */
        assert_agrees(reflected_radiance(&lambert, constant, &L0, wr, N_BRDF), 0.6 * L0);
        assert_agrees(reflected_radiance(&lambert, graded_sky, &L0, wr, N_BRDF), 0.6 * L0 * 5.0 / 3.0);
    }
    /* The glossy mirror at normal viewing: rho L0 (1 + (p+2)/(p+3)). */
    brdf glossy = brdf_glossy_mirror(0.9, 50.0);
    assert_agrees(reflected_radiance(&glossy, graded_sky, &L0, UP, N_BRDF), 0.9 * L0 * (1.0 + 52.0 / 53.0));
    /* Any BRDF under a uniform sky reflects its albedo times the sky. */
    brdf phong = brdf_blinn_phong(0.5, 0.5, 32.0);
    assert_agrees(reflected_radiance(&phong, constant, &L0, UP, N_BRDF), L0 * brdf_albedo_at_normal(&phong));
}

/* ---- The rendering equation: the closed furnace ----------------------------- */

/* Relative rounding of the furnace series after k bounces: the loop adds k+1
 * terms (k+1 roundings), each term is a pow (an ulp or two), and the closed
 * form has a pow, a subtraction that loses at most log2(1/(1-rho)) bits, and
 * a division. 16 ulps per bounce plus the cancellation covers it. */
static double series_rounding(double rho, int k) { return (16.0 * (k + 1) + 1.0 / (1.0 - rho)) * DBL_EPSILON; }

static void test_furnace_partial_sums_equal_the_closed_form(void **state)
{
    (void)state;
    const double rhos[] = {0.0, 0.3, 0.5, 0.8, 0.99};
    for (int r = 0; r < 5; r++) {
        double Le = 1.5, rho = rhos[r];
        for (int k = 0; k <= 200; k++) {
            double sum = furnace_partial_sum(Le, rho, k), closed = furnace_partial_sum_closed(Le, rho, k);
            assert_close(sum, closed, series_rounding(rho, k) * closed);
            assert_close(furnace_bounce(Le, rho, k), Le * pow(rho, k), 0.0);
            assert_true(sum <= furnace_radiance(Le, rho) * (1.0 + series_rounding(rho, k)));
        }
        /* The series converges to Le / (1 - rho). */
        double tail = Le * pow(rho, 2001) / (1.0 - rho);
        assert_close(furnace_partial_sum_closed(Le, rho, 2000), furnace_radiance(Le, rho),
                     tail + series_rounding(rho, 0) * furnace_radiance(Le, rho));
    }
    /* rho = 1: no limit; the sum grows by Le per bounce. */
    assert_close(furnace_partial_sum_closed(2.0, 1.0, 9), 20.0, 0.0);
}

static void test_sphere_form_factors_are_area_over_4_pi_R2(void **state)
{
    (void)state;
    double R = 2.5;
    sphere_patches s;
    sphere_patches_build(&s, R, 8, 16);
    /* The kernel cos cos' / (pi r^2) between any two points of the sphere,
     * normals pointing inwards, is 1 / (4 pi R^2). */
    double expected = 1.0 / (4.0 * PI * R * R);
    for (int i = 0; i < s.count; i += 7)
        for (int j = 0; j < s.count; j += 5) {
            if (i == j)
                continue;
            dvec3 ni = dvec3_scale(s.centre[i], -1.0 / R), nj = dvec3_scale(s.centre[j], -1.0 / R);
            double k = form_factor_kernel(s.centre[i], ni, s.centre[j], nj);
            assert_close(k, expected, 64 * DBL_EPSILON * expected);
            /* F_ij is that times A_j. */
            assert_close(s.form_factor[(size_t)i * (size_t)s.count + (size_t)j], expected * s.area[j],
                         8 * DBL_EPSILON * expected * s.area[j]);
            /* The twin: the kernel without its 1/pi is not the sphere's. */
            double no_pi = k * PI;
            assert_true(fabs(no_pi - expected) > 1.0 * expected);
        }
    /* Every row sums to 1: a point inside a closed sphere sees only the sphere. */
    for (int i = 0; i < s.count; i++) {
        double sum = 0.0;
        for (int j = 0; j < s.count; j++)
            sum += s.form_factor[(size_t)i * (size_t)s.count + (size_t)j];
        assert_close(sum, 1.0, (s.count + 8.0) * DBL_EPSILON);
    }
    sphere_patches_free(&s);
}

/* Rounding of L_k on the patches, relative: each step sums count terms and
 * adds E; errors of earlier steps carry over multiplied by rho <= 1. So
 * (count + 2)(k + 1) eps, plus the series' own rounding. */
static double patch_rounding(int count, double rho, int k)
{
    return (count + 2.0) * (k + 1.0) * DBL_EPSILON + series_rounding(rho, k);
}

static void test_operator_iteration_equals_the_partial_sums(void **state)
{
    (void)state;
    sphere_patches s;
    sphere_patches_build(&s, 1.0, 16, 32);
    double *E = memory_allocate((size_t)s.count, sizeof *E);
    double *L = memory_allocate((size_t)s.count, sizeof *L);
    double *next = memory_allocate((size_t)s.count, sizeof *next);
    const double rhos[] = {0.5, 0.8, 0.95};
    for (int r = 0; r < 3; r++) {
        double Le = 1.0, rho = rhos[r];
        for (int i = 0; i < s.count; i++)
            E[i] = L[i] = Le;
        double L_quadrature = Le;
        for (int k = 1; k <= 60; k++) {
            rendering_operator_apply(&s, rho, E, L, next);
            double *swap = L;
            L = next;
            next = swap;
            quadrature_result q = furnace_step_quadrature(Le, rho, L_quadrature, N_DIRECTIONS);
            L_quadrature = q.value;
            double closed = furnace_partial_sum_closed(Le, rho, k);
            for (int i = 0; i < s.count; i++)
                assert_close(L[i], closed, patch_rounding(s.count, rho, k) * closed);
            /* K by quadrature: each step's error estimate, accumulated. */
            assert_close(L_quadrature, closed, (k + 1) * q.error_estimate + series_rounding(rho, k) * closed);
        }
    }
    free(E);
    free(L);
    free(next);
    sphere_patches_free(&s);
}

/* Non-uniform emission: only a cap emits. K E is rho times the area-weighted
 * average <E> on every patch, so L_k = E + <E> rho (1 - rho^k) / (1 - rho):
 * the indirect light inside a sphere is uniform. */
static void test_furnace_with_a_lamp_has_uniform_indirect_light(void **state)
{
    (void)state;
    sphere_patches s;
    sphere_patches_build(&s, 1.0, 16, 32);
    double *E = memory_allocate((size_t)s.count, sizeof *E);
    double *L = memory_allocate((size_t)s.count, sizeof *L);
    double *next = memory_allocate((size_t)s.count, sizeof *next);
    double rho = 0.7, average = 0.0;
    for (int i = 0; i < s.count; i++) {
        E[i] = L[i] = s.centre[i].z > cos(deg(30)) ? 4.0 : 0.0;
        average += E[i] * s.area[i] / (4.0 * PI);
    }
    assert_true(average > 0.0 && average < 4.0);
    for (int k = 1; k <= 40; k++) {
        rendering_operator_apply(&s, rho, E, L, next);
        double *swap = L;
        L = next;
        next = swap;
        double indirect = average * rho * (1.0 - pow(rho, k)) / (1.0 - rho);
        for (int i = 0; i < s.count; i++)
            assert_close(L[i], E[i] + indirect, patch_rounding(s.count, rho, k) * (E[i] + indirect));
    }
    free(E);
    free(L);
    free(next);
    sphere_patches_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gauss_legendre_is_exact_for_degree_2n_minus_1_and_not_2n),
        cmocka_unit_test(test_midpoint_error_falls_as_h_squared_and_the_estimate_covers_it),
        cmocka_unit_test(test_solid_angle_of_the_sphere_is_4pi),
        cmocka_unit_test(test_solid_angle_of_cones_up_to_half_angle_pi),
        cmocka_unit_test(test_solid_angle_of_a_sphere_seen_from_outside),
        cmocka_unit_test(test_triangle_solid_angle_matches_the_area_integral),
        cmocka_unit_test(test_triangle_seen_edge_on_has_zero_solid_angle),
        cmocka_unit_test(test_large_close_triangle_covers_more_than_pi_and_atan2_keeps_it),
        cmocka_unit_test(test_naive_atan_gets_the_large_triangle_wrong),
        cmocka_unit_test(test_closed_cube_solid_angles_sum_to_4pi_inside_and_0_outside),
        cmocka_unit_test(test_flux_is_the_integral_of_intensity),
        cmocka_unit_test(test_uniform_sky_gives_pi_L),
        cmocka_unit_test(test_disk_light_on_axis_in_both_forms),
        cmocka_unit_test(test_sphere_light_on_axis_and_tilted),
        cmocka_unit_test(test_sphere_light_across_and_below_the_horizon),
        cmocka_unit_test(test_point_light_is_the_limit_of_a_small_sphere),
        cmocka_unit_test(test_polygon_irradiance_matches_the_area_integral),
        cmocka_unit_test(test_lambertian_albedo_is_rho_at_every_angle),
        cmocka_unit_test(test_albedo_without_cosine_fails_the_lambertian_check),
        cmocka_unit_test(test_blinn_phong_albedo_matches_its_closed_form_at_normal_viewing),
        cmocka_unit_test(test_blinn_phong_with_big_ks_gains_energy),
        cmocka_unit_test(test_glossy_mirror_albedo_is_rho_at_normal_and_at_most_rho),
        cmocka_unit_test(test_brdfs_are_reciprocal_except_the_shading_formula),
        cmocka_unit_test(test_brdf_is_zero_below_the_horizon),
        cmocka_unit_test(test_reflection_equation_under_uniform_and_graded_skies),
        cmocka_unit_test(test_furnace_partial_sums_equal_the_closed_form),
        cmocka_unit_test(test_sphere_form_factors_are_area_over_4_pi_R2),
        cmocka_unit_test(test_operator_iteration_equals_the_partial_sums),
        cmocka_unit_test(test_furnace_with_a_lamp_has_uniform_indirect_light),
    };
    return cmocka_run_group_tests_name("ch07 radiometry", tests, NULL, NULL);
}
