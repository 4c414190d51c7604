/* flat.c -- every triangle, eight at a time (flat.h). */
#include "13-production/flat.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "13-production/wide_bvh.h"
#include "memory.h"
#include "timer.h"

#if defined(__x86_64__) && defined(__GNUC__) && !defined(WIDE_BVH_NO_SIMD)
#define FLAT_HAVE_X86 1
#include <immintrin.h>

#include "13-production/watertight_simd.h"
#else
#define FLAT_HAVE_X86 0
#endif

/* Each kernel below is written once with `watertight` a parameter and
 * inlined into two entry points, one per triangle test, so that the test
 * is a constant inside and the choice is made once per ray or packet. */
#if defined(__GNUC__)
#define ALWAYS_INLINE inline __attribute__((always_inline))
#else
#define ALWAYS_INLINE inline
#endif

/* ---- the plain C kernel ---------------------------------------------------------
 * Lane by lane, in triangle order, chapter 01's test on what the block
 * stores: watertight_intersect() on the corners (the ray's part in wr), or
 * triangle_intersect_edges() on P0 and the edges (the arithmetic of
 * triangle_intersect_barycentric): the reference the others must equal.
 * Returns the lane hit nearest in (t_min, *t_max), or -1, and lowers
 * *t_max to it; a later lane must be strictly nearer to replace it. */
static ALWAYS_INLINE int block_closest_scalar(const flat_block *b, const ray *r, const watertight_ray *wr,
                                              bool watertight, float *t_max, float *b1, float *b2)
{
    int found = -1;
    for (int k = 0; k < FLAT_LANES; k++) {
        if (watertight) {
            const float p0[3] = {b->p0[0][k], b->p0[1][k], b->p0[2][k]};
            const float p1[3] = {b->p1[0][k], b->p1[1][k], b->p1[2][k]};
            const float p2[3] = {b->p2[0][k], b->p2[1][k], b->p2[2][k]};
            if (watertight_intersect(wr, p0, p1, p2, *t_max, t_max, b1, b2))
                found = k;
            continue;
        }
        vec3 p0 = vec3_make(b->p0[0][k], b->p0[1][k], b->p0[2][k]);
        vec3 e1 = vec3_make(b->e1[0][k], b->e1[1][k], b->e1[2][k]);
        vec3 e2 = vec3_make(b->e2[0][k], b->e2[1][k], b->e2[2][k]);
        if (triangle_intersect_edges(p0, e1, e2, r, *t_max, t_max, b1, b2))
            found = k;
    }
    return found;
}

/* ---- eight lanes, or four ------------------------------------------------------
 * The same operations in the same order, every lane run to the end and its
 * conditions and-ed (a lane the scalar test leaves early computes inf or
 * NaN on the way, which fail its remaining comparisons). One macro writes
 * both widths, so that they cannot drift apart: V is the vector type, P the
 * intrinsics' prefix. Each lane keeps its own nearest hit; lanes are
 * compared once, at the end. Selection is and/andnot/or, not blendv, which
 * GCC has been seen to turn into scalar code inside a target("avx")
 * function. */
#if FLAT_HAVE_X86
/* Moller-Trumbore: triangle_intersect_edges() lane by lane. */
#define FLAT_LANE_TEST(V, P, LOAD, CMP_NE, CMP_GE, CMP_LE, CMP_GT, CMP_LT, block, offset, nearest, which, hit_b1, hit_b2,    \
                       any)                                                                                         \
    do {                                                                                                           \
        V e1x = LOAD(block->e1[0] + offset), e1y = LOAD(block->e1[1] + offset), e1z = LOAD(block->e1[2] + offset); \
        V e2x = LOAD(block->e2[0] + offset), e2y = LOAD(block->e2[1] + offset), e2z = LOAD(block->e2[2] + offset); \
        V s1x = P##_sub_ps(P##_mul_ps(dy, e2z), P##_mul_ps(dz, e2y));                                              \
        V s1y = P##_sub_ps(P##_mul_ps(dz, e2x), P##_mul_ps(dx, e2z));                                              \
        V s1z = P##_sub_ps(P##_mul_ps(dx, e2y), P##_mul_ps(dy, e2x));                                              \
        V determinant = P##_add_ps(P##_add_ps(P##_mul_ps(s1x, e1x), P##_mul_ps(s1y, e1y)), P##_mul_ps(s1z, e1z));  \
        V ok = CMP_NE(determinant, zero);                                                                          \
        V inverse = P##_div_ps(one, determinant);                                                                  \
        V sx = P##_sub_ps(ox, LOAD(block->p0[0] + offset));                                                        \
        V sy = P##_sub_ps(oy, LOAD(block->p0[1] + offset));                                                        \
        V sz = P##_sub_ps(oz, LOAD(block->p0[2] + offset));                                                        \
        V u = P##_mul_ps(P##_add_ps(P##_add_ps(P##_mul_ps(s1x, sx), P##_mul_ps(s1y, sy)), P##_mul_ps(s1z, sz)),    \
                         inverse);                                                                                 \
        ok = P##_and_ps(ok, P##_and_ps(CMP_GE(u, zero), CMP_LE(u, one)));                                          \
        V s2x = P##_sub_ps(P##_mul_ps(sy, e1z), P##_mul_ps(sz, e1y));                                              \
        V s2y = P##_sub_ps(P##_mul_ps(sz, e1x), P##_mul_ps(sx, e1z));                                              \
        V s2z = P##_sub_ps(P##_mul_ps(sx, e1y), P##_mul_ps(sy, e1x));                                              \
        V v = P##_mul_ps(P##_add_ps(P##_add_ps(P##_mul_ps(s2x, dx), P##_mul_ps(s2y, dy)), P##_mul_ps(s2z, dz)),    \
                         inverse);                                                                                 \
        ok = P##_and_ps(ok, P##_and_ps(CMP_GE(v, zero), CMP_LE(P##_add_ps(u, v), one)));                           \
        V t = P##_mul_ps(P##_add_ps(P##_add_ps(P##_mul_ps(s2x, e2x), P##_mul_ps(s2y, e2y)), P##_mul_ps(s2z, e2z)), \
                         inverse);                                                                                 \
        ok = P##_and_ps(ok, P##_and_ps(CMP_GT(t, t_min), CMP_LT(t, nearest)));                                     \
        nearest = P##_or_ps(P##_and_ps(ok, t), P##_andnot_ps(ok, nearest));                                        \
        V lane_index = LOAD((const float *)block->index + offset);                                                 \
        which = P##_or_ps(P##_and_ps(ok, lane_index), P##_andnot_ps(ok, which));                                   \
        hit_b1 = P##_or_ps(P##_and_ps(ok, u), P##_andnot_ps(ok, hit_b1));                                          \
        hit_b2 = P##_or_ps(P##_and_ps(ok, v), P##_andnot_ps(ok, hit_b2));                                          \
        any = P##_or_ps(any, ok);                                                                                  \
    } while (0)



