/* bvh_build.c -- building a BVH: the lecture's recursive partition of the
 * objects, split at the median object or by the surface area heuristic,
 * written straight into one flat array of nodes. */
#include "06-bvh/bvh.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "06-bvh/bvh_internal.h"
#include "memory.h"
#include "timer.h"

/* ---- constants of the two heuristics -------------------------------------- */

/* The lecture's "stop when the node contains few elements": a set of at most
 * this many triangles becomes a leaf. Four is a common choice (the README's
 * first exercise tries 1 and 16). */
enum { BVH_MEDIAN_LEAF_SIZE = 4 };

/* SAH: centroids are sorted into this many bins of equal width per axis, and
 * only the BVH_SAH_BINS - 1 planes between bins are tried (Wald 2007 uses 8
 * to 32). On the tori field 8, 16 and 32 bins gave the same ray speed within
 * the noise of our measurements; 32 builds slower. */
enum { BVH_SAH_BINS = 16 };

/* SAH: the cost of visiting an interior node (C_t) and of testing one
 * triangle (C_i); only their ratio matters. Counting instructions, our box
 * test and triangle test cost about the same, but a visit also pushes and
 * pops, and every node is memory to fetch. On the tori field, C_t / C_i of
 * 1, 1.5, 2 and 3 traced equally fast within the noise of our measurements
 * (README); 2 gives leaves of about 3 triangles and 38 % fewer nodes than 1. */
static const float BVH_SAH_TRAVERSAL_COST = 2.0f;
static const float BVH_SAH_INTERSECTION_COST = 1.0f;

/* SAH: a set larger than this is split even when the SAH says a leaf would be
 * cheaper (which happens for small, tightly packed sets): it bounds the work
 * of a leaf. */
enum { BVH_SAH_MAX_LEAF_SIZE = 8 };

/* SAH: can build a chain, one triangle split off per level, when triangles
 * get exponentially larger along an axis. Below this depth it splits at the
 * median instead, which halves the set each time: at most 31 more levels for
 * any int count, so the tree stays within BVH_STACK_SIZE. */
enum { BVH_SAH_DEPTH_LIMIT = BVH_STACK_SIZE - 33 };

/* ---- the builder's working set -------------------------------------------- */

/* What the build knows of a triangle: its box and where it came from. The
 * array of these is partitioned in place, so the triangles of every node are
 * a contiguous range [begin, end) of it, and at the end it is the leaf order. */
typedef struct {
    float lo[3], hi[3];
    int index;
} build_triangle;

typedef struct {
    build_triangle *tris;
    bvh_node *nodes; /* room for 2 N - 1, the most a binary tree with N leaves can have */
    bvh_split split;
    bvh_sah_params sah;
    float root_area; /* the root box's, for sah.top_area_fraction */
} builder;

/* The SAH counts a leaf's triangles in blocks of sah.leaf_block: a 4-wide
 * triangle test (chapter 13's wide BVH) costs the same for 1 to 4 triangles. */
static inline float sah_blocks(const builder *b, int n)
{
    return (float)((n + b->sah.leaf_block - 1) / b->sah.leaf_block);
}

/* The box's centroid along one axis, computed the same way everywhere. */
static inline float centroid(const build_triangle *t, int axis) { return 0.5f * (t->lo[axis] + t->hi[axis]); }

/* min/max as comparisons: fminf/fmaxf are function calls in the hot loops of
 * the build, and the inputs here are never NaN (triangle_set boxes). */
static inline float min_f(float a, float b) { return a < b ? a : b; }
static inline float max_f(float a, float b) { return a > b ? a : b; }

typedef struct {
    float lo[3], hi[3];
} box3;

static inline box3 box3_empty(void) { return (box3){{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}}; }

/* Written out axis by axis: this runs once per triangle per axis per level. */
static inline void box3_grow(box3 *b, const float lo[3], const float hi[3])
{
    b->lo[0] = min_f(b->lo[0], lo[0]);
    b->lo[1] = min_f(b->lo[1], lo[1]);
    b->lo[2] = min_f(b->lo[2], lo[2]);
    b->hi[0] = max_f(b->hi[0], hi[0]);
    b->hi[1] = max_f(b->hi[1], hi[1]);
    b->hi[2] = max_f(b->hi[2], hi[2]);
}

