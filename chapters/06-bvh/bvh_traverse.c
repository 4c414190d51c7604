/* bvh_traverse.c -- a ray through a BVH: test a node's box; if the ray hits
 * it, test the triangles of a leaf or visit both children of an interior
 * node, the nearer first, and skip whatever begins beyond the closest hit
 * found so far. */
#include <stdlib.h>

#include "06-bvh/bvh.h"
#include "06-bvh/bvh_internal.h"

/* The triangle tests and the leaf loop are inlined into each traversal
 * whatever the compiler's size heuristics say: GCC 12 left
 * bvh_triangle_test() out of line, a call per triangle. */
#if defined(__GNUC__)
#define BVH_INLINE static inline __attribute__((always_inline))
#else
#define BVH_INLINE static inline
#endif

/* Moller-Trumbore with the edges stored (bvh_triangle), for a BVH told to
 * use it (accel_use_triangle_test): the lecture's
 *     [t, b1, b2] = 1 / (S1 . E1) [S2 . E2, S1 . S, S2 . D]
 * with E1 = P1 - P0, E2 = P2 - P0, S = O - P0, S1 = D x E2, S2 = S x E1.
 * Every product is computed in the same order as in
 * triangle_intersect_barycentric() (chapter 01), so the result is the same
 * float, bit for bit; only the two subtractions for E1 and E2 moved to the
 * build. The same rules too: only an exactly zero determinant is refused,
 * and the comparisons are false for NaN. */
BVH_INLINE bool bvh_triangle_intersect(const bvh_triangle *tri, const ray *r, float t_max, float *t_out,
                                          float *b1_out, float *b2_out)
{
    vec3 s1 = vec3_cross(r->direction, tri->e2);
    float determinant = vec3_dot(s1, tri->e1);
    if (determinant == 0.0f)
        return false;
    float inverse = 1.0f / determinant;
    vec3 s = vec3_sub(r->origin, tri->p0);
    float b1 = vec3_dot(s1, s) * inverse;
    if (!(b1 >= 0.0f && b1 <= 1.0f))
        return false;
    vec3 s2 = vec3_cross(s, tri->e1);
    float b2 = vec3_dot(s2, r->direction) * inverse;
    if (!(b2 >= 0.0f && b1 + b2 <= 1.0f))
        return false;
    float t = vec3_dot(s2, tri->e2) * inverse;
    if (!(t > r->t_min && t < t_max))
        return false;
    *t_out = t;
    *b1_out = b1;
    *b2_out = b2;
    return true;
}

/* The watertight test (chapter 01's, what the BVH runs unless told
 * otherwise) on the stored corners, or Moller-Trumbore on the stored edges:
 * with `test` a constant, each traversal below is compiled for one. */
BVH_INLINE bool bvh_triangle_test(triangle_test test, const bvh_triangle *tri, const ray *r,
                                     const watertight_ray *wr, float t_max, float *t, float *b1, float *b2)
{
    if (test == TRIANGLE_TEST_WATERTIGHT)
        return watertight_intersect(wr, &tri->p0.x, &tri->p1.x, &tri->p2.x, t_max, t, b1, b2);
    return bvh_triangle_intersect(tri, r, t_max, t, b1, b2);
}

/* Skipping a box that begins beyond the closest hit so far is only safe if
 * no triangle inside can be reported closer than the box begins. The box
 * test is exact to a few ulps, but a triangle test's t is not: a triangle
 * whose exact hit lies in a box that begins just beyond the closest hit may
 * still come out of the test in front of it, and brute force, which tests
 * every triangle, then returns it. Rays aimed at a vertex shared by several
 * triangles make such near-ties on purpose, and in a BVH every vertex lies
 * on its leaf boxes' faces. Measured on the differential test's 475 000
 * hits (ch06 README): Moller-Trumbore's t is off from the exact t by up to
 * 6.2e-4 relative (at grazing angles; 37 hits above 2^-15). So boxes are
 * culled against the closest hit times 1 + 2^-9 (1.95e-3, three times the
 * worst seen); the triangle tests still use the closest hit itself, so the
 * answer is exactly brute force's whenever the slack changes nothing.
 * (BVH_CULL_SLACK is in bvh_internal.h: the 4-wide BVH culls with it too.) */

