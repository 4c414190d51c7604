/* motion_scene.h -- chapter 09's scene plus objects that move while the
 * shutter is open, and the rays that carry a time to find them.
 *
 * The shutter is open for time in [0, 1). A moving sphere's centre is
 * c + t m; a moving mesh is its triangles (in their own BVH, built once)
 * translated by t m. To hit the mesh at time t we move the ray instead: the
 * ray o - t m + s d meets the untranslated mesh where o + s d meets the
 * translated one, at the same s. The static part (walls, lights, materials,
 * camera) is a pt_scene, so chapter 09's path tracer renders the same
 * scene, and its emitters are the lights sampled here too. Moving objects do
 * not emit light that is sampled: they are reached, like chapter 09's
 * emitting spheres, only by rays that hit them.
 *
 * Usage:
 *   motion_scene ms; motion_scene_init(&ms);      then build ms.base with pt_scene_add_*
 *   pt_scene_finish(&ms.base);
 *   motion_scene_add_sphere(&ms, centre, motion, radius, material);
 *   motion_scene_add_mesh(&ms, &triangles, motion);     (takes the mesh)
 *   if (motion_scene_intersect(&ms, (timed_ray){r, 0.3f}, &hit, &counters)) ...
 *   motion_scene_free(&ms);
 */
#ifndef MOTION_SCENE_H
#define MOTION_SCENE_H

#include "03-aabb-slabs/aabb.h"
#include "09-path-tracing/scene_pt.h"

/* A ray and the instant, in [0, 1) of the shutter interval, it travels at.
 * Its own type, not a field of common's ray, which every chapter shares. */
typedef struct {
    ray r;
    float time;
} timed_ray;

typedef struct {
    vec3 center; /* at time 0 */
    vec3 motion; /* displacement over the whole shutter: centre(t) = center + t motion */
    float radius;
    int material;
} moving_sphere;

typedef struct {
    mesh geometry; /* face materials index the base scene's materials */
    triangle_set triangles;
    accel *bvh;
    vec3 motion;   /* offset(t) = t motion */
    aabb swept;    /* the bounds over the whole shutter: at t = 0 united with t = 1 */
} moving_mesh;

typedef struct {
    pt_scene base;
    moving_sphere *spheres;
    int sphere_count, sphere_capacity;
    moving_mesh **meshes; /* each allocated on its own: its BVH points into it */
    int mesh_count, mesh_capacity;
    /* The lens the scene suggests (0: a pinhole), for the program's defaults. */
    float aperture_radius, focus_distance;
} motion_scene;

void motion_scene_init(motion_scene *ms);
void motion_scene_free(motion_scene *ms);
void motion_scene_add_sphere(motion_scene *ms, vec3 center, vec3 motion, float radius, int material);
/* Takes ownership of *geometry (left empty) and builds its BVH. */
void motion_scene_add_mesh(motion_scene *ms, mesh *geometry, vec3 motion);

/* Where a moving object is at `time`. */
vec3 moving_sphere_center(const moving_sphere *s, float time);
vec3 moving_mesh_offset(const moving_mesh *m, float time);
/* The bounds of a moving sphere over the whole shutter. */
aabb moving_sphere_swept_bounds(const moving_sphere *s);

/* The closest hit of the ray at its time: static triangles (shape_id >= 0,
 * the only hits whose emission the light samples already count), static
 * spheres, moving spheres and moving meshes (shape_id < 0). */
bool motion_scene_intersect(const motion_scene *ms, timed_ray tr, hit_record *hit, ray_counters *counters);
bool motion_scene_occluded(const motion_scene *ms, timed_ray tr, ray_counters *counters);

/* Chapter 10's built-in scene: every effect at once, in the Cornell box's
 * room. A GGX plate on the floor, a mirror sphere at the back, a glass
 * sphere in front (out of focus), a sphere moving sideways and a cube moving
 * up (motion blur) at the focus distance. */
void motion_scene_build_showcase(motion_scene *ms);
/* Its still part, the room, plate, mirror and glass (and the movers'
 * materials): chapters/10-distribution/scenes/showcase.scene. */
void motion_scene_build_showcase_still(pt_scene *sc);

#endif