/* The watertight test, watertight_intersect() lane by lane: the ray's part
 * in w_ox .. w_sy and kx, ky, kz (the same for every lane: the rows of the
 * ray's axes are loaded, so the permutation costs nothing). The lanes the
 * ray passes inside go on to t (rarely any: one branch per block), from
 * the block's N. A lane hit keeps v, w and det, of which the barycentrics
 * are made once, for the nearest (flat_barycentrics). IN_DOUBLE:
 * WATERTIGHT_IN_DOUBLE4 or 8 (watertight_simd.h). */
#define FLAT_LANE_TEST_WATERTIGHT(V, P, LOAD, IN_DOUBLE, CMP_GT, CMP_LT, block, offset, nearest, which, hit_v,     \
                                  hit_w, hit_det, any)                                                             \
    do {                                                                                                           \
        V a_z = P##_sub_ps(LOAD(block->p0[kz] + offset), w_oz);                                                    \
        V b_z = P##_sub_ps(LOAD(block->p1[kz] + offset), w_oz);                                                    \
        V c_z = P##_sub_ps(LOAD(block->p2[kz] + offset), w_oz);                                                    \
        V ax = P##_sub_ps(P##_sub_ps(LOAD(block->p0[kx] + offset), w_ox), P##_mul_ps(w_sx, a_z));                  \
        V ay = P##_sub_ps(P##_sub_ps(LOAD(block->p0[ky] + offset), w_oy), P##_mul_ps(w_sy, a_z));                  \
        V bx = P##_sub_ps(P##_sub_ps(LOAD(block->p1[kx] + offset), w_ox), P##_mul_ps(w_sx, b_z));                  \
        V by = P##_sub_ps(P##_sub_ps(LOAD(block->p1[ky] + offset), w_oy), P##_mul_ps(w_sy, b_z));                  \
        V cx = P##_sub_ps(P##_sub_ps(LOAD(block->p2[kx] + offset), w_ox), P##_mul_ps(w_sx, c_z));                  \
        V cy = P##_sub_ps(P##_sub_ps(LOAD(block->p2[ky] + offset), w_oy), P##_mul_ps(w_sy, c_z));                  \
        V u = P##_sub_ps(P##_mul_ps(cx, by), P##_mul_ps(cy, bx));                                                  \
        V v = P##_sub_ps(P##_mul_ps(ax, cy), P##_mul_ps(ay, cx));                                                  \
        V w = P##_sub_ps(P##_mul_ps(bx, ay), P##_mul_ps(by, ax));                                                  \
        WATERTIGHT_INSIDE(V, P, IN_DOUBLE, ok, determinant, ax, ay, bx, by, cx, cy, u, v, w);                      \
        if (P##_movemask_ps(ok) != 0) {                                                                            \
            WATERTIGHT_PLANE_T_N(V, P, t, LOAD(block->p0[0] + offset), LOAD(block->p0[1] + offset),                \
                                 LOAD(block->p0[2] + offset), LOAD(block->n[0] + offset), LOAD(block->n[1] + offset), \
                                 LOAD(block->n[2] + offset), ox, oy, oz, dx, dy, dz);                              \
            ok = P##_and_ps(ok, P##_and_ps(CMP_GT(t, t_min), CMP_LT(t, nearest)));                                 \
            nearest = P##_or_ps(P##_and_ps(ok, t), P##_andnot_ps(ok, nearest));                                    \
            V lane_index = LOAD((const float *)block->index + offset);                                             \
            which = P##_or_ps(P##_and_ps(ok, lane_index), P##_andnot_ps(ok, which));                               \
            hit_v = P##_or_ps(P##_and_ps(ok, v), P##_andnot_ps(ok, hit_v));                                        \
            hit_w = P##_or_ps(P##_and_ps(ok, w), P##_andnot_ps(ok, hit_w));                                        \
            hit_det = P##_or_ps(P##_and_ps(ok, determinant), P##_andnot_ps(ok, hit_det));                          \
            any = P##_or_ps(any, ok);                                                                              \
        }                                                                                                          \
    } while (0)

#define SSE_CMP_NE(a, b) _mm_cmpneq_ps(a, b)
#define SSE_CMP_GE(a, b) _mm_cmpge_ps(a, b)
#define SSE_CMP_LE(a, b) _mm_cmple_ps(a, b)
#define SSE_CMP_GT(a, b) _mm_cmpgt_ps(a, b)
#define SSE_CMP_LT(a, b) _mm_cmplt_ps(a, b)
/* The ordered predicates are the SSE ones (cmpneq is unordered: NaN != 0). */
#define AVX_CMP_NE(a, b) _mm256_cmp_ps(a, b, _CMP_NEQ_UQ)
#define AVX_CMP_GE(a, b) _mm256_cmp_ps(a, b, _CMP_GE_OS)
#define AVX_CMP_LE(a, b) _mm256_cmp_ps(a, b, _CMP_LE_OS)
#define AVX_CMP_GT(a, b) _mm256_cmp_ps(a, b, _CMP_GT_OS)
#define AVX_CMP_LT(a, b) _mm256_cmp_ps(a, b, _CMP_LT_OS)
#endif

