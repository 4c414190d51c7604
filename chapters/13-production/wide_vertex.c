/* wide_vertex.c -- one lane of the eight-path renderer at a vertex
 * (wide_lanes.h): the light sample, the bounces of every material, the
 * point lights and the hit records, each through chapter 09's pieces
 * (light_transport.h, bsdf.h) for one lane; and the tests' way in to the
 * light sample and the bounce of eight lanes (path_tracer_wide.h). */
#include <string.h>

#include "08-monte-carlo/sampling.h"
#include "09-path-tracing/bsdf.h"
#include "09-path-tracing/light_transport.h"
#include "13-production/fast_sincos.h"
#include "13-production/wide_lanes.h"

/* Lane k's value of a field of the lanes (three coordinates). */
#define AT(v) vec3_make(L->v[0][k], L->v[1][k], L->v[2][k])

/* Lane k's hit, as chapter 09's pieces read it (light_transport.h): the
 * point, its error bound, the geometric and shading normals. */
hit_record lane_hit(const vertex_lanes *L, int k)
{
    hit_record hit = {.point = AT(p), .point_error = L->p_error[k], .normal_geometric = AT(ng),
                      .normal_shading = AT(n)};
    return hit;
}

/* Lane k's light sample, chapter 09's solid-angle form
 * (direct_light_solid_angle(), what sample_direct_light() adds): the mask
 * bit says whether it adds anything (light and surface face each other, f
 * is not black); its contribution, times the throughput, if its shadow ray
 * gets through, and that ray, into the lanes. With `mis`, weighed by the
 * power heuristic against the one BSDF sample drawn next. */
int light_math_lane(vertex_lanes *L, int k, const pt_material *m, bool mis)
{
    hit_record p = lane_hit(L, k);
    pt_light_sample x = {.point = AT(x_light), .normal = AT(n_light), .emission = AT(le),
                         .point_error = L->x_error[k], .pdf_light = L->pdf_area[k]};
    light_contribution l = direct_light_solid_angle(m, &p, AT(wo), &x, 1, mis ? 1 : 0);
    if (!l.adds)
        return 0;
    lanes_set(L->contribution, k, vec3_mul(AT(throughput), l.radiance));
    lanes_set(L->shadow_origin, k, l.shadow.origin);
    lanes_set(L->shadow_direction, k, l.shadow.direction);
    L->shadow_t_min[k] = l.shadow.t_min;
    L->shadow_t_max[k] = l.shadow.t_max;
    return 1 << k;
}

/* A diffuse lane's next ray along wi, and its throughput times weight
 * (and the roulette's 1 / q): what every rung's bounce writes. */
static void lane_store_bounce(vertex_lanes *L, int k, vec3 wi, vec3 weight)
{
    vec3 p = vec3_make(L->p[0][k], L->p[1][k], L->p[2][k]), ng = vec3_make(L->ng[0][k], L->ng[1][k], L->ng[2][k]);
    vec3 throughput = vec3_make(L->throughput[0][k], L->throughput[1][k], L->throughput[2][k]);
    ray next = ray_spawn(p, L->p_error[k], ng, wi);
    lanes_set(L->ray.origin, k, next.origin);
    L->ray.t_min[k] = next.t_min;
    lanes_set(L->ray.direction, k, wi);
    lanes_set(L->throughput, k, vec3_scale(vec3_mul(throughput, weight), L->rr_scale[k]));
    lanes_set(L->wo, k, vec3_neg(wi));
}

/* shade()'s bounce for one lane: wi uniform on the hemisphere (its
 * azimuth by fast_sincos_turns(), as the AVX kernel computes it), chapter
 * 09's bounce_weight() f cos / pdf, the throughput after it; the lane's bit
 * if that is not black. */
int bounce_math_lane(vertex_lanes *L, int k, const pt_material *m)
{
    vec3 n = AT(n), local = sample_uniform_hemisphere_fast(L->u_x[k], L->u_y[k]);
    vec3 wi = frame_to_world(n, local);
    vec3 weight = bounce_weight(m, n, AT(wo), wi, local.z, uniform_hemisphere_pdf());
    if (vec3_is_black(weight))
        return 0;
    lane_store_bounce(L, k, wi, weight);
    return 1 << k;
}

/* trace_iterative()'s Russian roulette, after the bounce, on the throughput
 * it left (and the surface's albedo): false if the path ends here, else the
 * throughput divided by the probability it went on with. */
