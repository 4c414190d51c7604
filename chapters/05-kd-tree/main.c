/* 05-kd-tree: a kd-tree over a mesh, split where the surface area heuristic
 * says, walked front to back.
 *
 * Builds the kd-tree over the tori field (102400 triangles by default), the
 * teapot in a stadium, an icosphere or an OBJ file; renders it (or, with
 * --heatmap, what each ray cost); prints the tree's figures, the tests per
 * ray, and how the build time compares with the time spent tracing. --bench
 * also times the Embree harness's two ray sets on one thread. */
#include <stdio.h>

#include "03-aabb-slabs/accel_program.h"
#include "03-aabb-slabs/accel_view.h"
#include "05-kd-tree/kdtree.h"
#include "cli.h"
#include "program.h"

/* ---- the program ------------------------------------------------------------------ */

/* The tree's figures: its size, its depth and its SAH cost. */
static void print_tree(const char *mesh_name, const accel *a, const kdtree_options *options)
{
    const kd_tree *tree = (const kd_tree *)a;
    const accel_stats *st = &a->stats;
    double n = (double)a->set->count;
    printf("%s: %d triangles; SAH C_traverse = %g, C_isect = %g, empty bonus %g\n", mesh_name, a->set->count,
           (double)options->traversal_cost, (double)options->intersection_cost, (double)options->empty_bonus);
    printf("kd-tree: built in %.1f ms; %d nodes, %d leaves (%d empty), depth %d (limit %d)\n",
           st->build_seconds * 1e3, st->nodes, st->leaves, tree->empty_leaves, st->max_depth, tree->depth_limit);
    printf("         %.2f references per triangle, %.1f triangles per non-empty leaf, %.1f bytes per triangle\n",
           (double)st->references / n,
           (double)st->references / (double)(st->leaves > tree->empty_leaves ? st->leaves - tree->empty_leaves : 1),
           (double)st->bytes / n);
    printf("         SAH cost of the tree %.2f (a leaf holding everything: %.0f)\n", tree->sah_cost,
           (double)options->intersection_cost * n);
}

/* What the render cost per ray, and the build against the tracing. */
static void print_costs(const accel *a, const render_stats *stats)
{
    double rays = (double)stats->counters.camera_rays;
    double build = a->stats.build_seconds;
    printf("per ray: %.2f nodes visited, %.2f triangles tested (brute force: %d)\n",
           (double)stats->counters.box_tests / rays, (double)stats->counters.primitive_tests / rays, a->set->count);
    if (stats->seconds > 0.0)
        printf("build vs trace: the build took as long as tracing %.0f rays here (%.2f images of this size)\n",
               build * rays / stats->seconds, build / stats->seconds);
}

/* The program's own flags. Its run() reads as chapter 04's and 06's do (load the
 * mesh, build, print the structure, render, print the costs): each
 * program is read whole on its chapter's page, so the steps they share
 * are one call each into chapter 03's accel_program.h (accel_input_load,
 * accel_input_render), and what stays is the chapter's own. */
typedef struct {
    cli_choice mesh;
    const char *obj_path;
    int triangles;
    bool heatmap, run_bench;
    float heatmap_max;
    kdtree_options options;
    camera_override view; /* --eye, --target, --fov */
} kd_flags;

/* Builds the tree over the mesh the flags ask for, prints its figures,
 * renders it and prints what each ray cost; --bench times the harness's
 * ray sets. Returns the exit status. */
static int run(cli_options *opts, const char *program, const kd_flags *f)
{
    accel_input in;
    int load_status = accel_input_load(&in, opts, program, cli_choice_name(&f->mesh), f->obj_path, f->triangles, 6);
    if (load_status != 0)
        return load_status;
    triangle_set set;
    triangle_set_from_mesh(&set, &in.m);
    accel *a = kdtree_build_with(&set, &f->options);
    if (!opts->quiet)
        print_tree(in.name, a, &f->options);

    render_stats stats;
    int status = accel_input_render(opts, program, &in, a, f->heatmap, f->heatmap_max, &f->view, &stats);
    if (status == 0 && !opts->quiet)
        print_costs(a, &stats);
    if (status == 0 && f->run_bench) {
        accel_bench_harness(a, true);
        accel_bench_harness(a, false);
    }
    accel_destroy(a);
    triangle_set_free(&set);
    accel_input_free(&in);
    return status;
}

int main(int argc, char **argv)
{
    cli_options opts = cli_defaults("build/out/ch05.exr", 640, 480, 1);
    kd_flags f = {{accel_mesh_names, NULL, 0}, NULL, 102400, false, false, 120.0f, kdtree_default_options(),
                  CAMERA_NOT_OVERRIDDEN};
    const cli_flag extras[] = {
        {"--mesh", CLI_CHOICE, &f.mesh, NULL,
         "the procedural mesh (default tori); stadium: a dense sphere (the teapot) in a huge sparse stadium", 0, 0},
        {"--triangles", CLI_INT, &f.triangles, "N", "tori field size: 1024, 10240, 102400 (default) or 1048576", 1,
         1048576},
        {"--obj", CLI_STRING, &f.obj_path, "FILE", "load a Wavefront OBJ file instead", 0, 0},
        CLI_CAMERA_FLAGS(f.view),
        {"--heatmap", CLI_BOOL, &f.heatmap, NULL, "show the cost of each ray: nodes visited + triangles tested", 0, 0},
        {"--heatmap-max", CLI_FLOAT, &f.heatmap_max, "COST", "the cost shown as white (default 120)", 1, 1e6},
        {"--traversal-cost", CLI_FLOAT, &f.options.traversal_cost, "X", "the SAH's C_traverse (default 2)", 0.001,
         1e6},
        {"--intersection-cost", CLI_FLOAT, &f.options.intersection_cost, "X", "the SAH's C_isect (default 1)",
         0.001, 1e6},
        {"--empty-bonus", CLI_FLOAT, &f.options.empty_bonus, "X",
         "cost factor for a split with an empty side (default 0.8; 1 = none)", 0.01, 1},
        {"--max-depth", CLI_INT, &f.options.max_depth, "N", "depth limit (default 8 + 1.3 log2 N)", 0, KD_MAX_DEPTH},
        {"--bench", CLI_BOOL, &f.run_bench, NULL, "also time the Embree harness's ray sets on one thread", 0, 0},
    };
    cli_spec spec = {"05-kd-tree",
                     "KD-trees (GAMES101 lecture 14): spatial partitions. Split space by one axis-aligned plane\n"
                     "per node, placed where the surface area heuristic predicts the cheapest tracing; a\n"
                     "triangle that straddles the plane goes to both sides. A ray walks the cells it crosses\n"
                     "front to back and stops at the first cell holding a hit inside it. Prints the tree's\n"
                     "figures, the node and triangle tests per ray, and build time against tracing time.",
                     extras, (int)(sizeof extras / sizeof extras[0]), "its camera ray (the nodes it visits and the triangles it tests)"};
    cli_parse_or_exit(argc, argv, &spec, &opts);
    return run(&opts, spec.program, &f);
}
