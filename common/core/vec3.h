/* vec3.h -- three floats and the handful of operations a ray tracer needs.
 *
 * Usage: #include "vec3.h"; every function is a small static inline on
 * values (no macros, so no argument is evaluated twice). Geometry is float;
 * accumulation across samples is done in double elsewhere (see render.h).
 */
#ifndef VEC3_H
#define VEC3_H

#include <math.h>
#include <stdbool.h>

#define PI 3.14159265358979323846

typedef struct {
    float x, y, z;
} vec3;

static inline vec3 vec3_make(float x, float y, float z) { return (vec3){x, y, z}; }
static inline vec3 vec3_splat(float s) { return (vec3){s, s, s}; }
static inline vec3 vec3_add(vec3 a, vec3 b) { return (vec3){a.x + b.x, a.y + b.y, a.z + b.z}; }
static inline vec3 vec3_sub(vec3 a, vec3 b) { return (vec3){a.x - b.x, a.y - b.y, a.z - b.z}; }
/* Component-wise product: colour times colour (albedo * radiance). */
static inline vec3 vec3_mul(vec3 a, vec3 b) { return (vec3){a.x * b.x, a.y * b.y, a.z * b.z}; }
static inline vec3 vec3_scale(vec3 a, float s) { return (vec3){a.x * s, a.y * s, a.z * s}; }
static inline vec3 vec3_neg(vec3 a) { return (vec3){-a.x, -a.y, -a.z}; }
static inline float vec3_dot(vec3 a, vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline vec3 vec3_cross(vec3 a, vec3 b)
{
    return (vec3){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
static inline float vec3_length_squared(vec3 a) { return vec3_dot(a, a); }
static inline float vec3_length(vec3 a) { return sqrtf(vec3_dot(a, a)); }
static inline vec3 vec3_normalize(vec3 a) { return vec3_scale(a, 1.0f / vec3_length(a)); }
static inline vec3 vec3_min(vec3 a, vec3 b) { return (vec3){fminf(a.x, b.x), fminf(a.y, b.y), fminf(a.z, b.z)}; }
static inline vec3 vec3_max(vec3 a, vec3 b) { return (vec3){fmaxf(a.x, b.x), fmaxf(a.y, b.y), fmaxf(a.z, b.z)}; }
static inline vec3 vec3_abs(vec3 a) { return (vec3){fabsf(a.x), fabsf(a.y), fabsf(a.z)}; }
static inline float vec3_max_component(vec3 a) { return fmaxf(a.x, fmaxf(a.y, a.z)); }
/* Axis by index (0 = x, 1 = y, 2 = z), for code that loops over the three slabs. */
static inline float vec3_axis(vec3 a, int axis) { return axis == 0 ? a.x : axis == 1 ? a.y : a.z; }
static inline vec3 vec3_lerp(vec3 a, vec3 b, float t) { return vec3_add(vec3_scale(a, 1.0f - t), vec3_scale(b, t)); }
/* All three channels exactly 0: a BSDF value or weight that adds nothing
 * (so no ray needs tracing for it). */
static inline bool vec3_is_black(vec3 c) { return c.x == 0.0f && c.y == 0.0f && c.z == 0.0f; }
static inline int vec3_is_finite(vec3 a) { return isfinite(a.x) && isfinite(a.y) && isfinite(a.z); }
/* Luminance of a linear-sRGB colour (Rec. 709 weights). */
static inline float vec3_luminance(vec3 c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

/* Mirror reflection of incident direction d about unit normal n: d - 2 (d.n) n. */
static inline vec3 vec3_reflect(vec3 d, vec3 n)
{
    /* exercise: reflect */
    return vec3_sub(d, vec3_scale(n, 2.0f * vec3_dot(d, n)));
    /* end of exercise reflect */
}

/* An orthonormal basis (t, b, n) around unit n, without a branchy "pick an
 * axis" step: Duff et al., "Building an Orthonormal Basis, Revisited" (2017). */
static inline void vec3_basis(vec3 n, vec3 *t, vec3 *b)
{
    float sign = copysignf(1.0f, n.z);
    float a = -1.0f / (sign + n.z);
    float c = n.x * n.y * a;
    *t = (vec3){1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x};
    *b = (vec3){c, sign + n.y * n.y * a, -n.y};
}

#endif
