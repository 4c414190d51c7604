/* path_tracer_wide.h -- chapter 09's path tracer, eight paths at a time.
 *
 * One path is a chain: each bounce waits for the ray before it, and the
 * processor has little to do while it waits. Eight paths -- eight pixels,
 * each with its own random numbers, its samples one after another -- are
 * eight chains side by side: their rays are traced together, eight at a
 * time (wide_trace.h: the flat set's AVX kernels for a few dozen
 * triangles, the 8-wide BVH for meshes; shadow rays queued until
 * there are eight, and tested against the occluders alone when all eight
 * lie inside the walls), so are the diffuse lanes' light sample and bounce
 * (AVX2, where the processor has it; lane by lane, with the same bits,
 * where not) and the two rays' offsets. Lanes on glossy surfaces, mirrors
 * and glass, point lights and spheres are done one lane at a time with
 * chapter 09's BSDFs (bsdf_eval, bsdf_sample). A lane whose path ends
 * starts its pixel's next sample; a lane whose pixel is done takes the
 * next pixel.
 *
 * Each pixel draws the same numbers in the same order as
 * path_trace_radiance() -- from its random stream, or with --sampler sobol
 * from its scrambled Sobol points as path_trace_sobol_sample() (found from
 * the sample before's, sobol_pixel.h) -- and makes
 * the same decisions (the same rays, hits, light samples and roulette), so
 * its samples are chapter 09's of the same rung but for rounding: the sum
 * along a path is added from the camera out instead of from the last
 * bounce back (the lecture's recursion), and the diffuse bounce's angle
 * comes from a polynomial (fast_sincos.h). One exception, on the lecture
 * rung: a path whose f cos / pdf is
 * exactly black ends here, where the recursion goes on and draws numbers
 * for nothing; the image's distribution is the same.
 *
 * Every scene chapter 09 renders: triangles in any structure (the
 * production one, walls.h, or any of chapter 03's interface), spheres, all
 * materials, area and point lights, the environment; any Russian roulette;
 * and every rung of chapter 09's ladder. The lecture rung as shade() does
 * it (above); the cosine and MIS rungs as trace_iterative() does them, in
 * its order: the light sample (with the power heuristic's weight on the
 * MIS rung), then the next direction -- cosine-weighted on the cosine
 * rung, from bsdf_sample() on the MIS rung and on mirrors and glass --
 * and the roulette after the bounce, on the new throughput; the emission
 * a BSDF-sampled ray finds counted with its MIS weight. Their diffuse
 * lanes' light sample and bounce are eight-wide as the lecture's are (the
 * cosine-weighted direction through sample_cosine_hemisphere()'s
 * concentric map, its angle by the same polynomial). Not --explain.
 *
 * Usage:
 *   estimate_image e;
 *   if (render_estimate_wide(&pt, &cam, spp, seed, threads, &e)) ... else render_estimate(...)
 */
#ifndef PATH_TRACER_WIDE_H
#define PATH_TRACER_WIDE_H

#include <stdbool.h>
#include <stddef.h>

#include "09-path-tracing/experiments.h"
#include "09-path-tracing/path_tracer.h"
#include "13-production/wide_trace.h"

/* What chapter 13's program renders with unless told otherwise (and what
 * make bench times as chapter 13): chapter 09's defaults, with the rung,
 * the numbers and the roulette production renderers use -- chapter 09's
 * MIS rung (--integrator mis: directions from the BSDF, light and BSDF
 * samples weighed by the power heuristic), each pixel's samples the points
 * of its scrambled Sobol sequence (--sampler sobol), and a path ended with
 * probability 1 - min(1, max throughput) from bounce 3 (--rr throughput;
 * chapter 09's table of roulettes). None changes the image's expectation;
 * each lowers its error at the same time. */
