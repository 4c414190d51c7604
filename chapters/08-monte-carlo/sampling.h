/* sampling.h -- turning uniform random numbers into samples of the shapes a
 * renderer integrates over (lecture 16). Every distribution comes as a triad:
 *
 *   sample_X(u, ...)   a point of X, from a uniform sample u in [0,1)^2
 *   X_pdf(...)         its probability density (per unit solid angle for
 *                      directions, per unit area for points)
 *   invert_X(p, ...)   the u that sample_X maps to p (where the map is a
 *                      bijection): sample_X(invert_X(p)) == p
 *
 * Usage (a diffuse bounce in a path tracer, chapter 09):
 *   vec3 t, b;  vec3_basis(n, &t, &b);
 *   float u1 = pcg32_float(&rng), u2 = pcg32_float(&rng);  (two statements' worth: in this order)
 *   vec3 local = sample_cosine_hemisphere(vec2_make(u1, u2));
 *   vec3 wi = vec3_add(vec3_add(vec3_scale(t, local.x), vec3_scale(b, local.y)), vec3_scale(n, local.z));
 *   float pdf = cosine_hemisphere_pdf(local.z);
 *
 * Directions are in a local frame with z up (the surface normal, or the axis
 * of a cone). Each routine takes the two numbers as a vec2 rather than a
 * generator, so stratified or low-discrepancy points (estimators.h) plug in
 * where random ones would.
 *
 * Float, like the rest of the geometry. The 1D tabulated distribution at the
 * end is double: it importance-samples the chapter's 1D integrals, whose
 * errors (down to ~1e-8) are below float's resolution.
 */
#ifndef SAMPLING_H
#define SAMPLING_H

#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "vec3.h"

typedef struct {
    float x, y;
} vec2;

static inline vec2 vec2_make(float x, float y) { return (vec2){x, y}; }

/* ---- an angle given in turns ---------------------------------------------
 * sin and cos of 2 pi u, for u in [0, 1]: the azimuth phi = 2 pi u of every
 * warp below, as the lecture writes it, with libm's sinf and cosf. */
static inline void sincos_turns(float u, float *sin_out, float *cos_out)
{
    float phi = (float)(2.0 * PI) * u;
    *sin_out = sinf(phi);
    *cos_out = cosf(phi);
}

/* ---- hemisphere, uniform: p(w) = 1 / (2 pi) ------------------------------ */
vec3 sample_uniform_hemisphere(vec2 u);
float uniform_hemisphere_pdf(void);
vec2 invert_uniform_hemisphere(vec3 w);

/* ---- hemisphere, cosine-weighted: p(w) = cos(theta) / pi ----------------- */
/* Malley's method: a uniform point on the unit disk (concentric map), lifted
 * straight up onto the hemisphere. */
vec3 sample_cosine_hemisphere(vec2 u);
float cosine_hemisphere_pdf(float cos_theta);
vec2 invert_cosine_hemisphere(vec3 w);

/* ---- sphere, uniform: p(w) = 1 / (4 pi) ---------------------------------- */
vec3 sample_uniform_sphere(vec2 u);
float uniform_sphere_pdf(void);
vec2 invert_uniform_sphere(vec3 w);

/* ---- unit disk, uniform: p(x, y) = 1 / pi -------------------------------- */
/* Two maps with the same density. Concentric (Shirley and Chiu 1997) sends
 * squares to rings of the disk with little distortion, so a stratified or
 * low-discrepancy set of u stays well spread on the disk; the cosine
 * hemisphere uses it. Polar (r = sqrt(u1), phi = 2 pi u2) is the one the
 * inversion method derives first; it stretches the square's cells into thin
 * wedges near the centre. */
vec2 sample_uniform_disk_concentric(vec2 u);
vec2 invert_uniform_disk_concentric(vec2 p);
vec2 sample_uniform_disk_polar(vec2 u);
vec2 invert_uniform_disk_polar(vec2 p);
float uniform_disk_pdf(void);

/* ---- triangle, uniform: p = 1 / area ------------------------------------- */
/* Returns barycentrics (b0, b1, b2) in x, y, z; the point is
 * b0 p0 + b1 p1 + b2 p2 (triangle_point). Warp: b0 = 1 - sqrt(u1),
 * b1 = u2 sqrt(u1). */
vec3 sample_uniform_triangle(vec2 u);
float uniform_triangle_pdf(vec3 p0, vec3 p1, vec3 p2);
vec2 invert_uniform_triangle(vec3 barycentrics);
float triangle_area(vec3 p0, vec3 p1, vec3 p2);
vec3 triangle_point(vec3 p0, vec3 p1, vec3 p2, vec3 barycentrics);

/* ---- cone about z, uniform: p(w) = 1 / (2 pi (1 - cos_theta_max)) -------- */
/* All directions within theta_max of the axis: what a spherical light
 * subtends seen from outside it (chapter 09). cos_theta_max in [-1, 1). */
vec3 sample_uniform_cone(vec2 u, float cos_theta_max);
float uniform_cone_pdf(float cos_theta_max);
vec2 invert_uniform_cone(vec3 w, float cos_theta_max);

/* ---- 1D, piecewise constant (tabulated) ---------------------------------- */
/* A density proportional to a table of n non-negative values over [min, max]
 * (n equal bins). It importance-samples any 1D function that the table
 * follows roughly; it must be positive wherever the function is, or the
 * estimator loses that part of the integral (see the chapter text).
 *
 *   piecewise_constant_1d d;
 *   piecewise_constant_1d_init(&d, values, n, 0.0, 1.0);
 *   double pdf; double x = sample_piecewise_constant_1d(&d, u, &pdf);
 *   piecewise_constant_1d_free(&d);
 */
typedef struct {
    int count;
    double min, max;
    double *func;     /* count values, |f| (all 1 if the table was all zero) */
    double *cdf;      /* count + 1 values: cdf[0] = 0, cdf[count] = 1 */
    double integral;  /* integral of the step function over [min, max] */
} piecewise_constant_1d;

/* Returns false (and leaves d empty) if count < 1, min >= max, or a value is
 * negative, NaN or infinite. */
bool piecewise_constant_1d_init(piecewise_constant_1d *d, const double *values, int count, double min,
                                double max);
void piecewise_constant_1d_free(piecewise_constant_1d *d);
/* u in [0, 1): x in [min, max) with density pdf(x). Never lands in a zero bin. */
double sample_piecewise_constant_1d(const piecewise_constant_1d *d, double u, double *pdf);
double piecewise_constant_1d_pdf(const piecewise_constant_1d *d, double x);
double invert_piecewise_constant_1d(const piecewise_constant_1d *d, double x);

#endif
