/* sobol_sampler.c -- Sobol's sequence in SOBOL_DIMENSIONS dimensions, Owen
 * scrambled, as a source of a path's numbers (see sobol_sampler.h). */
#include "09-path-tracing/sobol_sampler.h"

#include <threads.h>

#include "08-monte-carlo/estimators.h"

/* ---- the sequence -------------------------------------------------------------
 * Dimension d of point i is the xor of the direction numbers v_k of d over
 * the set bits k of i (chapter 08's sobol_bits, in two dimensions). Sobol's
 * recipe for v_k: a primitive polynomial x^s + a_1 x^(s-1) + ... + 1 per
 * dimension, the first s direction numbers v_k = m_k / 2^k (m_k odd, below
 * 2^k) chosen freely, and the rest by the polynomial's recurrence
 *   v_k = a_1 v_(k-1) xor ... xor a_(s-1) v_(k-s+1) xor v_(k-s) xor v_(k-s) / 2^s.
 * Any odd m_k give a sequence whose first 2^m points are a net; which ones
 * decides how evenly pairs of dimensions fill the square. These are Joe and
 * Kuo's (2008, the file new-joe-kuo-6.21201), chosen so that the
 * two-dimensional projections are as even as they could make them: for
 * dimensions 1 to 63, the degree s, the bits a_1 .. a_(s-1) of a (a_1 the
 * highest), and m_1 .. m_s. */
typedef struct {
    uint8_t degree;
    uint8_t a;
    uint16_t m[9];
} sobol_direction_seed;

static const sobol_direction_seed JOE_KUO[SOBOL_DIMENSIONS - 1] = {
    {1, 0, {1}}, {2, 1, {1, 3}}, {3, 1, {1, 3, 1}}, {3, 2, {1, 1, 1}}, {4, 1, {1, 1, 3, 3}}, {4, 4, {1, 3, 5, 13}},
    {5, 2, {1, 1, 5, 5, 17}}, {5, 4, {1, 1, 5, 5, 5}}, {5, 7, {1, 1, 7, 11, 19}}, {5, 11, {1, 1, 5, 1, 1}},
    {5, 13, {1, 1, 1, 3, 11}}, {5, 14, {1, 3, 5, 5, 31}}, {6, 1, {1, 3, 3, 9, 7, 49}},
    {6, 13, {1, 1, 1, 15, 21, 21}}, {6, 16, {1, 3, 1, 13, 27, 49}}, {6, 19, {1, 1, 1, 15, 7, 5}},
    {6, 22, {1, 3, 1, 15, 13, 25}}, {6, 25, {1, 1, 5, 5, 19, 61}}, {7, 1, {1, 3, 7, 11, 23, 15, 103}},
    {7, 4, {1, 3, 7, 13, 13, 15, 69}}, {7, 7, {1, 1, 3, 13, 7, 35, 63}}, {7, 8, {1, 3, 5, 9, 1, 25, 53}},
    {7, 14, {1, 3, 1, 13, 9, 35, 107}}, {7, 19, {1, 3, 1, 5, 27, 61, 31}}, {7, 21, {1, 1, 5, 11, 19, 41, 61}},
    {7, 28, {1, 3, 5, 3, 3, 13, 69}}, {7, 31, {1, 1, 7, 13, 1, 19, 1}}, {7, 32, {1, 3, 7, 5, 13, 19, 59}},
    {7, 37, {1, 1, 3, 9, 25, 29, 41}}, {7, 41, {1, 3, 5, 13, 23, 1, 55}}, {7, 42, {1, 3, 7, 3, 13, 59, 17}},
    {7, 50, {1, 3, 1, 3, 5, 53, 69}}, {7, 55, {1, 1, 5, 5, 23, 33, 13}}, {7, 56, {1, 1, 7, 7, 1, 61, 123}},
    {7, 59, {1, 1, 7, 9, 13, 61, 49}}, {7, 62, {1, 3, 3, 5, 3, 55, 33}}, {8, 14, {1, 3, 1, 15, 31, 13, 49, 245}},
    {8, 21, {1, 3, 5, 15, 31, 59, 63, 97}}, {8, 22, {1, 3, 1, 11, 11, 11, 77, 249}},
    {8, 38, {1, 3, 1, 11, 27, 43, 71, 9}}, {8, 47, {1, 1, 7, 15, 21, 11, 81, 45}},
    {8, 49, {1, 3, 7, 3, 25, 31, 65, 79}}, {8, 50, {1, 3, 1, 1, 19, 11, 3, 205}},
    {8, 52, {1, 1, 5, 9, 19, 21, 29, 157}}, {8, 56, {1, 3, 7, 11, 1, 33, 89, 185}},
    {8, 67, {1, 3, 3, 3, 15, 9, 79, 71}}, {8, 70, {1, 3, 7, 11, 15, 39, 119, 27}},
    {8, 84, {1, 1, 3, 1, 11, 31, 97, 225}}, {8, 97, {1, 1, 1, 3, 23, 43, 57, 177}},
    {8, 103, {1, 3, 7, 7, 17, 17, 37, 71}}, {8, 115, {1, 3, 1, 5, 27, 63, 123, 213}},
    {8, 122, {1, 1, 3, 5, 11, 43, 53, 133}}, {9, 8, {1, 3, 5, 5, 29, 17, 47, 173, 479}},
    {9, 13, {1, 3, 3, 11, 3, 1, 109, 9, 69}}, {9, 16, {1, 1, 1, 5, 17, 39, 23, 5, 343}},
    {9, 22, {1, 3, 1, 5, 25, 15, 31, 103, 499}}, {9, 25, {1, 1, 1, 11, 11, 17, 63, 105, 183}},
    {9, 44, {1, 1, 5, 11, 9, 29, 97, 231, 363}}, {9, 47, {1, 1, 5, 15, 19, 45, 41, 7, 383}},
    {9, 52, {1, 3, 7, 7, 31, 19, 83, 137, 221}}, {9, 55, {1, 1, 1, 3, 23, 15, 111, 223, 83}},
    {9, 59, {1, 1, 5, 13, 31, 15, 55, 25, 161}}, {9, 62, {1, 1, 3, 13, 25, 47, 39, 87, 257}}
};

