/* wide_bvh_kernels.h -- the tests a ray through the wide BVH runs at each
 * node and leaf (wide_bvh_traverse.c): the ray prepared once, the slab
 * test of a node's WIDE_BVH_WIDTH boxes, and the triangle tests of a
 * packet's four lanes, watertight or Moller-Trumbore, each with SSE
 * intrinsics and as a plain C loop over the lanes (the same float
 * operations in the same order, so the same answers). Static inline, in a
 * header, because the traversal's loops inline them (a call per node cost
 * more than the test); only wide_bvh_traverse.c includes it. */
#ifndef WIDE_BVH_KERNELS_H
#define WIDE_BVH_KERNELS_H

#include <math.h>
#include <string.h>

#include "13-production/wide_bvh.h"
#include "06-bvh/bvh_internal.h"

#if WIDE_BVH_HAVE_SSE
#include <immintrin.h>

#include "13-production/watertight_simd.h"
#endif

/* traverse4(), test_leaf4() and triangle_test4() are inlined into each of
 * their callers, so that `sse`, `watertight` and `stop_at_first` are
 * constants there and the compiler drops the branches on them. */
/* Code compiled for AVX, called only where the processor has it. */
#define AVX_CODE __attribute__((target("avx")))

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
#if WIDE_BVH_HAVE_SSE
    __m128 origin[3], inverse_direction[3], direction[3];
    /* the same, in the watertight test's axes: o_kx, o_ky, o_kz; the shear
     * d_kx / d_kz, d_ky / d_kz; t_min */
    __m128 w_origin[3], w_shear[2], w_t_min;
#endif
} wide_bvh_ray;

