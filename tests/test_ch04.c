/* test_ch04.c -- the uniform grid: brute force agreement on every test mesh,
 * the resolution heuristic, and the 3D-DDA's hard cases, each with its
 * answer worked out by hand, plus the naive early exit failing the case it
 * exists for. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>

#include "test_support.h"
#include "accel_check.h"

#include "04-uniform-grid/grid.h"

/* t values below are exact in real numbers; the triangle test in float gets
 * within a few ulps of t <= 10. */
static const double T_TOLERANCE = 1e-5;

typedef accel *(*grid_builder)(const triangle_set *set, float cell_density);

/* A handful of triangles, their set and a grid over them. */
typedef struct {
    mesh m;
    triangle_set set;
    accel *grid;
    accel *brute;
} scene;

static void scene_make(scene *s, const vec3 (*corners)[3], int count, float density, grid_builder build)
{
    mesh_init(&s->m);
    for (int i = 0; i < count; i++) {
        int a = mesh_add_position(&s->m, corners[i][0]);
        int b = mesh_add_position(&s->m, corners[i][1]);
        int c = mesh_add_position(&s->m, corners[i][2]);
        mesh_add_triangle(&s->m, a, b, c, -1);
    }
    triangle_set_from_mesh(&s->set, &s->m);
    s->grid = build(&s->set, density);
    s->brute = brute_force_build(&s->set);
}

static void scene_free(scene *s)
{
    accel_destroy(s->grid);
    accel_destroy(s->brute);
    triangle_set_free(&s->set);
    mesh_free(&s->m);
}

typedef struct {
    bool found;
    float t;
    int triangle;
    ray_counters counters;
} trace_result;

/* Trace r through the scene's grid; also checks that brute force finds the
 * same and that any-hit agrees. */
static trace_result trace(const scene *s, ray r)
{
    trace_result out = {0};
    hit_record hit, want;
    out.found = accel_closest_hit(s->grid, r, &hit, &out.counters);
    if (out.found) {
        out.t = hit.t;
        out.triangle = hit.shape_id;
    }
    ray_counters scratch = {0};
    bool want_found = accel_closest_hit(s->brute, r, &want, &scratch);
    assert_int_equal(out.found, want_found);
    if (want_found)
        assert_close(out.t, want.t, ACCEL_CHECK_T_TOLERANCE * want.t);
    assert_int_equal(accel_any_hit(s->grid, r, &scratch), want_found);
    return out;
}

static ray ray_from(float ox, float oy, float oz, float dx, float dy, float dz)
{
    return ray_make(vec3_make(ox, oy, oz), vec3_make(dx, dy, dz));
}

static void assert_resolution(const accel *g, int nx, int ny, int nz)
{
    grid_summary s = grid_summarize(g);
    assert_int_equal(s.resolution[0], nx);
    assert_int_equal(s.resolution[1], ny);
    assert_int_equal(s.resolution[2], nz);
}

/* Small triangles in two opposite corners that make the bounds [0,4]^3
 * (or the box shifted by `offset`). With 4 triangles and C = 16 the grid
 * has C N = 64 cells over a volume of 64: 4 x 4 x 4 unit cells, boundaries
 * at 1, 2 and 3 (plus the offset). Rays in the tests stay clear of them. */
static const vec3 corner_low[3] = {{0, 0, 0}, {0.1f, 0, 0}, {0, 0.1f, 0}};
static const vec3 corner_high[3] = {{4, 4, 4}, {3.9f, 4, 4}, {4, 3.9f, 4}};
static const float FOUR_CUBED_DENSITY = 16.0f; /* with 4 triangles */

/* ---- the differential test ----------------------------------------------- */

static accel *build_grid(const triangle_set *s) { return grid_build(s, GRID_DEFAULT_DENSITY); }

static void test_grid_agrees_with_brute_force(void **state)
{
    (void)state;
    exercise_checks("dda_step");
    accel_check_all(build_grid, 15000, "grid");
}

/* Very coarse (C = 0.5: most cells hold many triangles, big triangles span
 * few cells) and very fine (C = 300: triangles span many cells, rays walk
 * long) grids take the same test on the meshes where that matters. */