#if FLAT_HAVE_X86
/* The lanes' nearest hits, compared: the nearest t, of equal t the lowest
 * triangle index -- what testing them one by one in order gives. */
typedef hits8 lane_hits;

static int nearest_lane(const lane_hits *h, int lanes, float t_max)
{
    int best = -1;
    for (int k = 0; k < lanes; k++)
        if (h->index[k] >= 0 && h->t[k] < t_max && (best < 0 || h->t[k] < h->t[best] ||
                                                     (h->t[k] == h->t[best] && h->index[k] < h->index[best])))
            best = k;
    return best;
}
#endif

/* ---- closest and any hit, for each kernel -------------------------------------- */

static bool finish(const flat *f, const ray *r, int index, float t, float b1, float b2, hit_record *hit)
{
    if (index < 0)
        return false;
    triangle_set_fill_hit(f->base.set, index, *r, t, b1, b2, hit);
    return true;
}

static ALWAYS_INLINE bool closest_scalar(const accel *a, ray r, hit_record *hit, ray_counters *counters,
                                         bool watertight)
{
    const flat *f = (const flat *)a;
    counters->primitive_tests += (uint64_t)f->base.set->count;
    const watertight_ray wr = watertight_ray_make(&r);
    float t_max = r.t_max, b1 = 0.0f, b2 = 0.0f;
    int index = -1;
    for (int i = 0; i < f->block_count; i++) {
        int lane = block_closest_scalar(&f->blocks[i], &r, &wr, watertight, &t_max, &b1, &b2);
        if (lane >= 0)
            index = f->blocks[i].index[lane];
    }
    return finish(f, &r, index, t_max, b1, b2, hit);
}

static ALWAYS_INLINE bool any_scalar(const accel *a, ray r, ray_counters *counters, bool watertight)
{
    const flat *f = (const flat *)a;
    const watertight_ray wr = watertight_ray_make(&r);
    for (int i = 0; i < f->block_count; i++) {
        float t_max = r.t_max, b1, b2;
        counters->primitive_tests += (uint64_t)(f->base.set->count - i * FLAT_LANES < FLAT_LANES
                                                    ? f->base.set->count - i * FLAT_LANES
                                                    : FLAT_LANES);
        if (block_closest_scalar(&f->blocks[i], &r, &wr, watertight, &t_max, &b1, &b2) >= 0)
            return true;
    }
    return false;
}

static bool closest_hit_scalar(const accel *a, ray r, hit_record *hit, ray_counters *counters)
{
    return a->triangle_test == TRIANGLE_TEST_WATERTIGHT ? closest_scalar(a, r, hit, counters, true)
                                                        : closest_scalar(a, r, hit, counters, false);
}

static bool any_hit_scalar(const accel *a, ray r, ray_counters *counters)
{
    return a->triangle_test == TRIANGLE_TEST_WATERTIGHT ? any_scalar(a, r, counters, true)
                                                        : any_scalar(a, r, counters, false);
}

#if FLAT_HAVE_X86
/* The triangles of blocks [0, i] that are real: what any hit counts when
 * it stops after block i. */
static uint64_t tested_through(const flat *f, int i)
{
    int n = (i + 1) * FLAT_LANES;
    return (uint64_t)(n < f->base.set->count ? n : f->base.set->count);
}

/* What both tests need of the ray, as vectors of V (for FLAT_LANE_TEST and
 * FLAT_LANE_TEST_WATERTIGHT): the origin, the direction, t_min, and the
 * watertight test's part (chapter 01's watertight_ray) in its axes. */
#define FLAT_RAY_VECTORS(V, SET1, r)                                                                               \
    const V ox = SET1((r).origin.x), oy = SET1((r).origin.y), oz = SET1((r).origin.z);                             \
    const V dx = SET1((r).direction.x), dy = SET1((r).direction.y), dz = SET1((r).direction.z);                    \
    const V t_min = SET1((r).t_min);                                                                               \
    const watertight_ray wr_ = watertight_ray_make(&(r));                                                          \
    const int kx = wr_.kx, ky = wr_.ky, kz = wr_.kz;                                                               \
    const V w_ox = SET1(vec3_axis(wr_.origin, kx)), w_oy = SET1(vec3_axis(wr_.origin, ky));                        \
    const V w_oz = SET1(vec3_axis(wr_.origin, kz));                                                                \
    const V w_sx = SET1(wr_.shear_x), w_sy = SET1(wr_.shear_y)

/* A block as two halves of four, each with its own lanes' nearest hits. */
#define SSE_BLOCK_TEST(watertight, block, nearest, which, hit_b1, hit_b2, hit_det, any)                            \
    do {                                                                                                           \
        if (watertight) {                                                                                          \
            FLAT_LANE_TEST_WATERTIGHT(__m128, _mm, _mm_load_ps, WATERTIGHT_IN_DOUBLE4, SSE_CMP_GT, SSE_CMP_LT, block, \
                                      0, nearest[0], which[0], hit_b1[0], hit_b2[0], hit_det[0], any);             \
            FLAT_LANE_TEST_WATERTIGHT(__m128, _mm, _mm_load_ps, WATERTIGHT_IN_DOUBLE4, SSE_CMP_GT, SSE_CMP_LT, block, \
                                      4, nearest[1], which[1], hit_b1[1], hit_b2[1], hit_det[1], any);             \
        } else {                                                                                                   \
            FLAT_LANE_TEST(__m128, _mm, _mm_load_ps, SSE_CMP_NE, SSE_CMP_GE, SSE_CMP_LE, SSE_CMP_GT, SSE_CMP_LT,   \
                           block, 0, nearest[0], which[0], hit_b1[0], hit_b2[0], any);                             \
            FLAT_LANE_TEST(__m128, _mm, _mm_load_ps, SSE_CMP_NE, SSE_CMP_GE, SSE_CMP_LE, SSE_CMP_GT, SSE_CMP_LT,   \
                           block, 4, nearest[1], which[1], hit_b1[1], hit_b2[1], any);                             \
        }                                                                                                          \
    } while (0)

