/* path_tracer_wide.c -- eight paths at a time (path_tracer_wide.h). */
#include "13-production/path_tracer_wide.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "13-production/fast_sincos.h"
#include "13-production/rays8.h"
#include "13-production/walls.h"
#include "13-production/wide_trace.h"
#include "08-monte-carlo/sampling.h"
#include "09-path-tracing/bsdf.h"
#include "09-path-tracing/light_transport.h"
#include "13-production/sobol_pixel.h"
#include "explain.h"
#include "memory.h"
#include "stats.h"
#include "timer.h"

#include "13-production/spawn_avx.h"

/* The lanes' arithmetic in AVX needs AVX2 for the hit records' gathers
 * (spawn_avx.h's target); without it, lane by lane. */
#define WIDE_HAVE_AVX SPAWN_HAVE_AVX2

enum { LANES = RAYS8_LANES };

/* On the functions only the cosine and MIS rungs call from render_row:
 * inlined, they grew it past what the compiler inlines into it, and left
 * the light's pick (pt_scene_sample_emitter) a call at every step of every
 * lane of every rung. */
#define NOT_INLINED __attribute__((noinline))

/* path_tracer_wide_use_avx(): the lanes' arithmetic in AVX2 where the
 * processor has it, or lane by lane (the same bits; for the tests). */
static bool use_avx = true;
void path_tracer_wide_use_avx(bool on) { use_avx = on; }

/* path_tracer_wide_twin(): the tests' wrong renderers */
static wide_twin twin_wrong = WIDE_TWIN_NONE;
void path_tracer_wide_twin(wide_twin twin) { twin_wrong = twin; }

/* The AVX kernels' constants, as chapter 08's sampling.c and chapter 09's
 * bsdf.c round them: cosine_hemisphere_pdf()'s 1 / pi, and the Lambertian
 * f = rho x (1 / pi). */
static const float INV_PI_F = (float)(1.0 / PI);
static const float DIFFUSE_INV_PI_F = 1.0f / (float)PI;

static bool wide_cpu_has_avx2(void)
{
#if WIDE_HAVE_AVX
    return __builtin_cpu_supports("avx2");
#else
    return false;
#endif
}

bool path_tracer_wide_supported(const path_tracer *pt, char *why, size_t why_size)
{
    const char *reason = NULL;
    if (explain_on())
        reason = "--explain follows one path";
    else if (pt->scene->triangles.count > 0 && pt->scene->bvh == NULL)
        reason = "the scene's triangles are in no structure (pt_scene_finish)";
    if (reason != NULL && why != NULL)
        snprintf(why, why_size, "%s", reason);
    return reason == NULL;
}

wide_scene_tracers wide_scene_tracers_for(const pt_scene *sc)
{
    wide_scene_tracers t;
    const accel *a = sc->bvh;
    bool walls = a != NULL && walls_is(a);
    t.all = wide_tracer_for(walls ? walls_all(a) : a);
    t.walls = walls && walls_found(a) ? a : NULL;
    t.occluders = wide_tracer_for(t.walls != NULL ? walls_occluders(a) : NULL);
    return t;
}

/* The eight lanes' paths and vertices, structure of arrays, so that the
 * AVX code reads and writes eight lanes per instruction, and nothing is
 * copied between steps. What each path carries from vertex to vertex: the
 * ray to trace next, the direction back along it (wo) and the throughput
 * before the vertex it will hit. What light_math reads at a vertex (the
 * hit point p and its error bound, geometric normal ng, shading normal n
 * and albedo, from the hit records; wo and throughput; the point on the
 * light, its error bound, normal, radiance and pdf per unit area) and
 * writes (each lane's contribution, times its throughput, and its shadow
 * ray); what bounce_math reads (p and its error bound, ng, n, wo, albedo,
 * throughput again; the hemisphere's two numbers, and the MIS rung's
 * lobe number; 1 / P_RR) and writes (the next ray, its wo, and the
 * throughput after the bounce, in place; on the cosine and MIS rungs, the
 * direction's pdf). bounce_math_avx writes all eight lanes; a lane whose
 * path ends there is given its next camera ray (start_sample) before the
 * next step reads it. */
typedef struct {
    rays8 ray;
    _Alignas(32) float wo[3][LANES], throughput[3][LANES];
    _Alignas(32) float p[3][LANES], p_error[LANES], ng[3][LANES], n[3][LANES], albedo[3][LANES];
    _Alignas(32) float x_light[3][LANES], x_error[LANES], n_light[3][LANES], le[3][LANES], pdf_area[LANES];
    _Alignas(32) float contribution[3][LANES], shadow_origin[3][LANES], shadow_direction[3][LANES];
    _Alignas(32) float shadow_t_min[LANES], shadow_t_max[LANES];
    _Alignas(32) float u_x[LANES], u_y[LANES], u_lobe[LANES], rr_scale[LANES];
    _Alignas(32) float pdf[LANES]; /* the cosine and MIS rungs: the pdf the next direction was drawn with */
} vertex_lanes;