/* What a traversal found: the closest triangle so far (in leaf order). */
typedef struct {
    int triangle; /* -1: none */
    float t, b1, b2;
} bvh_found;

/* Test the triangles of a leaf against (t_min, found->t); with
 * stop_at_first, return true at the first hit. */
BVH_INLINE bool test_leaf(const bvh *b, const bvh_node *node, const ray *r, const watertight_ray *wr,
                             triangle_test test, bvh_found *found, bool stop_at_first, uint64_t *primitive_tests)
{
    int first = node->first, end = first + bvh_node_triangles(node);
    for (int i = first; i < end; i++) {
        float t, b1, b2;
        if (bvh_triangle_test(test, &b->triangles[i], r, wr, found->t, &t, &b1, &b2)) {
            *found = (bvh_found){i, t, b1, b2};
            if (stop_at_first) {
                *primitive_tests += (uint64_t)(i + 1 - first);
                return true;
            }
        }
    }
    *primitive_tests += (uint64_t)(end - first);
    return false;
}

/* ---- near child first by the sign of the direction on the split axis ------- */

/* The box of every node popped is tested against [t_min, closest hit], so a
 * far child that begins beyond the closest hit fails its box test.
 * It starts as traverse_distance() does (the ray prepared, the stack), and
 * stays whole: each order is read as one function on the chapter's page,
 * and `stop_at_first` makes each one function for closest and any hit. */
static inline bvh_found traverse_axis_sign(const bvh *b, const ray *r, bool stop_at_first, triangle_test test,
                                           ray_counters *counters)
{
    bvh_found found = {-1, r->t_max, 0.0f, 0.0f};
    if (b->node_count == 0)
        return found;
    bvh_ray br = bvh_ray_make(r);
    watertight_ray wr = watertight_ray_make(r);
    /* Along an axis where d is negative, the ray meets the upper child (the
     * second: larger centroids) first. */
    const int negative[3] = {br.near_x != 0, br.near_y != 1, br.near_z != 2};
    int stack[BVH_STACK_SIZE];
    int top = 0, current = 0;
    uint64_t box_tests = 0, primitive_tests = 0;
    for (;;) {
        const bvh_node *node = &b->nodes[current];
        float t_enter;
        box_tests++;
        if (bvh_slab_test(node, &br, r->t_min, found.t * BVH_CULL_SLACK, &t_enter)) {
            if (!bvh_node_is_leaf(node)) {
                /* Interior: visit the near child now, the far one later. */
                int second_first = negative[bvh_node_axis(node)];
                stack[top++] = node->first + 1 - second_first; /* far */
                current = node->first + second_first;          /* near */
                continue;
            }
            if (test_leaf(b, node, r, &wr, test, &found, stop_at_first, &primitive_tests))
                break;
        }
        if (top == 0)
            break;
        current = stack[--top];
    }
    counters->box_tests += box_tests;
    counters->primitive_tests += primitive_tests;
    return found;
}

/* ---- near child first by t_enter, far child skipped beyond the closest hit ---- */

/* Both children's boxes are tested at their parent; the far child goes on
 * the stack with its t_enter, and when it comes off, it is skipped without
 * another box test if a hit closer than t_enter was found meanwhile. (Its
 * start is traverse_axis_sign()'s, kept so that each reads whole.) */
