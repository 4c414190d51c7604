/* bench_scenes.h -- the benchmark's scenes: what chapter 13's renderer is
 * timed on, beside Embree's kernels, chapter 09's MIS rung and Blender's
 * Cycles (make bench). Generated, so that nothing needs a download:
 *
 *   cornell        chapter 09's Cornell box (32 triangles)
 *   cornell-10k    the box with a bumpy torus of 10,240 triangles on the short block
 *   cornell-100k   ... of 102,400 triangles
 *   cornell-1m     ... of 1,048,576 triangles
 *   glossy-glass   chapter 09's materials scene (a GGX copper block, a glass
 *                  ball), the ball as 5,120 flat triangles (OBJ has no spheres)
 *   open-100k      no room: the Embree harness's tori field (102,400
 *                  triangles) in GGX gold over a ground, under a sky, with
 *                  one small lamp (the scene file's `background`)
 *   many-lights    the box with 5,104 small lamps of random power (10,208
 *                  emitting triangles) on its ceiling and three walls:
 *                  what chapter 13's light tree is for (light_tree.h)
 *
 * The torus is the same surface at every size (a grid of U x V quads, two
 * triangles each; the sizes of the Embree harness's tori field), so the
 * images differ only by tessellation.
 *
 * Usage:
 *   pt_scene sc;
 *   if (bench_scene_build(&sc, "cornell-100k")) ... pt_scene_free(&sc);
 *   bench_scenes_write("build/bench/scenes", err, sizeof err);   every scene as
 *       NAME.obj + NAME.mtl (pt_scene_write_obj) and NAME.scene (camera + mesh)
 */
#ifndef BENCH_SCENES_H
#define BENCH_SCENES_H

#include <stdbool.h>
#include <stddef.h>

#include "09-path-tracing/scene_pt.h"

/* The names, NULL-terminated, and a line on each. */
extern const char *const BENCH_SCENE_NAMES[];
extern const char *const BENCH_SCENE_NOTES[];

/* Builds the scene named `name` (finished: chapter 06's BVH, emitters);
 * false, sc untouched, if there is none of that name. */
bool bench_scene_build(pt_scene *sc, const char *name);

/* A bumpy torus lying around the y axis, centre c, major radius R, tube
 * radius r0 modulated by 20 % and 6 % waves: 2 u v triangles of material m. */
void bench_bumpy_torus(mesh *m, vec3 c, float major, float r0, int u, int v, int material);

/* Writes DIR/NAME.obj, NAME.mtl and NAME.scene for the scene `name` (the
 * scene file: its camera, and `mesh path "NAME.obj"`). Each through a
 * temporary file. False with err on failure. */
bool bench_scene_write(const char *dir, const char *name, char *err, size_t err_size);

#endif