/* One lane: a pixel, the path of its current sample, and what that path has
 * gathered. */
typedef struct {
    int x, y, samples_left; /* x < 0: idle */
    pcg32 rng;
    welford channel[3];
    int depth;         /* bounces before the vertex its next ray (vertex_lanes) will hit */
    vec3 radiance;     /* gathered so far */
    /* Shadow rays wait in the row's queue until there are eight (below):
     * how many of this sample's do, and the sample before it, ended but
     * still waiting for some (at most one: it is settled before the next
     * one ends, so samples reach the pixel's mean in order). */
    int sample_id, unsettled;
    bool waiting;
    int waiting_unsettled;
    vec3 waiting_radiance;
    /* --sampler sobol: the pixel's points, the sample's the current one
     * (its rng is the lane's) */
    sobol_pixel sobol;
    /* Does the emission the next ray meets count (at the camera, and after
     * a mirror or glass: no light sample at that vertex counted it)? */
    bool emission_counts;
    /* The cosine and MIS rungs: the vertex the next ray leaves, and the
     * pdf its direction was drawn with (trace_iterative's previous_point,
     * previous_pdf), for the MIS weight of the emission it finds. */
    vec3 previous_point;
    float previous_pdf;
} lane;

/* Shadow rays waiting to be traced, eight by eight, and what each brings
 * if it gets through: entry q is lane q % 8 of rays[q / 8]. Fewer than 8
 * wait between steps, and a step adds at most 8 for the light samples and
 * 8 per point light: capacity entries, a multiple of 8 (queue_make). */
typedef struct {
    rays8 *rays;
    vec3 *contribution;
    int *lane, *sample_id;
    int capacity;
} shadow_queue;

typedef struct {
    const path_tracer *pt;
    const camera *cam;
    int spp;
    uint64_t seed;
    image *mean, *standard_error;
    int y, next_x; /* the row, and its next pixel not yet given to a lane */
    int x_end;     /* the row's end (0: the image's width) */
    ray_counters *counters;
    lane *lanes;
    vertex_lanes *vertex; /* render_row's */
    shadow_queue queue;
    int queued;
    int camera; /* the lanes whose next ray (vertex_lanes ray) is a camera ray */
    const wide_scene_tracers *trace; /* the triangles' structures, eight rays at a time */
    bool avx; /* light_math_avx and bounce_math_avx, where the processor has AVX2 */
    /* pt_scene_emitter_pdf_area() of each material, worked out once: a
     * division in double at every light sample was 5 % of the time */
    const float *pdf_area;
} row_job;


path_tracer production_path_tracer_defaults(const pt_scene *scene)
{
    path_tracer pt = path_tracer_defaults(scene);
    pt.sampler = PRODUCTION_SAMPLER;
    pt.russian_roulette = PRODUCTION_ROULETTE;
    pt.integrator = PRODUCTION_INTEGRATOR;
    return pt;
}

/* The lane's next number, from where chapter 09's path tracer takes it
 * (path_tracer.h, --sampler): the pixel's stream, or the sample's point of
 * the pixel's scrambled Sobol sequence. */
static inline float lane_float(lane *l, const path_tracer *pt)
{
    return pt->sampler == PT_SAMPLER_SOBOL ? sobol_pixel_next(&l->sobol) : pcg32_float(&l->rng);
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

/* Lane k's shadow ray at the end of the queue, with what it brings. */
static void queue_push(row_job *job, int k, ray shadow, vec3 contribution)
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

/* ---- one vertex of eight paths ------------------------------------------------
 * What shade() of path_tracer.c does at a vertex, for the lecture rung on
 * diffuse surfaces, in the same order and with the same random numbers,
 * in five parts: the hit records are made for all eight lanes at once
 * (hit_records, below); each lane picks its point on a light (pick_light);
 * the light sample's arithmetic runs for all eight at once (light_math);
 * each lane then queues its shadow ray and draws the roulette and the two
 * numbers of its next direction (roll_bounce); the bounce's arithmetic runs
 * for all eight at once (bounce_math). */


static void lanes_set(float v[3][LANES], int k, vec3 x)
{
    v[0][k] = x.x;
    v[1][k] = x.y;
    v[2][k] = x.z;
}

/* Lane k's random numbers for its light sample, and the point they pick:
 * false if there is no light to sample. */
static bool pick_light(lane *l, const path_tracer *pt, const float *pdf_area, vertex_lanes *L, int k)
{
    const pt_scene *sc = pt->scene;
    vec3 x_light, n_light;
    int light_material;
    float u_pick = lane_float(l, pt), u1 = lane_float(l, pt), u2 = lane_float(l, pt);
    if (!pt_scene_sample_emitter(sc, u_pick, u1, u2, &x_light, &L->x_error[k], &n_light, &light_material))
        return false;
    lanes_set(L->x_light, k, x_light);
    lanes_set(L->n_light, k, n_light);
    lanes_set(L->le, k, sc->materials[light_material].emission);
    L->pdf_area[k] = pdf_area[light_material];
    return true;
}

#define AT(v) vec3_make(L->v[0][k], L->v[1][k], L->v[2][k])

/* Lane k's hit, as chapter 09's pieces read it (light_transport.h): the
 * point, its error bound, the geometric and shading normals. */
static hit_record lane_hit(const vertex_lanes *L, int k)
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
static int light_math_lane(vertex_lanes *L, int k, const pt_material *m, bool mis)
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
#undef AT

#if WIDE_HAVE_AVX
/* For light_math_avx and bounce_math_avx: a field of L for eight lanes, and
 * vec3_dot()'s sum, in its order. */
#define LOAD3(v, i) _mm256_load_ps(L->v[i])
#define DOT(ax, ay, az, bx, by, bz)                                                                          \
    _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(ax, bx), _mm256_mul_ps(ay, by)), _mm256_mul_ps(az, bz))