/* The watertight test's barycentrics of lane k: v (1 / det) and w (1 / det),
 * the scalar test's operations, from what the lane kept. */
static void flat_barycentrics(lane_hits *h, const float det[FLAT_LANES], int k)
{
    float inverse = 1.0f / det[k];
    h->b1[k] *= inverse;
    h->b2[k] *= inverse;
}

static ALWAYS_INLINE bool closest_sse(const accel *a, ray r, hit_record *hit, ray_counters *counters, bool watertight)
{
    const flat *f = (const flat *)a;
    counters->primitive_tests += (uint64_t)f->base.set->count;
    FLAT_RAY_VECTORS(__m128, _mm_set1_ps, r);
    const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f);
    __m128 nearest[2], which[2], hit_b1[2] = {zero, zero}, hit_b2[2] = {zero, zero}, hit_det[2] = {one, one};
    __m128 any = zero;
    nearest[0] = nearest[1] = _mm_set1_ps(r.t_max);
    which[0] = which[1] = _mm_castsi128_ps(_mm_set1_epi32(-1));
    for (int i = 0; i < f->block_count; i++) {
        const flat_block *block = &f->blocks[i];
        SSE_BLOCK_TEST(watertight, block, nearest, which, hit_b1, hit_b2, hit_det, any);
    }
    if (_mm_movemask_ps(any) == 0)
        return false;
    lane_hits h;
    _Alignas(16) float det[FLAT_LANES];
    for (int half = 0; half < 2; half++) {
        _mm_store_ps(h.t + 4 * half, nearest[half]);
        _mm_store_ps((float *)h.index + 4 * half, which[half]);
        _mm_store_ps(h.b1 + 4 * half, hit_b1[half]);
        _mm_store_ps(h.b2 + 4 * half, hit_b2[half]);
        _mm_store_ps(det + 4 * half, hit_det[half]);
    }
    int k = nearest_lane(&h, FLAT_LANES, r.t_max);
    if (k >= 0 && watertight)
        flat_barycentrics(&h, det, k);
    return k >= 0 && finish(f, &r, h.index[k], h.t[k], h.b1[k], h.b2[k], hit);
}

static ALWAYS_INLINE bool any_sse(const accel *a, ray r, ray_counters *counters, bool watertight)
{
    const flat *f = (const flat *)a;
    FLAT_RAY_VECTORS(__m128, _mm_set1_ps, r);
    const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f);
    for (int i = 0; i < f->block_count; i++) {
        const flat_block *block = &f->blocks[i];
        /* the nearest hit does not matter, only whether there is one */
        __m128 nearest[2], which[2] = {zero, zero}, hit_b1[2] = {zero, zero}, hit_b2[2] = {zero, zero};
        __m128 hit_det[2] = {one, one}, any = zero;
        nearest[0] = nearest[1] = _mm_set1_ps(r.t_max);
        SSE_BLOCK_TEST(watertight, block, nearest, which, hit_b1, hit_b2, hit_det, any);
        if (_mm_movemask_ps(any) != 0) {
            counters->primitive_tests += tested_through(f, i);
            return true;
        }
    }
    counters->primitive_tests += (uint64_t)f->base.set->count;
    return false;
}

static bool closest_hit_sse(const accel *a, ray r, hit_record *hit, ray_counters *counters)
{
    return a->triangle_test == TRIANGLE_TEST_WATERTIGHT ? closest_sse(a, r, hit, counters, true)
                                                        : closest_sse(a, r, hit, counters, false);
}

static bool any_hit_sse(const accel *a, ray r, ray_counters *counters)
{
    return a->triangle_test == TRIANGLE_TEST_WATERTIGHT ? any_sse(a, r, counters, true)
                                                        : any_sse(a, r, counters, false);
}
#endif

/* ---- eight rays against one triangle at a time ----------------------------------
 * The rays' origins, directions and ends as eight lanes; each triangle
 * broadcast to all eight; the lane arithmetic of the tests above with the
 * roles swapped. The triangles go in order and a later one must be
 * strictly nearer, so of equal t the lower index wins, as for one ray.
 *
 * The watertight test's axes are now each lane's own: kz is the axis of
 * that ray's largest |d| (the same for all eight in one packet in ten, in
 * the eight-path renderer on the Cornell box). So each corner's
 * coordinates are put in each lane's order (FLAT_CORNER8), where one ray
 * alone loaded the rows it needed. The picks are exact, so every lane
 * still does watertight_intersect()'s arithmetic. */
#if FLAT_HAVE_X86
typedef struct {
    __m256 ox, oy, oz, dx, dy, dz, t_min, t_max;
    /* the watertight test's part, lane by lane (watertight_ray): the
     * indices kx, ky, kz (for vpermilps), the origin in the lanes' axes,
     * the shear */
    __m256i perm_x, perm_y, perm_z;
    __m256 w_ox, w_oy, w_oz, w_sx, w_sy;
} ray8;

/* Moller-Trumbore of triangle (block, lane j) for the eight rays: the mask
 * of rays that hit it in (t_min, nearest), and their t, b1, b2. */