#define PRODUCTION_SAMPLER ((pt_sampler)PT_SAMPLER_SOBOL)
#define PRODUCTION_ROULETTE ((pt_russian_roulette)RR_THROUGHPUT)
#define PRODUCTION_INTEGRATOR ((pt_integrator)PT_MIS)
path_tracer production_path_tracer_defaults(const pt_scene *scene);

/* Can pt render eight paths at a time? If not, why (into why, if not NULL). */
bool path_tracer_wide_supported(const path_tracer *pt, char *why, size_t why_size);

/* What the renderer traces the scene's triangles with: every triangle
 * (closest hits, and shadow rays not inside the walls), and, where the
 * scene's structure found walls (walls.h), the occluders that shadow rays
 * inside them meet, and the walls to check them against (NULL: none). */
typedef struct {
    wide_tracer all, occluders;
    const accel *walls;
} wide_scene_tracers;

/* The tracers of the scene's own structure (sc->bvh): wide_tracer_for()
 * of it, or of the walls_accel's two structures. */
wide_scene_tracers wide_scene_tracers_for(const pt_scene *sc);

/* render_estimate(), eight paths at a time: the same per-pixel streams, the
 * same counters but for primitive_tests and box_tests (each structure
 * counts its own way). False, and *out untouched, if not supported. */
bool render_estimate_wide(const path_tracer *pt, const camera *cam, int spp, uint64_t seed, int threads,
                          estimate_image *out);
/* The same with the triangles traced by `trace` (another library's
 * kernels, for a benchmark; wide_trace.h). */
bool render_estimate_wide_traced(const path_tracer *pt, const wide_scene_tracers *trace, const camera *cam, int spp,
                                 uint64_t seed, int threads, estimate_image *out);

/* How long the render would take on one thread, in seconds, from a pilot:
 * about `pixels` pixels spread over the image (runs of eight), rendered at
 * the full spp and thrown away. 0 if not supported. */
double render_estimate_wide_pilot(const path_tracer *pt, const camera *cam, int spp, uint64_t seed, int pixels);

/* The lanes' arithmetic (light sample, bounce, ray offsets) eight lanes
 * per AVX instruction (true, the default, where the processor has AVX2) or
 * one lane at a time: the
 * same bits either way (tests/test_ch09.c). Not thread-safe: set it before
 * rendering. */
void path_tracer_wide_use_avx(bool on);

/* For the tests' twins only: the renderer with one of the MIS rung's two
 * weights left off -- the emission a BSDF-sampled ray finds counted in
 * full, or the light sample counted in full -- which its comparison with
 * chapter 09 must catch. Not thread-safe: set it before rendering. */
typedef enum { WIDE_TWIN_NONE, WIDE_TWIN_EMISSION_UNWEIGHTED, WIDE_TWIN_LIGHT_UNWEIGHTED } wide_twin;
void path_tracer_wide_twin(wide_twin twin);

/* One vertex's light sample as the lanes compute it: the hit (point, its
 * error bound, geometric and shading normals), the direction back along the
 * path, the surface's albedo (diffuse), the path's throughput, and the
 * point picked on a light (point, error bound, normal, L_e, pdf per unit
 * area). */
typedef struct {
    vec3 p, ng, n, wo, albedo, throughput;
    float p_error;
    vec3 x_light, n_light, le;
    float x_error, pdf_area;
} wide_light_vertex;

/* For the tests: the light samples' arithmetic of up to eight vertices
 * on diffuse surfaces, as the eight-path renderer does it (in AVX where it
 * runs, else lane by lane): bit k of the result says whether vertex k's
 * sample adds light, and contribution[k] is what it adds, times the
 * throughput, if its shadow ray gets through -- with the power heuristic's
 * weight against the cosine-weighted BSDF sample if `mis`. Chapter 09's
 * shade() and sample_direct_light() compute the same from
 * pt_scene_sample_light(), bsdf_eval() and bsdf_pdf(). */
int path_tracer_wide_light_math(const wide_light_vertex *v, int count, bool mis, vec3 contribution[8]);

#endif
