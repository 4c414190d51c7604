/* watertight_simd.h -- parts of chapter 01's watertight triangle test
 * (shapes.h) written once for every vector width, so that the kernels of
 * wide_bvh_traverse.c and flat.c (SSE, AVX, AVX-512 registers) cannot drift
 * apart from the scalar test or from each other: V is the vector type, P
 * the intrinsics' prefix (_mm, _mm256). Included after <immintrin.h>. */
#ifndef WATERTIGHT_SIMD_H
#define WATERTIGHT_SIMD_H

#include "01-ray-casting/shapes.h"

/* Steps 3 to 5 of watertight_intersect() lane by lane: V ok, the lanes the
 * ray passes inside (the edge functions u, v, w not of both signs, their
 * sum det neither 0 nor NaN), and V det. IN_DOUBLE(lanes, ax, .., cy, &u,
 * &v, &w) recomputes the lanes with an exactly-0 edge function in double.
 * The same answer as the scalar test by another route, fewer operations:
 *   - "some < 0 and some > 0" as min(u, v, w) < 0 and max(u, v, w) > 0
 *     (P_min_ps(a, b) = a < b ? a : b). The two differ only where one of
 *     u, v, w is NaN; det is then NaN, and both refuse the lane.
 *   - the double path only for lanes not already outside: rounding is
 *     monotonic, so an edge function that is not exactly 0 has the sign
 *     of its exact value, and a lane with strictly opposite signs stays
 *     outside whatever the double path gives its zeros. A lane not
 *     outside has all of u, v, w >= 0 or all <= 0, so it holds an exact 0
 *     iff min or max is 0.
 *   - det "neither 0 nor NaN" as |det| > 0; the scalar test asks the same. */
#define WATERTIGHT_INSIDE(V, P, IN_DOUBLE, ok, det, ax, ay, bx, by, cx, cy, u, v, w)                              \
    V ok, det;                                                                                                    \
    do {                                                                                                          \
        const V zero_ = P##_setzero_ps(), sign_ = P##_set1_ps(-0.0f);                                             \
        V min_ = P##_min_ps(P##_min_ps(u, v), w), max_ = P##_max_ps(P##_max_ps(u, v), w);                         \
        V outside_ = P##_and_ps(P##_cmplt_ps_(min_, zero_), P##_cmpgt_ps_(max_, zero_));                          \
        V zero_edge_ = P##_andnot_ps(outside_, P##_or_ps(P##_cmpeq_ps_(min_, zero_), P##_cmpeq_ps_(max_, zero_)));  \
        int lanes_ = P##_movemask_ps(zero_edge_);                                                                 \
        if (__builtin_expect(lanes_ != 0, 0)) {                                                                   \
            IN_DOUBLE(lanes_, ax, ay, bx, by, cx, cy, &u, &v, &w);                                                \
            min_ = P##_min_ps(P##_min_ps(u, v), w), max_ = P##_max_ps(P##_max_ps(u, v), w);                       \
            outside_ = P##_and_ps(P##_cmplt_ps_(min_, zero_), P##_cmpgt_ps_(max_, zero_));                        \
        }                                                                                                         \
        det = P##_add_ps(P##_add_ps(u, v), w);                                                                    \
        ok = P##_andnot_ps(outside_, P##_cmpgt_ps_(P##_andnot_ps(sign_, det), zero_));                            \
    } while (0)

/* IN_DOUBLE for WATERTIGHT_INSIDE at 4 and 8 lanes: the lanes' projected
 * corners through memory to watertight_edges_in_double(), lane by lane.
 * Out of line and cold: it runs for rays through edges and vertices. */
__attribute__((noinline, cold, unused)) static void watertight_edges_in_double_lanes(int lanes, int width,
                                                                                     const float *c, float *u,
                                                                                     float *v, float *w)
{
    for (int k = 0; k < width; k++)
        if (lanes >> k & 1)
            watertight_edges_in_double(c[k], c[width + k], c[2 * width + k], c[3 * width + k], c[4 * width + k],
                                       c[5 * width + k], &u[k], &v[k], &w[k]);
}

#define WATERTIGHT_IN_DOUBLE_WIDTH(V, P, WIDTH, lanes, ax, ay, bx, by, cx, cy, pu, pv, pw)                         \
    do {                                                                                                          \
        float c_[6 * (WIDTH)], u_[WIDTH], v_[WIDTH], w_[WIDTH];                                                   \
        P##_storeu_ps(c_, ax), P##_storeu_ps(c_ + (WIDTH), ay), P##_storeu_ps(c_ + 2 * (WIDTH), bx);              \
        P##_storeu_ps(c_ + 3 * (WIDTH), by), P##_storeu_ps(c_ + 4 * (WIDTH), cx), P##_storeu_ps(c_ + 5 * (WIDTH), cy); \
        P##_storeu_ps(u_, *(pu)), P##_storeu_ps(v_, *(pv)), P##_storeu_ps(w_, *(pw));                             \
        watertight_edges_in_double_lanes(lanes, WIDTH, c_, u_, v_, w_);                                           \
        *(pu) = P##_loadu_ps(u_), *(pv) = P##_loadu_ps(v_), *(pw) = P##_loadu_ps(w_);                             \
    } while (0)
