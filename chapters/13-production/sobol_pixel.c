/* sobol_pixel.c -- a pixel's Sobol points one after another (sobol_pixel.h). */
#include "13-production/sobol_pixel.h"

#include <string.h>
#include <threads.h>

#include "08-monte-carlo/estimators.h"

/* step[c][d]: what coordinate d changes by when the index goes from i to
 * i + 1 and i ends in c ones: v_1 xor ... xor v_(c+1) of dimension d,
 * reversed as the points are. By count, then by dimension, so that a step
 * reads one row. */
static _Alignas(32) uint32_t step[32][SOBOL_DIMENSIONS];
static once_flag steps_made = ONCE_FLAG_INIT;
static bool have_avx2; /* the processor's, asked once */
static bool cpu_has_avx2(void);

static void make_steps(void)
{
    have_avx2 = cpu_has_avx2();
    for (int d = 0; d < SOBOL_DIMENSIONS; d++) {
        const uint32_t *v = sobol_direction_numbers(d);
        uint32_t flips = 0;
        for (int c = 0; c < 32; c++) {
            flips ^= v[c];
            step[c][d] = reverse_bits(flips);
        }
    }
}

void sobol_pixel_start(sobol_pixel *s, uint64_t seed, uint64_t pixel, uint32_t index, pcg32 *rng)
{
    call_once(&steps_made, make_steps);
    if (index == 0) /* every coordinate of point 0 is 0 */
        memset(s->point_reversed, 0, sizeof s->point_reversed);
    else
        for (int d = 0; d < SOBOL_DIMENSIONS; d++)
            s->point_reversed[d] = reverse_bits(sobol_sequence_bits(index, d));
    s->key = sobol_sampler_start(seed, pixel, index, rng);
    s->scrambled = 0;
    s->ready = 0;
    s->index = index;
    s->dimension = 0;
    s->rng = rng;
}

void sobol_pixel_next_sample(sobol_pixel *s)
{
    /* trailing ones of i: trailing zeros of ~i (i = 2^32 - 1 wraps to 0,
     * all 32 bits flipped) */
    uint32_t flipped = ~s->index;
    int c = flipped == 0 ? 31 : __builtin_ctz(flipped);
    const uint32_t *row = step[c];
    for (int d = 0; d < SOBOL_DIMENSIONS; d++)
        s->point_reversed[d] ^= row[d];
    s->index++;
    s->ready = 0;
    s->dimension = 0;
}

/* ---- eight dimensions' numbers at once ------------------------------------------
 * sobol_sampler_next()'s arithmetic, owen_scramble() and the shift, on
 * eight lanes of 32-bit integers (GCC's vector types: AVX2 in the function
 * compiled for it, SSE2 pairs in the other). Integer steps and an exact
 * conversion (24 bits into a float), so every lane gets the scalar bits. */
typedef uint32_t u32x8 __attribute__((vector_size(32)));
typedef int32_t i32x8 __attribute__((vector_size(32)));
typedef float f32x8 __attribute__((vector_size(32)));

/* reverse_bits() on eight lanes (a macro: a function returning a vector
 * type would have a different ABI with and without AVX) */
#define REVERSE_BITS8(x)                                                        \
    do {                                                                        \
        x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);                \
        x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);                \
        x = ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);                \
        x = ((x >> 8) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8);                \
        x = (x >> 16) | (x << 16);                                              \
    } while (0)

static inline __attribute__((always_inline)) void numbers8(sobol_pixel *s, int first)
{
    u32x8 x, seed, shift;
    memcpy(&x, &s->point_reversed[first], sizeof x);
    memcpy(&seed, &s->owen_seed[first], sizeof seed);
    memcpy(&shift, &s->shift[first], sizeof shift);
    x ^= x * 0x3d20adeau; /* owen_scramble_reversed's steps */
    x += seed;
    x *= (seed >> 16) | 1u;
    x ^= x * 0x05526c56u;
    x ^= x * 0x53a22864u;
    REVERSE_BITS8(x);
    x ^= shift;
    f32x8 u = __builtin_convertvector((i32x8)(x >> 8), f32x8) * 0x1.0p-24f; /* the top 24 bits */
    memcpy(&s->number[first], &u, sizeof u);
}

static void numbers8_plain(sobol_pixel *s, int first) { numbers8(s, first); }

#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
__attribute__((target("avx2"))) static void numbers8_avx2(sobol_pixel *s, int first) { numbers8(s, first); }
static bool cpu_has_avx2(void) { return __builtin_cpu_supports("avx2"); }
#else
#define numbers8_avx2 numbers8_plain
static bool cpu_has_avx2(void) { return false; }
#endif

/* One dimension at a time: the scalar functions, for the twin of the
 * vector path and for processors without AVX2. */
static void numbers1(sobol_pixel *s, int first)
{
    for (int d = first; d < first + SOBOL_PIXEL_BLOCK; d++) {
        uint32_t bits = reverse_bits(owen_scramble_reversed(s->point_reversed[d], s->owen_seed[d])) ^ s->shift[d];
        s->number[d] = (float)(bits >> 8) * 0x1.0p-24f;
    }
}

static bool use_simd = true;
void sobol_pixel_use_simd(bool on) { use_simd = on; }

_Static_assert(SOBOL_DIMENSIONS % SOBOL_PIXEL_BLOCK == 0, "whole blocks");

void sobol_pixel_fill(sobol_pixel *s, int d)
{
    int first = d - d % SOBOL_PIXEL_BLOCK, end = first + SOBOL_PIXEL_BLOCK;
    for (int k = s->scrambled; k < end; k++) { /* the pixel's first draw this far */
        sobol_scramble scramble = sobol_sampler_scramble(&s->key, k);
        s->owen_seed[k] = scramble.owen_seed;
        s->shift[k] = scramble.shift;
    }
    if (s->scrambled < end)
        s->scrambled = end;
    if (!use_simd)
        numbers1(s, first);
    else if (have_avx2)
        numbers8_avx2(s, first);
    else
        numbers8_plain(s, first);
    s->ready = end;
}
