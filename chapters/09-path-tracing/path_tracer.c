/* path_tracer.c -- lecture 16: solving the rendering equation by Monte Carlo.
 *
 *   L_o(p, wo) = L_e(p, wo) + integral over the hemisphere of
 *                L_i(p, wi) f_r(p, wi, wo) cos(theta) d wi
 *
 * One sample per bounce (N = 1, so the number of rays does not explode with
 * depth), many paths per pixel; light from the emitters is sampled directly
 * at every bounce, and rays that bounce on to hit an emitter do not count its
 * emission again. */
#include "path_tracer.h"

#include <string.h>

#include "09-path-tracing/bsdf.h"

path_tracer path_tracer_defaults(const pt_scene *scene)
{
    path_tracer pt;
    pt.scene = scene;
    pt.integrator = PT_LECTURE;
    pt.russian_roulette = RR_FIXED;
    pt.rr_probability = 0.8f;
    pt.rr_start_depth = 3;
    pt.max_depth = 64;
    return pt;
}

static const char *const integrator_names[] = {"lecture", "cosine", "mis"};

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

static bool is_black(vec3 c) { return c.x == 0.0f && c.y == 0.0f && c.z == 0.0f; }

/* The power heuristic (Veach 1997) with exponent 2: the weight of a sample
 * drawn with density a, when density b could have drawn it too. */
static float power_heuristic(float a, float b)
{
    float a2 = a * a, b2 = b * b;
    return a2 + b2 > 0.0f ? a2 / (a2 + b2) : 0.0f;
}

/* Does this hit count its own emission? Emitters are one-sided. */
static vec3 emitted(const pt_scene *sc, const hit_record *hit)
{
    const pt_material *m = &sc->materials[hit->material_id];
    return hit->front_face ? m->emission : vec3_splat(0.0f);
}

/* ---- direct light: sampling the light ---------------------------------------
 * The lecture's change of variables: instead of waiting for a hemisphere
 * sample to hit the light, pick a point x' on the light uniformly by area
 * (pdf = 1/A) and integrate over the light's area:
 *   L_dir = L_e(x', -wi) f_r(p, wi, wo) cos(theta) cos(theta') / |x' - p|^2 / (1/A)
 * if the shadow ray from p to x' is not blocked. With with_mis, the sample is
 * weighted against the BSDF sampling that could also have found x'. */
