/* distribution.c -- Cook's distribution ray tracing, in the shape of
 * chapter 02's recursion. */
#include "10-distribution/distribution.h"

#include "02-whitted/whitted.h"
#include "09-path-tracing/bsdf.h"
#include "09-path-tracing/light_transport.h"
#include "effects.h"
#include "explain.h"

/* ---- the thin lens -------------------------------------------------------------
 * A lens of focal length F images the plane at distance f onto the film;
 * every ray from a point of that plane through the lens converges to one
 * film point. So instead of modelling the film and the refraction, pick the
 * point P where the pinhole ray through this pixel meets the plane of focus
 * (distance f along the view direction), pick a point L on the lens disk,
 * and trace from L towards P. Points on the plane of focus are sharp; a
 * point at distance z spreads, on the plane of focus, over a disk of
 * diameter 2 a |z - f| / z (similar triangles): the circle of confusion. */
thin_lens thin_lens_make(const camera *cam, float aperture_radius, float focus_distance)
{
    return (thin_lens){cam->eye, cam->right, cam->up, cam->forward, aperture_radius, focus_distance};
}

ray thin_lens_ray(const thin_lens *lens, ray pinhole, vec2 u)
{
    /* exercise: thin_lens */
    if (!(lens->aperture_radius > 0.0f))
        return pinhole; /* a pinhole: every ray through the eye, as chapter 01 */
    float along = vec3_dot(pinhole.direction, lens->forward);
    vec3 focus_point = ray_at(pinhole, lens->focus_distance / along);
    vec2 disk = sample_uniform_disk_concentric(u);
    vec3 on_lens = vec3_add(pinhole.origin, vec3_add(vec3_scale(lens->right, disk.x * lens->aperture_radius),
                                                     vec3_scale(lens->up, disk.y * lens->aperture_radius)));
    return ray_make(on_lens, vec3_normalize(vec3_sub(focus_point, on_lens)));
    /* end of exercise thin_lens */
}

float thin_lens_confusion_diameter(const thin_lens *lens, float distance)
{
    return 2.0f * lens->aperture_radius * fabsf(distance - lens->focus_distance) / distance;
}

distribution_tracer distribution_tracer_defaults(const motion_scene *scene, const camera *cam)
{
    distribution_tracer dt;
    dt.scene = scene;
    dt.lens = thin_lens_make(cam, scene->aperture_radius, scene->focus_distance);
    dt.light_samples = 1;
    dt.glossy_samples = 1;
    dt.max_depth = 5;
    dt.motion = true;
    dt.effects = EFFECT_ALL;
    return dt;
}

double distribution_glossy_rays_per_camera_ray(int glossy_samples, int max_depth)
{
    double total = 0.0, level = 1.0;
    for (int d = 1; d <= max_depth; d++) {
        level *= glossy_samples;
        total += level;
    }
    return total;
}


/* How a ray came to be traced: does the emission it finds count in full
 * (seen from the eye, or through a mirror or glass, where no light sample
 * could have found it), or was it drawn from a glossy lobe with density
 * pdf at `from`, so that it shares the direct light with the light samples
 * there (multiple importance sampling)? */
typedef struct {
    bool emission_counts;
    float pdf;
    vec3 from;
} arrival;

/* Does a light sample's shadow ray, at the ray's instant, get through? (With
 * the shadows effect off, without a shadow ray.) */
static bool lit_at(const distribution_tracer *dt, const light_contribution *l, float time, ray_counters *counters)
{
    if (!(dt->effects & EFFECT_SHADOWS))
        return true;
    counters->shadow_rays++;
    return !motion_scene_occluded(dt->scene, (timed_ray){l->shadow, time}, counters);
}

/* ---- soft shadows: N_light samples of the area lights ---------------------------
 * L_dir = integral over the lights' area A of
 *         L_e f_r cos(theta) cos(theta') / |x' - p|^2 V(p, x') dA
 * estimated with N_light points x'_k, picked as chapter 09 picks one
 * (pdf 1/A for lights of one radiance):
 *   L_dir ~ 1/N_light sum_k L_e f_r cos cos' / |x'_k - p|^2 V / pdf.
 * V needs a shadow ray per sample, at the ray's instant: the penumbra is the
 * fraction of the light each point sees. Point lights (a delta in position)
 * need one ray each. With `mis`, each sample is weighted against the
 * N_glossy lobe samples that could also have found the light (the power
 * heuristic with Veach's counts, 9.2.4: the counts multiply the densities).
 * What each sample adds, and the segment its shadow ray tests, is chapter
 * 09's (light_transport.h); only the rays' instant is this chapter's. */
