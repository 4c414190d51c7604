/* path_tracer.c -- lecture 16: solving the rendering equation by Monte Carlo.
 *
 *   L_o(p, wo) = L_e(p, wo) + integral over the hemisphere of
 *                L_i(p, wi) f_r(p, wi, wo) cos(theta) d wi
 *
 * One sample per bounce (N = 1, so the number of rays does not explode with
 * depth), many paths per pixel; light from the emitters is sampled directly
 * at every bounce, and rays that bounce on to hit an emitter do not count its
 * emission again. */
#include "09-path-tracing/path_tracer.h"

#include <string.h>

#include "09-path-tracing/bsdf.h"
#include "09-path-tracing/light_transport.h"
#include "09-path-tracing/sobol_sampler.h"
#include "explain.h"

path_tracer path_tracer_defaults(const pt_scene *scene)
{
    path_tracer pt;
    pt.scene = scene;
    pt.integrator = PT_LECTURE;
    pt.russian_roulette = RR_FIXED;
    pt.rr_probability = 0.8f;
    pt.rr_start_depth = 3;
    pt.max_depth = 64;
    pt.effects = EFFECT_ALL;
    pt.sampler = PT_SAMPLER_RANDOM;
    return pt;
}

const char *const PT_INTEGRATOR_NAMES[] = {"lecture", "cosine", "mis", NULL};
static const char *const *const integrator_names = PT_INTEGRATOR_NAMES;
/* in the order of pt_russian_roulette */
const char *const PT_ROULETTE_NAMES[] = {"off", "fixed", "throughput", "albedo", NULL};
static const char *const *const roulette_names = PT_ROULETTE_NAMES;
const char *const PT_SAMPLER_NAMES[] = {"random", "sobol", NULL};

const char *pt_russian_roulette_name(pt_russian_roulette r) { return roulette_names[r]; }

bool pt_russian_roulette_parse(const char *name, pt_russian_roulette *out)
{
    for (int i = 0; roulette_names[i] != NULL; i++)
        if (strcmp(name, roulette_names[i]) == 0) {
            *out = (pt_russian_roulette)i;
            return true;
        }
    return false;
}

const char *pt_integrator_name(pt_integrator i) { return integrator_names[i]; }

bool pt_integrator_parse(const char *name, pt_integrator *out)
{
    for (int i = 0; i < 3; i++)
        if (strcmp(name, integrator_names[i]) == 0) {
            *out = (pt_integrator)i;
            return true;
        }
    return false;
}


/* ---- effects ------------------------------------------------------------------
 * Does a path go on from a non-delta surface of this material? Diffuse
 * surfaces pass on indirect light, glossy ones glossy reflections. */
static bool continues_from(const path_tracer *pt, const pt_material *m)
{
    return (pt->effects & (m->kind == BSDF_GLOSSY ? EFFECT_GLOSSY : EFFECT_INDIRECT)) != 0;
}

/* May a path follow this delta sample (mirror reflection, glass)? */
static bool delta_allowed(const path_tracer *pt, const bsdf_sample_result *s)
{
    return (pt->effects & (s->is_transmission ? EFFECT_REFRACTION : EFFECT_REFLECTION)) != 0;
}

/* ---- --explain ------------------------------------------------------------------ */

static void explain_pt_hit(const pt_scene *sc, const hit_record *hit, int depth)
{
    char p[64];
    const pt_material *m = &sc->materials[hit->material_id];
    explain_line(depth, "hit %s #%d, material #%d (%s), at t = %.6g, point %s%s",
                 hit->shape_id >= 0 ? "triangle" : "sphere", hit->shape_id >= 0 ? hit->shape_id : -1 - hit->shape_id,
                 hit->material_id, bsdf_kind_name(m->kind), (double)hit->t, explain_vec3(p, hit->point),
                 hit->front_face ? "" : " (back face)");
}

/* Does this hit count its own emission? Emitters are one-sided. */
static vec3 emitted(const pt_scene *sc, const hit_record *hit)
{
    const pt_material *m = &sc->materials[hit->material_id];
    return hit->front_face ? m->emission : vec3_splat(0.0f);
}

/* ---- the shadow-ray hook ------------------------------------------------------
 * Does the shadow ray get through its segment? With the shadows effect off
 * (nothing in the scene can block a light), without a shadow ray. */
static bool light_visible(const path_tracer *pt, const ray *shadow, ray_counters *counters)
{
    return !(pt->effects & EFFECT_SHADOWS) || pt_scene_segment_clear(pt->scene, *shadow, counters);
}