/* Surface area of a box that is not empty (of an empty one it is inf or
 * NaN, which the sweep below never uses). */
static inline float box3_area(const box3 *b)
{
    float x = b->hi[0] - b->lo[0], y = b->hi[1] - b->lo[1], z = b->hi[2] - b->lo[2];
    return 2.0f * (x * y + y * z + z * x);
}

static inline aabb box3_to_aabb(const box3 *b)
{
    return (aabb){vec3_make(b->lo[0], b->lo[1], b->lo[2]), vec3_make(b->hi[0], b->hi[1], b->hi[2])};
}

static inline void swap_triangles(build_triangle *a, build_triangle *b)
{
    build_triangle t = *a;
    *a = *b;
    *b = t;
}

/* ---- the lecture's heuristics: longest axis, median object ---------------- */

/* Quickselect (what C++ calls nth_element): reorder tris[begin, end) so that
 * position nth holds the triangle that would be there if the range were
 * sorted by centroid along `axis`, with no larger centroid before it and no
 * smaller one after it. Each round partitions around a pivot into < = >
 * (three ways, so that many equal centroids cannot make it quadratic) and
 * keeps only the part holding nth: O(n) on average, not the O(n log n) of a
 * sort. */
static void select_nth(build_triangle *tris, int begin, int end, int nth, int axis)
{
    while (end - begin > 1) {
        /* pivot: the median of the first, middle and last centroids */
        float a = centroid(&tris[begin], axis), b = centroid(&tris[begin + (end - begin) / 2], axis),
              c = centroid(&tris[end - 1], axis);
        float pivot = max_f(min_f(a, b), min_f(max_f(a, b), c));
        int less = begin, i = begin, greater = end;
        while (i < greater) {
            float key = centroid(&tris[i], axis);
            if (key < pivot)
                swap_triangles(&tris[less++], &tris[i++]);
            else if (key > pivot)
                swap_triangles(&tris[i], &tris[--greater]);
            else
                i++;
        }
        if (nth < less)
            end = less;
        else if (nth >= greater)
            begin = greater;
        else
            return; /* nth is among the centroids equal to the pivot */
    }
}

/* Split at the median object along the longest axis of the centroids'
 * bounds. Returns false for a leaf. */
static bool split_median(builder *b, int begin, int end, const box3 *centroids, int *axis_out, int *mid_out)
{
    /* Stop when the node contains few elements */
    if (end - begin <= BVH_MEDIAN_LEAF_SIZE)
        return false;
    /* Always choose the longest axis in node. Of the centroids' bounds, not
     * the node's box: one long triangle can make the box long along an axis
     * on which the centroids do not differ at all. */
    aabb c = box3_to_aabb(centroids);
    int axis = aabb_longest_axis(c);
    /* All centroids equal: no plane separates any two of them; splitting by
     * count would make two children with the same box as this node, which
     * every ray would visit for nothing. */
    if (!(vec3_axis(aabb_extent(c), axis) > 0.0f))
        return false;
    /* Split node at location of median object */
    int mid = begin + (end - begin) / 2;
    select_nth(b->tris, begin, end, mid, axis);
    *axis_out = axis;
    *mid_out = mid;
    return true;
}

/* ---- the surface area heuristic, with bins -------------------------------- */

/* floor((c - lo) * scale) clamped to 0 .. bin_count - 1, without a branch:
 * the clamps are done on the float, before the conversion to int (which
 * would be undefined behaviour for a float out of int's range, or NaN). */
static inline int bin_of(float c, float lo, float scale, float last_bin)
{
    float f = (c - lo) * scale;
    f = f > 0.0f ? f : 0.0f;           /* below the first bin, or NaN: bin 0 */
    f = f < last_bin ? f : last_bin;   /* c on the maximum: f = bin_count */
    return (int)f;
}

int bvh_bin_index(float c, float lo, float scale, int bin_count)
{
    return bin_of(c, lo, scale, (float)(bin_count - 1));
}

typedef struct {
    box3 box;
    int count;
} sah_bin;

/* The best split so far: its cost (times the node's area), the axis, and the
 * plane (after bin `plane`: bins 0 .. plane go left). */