bool roulette_after_bounce(lane *l, const path_tracer *pt, vec3 *throughput, vec3 albedo)
{
    float q;
    if (!path_tracer_roulette(pt, l->depth, *throughput, albedo, &q))
        return true;
    if (lane_float(l, pt) >= q)
        return false;
    *throughput = vec3_scale(*throughput, 1.0f / q);
    return true;
}

/* trace_iterative()'s bounce at a diffuse vertex for one lane: wi
 * cosine-weighted (its angle by fast_sincos_turns(), as the AVX kernel
 * computes it), its pdf cosine_hemisphere_pdf(), and f cos / pdf -- on the
 * cosine rung chapter 09's bounce_weight(), if the pdf is > 0; on the MIS
 * rung bsdf_sample()'s rho, if z > 0 -- the throughput after it, and the
 * pdf. The lane's bit if the path goes on (f cos / pdf is not black). */
int bounce_cosine_lane(vertex_lanes *L, int k, const pt_material *m, bool mis)
{
    vec3 local = sample_cosine_hemisphere_fast(L->u_x[k], L->u_y[k]);
    vec3 n = AT(n);
    vec3 wi = frame_to_world(n, local);
    float pdf = cosine_hemisphere_pdf(local.z);
    vec3 weight;
    if (mis) {
        if (!(local.z > 0.0f))
            return 0;
        weight = m->albedo;
    } else {
        if (!(pdf > 0.0f))
            return 0;
        weight = bounce_weight(m, n, AT(wo), wi, local.z, pdf);
    }
    if (vec3_is_black(weight))
        return 0;
    lane_store_bounce(L, k, wi, weight);
    L->pdf[k] = pdf;
    return 1 << k;
}

/* ---- the other materials, one lane at a time --------------------------------------
 * Glossy surfaces, mirrors and glass, and point lights, through chapter
 * 09's BSDFs (bsdf_eval, bsdf_sample): the lanes on them are few in most
 * scenes, and their arithmetic is the book's, not a copy. */

/* The lane's next ray from p along wi, and the throughput it carries. */
static void lane_bounce_set(lane_bounce *out, const vertex_lanes *L, int k, vec3 wi, vec3 throughput)
{
    out->next = ray_spawn(AT(p), L->p_error[k], AT(ng), wi);
    out->throughput = throughput;
    out->wo = vec3_neg(wi);
}

/* shade()'s bounce at a glossy vertex: wi uniform on the hemisphere
 * (chapter 08's sample_uniform_hemisphere), f cos / pdf from bsdf_eval();
 * false if that is black. */
bool bounce_surface_lane(const vertex_lanes *L, int k, const pt_material *m, lane_bounce *out)
{
    vec3 n = AT(n);
    vec3 local = sample_uniform_hemisphere(vec2_make(L->u_x[k], L->u_y[k]));
    vec3 wi = frame_to_world(n, local);
    vec3 weight = bounce_weight(m, n, AT(wo), wi, local.z, uniform_hemisphere_pdf());
    if (vec3_is_black(weight))
        return false;
    out->next = ray_spawn(AT(p), L->p_error[k], AT(ng), wi);
    out->throughput = vec3_scale(vec3_mul(AT(throughput), weight), L->rr_scale[k]);
    out->wo = vec3_neg(wi);
    return true;
}

/* shade_delta(): a mirror or glass picks the direction (bsdf_sample), from
 * the roulette's number and three more, in its order; the emission the ray
 * meets then counts. False if the path ends here. */
bool bounce_delta_lane(lane *l, const path_tracer *pt, const vertex_lanes *L, int k, const pt_material *m,
                              bool front, lane_bounce *out, ray_counters *counters)
{
    if (pt->integrator != PT_LECTURE)
        return bounce_iterative_lane(l, pt, L, k, m, front, out, counters);
    if (l->depth + 2 > pt->max_depth)
        return false;
    float p_rr = 1.0f;
    if (path_tracer_roulette(pt, l->depth, AT(throughput), m->albedo, &p_rr) && !(lane_float(l, pt) < p_rr))
        return false;
    float u_y = lane_float(l, pt), u_x = lane_float(l, pt), u_lobe = lane_float(l, pt);
    bsdf_sample_result s;
    if (!bsdf_sample(m, AT(n), AT(wo), vec2_make(u_x, u_y), u_lobe, front, &s) ||
        !(pt->effects & (s.is_transmission ? EFFECT_REFRACTION : EFFECT_REFLECTION)))
        return false;
    if (s.is_transmission)
        counters->refraction_rays++;
    else
        counters->reflection_rays++;
    out->next = ray_spawn(AT(p), L->p_error[k], AT(ng), s.wi);
    out->throughput = vec3_mul(AT(throughput), vec3_scale(s.weight, 1.0f / p_rr));
    out->wo = vec3_neg(s.wi);
    return true;
}

