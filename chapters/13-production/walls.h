/* walls.h -- the production structures, and one shortcut that pays on rooms.
 *
 * production_accel_build() picks a structure by size: the flat set (every
 * triangle tested, eight per AVX instruction) for a few dozen triangles,
 * the 8-wide BVH above that.
 *
 * Walls cast no shadows. A triangle lies in a plane; a segment whose two
 * ends are in front of that plane cannot meet it (a half-space is convex).
 * A shadow ray is such a segment, from a surface point to a point on a
 * light, so a triangle with the whole scene in front of it -- a wall of a
 * room -- never blocks one. walls_accel_build() finds such triangles once
 * and answers each shadow ray whose two ends lie in front of every wall
 * plane from the other triangles alone (the occluders). The check of each
 * ray's ends, not the analysis, makes the answer right: a ray from
 * anywhere still gets the answer of the full structure.
 *
 * This is a scene-specific shortcut: it pays on the Cornell box, whose
 * five walls every shadow ray's box overlaps, and does nothing for a mesh
 * in the open (no triangle has the whole scene in front of it). The
 * README's "Scene-specific shortcuts" measures both.
 *
 * Usage (chapter 09's scene, traced through it):
 *   pt_scene_use_accel(&sc, production_scene_accel, &sc);  walls on
 *   ... walls_found(sc.bvh), walls_triangle_count(sc.bvh)
 */
#ifndef WALLS_H
#define WALLS_H

#include <stdbool.h>

#include "09-path-tracing/scene_pt.h"
#include "03-aabb-slabs/accel.h"
#include "13-production/rays8.h"
#include "13-production/light_tree.h"

/* The flat set for at most 64 triangles, else the 8-wide BVH (binned SAH). */
accel *production_accel_build(const triangle_set *set);

typedef struct walls_accel walls_accel;

/* The structure of all triangles (production_accel_build), with the walls
 * of `scene` found (every vertex and sphere of the scene on their front
 * side) unless `on` is false. Closest hits go to the structure of all
 * triangles; any-hit queries skip the walls where they cannot block. */
accel *walls_accel_build(const triangle_set *set, const pt_scene *scene, bool on);
/* The same over another structure: `inner` builds both the structure of
 * all triangles and that of the occluders (the Embree bench passes
 * Embree's, to compare kernels with the walls in both). */
typedef accel *(*walls_inner_builder)(const triangle_set *set);
accel *walls_accel_build_over(const triangle_set *set, const pt_scene *scene, bool on, walls_inner_builder inner);
/* chapter 09's pt_accel_builder form of it, walls on; context: the pt_scene. */
accel *production_scene_accel(const triangle_set *set, const void *scene);
/* ... and walls off: the production structure alone. */
accel *production_scene_accel_no_walls(const triangle_set *set, const void *scene);

bool walls_is(const accel *a);
/* Has the analysis found walls (and are they on)? */
bool walls_found(const accel *a);
int walls_triangle_count(const accel *a);
/* The distinct planes of the walls (a flat quad's two triangles share one). */
int walls_plane_count(const accel *a);
/* For the tests' twins only: the planes without their margin for rounding. */
void walls_drop_slack(accel *a);
/* The structure of all triangles, and of the occluders (NULL if none). */
const accel *walls_all(const accel *a);
const accel *walls_occluders(const accel *a);
/* The scene's light tree, built with the structures for a scene of at
 * least LIGHT_TREE_MIN_EMITTERS emitting triangles; else NULL (and NULL
 * when a is not a walls_accel). */
const light_tree *walls_light_tree(const accel *a);

/* Do both ends of r, r(t_min) and r(t_max), lie in front of every wall
 * plane, by more than the rounding of the test? False for an infinite
 * t_max, when there are no walls, and when a is not a walls_accel. */
bool walls_segment_inside(const accel *a, const ray *r);
/* The same for the lanes of `active` of eight rays (rays8.h): bit k
 * is walls_segment_inside() of lane k, eight lanes per AVX instruction
 * where the processor has AVX. */
int walls_segments8_inside(const accel *a, const rays8 *rays, int active);

#endif
