/* path_tracer_wide.c -- eight paths at a time (path_tracer_wide.h). */
#include "09-path-tracing/path_tracer_wide.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <string.h>

#include "06-bvh/flat.h"
#include "08-monte-carlo/sampling.h"
#include "09-path-tracing/bsdf.h"
#include "explain.h"
#include "stats.h"
#include "timer.h"

enum { LANES = FLAT_LANES };

bool path_tracer_wide_supported(const path_tracer *pt, char *why, size_t why_size)
{
    const pt_scene *sc = pt->scene;
    const char *reason = NULL;
    if (pt->integrator != PT_LECTURE)
        reason = "only the lecture rung";
    else if (explain_on())
        reason = "--explain follows one path";
    else if (sc->sphere_count > 0 || sc->point_light_count > 0)
        reason = "triangles and area lights only (no spheres, no point lights)";
    else if (sc->triangles.count == 0 || !flat_is(sc->bvh))
        reason = "the scene's triangles are not a flat set (more than 64)";
    for (int k = 0; k < sc->material_count && reason == NULL; k++)
        if (sc->materials[k].kind != BSDF_DIFFUSE)
            reason = "diffuse materials only";
    if (reason != NULL && why != NULL)
        snprintf(why, why_size, "%s", reason);
    return reason == NULL;
}

/* One lane: a pixel, the path of its current sample, and what that path has
 * gathered. */
typedef struct {
    int x, y, samples_left; /* x < 0: idle */
    pcg32 rng;
    welford channel[3];
    ray r;             /* the ray to trace next */
    bool camera;       /* r is the camera ray */
    int depth;         /* bounces before the vertex r will hit */
    vec3 wo;           /* the direction back along r, for that vertex */
    vec3 radiance;     /* gathered so far */
    vec3 throughput;   /* the product of f cos / pdf / P_RR before that vertex */
    vec3 pending;      /* a light sample's contribution, if its shadow ray gets through */
    bool goes_on;      /* after this vertex: trace r (set to the next ray) */
    /* Shadow rays wait in the row's queue until there are eight (below):
     * how many of this sample's do, and the sample before it, ended but
     * still waiting for some (at most one: it is settled before the next
     * one ends, so samples reach the pixel's mean in order). */
    int sample_id, unsettled;
    bool waiting;
    int waiting_unsettled;
    vec3 waiting_radiance;
} lane;

/* A shadow ray waiting in the queue, and what it brings if it gets through. */
typedef struct {
    ray r;
    vec3 contribution;
    int lane, sample_id;
} queued_shadow;

typedef struct {
    const path_tracer *pt;
    const camera *cam;
    int spp;
    uint64_t seed;
    image *mean, *standard_error;
    int y, next_x; /* the row, and its next pixel not yet given to a lane */
    ray_counters *counters;
    lane *lanes;
    queued_shadow queue[2 * FLAT_LANES];
    int queued;
} row_job;

static bool is_black(vec3 c) { return c.x == 0.0f && c.y == 0.0f && c.z == 0.0f; }

/* A lane's next camera sample, drawn as render_pixel() draws it (jitter
 * within the pixel: two numbers). */
static void start_sample(lane *l, const row_job *job)
{
    float px = (float)l->x + pcg32_float(&l->rng), py = (float)l->y + pcg32_float(&l->rng);
    l->r = camera_ray(job->cam, px, py);
    job->counters->camera_rays++;
    l->camera = true;
    l->depth = 0;
    l->radiance = vec3_splat(0.0f);
    l->throughput = vec3_splat(1.0f);
}

/* The lane's next pixel of the row, or idle. */
static void start_pixel(lane *l, row_job *job)
{
    if (job->next_x >= job->cam->width) {
        l->x = -1;
        return;
    }
    l->x = job->next_x++;
    l->y = job->y;
    l->samples_left = job->spp;
    l->sample_id = 0;
    l->unsettled = 0;
    l->waiting = false;
    l->rng = pcg32_for_pixel(job->seed, (uint64_t)l->y * (uint64_t)job->cam->width + (uint64_t)l->x);
    memset(l->channel, 0, sizeof l->channel);
    start_sample(l, job);
}

