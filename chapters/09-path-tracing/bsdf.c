/* bsdf.c -- Lambertian, GGX microfacet, smooth glass, mirror: each BSDF's
 * f, pdf and sampling, and one table (bsdf_table, at the end) that the
 * interface reads by kind. */
#include "09-path-tracing/bsdf.h"

#include "02-whitted/whitted.h"

vec3 frame_to_world(vec3 n, vec3 local)
{
    vec3 t, b;
    vec3_basis(n, &t, &b);
    return vec3_add(vec3_add(vec3_scale(t, local.x), vec3_scale(b, local.y)), vec3_scale(n, local.z));
}

/* The BSDFs' rows of the scene format's kinds (scene_pt.h, BSDF_KINDS). */
scene_material_kind bsdf_kind_scene_kind(bsdf_kind k)
{
    static const scene_material_kind scene_kinds[BSDF_KIND_COUNT] = {
#define BSDF_SCENE_KIND(id, scene_kind) scene_kind,
        BSDF_KINDS(BSDF_SCENE_KIND)
#undef BSDF_SCENE_KIND
    };
    return (unsigned)k < BSDF_KIND_COUNT ? scene_kinds[k] : SCENE_MATERIAL_KIND_COUNT;
}

const char *bsdf_kind_name(bsdf_kind k) { return scene_material_kind_name(bsdf_kind_scene_kind(k)); }

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

/* Sampling GGX: h is drawn from the normals wo can see, D_wo(h) =
 * G1(wo) max(0, wo . h) D(h) / cos(theta_o) (Heitz 2018), and wi is wo
 * reflected about h (Jacobian 1 / (4 wo . h)), so
 *   pdf(wi) = G1(wo) D(h) / (4 cos(theta_o))
 * and the sample's weight f cos(theta_i) / pdf is F G1(wi): never above 1.
 * Drawing h from D(h) cos(theta_h) instead gives the weight
 * F G (wo . h) / (cos(theta_o) cos(theta_h)), which grows without bound as wo
 * grazes: rare, bright samples on every rough metal seen at an angle. */
static float ggx_pdf(const pt_material *m, vec3 n, vec3 wo, vec3 wi)
{
    float cos_o = vec3_dot(n, wo);
    if (cos_o <= 0.0f || vec3_dot(n, wi) <= 0.0f)
        return 0.0f;
    vec3 h = vec3_normalize(vec3_add(wo, wi));
    return ggx_smith_g1(cos_o, m->roughness) * ggx_distribution(vec3_dot(n, h), m->roughness) / (4.0f * cos_o);
}

/* A visible normal for wo (local frame, z the normal) from u: stretch the
 * ellipsoid of microfacets into a hemisphere (the view direction with it),
 * pick a point of the projected disk the stretched view sees, uniformly (the
 * disk's far half foreshortened by (1 + v_z) / 2), lift it onto the
 * hemisphere, and unstretch the normal there. */
static vec3 ggx_sample_visible_normal(vec3 wo, float alpha, vec2 u)
{
    vec3 v = vec3_normalize(vec3_make(alpha * wo.x, alpha * wo.y, wo.z));
    float length2 = v.x * v.x + v.y * v.y;
    vec3 t1 = length2 > 0.0f ? vec3_scale(vec3_make(-v.y, v.x, 0.0f), 1.0f / sqrtf(length2)) : vec3_make(1, 0, 0);
    vec3 t2 = vec3_cross(v, t1);
    float r = sqrtf(u.x), phi = 2.0f * (float)PI * u.y;
    float p1 = r * cosf(phi), p2 = r * sinf(phi), s = 0.5f * (1.0f + v.z);
    p2 = (1.0f - s) * sqrtf(fmaxf(0.0f, 1.0f - p1 * p1)) + s * p2;
    float p3 = sqrtf(fmaxf(0.0f, 1.0f - p1 * p1 - p2 * p2));
    vec3 h = vec3_add(vec3_add(vec3_scale(t1, p1), vec3_scale(t2, p2)), vec3_scale(v, p3));
    return vec3_normalize(vec3_make(alpha * h.x, alpha * h.y, fmaxf(0.0f, h.z)));
}