/* light_math_lane() of the diffuse lanes of `lanes`, eight per AVX
 * instruction: direct_light_solid_angle()'s operations, with bsdf_eval()
 * and bsdf_pdf() of a diffuse surface, in the same order (sqrt and
 * division are exact in IEEE, so every lane gets the very bits of the
 * scalar function; tests/test_ch13.c compares them value by value). */
SPAWN_TARGET static int light_math_avx(vertex_lanes *L, int lanes, bool mis)
{
    const __m256 zero = _mm256_setzero_ps();
    __m256 tx = _mm256_sub_ps(LOAD3(x_light, 0), LOAD3(p, 0)), ty = _mm256_sub_ps(LOAD3(x_light, 1), LOAD3(p, 1)),
           tz = _mm256_sub_ps(LOAD3(x_light, 2), LOAD3(p, 2));
    __m256 distance2 = DOT(tx, ty, tz, tx, ty, tz);
    __m256 inverse = _mm256_div_ps(_mm256_set1_ps(1.0f), _mm256_sqrt_ps(distance2));
    __m256 wx = _mm256_mul_ps(tx, inverse), wy = _mm256_mul_ps(ty, inverse), wz = _mm256_mul_ps(tz, inverse);
    __m256 nx = LOAD3(n, 0), ny = LOAD3(n, 1), nz = LOAD3(n, 2);
    __m256 cos_theta = DOT(nx, ny, nz, wx, wy, wz);
    __m256 cos_theta_light = _mm256_sub_ps(zero, DOT(LOAD3(n_light, 0), LOAD3(n_light, 1), LOAD3(n_light, 2), wx, wy, wz));
    __m256 cos_wo = DOT(nx, ny, nz, LOAD3(wo, 0), LOAD3(wo, 1), LOAD3(wo, 2));
    __m256 ok = _mm256_and_ps(_mm256_cmp_ps(cos_theta_light, zero, _CMP_GT_OQ), _mm256_cmp_ps(cos_theta, zero, _CMP_GT_OQ));
    ok = _mm256_and_ps(ok, _mm256_cmp_ps(cos_wo, zero, _CMP_GT_OQ));
    const __m256 inv_pi = _mm256_set1_ps(DIFFUSE_INV_PI_F);
    __m256 fx = _mm256_mul_ps(LOAD3(albedo, 0), inv_pi), fy = _mm256_mul_ps(LOAD3(albedo, 1), inv_pi),
           fz = _mm256_mul_ps(LOAD3(albedo, 2), inv_pi);
    __m256 black = _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(fx, zero, _CMP_EQ_OQ), _mm256_cmp_ps(fy, zero, _CMP_EQ_OQ)),
                                 _mm256_cmp_ps(fz, zero, _CMP_EQ_OQ));
    ok = _mm256_andnot_ps(black, ok);
    __m256 pdf_light = _mm256_div_ps(_mm256_mul_ps(distance2, _mm256_load_ps(L->pdf_area)), cos_theta_light);
    __m256 scale = _mm256_div_ps(cos_theta, pdf_light);
    if (mis) { /* power_heuristic(pdf_light, cos(theta) / pi); without it the weight is 1, and x 1 changes no bit */
        __m256 pdf_bsdf = _mm256_mul_ps(cos_theta, _mm256_set1_ps(INV_PI_F));
        __m256 a2 = _mm256_mul_ps(pdf_light, pdf_light), b2 = _mm256_mul_ps(pdf_bsdf, pdf_bsdf);
        __m256 sum = _mm256_add_ps(a2, b2);
        __m256 weight = _mm256_and_ps(_mm256_div_ps(a2, sum), _mm256_cmp_ps(sum, zero, _CMP_GT_OQ));
        scale = _mm256_mul_ps(scale, weight);
    }
    _mm256_store_ps(L->contribution[0], _mm256_mul_ps(LOAD3(throughput, 0), _mm256_mul_ps(_mm256_mul_ps(LOAD3(le, 0), fx), scale)));
    _mm256_store_ps(L->contribution[1], _mm256_mul_ps(LOAD3(throughput, 1), _mm256_mul_ps(_mm256_mul_ps(LOAD3(le, 1), fy), scale)));
    _mm256_store_ps(L->contribution[2], _mm256_mul_ps(LOAD3(throughput, 2), _mm256_mul_ps(_mm256_mul_ps(LOAD3(le, 2), fz), scale)));
    /* the shadow ray: ray_spawn_to() */
    const __m256 p[3] = {LOAD3(p, 0), LOAD3(p, 1), LOAD3(p, 2)}, ng[3] = {LOAD3(ng, 0), LOAD3(ng, 1), LOAD3(ng, 2)};
    const __m256 x_light[3] = {LOAD3(x_light, 0), LOAD3(x_light, 1), LOAD3(x_light, 2)};
    const __m256 n_light[3] = {LOAD3(n_light, 0), LOAD3(n_light, 1), LOAD3(n_light, 2)};
    __m256 origin[3], direction[3], t_min, t_max;
    ray_spawn_to8(p, _mm256_load_ps(L->p_error), ng, x_light, _mm256_load_ps(L->x_error), n_light, origin, direction,
                  &t_min, &t_max);
    for (int c = 0; c < 3; c++) {
        _mm256_store_ps(L->shadow_origin[c], origin[c]);
        _mm256_store_ps(L->shadow_direction[c], direction[c]);
    }
    _mm256_store_ps(L->shadow_t_min, t_min);
    _mm256_store_ps(L->shadow_t_max, t_max);
    int mask = _mm256_movemask_ps(ok) & lanes;
    _mm256_zeroupper();
    return mask;
}
#endif

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
static int bounce_math_lane(vertex_lanes *L, int k, const pt_material *m)
{
#define AT(v) vec3_make(L->v[0][k], L->v[1][k], L->v[2][k])
    vec3 n = AT(n), local = sample_uniform_hemisphere_fast(L->u_x[k], L->u_y[k]);
    vec3 wi = frame_to_world(n, local);
    vec3 weight = bounce_weight(m, n, AT(wo), wi, local.z, uniform_hemisphere_pdf());
    if (vec3_is_black(weight))
        return 0;
    lane_store_bounce(L, k, wi, weight);
    return 1 << k;
#undef AT
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

/* trace_iterative()'s Russian roulette, after the bounce, on the throughput
 * it left (and the surface's albedo): false if the path ends here, else the
 * throughput divided by the probability it went on with. */
static bool roulette_after_bounce(lane *l, const path_tracer *pt, vec3 *throughput, vec3 albedo)
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
static int bounce_cosine_lane(vertex_lanes *L, int k, const pt_material *m, bool mis)
{
#define AT(v) vec3_make(L->v[0][k], L->v[1][k], L->v[2][k])
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
#undef AT
}

#if WIDE_HAVE_AVX
/* fast_sincos_turns() of eight numbers, operation for operation. */
SPAWN_TARGET static inline void fast_sincos_turns8(__m256 u, __m256 *sin_out, __m256 *cos_out)
{
    const __m256 one = _mm256_set1_ps(1.0f), sign_bit = _mm256_set1_ps(-0.0f);
    __m256 q = _mm256_cvtepi32_ps(_mm256_cvttps_epi32(_mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(4.0f), u),
                                                                     _mm256_set1_ps(0.5f))));
    __m256 rest = _mm256_sub_ps(u, _mm256_mul_ps(_mm256_set1_ps(0.25f), q));
    __m256 r2 = _mm256_mul_ps(rest, rest);