static float check_density;
static accel *build_grid_at_density(const triangle_set *s) { return grid_build(s, check_density); }

static void test_grid_agrees_with_brute_force_coarse_and_fine(void **state)
{
    (void)state;
    const float densities[2] = {0.5f, 300.0f};
    const accel_check_mesh kinds[4] = {MESH_SOUP, MESH_STADIUM, MESH_COINCIDENT, MESH_FLAT};
    long mismatches = 0;
    for (int i = 0; i < 2; i++) {
        check_density = densities[i];
        for (int k = 0; k < 4; k++)
            mismatches += accel_check_mesh_kind(build_grid_at_density, kinds[k], 2000, "grid");
    }
    assert_int_equal(mismatches, 0);
}

/* ---- the resolution heuristic -------------------------------------------- */

/* #cells = C * #triangles, cells near cubic: on the tori field (10240
 * triangles) the count is within rounding of 27 * 10240 = 276480 (each axis
 * rounds by at most half a cell out of about 65, 1.5 %, so 5 % covers all
 * three), and the cell sides agree to the same rounding. */
static void test_resolution_follows_the_lecture_heuristic(void **state)
{
    (void)state;
    mesh m;
    accel_check_make_mesh(&m, MESH_TORI_FIELD);
    triangle_set set;
    triangle_set_from_mesh(&set, &m);
    accel *g = grid_build(&set, GRID_DEFAULT_DENSITY);
    grid_summary s = grid_summarize(g);
    double target = 27.0 * set.count;
    assert_in_range(s.cells, (long)(0.95 * target), (long)(1.05 * target));
    float smallest = fminf(s.cell_size.x, fminf(s.cell_size.y, s.cell_size.z));
    float largest = vec3_max_component(s.cell_size);
    assert_true(largest / smallest < 1.05f);
    assert_int_equal(g->stats.nodes, s.cells);
    assert_int_equal(g->stats.leaves, s.cells - s.empty_cells);
    accel_destroy(g);

    /* An absurd C is capped: memory stays bounded (2^24 cells), and the
     * grid is still right. */
    g = grid_build(&set, 1e9f);
    s = grid_summarize(g);
    assert_true(s.cells <= (1L << 24));
    assert_true(s.cells > (1L << 23));
    ray_counters c = {0};
    hit_record hit;
    ray r = ray_make(vec3_make(0, 0, -10), vec3_make(0.01f, 0.02f, 1));
    bool found = accel_closest_hit(g, r, &hit, &c);
    accel *brute = brute_force_build(&set);
    hit_record want;
    assert_int_equal(found, accel_closest_hit(brute, r, &want, &c));
    if (found)
        assert_close(hit.t, want.t, ACCEL_CHECK_T_TOLERANCE * want.t);
    accel_destroy(brute);
    accel_destroy(g);
    triangle_set_free(&set);
    mesh_free(&m);
}

/* ---- hard cases ------------------------------------------------------------ */

