/* bvh4_traverse.c -- a ray through a 4-wide BVH: at each node, slab-test
 * the children's boxes at once (four, or eight: BVH4_WIDTH), go on with the
 * nearest child hit and put the others on the stack, farthest deepest; in
 * a leaf, test its triangles four at a time, with the watertight test (or
 * Moller-Trumbore, when asked). Every test exists twice, with SSE
 * intrinsics and as a plain C loop over the lanes; the two do the same
 * float operations in the same order, so they give the same answers
 * (test_ch13 runs both). */
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "13-production/bvh4.h"
#include "06-bvh/bvh_internal.h"

#if BVH4_HAVE_SSE
#include <immintrin.h>

#include "13-production/watertight_simd.h"
#endif

/* traverse4(), test_leaf4() and triangle_test4() are inlined into each of
 * their callers, so that `sse`, `watertight` and `stop_at_first` are
 * constants there and the compiler drops the branches on them. */
#if defined(__GNUC__)
#define ALWAYS_INLINE inline __attribute__((always_inline))
#else
#define ALWAYS_INLINE inline
#endif

/* ---- the ray, prepared once ---------------------------------------------------- */

typedef struct {
    bvh_ray scalar; /* origin, 1/d, and which plane of each axis is met first */
    int far_x, far_y, far_z;
    watertight_ray watertight; /* the watertight test's part for the ray (chapter 01) */
#if BVH4_HAVE_SSE
    __m128 origin[3], inverse_direction[3], direction[3];
    /* the same, in the watertight test's axes: o_kx, o_ky, o_kz; the shear
     * d_kx / d_kz, d_ky / d_kz; t_min */
    __m128 w_origin[3], w_shear[2], w_t_min;
#endif
} bvh4_ray;

static inline bvh4_ray bvh4_ray_make(const ray *r)
{
    bvh4_ray b;
    b.scalar = bvh_ray_make(r);
    b.far_x = 3 - b.scalar.near_x;
    b.far_y = 5 - b.scalar.near_y;
    b.far_z = 7 - b.scalar.near_z;
    b.watertight = watertight_ray_make(r);
#if BVH4_HAVE_SSE
    const watertight_ray *w = &b.watertight;
    b.w_origin[0] = _mm_set1_ps(vec3_axis(w->origin, w->kx));
    b.w_origin[1] = _mm_set1_ps(vec3_axis(w->origin, w->ky));
    b.w_origin[2] = _mm_set1_ps(vec3_axis(w->origin, w->kz));
    b.w_shear[0] = _mm_set1_ps(w->shear_x);
    b.w_shear[1] = _mm_set1_ps(w->shear_y);
    b.w_t_min = _mm_set1_ps(w->t_min);
    b.origin[0] = _mm_set1_ps(r->origin.x);
    b.origin[1] = _mm_set1_ps(r->origin.y);
    b.origin[2] = _mm_set1_ps(r->origin.z);
    b.inverse_direction[0] = _mm_set1_ps(b.scalar.inverse_direction.x);
    b.inverse_direction[1] = _mm_set1_ps(b.scalar.inverse_direction.y);
    b.inverse_direction[2] = _mm_set1_ps(b.scalar.inverse_direction.z);
    b.direction[0] = _mm_set1_ps(r->direction.x);
    b.direction[1] = _mm_set1_ps(r->direction.y);
    b.direction[2] = _mm_set1_ps(r->direction.z);
#endif
    return b;
}

/* ---- four (or eight) slab tests ----------------------------------------------------
 * bvh_slab_test() (bvh.h) for the BVH4_WIDTH children: the same operations
 * in the same order, so the same answer for every box, including its IEEE
 * rules (NaN from 0 * inf leaves t_enter and t_exit as they are; the
 * flat-box pad on t_exit). Returns a BVH4_WIDTH-bit mask of the boxes hit,
 * with their t_enter. The SSE version tests four boxes per instruction, a
 * group of four at a time: one group for a 4-wide node, two for 8-wide. */

static inline int slab_test4_scalar(const bvh4_node *node, const bvh4_ray *r, float t_min, float t_max,
                                    float t_enter[BVH4_WIDTH])
{
    const bvh_ray *s = &r->scalar;
    int mask = 0;
    for (int k = 0; k < BVH4_WIDTH; k++) {
        float near_x = (node->bounds[s->near_x][k] - s->origin.x) * s->inverse_direction.x;
        float far_x = (node->bounds[r->far_x][k] - s->origin.x) * s->inverse_direction.x;
        float near_y = (node->bounds[s->near_y][k] - s->origin.y) * s->inverse_direction.y;
        float far_y = (node->bounds[r->far_y][k] - s->origin.y) * s->inverse_direction.y;
        float near_z = (node->bounds[s->near_z][k] - s->origin.z) * s->inverse_direction.z;
        float far_z = (node->bounds[r->far_z][k] - s->origin.z) * s->inverse_direction.z;
        float enter = t_min, exit = INFINITY;
        enter = near_x > enter ? near_x : enter;
        enter = near_y > enter ? near_y : enter;
        enter = near_z > enter ? near_z : enter;
        exit = far_x < exit ? far_x : exit;
        exit = far_y < exit ? far_y : exit;
        exit = far_z < exit ? far_z : exit;
        exit *= BVH_SLAB_ROUNDING_PAD;
        exit = t_max < exit ? t_max : exit;
        t_enter[k] = enter;
        mask |= (enter <= exit) << k;
    }
    return mask;
}

