/* path_tracer_wide.c -- eight paths at a time (path_tracer_wide.h): the
 * lanes' schedule -- pixels, samples and their random numbers, the
 * shadow-ray queue, one vertex of eight paths (render_row) -- and the
 * renders. What a lane does at a vertex is wide_vertex.c's, and for the
 * diffuse lanes eight at a time wide_kernels_avx.c's (wide_lanes.h). */
#include "13-production/path_tracer_wide.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "09-path-tracing/light_transport.h"
#include "13-production/walls.h"
#include "13-production/wide_lanes.h"
#include "explain.h"
#include "memory.h"
#include "timer.h"

/* path_tracer_wide_use_avx(): the lanes' arithmetic in AVX2 where the
 * processor has it, or lane by lane (the same bits; for the tests). */
static bool use_avx = true;
void path_tracer_wide_use_avx(bool on) { use_avx = on; }

/* path_tracer_wide_lights(): how the lanes pick a light */
static wide_lights light_picking = WIDE_LIGHTS_AUTO;
void path_tracer_wide_lights(wide_lights how) { light_picking = how; }

bool path_tracer_wide_uses_light_tree(const pt_scene *sc)
{
    return sc->emitter_count > 0 && (light_picking == WIDE_LIGHTS_TREE ||
                                     (light_picking == WIDE_LIGHTS_AUTO && sc->emitter_count >= LIGHT_TREE_MIN_EMITTERS));
}

/* The light tree the render picks by, or NULL if it picks by power: the
 * one built with the scene's structures, or, where none was (a tree asked
 * for on a scene of few emitters), one built into *tree now, which
 * *built says the caller frees. */
static const light_tree *lights_for(const pt_scene *sc, const wide_scene_tracers *trace, light_tree *tree,
                                    bool *built)
{
    *built = false;
    if (!path_tracer_wide_uses_light_tree(sc))
        return NULL;
    if (trace->lights != NULL)
        return trace->lights;
    light_tree_build(tree, sc);
    *built = true;
    return tree;
}

/* path_tracer_wide_twin(): the tests' wrong renderers */
static wide_twin twin_wrong = WIDE_TWIN_NONE;
void path_tracer_wide_twin(wide_twin twin) { twin_wrong = twin; }

static bool wide_cpu_has_avx2(void)
{
#if WIDE_HAVE_AVX
    return __builtin_cpu_supports("avx2");
#else
    return false;
#endif
}

bool wide_avx_runs(void) { return use_avx && wide_cpu_has_avx2(); }

/* The material kinds the lanes render: diffuse (eight at a time), glossy,
 * mirror and glass (one lane at a time, through chapter 09's BSDFs;
 * light_found() sorts them). A scene with a kind of chapter 09's that is
 * not one of these is refused by name (path_tracer_wide_supported), so
 * that it is rendered one path at a time, never with black lanes. */
static bool lanes_render_kind(bsdf_kind kind)
{
    return kind == BSDF_DIFFUSE || kind == BSDF_GLOSSY || kind == BSDF_MIRROR || kind == BSDF_GLASS;
}

bool path_tracer_wide_supported(const path_tracer *pt, char *why, size_t why_size)
{
    const pt_scene *sc = pt->scene;
    char reason[160] = "";
    if (explain_on())
        snprintf(reason, sizeof reason, "--explain follows one path");
    else if (sc->triangles.count > 0 && sc->bvh == NULL)
        snprintf(reason, sizeof reason, "the scene's triangles are in no structure (pt_scene_finish)");
    for (int i = 0; i < sc->material_count && reason[0] == '\0'; i++)
        if (!lanes_render_kind(sc->materials[i].kind))
            snprintf(reason, sizeof reason,
                     "material %d is of kind '%s', which the lanes do not render (diffuse, glossy, mirror, glass)",
                     i, bsdf_kind_name(sc->materials[i].kind));
    if (reason[0] != '\0' && why != NULL)
        snprintf(why, why_size, "%s", reason);
    return reason[0] == '\0';
}

wide_scene_tracers wide_scene_tracers_for(const pt_scene *sc)
{
    wide_scene_tracers t;
    const accel *a = sc->bvh;
    bool walls = a != NULL && walls_is(a);
    t.all = wide_tracer_for(walls ? walls_all(a) : a);
    t.walls = walls && walls_found(a) ? a : NULL;
    t.occluders = wide_tracer_for(t.walls != NULL ? walls_occluders(a) : NULL);
    t.lights = walls_light_tree(a);
    return t;
}

path_tracer production_path_tracer_defaults(const pt_scene *scene)
{
    path_tracer pt = path_tracer_defaults(scene);
    pt.sampler = PRODUCTION_SAMPLER;
    pt.russian_roulette = PRODUCTION_ROULETTE;
    pt.integrator = PRODUCTION_INTEGRATOR;
    return pt;
}

/* A lane's next camera sample, drawn as render_pixel() draws it (jitter
 * within the pixel: two numbers). */