/* A triangle in the plane z = 2.5 around (1.5, 2.5), inside cell (1, 2, 2). */
static void test_rays_starting_outside_and_inside_the_grid(void **state)
{
    (void)state;
    exercise_checks("dda_step");
    const vec3 tris[4][3] = {{corner_low[0], corner_low[1], corner_low[2]},
                             {corner_high[0], corner_high[1], corner_high[2]},
                             {{1.2f, 2.2f, 2.5f}, {1.8f, 2.2f, 2.5f}, {1.5f, 2.8f, 2.5f}},
                             {{3.2f, 0.2f, 0.5f}, {3.8f, 0.2f, 0.5f}, {3.5f, 0.8f, 0.5f}}};
    scene s;
    scene_make(&s, tris, 4, FOUR_CUBED_DENSITY, grid_build);
    assert_resolution(s.grid, 4, 4, 4);

    /* Outside, below: enters at z = 0 (t = 3), walks cells z = 0, 1, 2 of
     * column (1, 2) and hits at z = 2.5: t = 5.5. 1 bounds test + 3 cells;
     * only the last cell holds a triangle. */
    trace_result h = trace(&s, ray_from(1.5f, 2.5f, -3, 0, 0, 1));
    assert_true(h.found);
    assert_int_equal(h.triangle, 2);
    assert_close(h.t, 5.5, T_TOLERANCE);
    assert_int_equal(h.counters.box_tests, 4);
    assert_int_equal(h.counters.primitive_tests, 1);

    /* Outside, far away on a diagonal, aimed at the hit point: t = 1. */
    vec3 origin = vec3_make(-3, -2, -1), target = vec3_make(1.5f, 2.5f, 2.5f);
    h = trace(&s, ray_make(origin, vec3_sub(target, origin)));
    assert_true(h.found);
    assert_int_equal(h.triangle, 2);
    assert_close(h.t, 1.0, T_TOLERANCE);

    /* Outside and missing the grid: one bounds test, no cell, no triangle. */
    h = trace(&s, ray_from(1.5f, 5, -3, 0, 0, 1));
    assert_false(h.found);
    assert_int_equal(h.counters.box_tests, 1);
    assert_int_equal(h.counters.primitive_tests, 0);
    /* Outside, pointing away from the grid. */
    h = trace(&s, ray_from(1.5f, 2.5f, -3, 0, 0, -1));
    assert_false(h.found);
    assert_int_equal(h.counters.box_tests, 1);

    /* Inside: starts in cell (1, 2, 0): t = 2, 3 cells. */
    h = trace(&s, ray_from(1.5f, 2.5f, 0.5f, 0, 0, 1));
    assert_true(h.found);
    assert_close(h.t, 2.0, T_TOLERANCE);
    assert_int_equal(h.counters.box_tests, 4);
    /* Inside, with t_min past the triangle: nothing. */
    ray r = ray_from(1.5f, 2.5f, 0.5f, 0, 0, 1);
    r.t_min = 2.5f;
    h = trace(&s, r);
    assert_false(h.found);
    /* Inside, ending (t_max) before the triangle: the walk stops in the
     * cell where the ray ends, z = 1: cells z = 0, 1. */
    r = ray_from(1.5f, 2.5f, 0.5f, 0, 0, 1);
    r.t_max = 1.0f;
    h = trace(&s, r);
    assert_false(h.found);
    assert_int_equal(h.counters.box_tests, 3);
    /* Going down, from inside cell (3, 0, 3) to the triangle at z = 0.5. */
    h = trace(&s, ray_from(3.5f, 0.5f, 3.5f, 0, 0, -1));
    assert_true(h.found);
    assert_int_equal(h.triangle, 3);
    assert_close(h.t, 3.0, T_TOLERANCE);
    assert_int_equal(h.counters.box_tests, 1 + 4);
    scene_free(&s);
}

/* A ray running along the line x = 2, y = 2: on two cell boundary planes at
 * once, with direction (+-0, +-0, +-1). 1/d is +-inf along x and y; those
 * axes must never be stepped (t_max = inf), and no NaN may appear. Two
 * triangles: one at z = 2.5 crossing the line, one at z = 1.5 with an edge
 * exactly on the line (it lies in the cells on the x = 1 side and touches
 * x = 2), whose edge the ray hits. */
