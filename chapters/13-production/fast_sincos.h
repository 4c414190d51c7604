/* fast_sincos.h -- sin and cos of an angle given in turns, by a fitted
 * polynomial: what the production renderer uses for the azimuth phi = 2 pi u
 * of its hemisphere and disk samples. The lecture's samplers (chapter 08,
 * sampling.h) call libm's sinf and cosf of 2 pi u instead.
 *
 * Usage:
 *   float s, c;
 *   fast_sincos_turns(u, &s, &c);   s = sin(2 pi u), c = cos(2 pi u), u in [0, 1]
 */
#ifndef FAST_SINCOS_H
#define FAST_SINCOS_H

#include <stdint.h>
#include <string.h>

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

#endif
