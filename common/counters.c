#include "counters.h"
#include "run_record.h"

#include "atomic_file.h"

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

void counters_path_for_image(const char *image_path, char *out, size_t out_size)
{
    const char *dot = strrchr(image_path, '.');
    const char *slash = strrchr(image_path, '/');
    size_t stem = (dot != NULL && (slash == NULL || dot > slash)) ? (size_t)(dot - image_path) : strlen(image_path);
    snprintf(out, out_size, "%.*s.counters.json", (int)stem, image_path);
}

bool counters_write_json(const char *path, const ray_counters *c, double seconds, const char *extra, char *err,
                         size_t err_size)
{
    char record[8192];
    run_record_json(record, sizeof record);
    atomic_file out;
    if (!atomic_file_open(&out, path, err, err_size))
        return false;
    fprintf(out.stream,
            "{\n  \"camera_rays\": %" PRIu64 ",\n  \"shadow_rays\": %" PRIu64 ",\n  \"shadow_rays_inside_walls\": %" PRIu64
            ",\n  \"reflection_rays\": %" PRIu64
            ",\n  \"refraction_rays\": %" PRIu64 ",\n  \"indirect_rays\": %" PRIu64 ",\n  \"box_tests\": %" PRIu64
            ",\n  \"primitive_tests\": %" PRIu64 ",\n  \"nonfinite_samples_dropped\": %" PRIu64
            ",\n  \"seconds\": %.6f%s%s%s%s\n}\n",
            c->camera_rays, c->shadow_rays, c->shadow_rays_inside_walls, c->reflection_rays, c->refraction_rays,
            c->indirect_rays, c->box_tests, c->primitive_tests, c->nonfinite_samples, seconds,
            extra != NULL ? ",\n  " : "", extra != NULL ? extra : "", record[0] != '\0' ? ",\n  " : "", record);
    return atomic_file_commit(&out, err, err_size);
}