#if BVH4_HAVE_SSE
/* _mm_max_ps(a, b) is a > b ? a : b and _mm_min_ps(a, b) is a < b ? a : b,
 * operand order included (with a NaN, they return b): exactly the scalar
 * selections above. */
static inline int slab_test4_sse(const bvh4_node *node, const bvh4_ray *r, float t_min, float t_max,
                                 float t_enter[BVH4_WIDTH])
{
    const bvh_ray *s = &r->scalar;
    int mask = 0;
    for (int g = 0; g < BVH4_WIDTH; g += 4) {
        __m128 near_x = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(&node->bounds[s->near_x][g]), r->origin[0]), r->inverse_direction[0]);
        __m128 far_x = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(&node->bounds[r->far_x][g]), r->origin[0]), r->inverse_direction[0]);
        __m128 near_y = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(&node->bounds[s->near_y][g]), r->origin[1]), r->inverse_direction[1]);
        __m128 far_y = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(&node->bounds[r->far_y][g]), r->origin[1]), r->inverse_direction[1]);
        __m128 near_z = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(&node->bounds[s->near_z][g]), r->origin[2]), r->inverse_direction[2]);
        __m128 far_z = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(&node->bounds[r->far_z][g]), r->origin[2]), r->inverse_direction[2]);
        __m128 enter = _mm_set1_ps(t_min), exit = _mm_set1_ps(INFINITY);
        enter = _mm_max_ps(near_x, enter);
        enter = _mm_max_ps(near_y, enter);
        enter = _mm_max_ps(near_z, enter);
        exit = _mm_min_ps(far_x, exit);
        exit = _mm_min_ps(far_y, exit);
        exit = _mm_min_ps(far_z, exit);
        exit = _mm_mul_ps(exit, _mm_set1_ps(BVH_SLAB_ROUNDING_PAD));
        exit = _mm_min_ps(_mm_set1_ps(t_max), exit);
        _mm_storeu_ps(&t_enter[g], enter);
        mask |= _mm_movemask_ps(_mm_cmple_ps(enter, exit)) << g;
        if (g + 4 < BVH4_WIDTH && node->child[g + 4] == BVH4_EMPTY)
            break; /* the next four slots are empty: no box there to hit */
    }
    return mask;
}
#endif

/* ---- four triangle tests, watertight ---------------------------------------------------
 * watertight_intersect() (chapter 01's shapes.h) on each lane: the same
 * operations in the same order, so the same t, b1, b2, bit for bit, and the
 * same rules. The lane's corners are read in the ray's axes: the packet
 * stores them by coordinate, so "coordinate kx of the four P0" is the row
 * p0[kx], and the permutation costs nothing. Returns the mask of lanes hit
 * in (t_min, t_max). */

static ALWAYS_INLINE int triangle_test4_watertight_scalar(const bvh4_packet *p, const bvh4_ray *r4, float t_max,
                                                          float t[4], float b1[4], float b2[4])
{
    int mask = 0;
    for (int k = 0; k < 4; k++) {
        const float p0[3] = {p->p0[0][k], p->p0[1][k], p->p0[2][k]};
        const float p1[3] = {p->p1[0][k], p->p1[1][k], p->p1[2][k]};
        const float p2[3] = {p->p2[0][k], p->p2[1][k], p->p2[2][k]};
        if (watertight_intersect(&r4->watertight, p0, p1, p2, t_max, &t[k], &b1[k], &b2[k]))
            mask |= 1 << k;
    }
    return mask;
}

#if BVH4_HAVE_SSE
/* The scalar test stops at the first failed condition; here every lane
 * runs to the end and the conditions are and-ed, as in
 * WATERTIGHT_INSIDE (watertight_simd.h), which says why the answers are the
 * same. Only the lanes the ray passes inside, if any, go on to t. */
