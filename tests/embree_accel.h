/* embree_accel.h -- Embree 3 behind chapter 03's accel interface, for the
 * benchmarks (bench_pt_embree.c, bench_scenes.c): a path tracer given this
 * accel (pt_scene_use_accel) traces every ray with rtcIntersect1 and
 * rtcOccluded1 and fills its hit records with the same
 * triangle_set_fill_hit() as ours. Header-only, static: each benchmark is
 * one program. Needs <embree3/rtcore.h> and -lembree3 (make bench-deps).
 *
 * Usage:
 *   accel *a = embree_build(set, TWIN_NONE);   NULL if Embree fails
 *   accel_closest_hit(a, r, &hit, &counters); ... accel_destroy(a);
 */
#ifndef EMBREE_ACCEL_H
#define EMBREE_ACCEL_H

#include <embree3/rtcore.h>
#include <stdlib.h>

#include "03-aabb-slabs/accel.h"
#include "memory.h"
#include "timer.h"

/* ---- an accel backed by Embree ------------------------------------------------ */

typedef enum { TWIN_NONE, TWIN_UV, TWIN_NO_SHADOWS } twin_kind;

typedef struct {
    accel base;
    RTCDevice device;
    RTCScene scene;
    twin_kind twin;
} embree_accel;

/* Embree's ray is ours field for field; its interval is closed, [tnear,
 * tfar], where ours is open: a hit exactly at t_min or t_max differs, which
 * float rounding makes as likely for either kernel. */
static struct RTCRay embree_ray(ray r)
{
    struct RTCRay e;
    e.org_x = r.origin.x;
    e.org_y = r.origin.y;
    e.org_z = r.origin.z;
    e.dir_x = r.direction.x;
    e.dir_y = r.direction.y;
    e.dir_z = r.direction.z;
    e.tnear = r.t_min;
    e.tfar = r.t_max;
    e.time = 0.0f;
    e.mask = 0xFFFFFFFFu;
    e.id = 0;
    e.flags = 0;
    return e;
}

static bool embree_closest_hit(const accel *a, ray r, hit_record *hit, ray_counters *counters)
{
    (void)counters;
    const embree_accel *ea = (const embree_accel *)a;
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    struct RTCRayHit rh;
    rh.ray = embree_ray(r);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(ea->scene, &context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID)
        return false;
    /* Embree's (u, v) weigh p1 and p2, as our (b1, b2) do: the point is
     * (1 - u - v) p0 + u p1 + v p2 (rtcore_ray.h). */
    float u = rh.hit.u, v = rh.hit.v;
    if (ea->twin == TWIN_UV) {
        float swap = u;
        u = v;
        v = swap;
    }
    triangle_set_fill_hit(a->set, (int)rh.hit.primID, r, rh.ray.tfar, u, v, hit);
    return true;
}

static bool embree_any_hit(const accel *a, ray r, ray_counters *counters)
{
    (void)counters;
    const embree_accel *ea = (const embree_accel *)a;
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    struct RTCRay e = embree_ray(r);
    rtcOccluded1(ea->scene, &context, &e);
    /* Embree marks an occluded ray by setting tfar to -inf. */
    return ea->twin != TWIN_NO_SHADOWS && e.tfar < 0.0f;
}

static void embree_destroy(accel *a)
{
    embree_accel *ea = (embree_accel *)a;
    rtcReleaseScene(ea->scene);
    rtcReleaseDevice(ea->device);
    free(ea);
}

static const accel_ops embree_ops = {embree_closest_hit, embree_any_hit, embree_destroy, NULL};

/* One triangle geometry over the set's corners (copied: triangle i is
 * vertices 3i, 3i+1, 3i+2, so Embree's primID is our triangle index), built
 * at medium quality as ../shared/anchors/embree_bench.c does. NULL if Embree
 * fails. */
static inline accel *embree_build(const triangle_set *set, twin_kind twin)
{
    double start = timer_seconds();
    /* One build thread: the scene is tiny, and the render's own threads do
     * the tracing (rtcIntersect1 may be called from any thread). */
    RTCDevice device = rtcNewDevice("threads=1");
    if (device == NULL)
        return NULL;
    RTCScene scene = rtcNewScene(device);
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_MEDIUM);
    RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(geometry, RTC_BUILD_QUALITY_MEDIUM);
    float *vertices = rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                              3 * sizeof(float), 3 * (size_t)set->count);
    unsigned *indices = rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                3 * sizeof(unsigned), (size_t)set->count);
    if (vertices == NULL || indices == NULL || rtcGetDeviceError(device) != RTC_ERROR_NONE) {
        rtcReleaseGeometry(geometry);
        rtcReleaseScene(scene);
        rtcReleaseDevice(device);
        return NULL;
    }
    for (int i = 0; i < set->count; i++) {
        const triangle *t = &set->triangles[i];
        const vec3 corners[3] = {t->p0, t->p1, t->p2};
        for (int c = 0; c < 3; c++) {
            vertices[9 * i + 3 * c + 0] = corners[c].x;
            vertices[9 * i + 3 * c + 1] = corners[c].y;
            vertices[9 * i + 3 * c + 2] = corners[c].z;
            indices[3 * i + c] = (unsigned)(3 * i + c);
        }
    }
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(scene, geometry);
    rtcReleaseGeometry(geometry);
    rtcCommitScene(scene);
    if (rtcGetDeviceError(device) != RTC_ERROR_NONE) {
        rtcReleaseScene(scene);
        rtcReleaseDevice(device);
        return NULL;
    }
    embree_accel *ea = memory_allocate(1, sizeof *ea);
    ea->base.ops = &embree_ops;
    ea->base.set = set;
    ea->base.stats = (accel_stats){.name = "Embree 3 (medium)", .build_seconds = timer_seconds() - start};
    ea->device = device;
    ea->scene = scene;
    ea->twin = twin;
    return &ea->base;
}

#endif