/* ---- lights without area ----------------------------------------------------
 * Point lights: a delta in position, so only light sampling finds them:
 * L_dir = f_r I cos(theta) / r^2 (direct_light_point). Not on the slide;
 * every rung adds them. */
static vec3 point_lights(const path_tracer *pt, const hit_record *p, vec3 wo, const pt_material *m,
                         int explain_depth, ray_counters *counters)
{
    const pt_scene *sc = pt->scene;
    vec3 radiance = vec3_splat(0.0f);
    for (int i = 0; i < sc->point_light_count; i++) {
        light_contribution l = direct_light_point(m, p, wo, &sc->point_lights[i]);
        if (!l.adds)
            continue;
        if (!light_visible(pt, &l.shadow, counters)) {
            explain_line(explain_depth, "point light %d: shadow ray blocked", i);
            continue;
        }
        radiance = vec3_add(radiance, l.radiance);
        char cb[64];
        if (explain_on())
            explain_line(explain_depth, "point light %d: visible, cos %.4g, r^2 %.4g, adds %s", i,
                         (double)l.cos_theta, (double)l.distance2, explain_vec3(cb, l.radiance));
    }
    return radiance;
}

/* A point x' on the lights (pt_scene_sample_light), from the path's next
 * three numbers in a written order. */
static bool sample_light(const pt_scene *sc, pt_random *rng, pt_light_sample *x)
{
    float u_pick = pt_random_float(rng), u1 = pt_random_float(rng), u2 = pt_random_float(rng);
    return pt_scene_sample_light(sc, u_pick, u1, u2, x);
}

/* ---- direct light: sampling the light ---------------------------------------
 * The lecture's change of variables: instead of waiting for a hemisphere
 * sample to hit the light, pick a point x' on the light uniformly by area
 * (pdf = 1/A) and integrate over the light's area. In the solid-angle form
 * the later rungs use (so that MIS can weigh it against BSDF sampling),
 * pdf_light per steradian is |x' - p|^2 / (cos(theta') A):
 *   L_dir = L_e f_r cos(theta) / pdf_light
 * if the shadow ray from p to x' is not blocked. */
static vec3 sample_direct_light(const path_tracer *pt, const hit_record *hit, vec3 wo, const pt_material *m,
                                bool with_mis, int explain_depth, pt_random *rng, ray_counters *counters)
{
    vec3 radiance = point_lights(pt, hit, wo, m, explain_depth, counters);
    pt_light_sample x;
    if (!sample_light(pt->scene, rng, &x))
        return radiance;
    /* with MIS, weighed against the one BSDF sample drawn next */
    light_contribution l = direct_light_solid_angle(m, hit, wo, &x, 1, with_mis ? 1 : 0);
    if (!l.adds) {
        explain_line(explain_depth, "light sample: faces away, lies below the surface or f = 0: no shadow ray");
        return radiance;
    }
    if (!light_visible(pt, &l.shadow, counters)) {
        explain_line(explain_depth, "light sample: shadow ray blocked");
        return radiance;
    }
    if (explain_on()) {
        char xb[64], cb[64], wb[32] = "";
        if (with_mis) /* the weight only where MIS weighs: the other rungs use none */
            snprintf(wb, sizeof wb, ", MIS weight %.3g", (double)l.weight);
        explain_line(explain_depth, "light sample at %s: visible, pdf %.4g per sr, cos %.4g%s, adds %s",
                     explain_vec3(xb, x.point), (double)l.pdf_light, (double)l.cos_theta, wb,
                     explain_vec3(cb, l.radiance));
    }
    return vec3_add(radiance, l.radiance);
}

/* --explain: the roulette's draw and what it decided. */
static void explain_roulette(const path_tracer *pt, int indent, float u_rr, float q)
{
    bool fixed = pt->russian_roulette == RR_FIXED;
    const char *on = fixed ? "" : pt->russian_roulette == RR_ALBEDO ? " on albedo" : " on throughput";
    explain_line(indent, "Russian roulette%s: u = %.4f %s %s = %.3g: %s", on, (double)u_rr,
                 u_rr >= q ? ">=" : "<", fixed ? "P_RR" : "q", (double)q,
                 u_rr >= q ? "the path ends" : fixed ? "continue, dividing by P_RR" : "continue, dividing by q");
}