#define WATERTIGHT_IN_DOUBLE4(lanes, ax, ay, bx, by, cx, cy, pu, pv, pw)                                          \
    WATERTIGHT_IN_DOUBLE_WIDTH(__m128, _mm, 4, lanes, ax, ay, bx, by, cx, cy, pu, pv, pw)
#define WATERTIGHT_IN_DOUBLE8(lanes, ax, ay, bx, by, cx, cy, pu, pv, pw)                                          \
    WATERTIGHT_IN_DOUBLE_WIDTH(__m256, _mm256, 8, lanes, ax, ay, bx, by, cx, cy, pu, pv, pw)

/* The comparisons the macros above use, the ordered ones (false for NaN)
 * for both widths. */
#define _mm_cmplt_ps_(a, b) _mm_cmplt_ps(a, b)
#define _mm_cmpgt_ps_(a, b) _mm_cmpgt_ps(a, b)
#define _mm_cmpeq_ps_(a, b) _mm_cmpeq_ps(a, b)
#define _mm256_cmplt_ps_(a, b) _mm256_cmp_ps(a, b, _CMP_LT_OQ)
#define _mm256_cmpgt_ps_(a, b) _mm256_cmp_ps(a, b, _CMP_GT_OQ)
#define _mm256_cmpeq_ps_(a, b) _mm256_cmp_ps(a, b, _CMP_EQ_OQ)

/* V t = watertight_plane_t() lane by lane, the same operations in the same
 * order, so the same float: the corners P0, P1, P2 and the ray's origin O
 * and direction D by coordinate x, y, z (not the ray's permuted axes). */
#define WATERTIGHT_PLANE_T(V, P, t, p0x, p0y, p0z, p1x, p1y, p1z, p2x, p2y, p2z, ox, oy, oz, dx, dy, dz)          \
    V t;                                                                                                          \
    do {                                                                                                          \
        V e1x_ = P##_sub_ps(p1x, p0x), e1y_ = P##_sub_ps(p1y, p0y), e1z_ = P##_sub_ps(p1z, p0z);                   \
        V e2x_ = P##_sub_ps(p2x, p0x), e2y_ = P##_sub_ps(p2y, p0y), e2z_ = P##_sub_ps(p2z, p0z);                   \
        V nx_ = P##_sub_ps(P##_mul_ps(e1y_, e2z_), P##_mul_ps(e1z_, e2y_));                                       \
        V ny_ = P##_sub_ps(P##_mul_ps(e1z_, e2x_), P##_mul_ps(e1x_, e2z_));                                       \
        V nz_ = P##_sub_ps(P##_mul_ps(e1x_, e2y_), P##_mul_ps(e1y_, e2x_));                                       \
        V sx_ = P##_sub_ps(p0x, ox), sy_ = P##_sub_ps(p0y, oy), sz_ = P##_sub_ps(p0z, oz);                         \
        V numerator_ = P##_add_ps(P##_add_ps(P##_mul_ps(sx_, nx_), P##_mul_ps(sy_, ny_)), P##_mul_ps(sz_, nz_));   \
        V denominator_ = P##_add_ps(P##_add_ps(P##_mul_ps(dx, nx_), P##_mul_ps(dy, ny_)), P##_mul_ps(dz, nz_));    \
        t = P##_div_ps(numerator_, denominator_);                                                                 \
    } while (0)

/* The same with N = (P1 - P0) x (P2 - P0) given (computed with
 * watertight_plane_t()'s operations, once per triangle): the same float. */
#define WATERTIGHT_PLANE_T_N(V, P, t, p0x, p0y, p0z, nx, ny, nz, ox, oy, oz, dx, dy, dz)                          \
    V t;                                                                                                          \
    do {                                                                                                          \
        V nx_ = (nx), ny_ = (ny), nz_ = (nz);                                                                     \
        V sx_ = P##_sub_ps(p0x, ox), sy_ = P##_sub_ps(p0y, oy), sz_ = P##_sub_ps(p0z, oz);                         \
        V numerator_ = P##_add_ps(P##_add_ps(P##_mul_ps(sx_, nx_), P##_mul_ps(sy_, ny_)), P##_mul_ps(sz_, nz_));   \
        V denominator_ = P##_add_ps(P##_add_ps(P##_mul_ps(dx, nx_), P##_mul_ps(dy, ny_)), P##_mul_ps(dz, nz_));    \
        t = P##_div_ps(numerator_, denominator_);                                                                 \
    } while (0)

#endif
