/* spawn_avx.h -- ray.h's ray_point_error(), ray_spawn() and ray_spawn_to()
 * for eight rays at once, one per lane of an AVX register
 * (path_tracer_wide.c).
 *
 * The same float operations in the same order as ray.h, so each lane gets
 * the very bits the one-ray functions give (test_spawn_avx_is_ray_h_bit_for_bit
 * in tests/test_ch13.c checks this, on hard cases too: coordinates at and
 * near zero, negative ones, far out, tiny and huge error bounds, normals
 * facing either way). ray.h's only branches, which way a normal faces,
 * become a sign flip by mask; |x| is a mask on the sign bit. Without fused
 * multiply-add (-ffp-contract=off, and the intrinsics below are plain
 * multiplies and adds) every product and sum rounds as in the scalar code.
 *
 * Points and vectors come as three registers, x, y and z of eight lanes. */
#ifndef SPAWN_AVX_H
#define SPAWN_AVX_H

#if defined(__x86_64__) && defined(__GNUC__)
#define SPAWN_HAVE_AVX2 1
#include <immintrin.h>

#include "ray.h"

/* AVX2 for the gathers of path_tracer_wide.c, which includes this. */
#define SPAWN_TARGET __attribute__((target("avx2")))

SPAWN_TARGET static inline __m256 spawn_dot8(const __m256 a[3], const __m256 b[3])
{
    return _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(a[0], b[0]), _mm256_mul_ps(a[1], b[1])),
                         _mm256_mul_ps(a[2], b[2]));
}

/* ray_point_error() */
SPAWN_TARGET static inline __m256 spawn_point_error8(const __m256 point[3], const __m256 n[3], __m256 size)
{
    const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
    __m256 p[3], m[3];
    for (int c = 0; c < 3; c++) {
        p[c] = _mm256_and_ps(point[c], abs_mask);
        m[c] = _mm256_and_ps(n[c], abs_mask);
    }
    __m256 across = spawn_dot8(p, m);
    return _mm256_mul_ps(_mm256_set1_ps(RAY_FLOAT_ROUNDING),
                         _mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(OFFSET_POINT_ROUNDINGS), across),
                                       _mm256_mul_ps(_mm256_set1_ps(OFFSET_SIZE_ROUNDINGS), size)));
}

/* ray_offset_origin() */
SPAWN_TARGET static inline void spawn_offset_origin8(const __m256 point[3], __m256 error, const __m256 side[3],
                                                     __m256 out[3])
{
    for (int c = 0; c < 3; c++)
        out[c] = _mm256_add_ps(point[c], _mm256_mul_ps(side[c], error));
}

/* n, or -n in the lanes of `flip` */
SPAWN_TARGET static inline void spawn_flip8(const __m256 n[3], __m256 flip, __m256 out[3])
{
    const __m256 sign = _mm256_and_ps(flip, _mm256_set1_ps(-0.0f));
    for (int c = 0; c < 3; c++)
        out[c] = _mm256_xor_ps(n[c], sign);
}

/* ray_spawn(): the origin and t_min of the ray leaving `point` (error
 * bound `error`, geometric normal n) in `direction`. */
SPAWN_TARGET static inline void ray_spawn8(const __m256 point[3], __m256 error, const __m256 n[3],
                                           const __m256 direction[3], __m256 origin[3], __m256 *t_min)
{
    __m256 side[3];
    spawn_flip8(n, _mm256_cmp_ps(spawn_dot8(direction, n), _mm256_setzero_ps(), _CMP_LT_OQ), side);
    spawn_offset_origin8(point, error, side, origin);
    *t_min = _mm256_div_ps(error, _mm256_sqrt_ps(spawn_dot8(direction, direction)));
}

/* ray_spawn_to(): the shadow ray from `point` to `target` on a surface
 * with normal target_normal (non-zero in every lane): its origin,
 * direction, t_min and t_max. */
SPAWN_TARGET static inline void ray_spawn_to8(const __m256 point[3], __m256 error, const __m256 n[3],
                                              const __m256 target[3], __m256 target_error,
                                              const __m256 target_normal[3], __m256 origin[3], __m256 direction[3],
                                              __m256 *t_min, __m256 *t_max)
{
    const __m256 zero = _mm256_setzero_ps();
    __m256 to_target[3], side[3], target_side[3], back[3], far_end[3];
    for (int c = 0; c < 3; c++)
        to_target[c] = _mm256_sub_ps(target[c], point[c]);
    __m256 length = _mm256_sqrt_ps(spawn_dot8(to_target, to_target));
    spawn_flip8(n, _mm256_cmp_ps(spawn_dot8(to_target, n), zero, _CMP_LT_OQ), side);
    spawn_offset_origin8(point, error, side, origin);
    for (int c = 0; c < 3; c++)
        back[c] = _mm256_sub_ps(origin[c], target[c]);
    spawn_flip8(target_normal, _mm256_cmp_ps(spawn_dot8(back, target_normal), zero, _CMP_LT_OQ), target_side);
    /* ray_far_end_pull(target_error, |to_target|) */
    __m256 pull = _mm256_add_ps(target_error,
                                _mm256_mul_ps(_mm256_set1_ps(OFFSET_SIZE_ROUNDINGS * RAY_FLOAT_ROUNDING), length));
    spawn_offset_origin8(target, pull, target_side, far_end);
    for (int c = 0; c < 3; c++)
        direction[c] = _mm256_sub_ps(far_end[c], origin[c]);
    /* t_min, t_max, and the empty segment where the length is 0 */
    __m256 some = _mm256_cmp_ps(length, zero, _CMP_GT_OQ);
    __m256 per_length = _mm256_div_ps(_mm256_set1_ps(1.0f), length);
    *t_min = _mm256_blendv_ps(zero, _mm256_mul_ps(error, per_length), some);
    *t_max = _mm256_blendv_ps(_mm256_set1_ps(-INFINITY),
                              _mm256_sub_ps(_mm256_set1_ps(1.0f), _mm256_mul_ps(pull, per_length)), some);
}

#else
#define SPAWN_HAVE_AVX2 0
#endif

#endif
