/* wide_trace.c -- eight rays through each structure (wide_trace.h). */
#include "13-production/wide_trace.h"

#include "13-production/wide_bvh.h"
#include "13-production/flat.h"

/* ---- the flat set: its own eight-ray kernels ---------------------------------- */

static int flat_closest(const void *context, const rays8 *rays, int active, hits8 *hits,
                        ray_counters *counters)
{
    return flat_closest_hit8_raw(context, rays, active, hits, counters);
}

static int flat_any(const void *context, const rays8 *rays, int active, ray_counters *counters)
{
    return flat_any_hit8_raw(context, rays, active, counters);
}

/* ---- the wide BVH: the lanes as a stream --------------------------------------- */

/* The active lanes, packed, as rays. */
static int lanes_to_rays(const rays8 *rays, int active, ray out[RAYS8_LANES], int lane_of[RAYS8_LANES])
{
    int n = 0;
    for (int left = active; left != 0; left &= left - 1) {
        int k = __builtin_ctz((unsigned)left);
        lane_of[n] = k;
        out[n++] = rays8_get(rays, k);
    }
    return n;
}

static int wide_bvh_closest(const void *context, const rays8 *rays, int active, hits8 *hits,
                        ray_counters *counters)
{
    ray r[RAYS8_LANES] = {0}; /* (all of it: GCC cannot see that only the first n are read) */
    int lane_of[RAYS8_LANES];
    int n = lanes_to_rays(rays, active, r, lane_of);
    wide_bvh_raw_hit raw[RAYS8_LANES];
    bool found[RAYS8_LANES];
    wide_bvh_closest_hit_stream_raw(context, r, n, raw, found, counters);
    int hit = 0;
    for (int i = 0; i < n; i++) {
        int k = lane_of[i];
        hits->index[k] = raw[i].index;
        hits->t[k] = raw[i].t;
        hits->b1[k] = raw[i].b1;
        hits->b2[k] = raw[i].b2;
        hit |= (int)found[i] << k;
    }
    return hit;
}

static int wide_bvh_any(const void *context, const rays8 *rays, int active, ray_counters *counters)
{
    ray r[RAYS8_LANES] = {0}; /* (all of it: GCC cannot see that only the first n are read) */
    int lane_of[RAYS8_LANES];
    int n = lanes_to_rays(rays, active, r, lane_of);
    bool found[RAYS8_LANES];
    wide_bvh_any_hit_stream(context, r, n, found, counters);
    int hit = 0;
    for (int i = 0; i < n; i++)
        hit |= (int)found[i] << lane_of[i];
    return hit;
}

/* The lanes one after the other, each walking the tree alone (the
 * default: for eight rays the stream's turns cost more than they hide,
 * 10-25 % more CPU per sample on the box with a 10k or 100k torus; and a
 * packet of the eight, walking together while they hit the same boxes,
 * 11-19 % more on the mesh scenes: the lanes are at different bounces and
 * part after a node or two). */
static int wide_bvh_closest_single(const void *context, const rays8 *rays, int active, hits8 *hits,
                               ray_counters *counters)
{
    int hit = 0;
    for (int left = active; left != 0; left &= left - 1) {
        int k = __builtin_ctz((unsigned)left);
        wide_bvh_raw_hit raw;
        wide_bvh_closest_hit_raw(context, rays8_get(rays, k), &raw, counters);
        hits->index[k] = raw.index;
        hits->t[k] = raw.t;
        hits->b1[k] = raw.b1;
        hits->b2[k] = raw.b2;
        hit |= (raw.index >= 0) << k;
    }
    return hit;
}

/* ---- any accel: one ray after the other ------------------------------------------ */

static int accel_closest(const void *context, const rays8 *rays, int active, hits8 *hits,
                         ray_counters *counters)
{
    int hit = 0;
    for (int left = active; left != 0; left &= left - 1) {
        int k = __builtin_ctz((unsigned)left);
        hit_record record;
        if (!accel_closest_hit(context, rays8_get(rays, k), &record, counters))
            continue;
        hits->index[k] = record.shape_id; /* chapter 03's records: the triangle, and b1, b2 as u, v */
        hits->t[k] = record.t;
        hits->b1[k] = record.u;
        hits->b2[k] = record.v;
        hit |= 1 << k;
    }
    return hit;
}

static int accel_any(const void *context, const rays8 *rays, int active, ray_counters *counters)
{
    int hit = 0;
    for (int left = active; left != 0; left &= left - 1) {
        int k = __builtin_ctz((unsigned)left);
        hit |= (int)accel_any_hit(context, rays8_get(rays, k), counters) << k;
    }
    return hit;
}

/* ---- nothing to hit -------------------------------------------------------------- */

static int none_closest(const void *context, const rays8 *rays, int active, hits8 *hits,
                        ray_counters *counters)
{
    (void)context, (void)rays, (void)active, (void)hits, (void)counters;
    return 0;
}

static int none_any(const void *context, const rays8 *rays, int active, ray_counters *counters)
{
    (void)context, (void)rays, (void)active, (void)counters;
    return 0;
}

wide_tracer wide_tracer_for(const accel *a)
{
    if (a == NULL || a->set == NULL || a->set->count == 0)
        return (wide_tracer){none_closest, none_any, a, "nothing"};
    if (flat_is(a))
        return (wide_tracer){flat_closest, flat_any, a, "the flat set, eight rays per AVX instruction"};
    if (wide_bvh_is(a))
        return (wide_tracer){wide_bvh_closest_single, accel_any, a, "the " WIDE_BVH_NAME ", each lane's ray walking it alone"};
    return (wide_tracer){accel_closest, accel_any, a, "one ray at a time"};
}

wide_tracer wide_tracer_streams(const accel *a)
{
    if (!wide_bvh_is(a))
        return wide_tracer_for(a);
    return (wide_tracer){wide_bvh_closest, wide_bvh_any, a, "the " WIDE_BVH_NAME ", the eight rays as a stream"};
}
