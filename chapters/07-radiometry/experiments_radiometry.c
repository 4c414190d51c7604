/* experiments_radiometry.c -- chapter 07's tables, the CSV for its plots,
 * and the irradiance a scene file's lights deliver (see
 * experiments_radiometry.h). */
#include "07-radiometry/experiments_radiometry.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "07-radiometry/radiometry.h"
#include "atomic_file.h"
#include "memory.h"

/* Quadrature sizes used throughout (points per dimension on the coarse grid;
 * the fine grid has twice as many). Chosen so that every smooth integral
 * below is resolved to about twelve digits, which the printed error
 * estimates show. */
enum {
    DIRECTIONS_N = 32,   /* integrals over cones of directions */
    DISK_N = 32,         /* integrals over a disk */
    TRIANGLE_N = 8,      /* Gauss-Legendre points per side of each triangle piece */
    BRDF_N = 64,         /* albedo and reflection integrals (narrow lobes need more) */
    FURNACE_RINGS = 16,  /* the furnace sphere's patches: rings x segments */
    FURNACE_SEGMENTS = 32,
};

/* Agreement of a quadrature with a closed form is judged by the quadrature's
 * own error estimate, plus this relative floor: the two are sums of ~100
 * doubles each and can differ by rounding (a few 1e-16) even where the
 * estimate is 0. Twelve digits is the accuracy the sizes above aim for. */
static const double AGREEMENT_ROUNDING_FLOOR = 1e-12;

/* Whether the tables print: set once by radiometry_experiments_print for
 * every function below (each row prints or not alike; a parameter through
 * each of them would say the same thing twenty times). */
static bool verbose = true;

/* ---- printing ------------------------------------------------------------- */

static void heading(const char *title)
{
    if (verbose)
        printf("\n%s\n", title);
}

static void table_header(void)
{
    if (verbose)
        printf("  %-54s %17s %17s %9s %9s %9s  %s\n", "quantity", "numeric", "closed form", "rel.err", "estimate",
               "evals", "agrees");
}

/* One quantity: the quadrature, its closed form, and whether they agree
 * within the quadrature's error estimate. Returns that verdict. */
static bool row(const char *name, quadrature_result q, double exact)
{
    bool agrees = fabs(q.value - exact) <= q.error_estimate;
    if (verbose)
        printf("  %-54s %17.12f %17.12f %9.1e %9.1e %9ld  %s\n", name, q.value, exact, relative_error(q.value, exact),
               q.error_estimate / fmax(fabs(exact), 1e-300), q.evaluations, agrees ? "yes" : "NO");
    return agrees;
}

/* ---- integrands of the program's own ---------------------------------------- */

static double constant(const void *ctx, dvec3 w)
{
    (void)w;
    return *(const double *)ctx;
}

static double cosine(const void *ctx, dvec3 w)
{
    (void)ctx;
    return w.z;
}

/* A sky brighter at the zenith: L_i(theta) = L0 (1 + cos theta). */
static double graded_sky(const void *ctx, dvec3 w)
{
    return *(const double *)ctx * (1.0 + w.z);
}

/* ---- Quadrature: how the integrals are computed ---------------------------- */

static void show_quadrature(void)
{
    heading("Quadrature: the integral of cos theta over the hemisphere (exact: pi), error and estimate\n"
            "(theta on n nodes, phi on 2n midpoints; the estimate is |I(2n) - I(n)| plus a rounding bound)");
    if (verbose)
        printf("  %4s %14s %14s %18s %14s\n", "n", "midpoint err", "estimate", "Gauss-Legendre err", "estimate");
    for (int n = 2; n <= 64; n *= 2) {
        quadrature_result m = integrate_over_hemisphere(cosine, NULL, dvec3_make(0, 0, 1), QUADRATURE_MIDPOINT, n);
        quadrature_result g =
            integrate_over_hemisphere(cosine, NULL, dvec3_make(0, 0, 1), QUADRATURE_GAUSS_LEGENDRE, n);
        if (verbose)
            printf("  %4d %14.2e %14.2e %18.2e %14.2e\n", n, fabs(m.value - PI), m.error_estimate, fabs(g.value - PI),
                   g.error_estimate);
    }
}

