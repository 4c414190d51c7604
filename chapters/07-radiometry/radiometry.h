/* radiometry.h -- lectures 14-15 as numbers: solid angle, radiant flux and
 * intensity, irradiance, radiance, the BRDF, the reflection equation and the
 * rendering equation in operator form, L = E + K L.
 *
 * Every quantity comes twice: as its closed form (a plain function of a few
 * numbers) and as the integral that defines it, computed by deterministic
 * quadrature (quadrature.h) with an error estimate, so that the two can be
 * compared. Units: flux in W, intensity in W/sr, irradiance in W/m^2,
 * radiance in W/(m^2 sr); lengths in any unit as long as it is the same one.
 *
 * Usage:
 *   double exact = irradiance_disk_on_axis(L, R, h);
 *   quadrature_result q = irradiance_from_cone(L, up, up, atan(R / h), QUADRATURE_GAUSS_LEGENDRE, 32);
 *   // q.value agrees with exact within q.error_estimate
 *
 *   brdf f = brdf_blinn_phong(0.5, 2.0, 32.0);
 *   quadrature_result a = brdf_albedo(&f, theta_o, 64);   // a.value > 1: gains energy
 *
 * Directions point away from the surface (the lecture's omega_i and omega_r
 * both start at the shading point). BRDFs work in a local frame with the
 * normal along +z, so cos theta = w.z.
 */
#ifndef RADIOMETRY_H
#define RADIOMETRY_H

#include <stdbool.h>

#include "07-radiometry/quadrature.h"

/* ---- Solid angle ---------------------------------------------------------- */

/* A cone of half-angle alpha: integral_0^{2 pi} integral_0^alpha sin theta
 * d theta d phi = 2 pi (1 - cos alpha). alpha = pi/2: a hemisphere (2 pi);
 * alpha = pi: the whole sphere (4 pi). */
double solid_angle_cone(double alpha);

/* A sphere of radius r whose centre is at distance d > r: the cone of
 * half-angle asin(r / d) that just touches it, 2 pi (1 - sqrt(1 - (r/d)^2)). */
double solid_angle_sphere(double r, double d);

/* The triangle (a, b, c) seen from p, by Van Oosterom and Strackee (1983):
 * with A = a - p, B = b - p, C = c - p and their lengths |A|, |B|, |C|,
 *
 *   tan(Omega / 2) = A . (B x C) / (|A||B||C| + (A.B)|C| + (A.C)|B| + (B.C)|A|)
 *
 * taken with atan2, so a triangle covering more than a quarter of the sphere
 * of directions (Omega > pi: the denominator is negative) comes out right.
 * Unsigned, in [0, 2 pi]. */
double solid_angle_triangle(dvec3 p, dvec3 a, dvec3 b, dvec3 c);
/* The same with the sign of the triple product A . (B x C): positive when p
 * is behind the triangle (its normal (b - a) x (c - a) points away from p).
 * Summed over a closed mesh with outward normals: 4 pi from inside, 0 from
 * outside. */
double solid_angle_triangle_signed(dvec3 p, dvec3 a, dvec3 b, dvec3 c);
/* The formula as often written, 2 atan(num / den): wrong (negative) for
 * Omega > pi, and for den = 0. Kept to show the failure; do not use. */
double solid_angle_triangle_naive(dvec3 p, dvec3 a, dvec3 b, dvec3 c);
/* By its definition: the integral over the triangle's area of
 * cos theta' / r^2 dA (theta' between the triangle's normal and the line to p). */
quadrature_result solid_angle_triangle_numeric(dvec3 p, dvec3 a, dvec3 b, dvec3 c, int level, int n);

/* ---- Radiant flux and intensity ------------------------------------------- */

/* An isotropic point light of flux Phi: I = Phi / (4 pi) in every direction. */
double intensity_isotropic_point(double flux);
/* A flat Lambertian emitter (constant radiance L, area A): Lambert's cosine
 * law for emitters, I(theta) = L A cos theta (0 behind it), and its flux,
 * the integral of I over the hemisphere, Phi = pi L A. */
double intensity_lambertian_emitter(double L, double area, double cos_theta);
double flux_lambertian_emitter(double L, double area);
quadrature_result flux_lambertian_emitter_numeric(double L, double area, int n);
/* A spherical emitter of radius r and radiance L looks like a disk of area
 * pi r^2 from every direction: I = pi r^2 L, Phi = 4 pi I. */
