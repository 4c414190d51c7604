/* distribution.h -- distribution ray tracing (Cook, Porter and Carpenter,
 * "Distributed Ray Tracing", SIGGRAPH 1984): chapter 02's recursion, with
 * each ray replaced by several spread over the dimension it integrates.
 *
 *   pixel area   stratified ("jittered") positions      render.h's stratify
 *   lens         a point on the thin lens's disk           thin_lens_ray()
 *   time         an instant in the shutter interval        timed_ray
 *   light area   N_light shadow rays to points on the light (soft shadows)
 *   reflection   N_glossy rays from the GGX lobe, each recursing (glossy)
 *
 * Mirrors and glass branch as in chapter 02 (reflection, and refraction
 * weighted by Fresnel). Diffuse surfaces take direct light only: light
 * that bounces off a diffuse surface and on is what distribution ray
 * tracing leaves out, and the path tracer of chapter 09 puts in.
 *
 * Usage:
 *   distribution_tracer dt = distribution_tracer_defaults(&scene, &cam);
 *   dt.glossy_samples = 4;
 *   render_job job = {..., .radiance = distribution_radiance, .scene = &dt, .stratify = true};
 *
 * Rays by kind (ray_counters): glossy rays are counted as indirect_rays
 * (rays sampled from a non-delta lobe, as chapter 09 counts them; here only
 * glossy surfaces spawn any), mirror and glass reflections as
 * reflection_rays, refractions as refraction_rays.
 */
#ifndef DISTRIBUTION_H
#define DISTRIBUTION_H

#include "10-distribution/motion_scene.h"
#include "08-monte-carlo/sampling.h"
#include "rng.h"

/* The thin lens: rays leave a disk of radius aperture_radius around the
 * eye, in the camera's right-up plane, and those through one pixel meet
 * again on the plane of focus, focus_distance in front of the eye (along
 * the view direction), where the pinhole ray through that pixel meets it.
 * aperture_radius 0 is the pinhole camera. */
typedef struct {
    vec3 eye, right, up, forward;
    float aperture_radius, focus_distance;
} thin_lens;

thin_lens thin_lens_make(const camera *cam, float aperture_radius, float focus_distance);
/* The lens ray for the pinhole ray through the same pixel position, with
 * u in [0,1)^2 picking the point on the lens (concentric disk map). With
 * aperture 0 the pinhole ray itself, bit for bit. */
ray thin_lens_ray(const thin_lens *lens, ray pinhole, vec2 u);
/* The diameter of the circle of confusion, measured on the plane of focus,
 * of a point at `distance` along the view direction:
 * 2 a |distance - focus| / distance. */
float thin_lens_confusion_diameter(const thin_lens *lens, float distance);

typedef struct {
    const motion_scene *scene;
    thin_lens lens;
    int light_samples;  /* N_light: shadow rays to each area light sample set per hit */
    int glossy_samples; /* N_glossy: rays from the GGX lobe per glossy hit (0: highlights only) */
    /* Light that bounced more than max_depth times is not counted (as in
     * chapter 09): a glossy or mirror chain is cut there. */
    int max_depth;
    bool motion;        /* false: the shutter instant is always 0 (a still) */
    unsigned effects;   /* EFFECT_* of scene_file.h; EFFECT_INDIRECT is never simulated */
} distribution_tracer;

distribution_tracer distribution_tracer_defaults(const motion_scene *scene, const camera *cam);

/* render.h's radiance_fn; ctx points to a distribution_tracer. Draws the
 * lens point (2 numbers) and the shutter instant (1) from rng, always, so
 * that the random streams are the same with or without lens and motion. */
vec3 distribution_radiance(const void *ctx, ray pinhole, pcg32 *rng, ray_counters *counters);

/* The rays one camera ray spawns at most, of each kind, when every hit is
 * glossy (the worst case): sum over depths of N_glossy^d. For the text and
 * the counter tests. */
double distribution_glossy_rays_per_camera_ray(int glossy_samples, int max_depth);

#endif
