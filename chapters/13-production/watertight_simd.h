/* watertight_simd.h -- parts of chapter 01's watertight triangle test
 * (shapes.h) written once for every vector width, so that the kernels of
 * bvh4_traverse.c and flat.c (SSE, AVX, AVX-512 registers) cannot drift
 * apart from the scalar test or from each other: V is the vector type, P
 * the intrinsics' prefix (_mm, _mm256). Included after <immintrin.h>. */
#ifndef WATERTIGHT_SIMD_H
#define WATERTIGHT_SIMD_H

#include "01-ray-casting/shapes.h"

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

#endif
