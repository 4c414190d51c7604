/* grid.c -- the uniform grid (lecture 14) and its 3D-DDA traversal
 * (Amanatides and Woo, "A Fast Voxel Traversal Algorithm for Ray Tracing",
 * 1987). */
#include "04-uniform-grid/grid.h"

#include <stdint.h>
#include <stdlib.h>

#include "memory.h"
#include "timer.h"

typedef struct {
    accel base;
    aabb bounds;               /* the grid's box: the bounds of all triangles */
    int n[3];                  /* cells along x, y, z */
    double lo[3];              /* bounds.lo, in double for the traversal */
    double cell_size[3];       /* extent / n; 0 on a flat axis */
    double inverse_cell_size[3]; /* n / extent; 0 on a flat axis */
    long cells;
    /* The cells, stored compactly: cell c holds the triangles
     * triangle_index[cell_start[c]] .. triangle_index[cell_start[c + 1] - 1],
     * cells numbered x fastest: c = x + n_x (y + n_y z). */
    uint32_t *cell_start;      /* cells + 1 entries (a prefix sum of the counts) */
    uint32_t *triangle_index;  /* all cells' triangles, one flat array */
    /* One bit per cell, set if the cell holds anything. Most cells a ray
     * crosses are empty (92 % of the tori field's at C = 27); the bits are
     * 1/32 the size of cell_start (350 KB against 11 MB there), so an empty
     * cell costs a test of a bit that is likely in cache, not a load from
     * main memory. */
    uint64_t *occupied;
} grid;

/* The cap on the number of cells: 2^24 cells is 64 MB of cell_start. The
 * lecture's C * N asks for 28 million cells at 10^6 triangles; above the cap
 * the cells simply get larger. */
static const double GRID_MAX_CELLS = 16777216.0;
/* The cap on stored triangle references: 2^26 of them is 256 MB. A grid
 * over many large triangles (each overlapping a large part of the box) could
 * otherwise ask for cells x triangles; the build then halves the cell count
 * until the references fit. */
static const uint64_t GRID_MAX_REFERENCES = (uint64_t)1 << 26;
/* Each triangle's box is grown by this fraction of the scene's size before
 * it is turned into a range of cells: 64 float ulps (2^-24 each) of the
 * largest coordinate or extent. A triangle that touches a cell boundary, or
 * comes within rounding of one, is then stored in the cells on both sides.
 * It covers the two roundings that decide which side of a boundary a hit
 * lies on: the traversal's, computed in double (about 2^-53 relative,
 * nothing next to this), and the float t that the triangle test returns for
 * the hit (a few ulps of the distance travelled, so rays starting within
 * several scene sizes of the scene are covered with room to spare). The cost
 * is a handful of extra references, for triangles within 64 ulps of a
 * boundary. */
static const double GRID_INSERT_PAD = 64.0 * 0x1.0p-24;

static const accel_ops grid_ops;
static const accel_ops grid_naive_ops;

/* ---- Choose the resolution: #cells = C * #objects, cells near cubic -------
 * With N triangles in a box of volume V, cells of side s = cbrt(V / (C N))
 * give C N cells: n_x = extent_x / s = extent_x * cbrt(C N / V), and the same
 * for y and z. An axis along which the box is thinner than one cell (or flat,
 * extent 0) gets a single cell, and the budget is spent on the others: with
 * d axes left, C^(d/3) cells per triangle (the lecture's 27 = 3^3 cells, three
 * per axis, becomes 3^2 = 9 in a plane). Nothing is divided by a zero
 * extent: flat axes never enter the product. */