typedef struct {
    float cost;
    int axis, plane;
} sah_choice;

/* The surface area heuristic on one axis: sweep the planes between the
 * bins, and keep in *best the cheapest split so far,
 *   C = C_t A + C_i (A_L N_L + A_R N_R)
 * (traversal_area = C_t A; N counted in blocks, sah_blocks). Once from the
 * right, to know the area and count of bins k .. end, then from the left,
 * where each plane's cost is computed; a plane with an empty side is not a
 * split. */
static void sah_sweep(const builder *b, const sah_bin *bins, int bin_count, float traversal_area, int axis,
                      sah_choice *best)
{
    /* exercise: sah_split */
    /* from the right: area and count of bins k .. end */
    float right_area[BVH_SAH_BINS];
    int right_count[BVH_SAH_BINS];
    box3 right = box3_empty();
    int n = 0;
    for (int k = bin_count - 1; k > 0; k--) {
        box3_grow(&right, bins[k].box.lo, bins[k].box.hi);
        n += bins[k].count;
        right_area[k] = box3_area(&right);
        right_count[k] = n;
    }
    /* from the left: the plane after bin k */
    box3 left = box3_empty();
    n = 0;
    for (int k = 0; k < bin_count - 1; k++) {
        box3_grow(&left, bins[k].box.lo, bins[k].box.hi);
        n += bins[k].count;
        if (n == 0 || right_count[k + 1] == 0)
            continue; /* one side empty: not a split */
        float cost = traversal_area + BVH_SAH_INTERSECTION_COST * (box3_area(&left) * sah_blocks(b, n) +
                                                                   right_area[k + 1] * sah_blocks(b, right_count[k + 1]));
        if (cost < best->cost)
            *best = (sah_choice){cost, axis, k};
    }
    /* end of exercise sah_split */
}

/* Split where the SAH's expected cost of a ray,
 *     cost = C_t + (A_L N_L + A_R N_R) / A * C_i,
 * is lowest, among the planes between bins on all three axes, if that beats
 * the cost of a leaf, N C_i. (A is the node's surface area, A_L and A_R the
 * areas of the boxes of the two subsets, N_L and N_R their sizes: a random
 * ray that hits the node hits a child with probability A_child / A.) Both
 * sides are compared multiplied by A, which changes nothing for A > 0 and
 * needs no division for a node whose box is flat in two directions (A = 0). */
