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
/* The triangle test's t is not exact either, and its error grows as
 * 1/sin(angle) as the ray grazes the triangle's plane. After a hit at t the
 * walk must therefore go on into every cell the exact ray enters no later
 * than the exact hit t*, which lies anywhere in [t - e, t + e] for the
 * hit's error bound e: a triangle there (a neighbour sharing the vertex the
 * ray is aimed at, say) may report a t below the hit found, and brute
 * force, which takes the least t of all, answers that one. A fixed relative
 * margin covers hits down to some angle only (2^-16 reached about half a
 * degree). The bound comes from the test's own numbers, recomputed after a
 * hit (rare beside the tests that miss), in the way pbrt-v4 bounds its
 * triangle t (Pharr, Jakob, Humphreys, section 6.8): each float operation
 * is the exact one times (1 + d), |d| <= u = 2^-24, and a chain of n of
 * them stays within gamma(n) = n u / (1 - n u).
 *
 * The watertight test's t = num / den, num = (P0 - O) . N and den = D . N,
 * N = E1 x E2 (watertight_plane_t()). Each edge is rounded once, each
 * component of N is a difference of two products of those: N_x is within
 * gamma(4) a_x of the exact one, a_x = |E1_y E2_z| + |E1_z E2_y| (likewise
 * y, z). P0 - O is rounded once; each dot product adds a product and two
 * sums. So num is within E_num = gamma(8) sum_i |P0_i - O_i| a_i of the
 * exact one, den within E_den = gamma(8) sum_i |D_i| a_i (D is exact: the
 * ray is the one given). Then
 *   |num / den - num* / den*| <= (E_num + |t| E_den) / (|den| - E_den),
 * plus one rounding of the division. When |den| <= E_den the sign of den,
 * and so t, is not known at all: the bound is infinite (the walk goes on to
 * the end; such a ray lies in the plane to within rounding). Moller-
 * Trumbore, t = ((O - P0) x E1) . E2 / ((D x E2) . E1), is bounded the
 * same way with its own products (gamma(9) for its numerator, one rounding
 * more). The constant taken is gamma(12): the bound is itself computed in
 * float, and its dozen roundings make it smaller than the exact bound by a
 * factor 1 - gamma(12) at worst, which gamma(12) / gamma(9) covers many
 * times over. The division's own rounding (two for Moller-Trumbore) is the
 * last term, within gamma(12) |t|. Checked against measured errors in
 * tests/test_ch05.c (the worst at 0.11 of the bound). */
static const float T_ERROR_GAMMA = 12.0f * 0x1.0p-24f / (1.0f - 12.0f * 0x1.0p-24f);

float kdtree_hit_t_error(triangle_test test, const triangle *tri, const ray *r, float t)
{
    const float *p0 = &tri->p0.x, *p1 = &tri->p1.x, *p2 = &tri->p2.x;
    const float o[3] = {r->origin.x, r->origin.y, r->origin.z};
    const float d[3] = {r->direction.x, r->direction.y, r->direction.z};
    float e1[3], e2[3], s[3];
    for (int k = 0; k < 3; k++) {
        e1[k] = p1[k] - p0[k];
        e2[k] = p2[k] - p0[k];
        s[k] = p0[k] - o[k];
    }
    float den = 0.0f, e_num = 0.0f, e_den = 0.0f;
    for (int k = 0; k < 3; k++) {
        int j = (k + 1) % 3, l = (k + 2) % 3;
        if (test == TRIANGLE_TEST_WATERTIGHT) {
            /* N_k = E1_j E2_l - E1_l E2_j, den = D . N in the test's order */
            float n = e1[j] * e2[l] - e1[l] * e2[j], a = fabsf(e1[j] * e2[l]) + fabsf(e1[l] * e2[j]);
            den += d[k] * n;
            e_num += fabsf(s[k]) * a;
            e_den += fabsf(d[k]) * a;
        } else {
            /* den = (D x E2) . E1; num = ((O - P0) x E1) . E2, whose
             * k-th product is (s_j E1_l - s_l E1_j) E2_k up to sign */
            float q = d[j] * e2[l] - d[l] * e2[j], b = fabsf(d[j] * e2[l]) + fabsf(d[l] * e2[j]);
            float c = fabsf(s[j] * e1[l]) + fabsf(s[l] * e1[j]);
            den += q * e1[k];
            e_den += b * fabsf(e1[k]);
            e_num += c * fabsf(e2[k]);
        }
    }
    e_num *= T_ERROR_GAMMA;
    e_den *= T_ERROR_GAMMA;
    float margin = fabsf(den) - e_den;
    if (!(margin > 0.0f))
        return INFINITY;
    return (e_num + fabsf(t) * e_den) / margin + fabsf(t) * T_ERROR_GAMMA;
}

/* Where the walk may stop after a hit at t on tri: the first cell that
 * starts beyond this is entered by the exact ray after t + e >= t*. Every
 * cell's t_enter is a t_split (or the root box's entry), within gamma(3)
 * of its exact value; so one beyond (t + e)(1 + 2 gamma(3)), which is
 * SPLIT_SLACK again (one gamma(3) for t_enter, the rest for rounding this
 * sum and product), begins beyond t* exactly, and holds no triangle the
 * exact ray meets before the hit. With fixed_margin > 0, the rule before:
 * t (1 + fixed_margin), kept for the twin of the test that shows it fail
 * (kd_tree.fixed_hit_margin). */
static inline float kd_stop_after(triangle_test test, const triangle *tri, const ray *r, float t, float fixed_margin)
{
    if (fixed_margin > 0.0f)
        return t + fabsf(t) * fixed_margin;
    float upper = t + kdtree_hit_t_error(test, tri, r, t);
    return upper + fabsf(upper) * SPLIT_SLACK;
}

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
    /* The walk goes on into cells that start no later than this: the
     * ray's own t_max (exact) until a hit, then the hit's t plus its error
     * bound (see kd_stop_after()). */
    float t_stop = r->t_max + fabsf(r->t_max) * SPLIT_SLACK;
    const float fixed_margin = tree->fixed_hit_margin;
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
            int best_before = best;
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
            if (best != best_before) /* a closer hit in this leaf */
                t_stop = kd_stop_after(test, &triangles[best], r, r->t_max, fixed_margin);

            /* Next cell from the stack; stop when it starts beyond the
             * closest hit so far. That is the lecture's "stop at the first
             * cell holding a hit inside it (t <= the cell's t_exit)", made
             * at the next cell's entry t_split, which is where the current
             * cell ends, and with the hit's error bound (kd_stop_after()).
             * Stack entries lie front to back, so the first one beyond ends
             * the walk; only a ray lying in a split plane pushes a sibling
             * that is not behind the current cell, and until that one has
             * been popped the walk must go on. */
            bool found = false;
            while (top > 0) {
                kd_stack_entry e = stack[--top];
                in_plane_pending -= (int)e.in_plane;
                if (e.t_enter > t_stop) {
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