#define FLAT_RAYS_TEST(block, j, R, nearest, ok_out, t_out, u_out, v_out)                                            \
    do {                                                                                                           \
        const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);                                       \
        __m256 e1x = _mm256_broadcast_ss(&(block)->e1[0][j]), e1y = _mm256_broadcast_ss(&(block)->e1[1][j]);       \
        __m256 e1z = _mm256_broadcast_ss(&(block)->e1[2][j]);                                                      \
        __m256 e2x = _mm256_broadcast_ss(&(block)->e2[0][j]), e2y = _mm256_broadcast_ss(&(block)->e2[1][j]);       \
        __m256 e2z = _mm256_broadcast_ss(&(block)->e2[2][j]);                                                      \
        __m256 s1x = _mm256_sub_ps(_mm256_mul_ps((R).dy, e2z), _mm256_mul_ps((R).dz, e2y));                        \
        __m256 s1y = _mm256_sub_ps(_mm256_mul_ps((R).dz, e2x), _mm256_mul_ps((R).dx, e2z));                        \
        __m256 s1z = _mm256_sub_ps(_mm256_mul_ps((R).dx, e2y), _mm256_mul_ps((R).dy, e2x));                        \
        __m256 determinant = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(s1x, e1x), _mm256_mul_ps(s1y, e1y)),         \
                                           _mm256_mul_ps(s1z, e1z));                                               \
        __m256 ok = AVX_CMP_NE(determinant, zero);                                                                 \
        __m256 inverse = _mm256_div_ps(one, determinant);                                                          \
        __m256 sx = _mm256_sub_ps((R).ox, _mm256_broadcast_ss(&(block)->p0[0][j]));                                \
        __m256 sy = _mm256_sub_ps((R).oy, _mm256_broadcast_ss(&(block)->p0[1][j]));                                \
        __m256 sz = _mm256_sub_ps((R).oz, _mm256_broadcast_ss(&(block)->p0[2][j]));                                \
        __m256 u = _mm256_mul_ps(                                                                                  \
            _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(s1x, sx), _mm256_mul_ps(s1y, sy)), _mm256_mul_ps(s1z, sz)),   \
            inverse);                                                                                              \
        ok = _mm256_and_ps(ok, _mm256_and_ps(AVX_CMP_GE(u, zero), AVX_CMP_LE(u, one)));                            \
        __m256 s2x = _mm256_sub_ps(_mm256_mul_ps(sy, e1z), _mm256_mul_ps(sz, e1y));                                \
        __m256 s2y = _mm256_sub_ps(_mm256_mul_ps(sz, e1x), _mm256_mul_ps(sx, e1z));                                \
        __m256 s2z = _mm256_sub_ps(_mm256_mul_ps(sx, e1y), _mm256_mul_ps(sy, e1x));                                \
        __m256 v = _mm256_mul_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(s2x, (R).dx), _mm256_mul_ps(s2y, (R).dy)), \
                                               _mm256_mul_ps(s2z, (R).dz)),                                        \
                                 inverse);                                                                         \
        ok = _mm256_and_ps(ok, _mm256_and_ps(AVX_CMP_GE(v, zero), AVX_CMP_LE(_mm256_add_ps(u, v), one)));          \
        __m256 t = _mm256_mul_ps(                                                                                  \
            _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(s2x, e2x), _mm256_mul_ps(s2y, e2y)), _mm256_mul_ps(s2z, e2z)), \
            inverse);                                                                                              \
        ok_out = _mm256_and_ps(ok, _mm256_and_ps(AVX_CMP_GT(t, (R).t_min), AVX_CMP_LT(t, nearest)));               \
        t_out = t;                                                                                                 \
        u_out = u;                                                                                                 \
        v_out = v;                                                                                                 \
    } while (0)

/* The selection `mask ? b : a`, lane by lane (blendv: one instruction). */
#define FLAT_SELECT(mask, b, a) _mm256_blendv_ps(a, b, mask)

/* A corner of a triangle, one of its three rows of four floats in
 * flat.corners (x, y, z, unused), put in each lane's axes: the four floats
 * fill both halves of a vector (one load) and each lane picks its
 * coordinate kx, ky or kz by index (R.perm_x, R.perm_y, R.perm_z:
 * vpermilps). kz = x makes the axes (y, z, x), kz = y (z, x, y), kz = z
 * (x, y, z). Three instructions a corner, against nine (three broadcasts,
 * six selections) from the blocks' rows: the eight-path renderer spent a
 * third of its time more with those. The picks are exact. */
#define FLAT_CORNER8(corner, R, px, py, pz)                                                                        \
    __m256 px, py, pz;                                                                                             \
    do {                                                                                                           \
        const __m256 xyz_ = _mm256_broadcast_ps((const __m128 *)(corner));                                         \
        px = _mm256_permutevar_ps(xyz_, (R).perm_x);                                                               \
        py = _mm256_permutevar_ps(xyz_, (R).perm_y);                                                               \
        pz = _mm256_permutevar_ps(xyz_, (R).perm_z);                                                               \
    } while (0)

/* The watertight test of triangle i (its corners c = flat.corners[i]) for
 * the eight rays: watertight_intersect() lane by lane, each lane in its own
 * axes. The mask of rays that hit it in (t_min, nearest), their t, and v,
 * w and det, of which b1 = v (1 / det) and b2 = w (1 / det), computed once
 * for the nearest hits at the end (the scalar test's operations: the same
 * bits). Every lane runs to the end: whether any of eight rays passes
 * inside a triangle of the Cornell box is a coin toss, and a branch on it
 * was measured slower than computing t for all. */
