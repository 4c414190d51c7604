/* path_tracer.h -- lecture 16's path tracer, then the steps beyond it.
 *
 * The rungs of the ladder (--integrator), each a small step from the last:
 *   PT_LECTURE  the lecture's shade(p, wo), exactly: the light sampled by
 *               area (pdf 1/A), the hemisphere sampled uniformly
 *               (pdf 1/(2 pi)), Russian roulette with a fixed P_RR
 *   PT_COSINE   the same, but directions drawn in proportion to cos(theta)
 *   PT_MIS      directions drawn from the BSDF, and light sampling and BSDF
 *               sampling combined by multiple importance sampling (power
 *               heuristic): glossy surfaces and small lights both work
 * and, separately, Russian roulette: with a fixed probability (the
 * lecture), on the surface's albedo (smallpt) or on the path's throughput
 * (pbrt); and where the numbers come from (--sampler): independent random
 * numbers (the lecture), or a pixel's samples as the points of an
 * Owen-scrambled Sobol sequence (sobol_sampler.h).
 *
 * Usage:
 *   path_tracer pt = path_tracer_defaults(&scene);
 *   pt.integrator = PT_MIS;
 *   render_job job = {..., .radiance = path_trace_radiance, .scene = &pt,
 *                     .sample = path_tracer_sample_fn(&pt)};
 */
#ifndef PATH_TRACER_H
#define PATH_TRACER_H

#include "09-path-tracing/scene_pt.h"
#include "render.h"
#include "rng.h"
#include "scene_file.h"

typedef enum { PT_LECTURE, PT_COSINE, PT_MIS } pt_integrator;
typedef enum {
    RR_OFF,        /* no Russian roulette: paths end at max_depth */
    RR_FIXED,      /* continue with probability P_RR at every bounce (the lecture) */
    RR_THROUGHPUT, /* continue with probability min(1, max throughput), from bounce rr_start_depth on (pbrt) */
    RR_ALBEDO,     /* continue with probability min(1, max albedo), from bounce rr_start_depth on (smallpt) */
} pt_russian_roulette;

/* The first bounce the references play their roulettes on: pbrt-v3's
 * PathIntegrator from `bounces > 3` of its 0-based count (bounce 5), smallpt
 * from `++depth > 5` (bounce 6). The speed table and its tests use them. */
enum { RR_START_PBRT = 5, RR_START_SMALLPT = 6 };

typedef enum {
    PT_SAMPLER_RANDOM, /* the pixel's pcg32 stream: independent numbers (the lecture) */
    PT_SAMPLER_SOBOL,  /* sample i of a pixel: point i of an Owen-scrambled Sobol sequence */
} pt_sampler;

typedef struct {
    const pt_scene *scene;
    pt_integrator integrator;
    pt_russian_roulette russian_roulette;
    float rr_probability; /* P_RR of RR_FIXED */
    /* RR_THROUGHPUT and RR_ALBEDO: the first bounce the roulette may end
     * (pbrt-v3 plays it from bounce 5 on, smallpt from bounce 6 on) */
    int rr_start_depth;
    /* Light that bounced more than max_depth times is not counted. With
     * Russian roulette this is only a guard (0.8^64 = 6e-7 of the paths get
     * that far); without it, it is the truncation. */
    int max_depth;
    /* The effects to simulate (EFFECT_* of scene_file.h; EFFECT_ALL unless a
     * scene file's effects analysis narrowed them). Without EFFECT_SHADOWS
     * light samples are not tested for occlusion; without EFFECT_INDIRECT
     * (or EFFECT_GLOSSY) a path ends after the direct light at a diffuse (or
     * glossy) vertex; without EFFECT_REFLECTION or EFFECT_REFRACTION a
     * mirror's or glass's sample in that lobe ends the path. */
    unsigned effects;
    /* Where the numbers come from; a render honours it through
     * path_tracer_sample_fn. */
    pt_sampler sampler;
} path_tracer;