/* ---- Lambertian -------------------------------------------------------------- */

/* rho / pi, on the side of wo only */
static vec3 lambert_eval(const pt_material *m, vec3 n, vec3 wo, vec3 wi)
{
    if (vec3_dot(n, wi) <= 0.0f || vec3_dot(n, wo) <= 0.0f)
        return vec3_splat(0.0f);
    return vec3_scale(m->albedo, 1.0f / (float)PI);
}

static float lambert_pdf(const pt_material *m, vec3 n, vec3 wo, vec3 wi)
{
    (void)m;
    float cos_i = vec3_dot(n, wi);
    return cos_i > 0.0f && vec3_dot(n, wo) > 0.0f ? cosine_hemisphere_pdf(cos_i) : 0.0f;
}

/* cosine-weighted: f cos / pdf = (rho/pi) cos / (cos/pi) = rho */
static bool lambert_sample(const pt_material *m, vec3 n, vec3 wo, vec2 u, float u_lobe, bool entering,
                           bsdf_sample_result *out)
{
    (void)wo, (void)u_lobe, (void)entering;
    vec3 local = sample_cosine_hemisphere(u);
    if (local.z <= 0.0f)
        return false;
    out->wi = frame_to_world(n, local);
    out->pdf = cosine_hemisphere_pdf(local.z);
    out->weight = m->albedo;
    return true;
}

static pt_material lambert_from_scene(const scene_material *sm) { return pt_diffuse(sm->albedo); }

/* ---- GGX, sampled ---------------------------------------------------------------- */

/* h among the normals wo sees (ggx_pdf above) */
static bool ggx_sample(const pt_material *m, vec3 n, vec3 wo, vec2 u, float u_lobe, bool entering,
                       bsdf_sample_result *out)
{
    (void)u_lobe, (void)entering;
    vec3 t, b;
    vec3_basis(n, &t, &b);
    vec3 wo_local = vec3_make(vec3_dot(wo, t), vec3_dot(wo, b), vec3_dot(wo, n));
    if (!(wo_local.z > 0.0f))
        return false;
    vec3 h = frame_to_world(n, ggx_sample_visible_normal(wo_local, m->roughness, u));
    vec3 wi = vec3_reflect(vec3_neg(wo), h);
    float pdf = ggx_pdf(m, n, wo, wi);
    if (!(pdf > 0.0f))
        return false;
    out->wi = wi;
    out->pdf = pdf;
    out->weight = vec3_scale(ggx_eval(m, n, wo, wi), vec3_dot(n, wi) / pdf);
    return true;
}

static pt_material ggx_from_scene(const scene_material *sm) { return pt_glossy(sm->albedo, sm->roughness); }

/* ---- mirror and glass: delta lobes, no density to evaluate ------------------------ */

static bool mirror_sample(const pt_material *m, vec3 n, vec3 wo, vec2 u, float u_lobe, bool entering,
                          bsdf_sample_result *out)
{
    (void)u, (void)u_lobe, (void)entering;
    out->wi = vec3_reflect(vec3_neg(wo), n);
    out->pdf = 1.0f;
    out->weight = m->albedo;
    out->is_delta = true;
    return true;
}

static pt_material mirror_from_scene(const scene_material *sm) { return pt_mirror(sm->albedo); }

/* Reflect with probability R (exact Fresnel, chapter 02), else refract:
 * f cos / pdf is then 1 either way, so glass neither gains nor loses energy.
 * The refracted weight leaves out (eta_i / eta_t)^2, the factor by which
 * radiance itself changes across the surface (pbrt applies it to paths that
 * carry radiance, not to those that carry importance). What the project
 * transports is basic radiance L / eta^2, which a refraction leaves
 * unchanged and which equals radiance in air (eta = 1), where every camera
 * and light of the book sits: a path from the eye to a light leaves each
 * closed glass object as often as it enters it, and the factors it would
 * carry cancel. A light or a camera inside glass, or an open glass surface,
 * would need it. */
