/* 06-bvh: a bounding volume hierarchy over a mesh, split at the median object
 * (the lecture's heuristics) or by the surface area heuristic.
 *
 * Builds the BVH over the tori field (102400 triangles by default), renders
 * it (or, with --heatmap, what each ray cost), and prints the tree's figures
 * and the tests per ray. --bench also times the Embree harness's two ray
 * sets (the same rays as Embree's benchmark harness) on one thread. */
#include <stdio.h>
#include <string.h>

#include "03-aabb-slabs/accel_program.h"
#include "03-aabb-slabs/accel_view.h"
#include "06-bvh/bvh.h"
#include "cli.h"
#include "program.h"
#include "mpi_split.h"

/* ---- the program -------------------------------------------------------------- */

typedef struct {
    cli_choice split, order, mesh;
    const char *obj;
    int triangles;
    bool heatmap, bench;
    float heatmap_max;
    camera_override view; /* --eye, --target, --fov */
} chapter_flags;

static const char *const SPLITS[] = {"median", "sah", NULL};
static const char *const SPLIT_NOTES[] = {"longest axis, median object (the lecture)",
                                          "surface area heuristic (default)", NULL};
static const char *const ORDERS[] = {"sign", "distance", "recursive", NULL};
static const char *const ORDER_NOTES[] = {"near child first by the sign of d on the split axis (default)",
                                          "near child first by where the ray enters its box",
                                          "the slide's Intersect(ray, node): both children, recursively", NULL};
static const char *const MESHES[] = {"tori", "stadium", "icosphere", NULL};

/* What the tree is: its size, shape and the SAH's estimate of its cost. */
static void print_tree(const accel *a, const triangle_set *set)
{
    const accel_stats *s = &a->stats;
    const bvh *b = (const bvh *)a;
    double n = (double)set->count;
    printf("%s over %d triangles: built in %.1f ms; %.1f bytes per triangle (nodes %.1f, index %.1f, "
           "triangles %.1f)\n",
           s->name, set->count, s->build_seconds * 1e3, (double)s->bytes / n,
           (double)b->node_count * sizeof(bvh_node) / n, (double)sizeof(int), (double)sizeof(bvh_triangle));
    printf("%d nodes, %d leaves (%.2f triangles per leaf), depth %d, %.2f references per triangle, "
           "SAH cost %.1f\n",
           s->nodes, s->leaves, n / s->leaves, s->max_depth, (double)s->references / n, bvh_sah_cost(b));
}

/* The mesh through the tree: its picture (or heat map), then the tests per ray. */
static int render(const cli_options *opts, const chapter_flags *f, const accel_input *in, const accel *a)
{
    program_note_accel(a->stats.name);
    render_stats stats;
    int status = accel_input_render(opts, "06-bvh", in, a, f->heatmap, f->heatmap_max, &f->view, &stats);
    if (status == 0 && !opts->quiet) {
        double rays = (double)stats.counters.camera_rays;
        printf("%s, %s order: %.2f nodes visited and %.2f triangles tested per ray\n", a->stats.name,
               cli_choice_name(&f->order), (double)stats.counters.box_tests / rays,
               (double)stats.counters.primitive_tests / rays);
    }
    return status;
}

int main(int argc, char **argv)
{
    cli_options opts = cli_defaults("build/out/ch06.exr", 640, 480, 1);
    chapter_flags f = {{SPLITS, SPLIT_NOTES, BVH_SPLIT_SAH}, {ORDERS, ORDER_NOTES, BVH_ORDER_AXIS_SIGN},
                       {MESHES, NULL, 0}, NULL, 102400, false, false, 120.0f, CAMERA_NOT_OVERRIDDEN};
    const cli_flag extras[] = {
        {"--split", CLI_CHOICE, &f.split, NULL, "where a node's objects are split in two", 0, 0},
        {"--order", CLI_CHOICE, &f.order, NULL, "which child a ray visits first", 0, 0},
        {"--mesh", CLI_CHOICE, &f.mesh, NULL, "the procedural mesh (default tori)", 0, 0},
        {"--triangles", CLI_INT, &f.triangles, "N", "tori field size: 1024, 10240, 102400 (default) or 1048576", 1,
         1048576},
        {"--obj", CLI_STRING, &f.obj, "FILE", "load a Wavefront OBJ file instead", 0, 0},
        CLI_CAMERA_FLAGS(f.view),
        {"--heatmap", CLI_BOOL, &f.heatmap, NULL, "show the cost of each ray: nodes visited + triangles tested", 0, 0},
        {"--heatmap-max", CLI_FLOAT, &f.heatmap_max, "COST", "the cost shown as white (default 120)", 1, 1e6},
        {"--bench", CLI_BOOL, &f.bench, NULL, "also time the Embree harness's ray sets on one thread", 0, 0},
    };
    cli_spec spec = {"06-bvh",
                     "Bounding volume hierarchies (GAMES101 lecture 14): find the bounding box of the objects,\n"
                     "recursively split the set of objects in two subsets, recompute their bounding boxes, stop\n"
                     "when a node contains few objects and store them in a leaf. --split median splits along\n"
                     "the longest axis at the median object; --split sah where the surface area heuristic says.\n"
                     "Prints the tree's figures and the box and triangle tests per ray. (Wider nodes, as\n"
                     "production kernels use: chapter 13.)",
                     extras, (int)(sizeof extras / sizeof extras[0]), "its camera ray (the nodes it visits and the triangles it tests)"};
    cli_parse_or_exit(argc, argv, &spec, &opts);
    if (f.bench && mpi_split_refuse(spec.program, "--bench"))
        return 2;
    accel_input in;
    int status = accel_input_load(&in, &opts, spec.program, cli_choice_name(&f.mesh), f.obj, f.triangles, 7);
    if (status != 0)
        return status;
    triangle_set set;
    triangle_set_from_mesh(&set, &in.m);
    accel *a = bvh_build(&set, (bvh_split)f.split.index);
    bvh_set_order(a, (bvh_order)f.order.index);
    if (!opts.quiet)
        print_tree(a, &set);
    if (f.bench) {
        accel_bench_harness(a, true);
        accel_bench_harness(a, false);
    }
    status = render(&opts, &f, &in, a);
    accel_destroy(a);
    triangle_set_free(&set);
    accel_input_free(&in);
    return status;
}
