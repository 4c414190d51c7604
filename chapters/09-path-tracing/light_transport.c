/* light_transport.c -- a vertex's light transport, tracing nothing
 * (light_transport.h). */
#include "09-path-tracing/light_transport.h"

#include "09-path-tracing/bsdf.h"

/* The direction from p to a point on a light, and the geometry between
 * them: wi, |x' - p|^2 and cos(theta) at p (against the shading normal). */
static vec3 towards(const hit_record *p, vec3 target, light_contribution *out)
{
    vec3 to_light = vec3_sub(target, p->point);
    out->distance2 = vec3_length_squared(to_light);
    vec3 wi = vec3_scale(to_light, 1.0f / sqrtf(out->distance2));
    out->cos_theta = vec3_dot(p->normal_shading, wi);
    return wi;
}

/* A density per unit area at a point of a light, per steradian as seen
 * from a point |x' - p|^2 away at the angle theta' to the light's normal. */
static float pdf_area_to_solid_angle(float pdf_area, float distance2, float cos_theta_light)
{
    return distance2 * pdf_area / cos_theta_light;
}

/* ---- the lecture's light sample, in the area form ---------------------------
 *   L_dir = L_i f_r cos(theta) cos(theta') / |x' - p|^2 / pdf_light
 * with theta at p and theta' at x', each against its normal. */
light_contribution direct_light_area(const pt_material *m, const hit_record *p, vec3 wo, const pt_light_sample *x)
{
    /* exercise: light_sample */
    light_contribution l = {.radiance = vec3_splat(0.0f), .weight = 1.0f};
    vec3 ws = towards(p, x->point, &l);
    l.cos_theta_light = -vec3_dot(x->normal, ws);
    l.adds = l.cos_theta > 0.0f && l.cos_theta_light > 0.0f;
    if (!l.adds)
        return l;
    l.radiance = vec3_scale(vec3_mul(x->emission, bsdf_eval(m, p->normal_shading, wo, ws)),
                            l.cos_theta * l.cos_theta_light / l.distance2 / x->pdf_light);
    /* the shadow ray: from p to x', stopping short of both surfaces */
    l.shadow = ray_spawn_to(p->point, p->point_error, p->normal_geometric, x->point, x->point_error, x->normal);
    return l;
    /* end of exercise light_sample */
}

/* ---- the later rungs' light sample, in the solid-angle form -------------------
 *   L_dir = L_e f_r cos(theta) / pdf_light x weight,
 *   pdf_light = |x' - p|^2 pdf_area / cos(theta') per steradian. */
light_contribution direct_light_solid_angle(const pt_material *m, const hit_record *p, vec3 wo,
                                            const pt_light_sample *x, int light_samples, int bsdf_samples)
{
    light_contribution l = {.radiance = vec3_splat(0.0f), .weight = 1.0f};
    vec3 n = p->normal_shading;
    vec3 wi = towards(p, x->point, &l);
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

/* ---- lights without area ----------------------------------------------------
 * A point light: L_dir = f_r I cos(theta) / r^2. Nothing to stop short of
 * at the light: its error bound and normal are 0. */
light_contribution direct_light_point(const pt_material *m, const hit_record *p, vec3 wo, const pt_point_light *light)
{
    light_contribution l = {.radiance = vec3_splat(0.0f), .weight = 1.0f};
    vec3 wi = towards(p, light->position, &l);
    vec3 f = l.cos_theta > 0.0f ? bsdf_eval(m, p->normal_shading, wo, wi) : vec3_splat(0.0f);
    l.adds = !vec3_is_black(f);
    if (!l.adds)
        return l;
    l.radiance = vec3_scale(vec3_mul(f, light->intensity), l.cos_theta / l.distance2);
    l.shadow = ray_spawn_to(p->point, p->point_error, p->normal_geometric, light->position, 0.0f, vec3_splat(0.0f));
    return l;
}

vec3 bounce_weight(const pt_material *m, vec3 n, vec3 wo, vec3 wi, float cos_theta, float pdf)
{
    return vec3_scale(bsdf_eval(m, n, wo, wi), cos_theta / pdf);
}

float power_heuristic(float a, float b)
{
    float a2 = a * a, b2 = b * b;
    return a2 + b2 > 0.0f ? a2 / (a2 + b2) : 0.0f;
}

float light_pdf_from(vec3 from, vec3 point, vec3 normal, vec3 wo, float pdf_area)
{
    return pdf_area_to_solid_angle(pdf_area, vec3_length_squared(vec3_sub(point, from)), fabsf(vec3_dot(normal, wo)));
}