static inline wide_bvh_ray wide_bvh_ray_make(const ray *r)
{
    wide_bvh_ray b;
    b.scalar = bvh_ray_make(r);
    b.far_x = 3 - b.scalar.near_x;
    b.far_y = 5 - b.scalar.near_y;
    b.far_z = 7 - b.scalar.near_z;
    b.watertight = watertight_ray_make(r);
#if WIDE_BVH_HAVE_SSE
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
 * bvh_slab_test() (bvh_internal.h) for the WIDE_BVH_WIDTH children: the
 * same operations in the same order, so the same answer for every box,
 * including its IEEE rules (NaN from 0 * inf leaves t_enter and t_exit as
 * they are; the flat-box pad on t_exit). Returns a WIDE_BVH_WIDTH-bit mask
 * of the boxes hit, with their t_enter. The scalar version is chapter 06's
 * test itself, child by child (bvh_slab_test_planes: child k's planes lie
 * WIDE_BVH_WIDTH floats apart); the SSE version tests four boxes per
 * instruction, a group of four at a time: one group for a 4-wide node, two
 * for 8-wide. */

/* bounds: the node's planes, bounds[p * WIDE_BVH_WIDTH + k] plane p of child k */
static inline int slab_planes_scalar(const float *bounds, const wide_bvh_ray *r, float t_min, float t_max,
                                     float t_enter[WIDE_BVH_WIDTH])
{
    int mask = 0;
    for (int k = 0; k < WIDE_BVH_WIDTH; k++)
        mask |= bvh_slab_test_planes(bounds + k, WIDE_BVH_WIDTH, &r->scalar, t_min, t_max, &t_enter[k])
                << k;
    return mask;
}

static inline int slab_test4_scalar(const wide_bvh_node *node, const wide_bvh_ray *r, float t_min, float t_max,
                                    float t_enter[WIDE_BVH_WIDTH])
{
    return slab_planes_scalar(&node->bounds[0][0], r, t_min, t_max, t_enter);
}

/* A quantized node: its planes dequantized (wide_bvh_dequantize), then the
 * same test; the empty slots masked. */
static inline int qslab_test_scalar(const wide_bvh_qnode *node, const wide_bvh_ray *r, float t_min, float t_max,
                                    float t_enter[WIDE_BVH_WIDTH])
{
    float bounds[6][WIDE_BVH_WIDTH];
    for (int p = 0; p < 6; p++)
        for (int k = 0; k < WIDE_BVH_WIDTH; k++)
            bounds[p][k] = wide_bvh_dequantize(node->origin[p % 3], node->exponent[p % 3], node->bounds[p][k]);
    return slab_planes_scalar(&bounds[0][0], r, t_min, t_max, t_enter) & ((1 << node->children) - 1);
}

#if WIDE_BVH_HAVE_SSE
/* _mm_max_ps(a, b) is a > b ? a : b and _mm_min_ps(a, b) is a < b ? a : b,
 * operand order included (with a NaN, they return b): exactly the scalar
 * selections above. */
/* The slab test's arithmetic on the planes near_x .. far_z (variables of
 * vector type V, intrinsics prefix P: SSE's or AVX's), in
 * bvh_slab_test_planes' order: defines enter and exit. */
#define SLAB_PLANES(V, P, ox, oy, oz, ix, iy, iz)                                                              \
    near_x = P##_mul_ps(P##_sub_ps(near_x, ox), ix);                                                           \
    far_x = P##_mul_ps(P##_sub_ps(far_x, ox), ix);                                                             \
    near_y = P##_mul_ps(P##_sub_ps(near_y, oy), iy);                                                           \
    far_y = P##_mul_ps(P##_sub_ps(far_y, oy), iy);                                                             \
    near_z = P##_mul_ps(P##_sub_ps(near_z, oz), iz);                                                           \
    far_z = P##_mul_ps(P##_sub_ps(far_z, oz), iz);                                                             \
    V enter = P##_set1_ps(t_min), exit = P##_set1_ps(INFINITY);                                                \
    enter = P##_max_ps(near_x, enter);                                                                         \
    enter = P##_max_ps(near_y, enter);                                                                         \
    enter = P##_max_ps(near_z, enter);                                                                         \
    exit = P##_min_ps(far_x, exit);                                                                            \
    exit = P##_min_ps(far_y, exit);                                                                            \
    exit = P##_min_ps(far_z, exit);                                                                            \
    exit = P##_mul_ps(exit, P##_set1_ps(BVH_SLAB_ROUNDING_PAD));                                               \
    exit = P##_min_ps(P##_set1_ps(t_max), exit)

/* Four boxes, given their six planes (near and far of each axis, for this
 * ray): the mask hit and t_enter. */
static inline int slab_group_sse(const wide_bvh_ray *r, __m128 near_x, __m128 far_x, __m128 near_y, __m128 far_y,
                                 __m128 near_z, __m128 far_z, float t_min, float t_max, float t_enter[4])
{
    SLAB_PLANES(__m128, _mm, r->origin[0], r->origin[1], r->origin[2], r->inverse_direction[0],
                r->inverse_direction[1], r->inverse_direction[2]);
    _mm_storeu_ps(t_enter, enter);
    return _mm_movemask_ps(_mm_cmple_ps(enter, exit));
}

static inline int slab_test4_sse(const wide_bvh_node *node, const wide_bvh_ray *r, float t_min, float t_max,
                                 float t_enter[WIDE_BVH_WIDTH])
{
    const bvh_ray *s = &r->scalar;
    int mask = 0;
    for (int g = 0; g < WIDE_BVH_WIDTH; g += 4) {
        mask |= slab_group_sse(r, _mm_load_ps(&node->bounds[s->near_x][g]), _mm_load_ps(&node->bounds[r->far_x][g]),
                               _mm_load_ps(&node->bounds[s->near_y][g]), _mm_load_ps(&node->bounds[r->far_y][g]),
                               _mm_load_ps(&node->bounds[s->near_z][g]), _mm_load_ps(&node->bounds[r->far_z][g]),
                               t_min, t_max, &t_enter[g])
                << g;
        if (g + 4 < WIDE_BVH_WIDTH && node->child[g + 4] == WIDE_BVH_EMPTY)
            break; /* the next four slots are empty: no box there to hit */
    }
    return mask;
}

/* Plane p of children g .. g + 3 of a quantized node, in SSE2: four bytes
 * widened to four ints (exact), to floats (exact), times the step (exact),
 * plus the origin: wide_bvh_dequantize's operations. */
static inline __m128 dequantize4_sse(const wide_bvh_qnode *node, int p, int g, const __m128 step[3])
{
    int32_t bytes;
    memcpy(&bytes, &node->bounds[p][g], sizeof bytes);
    const __m128i zero = _mm_setzero_si128();
    __m128i q = _mm_unpacklo_epi16(_mm_unpacklo_epi8(_mm_cvtsi32_si128(bytes), zero), zero);
    return _mm_add_ps(_mm_set1_ps(node->origin[p % 3]), _mm_mul_ps(_mm_cvtepi32_ps(q), step[p % 3]));
}

static inline int qslab_test_sse(const wide_bvh_qnode *node, const wide_bvh_ray *r, float t_min, float t_max,
                                 float t_enter[WIDE_BVH_WIDTH])
{
    const bvh_ray *s = &r->scalar;
    const __m128 step[3] = {_mm_set1_ps(wide_bvh_step(node->exponent[0])), _mm_set1_ps(wide_bvh_step(node->exponent[1])),
                            _mm_set1_ps(wide_bvh_step(node->exponent[2]))};
    int mask = 0;
    for (int g = 0; g < node->children; g += 4)
        mask |= slab_group_sse(r, dequantize4_sse(node, s->near_x, g, step), dequantize4_sse(node, r->far_x, g, step),
                               dequantize4_sse(node, s->near_y, g, step), dequantize4_sse(node, r->far_y, g, step),
                               dequantize4_sse(node, s->near_z, g, step), dequantize4_sse(node, r->far_z, g, step),
                               t_min, t_max, &t_enter[g])
                << g;
    return mask & ((1 << node->children) - 1);
}
#endif

#if WIDE_BVH_HAVE_AVX
#if WIDE_BVH_WIDTH == 8
/* Eight boxes, given their six planes for this ray: the mask hit and
 * t_enter. _mm256_max_ps and _mm256_min_ps select as their SSE forms do,
 * and _CMP_LE_OQ answers as _mm_cmple_ps (false for NaN): the same answer
 * for every box. */
AVX_CODE static inline int slab_planes_avx(const wide_bvh_ray *r, __m256 near_x, __m256 far_x, __m256 near_y,
                                           __m256 far_y, __m256 near_z, __m256 far_z, float t_min, float t_max,
                                           float t_enter[WIDE_BVH_WIDTH])
{
    const bvh_ray *s = &r->scalar;
    const __m256 ox = _mm256_set1_ps(s->origin.x), oy = _mm256_set1_ps(s->origin.y), oz = _mm256_set1_ps(s->origin.z);
    const __m256 ix = _mm256_set1_ps(s->inverse_direction.x), iy = _mm256_set1_ps(s->inverse_direction.y);
    const __m256 iz = _mm256_set1_ps(s->inverse_direction.z);
    SLAB_PLANES(__m256, _mm256, ox, oy, oz, ix, iy, iz);
    _mm256_storeu_ps(t_enter, enter);
    return _mm256_movemask_ps(_mm256_cmp_ps(enter, exit, _CMP_LE_OQ));
}
#endif

/* The same for all WIDE_BVH_WIDTH boxes of a node at once: one test of eight
 * lanes for an 8-wide node (a 4-wide one: the SSE test, in AVX's
 * encoding). The empty slots' boxes (+inf, -inf) fail as in the SSE
 * test. Its target is AVX, so it is not always_inline: it is inlined into
 * the AVX entry points (flatten), which alone call it. */
AVX_CODE static inline int slab_test_avx(const wide_bvh_node *node, const wide_bvh_ray *r, float t_min,
                                                                float t_max, float t_enter[WIDE_BVH_WIDTH])
{
#if WIDE_BVH_WIDTH == 8
    const bvh_ray *s = &r->scalar;
    return slab_planes_avx(r, _mm256_load_ps(node->bounds[s->near_x]), _mm256_load_ps(node->bounds[r->far_x]),
                           _mm256_load_ps(node->bounds[s->near_y]), _mm256_load_ps(node->bounds[r->far_y]),
                           _mm256_load_ps(node->bounds[s->near_z]), _mm256_load_ps(node->bounds[r->far_z]), t_min,
                           t_max, t_enter);
#else
    return slab_test4_sse(node, r, t_min, t_max, t_enter);
#endif
}

/* A quantized node in AVX2 (its one instruction that widens eight bytes to
 * eight ints): plane p of the eight children, wide_bvh_dequantize's
 * operations; then the same test. A 4-wide node: the SSE test in AVX2's
 * encoding. */
#define AVX2_CODE __attribute__((target("avx2")))
#if WIDE_BVH_WIDTH == 8
AVX2_CODE static inline __m256 dequantize8_avx2(const wide_bvh_qnode *node, int p, const __m256 step[3])
{
    __m256i q = _mm256_cvtepu8_epi32(_mm_loadl_epi64((const __m128i *)node->bounds[p]));
    return _mm256_add_ps(_mm256_set1_ps(node->origin[p % 3]), _mm256_mul_ps(_mm256_cvtepi32_ps(q), step[p % 3]));
}
#endif

AVX2_CODE static inline int qslab_test_avx2(const wide_bvh_qnode *node, const wide_bvh_ray *r, float t_min,
                                            float t_max, float t_enter[WIDE_BVH_WIDTH])
{
#if WIDE_BVH_WIDTH == 8
    const bvh_ray *s = &r->scalar;
    const __m256 step[3] = {_mm256_set1_ps(wide_bvh_step(node->exponent[0])),
                            _mm256_set1_ps(wide_bvh_step(node->exponent[1])),
                            _mm256_set1_ps(wide_bvh_step(node->exponent[2]))};
    int mask = slab_planes_avx(r, dequantize8_avx2(node, s->near_x, step), dequantize8_avx2(node, r->far_x, step),
                               dequantize8_avx2(node, s->near_y, step), dequantize8_avx2(node, r->far_y, step),
                               dequantize8_avx2(node, s->near_z, step), dequantize8_avx2(node, r->far_z, step), t_min,
                               t_max, t_enter);
    return mask & ((1 << node->children) - 1);
#else
    return qslab_test_sse(node, r, t_min, t_max, t_enter);
#endif
}

AVX2_CODE __attribute__((noinline)) static int qslab_test_avx2_alone(const wide_bvh_qnode *node,
                                                                    const wide_bvh_ray *r, float t_min, float t_max,
                                                                    float t_enter[WIDE_BVH_WIDTH])
{
    return qslab_test_avx2(node, r, t_min, t_max, t_enter);
}

AVX_CODE __attribute__((noinline)) static int slab_test_avx_alone(const wide_bvh_node *node, const wide_bvh_ray *r,
                                                                         float t_min, float t_max,
                                                                         float t_enter[WIDE_BVH_WIDTH])
{
    return slab_test_avx(node, r, t_min, t_max, t_enter);
}
#endif

/* ---- four triangle tests, watertight ---------------------------------------------------
 * watertight_intersect() (chapter 01's shapes.h) on each lane: the same
 * operations in the same order, so the same t, b1, b2, bit for bit, and the
 * same rules. The lane's corners are read in the ray's axes: the packet
 * stores them by coordinate, so "coordinate kx of the four P0" is the row
 * p0[kx], and the permutation costs nothing. Returns the mask of lanes hit
 * in (t_min, t_max). */

static ALWAYS_INLINE int triangle_test4_watertight_scalar(const wide_bvh_packet *p, const wide_bvh_ray *r4, float t_max,
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

#if WIDE_BVH_HAVE_SSE
/* The scalar test stops at the first failed condition; here every lane
 * runs to the end and the conditions are and-ed, as in
 * WATERTIGHT_INSIDE (watertight_simd.h), which says why the answers are the
 * same. Only the lanes the ray passes inside, if any, go on to t. */
static ALWAYS_INLINE int triangle_test4_watertight_sse(const wide_bvh_packet *p, const wide_bvh_ray *r4, float t_max,
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

static ALWAYS_INLINE int triangle_test4_scalar(const wide_bvh_packet *p, const ray *r, float t_max, float t[4],
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

#if WIDE_BVH_HAVE_SSE
/* The scalar test stops at the first failed condition; here every lane
 * runs to the end and the conditions are and-ed. A lane the scalar test
 * leaves early (determinant 0) computes 1/0 = inf and NaN on the way, which
 * fail its remaining comparisons: the mask is the same. */
static ALWAYS_INLINE int triangle_test4_sse(const wide_bvh_packet *p, const wide_bvh_ray *r4, const ray *r, float t_max,
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

/* The four lanes by the tree's triangle test and the kernel. */
static ALWAYS_INLINE int triangle_test4(const wide_bvh_packet *p, const wide_bvh_ray *r4, const ray *r, float t_max, float t[4],
                                        float b1[4], float b2[4], bool sse, bool watertight)
{
#if WIDE_BVH_HAVE_SSE
    if (sse)
        return watertight ? triangle_test4_watertight_sse(p, r4, t_max, t, b1, b2)
                          : triangle_test4_sse(p, r4, r, t_max, t, b1, b2);
#endif
    (void)sse;
    return watertight ? triangle_test4_watertight_scalar(p, r4, t_max, t, b1, b2)
                      : triangle_test4_scalar(p, r, t_max, t, b1, b2);
}

#endif