static ALWAYS_INLINE int triangle_test4_watertight_sse(const bvh4_packet *p, const bvh4_ray *r4, float t_max,
                                                       float t[4], float b1[4], float b2[4])
{
    const int kx = r4->watertight.kx, ky = r4->watertight.ky, kz = r4->watertight.kz;
    const __m128 *o = r4->w_origin, *shear = r4->w_shear;
    __m128 a_z = _mm_sub_ps(_mm_load_ps(p->p0[kz]), o[2]);
    __m128 b_z = _mm_sub_ps(_mm_load_ps(p->p1[kz]), o[2]);
    __m128 c_z = _mm_sub_ps(_mm_load_ps(p->p2[kz]), o[2]);
    __m128 ax = _mm_sub_ps(_mm_sub_ps(_mm_load_ps(p->p0[kx]), o[0]), _mm_mul_ps(shear[0], a_z));
    __m128 ay = _mm_sub_ps(_mm_sub_ps(_mm_load_ps(p->p0[ky]), o[1]), _mm_mul_ps(shear[1], a_z));
    __m128 bx = _mm_sub_ps(_mm_sub_ps(_mm_load_ps(p->p1[kx]), o[0]), _mm_mul_ps(shear[0], b_z));
    __m128 by = _mm_sub_ps(_mm_sub_ps(_mm_load_ps(p->p1[ky]), o[1]), _mm_mul_ps(shear[1], b_z));
    __m128 cx = _mm_sub_ps(_mm_sub_ps(_mm_load_ps(p->p2[kx]), o[0]), _mm_mul_ps(shear[0], c_z));
    __m128 cy = _mm_sub_ps(_mm_sub_ps(_mm_load_ps(p->p2[ky]), o[1]), _mm_mul_ps(shear[1], c_z));
    __m128 u = _mm_sub_ps(_mm_mul_ps(cx, by), _mm_mul_ps(cy, bx));
    __m128 v = _mm_sub_ps(_mm_mul_ps(ax, cy), _mm_mul_ps(ay, cx));
    __m128 w = _mm_sub_ps(_mm_mul_ps(bx, ay), _mm_mul_ps(by, ax));
    WATERTIGHT_INSIDE(__m128, _mm, WATERTIGHT_IN_DOUBLE4, ok, determinant, ax, ay, bx, by, cx, cy, u, v, w);
    if (_mm_movemask_ps(ok) == 0)
        return 0; /* most packets: the ray passes beside all four */
    WATERTIGHT_PLANE_T(__m128, _mm, distance, _mm_load_ps(p->p0[0]), _mm_load_ps(p->p0[1]), _mm_load_ps(p->p0[2]),
                       _mm_load_ps(p->p1[0]), _mm_load_ps(p->p1[1]), _mm_load_ps(p->p1[2]), _mm_load_ps(p->p2[0]),
                       _mm_load_ps(p->p2[1]), _mm_load_ps(p->p2[2]), r4->origin[0], r4->origin[1], r4->origin[2],
                       r4->direction[0], r4->direction[1], r4->direction[2]);
    ok = _mm_and_ps(ok, _mm_and_ps(_mm_cmpgt_ps(distance, r4->w_t_min), _mm_cmplt_ps(distance, _mm_set1_ps(t_max))));
    int mask = _mm_movemask_ps(ok);
    if (mask != 0) { /* all four lanes: the caller reads only those hit */
        __m128 inverse = _mm_div_ps(_mm_set1_ps(1.0f), determinant);
        _mm_storeu_ps(t, distance);
        _mm_storeu_ps(b1, _mm_mul_ps(v, inverse));
        _mm_storeu_ps(b2, _mm_mul_ps(w, inverse));
    }
    return mask;
}
#endif

/* ---- four triangle tests, Moller-Trumbore ------------------------------------------------
 * bvh_triangle_intersect() (bvh_traverse.c) on each lane: the same products
 * in the same order (vec3_cross, vec3_dot: (x + y) + z), so the same t, b1,
 * b2, bit for bit, and the same rules: a determinant of exactly 0 is refused,
 * every comparison is false for NaN. Returns the mask of lanes hit in
 * (t_min, t_max). */

static ALWAYS_INLINE int triangle_test4_scalar(const bvh4_packet *p, const ray *r, float t_max, float t[4],
                                               float b1[4], float b2[4])
{
    int mask = 0;
    for (int k = 0; k < 4; k++) {
        vec3 p0 = vec3_make(p->p0[0][k], p->p0[1][k], p->p0[2][k]);
        vec3 e1 = vec3_make(p->e1[0][k], p->e1[1][k], p->e1[2][k]);
        vec3 e2 = vec3_make(p->e2[0][k], p->e2[1][k], p->e2[2][k]);
        if (triangle_intersect_edges(p0, e1, e2, r, t_max, &t[k], &b1[k], &b2[k]))
            mask |= 1 << k;
    }
    return mask;
}

#if BVH4_HAVE_SSE
/* The scalar test stops at the first failed condition; here every lane
 * runs to the end and the conditions are and-ed. A lane the scalar test
 * leaves early (determinant 0) computes 1/0 = inf and NaN on the way, which
 * fail its remaining comparisons: the mask is the same. */
