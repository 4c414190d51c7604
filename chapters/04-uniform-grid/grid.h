/* grid.h -- the uniform grid of lecture 14: cut the scene's bounding box into
 * equal cells, store in each cell the triangles that overlap it, and walk a
 * ray through the cells it pierces, in order, with the 3D-DDA of Amanatides
 * and Woo (1987), testing only the triangles stored in those cells.
 *
 * Usage:
 *   triangle_set tris; triangle_set_from_mesh(&tris, &m);
 *   accel *g = grid_build(&tris, GRID_DEFAULT_DENSITY);     #cells = 27 * #triangles
 *   if (accel_closest_hit(g, r, &hit, &counters)) ...
 *   grid_summary s = grid_summarize(g);                      cells, empty cells, fullest cell
 *   accel_destroy(g);
 *
 * Counters, per ray: box_tests = 1 (the slab test against the grid's bounds)
 * + the cells visited; primitive_tests = the triangles tested (a triangle
 * stored in several cells the ray visits is tested once per cell: there is no
 * mailbox; the chapter text says why).
 */
#ifndef GRID_H
#define GRID_H

#include "03-aabb-slabs/accel.h"

/* The lecture's heuristic: #cells = C * #objects, with C about 27 in 3D
 * (3 x 3 x 3 cells per object). */
static const float GRID_DEFAULT_DENSITY = 27.0f;

/* cell_density: the C above (> 0). The resolution per axis follows the
 * bounds' aspect so that cells are nearly cubes; the total is capped (see
 * grid.c) so that memory stays bounded whatever C is asked for. */
accel *grid_build(const triangle_set *set, float cell_density);

/* The same grid, traversed with the naive rule "stop at the first cell in
 * which any triangle is hit". Wrong: a triangle stored in this cell may be
 * hit at a point in a later cell, and a closer hit may wait in the next
 * cell. Kept only to show that failure (tests/test_ch04.c). */
accel *grid_build_naive_exit(const triangle_set *set, float cell_density);

/* What a grid looks like inside: the figures that show where it works and
 * where it fails (teapot in a stadium). */
enum { GRID_HISTOGRAM_BINS = 7 };
typedef struct {
    int resolution[3];  /* cells along x, y, z */
    vec3 cell_size;
    long cells;
    long empty_cells;
    int largest_cell;   /* triangles in the fullest cell */
    long references;
    /* cells holding 0, 1, 2-4, 5-16, 17-64, 65-256, more than 256 triangles */
    long histogram[GRID_HISTOGRAM_BINS];
} grid_summary;

/* Zeros if a is not a grid. */
grid_summary grid_summarize(const accel *a);

#endif
