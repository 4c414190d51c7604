/* kdtree_trace.c -- walking a ray through the kd-tree, front to back.
 *
 * At an interior node the ray's interval [t_enter, t_exit] inside the node's
 * box is cut by the split plane at
 *
 *   t_split = (split - o_k) / d_k       (computed as (split - o_k) * (1/d_k))
 *
 * into a part in the near child, [t_enter, t_split], and a part in the far
 * child, [t_split, t_exit]; the near child is the one the ray is in before it
 * crosses the plane (below if d_k > 0). If t_split > t_exit the ray never
 * reaches the far child; if t_split < t_enter it has already left the near
 * one. Otherwise: visit the near child now and push the far child with its
 * interval on a small stack. Cells therefore come in the order the ray meets
 * them, and the first cell whose triangles give a hit *inside that cell*
 * (t <= the cell's t_exit) holds the closest hit: every later cell lies
 * beyond. A hit beyond the cell's t_exit does not end the walk: it belongs to
 * a triangle that straddles into later cells, and a later cell may hold
 * something closer.
 */
#include "05-kd-tree/kdtree.h"

#include <math.h>
#include <stdlib.h>

/* Every t_split = (split - o) * (1/d) is the exact value times (1 + e) with
 * |e| <= gamma(3) = 3u / (1 - 3u), u = 2^-24 (three roundings: the
 * subtraction, the reciprocal, the product; Ize 2013, pbrt's Bounds3). The
 * interval bounds t_enter, t_exit are such values too (or the root box's,
 * whose t_exit aabb_slab_test already grows). So when deciding "does the
 * ray reach this child", comparing t_enter <= t_split could say no by
 * rounding when the exact answer is yes (a ray through the corner where
 * cells meet, aimed at a shared vertex), and the triangle there would be
 * lost. Comparing instead against bounds widened by 2 gamma(3) relative
 * visits every child the exact ray touches (and, rarely, one it misses by a
 * few ulps, which costs a node and nothing else). */
static const float SPLIT_SLACK = 2.0f * (3.0f * 0x1.0p-24f) / (1.0f - 3.0f * 0x1.0p-24f);
/* The triangle test's t is not exact, and the error grows as the ray grazes
 * the triangle: measured for Moller-Trumbore over random triangles, about 2.4 ulps / sin(angle)
 * relative (16 ulps at 10 degrees, 141 at 1 degree, 592 at 0.3 degree). A
 * triangle in the next cell, which the ray reaches only at or after the
 * hit found, can so report a t a little *below* it; brute force, which takes
 * the least t of all, would then answer that triangle. The walk therefore
 * goes on into cells that start within this margin beyond the closest hit:
 * 2^-16 = 256 ulps relative, enough for hits down to about half a degree
 * from grazing. It costs a cell only when a hit lies that close to a cell's
 * far side, which is common only for rays aimed exactly at vertices (split
 * planes go through vertices). */
static const float HIT_MARGIN = 0x1.0p-16f;


/* Front to back at an interior node: the ray's interval [t_enter, t_exit]
 * in the node, cut by the split plane at t_split into [t_enter, t_split] in
 * the near child and [t_split, t_exit] in the far child; whether the ray
 * reaches each child, and those two intervals. */
typedef struct {
    bool near, far;
    float near_exit, far_enter;
} kd_children;

static inline kd_children kd_front_to_back(float t_split, float t_enter, float t_exit)
{
    /* exercise: kd_front_to_back */
    kd_children c;
    /* The near child unless the plane comes before t_enter, the far one
     * unless it comes after t_exit, each with SPLIT_SLACK; written as "not
     * before" and "not after" so that NaN (a ray in the plane) visits both. */
    c.near = !(t_split < t_enter - fabsf(t_enter) * SPLIT_SLACK);
    c.far = !(t_split > t_exit + fabsf(t_exit) * SPLIT_SLACK);
    c.near_exit = t_split < t_exit ? t_split : t_exit;
    c.far_enter = t_split > t_enter ? t_split : t_enter;
    return c;
    /* end of exercise kd_front_to_back */
}