static ALWAYS_INLINE int triangle_test4_sse(const bvh4_packet *p, const bvh4_ray *r4, const ray *r, float t_max,
                                            float t[4], float b1[4], float b2[4])
{
    const __m128 *d = r4->direction;
    __m128 e1x = _mm_load_ps(p->e1[0]), e1y = _mm_load_ps(p->e1[1]), e1z = _mm_load_ps(p->e1[2]);
    __m128 e2x = _mm_load_ps(p->e2[0]), e2y = _mm_load_ps(p->e2[1]), e2z = _mm_load_ps(p->e2[2]);
    /* S1 = D x E2 */
    __m128 s1x = _mm_sub_ps(_mm_mul_ps(d[1], e2z), _mm_mul_ps(d[2], e2y));
    __m128 s1y = _mm_sub_ps(_mm_mul_ps(d[2], e2x), _mm_mul_ps(d[0], e2z));
    __m128 s1z = _mm_sub_ps(_mm_mul_ps(d[0], e2y), _mm_mul_ps(d[1], e2x));
    __m128 determinant = _mm_add_ps(_mm_add_ps(_mm_mul_ps(s1x, e1x), _mm_mul_ps(s1y, e1y)), _mm_mul_ps(s1z, e1z));
    __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f);
    __m128 ok = _mm_cmpneq_ps(determinant, zero);
    __m128 inverse = _mm_div_ps(one, determinant);
    /* S = O - P0 */
    __m128 sx = _mm_sub_ps(r4->origin[0], _mm_load_ps(p->p0[0]));
    __m128 sy = _mm_sub_ps(r4->origin[1], _mm_load_ps(p->p0[1]));
    __m128 sz = _mm_sub_ps(r4->origin[2], _mm_load_ps(p->p0[2]));
    __m128 u = _mm_mul_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(s1x, sx), _mm_mul_ps(s1y, sy)), _mm_mul_ps(s1z, sz)), inverse);
    ok = _mm_and_ps(ok, _mm_and_ps(_mm_cmpge_ps(u, zero), _mm_cmple_ps(u, one)));
    /* S2 = S x E1 */
    __m128 s2x = _mm_sub_ps(_mm_mul_ps(sy, e1z), _mm_mul_ps(sz, e1y));
    __m128 s2y = _mm_sub_ps(_mm_mul_ps(sz, e1x), _mm_mul_ps(sx, e1z));
    __m128 s2z = _mm_sub_ps(_mm_mul_ps(sx, e1y), _mm_mul_ps(sy, e1x));
    __m128 v = _mm_mul_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(s2x, d[0]), _mm_mul_ps(s2y, d[1])), _mm_mul_ps(s2z, d[2])), inverse);
    ok = _mm_and_ps(ok, _mm_and_ps(_mm_cmpge_ps(v, zero), _mm_cmple_ps(_mm_add_ps(u, v), one)));
    __m128 distance =
        _mm_mul_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(s2x, e2x), _mm_mul_ps(s2y, e2y)), _mm_mul_ps(s2z, e2z)), inverse);
    ok = _mm_and_ps(ok, _mm_and_ps(_mm_cmpgt_ps(distance, _mm_set1_ps(r->t_min)),
                                   _mm_cmplt_ps(distance, _mm_set1_ps(t_max))));
    int mask = _mm_movemask_ps(ok);
    if (mask != 0) { /* all four lanes: the caller reads only those hit */
        _mm_storeu_ps(t, distance);
        _mm_storeu_ps(b1, u);
        _mm_storeu_ps(b2, v);
    }
    return mask;
}
#endif

int bvh4_slab_test(const bvh4_node *node, ray r, float t_min, float t_max, float t_enter[BVH4_WIDTH], bvh4_kernel kernel)
{
    bvh4_ray r4 = bvh4_ray_make(&r);
#if BVH4_HAVE_SSE
    if (kernel == BVH4_KERNEL_SSE)
        return slab_test4_sse(node, &r4, t_min, t_max, t_enter);
#endif
    (void)kernel;
    return slab_test4_scalar(node, &r4, t_min, t_max, t_enter);
}

/* The four lanes by the tree's triangle test and the kernel. */
static ALWAYS_INLINE int triangle_test4(const bvh4_packet *p, const bvh4_ray *r4, const ray *r, float t_max, float t[4],
                                        float b1[4], float b2[4], bool sse, bool watertight)
{
#if BVH4_HAVE_SSE
    if (sse)
        return watertight ? triangle_test4_watertight_sse(p, r4, t_max, t, b1, b2)
                          : triangle_test4_sse(p, r4, r, t_max, t, b1, b2);
#endif
    (void)sse;
    return watertight ? triangle_test4_watertight_scalar(p, r4, t_max, t, b1, b2)
                      : triangle_test4_scalar(p, r, t_max, t, b1, b2);
}

int bvh4_triangle_test(const bvh4_packet *packet, ray r, float t_max, float t[4], float b1[4], float b2[4],
                       bvh4_kernel kernel, triangle_test test)
{
    bvh4_ray r4 = bvh4_ray_make(&r);
    float lane_t[4], lane_b1[4], lane_b2[4];
    int mask = triangle_test4(packet, &r4, &r, t_max, lane_t, lane_b1, lane_b2, kernel == BVH4_KERNEL_SSE,
                              test == TRIANGLE_TEST_WATERTIGHT);
    for (int k = 0; k < 4; k++) /* lanes not hit keep what they had */
        if (mask >> k & 1) {
            t[k] = lane_t[k];
            b1[k] = lane_b1[k];
            b2[k] = lane_b2[k];
        }
    return mask;
}

/* ---- traversal ------------------------------------------------------------------- */


/* What a traversal found: the closest triangle so far (4 packet + lane). */
typedef struct {
    int lane; /* -1: none */
    float t, b1, b2;
} bvh4_found;

typedef struct {
    uint32_t ref;
    float t_enter;
} bvh4_entry;

