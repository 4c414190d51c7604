/* light_transport.h -- the path tracer's light transport, in pieces that
 * trace nothing.
 *
 * What a vertex of a path adds and passes on is arithmetic on what the rays
 * found: a point x' on a light and the surface at p give the light sample's
 * contribution and the segment its shadow ray must test; a point light gives
 * the same; a direction wi drawn with density pdf gives the bounce's weight
 * f_r cos(theta) / pdf; two densities give the MIS weight. The integrators
 * trace the rays and call these: chapter 09's shade() and its later rungs,
 * chapter 10's distribution ray tracer, chapter 13's eight paths at a time
 * (whose AVX kernels are tested against them, value by value). So a change
 * of the physics is made once.
 *
 * Usage (the lecture's light sample):
 *   light_contribution l = direct_light_area(m, p, wo, &x);
 *   if (l.adds && !pt_scene_occluded(scene, l.shadow, counters))
 *       l_dir = vec3_add(l_dir, l.radiance);
 */
#ifndef LIGHT_TRANSPORT_H
#define LIGHT_TRANSPORT_H

#include <stdbool.h>

#include "09-path-tracing/bsdf.h"
#include "09-path-tracing/scene_pt.h"

/* What a light sample (or a point light) adds at p, if nothing blocks the
 * shadow ray. */
typedef struct {
    vec3 radiance; /* what it adds to the light reflected at p towards wo */
    /* The segment from p to the light its shadow ray must test (ray.h's
     * ray_spawn_to: off both surfaces by their error bounds); set only
     * where `adds`. */
    ray shadow;
    /* false: it adds nothing whatever the shadow ray would find (the light
     * faces away, lies below the surface, or f_r is 0), so no shadow ray */
    bool adds;
    /* the geometry, for --explain: cos(theta) at p, cos(theta') at the
     * light, |x' - p|^2; in the solid-angle form also pdf_light per
     * steradian and the MIS weight (1 without) */
    float cos_theta, cos_theta_light, distance2, pdf_light, weight;
} light_contribution;

/* The direction from p to a point on a light, and the geometry between
 * them: wi, |x' - p|^2 and cos(theta) at p (against the shading normal). */
static inline vec3 light_towards(const hit_record *p, vec3 target, light_contribution *out)
{
    vec3 to_light = vec3_sub(target, p->point);
    out->distance2 = vec3_length_squared(to_light);
    vec3 wi = vec3_scale(to_light, 1.0f / sqrtf(out->distance2));
    out->cos_theta = vec3_dot(p->normal_shading, wi);
    return wi;
}

/* A density per unit area at a point of a light, per steradian as seen
 * from a point |x' - p|^2 away at the angle theta' to the light's normal. */
static inline float pdf_area_to_solid_angle(float pdf_area, float distance2, float cos_theta_light)
{
    return distance2 * pdf_area / cos_theta_light;
}

/* The lecture's light sample, in the slide's area form: x' picked on the
 * lights with density x->pdf_light per unit area,
 *   L_dir = L_i f_r cos(theta) cos(theta') / |x' - p|^2 / pdf_light,
 * if the ray from p to x' is not blocked in the middle. It adds wherever
 * light and surface face each other (cos(theta) > 0, cos(theta') > 0). */
light_contribution direct_light_area(const pt_material *m, const hit_record *p, vec3 wo, const pt_light_sample *x);

/* The power heuristic (Veach 1997) with exponent 2: the MIS weight of a
 * sample drawn with density a, when density b could have drawn it too.
 * (With sample counts, a and b are each count x density.) */
static inline float power_heuristic(float a, float b)
{
    float a2 = a * a, b2 = b * b;
    return a2 + b2 > 0.0f ? a2 / (a2 + b2) : 0.0f;
}

/* The same light sample in the solid-angle form the later rungs use, so
 * that multiple importance sampling can weigh it against BSDF sampling:
 * pdf_light per steradian is |x' - p|^2 pdf_area / cos(theta'), and
 *   L_dir = L_e f_r cos(theta) / pdf_light x weight.
 * The weight is the power heuristic between light_samples samples of the
 * light and bsdf_samples of the BSDF (Veach's counts; chapter 09 draws one
 * of each); bsdf_samples 0: no BSDF sample could find the light, weight 1.
 * It adds where light and surface face each other and f_r is not 0. */
static inline light_contribution direct_light_solid_angle(const pt_material *m, const hit_record *p, vec3 wo,
                                                          const pt_light_sample *x, int light_samples, int bsdf_samples)
{
    light_contribution l = {.radiance = vec3_splat(0.0f), .weight = 1.0f};
    vec3 n = p->normal_shading;
    vec3 wi = light_towards(p, x->point, &l);
    l.cos_theta_light = -vec3_dot(x->normal, wi);
    /* A light seen from behind (one-sided) or below the surface adds
     * nothing: no shadow ray needed to know it. */
    vec3 f = l.cos_theta_light > 0.0f && l.cos_theta > 0.0f ? bsdf_eval(m, n, wo, wi) : vec3_splat(0.0f);
    l.adds = !vec3_is_black(f);
    if (!l.adds)
        return l;
    l.pdf_light = pdf_area_to_solid_angle(x->pdf_light, l.distance2, l.cos_theta_light);
    if (bsdf_samples > 0)
        l.weight = power_heuristic((float)light_samples * l.pdf_light, (float)bsdf_samples * bsdf_pdf(m, n, wo, wi));
    l.radiance = vec3_scale(vec3_mul(x->emission, f), l.cos_theta / l.pdf_light * l.weight);
    l.shadow = ray_spawn_to(p->point, p->point_error, p->normal_geometric, x->point, x->point_error, x->normal);
    return l;
}

/* A point light (a delta in position, so only light sampling finds it):
 *   L_dir = f_r I cos(theta) / r^2.
 * It adds where f_r cos(theta) is not 0. */
static inline light_contribution direct_light_point(const pt_material *m, const hit_record *p, vec3 wo, const pt_point_light *light)
{
    light_contribution l = {.radiance = vec3_splat(0.0f), .weight = 1.0f};
    vec3 wi = light_towards(p, light->position, &l);
    vec3 f = l.cos_theta > 0.0f ? bsdf_eval(m, p->normal_shading, wo, wi) : vec3_splat(0.0f);
    l.adds = !vec3_is_black(f);
    if (!l.adds)
        return l;
    l.radiance = vec3_scale(vec3_mul(f, light->intensity), l.cos_theta / l.distance2);
    l.shadow = ray_spawn_to(p->point, p->point_error, p->normal_geometric, light->position, 0.0f, vec3_splat(0.0f));
    return l;
}

/* The bounce's weight: f_r(wo, wi) cos(theta) / pdf, for a direction wi
 * drawn with density pdf (cos_theta = n . wi, the local z of the sample). */
static inline vec3 bounce_weight(const pt_material *m, vec3 n, vec3 wo, vec3 wi, float cos_theta, float pdf)
{
    return vec3_scale(bsdf_eval(m, n, wo, wi), cos_theta / pdf);
}

/* The density per steradian with which a light sample from `from` picks
 * `point` on an emitter of normal `normal` and density pdf_area per unit
 * area, seen along wo (from `point` back to `from`): |point - from|^2
 * pdf_area / |cos(theta')|. What the MIS weight of emission that a BSDF
 * sample found weighs against. */
static inline float light_pdf_from(vec3 from, vec3 point, vec3 normal, vec3 wo, float pdf_area)
{
    return pdf_area_to_solid_angle(pdf_area, vec3_length_squared(vec3_sub(point, from)), fabsf(vec3_dot(normal, wo)));
}

#endif