uint32_t sobol_polynomial(int dimension, int *degree)
{
    if (dimension == 0) { /* the van der Corput sequence's generator matrix is the identity: x */
        *degree = 1;
        return 2u;
    }
    const sobol_direction_seed *p = &JOE_KUO[dimension - 1];
    *degree = p->degree;
    return (1u << p->degree) | ((uint32_t)p->a << 1) | 1u;
}

/* v_1 .. v_32 of every dimension, as 32-bit fractions, made once: a path
 * draws thirty numbers or more, and the recurrence for each would cost
 * more than the rest of the number. */
static uint32_t directions[SOBOL_DIMENSIONS][32];
static once_flag directions_made = ONCE_FLAG_INIT;

static void make_directions(void)
{
    for (int k = 0; k < 32; k++) /* dimension 0: chapter 08's, v_k = 1 / 2^k */
        directions[0][k] = sobol_bits(1u << k, 0);
    for (int d = 1; d < SOBOL_DIMENSIONS; d++) {
        const sobol_direction_seed *p = &JOE_KUO[d - 1];
        const int s = p->degree;
        uint32_t *v = directions[d];
        for (int k = 0; k < 32; k++) {
            if (k < s) {
                v[k] = (uint32_t)p->m[k] << (31 - k); /* m_(k+1) / 2^(k+1) */
                continue;
            }
            v[k] = v[k - s] ^ (v[k - s] >> s);
            for (int j = 1; j < s; j++)
                if ((p->a >> (s - 1 - j)) & 1u)
                    v[k] ^= v[k - j];
        }
    }
}

const uint32_t *sobol_direction_numbers(int dimension)
{
    call_once(&directions_made, make_directions);
    return directions[dimension];
}

uint32_t sobol_sequence_bits(uint32_t index, int dimension)
{
    const uint32_t *v = sobol_direction_numbers(dimension);
    uint32_t result = 0;
    for (int k = 0; index != 0; k++, index >>= 1)
        if (index & 1u)
            result ^= v[k];
    return result;
}

/* ---- one sample's numbers -------------------------------------------------------- */

/* SplitMix64's finaliser (as rng.c's): neighbouring inputs, unrelated outputs. */
static uint64_t mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

/* 2^64 / golden ratio: consecutive dimensions' keys land far apart. */
static const uint64_t GOLDEN_GAMMA = 0x9e3779b97f4a7c15ULL;
/* Set apart from the pixel's pcg32 seeding (rng.c hashes the same seed and
 * pixel), so that the scrambles are not a function of the stream's start. */
static const uint64_t SOBOL_KEY_SALT = 0x50b01c0ffee5eedULL;

sobol_sampler sobol_sampler_start(uint64_t seed, uint64_t pixel, uint32_t index, pcg32 *rng)
{
    sobol_sampler s = {.key = mix64(seed ^ mix64(pixel ^ SOBOL_KEY_SALT)), .index = index, .dimension = 0, .rng = rng};
    return s;
}

/* The dimension's scramble, the same for every sample of the pixel:
 * Owen's (chapter 08's owen_scramble) keeps the nets, and a random xor on
 * top (a digital shift) makes the point exactly uniform, whatever the
 * hash's quality, as in chapter 08's points_sobol_owen. */
sobol_scramble sobol_sampler_scramble(const sobol_sampler *s, int dimension)
{
    uint64_t h = mix64(s->key + (uint64_t)(dimension + 1) * GOLDEN_GAMMA);
    return (sobol_scramble){.owen_seed = (uint32_t)h, .shift = (uint32_t)(h >> 32)};
}

float sobol_sampler_next(void *state)
{
    sobol_sampler *s = state;
    int d = s->dimension++;
    if (d >= SOBOL_DIMENSIONS)
        return pcg32_float(s->rng);
    sobol_scramble scramble = sobol_sampler_scramble(s, d);
    uint32_t bits = owen_scramble(sobol_sequence_bits(s->index, d), scramble.owen_seed) ^ scramble.shift;
    return (float)(bits >> 8) * 0x1.0p-24f; /* the top 24 bits, as pcg32_float: never 1 */
}
