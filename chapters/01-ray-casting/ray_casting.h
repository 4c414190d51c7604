/* ray_casting.h -- lecture 13's ray casting: one eye ray per pixel, the
 * closest hit, a shadow ray to each light, Blinn-Phong shading.
 *
 * Usage: render_job job = {..., .radiance = ray_cast_radiance, .scene = &sc};
 */
#ifndef RAY_CASTING_H
#define RAY_CASTING_H

#include "01-ray-casting/scene.h"
#include "rng.h"

/* Blinn-Phong at a hit seen from direction `to_viewer` (unit, pointing away
 * from the surface), with a shadow ray to each light:
 *   L = k_a I_a + sum over visible lights of
 *       k_d (I / r^2) max(0, n.l) + k_s (I / r^2) max(0, n.h)^p,   h = unit(l + v)
 */
vec3 blinn_phong_shade(const scene *sc, const hit_record *hit, vec3 to_viewer, ray_counters *counters);

/* The same, with --explain lines indented at `depth` (chapter 02 calls it
 * deep in its recursion). */
vec3 blinn_phong_shade_at(const scene *sc, const hit_record *hit, vec3 to_viewer, int depth, ray_counters *counters);
/* One --explain line for a hit: shape, material, t, point, normal. */
void explain_hit(const scene *sc, const hit_record *hit, int depth);

/* Is the light at `light_position` visible from the hit point? Traces one
 * shadow ray (and counts it), unless the scene's effects say no light can
 * be blocked. */
bool light_visible(const scene *sc, const hit_record *hit, vec3 light_position, ray_counters *counters);

/* The integrator of chapter 01 (render.h's radiance_fn): the background if
 * the ray hits nothing, else Blinn-Phong at the closest hit. Mirrors and
 * glass are shaded as plain Blinn-Phong surfaces here: following their rays
 * is chapter 02. */
vec3 ray_cast_radiance(const void *scene, ray r, pcg32 *rng, ray_counters *counters);

/* The built-in scene of chapter 01: a sphere, a triangle and a torus on a
 * checkerboard plane under two point lights. */
void scene_build_ray_casting_demo(scene *sc);

#endif
