/* accel_program.h -- what the programs of chapters 03-06 share, so that
 * their main.c files hold only what is their own (the structure's flags
 * and figures): the mesh their flags ask for and the camera that looks at
 * it, the ray sets of the Embree harness and their timing on one thread,
 * and the triangles of a scene file.
 *
 * Usage:
 *   accel_input in;
 *   int status = accel_input_load(&in, &opts, "04-uniform-grid", "tori", NULL, 102400, 6);
 *   if (status != 0) return status;
 *   ... triangle_set_from_mesh(&set, &in.m); build; render with accel_input_camera() ...
 *   accel_bench_harness(structure, true);
 *   accel_input_free(&in);
 */
#ifndef ACCEL_PROGRAM_H
#define ACCEL_PROGRAM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "03-aabb-slabs/accel.h"
#include "camera.h"
#include "cli.h"
#include "mesh.h"
#include "render.h"
#include "scene_file.h"

/* The ray sets of the Embree harness (../shared/anchors/embree_bench.c),
 * generated operation for operation as it does, for timing on the same work:
 * coherent, a 1024 x 1024 pinhole image of the bounds in scanline order;
 * incoherent, 2^20 rays with origins uniform in the bounds and directions
 * uniform on the sphere (splitmix64 from seed 0xBADC0DE). The caller frees. */
ray *accel_harness_rays(aabb bounds, bool coherent, int *count);

/* Rays aimed at the mesh itself, whatever a camera sees: origins uniform in
 * the bounds, each aimed at the centroid of a triangle picked uniformly, so
 * a mesh's dense parts get their share of the rays (the teapot, not the
 * empty stadium). Seeded PCG32; the caller frees. */
ray *accel_aimed_rays(const triangle_set *set, int count, uint64_t seed);
/* ---- scene files (scene_mesh.c) ---------------------------------------------
 * Chapters 03-06 trace triangles only, lit by a headlight: from a scene file
 * they take the triangle, quad and mesh shapes, appended to m in order, and
 * the camera. Each shape statement is one object (the tori field generator
 * gives one per torus): *object_first (allocated, may be NULL to skip) gets
 * object_count + 1 entries, object k owning faces [first[k], first[k+1]).
 * Everything else -- spheres, planes, tori, lights, materials, effects -- is
 * named in one warning each, not silently dropped. False with err
 * ("file:line:col: ...") if a mesh fails to load or there are no
 * triangles; m is then unchanged. */
bool accel_mesh_from_desc(mesh *m, const scene_desc *d, const char *label, int **object_first, int *object_count,
                          char *err, size_t err_size);
/* The scene file's camera if it has one, else accel_view_camera(bounds) (accel_view.h). */
camera accel_scene_camera(const scene_desc *d, aabb bounds, int width, int height);

/* ---- what the programs of chapters 04-06 share (accel_program.c) -------------
 * The mesh their flags ask for: --scene FILE (its triangles and camera),
 * else --obj FILE, else the procedural --mesh NAME: "tori" (the harness's
 * field of tori_triangles), "stadium" (the teapot in a stadium) or
 * "icosphere". On bad input prints "program: message" and returns the exit
 * status (1: a bad or empty file, 2: a bad flag), with nothing left to free;
 * 0 on success, and then accel_input_free releases it. */
typedef struct {
    mesh m;
    scene_desc desc;  /* --scene's description (empty without --scene) */
    const char *name; /* what was loaded, for messages */
    bool stadium;     /* the teapot in a stadium: seen by a spectator */
} accel_input;

/* The procedural meshes by name, for a CLI_CHOICE --mesh flag:
 * "tori", "stadium", "icosphere", then NULL. */
extern const char *const accel_mesh_names[];

int accel_input_load(accel_input *in, cli_options *opts, const char *program, const char *mesh_name,
                     const char *obj_path, int tori_triangles, int icosphere_subdivisions);
/* The scene file's camera, a spectator's in the stadium, else the harness's
 * view of the bounds. */
camera accel_input_camera(const accel_input *in, aabb bounds, int width, int height);
void accel_input_free(accel_input *in);
/* The structure `a`, built over in's mesh, rendered as chapters 04-06 show
 * it: accel_view_radiance() (with heatmap, each ray's cost, white at
 * heatmap_max) through accel_input_camera() as --eye, --target and --fov
 * override it (view). Returns program_render()'s status, with its stats. */
int accel_input_render(const cli_options *opts, const char *program, const accel_input *in, const accel *a,
                       bool heatmap, float heatmap_max, const camera_override *view, render_stats *stats);
/* Times the harness's coherent or incoherent ray set (accel_harness_rays)
 * on one thread: the median of 3 runs of closest hit and of any hit, by the
 * wall clock and by this thread's CPU time, with the hit fraction, the sum of
 * t (to compare with Embree's) and the tests per ray. */
void accel_bench_harness(const accel *a, bool coherent);

#endif
