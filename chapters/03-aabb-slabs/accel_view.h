/* accel_view.h -- looking at a mesh through any acceleration structure
 * (accel.h): what the programs of chapters 03-06 render.
 *
 * Usage:
 *   accel_view view = {structure, heatmap, 200.0f};
 *   camera cam = accel_view_camera(set.bounds, width, height);
 *   program_render(&opts, "04-uniform-grid", accel_view_radiance, &view, &cam, &stats);
 */
#ifndef ACCEL_VIEW_H
#define ACCEL_VIEW_H

#include <stdbool.h>

#include "03-aabb-slabs/accel.h"
#include "camera.h"
#include "rng.h"

/* What every accelerator chapter's program renders: the mesh lit by a light
 * at the eye (brightest where it faces the camera), or, with heatmap set, the
 * cost of each ray: the nodes or cells it visited plus the triangles it
 * tested, as a colour from dark blue (cheap) to yellow and white (expensive),
 * so you can see where a structure works hard. */
typedef struct {
    const accel *structure;
    bool heatmap;
    float heatmap_max_cost; /* the cost shown as white */
} accel_view;

vec3 accel_view_radiance(const void *view, ray r, pcg32 *rng, ray_counters *counters);
/* The view of the Embree harness's coherent ray set: from
 * c + unit(0.3, 0.4, 1) * 2.5 * half-diagonal, looking at the centre c of
 * the bounds, tan(vertical fov / 2) = 0.3. */
camera accel_view_camera(aabb bounds, int width, int height);
/* The heat map's colour for cost / max_cost. */
vec3 accel_heat_colour(float fraction);

#endif