static void start_sample(lane *l, row_job *job)
{
    float px = (float)l->x + lane_float(l, job->pt);
    float py = (float)l->y + lane_float(l, job->pt);
    int k = (int)(l - job->lanes);
    rays8_set(&job->vertex->ray, k, camera_ray(job->cam, px, py));
    job->counters->camera_rays++;
    job->camera |= 1 << k;
    l->depth = 0;
    l->radiance = vec3_splat(0.0f);
    l->emission_counts = true;
    for (int c = 0; c < 3; c++)
        job->vertex->throughput[c][k] = 1.0f;
}

/* The lane's next pixel of the row, or idle. */
static void start_pixel(lane *l, row_job *job)
{
    if (job->next_x >= (job->x_end > 0 ? job->x_end : job->cam->width)) {
        l->x = -1;
        return;
    }
    l->x = job->next_x++;
    l->y = job->y;
    l->samples_left = job->spp;
    l->sample_id = 0;
    l->unsettled = 0;
    l->waiting = false;
    uint64_t pixel = (uint64_t)l->y * (uint64_t)job->cam->width + (uint64_t)l->x;
    l->rng = pcg32_for_pixel(job->seed, pixel);
    if (job->pt->sampler == PT_SAMPLER_SOBOL) /* path_trace_sobol_sample(): sample i is point i of the pixel's sequence */
        sobol_pixel_start(&l->sobol, job->seed, pixel, 0, &l->rng);
    memset(l->channel, 0, sizeof l->channel);
    start_sample(l, job);
}

/* A sample's radiance into its pixel's mean (NaN and Inf dropped and
 * counted, as render_pixel() does, with the same bias: the pixel is the
 * mean of its finite samples). */
static void settle(lane *l, vec3 s, row_job *job)
{
    if (vec3_is_finite(s)) {
        welford_add(&l->channel[0], s.x);
        welford_add(&l->channel[1], s.y);
        welford_add(&l->channel[2], s.z);
    } else {
        job->counters->nonfinite_samples++;
    }
}

/* Does a sphere of the scene lie on lane k's segment? (pt_scene_occluded's
 * spheres, lane by lane: a room holds few.) */
static bool spheres_block_lane(const pt_scene *sc, const rays8 *rays, int k, ray_counters *counters)
{
    ray r = rays8_get(rays, k);
    hit_record ignored;
    for (int i = 0; i < sc->sphere_count; i++) {
        sphere shape = {sc->spheres[i].center, sc->spheres[i].radius};
        counters->primitive_tests++;
        if (sphere_intersect(&shape, r, &ignored))
            return true;
    }
    return false;
}

/* Trace the first n queued shadow rays (8, or all if fewer) as one packet, and give
 * each that gets through its contribution, to the sample it belongs to:
 * the lane's current one, or the one before, which is settled once its
 * last shadow ray is traced. */
static void trace_queued(row_job *job, int n)
{
    const pt_scene *sc = job->pt->scene;
    const wide_scene_tracers *trace = job->trace;
    shadow_queue *queue = &job->queue;
    if (n <= 0)
        return;
    /* Walls cast no shadows (walls.h): a packet whose every ray lies
     * inside the walls is tested against the occluders alone. */
    const int active = (1 << n) - 1;
    int blocked;
    if (trace->walls != NULL && walls_segments8_inside(trace->walls, &queue->rays[0], active) == active) {
        job->counters->shadow_rays_inside_walls += (uint64_t)n;
        blocked = trace->occluders.any_hit8(trace->occluders.context, &queue->rays[0], active, job->counters);
    } else {
        blocked = trace->all.any_hit8(trace->all.context, &queue->rays[0], active, job->counters);
    }
    if (sc->sphere_count > 0)
        for (int left = active & ~blocked; left != 0; left &= left - 1) {
            int q = __builtin_ctz((unsigned)left);
            blocked |= (int)spheres_block_lane(sc, &queue->rays[0], q, job->counters) << q;
        }
    for (int q = 0; q < n; q++) {
        lane *l = &job->lanes[queue->lane[q]];
        bool through = !((blocked >> q) & 1);
        if (queue->sample_id[q] == l->sample_id) {
            if (through)
                l->radiance = vec3_add(l->radiance, queue->contribution[q]);
            l->unsettled--;
            continue;
        }
        if (through)
            l->waiting_radiance = vec3_add(l->waiting_radiance, queue->contribution[q]);
        if (--l->waiting_unsettled == 0) {
            settle(l, l->waiting_radiance, job);
            l->waiting = false;
        }
    }
    /* n is 8, or all of the queue: what is left moves up a whole packet */
    job->queued -= n;
    if (job->queued > 0) {
        memmove(queue->rays, queue->rays + 1, (size_t)((job->queued + LANES - 1) / LANES) * sizeof queue->rays[0]);
        memmove(queue->contribution, queue->contribution + n, (size_t)job->queued * sizeof queue->contribution[0]);
        memmove(queue->lane, queue->lane + n, (size_t)job->queued * sizeof queue->lane[0]);
        memmove(queue->sample_id, queue->sample_id + n, (size_t)job->queued * sizeof queue->sample_id[0]);
    }
}