double intensity_sphere_emitter(double L, double r);
/* By its definition: the integral over the sphere's visible half of
 * L cos theta dA, with a point c + r n on the sphere and dA = r^2 d omega(n). */
quadrature_result intensity_sphere_emitter_numeric(double L, double r, int n);

/* ---- Irradiance: E = integral of L_i(w) cos theta d omega ----------------- */

/* A uniform sky of radiance L over the whole hemisphere: E = pi L. */
double irradiance_uniform_sky(double L);
/* On the axis of a disk light (radius R, radiance L) at height h, facing it:
 * E = pi L sin^2 alpha = pi L R^2 / (R^2 + h^2). */
double irradiance_disk_on_axis(double L, double R, double h);
/* A sphere light (radius r, radiance L) whose centre is at distance d, at
 * angle theta from the normal: E = pi L (r/d)^2 cos theta, exactly, as long
 * as the whole sphere is above the horizon (cos theta >= r/d); 0 when it is
 * wholly below (cos theta <= -r/d). In between the sphere straddles the
 * horizon and this returns NaN: integrate it with irradiance_from_cone. */
double irradiance_sphere_light(double L, double r, double d, double cos_theta);
/* A point light of intensity I at distance d, at angle theta from the normal:
 * E = I max(0, cos theta) / d^2 (Lambert's cosine law and the inverse square
 * law; 0 for a light behind the surface). */
double irradiance_point_light(double I, double d, double cos_theta);
/* A polygonal light of radiance L, entirely above the plane through p with
 * normal n (Lambert 1760): with u_i the unit vectors from p to the vertices,
 *   E = (L/2) | sum_i angle(u_i, u_{i+1}) n . unit(u_i x u_{i+1}) |. */
double irradiance_polygon(double L, const dvec3 *vertices, int count, dvec3 p, dvec3 n);

/* Solid-angle form: a light of uniform radiance L filling the cone of
 * half-angle alpha around unit `axis`, seen from a point with unit normal n:
 * E = integral over the cone of L max(0, n . w) d omega. */
quadrature_result irradiance_from_cone(double L, dvec3 n, dvec3 axis, double alpha, quadrature_rule rule,
                                       int quadrature_n);
/* Area form: d omega = cos theta' dA / r^2, so
 * E = integral over the light of L cos theta cos theta' / r^2 dA, with the
 * receiver's cos theta clamped at 0. The lights emit from both faces. */
quadrature_result irradiance_from_disk_area(double L, dvec3 centre, dvec3 disk_normal, double radius, dvec3 p,
                                            dvec3 n, quadrature_rule rule, int quadrature_n);
quadrature_result irradiance_from_triangle_area(double L, dvec3 a, dvec3 b, dvec3 c, dvec3 p, dvec3 n, int level,
                                                int quadrature_n);

/* ---- The BRDF ------------------------------------------------------------- */

typedef enum {
    BRDF_LAMBERTIAN,           /* rho / pi */
    BRDF_BLINN_PHONG,          /* kd / pi + ks (n.h)^p */
    BRDF_BLINN_PHONG_AS_SHADED,/* chapter 01's shading formula read as a BRDF: kd + ks (n.h)^p / cos theta_i */
    BRDF_GLOSSY_MIRROR         /* rho (p + 2) / (2 pi) max(0, r.w_i)^p: a lobe around the mirror direction r */
} brdf_kind;

typedef struct {
    brdf_kind kind;
    double kd;        /* diffuse coefficient (rho for the Lambertian and the glossy mirror) */
    double ks;        /* specular coefficient */
    double shininess; /* the exponent p */
} brdf;

brdf brdf_lambertian(double rho);
brdf brdf_blinn_phong(double kd, double ks, double shininess);
brdf brdf_blinn_phong_as_shaded(double kd, double ks, double shininess);
brdf brdf_glossy_mirror(double rho, double shininess);
/* A short name for tables, e.g. "Blinn-Phong kd=0.5 ks=2 p=32" (buffer of `size`). */
void brdf_describe(const brdf *f, char *text, int size);

/* f_r(w_i -> w_o) in the local frame (normal +z); 0 when either direction is
 * below the horizon. */
double brdf_eval(const brdf *f, dvec3 wi, dvec3 wo);

/* The unit direction at polar angle theta in the xz-plane: (sin theta, 0, cos theta). */
dvec3 direction_at_polar_angle(double theta);