static inline int lowest_bit(unsigned mask) { return __builtin_ctz(mask); }

/* Ask for a child's memory before it is needed: a node's cache lines,
 * or a leaf's packets (160 bytes each). The children hit at a node are all
 * fetched at once, in parallel, instead of one after the other as the
 * traversal reaches them.
 *
 * Always inlined, and that matters: GCC counts __builtin_prefetch as having
 * no effect, so it takes a function made of prefetches for a pure one, and
 * a call to a pure function whose result is unused for dead code. Where
 * this function was not inlined early, as in the closest-hit traversal, the
 * call and every prefetch in it silently vanished (objdump showed none). */
static ALWAYS_INLINE void prefetch_child(const bvh4 *b, uint32_t ref)
{
#if defined(__GNUC__)
    if (!bvh4_is_leaf(ref)) {
        const char *p = (const char *)&b->nodes[ref];
        for (size_t line = 0; line < sizeof(bvh4_node); line += 64)
            __builtin_prefetch(p + line);
        return;
    }
    const char *p = (const char *)&b->packets[bvh4_leaf_first_packet(ref)];
    __builtin_prefetch(p);
    __builtin_prefetch(p + 64);
    __builtin_prefetch(p + 128);
    if (bvh4_leaf_triangles(ref) > 4) {
        __builtin_prefetch(p + 192);
        __builtin_prefetch(p + 256);
    }
#else
    (void)b;
    (void)ref;
#endif
}

/* A hit will be turned into a hit record from the set's material and unit
 * normal of the triangle (and the mesh's face, for vertex normals) and,
 * unless the packet gives the vertices back exactly (BVH4_LANE_EXACT), the
 * set's copy of the triangle: ask for them as soon as a hit is found, so
 * they are in the cache by the end of the traversal (usually the first hit
 * found is the closest). */
static ALWAYS_INLINE void prefetch_hit(const bvh4 *b, int32_t lane_index)
{
#if defined(__GNUC__)
    int index = bvh4_lane_triangle(lane_index);
    if (!(lane_index & BVH4_LANE_EXACT))
        __builtin_prefetch(&b->base.set->triangles[index]);
    const triangle_set *set = b->base.set;
    __builtin_prefetch(&set->surfaces[index]);
    if (set->source != NULL && set->vertex_normals)
        __builtin_prefetch(&set->source->faces[index]);
#else
    (void)b;
    (void)lane_index;
#endif
}

/* The leaf's packets against (t_min, found->t). The lanes hit in a packet
 * all lie before found->t; the closest of them, the first among equals,
 * wins: what testing the triangles one by one in lane order gives. */
static ALWAYS_INLINE bool test_leaf4(const bvh4 *b, uint32_t ref, const bvh4_ray *r4, const ray *r, bvh4_found *found,
                              bool stop_at_first, bool sse, bool watertight, uint64_t *primitive_tests)
{
    int count = bvh4_leaf_triangles(ref), first = bvh4_leaf_first_packet(ref);
    for (int p = 0; p * 4 < count; p++) {
        float t[4], b1[4], b2[4];
        const bvh4_packet *packet = &b->packets[first + p];
        int mask = triangle_test4(packet, r4, r, found->t, t, b1, b2, sse, watertight);
        *primitive_tests += (uint64_t)(count - 4 * p < 4 ? count - 4 * p : 4);
        if (mask == 0)
            continue;
        while (mask != 0) {
            int k = lowest_bit((unsigned)mask);
            mask &= mask - 1;
            if (t[k] < found->t)
                *found = (bvh4_found){4 * (first + p) + k, t[k], b1[k], b2[k]};
        }
        if (stop_at_first)
            return true;
        prefetch_hit(b, packet->index[found->lane % 4]);
    }
    return false;
}

/* Real children of a node (the empty slots come last). */
static inline int child_count(const bvh4_node *node)
{
    int count = 1;
    for (int k = 1; k < BVH4_WIDTH; k++)
        count += node->child[k] != BVH4_EMPTY;
    return count;
}

/* One ray's walk through the tree, as data: what the loop of a traversal
 * keeps between one node and the next. Kept in a struct, rather than in
 * local variables, so that several rays can take turns (the stream below);
 * for one ray alone the compiler keeps the scalars in registers all the
 * same. */
typedef struct {
    bvh4_ray r4;
    ray r;
    bvh4_found found;
    uint32_t current; /* the node or leaf to visit next */
    int top;          /* entries on the stack */
    uint64_t box_tests, primitive_tests;
    bvh4_entry stack[BVH4_STACK_SIZE];
} bvh4_traversal;

/* Start at the root; false if there is no tree to walk. */
static ALWAYS_INLINE bool traversal_begin(const bvh4 *b, const ray *r, bvh4_traversal *w)
{
    w->r = *r;
    w->r4 = bvh4_ray_make(r);
    w->found = (bvh4_found){-1, r->t_max, 0.0f, 0.0f};
    w->current = 0; /* the root */
    w->top = 0;
    w->box_tests = w->primitive_tests = 0;
    return b->node_count > 0;
}