/* (wide_lanes.h) */
void queue_push(row_job *job, int k, ray shadow, vec3 contribution)
{
    int q = job->queued++;
    rays8_set(&job->queue.rays[q / LANES], q % LANES, shadow);
    job->queue.contribution[q] = contribution;
    job->queue.lane[q] = k;
    job->queue.sample_id[q] = job->lanes[k].sample_id;
    job->lanes[k].unsettled++;
}

/* Settle the lane's waiting sample: its shadow rays were queued before
 * any of the current sample's, so tracing from the front of the queue
 * reaches them first, in packets as full as the queue allows. */
static void settle_waiting(lane *l, row_job *job)
{
    while (l->waiting && job->queued > 0)
        trace_queued(job, job->queued < RAYS8_LANES ? job->queued : RAYS8_LANES);
}

/* The sample's path is done: into the pixel's mean once its shadow rays
 * are traced, then the next sample or the next pixel. */
static void end_sample(lane *l, row_job *job)
{
    settle_waiting(l, job); /* the sample before it must reach the mean first */
    if (l->unsettled == 0) {
        settle(l, l->radiance, job);
    } else {
        l->waiting = true;
        l->waiting_unsettled = l->unsettled;
        l->waiting_radiance = l->radiance;
    }
    l->sample_id++;
    l->unsettled = 0;
    if (--l->samples_left > 0) {
        if (job->pt->sampler == PT_SAMPLER_SOBOL)
            sobol_pixel_next_sample(&l->sobol);
        start_sample(l, job);
        return;
    }
    settle_waiting(l, job); /* the pixel's last sample */
    image_set(job->mean, l->x, l->y,
              vec3_make((float)welford_mean(&l->channel[0]), (float)welford_mean(&l->channel[1]),
                        (float)welford_mean(&l->channel[2])));
    image_set(job->standard_error, l->x, l->y,
              vec3_make((float)welford_standard_error(&l->channel[0]), (float)welford_standard_error(&l->channel[1]),
                        (float)welford_standard_error(&l->channel[2])));
    start_pixel(l, job);
}

/* Lane k's random numbers for its light sample, and the point they pick:
 * false if there is no light to sample. The emitter is picked by power,
 * as chapter 09 picks it, or by the light tree for the lane's point and
 * normal; the point on it is uniform either way. */
static bool pick_light(row_job *job, lane *l, vertex_lanes *L, int k)
{
    const path_tracer *pt = job->pt;
    const pt_scene *sc = pt->scene;
    float u_pick = lane_float(l, pt), u1 = lane_float(l, pt), u2 = lane_float(l, pt);
    pt_light_sample x;
    if (job->lights != NULL) {
        vec3 p = vec3_make(L->p[0][k], L->p[1][k], L->p[2][k]), n = vec3_make(L->n[0][k], L->n[1][k], L->n[2][k]);
        if (!light_tree_sample_light(job->lights, sc, p, n, u_pick, u1, u2, &x))
            return false;
        if (twin_wrong == WIDE_TWIN_TREE_PDF_OF_POWER) /* the tests' wrong renderer: chapter 09's density */
            x.pdf_light = (x.emission.x + x.emission.y + x.emission.z) / 3.0f / (float)sc->emitter_power;
    } else {
        int light_material;
        if (!pt_scene_sample_emitter(sc, u_pick, u1, u2, &x.point, &x.point_error, &x.normal, &light_material))
            return false;
        x.emission = sc->materials[light_material].emission;
        x.pdf_light = job->pdf_area[light_material];
    }
    lanes_set(L->x_light, k, x.point);
    lanes_set(L->n_light, k, x.normal);
    lanes_set(L->le, k, x.emission);
    L->x_error[k] = x.point_error;
    L->pdf_area[k] = x.pdf_light;
    return true;
}

/* The roulette and the two numbers of the next direction, after the light
 * sample, drawn as shade() draws them: the lane's bit if the path may go on
 * (bounce_math then decides whether its f cos / pdf is black). */
static int roll_bounce(lane *l, const path_tracer *pt, vertex_lanes *L, int k, bsdf_kind kind)
{
    /* path_goes_on(): a glossy surface passes on glossy light, a diffuse one indirect light */
    if (l->depth + 2 > pt->max_depth || !(pt->effects & (kind == BSDF_GLOSSY ? EFFECT_GLOSSY : EFFECT_INDIRECT)))
        return 0;
    float p_rr = 1.0f;
    vec3 albedo = vec3_make(L->albedo[0][k], L->albedo[1][k], L->albedo[2][k]);
    vec3 throughput = vec3_make(L->throughput[0][k], L->throughput[1][k], L->throughput[2][k]);
    if (path_tracer_roulette(pt, l->depth, throughput, albedo, &p_rr) && lane_float(l, pt) >= p_rr)
        return 0;
    L->u_y[k] = lane_float(l, pt); /* shade()'s order */
    L->u_x[k] = lane_float(l, pt);
    L->rr_scale[k] = 1.0f / p_rr;
    return 1 << k;
}

