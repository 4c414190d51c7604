#include "counters.h"

#include <inttypes.h>
#include <stdio.h>
#include <string.h>

void counters_add(ray_counters *into, const ray_counters *from)
{
    into->camera_rays += from->camera_rays;
    into->shadow_rays += from->shadow_rays;
    into->shadow_rays_inside_walls += from->shadow_rays_inside_walls;
    into->reflection_rays += from->reflection_rays;
    into->refraction_rays += from->refraction_rays;
    into->indirect_rays += from->indirect_rays;
    into->box_tests += from->box_tests;
    into->primitive_tests += from->primitive_tests;
    into->nonfinite_samples += from->nonfinite_samples;
}

uint64_t counters_total_rays(const ray_counters *c)
{
    return c->camera_rays + c->shadow_rays + c->reflection_rays + c->refraction_rays + c->indirect_rays;
}

void counters_print(FILE *out, const ray_counters *c, double seconds)
{
    uint64_t rays = counters_total_rays(c);
    fprintf(out, "rays: %" PRIu64 " camera, %" PRIu64 " shadow, %" PRIu64 " reflection, %" PRIu64
                 " refraction, %" PRIu64 " indirect",
            c->camera_rays, c->shadow_rays, c->reflection_rays, c->refraction_rays, c->indirect_rays);
    /* No rate without a time (one explained pixel is not timed). */
    if (seconds > 0)
        fprintf(out, " (%.2f Mrays/s)", (double)rays / seconds * 1e-6);
    fputc('\n', out);
    if (rays > 0)
        fprintf(out, "tests per ray: %.2f primitive, %.2f box\n", (double)c->primitive_tests / (double)rays,
                (double)c->box_tests / (double)rays);
    if (c->shadow_rays_inside_walls > 0)
        fprintf(out, "shadow rays inside the walls (walls not tested): %" PRIu64 " of %" PRIu64 "\n",
                c->shadow_rays_inside_walls, c->shadow_rays);
    if (c->nonfinite_samples > 0)
        fprintf(out, "warning: %" PRIu64 " NaN/Inf samples dropped\n", c->nonfinite_samples);
}
