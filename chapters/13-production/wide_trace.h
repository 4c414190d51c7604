/* wide_trace.h -- how the eight-path renderer traces its rays: eight at a
 * time, through whatever structure the scene's triangles are in.
 *
 * The renderer (path_tracer_wide.h) keeps eight paths' rays side by side
 * (rays8.h) and asks two questions of them, for the lanes of a
 * mask: where does each ray first meet a triangle (closest_hit8, which
 * answers with the triangle's index, t and the barycentrics b1, b2 -- what
 * triangle_set_fill_hit() makes the hit record from), and is anything in
 * the way of each segment (any_hit8, a shadow ray per lane). A wide_tracer
 * is those two functions and their context: any structure that answers
 * them can stand behind the renderer.
 *
 *   the flat set     flat.h's eight-ray AVX kernels, eight rays per
 *                    instruction against every triangle: for a few dozen
 *                    triangles (the Cornell box)
 *   the 8-wide BVH   wide_bvh.h's traversal, each lane's ray walking the tree
 *                    alone (for meshes); or, on request, as a ray stream
 *                    (wide_bvh_closest_hit_stream: the eight take turns node
 *                    by node, so that one ray's wait for memory overlaps
 *                    the others' work -- for eight rays the turns cost
 *                    more than they hide)
 *   any accel        chapter 03's interface, one ray after the other (the
 *                    structures of chapters 03-06; a reference)
 *
 * A variant on another library's kernels (Embree's rtcIntersect8 and
 * rtcOccluded8: primID, tfar, u, v) fills the same two functions; the
 * renderer's answers are then as exact as that library's. Spheres are not
 * the tracer's business: the renderer tests them itself, lane by lane.
 *
 * Usage:
 *   wide_tracer t = wide_tracer_for(accel);     or your own
 *   int hit = t.closest_hit8(t.context, &rays, active, &hits, &counters);
 *   int blocked = t.any_hit8(t.context, &segments, active, &counters);
 */
#ifndef WIDE_TRACE_H
#define WIDE_TRACE_H

#include "03-aabb-slabs/accel.h"
#include "13-production/rays8.h"

typedef struct {
    /* The lanes of `active`: bit k of the result set if rays lane k meets a
     * triangle in (t_min, t_max); hits->index[k] is that triangle's index
     * in the scene's triangle_set, hits->t[k], b1[k], b2[k] where. Other
     * lanes' entries are left undefined. */
    int (*closest_hit8)(const void *context, const rays8 *rays, int active, hits8 *hits,
                        ray_counters *counters);
    /* The lanes of `active`: bit k set if anything lies on segment k, in
     * (t_min, t_max). */
    int (*any_hit8)(const void *context, const rays8 *rays, int active, ray_counters *counters);
    const void *context;
    const char *name; /* for what the renderer prints */
} wide_tracer;

/* The tracer of a built structure: the flat set's kernels for flat_build's,
 * the 8-wide BVH's walk for wide_bvh_build's, else accel_closest_hit() and
 * accel_any_hit() one ray at a time. NULL: a tracer that finds nothing (a
 * scene with no occluders). The structure must outlive the tracer. */
wide_tracer wide_tracer_for(const accel *a);
/* The same, but an 8-wide BVH's eight rays traced as a stream (to compare). */
wide_tracer wide_tracer_streams(const accel *a);

#endif