static bool split_sah(builder *b, int begin, int end, const box3 *box, const box3 *centroids, int depth,
                      int *axis_out, int *mid_out)
{
    int count = end - begin;
    if (count <= 1)
        return false;
    if (depth >= BVH_SAH_DEPTH_LIMIT)
        return split_median(b, begin, end, centroids, axis_out, mid_out);

    /* Bins of equal width over the centroids' bounds, per axis: BVH_SAH_BINS,
     * or one per triangle for smaller sets (the bins' setup and sweep cost
     * the same for 2 triangles as for 2 million: with 16 bins always, they
     * were most of the build time). An axis along which all centroids are
     * equal has nothing to split; one whose extent is so small (or large)
     * that bin_count / extent is not a finite positive number cannot be
     * binned. Such axes get scale 0 (every centroid in bin 0) and are not
     * swept. */
    const int bin_count = count < BVH_SAH_BINS ? count : BVH_SAH_BINS;
    const float last_bin = (float)(bin_count - 1);
    float scale[3];
    bool binned[3], any_extent = false, any_binned = false;
    for (int axis = 0; axis < 3; axis++) {
        float extent = centroids->hi[axis] - centroids->lo[axis];
        float s = (float)bin_count / extent;
        binned[axis] = extent > 0.0f && isfinite(s) && s > 0.0f;
        scale[axis] = binned[axis] ? s : 0.0f;
        any_extent |= extent > 0.0f;
        any_binned |= binned[axis];
    }
    /* All centroids equal (coincident triangles): a leaf, whatever its size.
     * No split by position is possible, and one by count would not help. */
    if (!any_extent)
        return false;

    float best_cost = INFINITY;
    int best_axis = -1, best_plane = -1;
    if (any_binned) {
        /* Put each centroid in its bin on every axis: count it, grow the bin's box. */
        sah_bin bins[3][BVH_SAH_BINS];
        for (int axis = 0; axis < 3; axis++)
            for (int k = 0; k < bin_count; k++)
                bins[axis][k] = (sah_bin){box3_empty(), 0};
        for (int i = begin; i < end; i++) {
            const build_triangle *t = &b->tris[i];
            for (int axis = 0; axis < 3; axis++) {
                sah_bin *bin = &bins[axis][bin_of(centroid(t, axis), centroids->lo[axis], scale[axis], last_bin)];
                bin->count++;
                box3_grow(&bin->box, t->lo, t->hi);
            }
        }
        /* Sweep the planes between bins, once from each side. */
        float node_area = box3_area(box);
        float traversal_cost = b->sah.top_area_fraction > 0.0f && node_area >= b->sah.top_area_fraction * b->root_area
                                   ? b->sah.top_traversal_cost
                                   : b->sah.traversal_cost;
        sah_choice best = {INFINITY, -1, -1};
        for (int axis = 0; axis < 3; axis++)
            if (binned[axis])
                sah_sweep(b, bins[axis], bin_count, traversal_cost * node_area, axis, &best);
        best_cost = best.cost;
        best_axis = best.axis;
        best_plane = best.plane;
    }

    /* Stop when necessary: when a leaf is cheaper, and small enough */
    float leaf_cost = BVH_SAH_INTERSECTION_COST * sah_blocks(b, count) * box3_area(box);
    bool must_split = count > b->sah.max_leaf_size;
    if (best_axis < 0) {
        /* No binned split (the extents defeat the bins, or the areas
         * overflow): split a set too big for a leaf at the median. */
        return must_split && split_median(b, begin, end, centroids, axis_out, mid_out);
    }
    if (!(best_cost < leaf_cost) && !must_split)
        return false;

    /* Partition: triangles whose centroid is in bins 0 .. best_plane go left.
     * The bin is computed exactly as when binning, so the sides get exactly
     * the counts the cost was computed for, and neither is empty. */
    float lo = centroids->lo[best_axis], s = scale[best_axis];
    int i = begin, j = end - 1;
    for (;;) {
        while (i <= j && bin_of(centroid(&b->tris[i], best_axis), lo, s, last_bin) <= best_plane)
            i++;
        while (i <= j && bin_of(centroid(&b->tris[j], best_axis), lo, s, last_bin) > best_plane)
            j--;
        if (i >= j)
            break;
        swap_triangles(&b->tris[i++], &b->tris[j--]);
    }
    *axis_out = best_axis;
    *mid_out = i;
    return true;
}

/* ---- the recursion --------------------------------------------------------- */

/* Sets of at least this many triangles build their two halves in parallel
 * (an OpenMP task for the first); smaller ones are not worth a task. */
enum { BVH_TASK_MIN = 4096 };

/* The lecture's recursion. The nodes below a set of n triangles (at most
 * 2 n - 2) get slots of their own from `descendants` on: the children the
 * first two, the first child's subtree the next 2 n_L - 2, the second's
 * the rest. So the two halves of a large set can be built at the same time
 * (an OpenMP task for the first) without waiting for each other's node
 * count, and the tree is the same however they were shared out;
 * number_nodes() numbers it afterwards as the serial recursion would. */
static void build_node(builder *b, int node_index, int descendants, int begin, int end, int depth)
{
    bvh_node *node = &b->nodes[node_index];

    /* Find bounding box (and that of the centroids, which the splits use) */
    box3 box = box3_empty(), centroids = box3_empty();
    for (int i = begin; i < end; i++) {
        const build_triangle *t = &b->tris[i];
        box3_grow(&box, t->lo, t->hi);
        float c[3] = {centroid(t, 0), centroid(t, 1), centroid(t, 2)};
        box3_grow(&centroids, c, c);
    }
    node->box = box3_to_aabb(&box);
    if (depth == 0)
        b->root_area = box3_area(&box);

    /* Recursively split set of objects in two subsets */
    int axis = 0, mid = begin;
    bool split = b->split == BVH_SPLIT_SAH ? split_sah(b, begin, end, &box, &centroids, depth, &axis, &mid)
                                           : split_median(b, begin, end, &centroids, &axis, &mid);
    if (!split) {
        /* Store objects in each leaf node: they are tris[begin, end) */
        node->first = begin;
        node->count_axis = (uint32_t)(end - begin) << 2;
        return;
    }
    /* The two children side by side: the second child's index is implicit. */
    int first_child = descendants;
    node->first = first_child;
    node->count_axis = (uint32_t)axis;
    int first_descendants = first_child + 2, second_descendants = first_descendants + 2 * (mid - begin) - 2;
    /* Recompute the bounding box of the subsets: the first step of each child */
    if (end - begin >= BVH_TASK_MIN) {
#pragma omp task default(none) firstprivate(b, first_child, first_descendants, begin, mid, depth)
        build_node(b, first_child, first_descendants, begin, mid, depth + 1);
    } else {
        build_node(b, first_child, first_descendants, begin, mid, depth + 1);
    }
    build_node(b, first_child + 1, second_descendants, mid, end, depth + 1);
}