#define POLY_STEP(acc, c) _mm256_add_ps(_mm256_mul_ps(acc, r2), _mm256_set1_ps(c))
    __m256 p = _mm256_set1_ps(0x1.4bbc38p+5f);
    p = _mm256_mul_ps(POLY_STEP(POLY_STEP(POLY_STEP(p, -0x1.32ca6cp+6f), 0x1.466bbap+6f), -0x1.4abbcep+5f), r2);
    __m256 sin_r = _mm256_add_ps(_mm256_mul_ps(rest, _mm256_set1_ps(0x1.921fb6p+2f)), _mm256_mul_ps(rest, p));
    __m256 c = _mm256_set1_ps(0x1.d9f7b2p+5f);
    c = _mm256_mul_ps(POLY_STEP(POLY_STEP(POLY_STEP(c, -0x1.55c664p+6f), 0x1.03c1dep+6f), -0x1.3bd3ccp+4f), r2);
    __m256 cos_r = _mm256_add_ps(one, c);
#undef POLY_STEP
    /* the quarter turn: odd ones swap, 2 and 3 negate the sine, 1 and 2 the cosine */
    __m256 q1 = _mm256_cmp_ps(q, one, _CMP_EQ_OQ), q2 = _mm256_cmp_ps(q, _mm256_set1_ps(2.0f), _CMP_EQ_OQ),
           q3 = _mm256_cmp_ps(q, _mm256_set1_ps(3.0f), _CMP_EQ_OQ);
    __m256 odd = _mm256_or_ps(q1, q3);
    *sin_out = _mm256_xor_ps(_mm256_blendv_ps(sin_r, cos_r, odd), _mm256_and_ps(_mm256_or_ps(q2, q3), sign_bit));
    *cos_out = _mm256_xor_ps(_mm256_blendv_ps(cos_r, sin_r, odd), _mm256_and_ps(_mm256_or_ps(q1, q2), sign_bit));
}