#define FLAT_RAYS_TEST_WATERTIGHT(c, R, nearest, ok_out, t_out, v_out, w_out, det_out)                              \
    do {                                                                                                           \
        FLAT_CORNER8((c), R, p0x, p0y, p0z);                                                                       \
        FLAT_CORNER8((c) + 4, R, p1x, p1y, p1z);                                                                   \
        FLAT_CORNER8((c) + 8, R, p2x, p2y, p2z);                                                                   \
        __m256 a_z = _mm256_sub_ps(p0z, (R).w_oz), b_z = _mm256_sub_ps(p1z, (R).w_oz);                             \
        __m256 c_z = _mm256_sub_ps(p2z, (R).w_oz);                                                                 \
        __m256 ax = _mm256_sub_ps(_mm256_sub_ps(p0x, (R).w_ox), _mm256_mul_ps((R).w_sx, a_z));                     \
        __m256 ay = _mm256_sub_ps(_mm256_sub_ps(p0y, (R).w_oy), _mm256_mul_ps((R).w_sy, a_z));                     \
        __m256 bx = _mm256_sub_ps(_mm256_sub_ps(p1x, (R).w_ox), _mm256_mul_ps((R).w_sx, b_z));                     \
        __m256 by = _mm256_sub_ps(_mm256_sub_ps(p1y, (R).w_oy), _mm256_mul_ps((R).w_sy, b_z));                     \
        __m256 cx = _mm256_sub_ps(_mm256_sub_ps(p2x, (R).w_ox), _mm256_mul_ps((R).w_sx, c_z));                     \
        __m256 cy = _mm256_sub_ps(_mm256_sub_ps(p2y, (R).w_oy), _mm256_mul_ps((R).w_sy, c_z));                     \
        __m256 u = _mm256_sub_ps(_mm256_mul_ps(cx, by), _mm256_mul_ps(cy, bx));                                    \
        __m256 v = _mm256_sub_ps(_mm256_mul_ps(ax, cy), _mm256_mul_ps(ay, cx));                                    \
        __m256 w = _mm256_sub_ps(_mm256_mul_ps(bx, ay), _mm256_mul_ps(by, ax));                                    \
        WATERTIGHT_INSIDE(__m256, _mm256, WATERTIGHT_IN_DOUBLE8, ok, determinant, ax, ay, bx, by, cx, cy, u, v, w); \
        WATERTIGHT_PLANE_T_N(__m256, _mm256, t, _mm256_broadcast_ss((c) + 0), _mm256_broadcast_ss((c) + 1),        \
                             _mm256_broadcast_ss((c) + 2), _mm256_broadcast_ss((c) + 3), _mm256_broadcast_ss((c) + 7), \
                             _mm256_broadcast_ss((c) + 11), (R).ox, (R).oy, (R).oz, (R).dx, (R).dy, (R).dz);        \
        ok_out = _mm256_and_ps(ok, _mm256_and_ps(AVX_CMP_GT(t, (R).t_min), AVX_CMP_LT(t, nearest)));               \
        t_out = t;                                                                                                 \
        v_out = v;                                                                                                 \
        w_out = w;                                                                                                 \
        det_out = determinant;                                                                                     \
    } while (0)

/* The AVX kernels (flat_avx.inc), compiled twice: for AVX's 16 vector
 * registers, and for AVX-512's 32, where the same operations give the
 * same answers but nothing spills to memory (the packet loop holds eight
 * rays, four running results and a triangle): 7 % less time for chapter 09's
 * --wide, 4 % for one ray at a time. Only the registers are AVX-512's: the
 * vectors stay eight lanes wide. */
#define FLAT_TARGET "avx"
#define FLAT_NAME(name) name##_avx
#include "13-production/flat_avx.inc"
#undef FLAT_TARGET
#undef FLAT_NAME
#define FLAT_TARGET "avx,avx512f,avx512vl"
#define FLAT_NAME(name) name##_avx512
#include "13-production/flat_avx.inc"
#undef FLAT_TARGET
#undef FLAT_NAME
#endif

int flat_closest_hit8_raw(const accel *a, const rays8 *rays, int active, hits8 *hits,
                          ray_counters *counters)
{
    const flat *f = (const flat *)a;
    int hit = 0;
#if FLAT_HAVE_X86
    if (f->kernel == FLAT_KERNEL_AVX || f->kernel == FLAT_KERNEL_AVX512) {
        int tested;
        hit = f->kernel == FLAT_KERNEL_AVX512 ? closest_hit8_avx512(f, rays, active, hits, &tested)
                                              : closest_hit8_avx(f, rays, active, hits, &tested);
        uint64_t lanes = (uint64_t)__builtin_popcount((unsigned)active);
        counters->primitive_tests += lanes * (uint64_t)tested;
        counters->box_tests += lanes * (uint64_t)f->group_count;
        return hit;
    }
#endif
    for (int k = 0; k < FLAT_LANES; k++) {
        hit_record record;
        if (((active >> k) & 1) && accel_closest_hit(a, rays8_get(rays, k), &record, counters)) {
            hits->t[k] = record.t;
            hits->index[k] = record.shape_id;
            hits->b1[k] = record.u;
            hits->b2[k] = record.v;
            hit |= 1 << k;
        }
    }
    return hit;
}

int flat_any_hit8_raw(const accel *a, const rays8 *rays, int active, ray_counters *counters)
{
    const flat *f = (const flat *)a;
    int hit = 0;
#if FLAT_HAVE_X86
    if (f->kernel == FLAT_KERNEL_AVX || f->kernel == FLAT_KERNEL_AVX512) {
        int tested;
        hit = f->kernel == FLAT_KERNEL_AVX512 ? any_hit8_avx512(f, rays, active, &tested)
                                              : any_hit8_avx(f, rays, active, &tested);
        counters->primitive_tests += (uint64_t)__builtin_popcount((unsigned)active) * (uint64_t)tested;
        return hit;
    }
#endif
    for (int k = 0; k < FLAT_LANES; k++)
        if ((active >> k) & 1)
            hit |= accel_any_hit(a, rays8_get(rays, k), counters) << k;
    return hit;
}

/* The ray[] forms: the rays copied into lanes (the active ones; the
 * kernels read no other lane). */
static void rays8_copy(rays8 *out, const ray rays[FLAT_LANES], int active)
{
    for (int k = 0; k < FLAT_LANES; k++)
        if ((active >> k) & 1)
            rays8_set(out, k, rays[k]);
}

