/* bsdf.h -- how surfaces scatter light (the BRDF of lecture 15, and glass).
 *
 * All directions point away from the surface: wo towards the viewer (where
 * the light goes), wi towards where it comes from. n is the shading normal
 * on the side of wo. Each material offers
 *
 *   bsdf_eval(m, n, wo, wi)      f(wo, wi), without the cosine
 *   bsdf_pdf(m, n, wo, wi)       the density bsdf_sample would pick wi with
 *   bsdf_sample(m, n, wo, u, ..) a direction wi, and f cos / pdf for it
 *
 * Smooth glass and mirrors scatter into single directions (delta
 * distributions): their eval and pdf are 0 for every wi one could name, and
 * only bsdf_sample finds the direction, flagged `is_delta`.
 */
#ifndef BSDF_H
#define BSDF_H

#include <stdbool.h>

#include "08-monte-carlo/sampling.h"
#include "09-path-tracing/scene_pt.h"

typedef struct {
    vec3 wi;
    vec3 weight;   /* f cos(theta_i) / pdf: what the path's throughput is multiplied by */
    float pdf;     /* per unit solid angle; for a delta lobe, the probability of the lobe */
    bool is_delta;
    bool is_transmission;
} bsdf_sample_result;

vec3 bsdf_eval(const pt_material *m, vec3 n, vec3 wo, vec3 wi);
float bsdf_pdf(const pt_material *m, vec3 n, vec3 wo, vec3 wi);
/* u: two uniform numbers for the direction, u_lobe one to choose between
 * reflection and refraction. False if no direction can be sampled. */
bool bsdf_sample(const pt_material *m, vec3 n, vec3 wo, vec2 u, float u_lobe, bool entering, bsdf_sample_result *out);
/* Does this material scatter only into single directions? */
bool bsdf_is_delta(const pt_material *m);

/* Whether bsdf.c's table has the code of kind k (a test holds every kind to it). */
bool bsdf_kind_implemented(bsdf_kind k);
/* The BSDF that is the scene file's kind scene_kind, if one is (false for
 * blinn_phong and emissive, which scene_pt_file.c renders as diffuse). */
bool bsdf_kind_of_scene_kind(scene_material_kind scene_kind, bsdf_kind *out);
/* A scene file's material of BSDF kind k, as the path tracer's. */
pt_material bsdf_material_from_scene(bsdf_kind k, const scene_material *sm);

/* GGX (Trowbridge-Reitz) normal distribution D(h) for cos(theta_h), and
 * Smith's masking G1 for a direction at cos(theta): exposed for the tests. */
float ggx_distribution(float cos_theta_h, float alpha);
float ggx_smith_g1(float cos_theta, float alpha);

/* A direction in the frame around n from local (x, y, z) coordinates. */
vec3 frame_to_world(vec3 n, vec3 local);

#endif