static bool glass_sample(const pt_material *m, vec3 n, vec3 wo, vec2 u, float u_lobe, bool entering,
                         bsdf_sample_result *out)
{
    (void)u;
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

static pt_material glass_from_scene(const scene_material *sm)
{
    pt_material m = pt_glass(sm->ior);
    m.albedo = sm->albedo;
    return m;
}

/* ---- the table and the interface --------------------------------------------------
 * Each kind's code, by kind (bsdf_kinds.h): the interface below reads the
 * row of the material's kind, so a new BSDF is its functions and its row
 * here, and no switch elsewhere learns of it. A delta lobe (mirror, glass)
 * has no eval or pdf: f and pdf are 0 for any direction one could ask
 * about, and its sample says is_delta. */
typedef struct {
    vec3 (*eval)(const pt_material *m, vec3 n, vec3 wo, vec3 wi);
    float (*pdf)(const pt_material *m, vec3 n, vec3 wo, vec3 wi);
    bool (*sample)(const pt_material *m, vec3 n, vec3 wo, vec2 u, float u_lobe, bool entering,
                   bsdf_sample_result *out);
    pt_material (*from_scene)(const scene_material *sm); /* a scene file's material of this kind */
} bsdf_code;

static const bsdf_code bsdf_table[BSDF_KIND_COUNT] = {
    [BSDF_DIFFUSE] = {lambert_eval, lambert_pdf, lambert_sample, lambert_from_scene},
    [BSDF_GLOSSY] = {ggx_eval, ggx_pdf, ggx_sample, ggx_from_scene},
    [BSDF_GLASS] = {NULL, NULL, glass_sample, glass_from_scene},
    [BSDF_MIRROR] = {NULL, NULL, mirror_sample, mirror_from_scene},
};

bool bsdf_kind_implemented(bsdf_kind k)
{
    if ((unsigned)k >= BSDF_KIND_COUNT)
        return false;
    const bsdf_code *c = &bsdf_table[k];
    return c->sample != NULL && c->from_scene != NULL && (c->eval == NULL) == (c->pdf == NULL);
}

bool bsdf_is_delta(const pt_material *m) { return bsdf_table[m->kind].eval == NULL; }

vec3 bsdf_eval(const pt_material *m, vec3 n, vec3 wo, vec3 wi)
{
    const bsdf_code *c = &bsdf_table[m->kind];
    return c->eval != NULL ? c->eval(m, n, wo, wi) : vec3_splat(0.0f);
}

float bsdf_pdf(const pt_material *m, vec3 n, vec3 wo, vec3 wi)
{
    const bsdf_code *c = &bsdf_table[m->kind];
    return c->pdf != NULL ? c->pdf(m, n, wo, wi) : 0.0f;
}

bool bsdf_sample(const pt_material *m, vec3 n, vec3 wo, vec2 u, float u_lobe, bool entering, bsdf_sample_result *out)
{
    out->is_delta = false;
    out->is_transmission = false;
    return bsdf_table[m->kind].sample(m, n, wo, u, u_lobe, entering, out);
}

bool bsdf_kind_of_scene_kind(scene_material_kind scene_kind, bsdf_kind *out)
{
    for (int k = 0; k < BSDF_KIND_COUNT; k++)
        if (bsdf_kind_scene_kind((bsdf_kind)k) == scene_kind) {
            *out = (bsdf_kind)k;
            return true;
        }
    return false;
}

pt_material bsdf_material_from_scene(bsdf_kind k, const scene_material *sm) { return bsdf_table[k].from_scene(sm); }
