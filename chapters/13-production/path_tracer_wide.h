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
 * chapter 09's BSDFs (bsdf_eval, bsdf_sample); the physics of every lane is
 * chapter 09's light transport pieces (light_transport.h), which the AVX
 * kernels vectorise. A lane whose path ends
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
 * for nothing; the image's distribution is the same. And in a scene of
 * many emitters (path_tracer_wide_lights below) the light sample's
 * emitter is picked by the light tree, from the same number, instead of
 * by power: other light samples, the same expectation.
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
#include "13-production/light_tree.h"

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

/* Can pt render eight paths at a time? If not, why (into why, if not NULL):
 * --explain, triangles in no structure, or a material of a kind the lanes
 * do not render (named; they take diffuse, glossy, mirror and glass). */
bool path_tracer_wide_supported(const path_tracer *pt, char *why, size_t why_size);

/* What the renderer traces the scene's triangles with: every triangle
 * (closest hits, and shadow rays not inside the walls), and, where the
 * scene's structure found walls (walls.h), the occluders that shadow rays
 * inside them meet, and the walls to check them against (NULL: none). */
typedef struct {
    wide_tracer all, occluders;
    const accel *walls;
    const light_tree *lights; /* the scene's, built with the structures; NULL: none built */
} wide_scene_tracers;

/* The tracers of the scene's own structure (sc->bvh): wide_tracer_for()
 * of it, or of the walls_accel's two structures, and its light tree. */
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
 * same bits either way (tests/test_ch13.c). Not thread-safe: set it before
 * rendering. */
void path_tracer_wide_use_avx(bool on);

/* Which emitter a vertex's light sample takes (light_tree.h): by the light
 * tree where the scene has at least LIGHT_TREE_MIN_EMITTERS emitting
 * triangles (WIDE_LIGHTS_AUTO, the default), always (WIDE_LIGHTS_TREE), or
 * never (WIDE_LIGHTS_POWER: in proportion to power, as chapter 09). The
 * point on it, and all the physics, are chapter 09's either way. Not
 * thread-safe: set it before rendering. */
typedef enum { WIDE_LIGHTS_AUTO, WIDE_LIGHTS_POWER, WIDE_LIGHTS_TREE } wide_lights;
void path_tracer_wide_lights(wide_lights how);
/* Does a render of sc pick its lights by the tree (as set above)? */
bool path_tracer_wide_uses_light_tree(const pt_scene *sc);

/* For the tests' twins only: the renderer with one of the MIS rung's two
 * weights left off -- the emission a BSDF-sampled ray finds counted in
 * full, or the light sample counted in full -- or, with the light tree,
 * the light picked by the tree but divided by the density of the pick by
 * power, which its comparison with chapter 09 must catch. Not
 * thread-safe: set it before rendering. */
typedef enum {
    WIDE_TWIN_NONE,
    WIDE_TWIN_EMISSION_UNWEIGHTED,
    WIDE_TWIN_LIGHT_UNWEIGHTED,
    WIDE_TWIN_TREE_PDF_OF_POWER
} wide_twin;
void path_tracer_wide_twin(wide_twin twin);

/* For the tests of the AVX kernels against chapter 09's scalar pieces
 * (light_transport.h): one diffuse vertex as the lanes hold it -- the hit
 * (point, its error bound, geometric and shading normals), the direction
 * back along the path, the surface's albedo, the path's throughput; the
 * point picked on a light (point, error bound, normal, L_e, pdf per unit
 * area); the two numbers of the next direction and the roulette's 1 / P_RR. */
typedef struct {
    vec3 p, ng, n, wo, albedo, throughput;
    float p_error;
    vec3 x_light, n_light, le;
    float x_error, pdf_area;
    float u_x, u_y, rr_scale;
} wide_vertex;

/* What a vertex's light sample adds, times the throughput, if its shadow
 * ray gets through, and that ray. */
typedef struct {
    vec3 contribution;
    ray shadow;
} wide_light_result;

/* The light samples of up to eight diffuse vertices as the eight-path
 * renderer computes them (light_math_avx where it runs, else lane by lane
 * through direct_light_solid_angle()): bit k of the result says whether
 * vertex k's sample adds light, and out[k] (set for those only) what, with
 * the power heuristic's weight against the one BSDF sample if `mis`. */
int path_tracer_wide_light_math(const wide_vertex *v, int count, bool mis, wide_light_result out[8]);

/* A vertex's bounce: the next ray (origin, direction, t_min; ray_spawn()),
 * the direction back along it, the throughput after it (times f cos / pdf
 * and rr_scale), and on the cosine and MIS rungs the direction's pdf. */
typedef struct {
    ray next;
    vec3 wo, throughput;
    float pdf;
} wide_bounce_result;

/* The bounces of up to eight diffuse vertices as the eight-path renderer
 * computes them on `rung` (bounce_math_avx on the lecture rung,
 * bounce_cosine_avx on the others, where they run; else lane by lane): the
 * direction from u_x, u_y (sample_uniform_hemisphere_fast() or
 * sample_cosine_hemisphere_fast(), fast_sincos.h) and f cos / pdf from
 * chapter 09's bounce_weight() (on the MIS rung bsdf_sample()'s rho). Bit
 * k says whether vertex k's path goes on; out[k] is set for those only. */
int path_tracer_wide_bounce_math(const wide_vertex *v, int count, pt_integrator rung, wide_bounce_result out[8]);

#endif