/* Copy the subtree at `from` of the build's sparse array into `to`,
 * numbered as the serial recursion numbers it: a node's two children get
 * the next two numbers when it is reached, then the first child's subtree
 * is numbered, then the second's. Counts the leaves and the depth. */
typedef struct {
    const bvh_node *from;
    bvh_node *to;
    int count, leaves, max_depth;
} numbering;

static void number_nodes(numbering *n, int from, int to, int depth)
{
    bvh_node node = n->from[from];
    if (depth > n->max_depth)
        n->max_depth = depth;
    if (bvh_node_is_leaf(&node)) {
        n->leaves++;
        if (n->to != NULL)
            n->to[to] = node;
        return;
    }
    int first = n->count;
    n->count += 2;
    if (n->to != NULL) {
        n->to[to] = node;
        n->to[to].first = first;
    }
    number_nodes(n, node.first, first, depth + 1);
    number_nodes(n, node.first + 1, first + 1, depth + 1);
}

/* ---- the node array ----------------------------------------------------------- */

/* A node's two children are read together (BVH_ORDER_DISTANCE tests both;
 * BVH_ORDER_AXIS_SIGN visits one and will come back for the other), so they
 * should arrive together: the array starts 32 bytes into a 64-byte cache
 * line, which puts the root alone in the second half of the first line and
 * every pair of children (the first child's index is always odd) in one
 * line of its own. */
enum { CACHE_LINE = 64 };

/* The array, not cleared: the build's sparse array is written by the
 * threads that build each subtree (the first touch of its pages shared out
 * with the work), and read only where a node was written. */
static bvh_node *nodes_reserve(int count, size_t *bytes_out)
{
    size_t bytes = ((size_t)count + 1) * sizeof(bvh_node);
    bytes = (bytes + CACHE_LINE - 1) / CACHE_LINE * CACHE_LINE; /* aligned_alloc wants a multiple */
    bvh_node *base = aligned_alloc(CACHE_LINE, bytes);
    if (base == NULL) {
        fprintf(stderr, "out of memory (asked for %zu bytes)\n", bytes);
        exit(1);
    }
    *bytes_out = bytes;
    return base + 1;
}

bvh_node *bvh_nodes_allocate(int count)
{
    size_t bytes;
    bvh_node *nodes = nodes_reserve(count, &bytes);
    memset(nodes - 1, 0, bytes);
    return nodes;
}

void bvh_nodes_free(bvh_node *nodes)
{
    if (nodes != NULL)
        free(nodes - 1);
}

/* ---- after the build -------------------------------------------------------- */

static bvh_triangle bvh_triangle_make(const triangle *t, triangle_test test)
{
    bvh_triangle b;
    b.p0 = t->p0;
    if (test == TRIANGLE_TEST_MOLLER_TRUMBORE) {
        /* E1 = P1 - P0, E2 = P2 - P0, exactly as triangle_intersect_barycentric()
         * computes them, so that the tests give the same t bit for bit. */
        b.e1 = vec3_sub(t->p1, t->p0);
        b.e2 = vec3_sub(t->p2, t->p0);
    } else if (triangle_is_degenerate(t)) {
        /* no ray may hit it (chapter 01): NaN fails the test's last comparison */
        b.p0 = b.p1 = b.p2 = vec3_splat(NAN);
    } else {
        b.p1 = t->p1;
        b.p2 = t->p2;
    }
    return b;
}