static void test_zero_direction_components_along_a_cell_boundary(void **state)
{
    (void)state;
    exercise_checks("dda_step");
    const vec3 tris[4][3] = {{corner_low[0], corner_low[1], corner_low[2]},
                             {corner_high[0], corner_high[1], corner_high[2]},
                             {{1.5f, 1.5f, 2.5f}, {2.7f, 1.6f, 2.5f}, {1.6f, 2.7f, 2.5f}},
                             {{2, 1.5f, 1.5f}, {2, 2.5f, 1.5f}, {1.2f, 2, 1.5f}}};
    scene s;
    scene_make(&s, tris, 4, FOUR_CUBED_DENSITY, grid_build);
    assert_resolution(s.grid, 4, 4, 4);
    const float zeros[2] = {0.0f, -0.0f};
    for (int i = 0; i < 2; i++)
        for (int j = 0; j < 2; j++) {
            float zx = zeros[i], zy = zeros[j];
            /* Up from z = -1: the edge at z = 1.5, t = 2.5; cells z = 0, 1. */
            trace_result h = trace(&s, ray_from(2, 2, -1, zx, zy, 1));
            assert_true(h.found);
            assert_int_equal(h.triangle, 3);
            assert_close(h.t, 2.5, T_TOLERANCE);
            assert_int_equal(h.counters.box_tests, 1 + 2);
            /* Down from z = 5: enters at z = 4, hits z = 2.5 at t = 2.5;
             * cells z = 3, 2. */
            h = trace(&s, ray_from(2, 2, 5, zx, zy, -1));
            assert_true(h.found);
            assert_int_equal(h.triangle, 2);
            assert_close(h.t, 2.5, T_TOLERANCE);
            assert_int_equal(h.counters.box_tests, 1 + 2);
            /* Along +x in the plane y = 2 at z = 2.5, the plane of triangle
             * 2: no hit (a ray in a triangle's plane never hits it), and the
             * walk crosses the 4 cells of row y = 2 (x = 0..3) from outside. */
            h = trace(&s, ray_from(-1, 2, 2.5f, 1, zx, zy));
            assert_false(h.found);
            assert_int_equal(h.counters.box_tests, 1 + 4);
        }
    scene_free(&s);
}

/* The whole mesh in negative space, [-10, -6]^3: cell boundaries at -9, -8,
 * -7. The origin (-8.5, -7.5, -9.5) lies in cell (1, 2, 0) of the grid; in
 * world units it is in the cell starting at floor(-8.5) = -9, where
 * truncation would say -8. */
static void test_negative_coordinates(void **state)
{
    (void)state;
    exercise_checks("dda_step");
    const vec3 tris[4][3] = {
        {{-10, -10, -10}, {-9.9f, -10, -10}, {-10, -9.9f, -10}},
        {{-6, -6, -6}, {-6.1f, -6, -6}, {-6, -6.1f, -6}},
        {{-8.8f, -7.8f, -7.5f}, {-8.2f, -7.8f, -7.5f}, {-8.5f, -7.2f, -7.5f}},
        {{-9.8f, -9.8f, -9.5f}, {-9.2f, -9.8f, -9.5f}, {-9.5f, -9.2f, -9.5f}},
    };
    scene s;
    scene_make(&s, tris, 4, FOUR_CUBED_DENSITY, grid_build);
    assert_resolution(s.grid, 4, 4, 4);
    /* Up: z from -9.5 to -7.5, t = 2; cells z = 0, 1, 2. */
    trace_result h = trace(&s, ray_from(-8.5f, -7.5f, -9.5f, 0, 0, 1));
    assert_true(h.found);
    assert_int_equal(h.triangle, 2);
    assert_close(h.t, 2.0, T_TOLERANCE);
    assert_int_equal(h.counters.box_tests, 1 + 3);
    /* Down from cell (1, 2, 3): t = 1; cells z = 3, 2. */
    h = trace(&s, ray_from(-8.5f, -7.5f, -6.5f, 0, 0, -1));
    assert_true(h.found);
    assert_int_equal(h.triangle, 2);
    assert_close(h.t, 1.0, T_TOLERANCE);
    assert_int_equal(h.counters.box_tests, 1 + 2);
    /* From outside, every component negative, aimed at (-9.5, -9.5, -9.5)
     * on triangle 3 in the corner cell (0, 0, 0): t = 1. */
    vec3 origin = vec3_make(-5, -5.5f, -4), target = vec3_make(-9.5f, -9.5f, -9.5f);
    h = trace(&s, ray_make(origin, vec3_sub(target, origin)));
    assert_true(h.found);
    assert_int_equal(h.triangle, 3);
    assert_close(h.t, 1.0, T_TOLERANCE);
    /* Along -x through row (y, z) = (2, 2) at y = -7.5, from inside cell
     * (3, 2, 2) at x = -6.5: triangle 2's plane is z = -7.5, and this ray
     * lies in it: no hit, 4 cells. */
    h = trace(&s, ray_from(-6.5f, -7.5f, -7.5f, -1, 0, 0));
    assert_false(h.found);
    assert_int_equal(h.counters.box_tests, 1 + 4);
    scene_free(&s);
}