static void count_continuation(ray_counters *counters, const bsdf_sample_result *s)
{
    if (!s->is_delta)
        counters->indirect_rays++;
    else if (s->is_transmission)
        counters->refraction_rays++;
    else
        counters->reflection_rays++;
}

/* ---- the hooks the lecture's shade() calls, one line each --------------------
 * light_visible (above), and: does the path go on from p (bounce depth + 1 to a vertex whose light
 * sample, bounce depth + 2, still counts; the effects ask for it; the
 * roulette lets it)? The probability P_RR it went on with, or 0 if it
 * ends here. */
static float path_goes_on(const path_tracer *pt, const pt_material *m, int depth, vec3 throughput, pt_random *rng)
{
    int indent = 2 * depth + 2; /* --explain: each bounce two steps deeper */
    float p_rr = 1.0f;
    if (depth + 2 > pt->max_depth) {
        explain_line(indent, "max depth %d: no further bounce", pt->max_depth);
        return 0.0f;
    }
    if (!bsdf_is_delta(m) && !continues_from(pt, m)) {
        explain_line(indent, "no %s effect: the path ends here", m->kind == BSDF_GLOSSY ? "glossy" : "indirect");
        return 0.0f;
    }
    if (!path_tracer_roulette(pt, depth, throughput, m->albedo, &p_rr))
        return 1.0f;
    float u_rr = pt_random_float(rng);
    explain_roulette(pt, indent, u_rr, p_rr);
    return u_rr < p_rr ? p_rr : 0.0f;
}


/* --explain: what shade() found at p, and the ray it traced on. */
static void explain_shade(const path_tracer *pt, int depth, const char *what, vec3 l, ray r, const hit_record *q,
                          bool hit)
{
    if (!explain_on())
        return;
    char b[64];
    explain_line(2 * depth + 2, "%s = %s", what, explain_vec3(b, l));
    if (r.t_max <= 0.0f)
        return;
    explain_ray(2 * depth + 2, "next ray", r);
    if (hit)
        explain_pt_hit(pt->scene, q, 2 * depth + 3);
    else
        explain_line(2 * depth + 3, "left the scene: the environment");
}

/* --explain: the lecture's light sample in the slide's area form. */
static void explain_light_sample(int depth, const pt_light_sample *x, const light_contribution *l_x)
{
    if (!explain_on())
        return;
    char xb[64], cb[64];
    explain_line(2 * depth + 2, "light sample at x' = %s: visible, cos theta %.4g, cos theta' %.4g, |x' - p|^2 %.4g, "
                 "pdf_light %.4g per unit area, adds %s", explain_vec3(xb, x->point), (double)l_x->cos_theta,
                 (double)l_x->cos_theta_light, (double)l_x->distance2, (double)x->pdf_light,
                 explain_vec3(cb, l_x->radiance));
}

/* --explain: a light sample that adds nothing, and why: it faces away (or
 * lies below the surface, or f = 0), and no shadow ray is traced; or its
 * shadow ray is blocked. */
static void explain_light_sample_lost(int depth, const pt_light_sample *x, bool shadow_ray_traced)
{
    if (!explain_on())
        return;
    char xb[64];
    explain_line(2 * depth + 2, "light sample at x' = %s: %s: adds 0", explain_vec3(xb, x->point),
                 shadow_ray_traced ? "shadow ray blocked" : "faces away, lies below the surface or f = 0, no shadow ray");
}

static vec3 shade(const path_tracer *pt, const hit_record *p, vec3 wo, int depth, vec3 throughput, pt_random *rng,
                  ray_counters *counters);

/* Mirrors and glass reflect into single directions that no hemisphere
 * sample finds and no light sample reaches: the BSDF picks the direction,
 * and the emission the ray meets counts, since no light sample at p did. */