/* Visit w->current -- slab-test a node's children, or test a leaf's
 * triangles -- and choose the next one to visit. Returns false when the
 * walk is over: the stack is empty, or (any hit) a triangle was hit. */
static ALWAYS_INLINE bool traversal_step(const bvh4 *b, bvh4_traversal *w, bool stop_at_first, bool sse,
                                         bool watertight)
{
    if (!bvh4_is_leaf(w->current)) {
        const bvh4_node *node = &b->nodes[w->current];
        float t_enter[BVH4_WIDTH];
        float cull = w->found.t * BVH_CULL_SLACK;
        int mask;
#if BVH4_HAVE_SSE
        if (sse)
            mask = slab_test4_sse(node, &w->r4, w->r.t_min, cull, t_enter);
        else
#endif
            mask = slab_test4_scalar(node, &w->r4, w->r.t_min, cull, t_enter);
        w->box_tests += (uint64_t)child_count(node);
        if (mask != 0) {
            int k = lowest_bit((unsigned)mask);
            mask &= mask - 1;
            if (mask == 0) {
                /* one child hit: no order to decide */
                w->current = node->child[k];
                return true;
            }
            int k2 = lowest_bit((unsigned)mask);
            mask &= mask - 1;
            if (mask == 0) {
                /* two (the commonest case): one comparison orders them */
                bool second_first = t_enter[k2] < t_enter[k];
                int near = second_first ? k2 : k, far = second_first ? k : k2;
                prefetch_child(b, node->child[far]);
                w->stack[w->top++] = (bvh4_entry){node->child[far], t_enter[far]};
                w->current = node->child[near];
                return true;
            }
            mask |= 1 << k2;
            /* Three or more: sort them by t_enter, nearest last
             * (insertion sort), push all but the nearest, visit it. */
            bvh4_entry hits[BVH4_WIDTH];
            int n = 0;
            hits[n++] = (bvh4_entry){node->child[k], t_enter[k]};
            prefetch_child(b, node->child[k]);
            while (mask != 0) {
                k = lowest_bit((unsigned)mask);
                mask &= mask - 1;
                bvh4_entry e = {node->child[k], t_enter[k]};
                prefetch_child(b, e.ref);
                int j = n++;
                while (j > 0 && hits[j - 1].t_enter < e.t_enter) {
                    hits[j] = hits[j - 1];
                    j--;
                }
                hits[j] = e;
            }
            for (int j = 0; j < n - 1; j++)
                w->stack[w->top++] = hits[j];
            w->current = hits[n - 1].ref;
            return true;
        }
    } else if (test_leaf4(b, w->current, &w->r4, &w->r, &w->found, stop_at_first, sse, watertight,
                          &w->primitive_tests)) {
        return false;
    }
    /* Next from the stack, skipping entries that begin beyond the
     * closest hit (their box test would fail now). */
    float cull = w->found.t * BVH_CULL_SLACK;
    while (w->top > 0 && w->stack[w->top - 1].t_enter > cull)
        w->top--;
    if (w->top == 0)
        return false;
    w->current = w->stack[--w->top].ref;
    return true;
}

static ALWAYS_INLINE bvh4_found traverse4(const bvh4 *b, const ray *r, bool stop_at_first, bool sse, bool watertight,
                                          ray_counters *counters)
{
    bvh4_traversal w;
    if (traversal_begin(b, r, &w))
        while (traversal_step(b, &w, stop_at_first, sse, watertight))
            ;
    counters->box_tests += w.box_tests;
    counters->primitive_tests += w.primitive_tests;
    return w.found;
}

/* ---- the accel interface ------------------------------------------------------------- */

static bool finish_closest(const bvh4 *b, const bvh4_found *found, const ray *r, hit_record *record)
{
    if (found->lane < 0)
        return false;
    const bvh4_packet *p = &b->packets[found->lane / 4];
    int k = found->lane % 4, index = bvh4_lane_triangle(p->index[k]);
    if (!(p->index[k] & BVH4_LANE_EXACT)) {
        triangle_set_fill_hit(b->base.set, index, *r, found->t, found->b1, found->b2, record);
        return true;
    }
    /* the set's triangle, bit for bit, from the cache lines the test read */
    vec3 p0 = vec3_make(p->p0[0][k], p->p0[1][k], p->p0[2][k]);
    vec3 v1 = vec3_make(p->p1[0][k], p->p1[1][k], p->p1[2][k]), v2 = vec3_make(p->p2[0][k], p->p2[1][k], p->p2[2][k]);
    triangle tri = {p0, v1, v2}; /* the watertight test's corners */
    if (b->base.triangle_test == TRIANGLE_TEST_MOLLER_TRUMBORE)
        tri = (triangle){p0, vec3_add(p0, v1), vec3_add(p0, v2)}; /* P0 + E1, P0 + E2 */
    triangle_set_fill_hit_from(b->base.set, &tri, index, *r, found->t, found->b1, found->b2, record);
    return true;
}

/* One entry point per kernel, query and triangle test, each with all three
 * constant inside (ALWAYS_INLINE), the test chosen once per ray. */