static vec3 sample_direct_light(const path_tracer *pt, const hit_record *hit, vec3 wo, const pt_material *m,
                                bool with_mis, pcg32 *rng, ray_counters *counters)
{
    const pt_scene *sc = pt->scene;
    vec3 n = hit->normal_shading;
    vec3 radiance = vec3_splat(0.0f);

    vec3 x_light, n_light;
    int light_material;
    float u_pick = pcg32_float(rng), u1 = pcg32_float(rng), u2 = pcg32_float(rng);
    if (pt_scene_sample_emitter(sc, u_pick, u1, u2, &x_light, &n_light, &light_material)) {
        vec3 to_light = vec3_sub(x_light, hit->point);
        float distance2 = vec3_length_squared(to_light);
        vec3 wi = vec3_scale(to_light, 1.0f / sqrtf(distance2));
        float cos_theta = vec3_dot(n, wi);
        float cos_theta_light = -vec3_dot(n_light, wi);
        /* A light seen from behind (one-sided) or below the surface adds
         * nothing: no shadow ray needed to know it. */
        if (cos_theta_light > 0.0f && cos_theta > 0.0f) {
            vec3 f = bsdf_eval(m, n, wo, wi);
            if (!is_black(f)) {
                /* The shadow ray must reach the light sample itself. */
                ray shadow = ray_spawn_to(hit->point, hit->normal_geometric, x_light, n_light);
                counters->shadow_rays++;
                if (!pt_scene_occluded(sc, shadow, counters)) {
                    /* pdf 1/A per unit area is distance^2 / (cos' A) per unit solid angle
                     * (with several lights, 1/A is the density of picking x'
                     * among all of them: scene_pt.h) */
                    float pdf_light = distance2 * pt_scene_emitter_pdf_area(sc, light_material) / cos_theta_light;
                    float weight = with_mis ? power_heuristic(pdf_light, bsdf_pdf(m, n, wo, wi)) : 1.0f;
                    vec3 le = sc->materials[light_material].emission;
                    radiance = vec3_add(radiance, vec3_scale(vec3_mul(le, f), cos_theta / pdf_light * weight));
                }
            }
        }
    }
    /* Point lights: a delta in position, so always sampled this way:
     * L_dir = f_r I cos(theta) / r^2. */
    for (int i = 0; i < sc->point_light_count; i++) {
        const pt_point_light *light = &sc->point_lights[i];
        vec3 to_light = vec3_sub(light->position, hit->point);
        float distance2 = vec3_length_squared(to_light);
        vec3 wi = vec3_scale(to_light, 1.0f / sqrtf(distance2));
        float cos_theta = vec3_dot(n, wi);
        if (cos_theta <= 0.0f)
            continue;
        vec3 f = bsdf_eval(m, n, wo, wi);
        if (is_black(f))
            continue;
        ray shadow = ray_spawn_to(hit->point, hit->normal_geometric, light->position, vec3_splat(0.0f));
        counters->shadow_rays++;
        if (!pt_scene_occluded(sc, shadow, counters))
            radiance = vec3_add(radiance, vec3_scale(vec3_mul(f, light->intensity), cos_theta / distance2));
    }
    return radiance;
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

/* ---- the lecture's algorithm, exactly ---------------------------------------
 *   shade(p, wo)
 *     L_dir   = light sampled by area (above)
 *     test Russian roulette with probability P_RR
 *     wi      = uniform on the hemisphere, pdf = 1 / (2 pi)
 *     trace a ray from p in wi; if it hits q:
 *       L_indir = shade(q, -wi) f_r cos(theta) / pdf / P_RR
 *     return L_dir + L_indir
 * shade() returns the light *reflected* at p: the emission of q was already
 * counted by light sampling at p, so it is not added again. Rays that leave
 * the scene bring the environment, which no light sample covers. Glass and
 * mirrors reflect into single directions no hemisphere sample can find; there
 * the BSDF is sampled instead, and the emission the ray then meets does
 * count. `depth` is the number of bounces before p. */
static vec3 shade(const path_tracer *pt, const hit_record *hit, vec3 wo, int depth, pcg32 *rng, ray_counters *counters)
{
    const pt_scene *sc = pt->scene;
    const pt_material *m = &sc->materials[hit->material_id];
    vec3 n = hit->normal_shading;
    bool delta = bsdf_is_delta(m);

    /* Direct light: bounce depth + 1 */
    vec3 l_dir = vec3_splat(0.0f);
    if (!delta && depth + 1 <= pt->max_depth)
        l_dir = sample_direct_light(pt, hit, wo, m, false, rng, counters);
    if (depth + 2 > pt->max_depth && !delta)
        return l_dir;
    if (depth + 1 > pt->max_depth)
        return l_dir;

    /* Russian roulette: continue with probability P_RR, and divide what the
     * continued path brings by P_RR, so the expectation is unchanged. */
    float p_rr = pt->russian_roulette == RR_OFF ? 1.0f : pt->rr_probability;
    if (pt->russian_roulette != RR_OFF && pcg32_float(rng) >= p_rr)
        return l_dir;

    bsdf_sample_result s;
    if (delta) {
        vec2 u = vec2_make(pcg32_float(rng), pcg32_float(rng));
        if (!bsdf_sample(m, n, wo, u, pcg32_float(rng), hit->front_face, &s))
            return l_dir;
    } else {
        /* wi uniform on the hemisphere around n: pdf = 1 / (2 pi) */
        vec3 local = sample_uniform_hemisphere(vec2_make(pcg32_float(rng), pcg32_float(rng)));
        s.wi = frame_to_world(n, local);
        s.pdf = uniform_hemisphere_pdf();
        s.weight = vec3_scale(bsdf_eval(m, n, wo, s.wi), local.z / s.pdf); /* f_r cos / pdf */
        s.is_delta = false;
        s.is_transmission = false;
        if (is_black(s.weight))
            return l_dir;
    }
    count_continuation(counters, &s);
    ray next = ray_spawn(hit->point, hit->normal_geometric, s.wi);
    hit_record q;
    vec3 incoming;
    if (pt_scene_intersect(sc, next, &q, counters)) {
        incoming = shade(pt, &q, vec3_neg(s.wi), depth + 1, rng, counters);
        /* Emission seen through a delta bounce was not light-sampled. */
        if (delta)
            incoming = vec3_add(incoming, emitted(sc, &q));
    } else {
        incoming = sc->environment;
    }
    vec3 l_indir = vec3_scale(vec3_mul(incoming, s.weight), 1.0f / p_rr);
    return vec3_add(l_dir, l_indir);
}

static vec3 trace_lecture(const path_tracer *pt, ray r, pcg32 *rng, ray_counters *counters)
{
    hit_record hit;
    if (!pt_scene_intersect(pt->scene, r, &hit, counters))
        return pt->scene->environment;
    /* What the eye sees directly: the emission at the first hit, plus the
     * light reflected there. */
    vec3 wo = vec3_normalize(vec3_neg(r.direction));
    return vec3_add(emitted(pt->scene, &hit), shade(pt, &hit, wo, 0, rng, counters));
}

/* ---- the later rungs, as a loop ---------------------------------------------
 * The recursion above, unrolled: `throughput` is the product of the
 * f cos / pdf factors along the path so far, and each bounce adds
 * throughput x (what is found there). */
static vec3 trace_iterative(const path_tracer *pt, ray r, pcg32 *rng, ray_counters *counters)
{
    const pt_scene *sc = pt->scene;
    bool mis = pt->integrator == PT_MIS;
    vec3 radiance = vec3_splat(0.0f), throughput = vec3_splat(1.0f);
    bool emission_counts = true; /* at the first hit, and after delta bounces */
    float previous_pdf = 0.0f;   /* the BSDF pdf the current ray was drawn with */
    vec3 previous_point = r.origin;

    for (int depth = 0;; depth++) {
        hit_record hit;
        if (!pt_scene_intersect(sc, r, &hit, counters)) {
            radiance = vec3_add(radiance, vec3_mul(throughput, sc->environment));
            break;
        }
        const pt_material *m = &sc->materials[hit.material_id];
        vec3 wo = vec3_normalize(vec3_neg(r.direction));
        vec3 n = hit.normal_shading;

        /* Emission found by this ray. Light sampling at the previous vertex
         * already counted emitting triangles; with MIS both count, weighted. */
        vec3 le = emitted(sc, &hit);
        if (!is_black(le)) {
            bool light_sampled = hit.shape_id >= 0; /* emitting triangles are in the light table */
            if (emission_counts || !light_sampled) {
                radiance = vec3_add(radiance, vec3_mul(throughput, le));
            } else if (mis) {
                float distance2 = vec3_length_squared(vec3_sub(hit.point, previous_point));
                float cos_light = fabsf(vec3_dot(hit.normal_geometric, wo));
                float pdf_light = distance2 * pt_scene_emitter_pdf_area(sc, hit.material_id) / cos_light;
                radiance = vec3_add(radiance, vec3_scale(vec3_mul(throughput, le), power_heuristic(previous_pdf, pdf_light)));
            }
        }
        bool delta = bsdf_is_delta(m);
        if (depth + 1 > pt->max_depth)
            break;
        if (!delta)
            radiance = vec3_add(radiance, vec3_mul(throughput, sample_direct_light(pt, &hit, wo, m, mis, rng, counters)));
        /* Continue if the next vertex can still add light within max_depth:
         * its light samples are bounce depth + 2; with MIS, the emission it
         * finds is bounce depth + 1, the BSDF's share of the direct light. */
        if (depth + 2 > pt->max_depth && !delta && !mis)
            break;

        /* The next direction: from the BSDF (MIS, and always for delta
         * surfaces), or cosine-weighted on the hemisphere. */
        bsdf_sample_result s;
        vec2 u = vec2_make(pcg32_float(rng), pcg32_float(rng));
        if (mis || delta) {
            if (!bsdf_sample(m, n, wo, u, pcg32_float(rng), hit.front_face, &s))
                break;
        } else {
            vec3 local = sample_cosine_hemisphere(u);
            s.wi = frame_to_world(n, local);
            s.pdf = cosine_hemisphere_pdf(local.z);
            if (!(s.pdf > 0.0f))
                break;
            s.weight = vec3_scale(bsdf_eval(m, n, wo, s.wi), local.z / s.pdf);
            s.is_delta = false;
            s.is_transmission = false;
        }
        if (is_black(s.weight))
            break;
        throughput = vec3_mul(throughput, s.weight);

        /* Russian roulette */
        if (pt->russian_roulette == RR_FIXED) {
            if (pcg32_float(rng) >= pt->rr_probability)
                break;
            throughput = vec3_scale(throughput, 1.0f / pt->rr_probability);
        } else if (pt->russian_roulette == RR_THROUGHPUT && depth + 1 >= pt->rr_start_depth) {
            /* Continue in proportion to what the path can still carry: a
             * path through dark surfaces ends sooner. */
            float q = fminf(1.0f, vec3_max_component(throughput));
            if (pcg32_float(rng) >= q)
                break;
            throughput = vec3_scale(throughput, 1.0f / q);
        }
        count_continuation(counters, &s);
        previous_point = hit.point;
        previous_pdf = s.pdf;
        emission_counts = s.is_delta;
        r = ray_spawn(hit.point, hit.normal_geometric, s.wi);
    }
    return radiance;
}

vec3 path_trace_radiance(const void *ctx, ray r, pcg32 *rng, ray_counters *counters)
{
    const path_tracer *pt = ctx;
    if (pt->integrator == PT_LECTURE)
        return trace_lecture(pt, r, rng, counters);
    return trace_iterative(pt, r, rng, counters);
}