static vec3 shade_delta(const path_tracer *pt, const hit_record *p, vec3 wo, int depth, vec3 throughput,
                        pt_random *rng, ray_counters *counters)
{
    const pt_scene *sc = pt->scene;
    const pt_material *m = &sc->materials[p->material_id];
    bsdf_sample_result s;
    float p_rr = path_goes_on(pt, m, depth, throughput, rng);
    if (p_rr == 0.0f)
        return vec3_splat(0.0f);
    float u_y = pt_random_float(rng), u_x = pt_random_float(rng);
    if (!bsdf_sample(m, p->normal_shading, wo, vec2_make(u_x, u_y), pt_random_float(rng), p->front_face, &s) ||
        !delta_allowed(pt, &s))
        return vec3_splat(0.0f);
    vec3 weight = vec3_scale(s.weight, 1.0f / p_rr);
    count_continuation(counters, &s);
    ray r = ray_spawn(p->point, p->point_error, p->normal_geometric, s.wi);
    hit_record q;
    bool hit = pt_scene_intersect(sc, r, &q, counters);
    explain_shade(pt, depth, s.is_transmission ? "refracted" : "reflected", weight, r, &q, hit);
    if (!hit)
        return vec3_mul(sc->environment, weight);
    vec3 l_q = shade(pt, &q, vec3_neg(s.wi), depth + 1, vec3_mul(throughput, weight), rng, counters);
    return vec3_mul(vec3_add(emitted(sc, &q), l_q), weight);
}

/* ---- the lecture's algorithm ----------------------------------------------------
 *   shade(p, wo)
 *     # Contribution from the light source
 *     uniformly sample the light at x' (pdf_light = 1 / A)
 *     shoot a ray from p to x'
 *     if the ray is not blocked in the middle
 *       L_dir = L_i * f_r * cos(theta) * cos(theta') / |x' - p|^2 / pdf_light
 *     # Contribution from other reflectors
 *     L_indir = 0.0
 *     test Russian roulette with probability P_RR
 *     uniformly sample the hemisphere toward wi (pdf_hemi = 1 / 2pi)
 *     trace a ray r(p, wi)
 *     if ray r hit a non-emitting object at q
 *       L_indir = shade(q, -wi) * f_r * cos(theta) / pdf_hemi / P_RR
 *     return L_dir + L_indir
 * shade() returns the light *reflected* at p, so the emission of q is not
 * added again: light sampling at p counted it. (q's own reflection is: an
 * emitter that also reflects passes light on like any surface.) `depth` is
 * the number of bounces before p, `throughput` the product of
 * f_r cos / pdf / P_RR along the path to p (for --rr throughput). */
static vec3 shade(const path_tracer *pt, const hit_record *p, vec3 wo, int depth, vec3 throughput, pt_random *rng,
                  ray_counters *counters)
{
    const pt_scene *sc = pt->scene;
    const pt_material *m = &sc->materials[p->material_id];
    vec3 n = p->normal_shading;
    if (bsdf_is_delta(m)) /* a mirror or glass: not on the slide (above) */
        return shade_delta(pt, p, wo, depth, throughput, rng, counters);
    /* exercise: shade */
    /* Contribution from the light source: x' uniformly on the light, pdf_light = 1 / A */
    vec3 l_dir = point_lights(pt, p, wo, m, 2 * depth + 2, counters); /* lights without area (above) */
    pt_light_sample x;
    if (sample_light(sc, rng, &x)) {
        /* L_i f_r cos(theta) cos(theta') / |x' - p|^2 / pdf_light, and the ray from p to x' */
        light_contribution l_x = direct_light_area(m, p, wo, &x);
        if (l_x.adds && light_visible(pt, &l_x.shadow, counters)) { /* not blocked in the middle */
            l_dir = vec3_add(l_dir, l_x.radiance);
            explain_light_sample(depth, &x, &l_x);
        } else {
            explain_light_sample_lost(depth, &x, l_x.adds);
        }
    }
    /* Contribution from other reflectors: Russian roulette with P_RR */
    float p_rr = path_goes_on(pt, m, depth, throughput, rng);
    if (p_rr == 0.0f)
        return l_dir;
    /* wi uniformly on the hemisphere, pdf_hemi = 1 / (2 pi) */
    float u_y = pt_random_float(rng), u_x = pt_random_float(rng);
    vec3 local = sample_uniform_hemisphere(vec2_make(u_x, u_y)); /* local.z = cos(theta) */
    vec3 wi = frame_to_world(n, local);
    vec3 f_cos_pdf = vec3_scale(bsdf_eval(m, n, wo, wi), local.z / uniform_hemisphere_pdf() / p_rr);
    /* trace a ray r(p, wi); if it hits q: L_indir = shade(q, -wi) f_r cos(theta) / pdf_hemi / P_RR */
    ray r = ray_spawn(p->point, p->point_error, p->normal_geometric, wi);
    counters->indirect_rays++;
    hit_record q;
    bool hit = pt_scene_intersect(sc, r, &q, counters);
    explain_shade(pt, depth, "L_dir", l_dir, r, &q, hit);
    vec3 l_q = hit ? shade(pt, &q, vec3_neg(wi), depth + 1, vec3_mul(throughput, f_cos_pdf), rng, counters)
                   : sc->environment; /* a ray that leaves the scene brings the environment */
    return vec3_add(l_dir, vec3_mul(l_q, f_cos_pdf));
    /* end of exercise shade */
}