typedef struct {
    uint32_t node;
    uint32_t in_plane; /* pushed by a ray lying in the split plane: see below */
    float t_enter, t_exit;
} kd_stack_entry;

/* One walk for both queries: closest (stop in the first cell holding a hit
 * in that cell) or any (stop at the first hit at all). Returns the triangle
 * index or -1; *r ends with t_max = the hit's t. */
static inline int kdtree_walk(const kd_tree *tree, ray *ray_io, bool any, triangle_test test, float *b1_out,
                              float *b2_out, ray_counters *counters)
{
    /* A local copy: the compiler keeps it in registers through the loops
     * (through the pointer it would reload it after every store). */
    ray r_local = *ray_io;
    ray *r = &r_local;
    float best_b1 = 0.0f, best_b2 = 0.0f;
    const kd_node *nodes = tree->nodes;
    const triangle *triangles = tree->base.set->triangles;
    /* What slab_ray_make() computes, once per ray: the origin and 1/d. */
    slab_ray sr = {r->origin, vec3_make(1.0f / r->direction.x, 1.0f / r->direction.y, 1.0f / r->direction.z)};
    /* and the watertight triangle test's part for the ray (chapter 01): the
     * leaves run chapter 01's test inline (shapes.h), so the same t and
     * barycentrics, bit for bit, as brute force gets */
    const watertight_ray wr = watertight_ray_make(r);
    uint64_t nodes_visited = 1, triangles_tested = 0;
    float t_enter, t_exit;
    int best = -1;
    if (aabb_slab_test(&tree->bounds, &sr, r->t_min, r->t_max, &t_enter, &t_exit)) {
        const float origin[3] = {sr.origin.x, sr.origin.y, sr.origin.z};
        const float inverse[3] = {sr.inverse_direction.x, sr.inverse_direction.y, sr.inverse_direction.z};
        /* All ones on the axes the ray goes down (d_k < 0, including -0,
         * whose 1/d_k is -inf), for picking the near child without a branch. */
        const uint32_t going_down[3] = {signbit(inverse[0]) ? ~0u : 0u, signbit(inverse[1]) ? ~0u : 0u,
                                        signbit(inverse[2]) ? ~0u : 0u};
        kd_stack_entry stack[KD_MAX_DEPTH];
        int top = 0, in_plane_pending = 0;
        uint32_t index = 0;
        for (;;) {
            const kd_node *node = &nodes[index];
            /* Descend to a leaf, near child first; push the far child with
             * its interval [t_split, t_exit]. */
            while (!kd_node_is_leaf(node)) {
                nodes_visited++;
                int axis = kd_node_axis(node);
                float t_split = (node->split - origin[axis]) * inverse[axis];
                /* The near child is below if the ray goes up the axis, above
                 * if it goes down. */
                uint32_t below = index + 1, above = kd_node_above_child(node);
                uint32_t swap = (below ^ above) & going_down[axis];
                uint32_t near = below ^ swap, far = above ^ swap;
                /* Does the ray reach each child? The near one unless the
                 * plane comes before t_enter, the far one unless it comes
                 * after t_exit (each with SPLIT_SLACK). A ray parallel to
                 * the plane but off it gets t_split = +inf or -inf
                 * (nonzero times 1/0): +inf keeps it in the near child,
                 * -inf (d_k = -0 below the plane: near and far swapped by
                 * the sign of the zero) in the far one.
                 *
                 * A ray lying in the plane (d_k = 0 and o_k = split) gets
                 * 0 * inf = NaN. It runs along the plane through both
                 * children at once, over its whole interval. Every
                 * comparison with NaN is false, so written as "not before"
                 * and "not after", both tests say yes, and the two
                 * intervals below stay [t_enter, t_exit]. Neither child is
                 * in front of the other then: a hit in the first does not
                 * mean the second holds nothing closer, so the stop test
                 * waits until that one has been popped (in_plane_pending). */
                kd_children reached = kd_front_to_back(t_split, t_enter, t_exit);
                bool visit_near = reached.near, visit_far = reached.far;
                bool in_plane = isnan(t_split);
                float near_exit = reached.near_exit, far_enter = reached.far_enter;
                /* Visit the near child now, push the far child with its
                 * interval [t_split, t_exit].
                 *
                 * Written with branches, not as a branch-free select: the
                 * next node's address then does not wait for t_split. The
                 * processor guesses the branch and loads the next node
                 * while t_split is still being computed; with a select
                 * every step waits for the load, the subtraction, the
                 * product and the comparisons of the step before. Guesses
                 * are good for coherent rays (neighbours take the same
                 * way down) and poor for incoherent ones; measured on the
                 * tori field against the BVH in the same run (the chapter
                 * text has the figures), branches are about 20% faster on
                 * coherent rays and 5-10% slower on incoherent ones. */
                if (visit_near) {
                    if (visit_far) {
                        stack[top++] = (kd_stack_entry){far, in_plane, far_enter, t_exit};
                        /* Ask for the far child's cache line now (GCC and
                         * Clang): it is usually visited next, after this
                         * subtree, and on big trees every such visit is a
                         * cache miss otherwise (measured: about 5% faster
                         * on incoherent rays). */
                        __builtin_prefetch(&nodes[far]);
                        in_plane_pending += in_plane;
                    }
                    index = near;
                    t_exit = near_exit;
                } else {
                    index = far;
                    t_enter = far_enter;
                }
                node = &nodes[index];
            }

            /* Test the leaf's triangles (with t_max = the closest hit so
             * far, so only closer hits count). */
            uint32_t count = kd_node_triangle_count(node);
            const uint32_t *refs = tree->references + node->first_reference;
            triangles_tested += count;
            for (uint32_t i = 0; i < count; i++) {
                float t, b1, b2;
                if (triangle_intersect_with(test, &wr, &triangles[refs[i]], r, r->t_max, &t, &b1, &b2)) {
                    best = (int)refs[i];
                    r->t_max = t;
                    best_b1 = b1;
                    best_b2 = b2;
                    if (any)
                        goto done;
                }
            }

            /* Next cell from the stack; stop when it starts beyond the
             * closest hit so far. That is the lecture's "stop at the first
             * cell holding a hit inside it (t <= the cell's t_exit)", made
             * at the next cell's entry t_split, which is where the current
             * cell ends, and with HIT_MARGIN for the rounding of t (above).
             * Stack entries lie front to back, so the first one beyond ends
             * the walk; only a ray lying in a split plane pushes a sibling
             * that is not behind the current cell, and until that one has
             * been popped the walk must go on. */
            bool found = false;
            while (top > 0) {
                kd_stack_entry e = stack[--top];
                in_plane_pending -= (int)e.in_plane;
                if (e.t_enter > r->t_max + fabsf(r->t_max) * HIT_MARGIN) {
                    if (in_plane_pending == 0)
                        break;
                    continue;
                }
                index = e.node;
                t_enter = e.t_enter;
                t_exit = e.t_exit;
                found = true;
                break;
            }
            if (!found)
                break;
        }
    }
done:
    ray_io->t_max = r->t_max;
    *b1_out = best_b1;
    *b2_out = best_b2;
    counters->box_tests += nodes_visited;
    counters->primitive_tests += triangles_tested;
    return best;
}

/* The walk compiled once per triangle test (accel.h, ACCEL_WALK). */
static bool kdtree_closest_hit(const accel *a, ray r, hit_record *hit, ray_counters *counters)
{
    float b1 = 0.0f, b2 = 0.0f;
    int best = ACCEL_WALK(a, kdtree_walk, (const kd_tree *)a, &r, false, &b1, &b2, counters);
    return accel_walk_hit(a, best, r, b1, b2, hit);
}

static bool kdtree_any_hit(const accel *a, ray r, ray_counters *counters)
{
    float b1, b2;
    return ACCEL_WALK(a, kdtree_walk, (const kd_tree *)a, &r, true, &b1, &b2, counters) >= 0;
}

static void kdtree_destroy(accel *a)
{
    kd_tree *tree = (kd_tree *)a;
    free(tree->nodes);
    free(tree->references);
    free(tree);
}

const accel_ops kdtree_ops = {kdtree_closest_hit, kdtree_any_hit, kdtree_destroy, accel_use_triangle_test_of_set};