/* Energy check: the directional albedo, the fraction of light arriving
 * uniformly from all directions that leaves towards w_o (theta_o from the
 * normal): integral over the hemisphere of f(w_i, w_o) cos theta_i d w_i.
 * At most 1 for a BRDF that conserves energy. n: Gauss-Legendre points in
 * theta_i (2n in phi_i), doubled once for the error estimate. */
quadrature_result brdf_albedo(const brdf *f, double theta_o, int n);
/* The classic mistake: the same integral without cos theta_i. A Lambertian
 * BRDF then has "albedo" 2 rho. Kept to show that the tests catch it. */
quadrature_result brdf_albedo_without_cosine(const brdf *f, double theta_o, int n);
/* Closed forms of the albedo at normal viewing (theta_o = 0):
 * Blinn-Phong: kd + 8 pi ks [ 2 (1 - 2^-(p+4)/2) / (p+4) - (1 - 2^-(p+2)/2) / (p+2) ];
 * glossy mirror: rho; Lambertian: rho. */
double brdf_albedo_at_normal(const brdf *f);

typedef struct {
    double worst_albedo;  /* the largest albedo found */
    double worst_theta_o; /* where */
    double worst_error;   /* its error estimate */
    bool conserves_energy;/* worst_albedo <= 1 + worst_error */
} energy_check;

/* brdf_albedo at `angles` viewing angles theta_o evenly spread over
 * [0, pi/2) (the midpoints of equal cells), the largest reported. */
energy_check brdf_check_energy(const brdf *f, int angles, int n);

/* ---- The reflection equation ---------------------------------------------- */

/* L_r(w_r) = integral over the hemisphere of f_r(w_i -> w_r) L_i(w_i) cos theta_i d w_i,
 * with the incident radiance L_i(ctx, w_i) given in the local frame. */
quadrature_result reflected_radiance(const brdf *f, direction_fn incident, const void *ctx, dvec3 wr, int n);

/* ---- The rendering equation: L = E + K L ---------------------------------- */

/* The closed furnace: inside a closed sphere whose surface everywhere emits
 * Le and reflects diffusely with albedo rho, every point sees the same
 * radiance in every direction. Bounce k (light that has reflected k times)
 * contributes Le rho^k; the sum of the series is L = Le / (1 - rho). */
double furnace_bounce(double Le, double rho, int k);
/* E + K E + ... + K^k E, added bounce by bounce. */
double furnace_partial_sum(double Le, double rho, int k);
/* The same in closed form: Le (1 - rho^(k+1)) / (1 - rho) (Le (k+1) for rho = 1). */
double furnace_partial_sum_closed(double Le, double rho, int k);
/* The limit, Le / (1 - rho), for rho < 1. */
double furnace_radiance(double Le, double rho);
/* One application of L -> E + K L for a uniform field, K by the reflection
 * equation with a Lambertian BRDF, integrated by quadrature (n points). */
quadrature_result furnace_step_quadrature(double Le, double rho, double L, int n);

/* The furnace discretized: the sphere's surface cut into rings x segments
 * patches (equal steps in theta and phi). The form factor from a point x to
 * a small area dA at y, cos theta_x cos theta_y / (pi r^2) dA, is
 * dA / (4 pi R^2) for any two points of a sphere (both cosines are
 * r / (2R)), so F_ij = A_j / (4 pi R^2) for every pair, i = j included. */
typedef struct {
    double radius;
    int rings, segments, count;
    double *area;        /* count patch areas, in closed form R^2 dphi (cos theta0 - cos theta1) */
    dvec3 *centre;       /* count patch centres (mid theta, mid phi), on the sphere */
    double *form_factor; /* count x count, row i: F_ij */
} sphere_patches;

void sphere_patches_build(sphere_patches *s, double radius, int rings, int segments);
void sphere_patches_free(sphere_patches *s);
/* The form factor kernel between points x and y with unit normals nx, ny:
 * max(0, cos theta_x) max(0, cos theta_y) / (pi r^2). */
double form_factor_kernel(dvec3 x, dvec3 nx, dvec3 y, dvec3 ny);
/* The rendering equation discretized: out_i = E_i + rho sum_j F_ij L_j. */
void rendering_operator_apply(const sphere_patches *s, double rho, const double *E, const double *L, double *out);

#endif