/* ---- the cosine and MIS rungs (trace_iterative()) -------------------------------
 * The same steps in trace_iterative()'s order: the light sample (with the
 * power heuristic's weight on the MIS rung), the numbers of the next
 * direction, the bounce, and then the roulette on the throughput the
 * bounce left. */

/* The numbers of the next direction, after the light sample, as
 * trace_iterative() draws them: u_y, u_x, and on the MIS rung the lobe's
 * number that bsdf_sample() takes. The lane's bit if the path may go on
 * from here: within max_depth (bounce depth + 1; on the cosine rung the
 * next vertex's light sample, bounce depth + 2, must count too; on the MIS
 * rung the emission it finds is bounce depth + 1, the BSDF's share of this
 * vertex's direct light), and the effects ask for it. */
NOT_INLINED static int roll_bounce_iterative(lane *l, const path_tracer *pt, vertex_lanes *L, int k, bsdf_kind kind)
{
    bool mis = pt->integrator == PT_MIS;
    if (l->depth + 1 > pt->max_depth || (l->depth + 2 > pt->max_depth && !mis) ||
        !(pt->effects & (kind == BSDF_GLOSSY ? EFFECT_GLOSSY : EFFECT_INDIRECT)))
        return 0;
    L->u_y[k] = lane_float(l, pt); /* trace_iterative()'s order */
    L->u_x[k] = lane_float(l, pt);
    if (mis)
        L->u_lobe[k] = lane_float(l, pt);
    L->rr_scale[k] = 1.0f; /* the roulette comes after the bounce */
    return 1 << k;
}

/* The first hits of the active lanes: the triangles' (through the
 * tracer), then the spheres' lane by lane; the hit records in the lanes'
 * arrays, the materials, and the bits of the lanes hit on their front
 * (*front) and of those that hit a sphere (*spheres). Returns the bits of
 * the lanes hit. */
static int closest_hits(row_job *job, vertex_lanes *L, int active, int material[LANES], int *front, int *spheres)
{
    const pt_scene *sc = job->pt->scene;
    const wide_tracer *all = &job->trace->all;
    hits8 hits;
    int hit_lanes = sc->triangles.count > 0 ? all->closest_hit8(all->context, &L->ray, active, &hits, job->counters) : 0;
    int sphere_lanes = 0;
    hit_record sphere_hits[LANES];
    if (sc->sphere_count > 0)
        for (int left = active; left != 0; left &= left - 1) {
            int k = __builtin_ctz((unsigned)left);
            float t_max = (hit_lanes >> k) & 1 ? hits.t[k] : L->ray.t_max[k];
            sphere_lanes |= (int)sphere_hit_lane(sc, &L->ray, k, t_max, &sphere_hits[k], job->counters) << k;
        }
    int triangle_lanes = hit_lanes & ~sphere_lanes;
    for (int k = 0; k < LANES; k++)
        L->triangle[k] = (triangle_lanes >> k) & 1 ? hits.index[k] : -1;
    *front = 0;
#if WIDE_HAVE_AVX
    if (triangle_lanes != 0 && job->avx && !sc->triangles.vertex_normals)
        *front = hit_records_avx(sc, &hits, triangle_lanes, L, material); /* (writes every lane: first) */
    else
#endif
        for (int left = triangle_lanes; left != 0; left &= left - 1)
            *front |= hit_record_lane(sc, &hits, __builtin_ctz((unsigned)left), L, material);
    for (int left = sphere_lanes; left != 0; left &= left - 1) {
        int k = __builtin_ctz((unsigned)left);
        *front |= hit_record_set(sc, &sphere_hits[k], k, L, material);
    }
    *spheres = sphere_lanes;
    return hit_lanes | sphere_lanes;
}

/* The emission lane k's ray found on the front of an emitter, after the
 * camera: in full where no light sample counted it -- after a mirror or
 * glass, or on the cosine and MIS rungs an emitter the light table does
 * not hold (a sphere); on the MIS rung, after a BSDF sample, with the power
 * heuristic's weight against the light sample that could have found it
 * too, as trace_iterative() weighs it; else not at all (the light sample
 * at the vertex before counted it). */
