/* small_bvh.c -- a BVH for scenes of a few hundred triangles, such as the
 * Cornell box: the surface area heuristic evaluated at every possible split
 * (a full sweep, not bins), with the cost of a box test and a triangle test
 * measured for the path tracer's rays. The tree is handed to chapter 06's
 * traversal through bvh_from_nodes(). See small_bvh.h. */
#include "small_bvh.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>

#include "06-bvh/bvh.h"
#include "memory.h"

/* The SAH's cost of visiting a node, relative to testing one triangle (1).
 * Chapter 06 uses 2, which on the Cornell box keeps eight of the room's
 * triangles (floor, back and side walls: each of their boxes is as large as
 * the room in two axes) in one leaf that every ray inside the room tests.
 * With 1 the walls go to leaves of their own; ray inside the room meets
 * only the boxes of the walls it can hit (README: "Speed"). */
static const float SMALL_BVH_TRAVERSAL_COST = 1.0f;

typedef struct {
    aabb box;
    vec3 centroid;
    float key; /* the centroid along the axis being sorted */
    int index; /* in the triangle_set */
} item;

typedef struct {
    item *items;
    aabb *suffix; /* scratch: box of items[i .. end) during a sweep */
    bvh_node *nodes;
    int node_count;
    int max_depth;
} small_builder;

static float area(aabb b) { return (float)aabb_surface_area(b); }

static int compare_keys(const void *a, const void *b)
{
    const item *p = a, *q = b;
    /* NaN (a triangle with a NaN corner) sorts first, so the order stays
     * a total order, which qsort needs */
    bool p_nan = isnan(p->key), q_nan = isnan(q->key);
    if (p_nan != q_nan)
        return p_nan ? -1 : 1;
    if (!p_nan && p->key != q->key)
        return p->key < q->key ? -1 : 1;
    return p->index - q->index; /* ties by index: the same tree from every qsort */
}

static void sort_along(item *items, int count, int axis)
{
    for (int i = 0; i < count; i++)
        items[i].key = vec3_axis(items[i].centroid, axis);
    qsort(items, (size_t)count, sizeof *items, compare_keys);
}

/* The split of items[begin, end) with the lowest SAH cost: the axis and the
 * number of items that go left after sorting along it. False if a leaf is
 * cheaper. */
static bool best_split(small_builder *b, int begin, int end, aabb box, int *axis_out, int *left_count_out)
{
    int count = end - begin;
    float parent_area = area(box);
    float best = (float)count; /* a leaf: every ray that reaches it tests all */
    bool found = false;
    for (int axis = 0; axis < 3; axis++) {
        sort_along(b->items + begin, count, axis);
        /* Right to left: the boxes of every suffix; then left to right. */
        aabb grow = aabb_empty();
        for (int i = end - 1; i > begin; i--) {
            grow = aabb_union(grow, b->items[i].box);
            b->suffix[i] = grow;
        }
        grow = aabb_empty();
        for (int i = begin + 1; i < end; i++) {
            grow = aabb_union(grow, b->items[i - 1].box);
            int left = i - begin, right = end - i;
            float cost = SMALL_BVH_TRAVERSAL_COST +
                         (area(grow) * (float)left + area(b->suffix[i]) * (float)right) / parent_area;
            if (parent_area > 0.0f && cost < best) {
                best = cost;
                *axis_out = axis;
                *left_count_out = left;
                found = true;
            }
        }
    }
    return found;
}

static void build(small_builder *b, int node_index, int begin, int end, int depth)
{
    aabb box = aabb_empty();
    for (int i = begin; i < end; i++)
        box = aabb_union(box, b->items[i].box);
    bvh_node *node = &b->nodes[node_index];
    node->box = box;
    if (depth > b->max_depth)
        b->max_depth = depth;
    int axis = 0, left = 0;
    /* Below BVH_STACK_SIZE - 1 levels, always; a sweep over n items can
     * never be deeper than n anyway, and small scenes are small. */
    if (end - begin == 1 || depth >= BVH_STACK_SIZE - 1 || !best_split(b, begin, end, box, &axis, &left)) {
        node->first = begin;
        node->count_axis = (uint32_t)(end - begin) << 2;
        return;
    }
    sort_along(b->items + begin, end - begin, axis);
    int first_child = b->node_count;
    b->node_count += 2;
    node->first = first_child;
    node->count_axis = (uint32_t)axis; /* the first child has the smaller centroids */
    build(b, first_child, begin, begin + left, depth + 1);
    build(b, first_child + 1, begin + left, end, depth + 1);
}

accel *small_bvh_build(const triangle_set *set)
{
    int n = set->count;
    if (n == 0)
        return bvh_build(set, BVH_SPLIT_SAH);
    small_builder b = {0};
    b.items = memory_allocate((size_t)n, sizeof *b.items);
    b.suffix = memory_allocate((size_t)n, sizeof *b.suffix);
    b.nodes = memory_allocate((size_t)(2 * n - 1), sizeof *b.nodes);
    for (int i = 0; i < n; i++) {
        b.items[i].box = set->boxes[i];
        b.items[i].centroid = vec3_scale(vec3_add(set->boxes[i].lo, set->boxes[i].hi), 0.5f);
        b.items[i].index = i;
    }
    b.node_count = 1;
    build(&b, 0, 0, n, 0);
    int *order = memory_allocate((size_t)n, sizeof *order);
    for (int i = 0; i < n; i++)
        order[i] = b.items[i].index;
    accel *a = bvh_from_nodes(set, b.nodes, b.node_count, order, n);
    free(order);
    free(b.items);
    free(b.suffix);
    free(b.nodes);
    return a;
}