static vec3 trace_lecture(const path_tracer *pt, ray r, pt_random *rng, ray_counters *counters)
{
    hit_record hit;
    if (!pt_scene_intersect(pt->scene, r, &hit, counters)) {
        explain_line(1, "left the scene: the environment");
        return pt->scene->environment;
    }
    if (explain_on())
        explain_pt_hit(pt->scene, &hit, 1);
    /* What the eye sees directly: the emission at the first hit, plus the
     * light reflected there (bounce 1 and on). */
    vec3 wo = vec3_normalize(vec3_neg(r.direction));
    vec3 reflected = pt->max_depth >= 1 ? shade(pt, &hit, wo, 0, vec3_splat(1.0f), rng, counters) : vec3_splat(0.0f);
    return vec3_add(emitted(pt->scene, &hit), reflected);
}

/* ---- the later rungs, as a loop ---------------------------------------------
 * The recursion above, unrolled: `throughput` is the product of the
 * f cos / pdf factors along the path so far, and each bounce adds
 * throughput x (what is found there). */
static vec3 trace_iterative(const path_tracer *pt, ray r, pt_random *rng, ray_counters *counters)
{
    const pt_scene *sc = pt->scene;
    bool mis = pt->integrator == PT_MIS;
    vec3 radiance = vec3_splat(0.0f), throughput = vec3_splat(1.0f);
    bool emission_counts = true; /* at the first hit, and after delta bounces */
    float previous_pdf = 0.0f;   /* the BSDF pdf the current ray was drawn with */
    vec3 previous_point = r.origin;

    for (int depth = 0;; depth++) {
        int indent = 2 * depth + 1; /* --explain: each bounce two steps deeper */
        hit_record hit;
        if (!pt_scene_intersect(sc, r, &hit, counters)) {
            radiance = vec3_add(radiance, vec3_mul(throughput, sc->environment));
            explain_line(indent, "left the scene: the environment, times throughput");
            break;
        }
        if (explain_on()) {
            char tb[64];
            explain_pt_hit(sc, &hit, indent);
            explain_line(indent, "throughput so far %s", explain_vec3(tb, throughput));
        }
        const pt_material *m = &sc->materials[hit.material_id];
        vec3 wo = vec3_normalize(vec3_neg(r.direction));
        vec3 n = hit.normal_shading;

        /* Emission found by this ray. Light sampling at the previous vertex
         * already counted emitting triangles; with MIS both count, weighted. */
        vec3 le = emitted(sc, &hit);
        if (!vec3_is_black(le)) {
            bool light_sampled = hit.shape_id >= 0; /* emitting triangles are in the light table */
            if (emission_counts || !light_sampled) {
                radiance = vec3_add(radiance, vec3_mul(throughput, le));
                explain_line(indent, "emission counted in full (%s)",
                             emission_counts ? "seen directly or through a delta bounce" : "not in the light table");
            } else if (mis) {
                float pdf_light = light_pdf_from(previous_point, hit.point, hit.normal_geometric, wo,
                                                 pt_scene_emitter_pdf_area(sc, hit.material_id));
                float weight = power_heuristic(previous_pdf, pdf_light);
                radiance = vec3_add(radiance, vec3_scale(vec3_mul(throughput, le), weight));
                explain_line(indent, "emission found by the BSDF sample: MIS weight %.3g (BSDF pdf %.4g, light pdf %.4g)",
                             (double)weight, (double)previous_pdf, (double)pdf_light);
            } else {
                explain_line(indent, "emission not counted: the light sample at the previous vertex did");
            }
        }
        bool delta = bsdf_is_delta(m);
        if (depth + 1 > pt->max_depth)
            break;
        /* Effects: a diffuse (glossy) vertex passes light on only if the
         * scene calls for indirect (glossy) light. A vertex that ends the
         * path takes its direct light from light sampling alone (weight 1):
         * the BSDF sample that MIS would weigh against is never drawn. */
        bool goes_on = delta || continues_from(pt, m);
        if (!delta) {
            vec3 direct = sample_direct_light(pt, &hit, wo, m, mis && goes_on, indent + 1, rng, counters);
            radiance = vec3_add(radiance, vec3_mul(throughput, direct));
        }
        if (!goes_on) {
            explain_line(indent, "no %s effect: the path ends here", m->kind == BSDF_GLOSSY ? "glossy" : "indirect");
            break;
        }
        /* Continue if the next vertex can still add light within max_depth:
         * its light samples are bounce depth + 2; with MIS, the emission it
         * finds is bounce depth + 1, the BSDF's share of the direct light. */
        if (depth + 2 > pt->max_depth && !delta && !mis)
            break;

        /* The next direction: from the BSDF (MIS, and always for delta
         * surfaces), or cosine-weighted on the hemisphere. */
        bsdf_sample_result s;
        /* u_y first, then u_x, as shade() above draws them (each declarator
     * is sequenced), so that every rung reads a path's numbers alike */
        float u_y = pt_random_float(rng), u_x = pt_random_float(rng);
        vec2 u = vec2_make(u_x, u_y);
        if (mis || delta) {
            if (!bsdf_sample(m, n, wo, u, pt_random_float(rng), hit.front_face, &s))
                break;
        } else {
            vec3 local = sample_cosine_hemisphere(u);
            s.wi = frame_to_world(n, local);
            s.pdf = cosine_hemisphere_pdf(local.z);
            if (!(s.pdf > 0.0f))
                break;
            s.weight = bounce_weight(m, n, wo, s.wi, local.z, s.pdf);
            s.is_delta = false;
            s.is_transmission = false;
        }
        if (vec3_is_black(s.weight))
            break;
        if (s.is_delta && !delta_allowed(pt, &s)) {
            explain_line(indent, "no %s effect: the path ends here", s.is_transmission ? "refraction" : "reflection");
            break;
        }
        throughput = vec3_mul(throughput, s.weight);

        /* Russian roulette */
        float q;
        if (path_tracer_roulette(pt, depth, throughput, m->albedo, &q)) {
            float u_rr = pt_random_float(rng);
            explain_roulette(pt, indent, u_rr, q);
            if (u_rr >= q)
                break;
            throughput = vec3_scale(throughput, 1.0f / q);
        }
        count_continuation(counters, &s);
        if (explain_on()) {
            char label[96], w[64], total[64];
            snprintf(label, sizeof label, "%s ray (bounce %d, pdf %.4g, f cos / pdf = %s)",
                     !s.is_delta ? "indirect" : s.is_transmission ? "refracted" : "reflected", depth + 1, (double)s.pdf,
                     explain_vec3(w, s.weight));
            explain_line(indent, "radiance so far %s", explain_vec3(total, radiance));
            explain_ray(indent, label, ray_spawn(hit.point, hit.point_error, hit.normal_geometric, s.wi));
        }
        previous_point = hit.point;
        previous_pdf = s.pdf;
        emission_counts = s.is_delta;
        r = ray_spawn(hit.point, hit.point_error, hit.normal_geometric, s.wi);
    }
    return radiance;
}