static vec3 direct_light(const distribution_tracer *dt, const hit_record *hit, vec3 wo, const pt_material *m,
                         float time, bool mis, pcg32 *rng, ray_counters *counters)
{
    const pt_scene *sc = &dt->scene->base;
    vec3 sum = vec3_splat(0.0f);
    for (int k = 0; k < dt->light_samples; k++) {
        pt_light_sample x;
        float u_pick = pcg32_float(rng), u1 = pcg32_float(rng), u2 = pcg32_float(rng);
        if (!pt_scene_sample_light(sc, u_pick, u1, u2, &x))
            break;
        light_contribution l =
            direct_light_solid_angle(m, hit, wo, &x, dt->light_samples, mis ? dt->glossy_samples : 0);
        if (l.adds && lit_at(dt, &l, time, counters))
            sum = vec3_add(sum, l.radiance);
    }
    vec3 radiance = vec3_scale(sum, 1.0f / (float)dt->light_samples);
    for (int i = 0; i < sc->point_light_count; i++) {
        light_contribution l = direct_light_point(m, hit, wo, &sc->point_lights[i]);
        if (l.adds && lit_at(dt, &l, time, counters))
            radiance = vec3_add(radiance, l.radiance);
    }
    return radiance;
}

/* A mirror's or glass's branch (below, after the recursion it calls). */
static vec3 trace_branch(const distribution_tracer *dt, const hit_record *hit, vec3 direction, const char *what,
                         float time, int depth, pcg32 *rng, ray_counters *counters);

/* ---- the recursion ----------------------------------------------------------------
 *   trace(ray):  hit = closest hit at the ray's instant
 *     L = emission of hit (unless the light samples before counted it)
 *     diffuse:  + direct light from N_light shadow rays
 *     glossy:   + direct light from N_light shadow rays
 *               + 1/N_glossy sum_k trace(ray k from the GGX lobe) f cos / pdf
 *     mirror:   + albedo trace(reflected ray)
 *     glass:    + R trace(reflected) + (1 - R) trace(refracted)
 * `depth` is the number of bounces before this hit. The instant stays the
 * camera ray's: the whole ray tree sees the scene at one moment. */