static void grid_choose_resolution(vec3 extent, long triangles, double density, double max_cells, int n[3])
{
    double e[3] = {extent.x, extent.y, extent.z};
    bool active[3];
    int dims = 0;
    for (int a = 0; a < 3; a++) {
        active[a] = e[a] > 0.0;
        dims += active[a];
        n[a] = 1;
    }
    double per_unit = 0.0; /* cells per unit length, 1 / s */
    while (dims > 0) {
        double target = (double)triangles * pow(density, (double)dims / 3.0);
        target = fmin(fmax(target, 1.0), max_cells);
        double measure = 1.0; /* volume, area or length of the active axes */
        for (int a = 0; a < 3; a++)
            if (active[a])
                measure *= e[a];
        per_unit = pow(target / measure, 1.0 / (double)dims);
        bool thin = false;
        for (int a = 0; a < 3; a++)
            if (active[a] && e[a] * per_unit < 1.0) {
                active[a] = false;
                dims--;
                thin = true;
            }
        if (!thin)
            break;
    }
    /* Every active axis now has e * per_unit >= 1 and their product is at
     * most max_cells, so no count overflows an int. */
    for (int a = 0; a < 3; a++)
        if (active[a])
            n[a] = (int)fmax(1.0, round(e[a] * per_unit));
    /* Rounding up may overshoot the cap: take cells off the longest axis. */
    while ((double)n[0] * (double)n[1] * (double)n[2] > max_cells) {
        int longest = n[0] >= n[1] && n[0] >= n[2] ? 0 : n[1] >= n[2] ? 1 : 2;
        n[longest]--;
    }
}

/* Which cell, along one axis, holds coordinate x: floor, not truncation
 * (truncation sends -0.5 to cell 0 instead of -1), then clamped into the
 * grid, since points computed on the boundary may round to just outside. */
static inline int grid_cell_coordinate(const grid *g, int axis, double x)
{
    double c = floor((x - g->lo[axis]) * g->inverse_cell_size[axis]);
    if (!(c >= 0.0)) /* also NaN */
        return 0;
    if (c >= (double)g->n[axis])
        return g->n[axis] - 1;
    return (int)c;
}

/* The cells a triangle's box overlaps, grown by `pad`: [lo[a], hi[a]] per axis. */
static void grid_box_cells(const grid *g, const aabb *box, double pad, int lo[3], int hi[3])
{
    for (int a = 0; a < 3; a++) {
        lo[a] = grid_cell_coordinate(g, a, (double)vec3_axis(box->lo, a) - pad);
        hi[a] = grid_cell_coordinate(g, a, (double)vec3_axis(box->hi, a) + pad);
    }
}

/* ---- Insert each triangle into every cell its bounding box overlaps --------
 * Conservative: the box overlaps more cells than the triangle itself (a
 * long diagonal triangle's box holds many cells the triangle never touches).
 * A cell holding a triangle it does not touch costs a wasted test; a cell
 * missing a triangle it does touch would lose a hit. An exact triangle-box
 * overlap test (the separating axis theorem) would remove the extra
 * references; exercise 4 in the chapter text. Two passes over the
 * triangles: count per cell, then fill. Returns the number of references,
 * or 0 with nothing allocated if it would exceed GRID_MAX_REFERENCES. */
static uint64_t grid_insert_triangles(grid *g, const triangle_set *set, double pad)
{
    long cells = g->cells;
    long stride_y = g->n[0], stride_z = (long)g->n[0] * g->n[1];
    /* Pass 1, count: cell_start[c] = how many triangles overlap cell c. */
    g->cell_start = memory_allocate((size_t)cells + 1, sizeof *g->cell_start);
    uint64_t total = 0;
    for (int i = 0; i < set->count; i++) {
        int lo[3], hi[3];
        grid_box_cells(g, &set->boxes[i], pad, lo, hi);
        total += (uint64_t)(hi[0] - lo[0] + 1) * (uint64_t)(hi[1] - lo[1] + 1) * (uint64_t)(hi[2] - lo[2] + 1);
        if (total > GRID_MAX_REFERENCES) {
            free(g->cell_start);
            g->cell_start = NULL;
            return 0;
        }
        for (int z = lo[2]; z <= hi[2]; z++)
            for (int y = lo[1]; y <= hi[1]; y++)
                for (int x = lo[0]; x <= hi[0]; x++)
                    g->cell_start[x + stride_y * y + stride_z * z]++;
    }
    /* Prefix sum: cell_start[c] = where cell c's list ends. */
    uint32_t running = 0;
    for (long c = 0; c < cells; c++) {
        running += g->cell_start[c];
        g->cell_start[c] = running;
    }
    g->cell_start[cells] = running;
    /* Pass 2, fill: each triangle goes just before its cell's end, which
     * moves the end back; afterwards cell_start[c] is where the list starts.
     * Going through the triangles backwards leaves each list in increasing
     * order. */
    g->triangle_index = memory_allocate((size_t)total, sizeof *g->triangle_index);
    for (int i = set->count - 1; i >= 0; i--) {
        int lo[3], hi[3];
        grid_box_cells(g, &set->boxes[i], pad, lo, hi);
        for (int z = lo[2]; z <= hi[2]; z++)
            for (int y = lo[1]; y <= hi[1]; y++)
                for (int x = lo[0]; x <= hi[0]; x++)
                    g->triangle_index[--g->cell_start[x + stride_y * y + stride_z * z]] = (uint32_t)i;
    }
    return total;
}

