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

int main(int argc, char **argv)
{
    cli_options opts = cli_defaults("build/out/ch05.exr", 640, 480, 1);
    const char *mesh_name = "tori", *obj_path = NULL;
    int triangles = 102400, max_depth = 0;
    bool heatmap = false, run_bench = false;
    float heatmap_max = 120.0f;
    kdtree_options options = kdtree_default_options();
    const cli_flag extras[] = {
        {"--mesh", CLI_STRING, &mesh_name, "tori|stadium|icosphere",
         "the procedural mesh (default tori); stadium: a dense sphere (the teapot) in a huge sparse stadium", 0, 0},
        {"--triangles", CLI_INT, &triangles, "N", "tori field size: 1024, 10240, 102400 (default) or 1048576", 1,
         1048576},
        {"--obj", CLI_STRING, &obj_path, "FILE", "load a Wavefront OBJ file instead", 0, 0},
        {"--heatmap", CLI_BOOL, &heatmap, NULL, "show the cost of each ray: nodes visited + triangles tested", 0, 0},
        {"--heatmap-max", CLI_FLOAT, &heatmap_max, "COST", "the cost shown as white (default 120)", 1, 1e6},
        {"--traversal-cost", CLI_FLOAT, &options.traversal_cost, "X", "the SAH's C_traverse (default 2)", 0.001,
         1e6},
        {"--intersection-cost", CLI_FLOAT, &options.intersection_cost, "X", "the SAH's C_isect (default 1)",
         0.001, 1e6},
        {"--empty-bonus", CLI_FLOAT, &options.empty_bonus, "X",
         "cost factor for a split with an empty side (default 0.8; 1 = none)", 0.01, 1},
        {"--max-depth", CLI_INT, &max_depth, "N", "depth limit (default 8 + 1.3 log2 N)", 0, KD_MAX_DEPTH},
        {"--bench", CLI_BOOL, &run_bench, NULL, "also time the Embree harness's ray sets on one thread", 0, 0},
    };
    cli_spec spec = {"05-kd-tree",
                     "KD-trees (GAMES101 lecture 14): spatial partitions. Split space by one axis-aligned plane\n"
                     "per node, placed where the surface area heuristic predicts the cheapest tracing; a\n"
                     "triangle that straddles the plane goes to both sides. A ray walks the cells it crosses\n"
                     "front to back and stops at the first cell holding a hit inside it. Prints the tree's\n"
                     "figures, the node and triangle tests per ray, and build time against tracing time.",
                     extras, (int)(sizeof extras / sizeof extras[0])};
    cli_parse_or_exit(argc, argv, &spec, &opts);
    options.max_depth = max_depth;

    accel_input in;
    int load_status = accel_input_load(&in, &opts, spec.program, mesh_name, obj_path, triangles, 6);
    if (load_status != 0)
        return load_status;
    triangle_set set;
    triangle_set_from_mesh(&set, &in.m);
    accel *a = kdtree_build_with(&set, &options);
    const kd_tree *tree = (const kd_tree *)a;
    const accel_stats *st = &a->stats;
    if (!opts.quiet) {
        double n = (double)set.count;
        printf("%s: %d triangles; SAH C_traverse = %g, C_isect = %g, empty bonus %g\n", in.name, set.count,
               (double)options.traversal_cost, (double)options.intersection_cost, (double)options.empty_bonus);
        printf("kd-tree: built in %.1f ms; %d nodes, %d leaves (%d empty), depth %d (limit %d)\n",
               st->build_seconds * 1e3, st->nodes, st->leaves, tree->empty_leaves, st->max_depth,
               tree->depth_limit);
        printf("         %.2f references per triangle, %.1f triangles per non-empty leaf, %.1f bytes per triangle\n",
               (double)st->references / n,
               (double)st->references / (double)(st->leaves > tree->empty_leaves ? st->leaves - tree->empty_leaves : 1),
               (double)st->bytes / n);
        printf("         SAH cost of the tree %.2f (a leaf holding everything: %.0f)\n", tree->sah_cost,
               (double)options.intersection_cost * n);
    }

    accel_view view = {a, heatmap, heatmap_max};
    camera cam = accel_input_camera(&in, set.bounds, opts.width, opts.height);
    render_stats stats;
    int status = program_render(&opts, spec.program, accel_view_radiance, &view, &cam, &stats);
    if (status == 0 && !opts.quiet) {
        double rays = (double)stats.counters.camera_rays;
        printf("per ray: %.2f nodes visited, %.2f triangles tested (brute force: %d)\n",
               (double)stats.counters.box_tests / rays, (double)stats.counters.primitive_tests / rays, set.count);
        if (stats.seconds > 0.0)
            printf("build vs trace: the build took as long as tracing %.0f rays here (%.2f images of this size)\n",
                   st->build_seconds * rays / stats.seconds, st->build_seconds / stats.seconds);
    }
    if (status == 0 && run_bench) {
        accel_bench_harness(a, true);
        accel_bench_harness(a, false);
    }
    accel_destroy(a);
    triangle_set_free(&set);
    accel_input_free(&in);
    return status;
}