void flat_closest_hit8(const accel *a, const ray rays[FLAT_LANES], int active, hit_record hits[FLAT_LANES],
                       bool found[FLAT_LANES], ray_counters *counters)
{
    const flat *f = (const flat *)a;
    rays8 lanes = {0};
    rays8_copy(&lanes, rays, active);
    hits8 h;
    int hit = flat_closest_hit8_raw(a, &lanes, active, &h, counters);
    for (int k = 0; k < FLAT_LANES; k++) {
        if (!((active >> k) & 1))
            continue;
        found[k] = (hit >> k) & 1;
        if (found[k])
            triangle_set_fill_hit(f->base.set, h.index[k], rays[k], h.t[k], h.b1[k], h.b2[k], &hits[k]);
    }
}

void flat_any_hit8(const accel *a, const ray rays[FLAT_LANES], int active, bool found[FLAT_LANES],
                   ray_counters *counters)
{
    rays8 lanes = {0};
    rays8_copy(&lanes, rays, active);
    int hit = flat_any_hit8_raw(a, &lanes, active, counters);
    for (int k = 0; k < FLAT_LANES; k++)
        if ((active >> k) & 1)
            found[k] = (hit >> k) & 1;
}

/* ---- build ------------------------------------------------------------------ */

static void flat_destroy(accel *a)
{
    flat *f = (flat *)a;
    free(f->blocks);
    free(f->corners);
    free(f->groups);
    free(f);
}

/* Every lane rewritten for `test` (flat.h), from the set. */
static bool flat_use_triangle_test(accel *a, triangle_test test)
{
    flat *f = (flat *)a;
    a->triangle_test = test;
    for (int i = 0; i < f->block_count * FLAT_LANES; i++) {
        flat_block *b = &f->blocks[i / FLAT_LANES];
        int k = i % FLAT_LANES;
        float p0[3], v1[3], v2[3];
        wide_bvh_lane_coordinates(i < a->set->count ? &a->set->triangles[i] : NULL, test, p0, v1, v2);
        /* N = (P1 - P0) x (P2 - P0), watertight_plane_t()'s operations (for
         * the watertight test; with Moller-Trumbore's edges it is unused) */
        float e1x = v1[0] - p0[0], e1y = v1[1] - p0[1], e1z = v1[2] - p0[2];
        float e2x = v2[0] - p0[0], e2y = v2[1] - p0[1], e2z = v2[2] - p0[2];
        const float n[3] = {e1y * e2z - e1z * e2y, e1z * e2x - e1x * e2z, e1x * e2y - e1y * e2x};
        for (int axis = 0; axis < 3; axis++) {
            b->p0[axis][k] = p0[axis];
            b->p1[axis][k] = v1[axis]; /* p1 and e1 are the same floats (flat.h) */
            b->p2[axis][k] = v2[axis];
            b->n[axis][k] = n[axis];
        }
        b->index[k] = i < a->set->count ? i : -1;
        if (i < a->set->count && test == TRIANGLE_TEST_WATERTIGHT) {
            for (int corner = 0; corner < 3; corner++) {
                const float *from = corner == 0 ? p0 : corner == 1 ? v1 : v2;
                float *to = &f->corners[i][4 * corner];
                to[0] = from[0], to[1] = from[1], to[2] = from[2], to[3] = n[corner];
            }
        }
    }
    return true;
}

static const accel_ops flat_ops_scalar = {closest_hit_scalar, any_hit_scalar, flat_destroy, flat_use_triangle_test};
#if FLAT_HAVE_X86
static const accel_ops flat_ops_sse = {closest_hit_sse, any_hit_sse, flat_destroy, flat_use_triangle_test};
static const accel_ops flat_ops_avx = {closest_hit_avx, any_hit_avx, flat_destroy, flat_use_triangle_test};
static const accel_ops flat_ops_avx512 = {closest_hit_avx512, any_hit_avx512, flat_destroy, flat_use_triangle_test};

