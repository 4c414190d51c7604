/* accel_view.c -- a mesh seen through any structure, or what each ray cost
 * (see accel_view.h). */
#include "03-aabb-slabs/accel_view.h"

#include "explain.h"

vec3 accel_heat_colour(float fraction)
{
    /* dark blue -> magenta -> orange -> yellow -> white, in linear RGB */
    static const vec3 ramp[5] = {{0.0f, 0.0f, 0.08f}, {0.45f, 0.02f, 0.45f}, {0.95f, 0.3f, 0.02f},
                                 {1.0f, 0.9f, 0.05f}, {1.0f, 1.0f, 1.0f}};
    float x = fminf(fmaxf(fraction, 0.0f), 1.0f) * 4.0f;
    int i = (int)fminf(x, 3.0f);
    return vec3_lerp(ramp[i], ramp[i + 1], x - (float)i);
}

vec3 accel_view_radiance(const void *view_ptr, ray r, pcg32 *rng, ray_counters *counters)
{
    (void)rng;
    const accel_view *view = view_ptr;
    uint64_t cost_before = counters->box_tests + counters->primitive_tests;
    hit_record hit;
    uint64_t boxes_before = counters->box_tests, triangles_before = counters->primitive_tests;
    bool found = accel_closest_hit(view->structure, r, &hit, counters);
    if (explain_on()) {
        explain_line(1, "%s: %llu nodes or cells visited, %llu triangles tested", view->structure->stats.name,
                     (unsigned long long)(counters->box_tests - boxes_before),
                     (unsigned long long)(counters->primitive_tests - triangles_before));
        if (found)
            explain_line(1, "closest hit: triangle #%d at t = %.6g; headlight shading |n . d| = %.4g", hit.shape_id,
                         (double)hit.t, (double)fabsf(vec3_dot(hit.normal_shading, vec3_normalize(r.direction))));
        else
            explain_line(1, "no triangle hit: the background");
    }
    if (view->heatmap) {
        float cost = (float)(counters->box_tests + counters->primitive_tests - cost_before);
        return accel_heat_colour(cost / view->heatmap_max_cost);
    }
    if (!found)
        return vec3_make(0.02f, 0.02f, 0.03f);
    float facing = fabsf(vec3_dot(hit.normal_shading, vec3_normalize(r.direction)));
    return vec3_scale(vec3_make(0.8f, 0.75f, 0.7f), 0.1f + 0.9f * facing);
}

camera accel_view_camera(aabb bounds, int width, int height)
{
    vec3 centre = aabb_centroid(bounds);
    float half_diagonal = 0.5f * vec3_length(aabb_extent(bounds));
    vec3 eye = vec3_add(centre, vec3_scale(vec3_normalize(vec3_make(0.3f, 0.4f, 1.0f)), 2.5f * half_diagonal));
    return camera_look_at(eye, centre, vec3_make(0, 1, 0), 2.0f * atanf(0.3f) * 180.0f / (float)PI, width, height);
}

