/* bvh_internal.h -- what the BVH's own files share (bvh_build.c,
 * bvh_traverse.c, and chapter 13's wide BVH built on them), and the tests that
 * check those parts one by one; no chapter program includes it. */
#ifndef BVH_INTERNAL_H
#define BVH_INTERNAL_H

#include "06-bvh/bvh.h"

/* ---- the slab test, tuned: what the iterative traversals run ----------------
 * The lecture's slab test is chapter 03's aabb_slab_test() (aabb.h); the
 * lecture's recursive traversal, bvh_closest_hit_recursive(), calls it.
 * This is the same test tuned to run for every node of a fast traversal:
 * the same arithmetic and the same answer, bit for bit
 * (test_slab_test_matches_chapter_03), but inline (a call into another file
 * per node cost more than the test itself) and without a branch. Chapter 03
 * swaps t_min and t_max of an axis where 1/d < 0; here that choice is made
 * once per ray and kept as an index into the node's bounds[]: the plane met
 * first is lo where 1/d >= 0 and hi where 1/d < 0 (1/(-0) = -inf included),
 * as in Williams et al., "An Efficient and Robust Ray-Box Intersection
 * Algorithm" (2005). Here and not in bvh.h because only traversal kernels
 * use it: bvh_traverse.c's iterative ones, and chapter 13's wide BVH's, which
 * takes bvh_ray_make() and BVH_SLAB_ROUNDING_PAD. */
typedef struct {
    vec3 origin;
    vec3 inverse_direction; /* 1/d per axis */
    int near_x, near_y, near_z; /* index in bvh_node.bounds of the plane met first */
} bvh_ray;

/* aabb.c's SLAB_ROUNDING_PAD: 1 + 2 gamma(3), which covers the rounding of
 * t = (p - o) (1/d) in both t_enter and t_exit (see aabb.c). */
static const float BVH_SLAB_ROUNDING_PAD = 1.0f + 2.0f * (3.0f * 0x1.0p-24f) / (1.0f - 3.0f * 0x1.0p-24f);

static inline bvh_ray bvh_ray_make(const ray *r)
{
    bvh_ray b;
    b.origin = r->origin;
    b.inverse_direction = vec3_make(1.0f / r->direction.x, 1.0f / r->direction.y, 1.0f / r->direction.z);
    b.near_x = b.inverse_direction.x < 0.0f ? 3 : 0;
    b.near_y = b.inverse_direction.y < 0.0f ? 4 : 1;
    b.near_z = b.inverse_direction.z < 0.0f ? 5 : 2;
    return b;
}

/* Does the ray meet the box for some t in [t_min, t_max]? Returns that,
 * and t_enter (the first such t). The box's six planes, in bvh_node.bounds'
 * order, lie `stride` floats apart from b: 1 for a node of this chapter,
 * the node's width for a child of chapter 13's wide BVH (whose scalar
 * kernel runs this very test, so the two cannot drift apart). The far
 * plane of each axis is the other one of its pair: 3 - near_x, 5 - near_y,
 * 7 - near_z. */
static inline bool bvh_slab_test_planes(const float *b, int stride, const bvh_ray *r, float t_min, float t_max,
                                        float *t_enter)
{
    float near_x = (b[r->near_x * stride] - r->origin.x) * r->inverse_direction.x;
    float far_x = (b[(3 - r->near_x) * stride] - r->origin.x) * r->inverse_direction.x;
    float near_y = (b[r->near_y * stride] - r->origin.y) * r->inverse_direction.y;
    float far_y = (b[(5 - r->near_y) * stride] - r->origin.y) * r->inverse_direction.y;
    float near_z = (b[r->near_z * stride] - r->origin.z) * r->inverse_direction.z;
    float far_z = (b[(7 - r->near_z) * stride] - r->origin.z) * r->inverse_direction.z;
    /* t_enter = max t_min, t_exit = min t_max; a NaN leaves them as they are */
    float enter = t_min, exit = INFINITY;
    enter = near_x > enter ? near_x : enter;
    enter = near_y > enter ? near_y : enter;
    enter = near_z > enter ? near_z : enter;
    exit = far_x < exit ? far_x : exit;
    exit = far_y < exit ? far_y : exit;
    exit = far_z < exit ? far_z : exit;
    /* aabb.c pads each axis's t_max before the minimum; padding the minimum
     * gives the same float (rounding is monotonic: min(a p, b p) = min(a, b) p)
     * for one multiplication instead of three. */
    exit *= BVH_SLAB_ROUNDING_PAD;
    exit = t_max < exit ? t_max : exit;
    *t_enter = enter;
    return enter <= exit;
}

/* The slab test of a node's box. */
static inline bool bvh_slab_test(const bvh_node *node, const bvh_ray *r, float t_min, float t_max, float *t_enter)
{
    return bvh_slab_test_planes(node->bounds, 1, r, t_min, t_max, t_enter);
}

extern const accel_ops bvh_ops_axis_sign; /* BVH_ORDER_AXIS_SIGN */
extern const accel_ops bvh_ops_distance;  /* BVH_ORDER_DISTANCE */
/* Their use_triangle_test: rewrites bvh.triangles for the test (bvh.h). */
bool bvh_use_triangle_test(accel *a, triangle_test test);

/* The node array, placed so that each pair of children shares a cache line
 * (see bvh_build.c); free it with bvh_nodes_free(). */
bvh_node *bvh_nodes_allocate(int count);
void bvh_nodes_free(bvh_node *nodes);

/* The SAH's constants, which chapter 13's wide BVH sets differently:
 * bvh_build() uses C_t = BVH_SAH_TRAVERSAL_COST, blocks of 1 and leaves of
 * at most BVH_SAH_MAX_LEAF_SIZE. */
typedef struct {
    float traversal_cost; /* C_t, with C_i = 1 */
    int leaf_block;       /* a leaf costs C_i per started block of this many triangles */
    int max_leaf_size;    /* split larger sets even when the SAH prefers a leaf */
    /* C_t for the sets whose box has at least top_area_fraction of the
     * root's surface area (none if it is 0): chapter 13's wide BVH splits
     * the few large sets near the root more eagerly (it says why). */
    float top_area_fraction, top_traversal_cost;
} bvh_sah_params;

accel *bvh_build_with(const triangle_set *set, bvh_split split, const bvh_sah_params *sah);

/* The tree as the recursion built it, for a caller that lays it out its own
 * way (chapter 13's collapse into wide nodes): nodes in the slots of a
 * sparse array of 2 N - 1 (the root in slot 0, a node's two children side
 * by side at first and first + 1; the slots no node reached are never
 * written), and the triangles' leaf order. bvh_build_with() numbers these nodes densely and
 * copies the triangles in leaf order for chapter 06's walk; a caller with
 * its own layout skips both. Free with bvh_tree_free(). */
typedef struct {
    bvh_node *nodes;
    int *triangle_index;
    int triangle_count;
} bvh_tree;

void bvh_tree_build(const triangle_set *set, bvh_split split, const bvh_sah_params *sah, bvh_tree *out);
void bvh_tree_free(bvh_tree *tree);

/* Boxes are culled against the closest hit times this: see bvh_traverse.c
 * for why and how much. */
static const float BVH_CULL_SLACK = 1.0f + 0x1.0p-9f;

#endif