/* The leaves' triangles, in leaf order, in the form b's triangle test reads. */
static void bvh_triangles_fill(bvh *b)
{
#pragma omp parallel for schedule(static) if (b->triangle_count >= BVH_TASK_MIN)
    for (int i = 0; i < b->triangle_count; i++)
        b->triangles[i] = bvh_triangle_make(&b->base.set->triangles[b->triangle_index[i]], b->base.triangle_test);
}

bool bvh_use_triangle_test(accel *a, triangle_test test)
{
    a->triangle_test = test;
    bvh_triangles_fill((bvh *)a);
    return true;
}

static void bvh_fill_stats(bvh *b, const char *name, int leaves, int max_depth)
{
    b->base.stats.name = name;
    b->base.stats.bytes = sizeof *b + (size_t)b->node_count * sizeof *b->nodes +
                          (size_t)b->triangle_count * (sizeof *b->triangles + sizeof *b->triangle_index);
    b->base.stats.nodes = b->node_count;
    b->base.stats.leaves = leaves;
    b->base.stats.max_depth = max_depth;
    b->base.stats.references = b->triangle_count;
}

static bvh *bvh_alloc(const triangle_set *set)
{
    bvh *b = memory_allocate(1, sizeof *b);
    b->base.ops = &bvh_ops_axis_sign;
    b->base.set = set;
    b->order = BVH_ORDER_AXIS_SIGN;
    return b;
}

accel *bvh_build(const triangle_set *set, bvh_split split)
{
    bvh_sah_params sah = {BVH_SAH_TRAVERSAL_COST, 1, BVH_SAH_MAX_LEAF_SIZE, 0.0f, 0.0f};
    return bvh_build_with(set, split, &sah);
}

accel *bvh_build_max_leaf(const triangle_set *set, int max_leaf_size)
{
    bvh_sah_params sah = {BVH_SAH_TRAVERSAL_COST, 1, max_leaf_size > 0 ? max_leaf_size : 1, 0.0f, 0.0f};
    return bvh_build_with(set, BVH_SPLIT_SAH, &sah);
}

void bvh_tree_build(const triangle_set *set, bvh_split split, const bvh_sah_params *sah, bvh_tree *out)
{
    int n = set->count;
    *out = (bvh_tree){NULL, NULL, n};
    if (n == 0)
        return;
    /* Everything allocated once, up front: the working set, and the most
     * nodes a tree over n triangles can have (2 n - 1, every leaf holding
     * one triangle). */
    builder b = {0};
    b.split = split;
    b.sah = *sah;
    b.tris = memory_allocate((size_t)n, sizeof *b.tris);
    size_t bytes;
    b.nodes = nodes_reserve(2 * n - 1, &bytes);
#pragma omp parallel for schedule(static) if (n >= BVH_TASK_MIN)
    for (int i = 0; i < n; i++) {
        const aabb *box = &set->boxes[i];
        b.tris[i] = (build_triangle){{box->lo.x, box->lo.y, box->lo.z}, {box->hi.x, box->hi.y, box->hi.z}, i};
    }
    /* The root's subtree in slots 1 .. 2 n - 2, its halves as tasks of the
     * team's threads (one thread: the serial recursion). */
#pragma omp parallel if (n >= BVH_TASK_MIN)
#pragma omp single
    build_node(&b, 0, 1, 0, n, 0);

    out->nodes = b.nodes;
    out->triangle_index = memory_allocate((size_t)n, sizeof *out->triangle_index);
#pragma omp parallel for schedule(static) if (n >= BVH_TASK_MIN)
    for (int i = 0; i < n; i++)
        out->triangle_index[i] = b.tris[i].index;
    free(b.tris);
}

void bvh_tree_free(bvh_tree *tree)
{
    bvh_nodes_free(tree->nodes);
    free(tree->triangle_index);
    *tree = (bvh_tree){NULL, NULL, 0};
}