static inline bvh_found traverse_distance(const bvh *b, const ray *r, bool stop_at_first, triangle_test test,
                                          ray_counters *counters)
{
    bvh_found found = {-1, r->t_max, 0.0f, 0.0f};
    if (b->node_count == 0)
        return found;
    bvh_ray br = bvh_ray_make(r);
    watertight_ray wr = watertight_ray_make(r);
    struct {
        int node;
        float t_enter;
    } stack[BVH_STACK_SIZE];
    int top = 0, current = 0;
    uint64_t box_tests = 1, primitive_tests = 0;
    float t_enter;
    if (bvh_slab_test(&b->nodes[0], &br, r->t_min, found.t * BVH_CULL_SLACK, &t_enter)) {
        for (;;) {
            const bvh_node *node = &b->nodes[current];
            if (!bvh_node_is_leaf(node)) {
                /* The two children share one cache line (bvh_build.c). */
                const bvh_node *pair = &b->nodes[node->first];
                float t0, t1;
                float cull = found.t * BVH_CULL_SLACK;
                bool hit0 = bvh_slab_test(&pair[0], &br, r->t_min, cull, &t0);
                bool hit1 = bvh_slab_test(&pair[1], &br, r->t_min, cull, &t1);
                box_tests += 2;
                if (hit0 && hit1) {
                    /* Both: the nearer now, the farther later. */
                    bool second_first = t1 < t0;
                    stack[top].node = node->first + !second_first;
                    stack[top].t_enter = second_first ? t0 : t1;
                    top++;
                    current = node->first + second_first;
                    continue;
                }
                if (hit0 || hit1) {
                    current = node->first + hit1;
                    continue;
                }
            } else if (test_leaf(b, node, r, &wr, test, &found, stop_at_first, &primitive_tests)) {
                break;
            }
            /* Next from the stack, skipping nodes that begin beyond the
             * closest hit (the box test would fail for them now). */
            while (top > 0 && stack[top - 1].t_enter > found.t * BVH_CULL_SLACK)
                top--;
            if (top == 0)
                break;
            current = stack[--top].node;
        }
    }
    counters->box_tests += box_tests;
    counters->primitive_tests += primitive_tests;
    return found;
}

/* ---- the lecture's recursion ---------------------------------------------------
 * GAMES101 lecture 14's pseudocode, line for line:
 *
 *   Intersect(Ray ray, BVH node) {
 *       if (ray misses node.bbox) return;
 *       if (node is a leaf node)
 *           test intersection with all objs;
 *           return closest intersection;
 *       hit1 = Intersect(ray, node.child1);
 *       hit2 = Intersect(ray, node.child2);
 *       return the closer of hit1, hit2;
 *   }
 *
 * with chapter 03's slab test and chapter 01's triangle test (the
 * watertight one, as every structure runs, or the one it was told to use:
 * accel_use_triangle_test). Every box and every triangle is tested over the whole ray
 * [t_min, t_max]; a hit found in one child changes nothing in the other. So
 * it visits every node whose parent's box the ray crosses, where the
 * iterative traversals above skip a box that begins beyond the closest hit
 * found so far (test_recursive_traversal_visits_at_least_as_many_nodes). */

/* "The closer of hit1, hit2": the smaller t; at equal t (triangles sharing
 * an edge, or coincident), the lower triangle index, the one brute force
 * keeps (it takes a hit only if strictly closer, in index order). The answer
 * is then brute force's, bit for bit, whatever the tree. Here
 * bvh_found.triangle is the triangle's index in the set. */
static bvh_found closer(bvh_found hit1, bvh_found hit2)
{
    if (hit1.triangle < 0)
        return hit2;
    if (hit2.triangle < 0)
        return hit1;
    if (hit2.t < hit1.t || (hit2.t == hit1.t && hit2.triangle < hit1.triangle))
        return hit2;
    return hit1;
}

/* The slide's Intersect(ray, node): the closest hit in the subtree of
 * nodes[node_index], or none (triangle -1). */
static bvh_found intersect(const bvh *b, const ray *r, const slab_ray *sr, const watertight_ray *wr,
                           int node_index, ray_counters *counters)
{
    /* exercise: bvh_intersect; a stub returns (bvh_found){-1, r->t_max, 0.0f, 0.0f} */
    const bvh_node *node = &b->nodes[node_index];
    const bvh_found none = {-1, r->t_max, 0.0f, 0.0f};
    float t_enter, t_exit;
    counters->box_tests++;
    if (!aabb_slab_test(&node->box, sr, r->t_min, r->t_max, &t_enter, &t_exit))
        return none; /* the ray misses node.bbox */
    if (bvh_node_is_leaf(node)) {
        /* test intersection with all objs; return the closest */
        bvh_found closest = none;
        for (int i = node->first; i < node->first + bvh_node_triangles(node); i++) {
            bvh_found hit = {b->triangle_index[i], 0.0f, 0.0f, 0.0f};
            if (triangle_intersect_with(b->base.triangle_test, wr, &b->base.set->triangles[hit.triangle], r,
                                        r->t_max, &hit.t, &hit.b1, &hit.b2))
                closest = closer(closest, hit);
            counters->primitive_tests++;
        }
        return closest;
    }
    bvh_found hit1 = intersect(b, r, sr, wr, node->first, counters);     /* child1 */
    bvh_found hit2 = intersect(b, r, sr, wr, node->first + 1, counters); /* child2 */
    return closer(hit1, hit2);
    /* end of exercise bvh_intersect */
}

