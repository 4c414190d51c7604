/* bvh_levels.c -- the figures of chapter 06's steps: the boxes of a BVH, one
 * level of the tree at a time, over the tori it was built on.
 *
 * The lecture builds a BVH by finding the bounding box of all objects,
 * splitting the set in two, recomputing the box of each subset and
 * recursing. This program builds chapter 06's tree with the lecture's split
 * (longest axis, median object) and draws the boxes of the nodes at depth
 * --level (and the leaves above it, so that the boxes always cover every
 * triangle): --level 0 is the root's box, 1 the two boxes of the first
 * split, and so on. Each triangle takes the colour of the box it belongs to
 * at that level, so the subsets of each split can be seen, and where two
 * boxes overlap (boxes are drawn up to BOXES_DRAWN_MAX of them; a --level
 * past the leaves shows the leaves by colour alone). It is not a chapter program: it exists to draw the book's
 * figures (docs/figures.txt), and reads the tree through bvh.h only.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "03-aabb-slabs/accel_view.h"
#include "06-bvh/bvh.h"
#include "camera.h"
#include "cli.h"
#include "memory.h"
#include "mesh.h"
#include "program.h"

/* Width of a drawn box edge, as a fraction of the box's largest extent. */
static const float EDGE_WIDTH = 0.004f;

/* Deeper in the tree the boxes are too many and too small to tell apart:
 * past this many, only the triangles' colours show the groups. */
enum { BOXES_DRAWN_MAX = 64 };

typedef struct {
    const accel *structure;
    aabb *boxes; /* the boxes at the chosen level */
    int box_count;
    int *group; /* for each triangle (original index), the box it is in */
} level_view;

static vec3 group_colour(int k)
{
    /* Distinct colours from a golden-ratio walk around the hue circle. */
    float h = fmodf(0.13f + 0.618034f * (float)k, 1.0f) * 6.0f;
    float x = 1.0f - fabsf(fmodf(h, 2.0f) - 1.0f);
    vec3 c = h < 1 ? vec3_make(1, x, 0) : h < 2 ? vec3_make(x, 1, 0) : h < 3 ? vec3_make(0, 1, x)
           : h < 4 ? vec3_make(0, x, 1) : h < 5 ? vec3_make(x, 0, 1) : vec3_make(1, 0, x);
    return vec3_add(vec3_scale(c, 0.55f), vec3_splat(0.2f));
}

/* A point on the box's surface is on one of its 12 edges when two of its
 * three coordinates lie on the box's faces. */
static bool near_box_edge(const aabb *b, vec3 p)
{
    vec3 e = aabb_extent(*b);
    float tolerance = EDGE_WIDTH * vec3_max_component(e);
    int on_faces = 0;
    for (int axis = 0; axis < 3; axis++) {
        float v = vec3_axis(p, axis);
        on_faces += fabsf(v - vec3_axis(b->lo, axis)) < tolerance || fabsf(v - vec3_axis(b->hi, axis)) < tolerance;
    }
    return on_faces >= 2;
}

static vec3 level_radiance(const void *ctx, ray r, pcg32 *rng, ray_counters *counters)
{
    (void)rng;
    const level_view *v = ctx;
    hit_record hit;
    bool found = accel_closest_hit(v->structure, r, &hit, counters);
    vec3 colour = vec3_make(0.02f, 0.02f, 0.03f);
    if (found) {
        /* Headlight shading, as chapter 03: brightest where the surface faces the eye. */
        float facing = fabsf(vec3_dot(hit.normal_geometric, vec3_normalize(r.direction)));
        colour = vec3_scale(group_colour(v->group[hit.shape_id]), 0.15f + 0.85f * facing);
    }
    /* Each box tints what lies behind it; its edges are drawn, also behind the tori. */
    slab_ray sr = slab_ray_make(r);
    for (int k = 0; k < (v->box_count <= BOXES_DRAWN_MAX ? v->box_count : 0); k++) {
        float t_enter, t_exit;
        if (!aabb_slab_test(&v->boxes[k], &sr, 0.0f, INFINITY, &t_enter, &t_exit))
            continue;
        vec3 c = group_colour(k);
        colour = vec3_add(colour, vec3_scale(c, 0.04f));
        bool front = !found || t_enter < hit.t, back = !found || t_exit < hit.t;
        if ((front && near_box_edge(&v->boxes[k], ray_at(r, t_enter))) ||
            (back && near_box_edge(&v->boxes[k], ray_at(r, t_exit))))
            colour = vec3_add(colour, vec3_scale(c, 0.8f));
    }
    return colour;
}

/* The leaves below node n hold bvh.triangles[first .. first + count); mark
 * their original triangles as being in group g. */
static void mark_group(const bvh *tree, int n, int g, int *group)
{
    const bvh_node *node = &tree->nodes[n];
    if (bvh_node_is_leaf(node)) {
        for (int i = node->first; i < node->first + bvh_node_triangles(node); i++)
            group[tree->triangle_index[i]] = g;
        return;
    }
    mark_group(tree, node->first, g, group);
    mark_group(tree, node->first + 1, g, group);
}

/* Collects the nodes at depth `level`, and the leaves above it. */
static void collect_level(const bvh *tree, int n, int depth, int level, level_view *v)
{
    const bvh_node *node = &tree->nodes[n];
    if (depth == level || bvh_node_is_leaf(node)) {
        v->boxes[v->box_count] = node->box;
        mark_group(tree, n, v->box_count, v->group);
        v->box_count++;
        return;
    }
    collect_level(tree, node->first, depth + 1, level, v);
    collect_level(tree, node->first + 1, depth + 1, level, v);
}

int main(int argc, char **argv)
{
    cli_options opts = cli_defaults("build/out/bvh_level.exr", 640, 480, 1);
    int level = 0, triangles = 10240;
    cli_flag extras[] = {
        {"--level", CLI_INT, &level, "L", "draw the boxes of the nodes at depth L (0: the root)", 0, 30},
        {"--triangles", CLI_INT, &triangles, "N", "triangles of the tori field (default 10240)", 16, 1 << 22},
    };
    cli_spec spec = {"bvh_levels",
                     "The boxes of chapter 06's BVH (the lecture's median split) at one depth of the tree,\n"
                     "over the tori it was built on; each triangle in the colour of its box. For the book.",
                     extras, sizeof extras / sizeof extras[0], NULL};
    cli_parse_or_exit(argc, argv, &spec, &opts);

    mesh m;
    mesh_init(&m);
    mesh_tori_field(&m, triangles);
    triangle_set set;
    triangle_set_from_mesh(&set, &m);
    accel *a = bvh_build(&set, BVH_SPLIT_MEDIAN);
    const bvh *tree = (const bvh *)a;

    level_view view = {.structure = a};
    view.boxes = memory_allocate((size_t)tree->node_count, sizeof *view.boxes);
    view.group = memory_allocate((size_t)set.count, sizeof *view.group);
    collect_level(tree, 0, 0, level, &view);
    if (!opts.quiet)
        printf("bvh_levels: depth %d: %d boxes over %d triangles; the root splits along %c\n", level, view.box_count,
               set.count, "xyz"[bvh_node_axis(&tree->nodes[0])]);

    camera cam = accel_view_camera(set.bounds, opts.width, opts.height);
    int status = program_render(&opts, "bvh_levels", level_radiance, &view, &cam, NULL);

    free(view.boxes);
    free(view.group);
    accel_destroy(a);
    triangle_set_free(&set);
    mesh_free(&m);
    return status;
}