/* frame_to_world(n, local) of eight lanes: vec3_basis(n), operation for
 * operation, then t x + b y + n z. */
SPAWN_TARGET static inline void frame_to_world8(const __m256 n[3], const __m256 local[3], __m256 w[3])
{
    const __m256 one = _mm256_set1_ps(1.0f), sign_bit = _mm256_set1_ps(-0.0f);
    __m256 nx = n[0], ny = n[1], nz = n[2];
    __m256 sign = _mm256_or_ps(_mm256_and_ps(nz, sign_bit), one);
    __m256 a = _mm256_div_ps(_mm256_set1_ps(-1.0f), _mm256_add_ps(sign, nz));
    __m256 cc = _mm256_mul_ps(_mm256_mul_ps(nx, ny), a);
    __m256 tx = _mm256_add_ps(one, _mm256_mul_ps(_mm256_mul_ps(_mm256_mul_ps(sign, nx), nx), a));
    __m256 ty = _mm256_mul_ps(sign, cc), tz = _mm256_mul_ps(_mm256_xor_ps(sign, sign_bit), nx);
    __m256 bx = cc, by = _mm256_add_ps(sign, _mm256_mul_ps(_mm256_mul_ps(ny, ny), a)), bz = _mm256_xor_ps(ny, sign_bit);
#define TO_WORLD(t, b, n)                                                                                    \
    _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(t, local[0]), _mm256_mul_ps(b, local[1])), _mm256_mul_ps(n, local[2]))
    w[0] = TO_WORLD(tx, bx, nx);
    w[1] = TO_WORLD(ty, by, ny);
    w[2] = TO_WORLD(tz, bz, nz);
#undef TO_WORLD
}

/* What every bounce in AVX ends with, for all eight lanes: the next ray
 * from p along wi (ray_spawn()), its wo, and the throughput times f cos /
 * pdf (weight) times rr_scale. */
SPAWN_TARGET static inline void bounce_store8(vertex_lanes *L, const __m256 wi[3], const __m256 weight[3])
{
    const __m256 sign_bit = _mm256_set1_ps(-0.0f);
    const __m256 point[3] = {LOAD3(p, 0), LOAD3(p, 1), LOAD3(p, 2)}, ng[3] = {LOAD3(ng, 0), LOAD3(ng, 1), LOAD3(ng, 2)};
    __m256 origin[3], t_min;
    ray_spawn8(point, _mm256_load_ps(L->p_error), ng, wi, origin, &t_min);
    __m256 rr_scale = _mm256_load_ps(L->rr_scale);
    for (int c = 0; c < 3; c++) {
        _mm256_store_ps(L->ray.origin[c], origin[c]);
        _mm256_store_ps(L->ray.direction[c], wi[c]);
        _mm256_store_ps(L->throughput[c], _mm256_mul_ps(_mm256_mul_ps(LOAD3(throughput, c), weight[c]), rr_scale));
        _mm256_store_ps(L->wo[c], _mm256_xor_ps(wi[c], sign_bit));
    }
    _mm256_storeu_ps(L->ray.t_min, t_min);
}

/* f cos / pdf of a diffuse surface (rho / pi where both directions are
 * above it, as bsdf_eval() says, times `scale` = cos / pdf) into weight;
 * the mask of the lanes where it is black. */
SPAWN_TARGET static inline __m256 diffuse_weight8(const vertex_lanes *L, const __m256 n[3], const __m256 wi[3],
                                                  __m256 scale, __m256 weight[3])
{
    const __m256 zero = _mm256_setzero_ps();
    const __m256 wo[3] = {LOAD3(wo, 0), LOAD3(wo, 1), LOAD3(wo, 2)};
    __m256 above = _mm256_and_ps(_mm256_cmp_ps(spawn_dot8(n, wi), zero, _CMP_GT_OQ),
                                 _mm256_cmp_ps(spawn_dot8(n, wo), zero, _CMP_GT_OQ));
    const __m256 inv_pi = _mm256_set1_ps(DIFFUSE_INV_PI_F);
    __m256 black = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
    for (int c = 0; c < 3; c++) {
        weight[c] = _mm256_mul_ps(_mm256_and_ps(_mm256_mul_ps(LOAD3(albedo, c), inv_pi), above), scale);
        black = _mm256_and_ps(black, _mm256_cmp_ps(weight[c], zero, _CMP_EQ_OQ));
    }
    return black;
}