static bvh4_found traverse4_with(const accel *a, const ray *r, bool stop_at_first, bool sse, ray_counters *counters)
{
    const bvh4 *b = (const bvh4 *)a;
    bool wt = a->triangle_test == TRIANGLE_TEST_WATERTIGHT;
#if BVH4_HAVE_SSE
    if (sse) {
        if (stop_at_first)
            return wt ? traverse4(b, r, true, true, true, counters) : traverse4(b, r, true, true, false, counters);
        return wt ? traverse4(b, r, false, true, true, counters) : traverse4(b, r, false, true, false, counters);
    }
#endif
    (void)sse;
    if (stop_at_first)
        return wt ? traverse4(b, r, true, false, true, counters) : traverse4(b, r, true, false, false, counters);
    return wt ? traverse4(b, r, false, false, true, counters) : traverse4(b, r, false, false, false, counters);
}

static bool closest_hit_scalar(const accel *a, ray r, hit_record *hit, ray_counters *counters)
{
    bvh4_found found = traverse4_with(a, &r, false, false, counters);
    return finish_closest((const bvh4 *)a, &found, &r, hit);
}

static bool any_hit_scalar(const accel *a, ray r, ray_counters *counters)
{
    return traverse4_with(a, &r, true, false, counters).lane >= 0;
}

#if BVH4_HAVE_SSE
static bool closest_hit_sse(const accel *a, ray r, hit_record *hit, ray_counters *counters)
{
    bvh4_found found = traverse4_with(a, &r, false, true, counters);
    return finish_closest((const bvh4 *)a, &found, &r, hit);
}

static bool any_hit_sse(const accel *a, ray r, ray_counters *counters)
{
    return traverse4_with(a, &r, true, true, counters).lane >= 0;
}
#endif

/* ---- a stream of rays, taking turns ---------------------------------------------------
 * On a mesh far larger than the cache, one ray's walk is a chain of waits:
 * a node must arrive from memory before its boxes can say which node comes
 * next. The processor overlaps little of that, because each fetch depends
 * on the one before. Rays of a stream do not depend on each other, so
 * BVH4_STREAM_LANES of them take turns: each visits one node, asks for
 * the memory of the node it will visit next (prefetch), and waits while the
 * others take their turn. By the time a ray's turn comes round again its
 * node has arrived. Each ray does exactly what it would alone, in the same
 * order: the same hits, bit for bit. */
static ALWAYS_INLINE void stream4(const bvh4 *b, const ray *rays, int count, hit_record *hits, bool *hit_found,
                                  bvh4_found *raw, bool stop_at_first, bool sse, bool watertight,
                                  ray_counters *counters)
{
    bvh4_traversal lanes[BVH4_STREAM_LANES];
    int ray_of[BVH4_STREAM_LANES]; /* the ray each lane walks, -1: none left */
    int next = 0, walking = 0;
    /* Closest hits found, waiting to become hit records. Making one reads
     * the triangle's material (and maybe its vertices) from the set, memory
     * that prefetch_hit() asked for when the hit was found, often just
     * before the walk ended: a ray waits here while BVH4_STREAM_LANES others
     * finish, so that the memory has arrived. */
    struct {
        int ray;
        bvh4_found found;
    } waiting[BVH4_STREAM_LANES];
    int waiting_count = 0, waiting_oldest = 0;
    for (int k = 0; k < BVH4_STREAM_LANES; k++)
        ray_of[k] = -1;
    /* Not needed (a lane is read only after traversal_begin() filled it),
     * but GCC cannot see that with one lane and warns. Everything but the
     * stacks: a few hundred bytes a lane. */
    for (int k = 0; k < BVH4_STREAM_LANES; k++)
        memset(&lanes[k], 0, offsetof(bvh4_traversal, stack));
    for (;;) {
        /* Give every idle lane the next ray; a ray with no tree to walk
         * (an empty tree) finishes at once. */
        for (int k = 0; k < BVH4_STREAM_LANES && next < count; k++) {
            if (ray_of[k] >= 0)
                continue;
            if (traversal_begin(b, &rays[next], &lanes[k])) {
                ray_of[k] = next;
                walking++;
            } else {
                hit_found[next] = false;
            }
            next++;
        }
        if (walking == 0)
            break;
        for (int k = 0; k < BVH4_STREAM_LANES; k++) {
            if (ray_of[k] < 0)
                continue;
            bvh4_traversal *w = &lanes[k];
            if (traversal_step(b, w, stop_at_first, sse, watertight)) {
                prefetch_child(b, w->current);
                continue;
            }
            int i = ray_of[k];
            hit_found[i] = w->found.lane >= 0;
            if (raw != NULL) /* the caller makes its own records */
                raw[i] = w->found;
            else if (!stop_at_first && hit_found[i]) {
                if (waiting_count == BVH4_STREAM_LANES) {
                    int j = waiting[waiting_oldest].ray;
                    finish_closest(b, &waiting[waiting_oldest].found, &rays[j], &hits[j]);
                    waiting_oldest = (waiting_oldest + 1) % BVH4_STREAM_LANES;
                    waiting_count--;
                }
                int slot = (waiting_oldest + waiting_count++) % BVH4_STREAM_LANES;
                waiting[slot].ray = i;
                waiting[slot].found = w->found;
            }
            counters->box_tests += w->box_tests;
            counters->primitive_tests += w->primitive_tests;
            ray_of[k] = -1;
            walking--;
        }
    }
    for (; waiting_count > 0; waiting_count--) {
        int j = waiting[waiting_oldest].ray;
        finish_closest(b, &waiting[waiting_oldest].found, &rays[j], &hits[j]);
        waiting_oldest = (waiting_oldest + 1) % BVH4_STREAM_LANES;
    }
}

