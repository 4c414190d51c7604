/* spawn_avx.h -- ray.h's ray_spawn() and ray_spawn_to() for eight rays at
 * once, one per lane of an AVX2 register (path_tracer_wide.c).
 *
 * The same float operations in the same order as ray.h, so each lane gets
 * the very bits the one-ray functions give (test_spawn_avx_is_ray_h_bit_for_bit
 * in tests/test_ch09.c checks this, on hard cases too: coordinates near and
 * at zero, negative ones, normals facing either way). ray.h's branches
 * become masks and blends: "p < 0 ? -ulps : ulps" is (ulps ^ m) - m with m
 * the sign of p spread over the lane, "|p| < 1/32 ? fixed : ulps" a blend.
 * Moving a float by whole ulps is an integer add on its bits, which is why
 * this needs AVX2 (AVX has no 256-bit integer add).
 *
 * Points and vectors come as three registers, x, y and z of eight lanes. */
#ifndef SPAWN_AVX_H
#define SPAWN_AVX_H

#if defined(__x86_64__) && defined(__GNUC__)
#define SPAWN_HAVE_AVX2 1
#include <immintrin.h>

#include "ray.h"

#define SPAWN_TARGET __attribute__((target("avx2")))

SPAWN_TARGET static inline __m256 spawn_dot8(const __m256 a[3], const __m256 b[3])
{
    return _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(a[0], b[0]), _mm256_mul_ps(a[1], b[1])),
                         _mm256_mul_ps(a[2], b[2]));
}

/* ray_offset_coordinate() */
SPAWN_TARGET static inline __m256 spawn_offset_coordinate8(__m256 p, __m256 n)
{
    const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
    __m256 near_zero = _mm256_cmp_ps(_mm256_and_ps(p, abs_mask), _mm256_set1_ps(ORIGIN_NEAR_ZERO), _CMP_LT_OQ);
    __m256 fixed = _mm256_add_ps(p, _mm256_mul_ps(_mm256_set1_ps(ORIGIN_FIXED_OFFSET), n));
    __m256i ulps = _mm256_cvttps_epi32(_mm256_mul_ps(_mm256_set1_ps(ORIGIN_OFFSET_ULPS), n));
    __m256i bits = _mm256_castps_si256(p);
    __m256i negative = _mm256_srai_epi32(bits, 31); /* all ones where p < 0 (|p| >= 1/32 here: no -0) */
    __m256i moved = _mm256_add_epi32(bits, _mm256_sub_epi32(_mm256_xor_si256(ulps, negative), negative));
    return _mm256_blendv_ps(_mm256_castsi256_ps(moved), fixed, near_zero);
}

/* ray_offset_origin() */
SPAWN_TARGET static inline void spawn_offset_origin8(const __m256 p[3], const __m256 n[3], __m256 out[3])
{
    for (int c = 0; c < 3; c++)
        out[c] = spawn_offset_coordinate8(p[c], n[c]);
}

/* n, or -n in the lanes of `flip` */
SPAWN_TARGET static inline void spawn_flip8(const __m256 n[3], __m256 flip, __m256 out[3])
{
    const __m256 sign = _mm256_and_ps(flip, _mm256_set1_ps(-0.0f));
    for (int c = 0; c < 3; c++)
        out[c] = _mm256_xor_ps(n[c], sign);
}

/* ray_spawn(): the origin of the ray leaving `point` (geometric normal n)
 * in `direction`. */
SPAWN_TARGET static inline void ray_spawn8(const __m256 point[3], const __m256 n[3], const __m256 direction[3],
                                           __m256 origin[3])
{
    __m256 side[3];
    spawn_flip8(n, _mm256_cmp_ps(spawn_dot8(direction, n), _mm256_setzero_ps(), _CMP_LT_OQ), side);
    spawn_offset_origin8(point, side, origin);
}

/* ray_spawn_to(): the shadow ray from `point` to `target` on a surface
 * with normal target_normal (non-zero in every lane), t from 0 to 1. */
SPAWN_TARGET static inline void ray_spawn_to8(const __m256 point[3], const __m256 n[3], const __m256 target[3],
                                              const __m256 target_normal[3], __m256 origin[3], __m256 direction[3])
{
    const __m256 zero = _mm256_setzero_ps();
    __m256 to_target[3], side[3], target_side[3], back[3], far_end[3], moved[3];
    for (int c = 0; c < 3; c++)
        to_target[c] = _mm256_sub_ps(target[c], point[c]);
    spawn_flip8(n, _mm256_cmp_ps(spawn_dot8(to_target, n), zero, _CMP_LT_OQ), side);
    spawn_offset_origin8(point, side, origin);
    for (int c = 0; c < 3; c++)
        back[c] = _mm256_sub_ps(origin[c], target[c]);
    spawn_flip8(target_normal, _mm256_cmp_ps(spawn_dot8(back, target_normal), zero, _CMP_LT_OQ), target_side);
    /* ray_offset_far_end(target, target_side, |to_target|) */
    __m256 length = _mm256_sqrt_ps(spawn_dot8(to_target, to_target));
    spawn_offset_origin8(target, target_side, far_end);
    __m256 minimum = _mm256_mul_ps(length, _mm256_set1_ps(ORIGIN_OFFSET_ULPS * 0x1.0p-24f));
    for (int c = 0; c < 3; c++)
        moved[c] = _mm256_sub_ps(far_end[c], target[c]);
    __m256 far_enough = _mm256_cmp_ps(spawn_dot8(moved, target_side), minimum, _CMP_GE_OQ);
    for (int c = 0; c < 3; c++) {
        __m256 pushed = _mm256_add_ps(target[c], _mm256_mul_ps(target_side[c], minimum));
        direction[c] = _mm256_sub_ps(_mm256_blendv_ps(pushed, far_end[c], far_enough), origin[c]);
    }
}

#else
#define SPAWN_HAVE_AVX2 0
#endif

#endif