/* "The object spans later cells", built by hand. A ray along +x at
 * y = z = 0.5 from x = -1. A big slanted triangle B in the plane x + z = 4,
 * corners (4,0,0), (4,2,0), (0,0,4): its box fills x, z in [0, 4], so it is
 * stored in the very first cell the ray enters, (0, 0, 0), but the ray meets
 * it at x = 3.5 (t = 4.5), in cell (3, 0, 0). A small triangle S in the plane
 * x = 1.5 sits in cell (1, 0, 0), where the ray meets it at t = 2.5: in front
 * of B's hit point, but in a later cell than the one where B is first found.
 *   cell 0 (t in [1, 2]): tests B (hit at 4.5 > 2: keep, walk on) and the
 *                         corner triangle in the z = 0 plane (missed)
 *   cell 1 (t in [2, 3]): tests B again and S (hit at 2.5 <= 3: stop)
 * so: S at t = 2.5, 1 + 2 box tests, 4 triangle tests. */
static const vec3 spans_tris[4][3] = {
    {{0, 0, 0}, {0.1f, 0, 0}, {0, 0.1f, 0}},                       /* corner, z = 0 */
    {{4, 4, 4}, {3.9f, 4, 4}, {4, 3.9f, 4}},                       /* corner, z = 4 */
    {{4, 0, 0}, {4, 2, 0}, {0, 0, 4}},                             /* B */
    {{1.5f, 0.25f, 0.25f}, {1.5f, 0.75f, 0.25f}, {1.5f, 0.5f, 0.75f}}, /* S */
};

static void test_object_spanning_later_cells_does_not_end_the_walk(void **state)
{
    (void)state;
    exercise_checks("dda_step");
    scene s;
    scene_make(&s, spans_tris, 4, FOUR_CUBED_DENSITY, grid_build);
    assert_resolution(s.grid, 4, 4, 4);
    trace_result h = trace(&s, ray_from(-1, 0.5f, 0.5f, 1, 0, 0));
    assert_true(h.found);
    assert_int_equal(h.triangle, 3);
    assert_close(h.t, 2.5, T_TOLERANCE);
    assert_int_equal(h.counters.box_tests, 1 + 2);
    assert_int_equal(h.counters.primitive_tests, 4);
    /* Without S in the way, B is found in cell 0, kept as the candidate, and
     * confirmed in cell 3, where its hit point is: 4 cells. */
    h = trace(&s, ray_from(-1, 0.9f, 0.5f, 1, 0, 0)); /* y = 0.9: beside S */
    assert_true(h.found);
    assert_int_equal(h.triangle, 2);
    assert_close(h.t, 4.5, T_TOLERANCE);
    assert_int_equal(h.counters.box_tests, 1 + 4);
    scene_free(&s);
}

/* The twin: stopping in the first cell where anything is hit returns B,
 * two cells too far. */
static void test_naive_early_exit_returns_the_far_triangle(void **state)
{
    (void)state;
    scene s;
    scene_make(&s, spans_tris, 4, FOUR_CUBED_DENSITY, grid_build_naive_exit);
    hit_record hit;
    ray_counters c = {0};
    assert_true(accel_closest_hit(s.grid, ray_from(-1, 0.5f, 0.5f, 1, 0, 0), &hit, &c));
    assert_int_equal(hit.shape_id, 2);
    assert_close(hit.t, 4.5, T_TOLERANCE);
    assert_int_equal(c.box_tests, 1 + 1);
    scene_free(&s);
}

/* One triangle, corners (0,0,0), (1,0,0), (0,1,1), in the plane z = y: box
 * [0,1]^3, C N = 27 cells of side 1/3, and the triangle's box overlaps all
 * 27 (conservative insertion). */