static vec3 trace(const distribution_tracer *dt, timed_ray tr, int depth, arrival how, pcg32 *rng,
                  ray_counters *counters)
{
    const pt_scene *sc = &dt->scene->base;
    hit_record hit;
    if (!motion_scene_intersect(dt->scene, tr, &hit, counters))
        return sc->environment;
    const pt_material *m = &sc->materials[hit.material_id];
    vec3 wo = vec3_normalize(vec3_neg(tr.r.direction));
    vec3 n = hit.normal_shading;
    vec3 radiance = vec3_splat(0.0f);
    int indent = 2 * depth + 2; /* --explain: each bounce two steps deeper */
    if (explain_on()) {
        char p[64];
        explain_line(indent - 1, "hit %s, material #%d (%s), at t = %.6g, point %s, bounce %d",
                     hit.shape_id >= 0 ? "a static triangle" : "a sphere or moving object", hit.material_id,
                     bsdf_kind_name(m->kind), (double)hit.t, explain_vec3(p, hit.point), depth);
    }

    /* Emission. Emitting static triangles are the lights the samples aim
     * at; a glossy ray that finds one shares it with them by MIS. */
    vec3 le = hit.front_face ? m->emission : vec3_splat(0.0f);
    if (!vec3_is_black(le)) {
        if (how.emission_counts || hit.shape_id < 0) {
            radiance = le;
        } else {
            float pdf_area = pt_scene_emitter_pdf_area(sc, hit.material_id);
            float pdf_light = light_pdf_from(how.from, hit.point, hit.normal_geometric, wo, pdf_area);
            /* Veach's counts multiply the densities */
            float weight = power_heuristic((float)dt->glossy_samples * how.pdf, (float)dt->light_samples * pdf_light);
            radiance = vec3_scale(le, weight);
        }
    }
    if (depth + 1 > dt->max_depth)
        return radiance;

    /* Each kind's way: mirror and glass branch as in chapter 02; diffuse,
     * glossy and any other BSDF take the direct light through bsdf_eval,
     * and glossy also its lobe's rays. (A later delta BSDF, whose eval is
     * 0, would need a branch of its own, as mirror and glass have.) */
    switch (m->kind) {
    default: {
        bool lobe_rays = m->kind == BSDF_GLOSSY && dt->glossy_samples > 0 && (dt->effects & EFFECT_GLOSSY);
        vec3 direct = direct_light(dt, &hit, wo, m, tr.time, lobe_rays, rng, counters);
        radiance = vec3_add(radiance, direct);
        if (explain_on()) {
            char b[64];
            explain_line(indent, "direct light from %d light samples%s: %s", dt->light_samples,
                         lobe_rays ? " (MIS with the lobe rays)" : "", explain_vec3(b, direct));
        }
        if (!lobe_rays)
            return radiance; /* diffuse: no indirect light, the path tracer's addition */
        /* Glossy reflection: 1/N sum f cos / pdf x L_i over N directions
         * drawn from the GGX lobe (bsdf.c); each recurses. */
        vec3 sum = vec3_splat(0.0f);
        for (int k = 0; k < dt->glossy_samples; k++) {
            bsdf_sample_result s;
            /* in a written order (C leaves a call's argument order open): GCC's */
            float u_y = pcg32_float(rng), u_x = pcg32_float(rng);
            vec2 u = vec2_make(u_x, u_y);
            if (!bsdf_sample(m, n, wo, u, 0.0f, hit.front_face, &s) || vec3_is_black(s.weight))
                continue;
            counters->indirect_rays++;
            timed_ray next = {ray_spawn(hit.point, hit.point_error, hit.normal_geometric, s.wi), tr.time};
            if (explain_on()) {
                char label[64];
                snprintf(label, sizeof label, "glossy ray %d of %d (pdf %.4g)", k + 1, dt->glossy_samples, (double)s.pdf);
                explain_ray(indent, label, next.r);
            }
            vec3 incoming = trace(dt, next, depth + 1, (arrival){false, s.pdf, hit.point}, rng, counters);
            sum = vec3_add(sum, vec3_mul(s.weight, incoming));
        }
        return vec3_add(radiance, vec3_scale(sum, 1.0f / (float)dt->glossy_samples));
    }
    /* Mirror and glass: chapter 02's branches, no sampling at all. */
    case BSDF_MIRROR: {
        vec3 reflected = vec3_reflect(vec3_neg(wo), n);
        if (dt->effects & EFFECT_REFLECTION) {
            counters->reflection_rays++;
            vec3 incoming = trace_branch(dt, &hit, reflected, "reflected ray", tr.time, depth, rng, counters);
            radiance = vec3_add(radiance, vec3_mul(m->albedo, incoming));
        }
        return radiance;
    }
    case BSDF_GLASS: {
        vec3 reflected = vec3_reflect(vec3_neg(wo), n);
        float eta_i = hit.front_face ? 1.0f : m->ior, eta_t = hit.front_face ? m->ior : 1.0f;
        vec3 refracted;
        bool can_refract = refract_direction(vec3_neg(wo), n, eta_i / eta_t, &refracted);
        float reflectance = can_refract ? fresnel_dielectric(vec3_dot(n, wo), eta_i, eta_t) : 1.0f;
        if ((dt->effects & EFFECT_REFLECTION) && reflectance > 0.0f) {
            counters->reflection_rays++;
            vec3 incoming = trace_branch(dt, &hit, reflected, "reflected ray", tr.time, depth, rng, counters);
            radiance = vec3_add(radiance, vec3_scale(vec3_mul(m->albedo, incoming), reflectance));
        }
        if ((dt->effects & EFFECT_REFRACTION) && can_refract && reflectance < 1.0f) {
            counters->refraction_rays++;
            vec3 incoming = trace_branch(dt, &hit, refracted, "refracted ray", tr.time, depth, rng, counters);
            radiance = vec3_add(radiance, vec3_scale(vec3_mul(m->albedo, incoming), 1.0f - reflectance));
        }
        return radiance;
    }
    }
    return radiance;
}

/* A mirror's or glass's branch: one ray, traced on (chapter 02); the caller weighs it. */
static vec3 trace_branch(const distribution_tracer *dt, const hit_record *hit, vec3 direction, const char *what,
                         float time, int depth, pcg32 *rng, ray_counters *counters)
{
    timed_ray next = {ray_spawn(hit->point, hit->point_error, hit->normal_geometric, direction), time};
    if (explain_on())
        explain_ray(2 * depth + 2, what, next.r);
    return trace(dt, next, depth + 1, (arrival){true, 0.0f, hit->point}, rng, counters);
}

vec3 distribution_radiance(const void *ctx, ray pinhole, pcg32 *rng, ray_counters *counters)
{
    const distribution_tracer *dt = ctx;
    /* The pixel position came from the render loop (stratified); now the
     * lens and the shutter. Both are drawn always, so that the streams of
     * the later numbers do not depend on the settings. */
    float u_lens_y = pcg32_float(rng), u_lens_x = pcg32_float(rng); /* in GCC's order, written out */
    vec2 u_lens = vec2_make(u_lens_x, u_lens_y);
    float u_time = pcg32_float(rng);
    timed_ray camera_ray = {thin_lens_ray(&dt->lens, pinhole, u_lens), dt->motion ? u_time : 0.0f};
    if (explain_on()) {
        char label[96];
        snprintf(label, sizeof label, "lens ray (aperture %g), at shutter instant %.4f", (double)dt->lens.aperture_radius,
                 (double)camera_ray.time);
        explain_ray(1, label, camera_ray.r);
    }
    return trace(dt, camera_ray, 0, (arrival){true, 0.0f, pinhole.origin}, rng, counters);
}