/* An estimate is only as good as the grid: a triangle 1/32 below the point
 * has an integrand (1/r^3) that changes on the scale 1/32, and until the
 * pieces are that small the two grids can agree with each other and both be
 * wrong. */
static void show_resolution(void)
{
    dvec3 p = dvec3_make(0, 0, 0);
    dvec3 a = dvec3_make(-4, -3, -0.03125), b = dvec3_make(5, -3, -0.03125), c = dvec3_make(0, 5, -0.03125);
    double exact = solid_angle_triangle(p, a, b, c);
    heading("Quadrature needs a resolved grid: solid angle of a 9-unit triangle 1/32 below the point\n"
            "(4^level pieces of 8 x 8 Gauss-Legendre points; estimate from level + 1)");
    if (verbose)
        printf("  %5s %12s %17s %12s %12s %s\n", "level", "piece side", "numeric", "error", "estimate", "");
    for (int level = 2; level <= 7; level++) {
        quadrature_result q = solid_angle_triangle_numeric(p, a, b, c, level, TRIANGLE_N);
        double error = fabs(q.value - exact);
        if (verbose)
            printf("  %5d %12.4f %17.12f %12.2e %12.2e %s\n", level, 9.0 / (1 << level), q.value, error, q.error_estimate,
                   error <= q.error_estimate ? "" : "<- the estimate is wrong: the grid does not resolve 1/r^3");
    }
    if (verbose)
        printf("  Van Oosterom-Strackee: %.12f\n", exact);
}

/* ---- Solid angle ----------------------------------------------------------- */

static bool show_solid_angle(void)
{
    bool ok = true;
    double one = 1.0;
    dvec3 up = dvec3_make(0, 0, 1);
    heading("Solid angle: Omega = A / r^2 on the unit sphere; d omega = sin theta d theta d phi");
    table_header();
    ok &= row("sphere (4 pi)", integrate_over_sphere(constant, &one, QUADRATURE_GAUSS_LEGENDRE, DIRECTIONS_N),
              4.0 * PI);
    const double alphas[] = {30.0, 90.0, 180.0};
    for (int i = 0; i < 3; i++) {
        char name[64];
        double alpha = alphas[i] * PI / 180.0;
        snprintf(name, sizeof name, "cone, half-angle %g deg: 2 pi (1 - cos alpha)", alphas[i]);
        ok &= row(name, integrate_over_cone(constant, &one, up, alpha, QUADRATURE_GAUSS_LEGENDRE, DIRECTIONS_N),
                  solid_angle_cone(alpha));
    }
    ok &= row("sphere r=1 seen from d=3 (cone asin(r/d))",
              integrate_over_cone(constant, &one, up, asin(1.0 / 3.0), QUADRATURE_GAUSS_LEGENDRE, DIRECTIONS_N),
              solid_angle_sphere(1.0, 3.0));

    /* Triangles: Van Oosterom-Strackee against the integral of cos theta' / r^2 dA. */
    dvec3 p = dvec3_make(0, 0, 0);
    dvec3 a = dvec3_make(-1, -1, 2), b = dvec3_make(2, -0.5, 2.5), c = dvec3_make(0, 1.5, 1.5);
    ok &= row("triangle, 2 away (Van Oosterom-Strackee)", solid_angle_triangle_numeric(p, a, b, c, 3, TRIANGLE_N),
              solid_angle_triangle(p, a, b, c));
    dvec3 A = dvec3_make(-4, -3, -0.25), B = dvec3_make(5, -3, -0.25), C = dvec3_make(0, 5, -0.25);
    ok &= row("large triangle 0.25 below the point (> pi)", solid_angle_triangle_numeric(p, A, B, C, 6, TRIANGLE_N),
              solid_angle_triangle(p, A, B, C));
    if (verbose)
        printf("  %-54s %17s %17.12f   (2 atan(num/den) loses 2 pi when den < 0)\n", "  ... the same by 2 atan(num/den)",
               "", solid_angle_triangle_naive(p, A, B, C));
    dvec3 E1 = dvec3_make(1, 0, 0), E2 = dvec3_make(3, 0, 0), E3 = dvec3_make(2, 2, 0);
    ok &= row("triangle seen edge-on (in its plane)", solid_angle_triangle_numeric(p, E1, E2, E3, 2, TRIANGLE_N),
              solid_angle_triangle(p, E1, E2, E3));
    return ok;
}