NOT_INLINED static void emission_found(row_job *job, const vertex_lanes *L, int k, int material, bool sphere)
{
    const path_tracer *pt = job->pt;
    lane *l = &job->lanes[k];
    float weight = 1.0f;
    if (!l->emission_counts && (pt->integrator == PT_LECTURE || !sphere)) {
        if (pt->integrator != PT_MIS)
            return;
        vec3 p = vec3_make(L->p[0][k], L->p[1][k], L->p[2][k]), ng = vec3_make(L->ng[0][k], L->ng[1][k], L->ng[2][k]);
        vec3 wo = vec3_make(L->wo[0][k], L->wo[1][k], L->wo[2][k]);
        float pdf_area = job->pdf_area[material];
        if (job->lights != NULL) /* the pmf of the vertex that sampled: its point and normal */
            pdf_area = light_tree_pdf_area(job->lights, l->previous_point, l->previous_normal, L->triangle[k]);
        float pdf_light = light_pdf_from(l->previous_point, p, ng, wo, pdf_area); /* per steradian */
        if (twin_wrong != WIDE_TWIN_EMISSION_UNWEIGHTED)
            weight = power_heuristic(l->previous_pdf, pdf_light);
    }
    vec3 throughput = vec3_make(L->throughput[0][k], L->throughput[1][k], L->throughput[2][k]);
    vec3 le = pt->scene->materials[material].emission;
    l->radiance = vec3_add(l->radiance, vec3_scale(vec3_mul(throughput, le), weight));
}

/* What the rays found that needs no light sample, and what the lanes hit:
 * the environment for the lanes that left the scene; the emission at the
 * first hit (camera lanes) and after a mirror or glass; the lanes' bits by
 * material (*diffuse, *glossy, *delta). */
static void light_found(row_job *job, vertex_lanes *L, int active, int hit_lanes, int front, int spheres,
                        const int material[LANES], int *diffuse, int *glossy, int *delta)
{
    const pt_scene *sc = job->pt->scene;
    lane *lanes = job->lanes;
    /* Lane by lane, lowest first, only the lanes each part concerns:
     * looping over all eight and asking each would branch on random
     * answers. */
    for (int left = active & ~hit_lanes; left != 0; left &= left - 1) {
        int k = __builtin_ctz((unsigned)left); /* left the scene: the environment */
        vec3 throughput = vec3_make(L->throughput[0][k], L->throughput[1][k], L->throughput[2][k]);
        lanes[k].radiance = vec3_add(lanes[k].radiance, vec3_mul(throughput, sc->environment));
    }
    for (int left = job->camera & hit_lanes; left != 0; left &= left - 1) {
        int k = __builtin_ctz((unsigned)left); /* what the eye sees directly: the emission at the first hit */
        lanes[k].radiance = (front >> k) & 1 ? sc->materials[material[k]].emission : vec3_splat(0.0f);
        vec3 direction = vec3_make(L->ray.direction[0][k], L->ray.direction[1][k], L->ray.direction[2][k]);
        lanes_set(L->wo, k, vec3_normalize(vec3_neg(direction)));
        lanes[k].emission_counts = false;
    }
    /* the lanes whose emission may count: after the camera, on their front;
     * on the lecture rung only after a mirror or glass */
    const bool lecture = job->pt->integrator == PT_LECTURE;
    const int found = front & ~(job->camera & hit_lanes);
    job->camera &= ~active;
    *diffuse = *glossy = *delta = 0;
    for (int left = hit_lanes; left != 0; left &= left - 1) {
        int k = __builtin_ctz((unsigned)left);
        const pt_material *m = &sc->materials[material[k]];
        *diffuse |= (m->kind == BSDF_DIFFUSE) << k;
        *glossy |= (m->kind == BSDF_GLOSSY) << k;
        *delta |= bsdf_is_delta(m) << k;
        if ((found >> k) & 1 && (lanes[k].emission_counts || !lecture) && !vec3_is_black(m->emission))
            emission_found(job, L, k, material[k], (spheres >> k) & 1);
        lanes[k].emission_counts = false;
    }
}

/* Each lit lane's shadow ray joins the queue. Every surface lane writes its
 * entry at the end of the queue, and only a lit one moves the end on: no
 * branch on whether the light sample counted. Without shadows every light
 * sample counts at once. */
static void queue_light_samples(row_job *job, const vertex_lanes *L, int surface, int lit)
{
    lane *lanes = job->lanes;
    const int shadows = job->pt->effects & EFFECT_SHADOWS ? lit : 0;
    for (int left = surface; left != 0; left &= left - 1) {
        int k = __builtin_ctz((unsigned)left), q = job->queued, is_lit = (shadows >> k) & 1;
        rays8 *shadow = &job->queue.rays[q / LANES];
        for (int c = 0; c < 3; c++) {
            shadow->origin[c][q % LANES] = L->shadow_origin[c][k];
            shadow->direction[c][q % LANES] = L->shadow_direction[c][k];
        }
        shadow->t_min[q % LANES] = L->shadow_t_min[k]; /* ray_spawn_to's */
        shadow->t_max[q % LANES] = L->shadow_t_max[k];
        job->queue.contribution[q] = vec3_make(L->contribution[0][k], L->contribution[1][k], L->contribution[2][k]);
        job->queue.lane[q] = k;
        job->queue.sample_id[q] = lanes[k].sample_id;
        job->queued += is_lit;
        lanes[k].unsettled += is_lit;
    }
    job->counters->shadow_rays += (uint64_t)__builtin_popcount((unsigned)shadows);
    for (int left = lit & ~shadows; left != 0; left &= left - 1) {
        int k = __builtin_ctz((unsigned)left);
        lanes[k].radiance = vec3_add(lanes[k].radiance,
                                     vec3_make(L->contribution[0][k], L->contribution[1][k], L->contribution[2][k]));
    }
}

