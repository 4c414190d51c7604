/* 04-uniform-grid: a uniform grid over a mesh, walked by the 3D-DDA.
 *
 * Builds the grid over the tori field (102400 triangles by default) with
 * #cells = C * #triangles, renders it (or, with --heatmap, what each ray
 * cost), and prints what the grid looks like inside: its resolution, how
 * many cells are empty, how full the fullest cell is, and the cells visited
 * and triangles tested per ray. --mesh stadium shows the "teapot in a
 * stadium", where a uniform grid fails; --density C changes C. */
#include <stdio.h>
#include <stdlib.h>

#include "03-aabb-slabs/accel_program.h"
#include "03-aabb-slabs/accel_view.h"
#include "04-uniform-grid/grid.h"
#include "cli.h"
#include "program.h"
#include "rng.h"
#include "timer.h"

/* The cost of rays aimed at the mesh itself (accel_aimed_rays), one thread,
 * timed. */
static void probe(const accel *a, int count, uint64_t seed)
{
    ray *rays = accel_aimed_rays(a->set, count, seed);
    ray_counters counters = {0};
    long hits = 0;
    double start = timer_seconds();
    for (int i = 0; i < count; i++) {
        hit_record hit;
        hits += accel_closest_hit(a, rays[i], &hit, &counters);
    }
    double seconds = timer_seconds() - start;
    printf("%d rays aimed at random triangles: %.1f cells visited, %.1f triangles tested per ray "
           "(%.0f %% hit; %.2f Mrays/s, 1 thread)\n",
           count, (double)counters.box_tests / count - 1.0, (double)counters.primitive_tests / count,
           100.0 * (double)hits / count, seconds > 0 ? count / seconds * 1e-6 : 0.0);
    free(rays);
}

static void print_grid(const accel *a)
{
    const accel_stats *s = &a->stats;
    grid_summary g = grid_summarize(a);
    double n = (double)a->set->count;
    printf("%s over %d triangles, C = %g: %d x %d x %d = %ld cells of %.3g x %.3g x %.3g\n", s->name,
           a->set->count, (double)g.cells / n, g.resolution[0], g.resolution[1], g.resolution[2], g.cells,
           (double)g.cell_size.x, (double)g.cell_size.y, (double)g.cell_size.z);
    printf("built in %.1f ms; %.1f bytes per triangle; %d cells (nodes), %d non-empty (leaves, %.1f %%), "
           "depth %d; %.2f references per triangle\n",
           s->build_seconds * 1e3, (double)s->bytes / n, s->nodes, s->leaves, 100.0 * s->leaves / (double)g.cells,
           s->max_depth, (double)s->references / n);
    printf("empty cells %.1f %%; the fullest cell holds %d triangles (%.1f %% of all)\n",
           100.0 * (double)g.empty_cells / (double)g.cells, g.largest_cell, 100.0 * g.largest_cell / n);
    static const char *const bins[GRID_HISTOGRAM_BINS] = {"0", "1", "2-4", "5-16", "17-64", "65-256", ">256"};
    printf("cells holding");
    for (int b = 0; b < GRID_HISTOGRAM_BINS; b++)
        printf(" %s: %ld%s", bins[b], g.histogram[b], b + 1 < GRID_HISTOGRAM_BINS ? "," : "");
    printf(" triangles\n");
}

/* The program's own flags. Its run() reads as chapter 05's and 06's do (load the
 * mesh, build, print the structure, render, print the costs): each
 * program is read whole on its chapter's page, so the steps they share
 * are one call each into chapter 03's accel_program.h (accel_input_load,
 * accel_input_render), and what stays is the chapter's own. */
typedef struct {
    cli_choice mesh;
    const char *obj_path;
    int triangles, probe_rays;
    float density, heatmap_max;
    bool heatmap;
    camera_override view; /* --eye, --target, --fov */
} grid_flags;

/* Builds the grid over the mesh the flags ask for, prints what it looks
 * like inside and what aimed rays cost, renders it and prints what each
 * camera ray cost. Returns the exit status. */
static int run(cli_options *opts, const char *program, const grid_flags *f)
{
    accel_input in;
    int load_status = accel_input_load(&in, opts, program, cli_choice_name(&f->mesh), f->obj_path, f->triangles, 6);
    if (load_status != 0)
        return load_status;
    triangle_set set;
    triangle_set_from_mesh(&set, &in.m);
    accel *a = grid_build(&set, f->density);
    if (!opts->quiet)
        print_grid(a);
    if (f->probe_rays > 0 && !opts->quiet)
        probe(a, f->probe_rays, opts->seed);

    render_stats stats;
    int status = accel_input_render(opts, program, &in, a, f->heatmap, f->heatmap_max, &f->view, &stats);
    if (status == 0 && !opts->quiet) {
        double rays = (double)stats.counters.camera_rays;
        printf("per camera ray: %.2f cells visited, %.2f triangles tested (plus 1 slab test of the bounds)\n",
               (double)stats.counters.box_tests / rays - 1.0, (double)stats.counters.primitive_tests / rays);
    }
    accel_destroy(a);
    triangle_set_free(&set);
    accel_input_free(&in);
    return status;
}

int main(int argc, char **argv)
{
    cli_options opts = cli_defaults("build/out/ch04.exr", 640, 480, 1);
    grid_flags f = {{accel_mesh_names, NULL, 0}, NULL, 102400, 10000, GRID_DEFAULT_DENSITY, 200.0f, false,
                    CAMERA_NOT_OVERRIDDEN};
    const cli_flag extras[] = {
        {"--density", CLI_FLOAT, &f.density, "C", "cells per triangle: #cells = C * #triangles (default 27)", 1e-3,
         1e6},
        {"--mesh", CLI_CHOICE, &f.mesh, NULL,
         "the procedural mesh (default tori); stadium: a dense sphere (the teapot) in a huge sparse stadium", 0,
         0},
        {"--triangles", CLI_INT, &f.triangles, "N", "tori field size: 1024, 10240, 102400 (default) or 1048576", 1,
         1048576},
        {"--obj", CLI_STRING, &f.obj_path, "FILE", "load a Wavefront OBJ file instead", 0, 0},
        CLI_CAMERA_FLAGS(f.view),
        {"--heatmap", CLI_BOOL, &f.heatmap, NULL, "show the cost of each ray: cells visited + triangles tested", 0, 0},
        {"--heatmap-max", CLI_FLOAT, &f.heatmap_max, "COST", "the cost shown as white (default 200)", 1, 1e7},
        {"--probe-rays", CLI_INT, &f.probe_rays, "N",
         "also trace N rays aimed at random triangles, one thread (default 10000; 0: none)", 0, 1 << 24},
    };
    cli_spec spec = {"04-uniform-grid",
                     "Uniform spatial partitions (GAMES101 lecture 14): find the bounding box, create a grid of\n"
                     "#cells = C * #objects (C about 27), store each object in the cells it overlaps, then step\n"
                     "each ray through the cells it pierces (3D-DDA) and test only the objects stored there.\n"
                     "Prints the grid's resolution, empty cells, the fullest cell, and tests per ray.\n"
                     "--mesh stadium shows the teapot in a stadium, where a uniform grid fails.",
                     extras, (int)(sizeof extras / sizeof extras[0]), "its camera ray (the cells it visits and the triangles it tests)"};
    cli_parse_or_exit(argc, argv, &spec, &opts);
    return run(&opts, spec.program, &f);
}
