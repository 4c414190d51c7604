/* bsdf.c -- Lambertian, GGX microfacet, smooth glass, mirror. */
#include "09-path-tracing/bsdf.h"

#include "02-whitted/whitted.h"

vec3 frame_to_world(vec3 n, vec3 local)
{
    vec3 t, b;
    vec3_basis(n, &t, &b);
    return vec3_add(vec3_add(vec3_scale(t, local.x), vec3_scale(b, local.y)), vec3_scale(n, local.z));
}

bool bsdf_is_delta(const pt_material *m) { return m->kind == BSDF_GLASS || m->kind == BSDF_MIRROR; }

/* ---- GGX microfacets --------------------------------------------------------
 * f = D(h) G(wo, wi) F(wo . h) / (4 cos(theta_o) cos(theta_i)), h = unit(wo + wi):
 * D the density of microfacet normals, G the fraction not shadowed or masked,
 * F Fresnel (Schlick's approximation with F0 = albedo, a metal). */
float ggx_distribution(float cos_theta_h, float alpha)
{
    if (cos_theta_h <= 0.0f)
        return 0.0f;
    float a2 = alpha * alpha;
    float c2 = cos_theta_h * cos_theta_h;
    float denominator = c2 * (a2 - 1.0f) + 1.0f;
    return a2 / ((float)PI * denominator * denominator);
}

float ggx_smith_g1(float cos_theta, float alpha)
{
    if (cos_theta <= 0.0f)
        return 0.0f;
    float c2 = cos_theta * cos_theta;
    float tan2 = (1.0f - c2) / c2;
    return 2.0f / (1.0f + sqrtf(1.0f + alpha * alpha * tan2));
}

static vec3 schlick_f0(vec3 f0, float cos_theta)
{
    float m = 1.0f - fmaxf(0.0f, fminf(1.0f, cos_theta));
    float m5 = m * m * m * m * m;
    return vec3_add(f0, vec3_scale(vec3_sub(vec3_splat(1.0f), f0), m5));
}

static vec3 ggx_eval(const pt_material *m, vec3 n, vec3 wo, vec3 wi)
{
    float cos_o = vec3_dot(n, wo), cos_i = vec3_dot(n, wi);
    if (cos_o <= 0.0f || cos_i <= 0.0f)
        return vec3_splat(0.0f);
    vec3 h = vec3_normalize(vec3_add(wo, wi));
    float d = ggx_distribution(vec3_dot(n, h), m->roughness);
    float g = ggx_smith_g1(cos_o, m->roughness) * ggx_smith_g1(cos_i, m->roughness);
    vec3 f = schlick_f0(m->albedo, vec3_dot(wo, h));
    return vec3_scale(f, d * g / (4.0f * cos_o * cos_i));
}

/* Sampling h from D(h) cos(theta_h), then reflecting wo about it: the pdf of
 * wi is D cos(theta_h) / (4 |wo . h|) (the 1/(4 wo.h) is the Jacobian of the
 * reflection). */
static float ggx_pdf(const pt_material *m, vec3 n, vec3 wo, vec3 wi)
{
    if (vec3_dot(n, wo) <= 0.0f || vec3_dot(n, wi) <= 0.0f)
        return 0.0f;
    vec3 h = vec3_normalize(vec3_add(wo, wi));
    float cos_h = vec3_dot(n, h);
    return ggx_distribution(cos_h, m->roughness) * cos_h / (4.0f * fabsf(vec3_dot(wo, h)));
}

/* ---- the interface ------------------------------------------------------------- */

vec3 bsdf_eval(const pt_material *m, vec3 n, vec3 wo, vec3 wi)
{
    switch (m->kind) {
    case BSDF_DIFFUSE:
        /* Lambertian: rho / pi, on the side of wo only */
        if (vec3_dot(n, wi) <= 0.0f || vec3_dot(n, wo) <= 0.0f)
            return vec3_splat(0.0f);
        return vec3_scale(m->albedo, 1.0f / (float)PI);
    case BSDF_GLOSSY:
        return ggx_eval(m, n, wo, wi);
    case BSDF_GLASS:
    case BSDF_MIRROR:
        return vec3_splat(0.0f);
    }
    return vec3_splat(0.0f);
}