/* A sample's radiance into its pixel's mean (NaN and Inf dropped, as
 * render_pixel() does). */
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

/* Trace the first n queued shadow rays (n <= 8) as one packet, and give
 * each that gets through its contribution, to the sample it belongs to:
 * the lane's current one, or the one before, which is settled once its
 * last shadow ray is traced. */
static void trace_queued(row_job *job, int n)
{
    const pt_scene *sc = job->pt->scene;
    ray rays[FLAT_LANES];
    bool blocked[FLAT_LANES];
    if (n <= 0)
        return;
    for (int k = 0; k < n; k++)
        rays[k] = job->queue[k].r;
    flat_any_hit8(sc->bvh, rays, (1 << n) - 1, blocked, job->counters);
    for (int k = 0; k < n; k++) {
        const queued_shadow *q = &job->queue[k];
        lane *l = &job->lanes[q->lane];
        if (q->sample_id == l->sample_id) {
            if (!blocked[k])
                l->radiance = vec3_add(l->radiance, q->contribution);
            l->unsettled--;
            continue;
        }
        if (!blocked[k])
            l->waiting_radiance = vec3_add(l->waiting_radiance, q->contribution);
        if (--l->waiting_unsettled == 0) {
            settle(l, l->waiting_radiance, job);
            l->waiting = false;
        }
    }
    job->queued -= n;
    memmove(job->queue, job->queue + n, (size_t)job->queued * sizeof job->queue[0]);
}

/* Settle the lane's waiting sample: its shadow rays were queued before
 * any of the current sample's, so tracing from the front of the queue
 * reaches them first, in packets as full as the queue allows. */