vec3 path_trace_radiance_from(const path_tracer *pt, ray r, pt_random *random, ray_counters *counters)
{
    if (pt->integrator == PT_LECTURE)
        return trace_lecture(pt, r, random, counters);
    return trace_iterative(pt, r, random, counters);
}

vec3 path_trace_radiance(const void *ctx, ray r, pcg32 *rng, ray_counters *counters)
{
    pt_random random = {.rng = rng, .next = NULL, .state = NULL};
    return path_trace_radiance_from(ctx, r, &random, counters);
}

vec3 path_trace_sobol_sample(const render_job *job, int x, int y, int index, pcg32 *rng, ray_counters *counters)
{
    uint64_t pixel = (uint64_t)y * (uint64_t)job->cam->width + (uint64_t)x;
    sobol_sampler sobol = sobol_sampler_start(job->seed, pixel, (uint32_t)index, rng);
    pt_random random = {.rng = rng, .next = sobol_sampler_next, .state = &sobol};
    /* coordinates 0 and 1: where in the pixel (each its own declaration:
     * C leaves the order of an initializer list's side effects open) */
    float px = (float)x + pt_random_float(&random);
    float py = (float)y + pt_random_float(&random);
    ray r = render_camera_ray(job, index, px, py, counters);
    return path_trace_radiance_from(job->scene, r, &random, counters);
}

render_sample_fn path_tracer_sample_fn(const path_tracer *pt)
{
    return pt->sampler == PT_SAMPLER_SOBOL ? path_trace_sobol_sample : NULL;
}