float bsdf_pdf(const pt_material *m, vec3 n, vec3 wo, vec3 wi)
{
    switch (m->kind) {
    case BSDF_DIFFUSE: {
        float cos_i = vec3_dot(n, wi);
        return cos_i > 0.0f && vec3_dot(n, wo) > 0.0f ? cosine_hemisphere_pdf(cos_i) : 0.0f;
    }
    case BSDF_GLOSSY:
        return ggx_pdf(m, n, wo, wi);
    case BSDF_GLASS:
    case BSDF_MIRROR:
        return 0.0f;
    }
    return 0.0f;
}

bool bsdf_sample(const pt_material *m, vec3 n, vec3 wo, vec2 u, float u_lobe, bool entering, bsdf_sample_result *out)
{
    out->is_delta = false;
    out->is_transmission = false;
    switch (m->kind) {
    case BSDF_DIFFUSE: {
        /* cosine-weighted: f cos / pdf = (rho/pi) cos / (cos/pi) = rho */
        vec3 local = sample_cosine_hemisphere(u);
        if (local.z <= 0.0f)
            return false;
        out->wi = frame_to_world(n, local);
        out->pdf = cosine_hemisphere_pdf(local.z);
        out->weight = m->albedo;
        return true;
    }
    case BSDF_GLOSSY: {
        /* h from D(h) cos(theta_h): cos^2(theta_h) = (1 - u1) / (1 + (alpha^2 - 1) u1) */
        float a2 = m->roughness * m->roughness;
        float cos2 = (1.0f - u.x) / (1.0f + (a2 - 1.0f) * u.x);
        float cos_h = sqrtf(fmaxf(0.0f, cos2)), sin_h = sqrtf(fmaxf(0.0f, 1.0f - cos2));
        float phi = 2.0f * (float)PI * u.y;
        vec3 h = frame_to_world(n, vec3_make(sin_h * cosf(phi), sin_h * sinf(phi), cos_h));
        vec3 wi = vec3_reflect(vec3_neg(wo), h);
        float pdf = ggx_pdf(m, n, wo, wi);
        if (!(pdf > 0.0f))
            return false;
        out->wi = wi;
        out->pdf = pdf;
        out->weight = vec3_scale(ggx_eval(m, n, wo, wi), vec3_dot(n, wi) / pdf);
        return true;
    }
    case BSDF_MIRROR:
        out->wi = vec3_reflect(vec3_neg(wo), n);
        out->pdf = 1.0f;
        out->weight = m->albedo;
        out->is_delta = true;
        return true;
    case BSDF_GLASS: {
        /* Reflect with probability R (exact Fresnel, chapter 02), else
         * refract: f cos / pdf is then 1 either way, so glass neither gains
         * nor loses energy.
         * The refracted weight leaves out (eta_i / eta_t)^2, the factor by
         * which radiance itself changes across the surface (pbrt applies it
         * to paths that carry radiance, not to those that carry importance).
         * What the project transports is basic radiance L / eta^2, which a
         * refraction leaves unchanged and which equals radiance in air
         * (eta = 1), where every camera and light of the book sits: a path
         * from the eye to a light leaves each closed glass object as often
         * as it enters it, and the factors it would carry cancel. A light
         * or a camera inside glass, or an open glass surface, would need it. */
        float eta_i = entering ? 1.0f : m->ior, eta_t = entering ? m->ior : 1.0f;
        float cos_o = vec3_dot(n, wo);
        float reflectance = fresnel_dielectric(cos_o, eta_i, eta_t);
        vec3 refracted;
        bool can_refract = refract_direction(vec3_neg(wo), n, eta_i / eta_t, &refracted);
        out->is_delta = true;
        if (!can_refract || u_lobe < reflectance) {
            out->wi = vec3_reflect(vec3_neg(wo), n);
            out->pdf = can_refract ? reflectance : 1.0f;
        } else {
            out->wi = refracted;
            out->pdf = 1.0f - reflectance;
            out->is_transmission = true;
        }
        out->weight = m->albedo;
        return true;
    }
    }
    return false;
}