/* The same as bounce_math_lane for the lanes of `lanes`, eight per AVX
 * instruction, operation for operation: sample_uniform_hemisphere() with
 * fast_sincos_turns(), frame_to_world() with vec3_basis(), bsdf_eval(). */
SPAWN_TARGET static int bounce_math_avx(vertex_lanes *L, int lanes)
{
    const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
    /* sample_uniform_hemisphere: z = u_x, r = sqrt(max(0, 1 - z^2)), phi = 2 pi u_y */
    __m256 z = _mm256_load_ps(L->u_x);
    __m256 r = _mm256_sqrt_ps(_mm256_max_ps(_mm256_sub_ps(one, _mm256_mul_ps(z, z)), zero));
    __m256 sin_phi, cos_phi;
    fast_sincos_turns8(_mm256_load_ps(L->u_y), &sin_phi, &cos_phi);
    const __m256 local[3] = {_mm256_mul_ps(r, cos_phi), _mm256_mul_ps(r, sin_phi), z};
    const __m256 n[3] = {LOAD3(n, 0), LOAD3(n, 1), LOAD3(n, 2)};
    __m256 wi[3], weight[3];
    frame_to_world8(n, local, wi);
    __m256 black = diffuse_weight8(L, n, wi, _mm256_div_ps(z, _mm256_set1_ps(uniform_hemisphere_pdf())), weight);
    bounce_store8(L, wi, weight);
    int mask = ~_mm256_movemask_ps(black) & lanes;
    _mm256_zeroupper();
    return mask;
}

/* sample_cosine_hemisphere_fast() of eight lanes, operation for operation:
 * the branches on the triangle become blends, and the centre's 0 / 0 a
 * mask. */
SPAWN_TARGET static inline void cosine_hemisphere8(__m256 u_x, __m256 u_y, __m256 local[3])
{
    const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f), two = _mm256_set1_ps(2.0f);
    const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
    __m256 ox = _mm256_sub_ps(_mm256_mul_ps(two, u_x), one), oy = _mm256_sub_ps(_mm256_mul_ps(two, u_y), one);
    __m256 sides = _mm256_cmp_ps(_mm256_and_ps(ox, abs_mask), _mm256_and_ps(oy, abs_mask), _CMP_GT_OQ);
    __m256 r = _mm256_blendv_ps(oy, ox, sides);
    __m256 top = _mm256_and_ps(_mm256_div_ps(ox, oy), _mm256_cmp_ps(oy, zero, _CMP_NEQ_OQ));
    __m256 ratio = _mm256_blendv_ps(top, _mm256_div_ps(oy, ox), sides);
    __m256 u = _mm256_blendv_ps(u_y, u_x, sides);
    __m256 one_minus_r = _mm256_mul_ps(two, _mm256_min_ps(u, _mm256_sub_ps(one, u)));
    __m256 s, c;
    fast_sincos_turns8(_mm256_mul_ps(_mm256_set1_ps(0.125f), ratio), &s, &c);
    local[0] = _mm256_mul_ps(r, _mm256_blendv_ps(s, c, sides));
    local[1] = _mm256_mul_ps(r, _mm256_blendv_ps(c, s, sides));
    __m256 z2 = _mm256_mul_ps(one_minus_r, _mm256_sub_ps(two, one_minus_r));
    local[2] = _mm256_sqrt_ps(_mm256_max_ps(z2, zero));
}

/* The same as bounce_cosine_lane for the lanes of `lanes`, eight per AVX
 * instruction, operation for operation. */
SPAWN_TARGET static int bounce_cosine_avx(vertex_lanes *L, int lanes, bool mis)
{
    const __m256 zero = _mm256_setzero_ps();
    __m256 local[3], wi[3], weight[3];
    cosine_hemisphere8(_mm256_load_ps(L->u_x), _mm256_load_ps(L->u_y), local);
    const __m256 n[3] = {LOAD3(n, 0), LOAD3(n, 1), LOAD3(n, 2)};
    frame_to_world8(n, local, wi);
    __m256 pdf = _mm256_mul_ps(_mm256_max_ps(local[2], zero), _mm256_set1_ps(INV_PI_F));
    __m256 on, black;
    if (mis) { /* bsdf_sample(): z > 0, and f cos / pdf = rho */
        on = _mm256_cmp_ps(local[2], zero, _CMP_GT_OQ);
        black = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
        for (int c = 0; c < 3; c++) {
            weight[c] = LOAD3(albedo, c);
            black = _mm256_and_ps(black, _mm256_cmp_ps(weight[c], zero, _CMP_EQ_OQ));
        }
    } else { /* pdf > 0, and bsdf_eval() cos / pdf */
        on = _mm256_cmp_ps(pdf, zero, _CMP_GT_OQ);
        black = diffuse_weight8(L, n, wi, _mm256_div_ps(local[2], pdf), weight);
    }
    bounce_store8(L, wi, weight);
    _mm256_store_ps(L->pdf, pdf);
    int mask = _mm256_movemask_ps(_mm256_andnot_ps(black, on)) & lanes;
    _mm256_zeroupper();
    return mask;
}
#undef LOAD3
#undef DOT
#endif