/* The glossy lanes' bounces (of `glossy`, those the roulette let go on)
 * and the mirrors' and glass's, kept aside: bounce_math_avx writes all
 * eight lanes. Returns the lanes that go on. */
static int bounces_aside(row_job *job, const vertex_lanes *L, int glossy, int delta, int front,
                         const int material[LANES], lane_bounce aside[LANES])
{
    const pt_material *materials = job->pt->scene->materials;
    int on = 0;
    for (int left = glossy; left != 0; left &= left - 1) {
        int k = __builtin_ctz((unsigned)left);
        const pt_material *m = &materials[material[k]];
        bool goes_on = job->pt->integrator == PT_LECTURE
                           ? bounce_surface_lane(L, k, m, &aside[k])
                           : bounce_iterative_lane(&job->lanes[k], job->pt, L, k, m, (front >> k) & 1, &aside[k],
                                                   job->counters);
        on |= (int)goes_on << k;
    }
    job->counters->indirect_rays += (uint64_t)__builtin_popcount((unsigned)on);
    for (int left = delta; left != 0; left &= left - 1) {
        int k = __builtin_ctz((unsigned)left);
        on |= (int)bounce_delta_lane(&job->lanes[k], job->pt, L, k, &materials[material[k]], (front >> k) & 1,
                                     &aside[k], job->counters)
              << k;
    }
    return on;
}

/* The diffuse lanes' bounces on the lecture rung (of `lanes`, those the
 * roulette let go on), in AVX or lane by lane: the lanes that go on. */
static int bounce_diffuse(row_job *job, vertex_lanes *L, int lanes, const int material[LANES])
{
#if WIDE_HAVE_AVX
    if (lanes != 0 && job->avx)
        return bounce_math_avx(L, lanes);
#endif
    int on = 0;
    for (int left = lanes; left != 0; left &= left - 1) {
        int k = __builtin_ctz((unsigned)left);
        on |= bounce_math_lane(L, k, &job->pt->scene->materials[material[k]]);
    }
    return on;
}

/* The same on the cosine and MIS rungs: the bounce (cosine-weighted), in
 * AVX or lane by lane, then each lane's roulette on its new throughput;
 * the vertex and the pdf the next ray was drawn with kept for the MIS
 * weight of the emission it finds. */
NOT_INLINED static int bounce_diffuse_iterative(row_job *job, vertex_lanes *L, int lanes, const int material[LANES])
{
    const path_tracer *pt = job->pt;
    bool mis = pt->integrator == PT_MIS;
    int on = 0;
#if WIDE_HAVE_AVX
    if (lanes != 0 && job->avx)
        on = bounce_cosine_avx(L, lanes, mis);
    else
#endif
        for (int left = lanes; left != 0; left &= left - 1) {
            int k = __builtin_ctz((unsigned)left);
            on |= bounce_cosine_lane(L, k, &pt->scene->materials[material[k]], mis);
        }
    for (int left = on; left != 0; left &= left - 1) {
        int k = __builtin_ctz((unsigned)left);
        lane *l = &job->lanes[k];
        vec3 throughput = vec3_make(L->throughput[0][k], L->throughput[1][k], L->throughput[2][k]);
        vec3 albedo = vec3_make(L->albedo[0][k], L->albedo[1][k], L->albedo[2][k]);
        if (!roulette_after_bounce(l, pt, &throughput, albedo)) {
            on &= ~(1 << k);
            continue;
        }
        lanes_set(L->throughput, k, throughput);
        l->previous_point = vec3_make(L->p[0][k], L->p[1][k], L->p[2][k]);
        l->previous_normal = vec3_make(L->n[0][k], L->n[1][k], L->n[2][k]);
        l->previous_pdf = L->pdf[k];
    }
    return on;
}