bool bvh_closest_hit_recursive(const bvh *b, ray r, hit_record *hit, ray_counters *counters)
{
    if (b->node_count == 0)
        return false;
    slab_ray sr = slab_ray_make(r);
    watertight_ray wr = watertight_ray_make(&r);
    bvh_found found = intersect(b, &r, &sr, &wr, 0, counters);
    if (found.triangle < 0)
        return false;
    triangle_set_fill_hit(b->base.set, found.triangle, r, found.t, found.b1, found.b2, hit);
    return true;
}

/* ---- the accel interface -------------------------------------------------- */

static bool finish_closest(const bvh *b, const bvh_found *found, const ray *r, hit_record *record)
{
    if (found->triangle < 0)
        return false;
    triangle_set_fill_hit(b->base.set, b->triangle_index[found->triangle], *r, found->t, found->b1, found->b2,
                          record);
    return true;
}

/* Each traversal compiled once per triangle test, chosen once per ray. */
static bvh_found axis_sign_with(const accel *a, const ray *r, bool stop_at_first, ray_counters *counters)
{
    if (a->triangle_test == TRIANGLE_TEST_WATERTIGHT)
        return traverse_axis_sign((const bvh *)a, r, stop_at_first, TRIANGLE_TEST_WATERTIGHT, counters);
    return traverse_axis_sign((const bvh *)a, r, stop_at_first, TRIANGLE_TEST_MOLLER_TRUMBORE, counters);
}

static bvh_found distance_with(const accel *a, const ray *r, bool stop_at_first, ray_counters *counters)
{
    if (a->triangle_test == TRIANGLE_TEST_WATERTIGHT)
        return traverse_distance((const bvh *)a, r, stop_at_first, TRIANGLE_TEST_WATERTIGHT, counters);
    return traverse_distance((const bvh *)a, r, stop_at_first, TRIANGLE_TEST_MOLLER_TRUMBORE, counters);
}

static bool closest_hit_axis_sign(const accel *a, ray r, hit_record *hit, ray_counters *counters)
{
    bvh_found found = axis_sign_with(a, &r, false, counters);
    return finish_closest((const bvh *)a, &found, &r, hit);
}

static bool any_hit_axis_sign(const accel *a, ray r, ray_counters *counters)
{
    return axis_sign_with(a, &r, true, counters).triangle >= 0;
}

static bool closest_hit_distance(const accel *a, ray r, hit_record *hit, ray_counters *counters)
{
    bvh_found found = distance_with(a, &r, false, counters);
    return finish_closest((const bvh *)a, &found, &r, hit);
}

static bool any_hit_distance(const accel *a, ray r, ray_counters *counters)
{
    return distance_with(a, &r, true, counters).triangle >= 0;
}

static void bvh_destroy(accel *a)
{
    bvh *b = (bvh *)a;
    bvh_nodes_free(b->nodes);
    free(b->triangles);
    free(b->triangle_index);
    free(b);
}

static bool closest_hit_recursive(const accel *a, ray r, hit_record *hit, ray_counters *counters)
{
    return bvh_closest_hit_recursive((const bvh *)a, r, hit, counters);
}

static bool any_hit_recursive(const accel *a, ray r, ray_counters *counters)
{
    hit_record hit;
    return bvh_closest_hit_recursive((const bvh *)a, r, &hit, counters);
}

const accel_ops bvh_ops_axis_sign = {closest_hit_axis_sign, any_hit_axis_sign, bvh_destroy, bvh_use_triangle_test};
const accel_ops bvh_ops_distance = {closest_hit_distance, any_hit_distance, bvh_destroy, bvh_use_triangle_test};
static const accel_ops bvh_ops_recursive = {closest_hit_recursive, any_hit_recursive, bvh_destroy,
                                            bvh_use_triangle_test};

void bvh_set_order(accel *a, bvh_order order)
{
    bvh *b = (bvh *)a;
    b->order = order;
    b->base.ops = order == BVH_ORDER_AXIS_SIGN ? &bvh_ops_axis_sign
                  : order == BVH_ORDER_DISTANCE ? &bvh_ops_distance
                                                : &bvh_ops_recursive;
}