/* ---- Radiant flux and intensity ------------------------------------------- */

static bool show_intensity(void)
{
    bool ok = true;
    heading("Radiant intensity I = d Phi / d omega, flux Phi");
    table_header();
    double flux = 100.0, I = intensity_isotropic_point(flux);
    ok &= row("isotropic point, Phi=100: integral of I d omega",
              integrate_over_sphere(constant, &I, QUADRATURE_GAUSS_LEGENDRE, DIRECTIONS_N), flux);
    ok &= row("flat Lambertian emitter L=2 A=3: Phi = pi L A", flux_lambertian_emitter_numeric(2.0, 3.0, DIRECTIONS_N),
              flux_lambertian_emitter(2.0, 3.0));
    ok &= row("sphere emitter L=2 r=0.5: I = pi r^2 L", intensity_sphere_emitter_numeric(2.0, 0.5, DIRECTIONS_N),
              intensity_sphere_emitter(2.0, 0.5));
    return ok;
}

/* ---- Irradiance ------------------------------------------------------------ */

static bool show_irradiance(void)
{
    bool ok = true;
    dvec3 up = dvec3_make(0, 0, 1), origin = dvec3_make(0, 0, 0);
    heading("Irradiance E = integral of L_i cos theta d omega (all lights radiance L = 1)");
    table_header();
    ok &= row("uniform sky: pi L",
              irradiance_from_cone(1.0, up, up, 0.5 * PI, QUADRATURE_GAUSS_LEGENDRE, DIRECTIONS_N),
              irradiance_uniform_sky(1.0));
    double R = 1.0, h = 2.0;
    ok &= row("disk R=1 at h=2, solid-angle form", irradiance_from_cone(1.0, up, up, atan(R / h),
                                                                        QUADRATURE_GAUSS_LEGENDRE, DIRECTIONS_N),
              irradiance_disk_on_axis(1.0, R, h));
    ok &= row("disk R=1 at h=2, area form cos cos' / r^2 dA",
              irradiance_from_disk_area(1.0, dvec3_make(0, 0, h), dvec3_make(0, 0, -1), R, origin, up,
                                        QUADRATURE_GAUSS_LEGENDRE, DISK_N),
              irradiance_disk_on_axis(1.0, R, h));
    double r = 0.5, d = 3.0;
    ok &= row("sphere r=0.5 at d=3, on axis: pi L (r/d)^2",
              irradiance_from_cone(1.0, up, up, asin(r / d), QUADRATURE_GAUSS_LEGENDRE, DIRECTIONS_N),
              irradiance_sphere_light(1.0, r, d, 1.0));
    double tilt = 40.0 * PI / 180.0;
    ok &= row("the same sphere 40 deg off the normal",
              irradiance_from_cone(1.0, up, direction_at_polar_angle(tilt), asin(r / d), QUADRATURE_GAUSS_LEGENDRE,
                                   DIRECTIONS_N),
              irradiance_sphere_light(1.0, r, d, cos(tilt)));
    /* A point light as the limit of a small sphere with the same intensity:
     * I = pi r^2 L, so L = I / (pi r^2). */
    double small = 1e-3, I = 1.0, L_small = I / (PI * small * small), theta = 60.0 * PI / 180.0;
    ok &= row("point I=1 at d=2, 60 deg (sphere r=1e-3): I cos/d^2",
              irradiance_from_cone(L_small, up, direction_at_polar_angle(theta), asin(small / 2.0),
                                   QUADRATURE_GAUSS_LEGENDRE, DIRECTIONS_N),
              irradiance_point_light(I, 2.0, cos(theta)));
    ok &= row("the same point light behind the surface (120 deg)",
              irradiance_from_cone(L_small, up, direction_at_polar_angle(PI - theta), asin(small / 2.0),
                                   QUADRATURE_GAUSS_LEGENDRE, DIRECTIONS_N),
              irradiance_point_light(I, 2.0, cos(PI - theta)));
    /* A unit square light at height 1, seen from the floor below its corner. */
    dvec3 square[4] = {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    quadrature_result q1 = irradiance_from_triangle_area(1.0, square[0], square[1], square[2], origin, up, 3, TRIANGLE_N);
    quadrature_result q2 = irradiance_from_triangle_area(1.0, square[0], square[2], square[3], origin, up, 3, TRIANGLE_N);
    quadrature_result both = {q1.value + q2.value, q1.coarse + q2.coarse, q1.error_estimate + q2.error_estimate,
                              q1.evaluations + q2.evaluations};
    ok &= row("unit square at height 1, below a corner (Lambert)", both, irradiance_polygon(1.0, square, 4, origin, up));
    return ok;
}

/* ---- The BRDF and its energy check ---------------------------------------- */

/* The BRDFs the program and the albedo plot look at. */
static brdf brdf_example(int i)
{
    switch (i) {
    case 0: return brdf_lambertian(0.8);
    case 1: return brdf_blinn_phong(0.5, 0.5, 32.0);
    case 2: return brdf_blinn_phong(0.5, 2.0, 32.0);
    case 3: return brdf_glossy_mirror(0.9, 200.0);
    default: return brdf_blinn_phong_as_shaded(0.75, 0.5, 64.0); /* chapter 01's red sphere, red channel */
    }
}
enum { BRDF_EXAMPLES = 5 };

static bool show_brdf(void)
{
    bool ok = true;
    heading("BRDF energy check: albedo(theta_o) = integral of f_r cos theta_i d omega_i must stay <= 1");
    if (verbose)
        printf("  %-36s %17s %17s %9s %9s  %s\n", "BRDF", "albedo(0)", "closed form", "rel.err", "estimate",
               "worst over theta_o (18 angles)");
    for (int i = 0; i < BRDF_EXAMPLES; i++) {
        brdf f = brdf_example(i);
        char name[64];
        brdf_describe(&f, name, sizeof name);
        quadrature_result a = brdf_albedo(&f, 0.0, BRDF_N);
        double exact = brdf_albedo_at_normal(&f);
        ok &= fabs(a.value - exact) <= a.error_estimate;
        energy_check e = brdf_check_energy(&f, 18, BRDF_N);
        if (verbose)
            printf("  %-36s %17.12f %17.12f %9.1e %9.1e  %.4f at %4.1f deg: %s\n", name, a.value, exact,
                   relative_error(a.value, exact), a.error_estimate / exact, e.worst_albedo,
                   e.worst_theta_o * 180.0 / PI, e.conserves_energy ? "conserves energy" : "GAINS ENERGY");
    }
    brdf lambert = brdf_lambertian(0.8);
    quadrature_result wrong = brdf_albedo_without_cosine(&lambert, 0.0, BRDF_N);
    if (verbose)
        printf("  %-36s %17.12f %17.12f   (forgot cos theta_i: 2 rho instead of rho)\n",
               "Lambertian rho=0.8, no cos theta_i", wrong.value, 0.8);
    return ok;
}

/* ---- The reflection equation ----------------------------------------------- */

static bool show_reflection(void)
{
    bool ok = true;
    double one = 1.0;
    dvec3 normal_view = dvec3_make(0, 0, 1);
    heading("Reflection equation L_r = integral of f_r L_i cos theta_i d omega_i (viewed along the normal)");
    table_header();
    brdf lambert = brdf_lambertian(0.8);
    ok &= row("Lambertian 0.8, uniform sky 1: rho L", reflected_radiance(&lambert, constant, &one, normal_view, BRDF_N),
              0.8);
    ok &= row("Lambertian 0.8, sky 1 + cos theta: 5/3 rho",
              reflected_radiance(&lambert, graded_sky, &one, normal_view, BRDF_N), 0.8 * 5.0 / 3.0);
    brdf glossy = brdf_glossy_mirror(0.9, 200.0);
    ok &= row("glossy mirror .9 p=200, sky 1+cos: rho(1+(p+2)/(p+3))",
              reflected_radiance(&glossy, graded_sky, &one, normal_view, BRDF_N), 0.9 * (1.0 + 202.0 / 203.0));
    brdf phong = brdf_blinn_phong(0.5, 0.5, 32.0);
    ok &= row("Blinn-Phong .5/.5/32, uniform sky: its albedo",
              reflected_radiance(&phong, constant, &one, normal_view, BRDF_N), brdf_albedo_at_normal(&phong));
    return ok;
}

/* ---- The rendering equation: the closed furnace ----------------------------- */

/* Rounding of the patch iteration, relative: each step sums `count` terms
 * (at most count eps of relative error) and adds E (one more rounding); the
 * errors of earlier steps are carried along (times rho <= 1), so after k
 * steps at most (count + 2) (k + 1) eps. The closed form's pow and division
 * add a few ulps; 8 more per step covers them. */
static double furnace_rounding_bound(int count, int k) { return (count + 8.0) * (k + 1.0) * DBL_EPSILON; }

/* The furnace iterated three ways for bounces 0..bounces: the series summed
 * bounce by bounce, L_{k+1} = E + K L_k on the discretized sphere, and the
 * same with K by quadrature of the reflection equation. Writes a CSV row per
 * bounce if csv is not NULL; prints the table if `print`. */
static bool furnace(double Le, double rho, int bounces, FILE *csv, bool main_rho, bool print)
{
    bool ok = true;
    sphere_patches s;
    sphere_patches_build(&s, 1.0, FURNACE_RINGS, FURNACE_SEGMENTS);
    double *E = memory_allocate((size_t)s.count, sizeof *E);
    double *L = memory_allocate((size_t)s.count, sizeof *L);
    double *next = memory_allocate((size_t)s.count, sizeof *next);
    for (int i = 0; i < s.count; i++)
        E[i] = L[i] = Le; /* L_0 = E: bounce 0 is the emission itself */
    double L_quadrature = Le;
    double limit = furnace_radiance(Le, rho);
    if (print && verbose)
        printf("  %3s %14s %16s %16s %16s %16s %10s\n", "k", "Le rho^k", "partial sum", "closed form",
               "patches L_k", "quadrature L_k", "limit - L_k");
    for (int k = 0; k <= bounces; k++) {
        if (k > 0) {
            rendering_operator_apply(&s, rho, E, L, next);
            double *swap = L;
            L = next;
            next = swap;
            L_quadrature = furnace_step_quadrature(Le, rho, L_quadrature, DIRECTIONS_N).value;
        }
        double patch_min = L[0], patch_max = L[0];
        for (int i = 1; i < s.count; i++) {
            patch_min = fmin(patch_min, L[i]);
            patch_max = fmax(patch_max, L[i]);
        }
        double sum = furnace_partial_sum(Le, rho, k), closed = furnace_partial_sum_closed(Le, rho, k);
        double bound = furnace_rounding_bound(s.count, k);
        ok &= relative_error(patch_max, closed) <= bound && relative_error(patch_min, closed) <= bound;
        if (print && verbose && (k <= 10 || k % 10 == 0))
            printf("  %3d %14.10f %16.12f %16.12f %16.12f %16.12f %10.2e\n", k, furnace_bounce(Le, rho, k), sum,
                   closed, patch_max, L_quadrature, limit - sum);
        if (csv != NULL)
            fprintf(csv, "%.17g,%d,%.17g,%.17g,%.17g,%.17g,%.17g,%d\n", rho, k, furnace_bounce(Le, rho, k), sum, L[0],
                    L_quadrature, limit, main_rho ? 1 : 0);
    }
    free(E);
    free(L);
    free(next);
    sphere_patches_free(&s);
    return ok;
}

/* A lamp in the furnace: only a cap around the north pole emits, made of
 * whole patches: those whose centres lie within 30 degrees of the pole (with
 * 16 rings, the top three rows: a cap reaching 33.75 degrees). Every patch
 * sees the same average, so the indirect light is the same everywhere:
 * L_i = E_i + <E> rho / (1 - rho). */
static void furnace_lamp(double rho, int bounces)
{
    sphere_patches s;
    sphere_patches_build(&s, 1.0, FURNACE_RINGS, FURNACE_SEGMENTS);
    double *E = memory_allocate((size_t)s.count, sizeof *E);
    double *L = memory_allocate((size_t)s.count, sizeof *L);
    double *next = memory_allocate((size_t)s.count, sizeof *next);
    double average = 0.0;
    for (int i = 0; i < s.count; i++) {
        E[i] = s.centre[i].z > cos(30.0 * PI / 180.0) ? 1.0 : 0.0;
        L[i] = E[i];
        average += E[i] * s.area[i] / (4.0 * PI);
    }
    for (int k = 1; k <= bounces; k++) {
        rendering_operator_apply(&s, rho, E, L, next);
        double *swap = L;
        L = next;
        next = swap;
    }
    double indirect = average * rho * (1.0 - pow(rho, bounces)) / (1.0 - rho);
    if (verbose)
        printf("  lamp (the rows whose centres lie within 30 deg of the pole) only: after %d bounces, lamp patch %.12f (E + indirect %.12f), dark patch %.12f\n"
               "  (indirect closed form <E> rho (1 - rho^k) / (1 - rho) = %.12f: the same on every patch)\n",
               bounces, L[0], 1.0 + indirect, L[s.count - 1], indirect);
    free(E);
    free(L);
    free(next);
    sphere_patches_free(&s);
}


/* ---- Data for the plots ----------------------------------------------------- */

/* DIR/NAME through atomic_file.h, with its header line. */
static bool csv_begin(atomic_file *f, const char *dir, const char *name, const char *header, char *err,
                      size_t err_size)
{
    if (!atomic_file_open_in(f, dir, name, err, err_size))
        return false;
    fprintf(f->stream, "%s\n", header);
    return true;
}

/* The furnace series for rho_main (column main = 1, the plot's left panel)
 * and, for comparison, 0.5 and 0.95 (the right panel's errors). */
static bool write_furnace_csv(const char *dir, double rho_main, char *err, size_t err_size)
{
    atomic_file f;
    if (!csv_begin(&f, dir, "ch07_furnace.csv", "rho,k,bounce,partial_sum,patch_iterate,quadrature_iterate,limit,main",
                   err, err_size))
        return false;
    const double rhos[3] = {0.5, rho_main, 0.95};
    for (int i = 0; i < 3; i++)
        if (i != 1 || (rho_main != 0.5 && rho_main != 0.95))
            furnace(1.0, rhos[i], 60, f.stream, i == 1 || rhos[i] == rho_main, false);
    return atomic_file_commit(&f, err, err_size);
}

/* Irradiance from a disk light against height: both numeric forms, the
 * closed form, and the point-light approximation I / h^2 with I = pi R^2 L. */
static bool write_disk_csv(const char *dir, char *err, size_t err_size)
{
    atomic_file f;
    if (!csv_begin(&f, dir, "ch07_disk_irradiance.csv",
                   "h_over_R,numeric_solid_angle,numeric_area,closed_form,point_light,error_estimate", err, err_size))
        return false;
    dvec3 up = dvec3_make(0, 0, 1), origin = dvec3_make(0, 0, 0);
    for (int i = 0; i <= 40; i++) {
        double h = pow(10.0, -1.5 + 3.5 * i / 40.0);
        quadrature_result cone = irradiance_from_cone(1.0, up, up, atan(1.0 / h), QUADRATURE_GAUSS_LEGENDRE, DIRECTIONS_N);
        quadrature_result area = irradiance_from_disk_area(1.0, dvec3_make(0, 0, h), dvec3_make(0, 0, -1), 1.0, origin,
                                                           up, QUADRATURE_GAUSS_LEGENDRE, DISK_N);
        fprintf(f.stream, "%.17g,%.17g,%.17g,%.17g,%.17g,%.3g\n", h, cone.value, area.value,
                irradiance_disk_on_axis(1.0, 1.0, h), irradiance_point_light(PI, h, 1.0),
                fmax(cone.error_estimate, area.error_estimate));
    }
    return atomic_file_commit(&f, err, err_size);
}

/* Albedo against viewing angle for the example BRDFs. */
static bool write_albedo_csv(const char *dir, char *err, size_t err_size)
{
    atomic_file f;
    if (!csv_begin(&f, dir, "ch07_albedo.csv",
                   "theta_o_deg,lambertian_0.8,blinn_phong_0.5_0.5_32,blinn_phong_0.5_2_32,glossy_mirror_0.9_200,"
                   "ch01_shading_0.75_0.5_64", err, err_size))
        return false;
    for (int t = 0; t <= 89; t++) {
        fprintf(f.stream, "%d", t);
        for (int i = 0; i < BRDF_EXAMPLES; i++) {
            brdf b = brdf_example(i);
            fprintf(f.stream, ",%.17g", brdf_albedo(&b, t * PI / 180.0, BRDF_N).value);
        }
        fprintf(f.stream, "\n");
    }
    return atomic_file_commit(&f, err, err_size);
}

bool radiometry_experiments_write_csv(const char *dir, double rho, char *err, size_t err_size)
{
    return write_furnace_csv(dir, rho, err, err_size) && write_disk_csv(dir, err, err_size) &&
           write_albedo_csv(dir, err, err_size);
}

/* ---- Every table ------------------------------------------------------------ */

bool radiometry_experiments_print(double rho, int bounces, bool print)
{
    verbose = print;
    bool ok = true;
    show_quadrature();
    show_resolution();
    ok &= show_solid_angle();
    ok &= show_intensity();
    ok &= show_irradiance();
    ok &= show_brdf();
    ok &= show_reflection();

    heading("Rendering equation, closed furnace: L = E + K L = E + K E + K^2 E + ...");
    if (verbose)
        printf("  Le = 1, rho = %g: bounce k adds Le rho^k; limit Le / (1 - rho) = %.12f\n"
               "  patches: the sphere cut into %d x %d patches, F_ij = A_j / (4 pi R^2), L_{k+1} = E + rho F L_k\n",
               rho, furnace_radiance(1.0, rho), FURNACE_RINGS, FURNACE_SEGMENTS);
    ok &= furnace(1.0, rho, bounces, NULL, true, true);
    furnace_lamp(rho, bounces);
    return ok;
}

/* ---- --scene: the irradiance a scene's lights deliver -------------------------- */

static dvec3 to_dvec3(vec3 v) { return dvec3_make(v.x, v.y, v.z); }

/* Per unit intensity, at p on a surface facing n. */
static double point_light_irradiance(const scene_light *l, dvec3 p, dvec3 n)
{
    dvec3 to_light = dvec3_sub(to_dvec3(l->position), p);
    double distance = dvec3_length(to_light);
    double geometric = irradiance_point_light(1.0, distance, dvec3_dot(n, to_light) / distance);
    printf("  line %d, point light: E = I cos(theta) / d^2 = %.12g x I (d = %g; a delta light, no integral)\n",
           l->line, geometric, distance);
    return geometric;
}

/* Per unit radiance, at p on a surface facing n: the area integral, and
 * Lambert's formula where it applies (the whole light above the surface's
 * horizon), which must agree with it (*ok). */
static double area_light_irradiance(const scene_light *l, dvec3 p, dvec3 n, bool *ok)
{
    dvec3 c[4];
    int above = 0;
    for (int k = 0; k < 4; k++) {
        c[k] = to_dvec3(l->corners[k]);
        above += dvec3_dot(n, dvec3_sub(c[k], p)) > 0.0;
    }
    dvec3 light_normal = dvec3_cross(dvec3_sub(c[1], c[0]), dvec3_sub(c[2], c[0]));
    if (dvec3_dot(light_normal, dvec3_sub(p, c[0])) <= 0.0) {
        printf("  line %d, area light: the point is behind it (lights emit from their front): E = 0\n", l->line);
        return 0.0;
    }
    quadrature_result q1 = irradiance_from_triangle_area(1.0, c[0], c[1], c[2], p, n, 3, TRIANGLE_N);
    quadrature_result q2 = irradiance_from_triangle_area(1.0, c[0], c[2], c[3], p, n, 3, TRIANGLE_N);
    double numeric = q1.value + q2.value, estimate = q1.error_estimate + q2.error_estimate;
    if (above < 4) {
        printf("  line %d, area light: straddles the surface's horizon, so Lambert's formula does not "
               "apply; area integral %.12g x L (estimate %.1e)\n", l->line, numeric, estimate);
        return numeric;
    }
    double closed = irradiance_polygon(1.0, c, 4, p, n);
    bool agrees = fabs(numeric - closed) <= estimate + AGREEMENT_ROUNDING_FLOOR * fabs(closed);
    *ok &= agrees;
    printf("  line %d, area light: Lambert's formula %.12g x L, area integral %.12g "
           "(estimate %.1e): %s\n", l->line, closed, numeric, estimate, agrees ? "agrees" : "NO");
    return closed;
}

bool radiometry_scene_irradiance(const scene_desc *d, const char *program)
{
    if (!d->has_camera) {
        fprintf(stderr, "%s: %s: no camera: the irradiance is computed at the camera's target\n", program, d->source);
        return false;
    }
    dvec3 p = to_dvec3(d->target);
    dvec3 n = dvec3_normalize(dvec3_sub(to_dvec3(d->eye), p));
    printf("%s: irradiance at the camera's target (%g, %g, %g), on a surface facing the eye, from each light of\n"
           "%s (no occlusion: radiometry only). Per unit radiance or intensity, then per RGB channel.\n",
           program, p.x, p.y, p.z, d->source);
    bool ok = true;
    dvec3 total = dvec3_make(0, 0, 0);
    for (int i = 0; i < d->light_count; i++) {
        const scene_light *l = &d->lights[i];
        bool point = l->kind == SCENE_LIGHT_POINT;
        double geometric = point ? point_light_irradiance(l, p, n) : area_light_irradiance(l, p, n, &ok);
        dvec3 colour = to_dvec3(point ? l->intensity : l->emission);
        dvec3 e = dvec3_make(geometric * colour.x, geometric * colour.y, geometric * colour.z);
        total = dvec3_add(total, e);
        printf("      E = (%.6g, %.6g, %.6g)\n", e.x, e.y, e.z);
    }
    if (d->light_count == 0)
        printf("  the scene has no point or area light (emissive shapes are not counted here)\n");
    printf("  total E = (%.6g, %.6g, %.6g); a white Lambertian surface there reflects L = E / pi = (%.6g, %.6g, "
           "%.6g)\n", total.x, total.y, total.z, total.x / PI, total.y / PI, total.z / PI);
    if (d->shape_count > 0 || d->material_count > 0)
        printf("  (shapes and materials are not used: chapter 07 computes radiometric quantities, it renders nothing)\n");
    return ok;
}
