/* speed.h -- what each production step buys, measured: seconds per million
 * camera samples for the lecture's path tracer on chapter 06's BVH, then on
 * the production structures, with the walls, and eight paths at a time.
 *
 * Usage:
 *   production_speed(256, 16, 5, "build/data/ch13_speed.csv", err, sizeof err);
 */
#ifndef SPEED_H
#define SPEED_H

#include <stdbool.h>
#include <stddef.h>

#include "09-path-tracing/scene_pt.h"

/* Every case counts at most this many bounces: Ray Tracing: The Rest of
 * Your Life's max_depth for its Cornell box. */
enum { SPEED_MAX_DEPTH = 50 };

enum { PRODUCTION_SPEED_CASES = 12 };
typedef struct {
    const char *label;
    double wall[2], cpu[2]; /* seconds per million camera samples, 1 and 2 threads */
    double scaling[2];      /* the 1-thread wall time over this one's */
    double rays_per_sample;
    bool wide; /* rendered eight paths at a time (path_tracer_wide.h) */
} production_speed_row;

/* The table for a scene the caller built: each case on 1 and 2 threads,
 * taking turns, the best of `repeats`. `production` builds the structure
 * the production cases trace through (production_scene_accel, or another
 * to compare with: the Embree bench passes Embree's), with `context`. The
 * scene's own structure is rebuilt per case and left as production's.
 * Fills rows[0 .. returned count - 1] if rows is not NULL. */
int production_speed_scene(pt_scene *sc, const char *label, int size, int spp, int repeats,
                           pt_accel_builder production, const void *context, production_speed_row *rows);

/* The table on the Cornell box, printed and written to csv_path (if not
 * NULL), then the watertight triangle test's cost to the renderer: the
 * lecture rung with the walls, one path and eight paths at a time, on the
 * watertight test and on Moller-Trumbore, taking turns. */
bool production_speed(int size, int spp, int repeats, const char *csv_path, char *err, size_t err_size);

/* The Cornell box's room (its walls and light, no blocks) with a diffuse
 * torus of about `triangles` triangles standing in it (2 u v of them,
 * u = 2 v): a scene larger than the flat set holds, whose size the
 * caller chooses (the benchmark's 10k and 100k meshes). Finished
 * (pt_scene_finish), on chapter 06's BVH. */
void production_scene_box_with_torus(pt_scene *sc, int triangles);

/* Seconds per million camera samples on 1 thread, wall and CPU, best of
 * `repeats`, on the Cornell box and the box with tori of 10k and 100k
 * triangles: eight paths at a time (the lecture rung, production
 * structures), one path at a time on the same structures (--one-path),
 * and chapter 09's MIS rung on chapter 06's BVH. Printed. */
void production_speed_scenes(int size, int spp, int repeats);

#endif