/* trace_iterative()'s bounce at a glossy vertex (whose numbers
 * roll_bounce_iterative drew), a mirror or glass (whose numbers it draws
 * here), one lane: the direction from bsdf_sample() on the MIS rung and on
 * delta surfaces, else cosine-weighted (chapter 08's
 * sample_cosine_hemisphere) with f cos / pdf from bsdf_eval(); then the
 * roulette on the new throughput. False if the path ends here. */
bool bounce_iterative_lane(lane *l, const path_tracer *pt, const vertex_lanes *L, int k, const pt_material *m,
                                  bool front, lane_bounce *out, ray_counters *counters)
{
    bool delta = bsdf_is_delta(m);
    vec3 n = AT(n), wo = AT(wo);
    bsdf_sample_result s;
    if (delta) {
        if (l->depth + 1 > pt->max_depth)
            return false;
        float u_y = lane_float(l, pt), u_x = lane_float(l, pt), u_lobe = lane_float(l, pt);
        if (!bsdf_sample(m, n, wo, vec2_make(u_x, u_y), u_lobe, front, &s))
            return false;
    } else if (pt->integrator == PT_MIS) {
        if (!bsdf_sample(m, n, wo, vec2_make(L->u_x[k], L->u_y[k]), L->u_lobe[k], front, &s))
            return false;
    } else {
        vec3 local = sample_cosine_hemisphere(vec2_make(L->u_x[k], L->u_y[k]));
        s.wi = frame_to_world(n, local);
        s.pdf = cosine_hemisphere_pdf(local.z);
        if (!(s.pdf > 0.0f))
            return false;
        s.weight = bounce_weight(m, n, wo, s.wi, local.z, s.pdf);
        s.is_delta = s.is_transmission = false;
    }
    if (vec3_is_black(s.weight))
        return false;
    if (s.is_delta && !(pt->effects & (s.is_transmission ? EFFECT_REFRACTION : EFFECT_REFLECTION)))
        return false;
    vec3 throughput = vec3_mul(AT(throughput), s.weight);
    if (!roulette_after_bounce(l, pt, &throughput, m->albedo))
        return false;
    if (s.is_delta && s.is_transmission)
        counters->refraction_rays++;
    else if (s.is_delta)
        counters->reflection_rays++;
    lane_bounce_set(out, L, k, s.wi, throughput);
    l->previous_point = AT(p);
    l->previous_normal = n;
    l->previous_pdf = s.pdf;
    return true;
}

/* point_lights() of chapter 09 for lane k: each point light's
 * f I cos(theta) / r^2 (direct_light_point()), times the throughput, its
 * shadow ray queued (or, without shadows, added at once). */
void point_lights_lane(row_job *job, const vertex_lanes *L, int k, const pt_material *m)
{
    const pt_scene *sc = job->pt->scene;
    hit_record p = lane_hit(L, k);
    for (int i = 0; i < sc->point_light_count; i++) {
        light_contribution l = direct_light_point(m, &p, AT(wo), &sc->point_lights[i]);
        if (!l.adds)
            continue;
        vec3 contribution = vec3_mul(AT(throughput), l.radiance);
        if (!(job->pt->effects & EFFECT_SHADOWS)) {
            job->lanes[k].radiance = vec3_add(job->lanes[k].radiance, contribution);
            continue;
        }
        job->counters->shadow_rays++;
        queue_push(job, k, l.shadow, contribution);
    }
}

/* pt_scene_intersect()'s spheres for lane k, after its triangles: a sphere
 * nearer than the triangle hit (t_max, or the ray's own) replaces it. */
bool sphere_hit_lane(const pt_scene *sc, const rays8 *rays, int k, float t_max, hit_record *hit,
                            ray_counters *counters)
{
    ray r = rays8_get(rays, k);
    r.t_max = t_max;
    return pt_scene_intersect_spheres(sc, r, hit, counters);
}

/* A full hit record into lane k's arrays (a sphere's, or a triangle's
 * made lane by lane). */
int hit_record_set(const pt_scene *sc, const hit_record *hit, int k, vertex_lanes *L, int material[LANES])
{
    lanes_set(L->p, k, hit->point);
    L->p_error[k] = hit->point_error;
    lanes_set(L->ng, k, hit->normal_geometric);
    lanes_set(L->n, k, hit->normal_shading);
    lanes_set(L->albedo, k, sc->materials[hit->material_id].albedo);
    material[k] = hit->material_id;
    return hit->front_face << k;
}

