/* counters.h -- what a render did, counted: rays by kind, tests per ray, and
 * samples dropped because they were NaN or Inf.
 *
 * They turn "what does this cost" into numbers a learner can see, and let the
 * tests assert that work a scene does not need is not done (no refraction
 * rays without glass). Each thread counts into its own copy; the render loop
 * adds them up at the end, so counting costs no synchronisation.
 */
#ifndef COUNTERS_H
#define COUNTERS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

typedef struct {
    uint64_t camera_rays;
    uint64_t shadow_rays;
    /* shadow rays whose two ends lie inside the scene's walls (the faces
     * with the whole scene in front of them): only the rest was tested */
    uint64_t shadow_rays_inside_walls;
    uint64_t reflection_rays;
    uint64_t refraction_rays;
    uint64_t indirect_rays;
    uint64_t box_tests;       /* ray-box tests in acceleration structures */
    uint64_t primitive_tests; /* ray-shape tests */
    uint64_t nonfinite_samples; /* NaN or Inf samples dropped before accumulation */
} ray_counters;

void counters_add(ray_counters *into, const ray_counters *from);
uint64_t counters_total_rays(const ray_counters *c);
/* A short human-readable report, e.g. after a render. */
void counters_print(FILE *out, const ray_counters *c, double seconds);

#endif