static accel *grid_make(const triangle_set *set, float cell_density, const accel_ops *ops)
{
    double start = timer_seconds();
    grid *g = memory_allocate(1, sizeof *g);
    g->base.ops = ops;
    g->base.set = set;
    g->base.stats.name = ops == &grid_ops ? "grid" : "grid-naive-exit";
    /* An empty set gets one empty cell around the origin. */
    g->bounds = set->count > 0 ? set->bounds : (aabb){vec3_splat(0.0f), vec3_splat(0.0f)};
    vec3 extent = aabb_extent(g->bounds);
    float scale = fmaxf(vec3_max_component(vec3_max(vec3_abs(g->bounds.lo), vec3_abs(g->bounds.hi))),
                        vec3_max_component(extent));
    double pad = GRID_INSERT_PAD * (double)scale;
    double density = cell_density > 0.0f ? (double)cell_density : (double)GRID_DEFAULT_DENSITY;

    double max_cells = GRID_MAX_CELLS;
    uint64_t references;
    for (;;) {
        grid_choose_resolution(extent, set->count, density, max_cells, g->n);
        g->cells = (long)g->n[0] * g->n[1] * g->n[2];
        for (int a = 0; a < 3; a++) {
            double e = (double)vec3_axis(extent, a);
            g->lo[a] = (double)vec3_axis(g->bounds.lo, a);
            g->cell_size[a] = e / (double)g->n[a];
            g->inverse_cell_size[a] = e > 0.0 ? (double)g->n[a] / e : 0.0;
        }
        references = grid_insert_triangles(g, set, pad);
        if (g->cell_start != NULL)
            break;
        max_cells = fmax(1.0, 0.5 * (double)g->cells); /* too many references: coarser */
    }

    long non_empty = 0;
    g->occupied = memory_allocate((size_t)(g->cells + 63) / 64, sizeof *g->occupied);
    for (long c = 0; c < g->cells; c++) {
        bool full = g->cell_start[c + 1] > g->cell_start[c];
        non_empty += full;
        g->occupied[c >> 6] |= (uint64_t)full << (c & 63);
    }
    g->base.stats.bytes = sizeof *g + ((size_t)g->cells + 1) * sizeof *g->cell_start +
                          (size_t)references * sizeof *g->triangle_index +
                          (size_t)(g->cells + 63) / 64 * sizeof *g->occupied;
    g->base.stats.nodes = (int)g->cells;
    g->base.stats.leaves = (int)non_empty;
    g->base.stats.max_depth = 1; /* one level: the cells */
    g->base.stats.references = (long)references;
    g->base.stats.build_seconds = timer_seconds() - start;
    return &g->base;
}

accel *grid_build(const triangle_set *set, float cell_density) { return grid_make(set, cell_density, &grid_ops); }

accel *grid_build_naive_exit(const triangle_set *set, float cell_density)
{
    return grid_make(set, cell_density, &grid_naive_ops);
}

/* ---- 3D-DDA traversal ---------------------------------------------------- */

typedef enum {
    WALK_CLOSEST,    /* the closest hit: stop when the closest so far lies in the current cell */
    WALK_ANY,        /* any hit: stop at the first */
    WALK_NAIVE_EXIT, /* wrong on purpose: stop after the first cell with any hit */
} walk_rule;

/* The walk's state, the paper's names: along axis a the ray is in cell
 * cell[a], crosses the next boundary at t_max[a], takes t_delta[a] to cross
 * one cell, and has left the grid when cell[a] = just_out[a]; step[a] is +1
 * or -1 (0 for an axis the ray runs parallel to, whose t_max is infinite),
 * stride[a] what a step adds to c, the current cell's index. */
typedef struct {
    int cell[3], step[3], just_out[3];
    long stride[3], c;
    double t_max[3], t_delta[3];
} dda_walk;

