/* whitted.h -- lecture 13's Whitted-style ray tracing: ray casting plus
 * recursion. At a mirror the ray reflects and is traced again; at glass it
 * splits into a reflected and a refracted ray, weighted by Fresnel; at a
 * diffuse surface it stops, with a shadow ray to each light (chapter 01).
 *
 * Usage:
 *   scene sc; scene_build_whitted_demo(&sc);
 *   whitted_context ctx = {&sc, 5};
 *   render_job job = {..., .radiance = whitted_radiance, .scene = &ctx};
 *
 * or one ray by hand: vec3 L = whitted_trace(&sc, r, 0, 5, &counters);
 */
#ifndef WHITTED_H
#define WHITTED_H

#include <stdbool.h>

#include "01-ray-casting/scene.h"
#include "rng.h"

/* Snell's law in vector form. d: unit incident direction; n: unit normal on
 * the incident side (n.d <= 0); eta_ratio = eta_i / eta_t. On success *out is
 * the unit refracted direction and the result is true; on total internal
 * reflection the result is false and *out is left alone. */
bool refract_direction(vec3 d, vec3 n, float eta_ratio, vec3 *out);

/* The exact Fresnel reflectance of a smooth dielectric boundary for
 * unpolarised light: R = (r_s^2 + r_p^2) / 2. eta_i is the index on the side
 * the light comes from, eta_t the other side's; cos_i is the cosine of the
 * angle of incidence measured from the normal that points into eta_i. A
 * negative cos_i means the light actually arrives from the eta_t side: the
 * two indices are swapped and |cos_i| is used. Returns 1 on total internal
 * reflection. The transmitted fraction is 1 - R. */
float fresnel_dielectric(float cos_i, float eta_i, float eta_t);

/* Schlick's approximation of the same R, with the same arguments:
 * R0 + (1 - R0) (1 - cos)^5, R0 = ((eta_i - eta_t) / (eta_i + eta_t))^2,
 * where cos is taken on the side with the lower index. See whitted.c for
 * its error. */
float fresnel_schlick(float cos_i, float eta_i, float eta_t);

/* The Whitted integrator: the radiance arriving along r. depth counts the
 * bounces that led to r (0 for a camera ray); at most max_depth reflected or
 * refracted rays are followed in a row, and a ray beyond that returns black. */
vec3 whitted_trace(const scene *sc, ray r, int depth, int max_depth, ray_counters *counters);

/* What whitted_radiance needs: the scene and the depth limit. */
typedef struct {
    const scene *sc;
    int max_depth;
} whitted_context;

/* render.h's radiance_fn: ctx points to a whitted_context. Deterministic:
 * rng is not used. */
vec3 whitted_radiance(const void *ctx, ray r, pcg32 *rng, ray_counters *counters);

/* The chapter's scene, after GAMES101 assignment 5: a diffuse sphere, a
 * glass sphere (ior 1.5) and a mirror sphere on a checkerboard floor, two
 * point lights, a sky-blue background. Sets sc->camera. */
void scene_build_whitted_demo(scene *sc);

#endif