path_tracer path_tracer_defaults(const pt_scene *scene);

/* Russian roulette before bounce depth + 1 (depth bounces already made),
 * with `throughput` the path's product of f cos / pdf (and earlier 1/q) up
 * to that point and `albedo` the surface's (pt_material's): false if no
 * roulette is played there; else true, and the probability q that the path
 * goes on in *q. Every rung asks this one question, so each mode means the
 * same in each. */
static inline bool path_tracer_roulette(const path_tracer *pt, int depth, vec3 throughput, vec3 albedo, float *q)
{
    switch (pt->russian_roulette) {
    case RR_FIXED:
        *q = pt->rr_probability;
        return true;
    case RR_THROUGHPUT:
        /* continue in proportion to what the path can still carry: a path
         * through dark surfaces ends sooner */
        if (depth + 1 < pt->rr_start_depth)
            return false;
        *q = fminf(1.0f, vec3_max_component(throughput));
        return true;
    case RR_ALBEDO:
        /* continue in proportion to what this surface reflects, whatever
         * the path carried here: smallpt's rule. Longer paths than on the
         * throughput, which after five bounces is a fraction of one. */
        if (depth + 1 < pt->rr_start_depth)
            return false;
        *q = fminf(1.0f, vec3_max_component(albedo));
        return true;
    case RR_OFF:
        break;
    }
    return false;
}

/* render.h's radiance_fn; ctx points to a path_tracer. */
vec3 path_trace_radiance(const void *ctx, ray r, pcg32 *rng, ray_counters *counters);

/* Where a path's random numbers come from. The path tracer is a function of
 * the uniform numbers it draws, one after another: a pixel's pcg32 stream
 * (rng, with next NULL: what path_trace_radiance uses), or any other source
 * that hands out numbers in [0, 1) -- chapter 12's Metropolis sampler
 * replays and mutates a vector of them ("primary sample space"). The
 * pcg32 case stays an inline call: a path draws five to eight numbers per
 * bounce. */
typedef struct {
    pcg32 *rng;                 /* used when next is NULL */
    float (*next)(void *state); /* else: the next number in [0, 1) */
    void *state;
} pt_random;

static inline float pt_random_float(pt_random *random)
{
    return random->next != NULL ? random->next(random->state) : pcg32_float(random->rng);
}

/* The radiance along r, with the path's numbers drawn from `random` in the
 * same order path_trace_radiance draws them from its stream. */
vec3 path_trace_radiance_from(const path_tracer *pt, ray r, pt_random *random, ray_counters *counters);

/* render.h's render_sample_fn for --sampler sobol (job->scene points to a
 * path_tracer): the position in pixel (x, y) and then the path, all from
 * point `index` of the pixel's scrambled Sobol sequence, in the order
 * path_trace_radiance draws them. */
vec3 path_trace_sobol_sample(const render_job *job, int x, int y, int index, pcg32 *rng, ray_counters *counters);

/* What a render_job of pt sets as .sample: NULL for PT_SAMPLER_RANDOM (the
 * render loop's jittered position, then path_trace_radiance), else
 * path_trace_sobol_sample. */
render_sample_fn path_tracer_sample_fn(const path_tracer *pt);

/* The names, in the enums' order, NULL-terminated (for --integrator, --rr,
 * --sampler). */
extern const char *const PT_INTEGRATOR_NAMES[];
extern const char *const PT_ROULETTE_NAMES[];
extern const char *const PT_SAMPLER_NAMES[];
const char *pt_integrator_name(pt_integrator i);
bool pt_integrator_parse(const char *name, pt_integrator *out);
/* "off", "fixed", "throughput", "albedo": --rr's words */
const char *pt_russian_roulette_name(pt_russian_roulette r);
bool pt_russian_roulette_parse(const char *name, pt_russian_roulette *out);

#endif
