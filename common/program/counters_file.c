/* counters_file.c -- the counters as JSON, written through atomic_file. */
#include "counters_file.h"

#include <inttypes.h>
#include <stdio.h>
#include <string.h>

#include "atomic_file.h"
#include "run_record.h"

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