/* One row of the image, eight pixels at a time. */
static void render_row(row_job *job)
{
    const path_tracer *pt = job->pt;
    const pt_scene *sc = pt->scene;
    const bool lecture = pt->integrator == PT_LECTURE;
    /* sample_direct_light()'s with_mis: on the MIS rung, where the path may
     * go on by a BSDF sample that could find the same light (the effects) */
    const bool mis = pt->integrator == PT_MIS && twin_wrong != WIDE_TWIN_LIGHT_UNWEIGHTED;
    const bool mis_diffuse = mis && (pt->effects & EFFECT_INDIRECT), mis_glossy = mis && (pt->effects & EFFECT_GLOSSY);
    lane lanes[LANES];
    vertex_lanes L;
    job->lanes = lanes;
    job->vertex = &L;
    job->queued = 0;
    for (int k = 0; k < LANES; k++)
        start_pixel(&lanes[k], job);
    for (;;) {
        int active = 0;
        for (int k = 0; k < LANES; k++)
            active |= (lanes[k].x >= 0) << k;
        if (active == 0)
            return; /* every pixel written, so no shadow ray waits */
        int material[LANES], front = 0, spheres = 0, picked = 0, diffuse, glossy, delta;
        int hit_lanes = closest_hits(job, &L, active, material, &front, &spheres);
        light_found(job, &L, active, hit_lanes, front, spheres, material, &diffuse, &glossy, &delta);
        /* Diffuse lanes take the AVX route; glossy ones, mirrors and glass
         * chapter 09's BSDFs lane by lane. Each lane's random numbers, in
         * shade()'s order: the point on the light, then the roulette and
         * the next direction (trace_iterative()'s: the point on the light,
         * the next direction, and after the bounce the roulette). The
         * direction's do not depend on the light sample,
         * so they are drawn before its arithmetic, and the light's and the
         * bounce's arithmetic run back to back, where the processor
         * overlaps their long chains of divisions and square roots.
         * Mirrors and glass draw theirs in bounce_delta_lane. */
        const int surface = diffuse | glossy;
        int lit = 0, bounce = 0;
        for (int left = surface; left != 0; left &= left - 1) {
            int k = __builtin_ctz((unsigned)left);
            if (lanes[k].depth + 1 <= pt->max_depth && pick_light(job, &lanes[k], &L, k))
                picked |= 1 << k;
            bsdf_kind kind = sc->materials[material[k]].kind;
            bounce |= lecture ? roll_bounce(&lanes[k], pt, &L, k, kind)
                              : roll_bounce_iterative(&lanes[k], pt, &L, k, kind);
        }
#if WIDE_HAVE_AVX
        if ((picked & diffuse) != 0 && job->avx)
            lit = light_math_avx(&L, picked & diffuse, mis_diffuse); /* (writes every lane: first) */
        else
#endif
            for (int left = picked & diffuse; left != 0; left &= left - 1) {
                int k = __builtin_ctz((unsigned)left);
                lit |= light_math_lane(&L, k, &sc->materials[material[k]], mis_diffuse);
            }
        for (int left = picked & glossy; left != 0; left &= left - 1) {
            int k = __builtin_ctz((unsigned)left);
            lit |= light_math_lane(&L, k, &sc->materials[material[k]], mis_glossy);
        }
        lane_bounce aside[LANES];
        int aside_on = bounces_aside(job, &L, bounce & glossy, delta, front, material, aside);
        queue_light_samples(job, &L, surface, lit);
        if (sc->point_light_count > 0) /* lights without area: before the bounce replaces wo and throughput */
            for (int left = surface; left != 0; left &= left - 1) {
                int k = __builtin_ctz((unsigned)left);
                if (lanes[k].depth + 1 <= pt->max_depth)
                    point_lights_lane(job, &L, k, &sc->materials[material[k]]);
            }
        bounce = lecture ? bounce_diffuse(job, &L, bounce & diffuse, material)
                         : bounce_diffuse_iterative(job, &L, bounce & diffuse, material);
        job->counters->indirect_rays += (uint64_t)__builtin_popcount((unsigned)bounce);
        for (int left = aside_on; left != 0; left &= left - 1) { /* the lanes kept aside, back */
            int k = __builtin_ctz((unsigned)left);
            rays8_set(&L.ray, k, aside[k].next);
            lanes_set(L.throughput, k, aside[k].throughput);
            lanes_set(L.wo, k, aside[k].wo);
            lanes[k].emission_counts = (delta >> k) & 1;
        }
        bounce |= aside_on;
        /* The shadow rays wait until there are eight: a light sample that
         * faces away needs none, so one step's would fill a packet a little
         * over half, and cost as much as a full one. */
        while (job->queued >= LANES)
            trace_queued(job, LANES);
        /* the next ray, from this vertex, or the path ends */
        for (int k = 0; k < LANES; k++)
            lanes[k].depth += (bounce >> k) & 1;
        for (int left = active & ~bounce; left != 0; left &= left - 1)
            end_sample(&lanes[__builtin_ctz((unsigned)left)], job);
    }
}

/* Room for the shadow rays of a row (shadow_queue). */
static shadow_queue queue_make(const pt_scene *sc)
{
    shadow_queue q;
    q.capacity = LANES * (2 + sc->point_light_count);
    /* the packets as the kernels load them: 32-byte aligned */
    size_t bytes = (size_t)(q.capacity / LANES) * sizeof *q.rays;
    q.rays = aligned_alloc(_Alignof(rays8), bytes);
    if (q.rays == NULL) {
        fprintf(stderr, "out of memory (%zu bytes for shadow rays)\n", bytes);
        exit(1);
    }
    q.contribution = memory_allocate((size_t)q.capacity, sizeof *q.contribution);
    q.lane = memory_allocate((size_t)q.capacity, sizeof *q.lane);
    q.sample_id = memory_allocate((size_t)q.capacity, sizeof *q.sample_id);
    return q;
}