static bool has_avx512(void) { return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl"); }
#endif

bool flat_is(const accel *a) { return a != NULL && a->ops->destroy == flat_destroy; }

flat_kernel flat_best_kernel(void)
{
#if FLAT_HAVE_X86
    return has_avx512() ? FLAT_KERNEL_AVX512 : __builtin_cpu_supports("avx") ? FLAT_KERNEL_AVX : FLAT_KERNEL_SSE;
#else
    return FLAT_KERNEL_SCALAR;
#endif
}

bool flat_kernel_runs(flat_kernel kernel)
{
    switch (kernel) {
    case FLAT_KERNEL_SCALAR:
        return true;
#if FLAT_HAVE_X86
    case FLAT_KERNEL_SSE:
        return true;
    case FLAT_KERNEL_AVX:
        return __builtin_cpu_supports("avx");
    case FLAT_KERNEL_AVX512:
        return has_avx512();
#endif
    default:
        return false;
    }
}

bool flat_set_kernel(accel *a, flat_kernel kernel)
{
    static const accel_ops *const ops[] = {
#if FLAT_HAVE_X86
        [FLAT_KERNEL_AVX512] = &flat_ops_avx512,
        [FLAT_KERNEL_AVX] = &flat_ops_avx,
        [FLAT_KERNEL_SSE] = &flat_ops_sse,
#endif
        [FLAT_KERNEL_SCALAR] = &flat_ops_scalar,
    };
    if (!flat_kernel_runs(kernel))
        return false;
    flat *f = (flat *)a;
    f->base.ops = ops[kernel];
    f->kernel = kernel;
    return true;
}

/* ---- groups -----------------------------------------------------------------
 * Eight rays that all miss a box need not test what is inside it: lecture
 * 14's bounding volume, one level deep. The triangles stay in their order
 * (so ties still go to the lower index) and are cut into runs, each with
 * its box; flat_closest_hit8() and flat_any_hit8() test a run only if one
 * of their rays meets its box. In the Cornell box the runs are the room
 * (walls and light, 12 triangles) and the two blocks (10 each): eight rays
 * that all pass beside a block skip its ten triangles.
 *
 * Where to cut is lecture 14's surface area heuristic: a run of n
 * triangles in box B costs one box test plus n triangle tests times the
 * chance that a ray which meets the scene's box S meets B, area(B) /
 * area(S). The cheapest cuts are found exactly, by dynamic programming
 * over where the last run starts (runs of at most GROUP_MAX).
 *
 * A box test for eight rays is about 25 operations against a triangle
 * test's 62, but it ends in a branch that goes either way at random, and
 * its price was measured, not counted: chapter 09's --wide on the Cornell
 * box, with the box priced at 0.5, 1, 2, 4 and 8 triangle tests. At 0.5
 * and 1 every wall is a run of its own (8 runs): no faster than no boxes
 * at all. At 2 and 4: the three runs above, 4 % faster. At 8 the blocks
 * merge: slower again.
 *
 * The box is padded by GROUP_PAD of the scene's size (its extent plus its
 * largest coordinate). The triangle test's t and barycentrics are rounded;
 * a hit it accepts may lie a little outside the exact triangle, and the
 * slab test's t are rounded too. Both errors are a few units in the last
 * place of the distances involved, 2^-24 of them, while the padding is
 * 2^-10 of the scene: a ray from within about a thousand scene sizes is
 * judged right with room to spare, even along a wall (a grazing ray stays
 * inside the padded box for a long stretch of t, as long as the error in
 * its t grows). Except a ray in a triangle's plane, within rounding: there
 * the determinant is rounding noise and the "hit" may be anywhere on the
 * line, hundreds of units from the triangle; the packet then skips it if
 * no ray meets the box, and gives the true nearest hit. The tests compare
 * every packet with each ray alone, bit for bit, on the hard meshes
 * (test_ch06), and along the Cornell box's triangles, where only such
 * lanes may differ (test_ch09). */
enum { GROUP_MAX = 64 };
static const float GROUP_PAD = 0x1.0p-10f;
static const float GROUP_BOX_COST = 2.0f;

static aabb padded(aabb b, float pad)
{
    return (aabb){vec3_sub(b.lo, vec3_splat(pad)), vec3_add(b.hi, vec3_splat(pad))};
}

static void group_triangles(flat *f, const triangle_set *set)
{
    int n = set->count;
    f->group_count = 0;
    f->groups = memory_allocate((size_t)(n > 0 ? n : 1), sizeof *f->groups);
    if (n == 0)
        return;
    aabb s = set->bounds;
    vec3 extent = aabb_extent(s), far = vec3_max(vec3_abs(s.lo), vec3_abs(s.hi));
    float size = fmaxf(fmaxf(extent.x, extent.y), extent.z) + fmaxf(fmaxf(far.x, far.y), far.z);
    float pad = GROUP_PAD * size;
    float scene_area = aabb_surface_area(padded(s, pad));
    /* cost[i]: the cheapest cutting of the first i triangles; start[i]: where
     * its last run starts */
    double *cost = memory_allocate((size_t)n + 1, sizeof *cost);
    int *start = memory_allocate((size_t)n + 1, sizeof *start);
    for (int end = 1; end <= n; end++) {
        aabb box = aabb_empty();
        cost[end] = INFINITY;
        for (int first = end - 1; first >= 0 && end - first <= GROUP_MAX; first--) {
            box = aabb_union(box, set->boxes[first]);
            double chance = scene_area > 0.0f ? fmin(1.0, aabb_surface_area(padded(box, pad)) / scene_area) : 1.0;
            double c = cost[first] + GROUP_BOX_COST + chance * (end - first);
            if (c < cost[end]) {
                cost[end] = c;
                start[end] = first;
            }
        }
    }
    /* the runs, read back from the end, then put in order */
    for (int end = n; end > 0; end = start[end]) {
        int first = start[end];
        aabb box = aabb_empty();
        for (int i = first; i < end; i++)
            box = aabb_union(box, set->boxes[i]);
        box = padded(box, pad);
        flat_group *g = &f->groups[f->group_count++];
        *g = (flat_group){{box.lo.x, box.lo.y, box.lo.z}, {box.hi.x, box.hi.y, box.hi.z}, first, end - first};
    }
    for (int i = 0, j = f->group_count - 1; i < j; i++, j--) {
        flat_group swap = f->groups[i];
        f->groups[i] = f->groups[j];
        f->groups[j] = swap;
    }
    free(cost);
    free(start);
}

accel *flat_build(const triangle_set *set)
{
    double start = timer_seconds();
    flat *f = memory_allocate(1, sizeof *f);
    f->base.set = set;
    f->block_count = (set->count + FLAT_LANES - 1) / FLAT_LANES;
    size_t bytes = (size_t)(f->block_count > 0 ? f->block_count : 1) * sizeof(flat_block);
    f->blocks = aligned_alloc(_Alignof(flat_block), bytes);
    if (f->blocks == NULL) {
        fprintf(stderr, "out of memory (asked for %zu bytes)\n", bytes);
        exit(1);
    }
    memset(f->blocks, 0, bytes);
    size_t corner_bytes = (size_t)(set->count > 0 ? set->count : 1) * sizeof *f->corners;
    f->corners = aligned_alloc(16, corner_bytes); /* a multiple of 16: 48 bytes a triangle */
    if (f->corners == NULL) {
        fprintf(stderr, "out of memory (asked for %zu bytes)\n", corner_bytes);
        exit(1);
    }
    flat_use_triangle_test(&f->base, TRIANGLE_TEST_WATERTIGHT); /* the lanes */
    group_triangles(f, set);
    flat_set_kernel(&f->base, flat_best_kernel());
    f->base.stats.name = "flat";
    f->base.stats.bytes = sizeof *f + bytes + corner_bytes + (size_t)f->group_count * sizeof *f->groups;
    f->base.stats.nodes = 0;
    f->base.stats.leaves = 1;
    f->base.stats.max_depth = 0;
    f->base.stats.references = set->count;
    f->base.stats.build_seconds = timer_seconds() - start;
    return &f->base;
}
