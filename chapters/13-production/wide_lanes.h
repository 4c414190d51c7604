/* wide_lanes.h -- what the eight-path renderer's files share
 * (path_tracer_wide.h): the lanes and their vertices, structure of arrays;
 * the row a thread renders; and the steps of one vertex, by file:
 *
 *   path_tracer_wide.c   the lanes' schedule: pixels, samples, their random
 *                        numbers, the shadow-ray queue, one vertex of
 *                        eight paths (render_row), the renders
 *   wide_vertex.c        one lane's physics at a vertex, through chapter
 *                        09's pieces (light_transport.h, bsdf.h): the
 *                        light sample, the bounces of every material, the
 *                        point lights, the hit records
 *   wide_kernels_avx.c   the same for the diffuse lanes, eight per AVX
 *                        instruction, the very bits of wide_vertex.c's
 *                        (tests/test_ch13.c compares them value by value)
 *
 * No program includes it: path_tracer_wide.h is the renderer's interface.
 */
#ifndef WIDE_LANES_H
#define WIDE_LANES_H

#include <stdbool.h>

#include "09-path-tracing/bsdf.h"
#include "13-production/light_tree.h"
#include "13-production/path_tracer_wide.h"
#include "13-production/rays8.h"
#include "13-production/sobol_pixel.h"
#include "13-production/spawn_avx.h"
#include "13-production/wide_trace.h"
#include "stats.h"

/* The lanes' arithmetic in AVX needs AVX2 for the hit records' gathers
 * (spawn_avx.h's target); without it, lane by lane. */
#define WIDE_HAVE_AVX SPAWN_HAVE_AVX2

enum { LANES = RAYS8_LANES };

/* On the functions only the cosine and MIS rungs call from render_row:
 * inlined, they grew it past what the compiler inlines into it, and left
 * the light's pick (pt_scene_sample_emitter) a call at every step of every
 * lane of every rung. */
#define NOT_INLINED __attribute__((noinline))

/* ---- one vertex of eight paths ------------------------------------------------
 * What shade() of path_tracer.c does at a vertex, for the lecture rung on
 * diffuse surfaces, in the same order and with the same random numbers,
 * in five parts: the hit records are made for all eight lanes at once
 * (hit_records, below); each lane picks its point on a light (pick_light);
 * the light sample's arithmetic runs for all eight at once (light_math);
 * each lane then queues its shadow ray and draws the roulette and the two
 * numbers of its next direction (roll_bounce); the bounce's arithmetic runs
 * for all eight at once (bounce_math). */

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
    int triangle[LANES]; /* the triangle hit (-1: a sphere), whose light pmf the light tree gives */
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
     * previous_pdf), for the MIS weight of the emission it finds; and its
     * shading normal, with which the light tree picked that vertex's light. */
    vec3 previous_point, previous_normal;
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
    /* The light tree the lanes pick their lights with (light_tree.h), or
     * NULL: chapter 09's pick by power (path_tracer_wide_light_tree) */
    const light_tree *lights;
} row_job;

/* The lane's next number, from where chapter 09's path tracer takes it
 * (path_tracer.h, --sampler): the pixel's stream, or the sample's point of
 * the pixel's scrambled Sobol sequence. */
static inline float lane_float(lane *l, const path_tracer *pt)
{
    return pt->sampler == PT_SAMPLER_SOBOL ? sobol_pixel_next(&l->sobol) : pcg32_float(&l->rng);
}

/* Lane k of a field of the lanes (three coordinates) set to x. */
static inline void lanes_set(float v[3][LANES], int k, vec3 x)
{
    v[0][k] = x.x;
    v[1][k] = x.y;
    v[2][k] = x.z;
}

/* The next ray of a lane, kept aside while bounce_math_avx writes all
 * eight lanes. */
typedef struct {
    ray next;
    vec3 throughput, wo;
} lane_bounce;

/* ---- path_tracer_wide.c ---- */

/* The lanes' arithmetic in AVX2 (path_tracer_wide_use_avx(), and the processor has it). */
bool wide_avx_runs(void);
/* Lane k's shadow ray at the end of the queue, with what it brings. */
void queue_push(row_job *job, int k, ray shadow, vec3 contribution);

/* ---- wide_vertex.c: one lane at a time (what each does: there) ---- */

hit_record lane_hit(const vertex_lanes *L, int k);
int light_math_lane(vertex_lanes *L, int k, const pt_material *m, bool mis);
int bounce_math_lane(vertex_lanes *L, int k, const pt_material *m);
bool roulette_after_bounce(lane *l, const path_tracer *pt, vec3 *throughput, vec3 albedo);
int bounce_cosine_lane(vertex_lanes *L, int k, const pt_material *m, bool mis);
bool bounce_surface_lane(const vertex_lanes *L, int k, const pt_material *m, lane_bounce *out);
bool bounce_delta_lane(lane *l, const path_tracer *pt, const vertex_lanes *L, int k, const pt_material *m, bool front,
                       lane_bounce *out, ray_counters *counters);
bool bounce_iterative_lane(lane *l, const path_tracer *pt, const vertex_lanes *L, int k, const pt_material *m,
                           bool front, lane_bounce *out, ray_counters *counters);
void point_lights_lane(row_job *job, const vertex_lanes *L, int k, const pt_material *m);
bool sphere_hit_lane(const pt_scene *sc, const rays8 *rays, int k, float t_max, hit_record *hit,
                     ray_counters *counters);
int hit_record_set(const pt_scene *sc, const hit_record *hit, int k, vertex_lanes *L, int material[LANES]);
int hit_record_lane(const pt_scene *sc, const hits8 *hits, int k, vertex_lanes *L, int material[LANES]);

/* ---- wide_kernels_avx.c: the diffuse lanes of `lanes`, eight at a time ---- */

#if WIDE_HAVE_AVX
SPAWN_TARGET int light_math_avx(vertex_lanes *L, int lanes, bool mis);
SPAWN_TARGET int bounce_math_avx(vertex_lanes *L, int lanes);
SPAWN_TARGET int bounce_cosine_avx(vertex_lanes *L, int lanes, bool mis);
SPAWN_TARGET int hit_records_avx(const pt_scene *sc, const hits8 *hits, int lanes, vertex_lanes *L,
                                 int material[LANES]);
#endif

#endif