/* Step to the next cell, across the nearest of the three next boundaries;
 * the current cell ends there, at t_exit = that t_max. A hit counts only if
 * it lies inside this cell, t <= t_exit: a triangle stored here may be hit
 * at a point in a later cell, and a closer hit may then be waiting in the
 * next cell. Such a hit stays the candidate (t_best) and the walk goes on.
 * The same test ends the walk when the ray itself ends in this cell. False
 * when the walk ends: here, or by leaving the grid. */
static inline bool dda_step(dda_walk *w, double t_best)
{
    /* exercise: dda_step */
    int a = w->t_max[0] < w->t_max[1] && w->t_max[0] < w->t_max[2] ? 0 : w->t_max[1] < w->t_max[2] ? 1 : 2;
    if (t_best <= w->t_max[a]) /* the closest hit lies in this cell */
        return false;
    w->cell[a] += w->step[a];
    if (w->cell[a] == w->just_out[a]) /* left the grid */
        return false;
    w->c += w->stride[a];
    w->t_max[a] += w->t_delta[a];
    return true;
    /* end of exercise dda_step */
}

/* Walks r through the cells it pierces, in order, and tests the triangles
 * stored in them; returns the closest hit triangle (-1: none), with its t in
 * r->t_max and its barycentrics in b1, b2. The walk's state is dda_walk's,
 * in the paper's names (t_max[0] is its t_max_x), and dda_step() steps it.
 *
 * t is kept in double, and t_max_x grows by t_delta_x at each step, as in the
 * paper. In float that sum would gather up to half an ulp per step: after a
 * few hundred steps, more than the 64-ulp insertion pad. In double a walk of
 * 10^6 steps drifts by about 10^-10 of the distance travelled, over 30000
 * times less than the pad. */
static inline int grid_walk(const grid *g, ray *r, walk_rule rule, triangle_test test, float *b1_out,
                            float *b2_out, ray_counters *counters)
{
    const triangle_set *set = g->base.set;
    /* Find the entry point: clip the ray to the grid's bounds (slab test) */
    slab_ray sr = slab_ray_make(*r);
    float t_enter, t_exit;
    counters->box_tests++;
    if (set->count == 0 || !aabb_slab_test(&g->bounds, &sr, r->t_min, r->t_max, &t_enter, &t_exit))
        return -1;
    (void)t_exit; /* the walk ends by cell index instead: see just_out */

    /* The starting cell: the cell of the point where the ray enters (its
     * origin, if it starts inside) */
    double origin[3] = {r->origin.x, r->origin.y, r->origin.z};
    double direction[3] = {r->direction.x, r->direction.y, r->direction.z};
    long cell_stride[3] = {1, g->n[0], (long)g->n[0] * g->n[1]};
    dda_walk w;
    for (int a = 0; a < 3; a++) {
        w.cell[a] = grid_cell_coordinate(g, a, origin[a] + (double)t_enter * direction[a]);
        if (direction[a] == 0.0) {
            /* A zero component (+0 or -0): the ray never crosses a boundary
             * along this axis. t_max = inf, so the axis is never stepped
             * (computing it as (boundary - o) / d would give 0 * inf = NaN
             * for an origin on a boundary). */
            w.step[a] = 0;
            w.just_out[a] = -1;
            w.t_max[a] = w.t_delta[a] = INFINITY;
        } else {
            /* t_max: where the ray crosses the cell's next boundary (its
             * upper one going up, its lower one going down), computed from
             * the cell index; t_delta = cell size / |d| */
            bool up = direction[a] > 0.0;
            double inverse = 1.0 / direction[a];
            double boundary = g->lo[a] + (double)(w.cell[a] + up) * g->cell_size[a];
            w.step[a] = up ? 1 : -1;
            w.just_out[a] = up ? g->n[a] : -1;
            w.t_max[a] = (boundary - origin[a]) * inverse;
            w.t_delta[a] = g->cell_size[a] * fabs(inverse);
        }
        w.stride[a] = w.step[a] * cell_stride[a];
    }
    w.c = w.cell[0] + cell_stride[1] * w.cell[1] + cell_stride[2] * w.cell[2];

    const triangle *triangles = set->triangles;
    /* the watertight triangle test's part for the ray, once (chapter 01) */
    const watertight_ray wr = watertight_ray_make(r);
    const uint32_t *cell_start = g->cell_start, *triangle_index = g->triangle_index;
    const uint64_t *occupied = g->occupied;
    uint64_t cells_visited = 0, tests = 0;
    double t_best = r->t_max; /* the closest hit so far, or the ray's end */
    int best = -1;
    for (;;) {
        cells_visited++;
        /* Test the triangles stored in this cell */
        long c = w.c;
        if (occupied[c >> 6] >> (c & 63) & 1) {
            uint32_t begin = cell_start[c], end = cell_start[c + 1];
            tests += end - begin;
            bool hit_here = false;
            for (uint32_t k = begin; k < end; k++) {
                uint32_t i = triangle_index[k];
                float t, b1, b2;
                if (triangle_intersect_with(test, &wr, &triangles[i], r, r->t_max, &t, &b1, &b2)) {
                    best = (int)i;
                    r->t_max = t; /* only closer hits from now on */
                    t_best = t;
                    *b1_out = b1;
                    *b2_out = b2;
                    hit_here = true;
                    if (rule == WALK_ANY) {
                        tests -= end - k - 1; /* the tests not made */
                        goto done;
                    }
                }
            }
            if (rule == WALK_NAIVE_EXIT && hit_here)
                break;
        }
        /* Step to the next cell; a hit counts only inside its cell (dda_step) */
        if (!dda_step(&w, t_best))
            break;
    }
done:
    counters->box_tests += cells_visited;
    counters->primitive_tests += tests;
    return best;
}