/* ---- the other materials, one lane at a time --------------------------------------
 * Glossy surfaces, mirrors and glass, and point lights, through chapter
 * 09's BSDFs (bsdf_eval, bsdf_sample): the lanes on them are few in most
 * scenes, and their arithmetic is the book's, not a copy. */

#define AT(v) vec3_make(L->v[0][k], L->v[1][k], L->v[2][k])

/* The next ray of a lane, kept aside while bounce_math_avx writes all
 * eight lanes. */
typedef struct {
    ray next;
    vec3 throughput, wo;
} lane_bounce;

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
static bool bounce_surface_lane(const vertex_lanes *L, int k, const pt_material *m, lane_bounce *out)
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

static bool bounce_iterative_lane(lane *l, const path_tracer *pt, const vertex_lanes *L, int k, const pt_material *m,
                                  bool front, lane_bounce *out, ray_counters *counters);

/* shade_delta(): a mirror or glass picks the direction (bsdf_sample), from
 * the roulette's number and three more, in its order; the emission the ray
 * meets then counts. False if the path ends here. */
static bool bounce_delta_lane(lane *l, const path_tracer *pt, const vertex_lanes *L, int k, const pt_material *m,
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
static bool bounce_iterative_lane(lane *l, const path_tracer *pt, const vertex_lanes *L, int k, const pt_material *m,
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
    l->previous_pdf = s.pdf;
    return true;
}

/* point_lights() of chapter 09 for lane k: each point light's
 * f I cos(theta) / r^2 (direct_light_point()), times the throughput, its
 * shadow ray queued (or, without shadows, added at once). */
static void point_lights_lane(row_job *job, const vertex_lanes *L, int k, const pt_material *m)
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
static bool sphere_hit_lane(const pt_scene *sc, const rays8 *rays, int k, float t_max, hit_record *hit,
                            ray_counters *counters)
{
    ray r = rays8_get(rays, k);
    r.t_max = t_max;
    return pt_scene_intersect_spheres(sc, r, hit, counters);
}

/* A full hit record into lane k's arrays (a sphere's, or a triangle's
 * made lane by lane). */
static int hit_record_set(const pt_scene *sc, const hit_record *hit, int k, vertex_lanes *L, int material[LANES])
{
    lanes_set(L->p, k, hit->point);
    L->p_error[k] = hit->point_error;
    lanes_set(L->ng, k, hit->normal_geometric);
    lanes_set(L->n, k, hit->normal_shading);
    lanes_set(L->albedo, k, sc->materials[hit->material_id].albedo);
    material[k] = hit->material_id;
    return hit->front_face << k;
}

#undef AT

/* ---- the hit records -----------------------------------------------------------
 * What triangle_set_fill_hit() makes of a lane's hit, as far as shading
 * needs it: the point (from the barycentrics) and its error bound, the
 * geometric normal facing the ray, the shading normal, the material and its
 * albedo, and whether the front was hit; written straight into the lanes'
 * arrays. */
static int hit_record_lane(const pt_scene *sc, const hits8 *hits, int k, vertex_lanes *L,
                           int material[LANES])
{
    hit_record hit;
    triangle_set_fill_hit(&sc->triangles, hits->index[k], rays8_get(&L->ray, k), hits->t[k], hits->b1[k],
                          hits->b2[k], &hit);
    return hit_record_set(sc, &hit, k, L, material);
}

#if WIDE_HAVE_AVX
/* The same for the lanes of `lanes`, eight per instruction, the triangles'
 * corners, normals and materials gathered by index (AVX2). Only where the
 * triangles have no vertex normals: then the shading normal is the
 * geometric one. */
SPAWN_TARGET static int hit_records_avx(const pt_scene *sc, const hits8 *hits, int lanes,
                                        vertex_lanes *L, int material[LANES])
{
    const triangle_set *set = &sc->triangles;
    _Static_assert(sizeof(triangle) == 9 * sizeof(float), "a triangle is its nine coordinates");
    _Static_assert(sizeof(triangle_surface) == 4 * sizeof(float), "a surface is a normal and a material");
    _Static_assert(sizeof(pt_material) % sizeof(float) == 0, "materials are a whole number of floats");
    const __m256i lane_bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
    __m256i hit_mask = _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32(lanes), lane_bits), lane_bits);
    /* lanes without a hit read triangle 0, and their answers are not used */
    __m256i index = _mm256_and_si256(_mm256_load_si256((const __m256i *)hits->index), hit_mask);
    __m256i corner = _mm256_mullo_epi32(index, _mm256_set1_epi32(9)), surface = _mm256_slli_epi32(index, 2);
    const float *t0 = &set->triangles[0].p0.x;
    __m256 b1 = _mm256_load_ps(hits->b1), b2 = _mm256_load_ps(hits->b2);
    const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
    /* triangle_fill_hit_normal: P0 + (b1 E1 + b2 E2), and the size of the
     * edges for the error bound (triangle_edge_size) */
    __m256 point[3], size = _mm256_setzero_ps();
    for (int c = 0; c < 3; c++) {
        __m256 p0 = _mm256_i32gather_ps(t0 + c, corner, 4), p1 = _mm256_i32gather_ps(t0 + 3 + c, corner, 4),
               p2 = _mm256_i32gather_ps(t0 + 6 + c, corner, 4);
        __m256 e1 = _mm256_sub_ps(p1, p0), e2 = _mm256_sub_ps(p2, p0);
        point[c] = _mm256_add_ps(p0, _mm256_add_ps(_mm256_mul_ps(e1, b1), _mm256_mul_ps(e2, b2)));
        size = _mm256_max_ps(size, _mm256_max_ps(_mm256_and_ps(e1, abs_mask), _mm256_and_ps(e2, abs_mask)));
    }
    const float *s0 = &set->surfaces[0].normal.x;
    __m256 normal[3], direction[3];
    for (int c = 0; c < 3; c++) {
        normal[c] = _mm256_i32gather_ps(s0 + c, surface, 4);
        direction[c] = _mm256_load_ps(L->ray.direction[c]);
    }
    _mm256_store_ps(L->p_error, spawn_point_error8(point, normal, size));
    __m256i materials = _mm256_i32gather_epi32(&set->surfaces[0].material, surface, 4);
    /* hit_set_normal: the front if the ray comes against the outward normal */
    __m256 front = _mm256_cmp_ps(spawn_dot8(direction, normal), _mm256_setzero_ps(), _CMP_LT_OQ);
    __m256 flip = _mm256_andnot_ps(front, _mm256_set1_ps(-0.0f));
    const int material_floats = (int)(sizeof(pt_material) / sizeof(float));
    __m256i albedo_at = _mm256_mullo_epi32(materials, _mm256_set1_epi32(material_floats));
    const float *a0 = &sc->materials[0].albedo.x;
    for (int c = 0; c < 3; c++) {
        __m256 ng = _mm256_xor_ps(normal[c], flip);
        _mm256_store_ps(L->p[c], point[c]);
        _mm256_store_ps(L->ng[c], ng);
        _mm256_store_ps(L->n[c], ng);
        _mm256_store_ps(L->albedo[c], _mm256_i32gather_ps(a0 + c, albedo_at, 4));
    }
    _mm256_storeu_si256((__m256i *)material, materials);
    int front_bits = _mm256_movemask_ps(front) & lanes;
    _mm256_zeroupper();
    return front_bits;
}
#endif

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
        float pdf_light = light_pdf_from(l->previous_point, p, ng, wo, job->pdf_area[material]); /* per steradian */
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
            if (lanes[k].depth + 1 <= pt->max_depth && pick_light(&lanes[k], pt, job->pdf_area, &L, k))
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
    const bool avx = use_avx && wide_cpu_has_avx2();
    const pt_scene *sc = pt->scene;
    float *pdf_area = memory_allocate((size_t)(sc->material_count > 0 ? sc->material_count : 1), sizeof(float));
    for (int k = 0; k < sc->material_count && sc->emitter_count > 0; k++)
        pdf_area[k] = pt_scene_emitter_pdf_area(sc, k);
    double start = timer_seconds();
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
                           .trace = trace, .avx = avx, .pdf_area = pdf_area};
            render_row(&job);
        }
        queue_free(&queue);
#pragma omp critical(render_wide_counters)
        counters_add(&e.counters, &mine);
    }
    e.seconds = timer_seconds() - start;
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
                       .counters = &ignored, .queue = queue, .trace = &trace, .avx = use_avx && wide_cpu_has_avx2(),
                       .pdf_area = pdf_area};
        done += job.x_end - x;
        render_row(&job);
    }
    double seconds = timer_seconds() - start;
    queue_free(&queue);
    free(pdf_area);
    image_free(&mean);
    image_free(&standard_error);
    return done > 0 ? seconds / done * (double)total : 0.0;
}

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

static bool tests_use_avx(void) { return use_avx && wide_cpu_has_avx2(); }

int path_tracer_wide_light_math(const wide_vertex *v, int count, bool mis, wide_light_result out[8])
{
    vertex_lanes L;
    pt_material m[LANES];
    int lanes = lanes_from(v, count, &L, m), lit = 0;
#if WIDE_HAVE_AVX
    if (tests_use_avx())
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
    if (tests_use_avx())
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