static void settle_waiting(lane *l, row_job *job)
{
    while (l->waiting && job->queued > 0)
        trace_queued(job, job->queued < FLAT_LANES ? job->queued : FLAT_LANES);
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

/* What shade() of path_tracer.c does at one vertex, for the lecture rung
 * on diffuse surfaces, in the same order and with the same random numbers:
 * the light sample (its shadow ray built into *shadow, its contribution
 * into l->pending, times the throughput), then the roulette and the next
 * direction (l->r, l->goes_on). Returns whether a shadow ray is to be
 * traced. */
static bool shade_vertex(lane *l, const hit_record *hit, const path_tracer *pt, ray *shadow, ray_counters *counters)
{
    const pt_scene *sc = pt->scene;
    const pt_material *m = &sc->materials[hit->material_id];
    vec3 n = hit->normal_shading;
    bool needs_shadow = false;
    l->goes_on = false;
    l->pending = vec3_splat(0.0f);
    if (l->depth + 1 <= pt->max_depth) {
        /* sample_direct_light(), with_mis false */
        vec3 x_light, n_light;
        int light_material;
        float u_pick = pcg32_float(&l->rng), u1 = pcg32_float(&l->rng), u2 = pcg32_float(&l->rng);
        if (pt_scene_sample_emitter(sc, u_pick, u1, u2, &x_light, &n_light, &light_material)) {
            vec3 to_light = vec3_sub(x_light, hit->point);
            float distance2 = vec3_length_squared(to_light);
            vec3 wi = vec3_scale(to_light, 1.0f / sqrtf(distance2));
            float cos_theta = vec3_dot(n, wi);
            float cos_theta_light = -vec3_dot(n_light, wi);
            if (cos_theta_light > 0.0f && cos_theta > 0.0f) {
                vec3 f = bsdf_eval(m, n, l->wo, wi);
                if (!is_black(f)) {
                    float pdf_light = distance2 * pt_scene_emitter_pdf_area(sc, light_material) / cos_theta_light;
                    vec3 le = sc->materials[light_material].emission;
                    vec3 contribution = vec3_scale(vec3_mul(le, f), cos_theta / pdf_light * 1.0f);
                    l->pending = vec3_mul(l->throughput, contribution);
                    if (pt->effects & EFFECT_SHADOWS) {
                        *shadow = ray_spawn_to(hit->point, hit->normal_geometric, x_light, n_light);
                        counters->shadow_rays++;
                        needs_shadow = true;
                    } else {
                        l->radiance = vec3_add(l->radiance, l->pending);
                    }
                }
            }
        }
    }
    if (l->depth + 2 > pt->max_depth || !(pt->effects & EFFECT_INDIRECT))
        return needs_shadow;
    float p_rr = pt->russian_roulette == RR_OFF ? 1.0f : pt->rr_probability;
    if (pt->russian_roulette != RR_OFF && pcg32_float(&l->rng) >= p_rr)
        return needs_shadow;
    float u_y = pcg32_float(&l->rng), u_x = pcg32_float(&l->rng); /* shade()'s order */
    vec3 local = sample_uniform_hemisphere(vec2_make(u_x, u_y));
    vec3 wi = frame_to_world(n, local);
    float pdf = uniform_hemisphere_pdf();
    vec3 weight = vec3_scale(bsdf_eval(m, n, l->wo, wi), local.z / pdf);
    if (is_black(weight))
        return needs_shadow;
    counters->indirect_rays++;
    l->r = ray_spawn(hit->point, hit->normal_geometric, wi);
    l->wo = vec3_neg(wi);
    l->throughput = vec3_scale(vec3_mul(l->throughput, weight), 1.0f / p_rr);
    l->goes_on = true;
    return needs_shadow;
}

/* One row of the image, eight pixels at a time. */
static void render_row(row_job *job)
{
    const path_tracer *pt = job->pt;
    const pt_scene *sc = pt->scene;
    lane lanes[LANES];
    job->lanes = lanes;
    job->queued = 0;
    for (int k = 0; k < LANES; k++)
        start_pixel(&lanes[k], job);
    for (;;) {
        int active = 0;
        ray rays[LANES];
        for (int k = 0; k < LANES; k++) {
            rays[k] = lanes[k].r;
            active |= (lanes[k].x >= 0) << k;
        }
        if (active == 0)
            return; /* every pixel written, so no shadow ray waits */
        hit_record hits[LANES];
        bool found[LANES];
        flat_closest_hit8(sc->bvh, rays, active, hits, found, job->counters);
        for (int k = 0; k < LANES; k++) {
            lane *l = &lanes[k];
            if (!((active >> k) & 1))
                continue;
            if (!found[k]) { /* left the scene: the environment */
                l->radiance = vec3_add(l->radiance, vec3_mul(l->throughput, sc->environment));
                l->goes_on = false;
                continue;
            }
            if (l->camera) { /* what the eye sees directly: the emission at the first hit */
                const pt_material *m = &sc->materials[hits[k].material_id];
                l->radiance = hits[k].front_face ? m->emission : vec3_splat(0.0f);
                l->wo = vec3_normalize(vec3_neg(l->r.direction));
                l->camera = false;
            }
            ray shadow;
            if (shade_vertex(l, &hits[k], pt, &shadow, job->counters)) {
                job->queue[job->queued++] = (queued_shadow){shadow, l->pending, k, l->sample_id};
                l->unsettled++;
            }
        }
        /* The shadow rays wait until there are eight: a light sample that
         * faces away needs none, so one step's would fill a packet a little
         * over half, and cost as much as a full one. */
        while (job->queued >= LANES)
            trace_queued(job, LANES);
        for (int k = 0; k < LANES; k++) {
            lane *l = &lanes[k];
            if (!((active >> k) & 1))
                continue;
            if (l->goes_on)
                l->depth++;
            else
                end_sample(l, job);
        }
    }
}

bool render_estimate_wide(const path_tracer *pt, const camera *cam, int spp, uint64_t seed, int threads,
                          estimate_image *out)
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
    double start = timer_seconds();
#pragma omp parallel num_threads(threads)
    {
        ray_counters mine = {0};
#pragma omp for schedule(dynamic, 1)
        for (int y = 0; y < cam->height; y++) {
            row_job job = {.pt = pt, .cam = cam, .spp = spp, .seed = seed, .mean = &e.mean,
                           .standard_error = &e.standard_error, .y = y, .counters = &mine};
            render_row(&job);
        }
#pragma omp critical(render_wide_counters)
        counters_add(&e.counters, &mine);
    }
    e.seconds = timer_seconds() - start;
    *out = e;
    return true;
}
