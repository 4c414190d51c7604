/* fast_sincos.h -- sin and cos of an angle given in turns, by a fitted
 * polynomial: what the production renderer uses for the azimuth phi = 2 pi u
 * of its hemisphere and disk samples. The lecture's samplers (chapter 08,
 * sampling.h) call libm's sinf and cosf of 2 pi u instead.
 *
 * Usage:
 *   float s, c;
 *   fast_sincos_turns(u, &s, &c);   s = sin(2 pi u), c = cos(2 pi u), u in [0, 1]
 *   vec3 local = sample_cosine_hemisphere_fast(u_x, u_y);   z up, as chapter 08's
 */
#ifndef FAST_SINCOS_H
#define FAST_SINCOS_H

#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "vec3.h"

/* sin and cos of 2 pi u, for u in [0, 1]. Why not sinf(2 pi u)? Two reasons.
 *  - Accuracy. 2 pi u rounded to a float is up to 2.4e-7 away from the
 *    angle meant before sinf sees it; sinf(2 pi u) and cosf(2 pi u) in
 *    float are up to 4.1e-7 from the exact values (measured over every
 *    float u in [0, 1)). Here u is split exactly into
 *    quarter turns q/4 and a rest r in [-1/8, 1/8] (u - q/4 loses no bit),
 *    and sin(2 pi r), cos(2 pi r) come from two short polynomials in r,
 *    fitted on that interval (least squares at Chebyshev nodes, reweighted
 *    towards the largest error). The quarter turns then only swap and
 *    negate. At most 2.1 ulp from the exact sine and cosine of 2 pi u
 *    (9.3e-8 absolute); u = 0, 1/4, 1/2, 3/4 give 0 and +-1 exactly.
 *  - Speed, and the same bits everywhere. It is a few multiplies and adds
 *    in a fixed order, with no table and no branch on u, so the same
 *    operations on the eight lanes of a vector register give the same bits
 *    as this scalar code, which libm's sincosf cannot promise. */
static inline void fast_sincos_turns(float u, float *sin_out, float *cos_out)
{
    float q = (float)(int)(4.0f * u + 0.5f); /* the nearest quarter turn, 0..4 */
    float r = u - 0.25f * q;                 /* exact */
    float r2 = r * r;
    /* sin(2 pi r) = r (2 pi + r^2 P(r^2)), cos(2 pi r) = 1 + r^2 Q(r^2) */
    float p = (((0x1.4bbc38p+5f * r2 - 0x1.32ca6cp+6f) * r2 + 0x1.466bbap+6f) * r2 - 0x1.4abbcep+5f) * r2;
    float sin_r = r * 0x1.921fb6p+2f + r * p;
    float cos_r = 1.0f + (((0x1.d9f7b2p+5f * r2 - 0x1.55c664p+6f) * r2 + 0x1.03c1dep+6f) * r2 - 0x1.3bd3ccp+4f) * r2;
    /* Each quarter turn more maps (sin, cos) to (cos, -sin): an odd quarter
     * swaps the two, quarters 2 and 3 negate the sine, 1 and 2 the cosine.
     * Done on the bits, because the quarter is as random as u and branches
     * on it would be mispredicted half the time. */
    uint32_t quarter = (uint32_t)q, s, c;
    memcpy(&s, &sin_r, sizeof s);
    memcpy(&c, &cos_r, sizeof c);
    uint32_t swap = (s ^ c) & (0u - (quarter & 1u));
    s ^= swap ^ (quarter & 2u) << 30;
    c ^= swap ^ ((quarter + 1u) & 2u) << 30;
    memcpy(sin_out, &s, sizeof s);
    memcpy(cos_out, &c, sizeof c);
}

/* Chapter 08's sample_uniform_hemisphere(), its azimuth by
 * fast_sincos_turns(): z = u_x, r = sqrt(max(0, 1 - z^2)), phi = 2 pi u_y.
 * The eight-path renderer's diffuse bounce on the lecture rung, as its AVX
 * kernel computes it, operation for operation. */
static inline vec3 sample_uniform_hemisphere_fast(float u_x, float u_y)
{
    float z = u_x, r = sqrtf(fmaxf(1.0f - z * z, 0.0f)), sin_phi, cos_phi;
    fast_sincos_turns(u_y, &sin_phi, &cos_phi);
    return vec3_make(r * cos_phi, r * sin_phi, z);
}

/* Chapter 08's sample_cosine_hemisphere() (the concentric map of the unit
 * square onto the disk, lifted to the hemisphere), its angle by
 * fast_sincos_turns(), as the AVX kernel computes it. The left and right
 * triangles' angle pi/4 (oy / ox) is (oy / ox) / 8 of a turn; the top and
 * bottom ones' pi/2 - pi/4 (ox / oy) has the sine and cosine of
 * (ox / oy) / 8 of a turn swapped. Those turns lie in [-1/8, 1/8], where
 * the polynomial was fitted. The centre, 0 / 0, is ratio 0 there: the
 * point (0, 0) and z = 1, as chapter 08 has it. */
static inline vec3 sample_cosine_hemisphere_fast(float u_x, float u_y)
{
    float ox = 2.0f * u_x - 1.0f, oy = 2.0f * u_y - 1.0f;
    bool sides = fabsf(ox) > fabsf(oy);
    float r = sides ? ox : oy;
    float ratio = sides ? oy / ox : oy != 0.0f ? ox / oy : 0.0f;
    float u = sides ? u_x : u_y, rest = 1.0f - u;
    float one_minus_r = 2.0f * (u < rest ? u : rest); /* 1 - |r|, without cancellation */
    float s, c;
    fast_sincos_turns(0.125f * ratio, &s, &c);
    float z2 = one_minus_r * (2.0f - one_minus_r);
    return vec3_make(r * (sides ? c : s), r * (sides ? s : c), sqrtf(z2 > 0.0f ? z2 : 0.0f));
}

#endif