accel *bvh_build_with(const triangle_set *set, bvh_split split, const bvh_sah_params *sah)
{
    double start = timer_seconds();
    bvh *result = bvh_alloc(set);
    result->split = split;
    int n = set->count;
    result->triangle_count = n;
    if (n == 0) {
        bvh_fill_stats(result, split == BVH_SPLIT_SAH ? "bvh sah" : "bvh median", 0, 0);
        result->base.stats.build_seconds = timer_seconds() - start;
        return &result->base;
    }
    bvh_tree tree;
    bvh_tree_build(set, split, sah, &tree);

    /* Flatten: count the nodes, then number them in the serial order. */
    numbering count = {tree.nodes, NULL, 1, 0, 0};
    number_nodes(&count, 0, 0, 0);
    result->nodes = bvh_nodes_allocate(count.count);
    numbering number = {tree.nodes, result->nodes, 1, 0, 0};
    number_nodes(&number, 0, 0, 0);
    result->node_count = number.count;
    /* Copy the triangles in leaf order, as the triangle test reads them. */
    result->triangle_index = tree.triangle_index;
    tree.triangle_index = NULL;
    result->triangles = memory_allocate((size_t)n, sizeof *result->triangles);
    bvh_triangles_fill(result);
    bvh_tree_free(&tree);

    bvh_fill_stats(result, split == BVH_SPLIT_SAH ? "bvh sah" : "bvh median", number.leaves, number.max_depth);
    result->base.stats.build_seconds = timer_seconds() - start;
    return &result->base;
}

/* ---- a tree built by hand ---------------------------------------------------- */

/* Checks node n and below; counts leaves and depth. */
static bool check_node(const bvh_node *nodes, int node_count, int n, int depth, int triangle_count, int *leaves,
                       int *max_depth)
{
    if (depth >= BVH_STACK_SIZE)
        return false;
    if (depth > *max_depth)
        *max_depth = depth;
    const bvh_node *node = &nodes[n];
    if (bvh_node_is_leaf(node)) {
        (*leaves)++;
        return node->first >= 0 && node->first + bvh_node_triangles(node) <= triangle_count;
    }
    if (node->first <= n || node->first + 1 >= node_count || bvh_node_axis(node) > 2)
        return false;
    return check_node(nodes, node_count, node->first, depth + 1, triangle_count, leaves, max_depth) &&
           check_node(nodes, node_count, node->first + 1, depth + 1, triangle_count, leaves, max_depth);
}

accel *bvh_from_nodes(const triangle_set *set, const bvh_node *nodes, int node_count, const int *triangle_index,
                      int triangle_count)
{
    int leaves = 0, max_depth = 0;
    if (node_count < 1 || triangle_count < 0 ||
        !check_node(nodes, node_count, 0, 0, triangle_count, &leaves, &max_depth))
        return NULL;
    for (int i = 0; i < triangle_count; i++)
        if (triangle_index[i] < 0 || triangle_index[i] >= set->count)
            return NULL;
    bvh *b = bvh_alloc(set);
    b->nodes = bvh_nodes_allocate(node_count);
    memcpy(b->nodes, nodes, (size_t)node_count * sizeof *nodes);
    b->node_count = node_count;
    b->triangle_count = triangle_count;
    b->triangles = memory_allocate((size_t)(triangle_count > 0 ? triangle_count : 1), sizeof *b->triangles);
    b->triangle_index = memory_allocate((size_t)(triangle_count > 0 ? triangle_count : 1), sizeof *b->triangle_index);
    for (int i = 0; i < triangle_count; i++)
        b->triangle_index[i] = triangle_index[i];
    bvh_triangles_fill(b);
    bvh_fill_stats(b, "bvh by hand", leaves, max_depth);
    return &b->base;
}

/* ---- the tree's SAH cost ------------------------------------------------------ */

double bvh_sah_cost(const bvh *b)
{
    if (b->node_count == 0)
        return 0.0;
    double root_area = aabb_surface_area(b->nodes[0].box);
    if (!(root_area > 0.0))
        return 0.0;
    double cost = 0.0;
    for (int i = 0; i < b->node_count; i++) {
        const bvh_node *node = &b->nodes[i];
        double p = aabb_surface_area(node->box) / root_area; /* chance a ray through the root hits it */
        if (bvh_node_is_leaf(node))
            cost += p * (double)BVH_SAH_INTERSECTION_COST * bvh_node_triangles(node);
        else
            cost += p * (double)BVH_SAH_TRAVERSAL_COST;
    }
    return cost;
}
