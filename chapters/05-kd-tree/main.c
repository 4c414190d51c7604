/* 05-kd-tree: a kd-tree over a mesh, split where the surface area heuristic
 * says, walked front to back.
 *
 * Builds the kd-tree over the tori field (102400 triangles by default), the
 * teapot in a stadium, an icosphere or an OBJ file; renders it (or, with
 * --heatmap, what each ray cost); prints the tree's figures, the tests per
 * ray, and how the build time compares with the time spent tracing. --bench
 * also times the Embree harness's two ray sets on one thread. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "05-kd-tree/kdtree.h"
#include "cli.h"
#include "memory.h"
#include "program.h"
#include "timer.h"

/* ---- the Embree harness's ray sets, for --bench ------------------------------ */

enum { BENCH_REPEATS = 3 };

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Median of BENCH_REPEATS timings of closest hit and of any hit, one thread. */
static void bench(const accel *a, bool coherent)
{
    int count;
    ray *rays = accel_harness_rays(a->set->bounds, coherent, &count);
    double closest[BENCH_REPEATS], any[BENCH_REPEATS];
    long hits = 0;
    double t_sum = 0.0;
    ray_counters counters = {0};
    for (int rep = 0; rep < BENCH_REPEATS; rep++) {
        hits = 0;
        t_sum = 0.0;
        double start = timer_seconds();
        for (int i = 0; i < count; i++) {
            hit_record hit;
            if (accel_closest_hit(a, rays[i], &hit, &counters)) {
                hits++;
                t_sum += hit.t;
            }
        }
        closest[rep] = timer_seconds() - start;
        start = timer_seconds();
        for (int i = 0; i < count; i++)
            accel_any_hit(a, rays[i], &counters);
        any[rep] = timer_seconds() - start;
    }
    qsort(closest, BENCH_REPEATS, sizeof *closest, compare_doubles);
    qsort(any, BENCH_REPEATS, sizeof *any, compare_doubles);
    printf("bench %-10s %7d rays: closest hit %.2f Mrays/s, any hit %.2f Mrays/s (1 thread; hit fraction %.4f, "
           "sum of t %.6e)\n",
           coherent ? "coherent" : "incoherent", count, count / closest[BENCH_REPEATS / 2] * 1e-6,
           count / any[BENCH_REPEATS / 2] * 1e-6, (double)hits / count, t_sum);
    double tests = (double)count * BENCH_REPEATS * 2;
    printf("      %.2f nodes visited and %.2f triangles tested per ray (closest and any hit together)\n",
           (double)counters.box_tests / tests, (double)counters.primitive_tests / tests);
    free(rays);
}

/* ---- the program ------------------------------------------------------------------ */

static void usage_error(const char *message, const char *value)
{
    fprintf(stderr, "05-kd-tree: %s '%s'\ntry --help\n", message, value);
    exit(2);
}

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

    mesh m;
    mesh_init(&m);
    const char *scene_name = mesh_name;
    bool stadium = false;
    if (obj_path != NULL) {
        char err[MESH_ERROR_SIZE];
        if (!mesh_load_obj(&m, obj_path, err, sizeof err)) {
            fprintf(stderr, "05-kd-tree: %s\n", err);
            mesh_free(&m); /* the load left m as it was, but its arrays may have grown */
            return 1;
        }
        scene_name = obj_path;
    } else if (strcmp(mesh_name, "tori") == 0) {
        mesh_tori_field(&m, triangles);
    } else if (strcmp(mesh_name, "stadium") == 0) {
        /* 81920 triangles of teapot (a sphere of radius 1), 10 of stadium
         * 200 x 50 x 200: chapter 04's scene, seen by chapter 04's camera. */
        mesh_teapot_in_stadium(&m, 6, 200.0f);
        stadium = true;
    } else if (strcmp(mesh_name, "icosphere") == 0) {
        mesh_icosphere(&m, vec3_make(0, 0, 0), 1.0f, 6, -1);
    } else {
        usage_error("--mesh must be tori, stadium or icosphere, not", mesh_name);
    }
    if (m.face_count == 0) {
        fprintf(stderr, "05-kd-tree: %s has no triangles\n", scene_name);
        mesh_free(&m);
        return 1;
    }

    /* --scene: the scene file's triangles (and camera) replace the mesh. */
    scene_desc desc;
    if (program_load_scene(&opts, spec.program, &desc)) {
        char err[SCENE_ERROR_SIZE];
        if (obj_path != NULL) {
            fprintf(stderr, "%s: --scene and --obj: choose one\n", spec.program);
            return 2;
        }
        scene_name = desc.source;
        mesh_free(&m);
        mesh_init(&m);
        if (!accel_mesh_from_desc(&m, &desc, spec.program, NULL, NULL, err, sizeof err)) {
            fprintf(stderr, "%s: %s\n", spec.program, err);
            scene_desc_free(&desc);
            return 1;
        }
        stadium = false;
    }
    triangle_set set;
    triangle_set_from_mesh(&set, &m);
    accel *a = kdtree_build_with(&set, &options);
    const kd_tree *tree = (const kd_tree *)a;
    const accel_stats *st = &a->stats;
    if (!opts.quiet) {
        double n = (double)set.count;
        printf("%s: %d triangles; SAH C_traverse = %g, C_isect = %g, empty bonus %g\n", scene_name, set.count,
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
    /* The Embree harness's view of the whole mesh; for the stadium, a view
     * from inside it of the teapot, which from outside is below a pixel. */
    camera cam = stadium ? camera_look_at(vec3_make(7, 5, 10), vec3_make(0, 1, 0), vec3_make(0, 1, 0), 30.0f,
                                          opts.width, opts.height)
                         : accel_scene_camera(&desc, set.bounds, opts.width, opts.height);
    scene_desc_free(&desc);
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
        bench(a, true);
        bench(a, false);
    }
    accel_destroy(a);
    triangle_set_free(&set);
    mesh_free(&m);
    return status;
}
