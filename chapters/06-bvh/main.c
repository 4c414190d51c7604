/* 06-bvh: a bounding volume hierarchy over a mesh, split at the median object
 * (the lecture's heuristics) or by the surface area heuristic.
 *
 * Builds the BVH over the tori field (102400 triangles by default), renders
 * it (or, with --heatmap, what each ray cost), and prints the tree's figures
 * and the tests per ray. --bench also times the Embree harness's two ray
 * sets (shared/anchors/embree_bench.c) on one thread. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "06-bvh/bvh.h"
#include "cli.h"
#include "program.h"

/* ---- the program -------------------------------------------------------------- */

static void usage_error(const char *message, const char *value)
{
    fprintf(stderr, "06-bvh: %s '%s'\ntry --help\n", message, value);
    exit(2);
}

int main(int argc, char **argv)
{
    cli_options opts = cli_defaults("build/out/ch06.exr", 640, 480, 1);
    const char *split_name = "sah", *order_name = "sign", *mesh_name = "tori", *obj_path = NULL;
    int triangles = 102400;
    bool heatmap = false, run_bench = false;
    float heatmap_max = 120.0f;
    const cli_flag extras[] = {
        {"--split", CLI_STRING, &split_name, "median|sah",
         "median: longest axis, median object (the lecture); sah: surface area heuristic (default)", 0, 0},
        {"--order", CLI_STRING, &order_name, "sign|distance",
         "near child first by the sign of d on the split axis (default), or by where the ray enters", 0, 0},
        {"--mesh", CLI_STRING, &mesh_name, "tori|stadium|icosphere", "the procedural mesh (default tori)", 0, 0},
        {"--triangles", CLI_INT, &triangles, "N", "tori field size: 1024, 10240, 102400 (default) or 1048576", 1,
         1048576},
        {"--obj", CLI_STRING, &obj_path, "FILE", "load a Wavefront OBJ file instead", 0, 0},
        {"--heatmap", CLI_BOOL, &heatmap, NULL, "show the cost of each ray: nodes visited + triangles tested", 0, 0},
        {"--heatmap-max", CLI_FLOAT, &heatmap_max, "COST", "the cost shown as white (default 120)", 1, 1e6},
        {"--bench", CLI_BOOL, &run_bench, NULL, "also time the Embree harness's ray sets on one thread", 0, 0},
    };
    cli_spec spec = {"06-bvh",
                     "Bounding volume hierarchies (GAMES101 lecture 14): find the bounding box of the objects,\n"
                     "recursively split the set of objects in two subsets, recompute their bounding boxes, stop\n"
                     "when a node contains few objects and store them in a leaf. --split median splits along\n"
                     "the longest axis at the median object; --split sah where the surface area heuristic says.\n"
                     "Prints the tree's figures and the box and triangle tests per ray. (Wider nodes, as\n"
                     "production kernels use: chapter 13.)",
                     extras, (int)(sizeof extras / sizeof extras[0])};
    cli_parse_or_exit(argc, argv, &spec, &opts);

    bvh_split split = BVH_SPLIT_SAH;
    if (strcmp(split_name, "median") == 0)
        split = BVH_SPLIT_MEDIAN;
    else if (strcmp(split_name, "sah") != 0)
        usage_error("--split must be median or sah, not", split_name);
    bvh_order order = BVH_ORDER_AXIS_SIGN;
    if (strcmp(order_name, "distance") == 0)
        order = BVH_ORDER_DISTANCE;
    else if (strcmp(order_name, "sign") != 0)
        usage_error("--order must be sign or distance, not", order_name);

    accel_input in;
    int load_status = accel_input_load(&in, &opts, spec.program, mesh_name, obj_path, triangles, 7);
    if (load_status != 0)
        return load_status;
    triangle_set set;
    triangle_set_from_mesh(&set, &in.m);
    accel *a = bvh_build(&set, split);
    bvh_set_order(a, order);
    const accel_stats *s = &a->stats;
    if (!opts.quiet) {
        const bvh *b = (const bvh *)a;
        double n = (double)set.count;
        printf("%s over %d triangles: built in %.1f ms; %.1f bytes per triangle (nodes %.1f, index %.1f, "
               "triangles %.1f)\n",
               s->name, set.count, s->build_seconds * 1e3, (double)s->bytes / n,
               (double)b->node_count * sizeof(bvh_node) / n, (double)sizeof(int),
               (double)sizeof(bvh_triangle));
        printf("%d nodes, %d leaves (%.2f triangles per leaf), depth %d, %.2f references per triangle, "
               "SAH cost %.1f\n",
               s->nodes, s->leaves, n / s->leaves, s->max_depth, (double)s->references / n, bvh_sah_cost(b));
    }
    if (run_bench) {
        accel_bench_harness(a, true);
        accel_bench_harness(a, false);
    }

    accel_view view = {a, heatmap, heatmap_max};
    camera cam = accel_input_camera(&in, set.bounds, opts.width, opts.height);
    render_stats stats;
    int status = program_render(&opts, spec.program, accel_view_radiance, &view, &cam, &stats);
    if (status == 0 && !opts.quiet) {
        double rays = (double)stats.counters.camera_rays;
        printf("%s, %s order: %.2f nodes visited and %.2f triangles tested per ray\n", s->name,
                   order == BVH_ORDER_DISTANCE ? "distance" : "axis-sign", (double)stats.counters.box_tests / rays,
                   (double)stats.counters.primitive_tests / rays);
    }
    accel_destroy(a);
    triangle_set_free(&set);
    accel_input_free(&in);
    return status;
}