/* ---- the hit records -----------------------------------------------------------
 * What triangle_set_fill_hit() makes of a lane's hit, as far as shading
 * needs it: the point (from the barycentrics) and its error bound, the
 * geometric normal facing the ray, the shading normal, the material and its
 * albedo, and whether the front was hit; written straight into the lanes'
 * arrays. */
int hit_record_lane(const pt_scene *sc, const hits8 *hits, int k, vertex_lanes *L, int material[LANES])
{
    hit_record hit;
    triangle_set_fill_hit(&sc->triangles, hits->index[k], rays8_get(&L->ray, k), hits->t[k], hits->b1[k],
                          hits->b2[k], &hit);
    return hit_record_set(sc, &hit, k, L, material);
}

#undef AT

/* ---- the tests' way in (path_tracer_wide.h) ---------------------------------- */

/* The tests' vertices into the lanes, and each one's diffuse material. */
static int lanes_from(const wide_vertex *v, int count, vertex_lanes *L, pt_material m[LANES])
{
    memset(L, 0, sizeof *L);
    int lanes = 0;
    for (int k = 0; k < count && k < LANES; k++) {
        lanes_set(L->p, k, v[k].p);
        lanes_set(L->ng, k, v[k].ng);
        lanes_set(L->n, k, v[k].n);
        lanes_set(L->wo, k, v[k].wo);
        lanes_set(L->albedo, k, v[k].albedo);
        lanes_set(L->throughput, k, v[k].throughput);
        lanes_set(L->x_light, k, v[k].x_light);
        lanes_set(L->n_light, k, v[k].n_light);
        lanes_set(L->le, k, v[k].le);
        L->p_error[k] = v[k].p_error;
        L->x_error[k] = v[k].x_error;
        L->pdf_area[k] = v[k].pdf_area;
        L->u_x[k] = v[k].u_x;
        L->u_y[k] = v[k].u_y;
        L->rr_scale[k] = v[k].rr_scale;
        m[k] = pt_diffuse(v[k].albedo);
        lanes |= 1 << k;
    }
    return lanes;
}

int path_tracer_wide_light_math(const wide_vertex *v, int count, bool mis, wide_light_result out[8])
{
    vertex_lanes L;
    pt_material m[LANES];
    int lanes = lanes_from(v, count, &L, m), lit = 0;
#if WIDE_HAVE_AVX
    if (wide_avx_runs())
        lit = light_math_avx(&L, lanes, mis);
    else
#endif
        for (int left = lanes; left != 0; left &= left - 1) {
            int k = __builtin_ctz((unsigned)left);
            lit |= light_math_lane(&L, k, &m[k], mis);
        }
    for (int left = lit; left != 0; left &= left - 1) {
        int k = __builtin_ctz((unsigned)left);
        out[k].contribution = vec3_make(L.contribution[0][k], L.contribution[1][k], L.contribution[2][k]);
        out[k].shadow.origin = vec3_make(L.shadow_origin[0][k], L.shadow_origin[1][k], L.shadow_origin[2][k]);
        out[k].shadow.direction =
            vec3_make(L.shadow_direction[0][k], L.shadow_direction[1][k], L.shadow_direction[2][k]);
        out[k].shadow.t_min = L.shadow_t_min[k];
        out[k].shadow.t_max = L.shadow_t_max[k];
    }
    return lit;
}

int path_tracer_wide_bounce_math(const wide_vertex *v, int count, pt_integrator rung, wide_bounce_result out[8])
{
    vertex_lanes L;
    pt_material m[LANES];
    int lanes = lanes_from(v, count, &L, m), on = 0;
    bool mis = rung == PT_MIS;
#if WIDE_HAVE_AVX
    if (wide_avx_runs())
        on = rung == PT_LECTURE ? bounce_math_avx(&L, lanes) : bounce_cosine_avx(&L, lanes, mis);
    else
#endif
        for (int left = lanes; left != 0; left &= left - 1) {
            int k = __builtin_ctz((unsigned)left);
            on |= rung == PT_LECTURE ? bounce_math_lane(&L, k, &m[k]) : bounce_cosine_lane(&L, k, &m[k], mis);
        }
    for (int left = on; left != 0; left &= left - 1) {
        int k = __builtin_ctz((unsigned)left);
        out[k].next = rays8_get(&L.ray, k);
        out[k].throughput = vec3_make(L.throughput[0][k], L.throughput[1][k], L.throughput[2][k]);
        out[k].wo = vec3_make(L.wo[0][k], L.wo[1][k], L.wo[2][k]);
        out[k].pdf = rung == PT_LECTURE ? 0.0f : L.pdf[k];
    }
    return on;
}
