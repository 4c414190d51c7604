/* path_tracer_wide.h -- the lecture's path tracer, eight paths at a time.
 *
 * One path is a chain: each bounce waits for the ray before it, and the
 * processor has little to do while it waits. Eight paths -- eight pixels,
 * each with its own random numbers, its samples one after another -- are
 * eight chains side by side: their rays are traced together, eight per AVX
 * instruction (chapter 06's flat_closest_hit8_raw and flat_any_hit8_raw,
 * shadow rays queued until there are eight, and tested against the
 * occluders alone when all eight lie inside the walls), so are the light
 * sample's and the
 * bounce's arithmetic and the two rays' offsets (AVX2, where the processor
 * has it; lane by lane, with the same bits, where not), and the rest of the
 * shading, one path at a time, gives the processor eight independent things
 * to do instead of one. A lane whose path ends
 * starts its pixel's next sample; a lane whose pixel is done takes the next
 * pixel.
 *
 * Each pixel draws the same random numbers in the same order as
 * path_trace_radiance() and makes the same decisions (the same rays, hits,
 * light samples and roulette), so its samples are the lecture rung's but for
 * rounding: the sum along a path is added from the camera out instead of
 * from the last bounce back (the recursion), which moves the last bits.
 *
 * For the lecture rung (any Russian roulette) on a scene the flat set holds (at most 64
 * triangles: chapter 09's Cornell box), diffuse materials only, no spheres
 * and no point lights; path_tracer_wide_supported() says why not otherwise.
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

/* Can pt render eight paths at a time? If not, why (into why, if not NULL). */
bool path_tracer_wide_supported(const path_tracer *pt, char *why, size_t why_size);

/* render_estimate(), eight paths at a time: the same per-pixel streams, the
 * same counters but for primitive_tests (every triangle for every ray, in
 * a packet that runs until all its rays are answered). False, and *out
 * untouched, if not supported. */
bool render_estimate_wide(const path_tracer *pt, const camera *cam, int spp, uint64_t seed, int threads,
                          estimate_image *out);

/* The lanes' arithmetic (light sample, bounce, ray offsets) eight lanes
 * per AVX instruction (true, the default, where the processor has AVX2) or
 * one lane at a time: the
 * same bits either way (tests/test_ch09.c). Not thread-safe: set it before
 * rendering. */
void path_tracer_wide_use_avx(bool on);

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

/* For the tests: the light samples' arithmetic of up to eight vertices,
 * as the eight-path renderer does it (in AVX where it runs, else lane by
 * lane): bit k of the result says whether vertex k's sample adds light,
 * and contribution[k] is what it adds, times the throughput, if its shadow
 * ray gets through. Chapter 09's shade() computes the same from
 * pt_scene_sample_light() and bsdf_eval(). */
int path_tracer_wide_light_math(const wide_light_vertex *v, int count, vec3 contribution[8]);

#endif