static void test_grid_over_a_single_triangle(void **state)
{
    (void)state;
    const vec3 tris[1][3] = {{{0, 0, 0}, {1, 0, 0}, {0, 1, 1}}};
    scene s;
    scene_make(&s, tris, 1, GRID_DEFAULT_DENSITY, grid_build);
    assert_resolution(s.grid, 3, 3, 3);
    assert_int_equal(s.grid->stats.references, 27);
    /* Up at (0.25, 0.25): hits z = 0.25 (t = 1.25) in the first cell. */
    trace_result h = trace(&s, ray_from(0.25f, 0.25f, -1, 0, 0, 1));
    assert_true(h.found);
    assert_close(h.t, 1.25, T_TOLERANCE);
    assert_int_equal(h.counters.box_tests, 1 + 1);
    assert_int_equal(h.counters.primitive_tests, 1);
    /* Up at (0.3, 0.6): the hit (z = 0.6, t = 1.6) is in the second cell up;
     * the first cell (t up to 4/3) finds it, must not stop, and the second
     * finds it again: 2 cells, 2 tests of the same triangle (no mailbox). */
    h = trace(&s, ray_from(0.3f, 0.6f, -1, 0, 0, 1));
    assert_true(h.found);
    assert_close(h.t, 1.6, T_TOLERANCE);
    assert_int_equal(h.counters.box_tests, 1 + 2);
    assert_int_equal(h.counters.primitive_tests, 2);
    /* (0.9, 0.9) is outside the triangle (b1 + b2 = 1.8): a miss after the
     * whole column, 3 cells. */
    h = trace(&s, ray_from(0.9f, 0.9f, -1, 0, 0, 1));
    assert_false(h.found);
    assert_int_equal(h.counters.box_tests, 1 + 3);
    /* From inside, down from (0.25, 0.25, 0.9): t = 0.65. */
    h = trace(&s, ray_from(0.25f, 0.25f, 0.9f, 0, 0, -1));
    assert_true(h.found);
    assert_close(h.t, 0.65, T_TOLERANCE);
    scene_free(&s);
}

/* Flat bounds: a square [0,2]^2 in the plane z = 0.5 (extent 0 along z), a
 * line of degenerate triangles along x (extent 0 along y and z), one point,
 * and no triangles at all. Nothing may divide by the zero extents.
 *   square, N = 2: 2 axes left, C^(2/3) = 9 cells per triangle, 18 cells
 *                  over an area of 4: sqrt(18 / 4) = 2.12 per unit,
 *                  round(2 * 2.12) = 4 along x and y: 4 x 4 x 1
 *   line,   N = 4: 1 axis, C^(1/3) = 3 per triangle, 12 cells along x
 *   point:         1 x 1 x 1 */
static void test_flat_bounds(void **state)
{
    (void)state;
    const vec3 square[2][3] = {{{0, 0, 0.5f}, {2, 0, 0.5f}, {2, 2, 0.5f}}, {{0, 0, 0.5f}, {2, 2, 0.5f}, {0, 2, 0.5f}}};
    scene s;
    scene_make(&s, square, 2, GRID_DEFAULT_DENSITY, grid_build);
    assert_resolution(s.grid, 4, 4, 1);
    /* Straight down at (0.5, 1.5), where y > x: triangle 1, t = 2.5, one cell. */
    trace_result h = trace(&s, ray_from(0.5f, 1.5f, 3, 0, 0, -1));
    assert_true(h.found);
    assert_int_equal(h.triangle, 1);
    assert_close(h.t, 2.5, T_TOLERANCE);
    assert_int_equal(h.counters.box_tests, 1 + 1);
    /* Slanted, aimed at (1.5, 0.5, 0.5) where y < x: triangle 0, t = 1. */
    vec3 origin = vec3_make(-1, 1, 1.5f), target = vec3_make(1.5f, 0.5f, 0.5f);
    h = trace(&s, ray_make(origin, vec3_sub(target, origin)));
    assert_true(h.found);
    assert_int_equal(h.triangle, 0);
    assert_close(h.t, 1.0, T_TOLERANCE);
    /* In the plane of the square, along +x at y = 1.1: no hit, no NaN, the 4
     * cells of row y = 2. */
    h = trace(&s, ray_from(-1, 1.1f, 0.5f, 1, 0, 0));
    assert_false(h.found);
    assert_int_equal(h.counters.box_tests, 1 + 4);
    scene_free(&s);

    const vec3 line[4][3] = {{{0, 0, 0}, {0.5f, 0, 0}, {1, 0, 0}},
                             {{1, 0, 0}, {1.5f, 0, 0}, {2, 0, 0}},
                             {{2, 0, 0}, {2.5f, 0, 0}, {3, 0, 0}},
                             {{3, 0, 0}, {3.5f, 0, 0}, {4, 0, 0}}};
    scene_make(&s, line, 4, GRID_DEFAULT_DENSITY, grid_build);
    assert_resolution(s.grid, 12, 1, 1);
    h = trace(&s, ray_from(0.7f, 0, -1, 0, 0, 1)); /* degenerate: never hit */
    assert_false(h.found);
    h = trace(&s, ray_from(-1, 0, 0, 1, 0, 0)); /* along the line */
    assert_false(h.found);
    assert_int_equal(h.counters.box_tests, 1 + 12);
    scene_free(&s);

    const vec3 point[1][3] = {{{1, 1, 1}, {1, 1, 1}, {1, 1, 1}}};
    scene_make(&s, point, 1, GRID_DEFAULT_DENSITY, grid_build);
    assert_resolution(s.grid, 1, 1, 1);
    h = trace(&s, ray_from(1, 1, 0, 0, 0, 1));
    assert_false(h.found);
    scene_free(&s);

    scene_make(&s, point, 0, GRID_DEFAULT_DENSITY, grid_build);
    assert_resolution(s.grid, 1, 1, 1);
    h = trace(&s, ray_from(1, 1, 0, 0, 0, 1));
    assert_false(h.found);
    scene_free(&s);
}