/* The kernel and the triangle test chosen once per stream, so stream4() is
 * compiled with them fixed. */
static void stream4_with_kernel(const accel *a, const ray *rays, int count, hit_record *hits, bool *hit_found,
                                bvh4_found *raw, bool stop_at_first, ray_counters *counters)
{
    const bvh4 *b = (const bvh4 *)a;
    bool watertight = a->triangle_test == TRIANGLE_TEST_WATERTIGHT;
#if BVH4_HAVE_SSE
    if (b->kernel == BVH4_KERNEL_SSE) {
        if (stop_at_first) {
            if (watertight)
                stream4(b, rays, count, hits, hit_found, NULL, true, true, true, counters);
            else
                stream4(b, rays, count, hits, hit_found, NULL, true, true, false, counters);
        } else {
            if (raw != NULL)
                stream4(b, rays, count, hits, hit_found, raw, false, true, watertight, counters);
            else if (watertight)
                stream4(b, rays, count, hits, hit_found, NULL, false, true, true, counters);
            else
                stream4(b, rays, count, hits, hit_found, NULL, false, true, false, counters);
        }
        return;
    }
#endif
    stream4(b, rays, count, hits, hit_found, raw, stop_at_first, false, watertight, counters);
}

void bvh4_closest_hit_stream(const accel *a, const ray *rays, int count, hit_record *hits, bool *hit_found,
                             ray_counters *counters)
{
    stream4_with_kernel(a, rays, count, hits, hit_found, NULL, false, counters);
}

void bvh4_any_hit_stream(const accel *a, const ray *rays, int count, bool *hit_found, ray_counters *counters)
{
    stream4_with_kernel(a, rays, count, NULL, hit_found, NULL, true, counters);
}

void bvh4_closest_hit_raw(const accel *a, ray r, bvh4_raw_hit *hit, ray_counters *counters)
{
    const bvh4 *b = (const bvh4 *)a;
    bvh4_found found = traverse4_with(a, &r, false, b->kernel == BVH4_KERNEL_SSE, counters);
    hit->index = found.lane < 0 ? -1 : bvh4_lane_triangle(b->packets[found.lane / 4].index[found.lane % 4]);
    hit->t = found.t;
    hit->b1 = found.b1;
    hit->b2 = found.b2;
}

void bvh4_closest_hit_stream_raw(const accel *a, const ray *rays, int count, bvh4_raw_hit *hits, bool *hit_found,
                                 ray_counters *counters)
{
    enum { CHUNK = 64 };
    const bvh4 *b = (const bvh4 *)a;
    bvh4_found found[CHUNK];
    for (int first = 0; first < count; first += CHUNK) {
        int n = count - first < CHUNK ? count - first : CHUNK;
        stream4_with_kernel(a, rays + first, n, NULL, hit_found + first, found, false, counters);
        for (int i = 0; i < n; i++) {
            bvh4_raw_hit *h = &hits[first + i];
            h->index = found[i].lane < 0 ? -1
                                         : bvh4_lane_triangle(b->packets[found[i].lane / 4].index[found[i].lane % 4]);
            h->t = found[i].t;
            h->b1 = found[i].b1;
            h->b2 = found[i].b2;
        }
    }
}

static void bvh4_destroy(accel *a)
{
    bvh4 *b = (bvh4 *)a;
    free(b->nodes);
    free(b->packets);
    free(b);
}

static const accel_ops bvh4_ops_scalar = {closest_hit_scalar, any_hit_scalar, bvh4_destroy, bvh4_use_triangle_test};
#if BVH4_HAVE_SSE
static const accel_ops bvh4_ops_sse = {closest_hit_sse, any_hit_sse, bvh4_destroy, bvh4_use_triangle_test};
#endif

bool bvh4_is(const accel *a) { return a != NULL && a->ops->destroy == bvh4_destroy; }

const accel_ops *bvh4_default_ops(void)
{
#if BVH4_HAVE_SSE
    return &bvh4_ops_sse;
#else
    return &bvh4_ops_scalar;
#endif
}

bool bvh4_set_kernel(accel *a, bvh4_kernel kernel)
{
    bvh4 *b = (bvh4 *)a;
    if (kernel == BVH4_KERNEL_SCALAR) {
        b->kernel = kernel;
        b->base.ops = &bvh4_ops_scalar;
        return true;
    }
#if BVH4_HAVE_SSE
    b->kernel = kernel;
    b->base.ops = &bvh4_ops_sse;
    return true;
#else
    return false;
#endif
}