/* The walk compiled once per triangle test (accel.h, ACCEL_WALK). */
static bool grid_closest_hit(const accel *a, ray r, hit_record *hit, ray_counters *counters)
{
    float b1 = 0.0f, b2 = 0.0f;
    int best = ACCEL_WALK(a, grid_walk, (const grid *)a, &r, WALK_CLOSEST, &b1, &b2, counters);
    return accel_walk_hit(a, best, r, b1, b2, hit);
}

static bool grid_any_hit(const accel *a, ray r, ray_counters *counters)
{
    float b1, b2;
    return ACCEL_WALK(a, grid_walk, (const grid *)a, &r, WALK_ANY, &b1, &b2, counters) >= 0;
}

static bool grid_naive_closest_hit(const accel *a, ray r, hit_record *hit, ray_counters *counters)
{
    float b1 = 0.0f, b2 = 0.0f;
    int best = ACCEL_WALK(a, grid_walk, (const grid *)a, &r, WALK_NAIVE_EXIT, &b1, &b2, counters);
    return accel_walk_hit(a, best, r, b1, b2, hit);
}

static void grid_destroy(accel *a)
{
    grid *g = (grid *)a;
    free(g->cell_start);
    free(g->triangle_index);
    free(g->occupied);
    free(g);
}

static const accel_ops grid_ops = {grid_closest_hit, grid_any_hit, grid_destroy, accel_use_triangle_test_of_set};
static const accel_ops grid_naive_ops = {grid_naive_closest_hit, grid_any_hit, grid_destroy,
                                         accel_use_triangle_test_of_set};

/* ---- what the grid looks like inside ------------------------------------- */

grid_summary grid_summarize(const accel *a)
{
    grid_summary s = {0};
    if (a == NULL || (a->ops != &grid_ops && a->ops != &grid_naive_ops))
        return s;
    const grid *g = (const grid *)a;
    static const uint32_t bin_top[GRID_HISTOGRAM_BINS - 1] = {0, 1, 4, 16, 64, 256};
    for (int k = 0; k < 3; k++)
        s.resolution[k] = g->n[k];
    s.cell_size = vec3_make((float)g->cell_size[0], (float)g->cell_size[1], (float)g->cell_size[2]);
    s.cells = g->cells;
    s.references = a->stats.references;
    for (long c = 0; c < g->cells; c++) {
        uint32_t count = g->cell_start[c + 1] - g->cell_start[c];
        s.empty_cells += count == 0;
        if ((int)count > s.largest_cell)
            s.largest_cell = (int)count;
        int bin = 0;
        while (bin < GRID_HISTOGRAM_BINS - 1 && count > bin_top[bin])
            bin++;
        s.histogram[bin]++;
    }
    return s;
}