/* ---- teapot in a stadium ------------------------------------------------- */

/* A dense sphere of radius 1 (5120 triangles) in a stadium 200 x 50 x 200
 * (10 triangles). C N = 27 * 5130 cells over 2 * 10^6 units^3: cells of side
 * cbrt(2e6 / 138510) = 2.43. The sphere's box is 2 wide, so it meets at
 * most 2 cells per axis, 8 cells: one of them holds at least 5120 / 8 = 640
 * triangles. 8 times the cells (C = 216) halve the side to 1.22: at most 3
 * cells per axis, 27 cells, so still at least 5120 / 27 = 190 in one. And
 * nearly every cell is empty: only the ground layer, the walls and the
 * sphere's cells hold anything. */
static void test_teapot_in_a_stadium_crowds_into_few_cells(void **state)
{
    (void)state;
    mesh m;
    mesh_init(&m);
    mesh_teapot_in_stadium(&m, 4, 200.0f);
    triangle_set set;
    triangle_set_from_mesh(&set, &m);
    const int teapot = 5120;
    assert_int_equal(set.count, teapot + 10);

    accel *g = grid_build(&set, 27.0f);
    grid_summary s = grid_summarize(g);
    assert_true(s.largest_cell >= teapot / 8);
    long walls = (long)s.resolution[0] * s.resolution[2] + 2L * s.resolution[1] * (s.resolution[0] + s.resolution[2]);
    assert_true(s.cells - s.empty_cells <= walls + 8);
    assert_true((double)s.empty_cells > 0.85 * (double)s.cells);
    accel_destroy(g);

    g = grid_build(&set, 216.0f);
    grid_summary fine = grid_summarize(g);
    assert_in_range(fine.cells, 7 * s.cells, 9 * s.cells);
    assert_true(fine.largest_cell >= teapot / 27);
    accel_destroy(g);
    triangle_set_free(&set);
    mesh_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_grid_agrees_with_brute_force),
        cmocka_unit_test(test_grid_agrees_with_brute_force_coarse_and_fine),
        cmocka_unit_test(test_resolution_follows_the_lecture_heuristic),
        cmocka_unit_test(test_rays_starting_outside_and_inside_the_grid),
        cmocka_unit_test(test_zero_direction_components_along_a_cell_boundary),
        cmocka_unit_test(test_negative_coordinates),
        cmocka_unit_test(test_object_spanning_later_cells_does_not_end_the_walk),
        cmocka_unit_test(test_naive_early_exit_returns_the_far_triangle),
        cmocka_unit_test(test_grid_over_a_single_triangle),
        cmocka_unit_test(test_flat_bounds),
        cmocka_unit_test(test_teapot_in_a_stadium_crowds_into_few_cells),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