static void queue_free(shadow_queue *q)
{
    free(q->rays);
    free(q->contribution);
    free(q->lane);
    free(q->sample_id);
}

bool render_estimate_wide_traced(const path_tracer *pt, const wide_scene_tracers *trace, const camera *cam, int spp,
                                 uint64_t seed, int threads, estimate_image *out)
{
    if (!path_tracer_wide_supported(pt, NULL, 0) || spp < 1)
        return false;
    estimate_image e;
    e.mean = image_make(cam->width, cam->height);
    e.standard_error = image_make(cam->width, cam->height);
    e.spp = spp;
    memset(&e.counters, 0, sizeof e.counters);
    if (threads <= 0)
        threads = omp_get_max_threads();
    const bool avx = wide_avx_runs();
    const pt_scene *sc = pt->scene;
    float *pdf_area = memory_allocate((size_t)(sc->material_count > 0 ? sc->material_count : 1), sizeof(float));
    for (int k = 0; k < sc->material_count && sc->emitter_count > 0; k++)
        pdf_area[k] = pt_scene_emitter_pdf_area(sc, k);
    double start = timer_seconds();
    light_tree tree;
    bool built;
    const light_tree *lights = lights_for(sc, trace, &tree, &built);
    /* Each row is one job, its pixels' streams its own: the same image
     * for any number of threads and any order of rows. */
#pragma omp parallel num_threads(threads)
    {
        ray_counters mine = {0};
        shadow_queue queue = queue_make(sc);
#pragma omp for schedule(dynamic, 1)
        for (int y = 0; y < cam->height; y++) {
            row_job job = {.pt = pt, .cam = cam, .spp = spp, .seed = seed, .mean = &e.mean,
                           .standard_error = &e.standard_error, .y = y, .counters = &mine, .queue = queue,
                           .trace = trace, .avx = avx, .pdf_area = pdf_area, .lights = lights};
            render_row(&job);
        }
        queue_free(&queue);
#pragma omp critical(render_wide_counters)
        counters_add(&e.counters, &mine);
    }
    e.seconds = timer_seconds() - start;
    if (built)
        light_tree_free(&tree);
    free(pdf_area);
    *out = e;
    return true;
}

bool render_estimate_wide(const path_tracer *pt, const camera *cam, int spp, uint64_t seed, int threads,
                          estimate_image *out)
{
    wide_scene_tracers trace = wide_scene_tracers_for(pt->scene);
    return render_estimate_wide_traced(pt, &trace, cam, spp, seed, threads, out);
}

double render_estimate_wide_pilot(const path_tracer *pt, const camera *cam, int spp, uint64_t seed, int pixels)
{
    if (!path_tracer_wide_supported(pt, NULL, 0) || spp < 1 || pixels < LANES)
        return 0.0;
    /* Runs of eight neighbouring pixels (one packet of lanes) spread over
     * the image, at the full spp, on one thread, into images of their own:
     * the render's own rows, cut short. */
    wide_scene_tracers trace = wide_scene_tracers_for(pt->scene);
    image mean = image_make(cam->width, cam->height), standard_error = image_make(cam->width, cam->height);
    float *pdf_area = memory_allocate((size_t)(pt->scene->material_count > 0 ? pt->scene->material_count : 1),
                                      sizeof(float));
    for (int k = 0; k < pt->scene->material_count && pt->scene->emitter_count > 0; k++)
        pdf_area[k] = pt_scene_emitter_pdf_area(pt->scene, k);
    shadow_queue queue = queue_make(pt->scene);
    ray_counters ignored = {0};
    light_tree tree;
    bool built;
    const light_tree *lights = lights_for(pt->scene, &trace, &tree, &built);
    long total = (long)cam->width * cam->height;
    int runs = pixels / LANES, done = 0;
    double start = timer_seconds();
    for (int r = 0; r < runs; r++) {
        /* run r in row (r + 1/2) h / runs, across the width by the golden
         * ratio's multiples: never all down one column (an image's edge is
         * often the empty background, far cheaper than the middle) */
        double across = fmod(0.6180339887498949 * (r + 0.5), 1.0);
        int y = (int)(((double)r + 0.5) * cam->height / runs);
        int x = (int)(across * (cam->width > LANES ? cam->width - LANES : 0));
        row_job job = {.pt = pt, .cam = cam, .spp = spp, .seed = seed, .mean = &mean, .standard_error = &standard_error,
                       .y = y, .next_x = x, .x_end = x + LANES < cam->width ? x + LANES : cam->width,
                       .counters = &ignored, .queue = queue, .trace = &trace, .avx = wide_avx_runs(),
                       .pdf_area = pdf_area, .lights = lights};
        done += job.x_end - x;
        render_row(&job);
    }
    double seconds = timer_seconds() - start;
    queue_free(&queue);
    if (built)
        light_tree_free(&tree);
    free(pdf_area);
    image_free(&mean);
    image_free(&standard_error);
    return done > 0 ? seconds / done * (double)total : 0.0;
}


