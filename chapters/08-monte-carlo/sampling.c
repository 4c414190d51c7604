/* sampling.c -- sample / pdf / invert for each distribution (see sampling.h).
 *
 * Every warp here comes from the inversion method: write the density in
 * coordinates where it factors, integrate to get the cumulative distribution
 * of the first coordinate (the marginal) and of the second given the first
 * (the conditional), and set each equal to a uniform number. The chapter
 * text derives each one; the comments name the step. */
#include "08-monte-carlo/sampling.h"

#include <math.h>
#include <stdlib.h>

#include "memory.h"

static const float TWO_PI_F = (float)(2.0 * PI);
static const float INV_PI_F = (float)(1.0 / PI);
static const float INV_TWO_PI_F = (float)(0.5 / PI);
static const float PI_OVER_4_F = (float)(PI / 4.0);
static const float PI_OVER_2_F = (float)(PI / 2.0);

/* The largest float below 1: where an inverse that rounds up to 1 goes back
 * into [0, 1). */
static const float ONE_MINUS_EPSILON_F = 0x1.fffffep-1f;

/* sqrt of something that is >= 0 in real numbers but may round to -1e-8. */
static float safe_sqrt(float x) { return sqrtf(x > 0.0f ? x : 0.0f); } /* not fmaxf: GCC calls libm for it */

/* The azimuth of (x, y) as a fraction of a turn, in [0, 1). */
static float azimuth_fraction(float x, float y)
{
    float phi = atan2f(y, x);
    if (phi < 0.0f)
        phi += TWO_PI_F;
    float u = phi * INV_TWO_PI_F;
    return u < 1.0f ? u : 0.0f; /* 2 pi after rounding is the same direction as 0 */
}

static float clamp_unit(float u) { return fminf(fmaxf(u, 0.0f), ONE_MINUS_EPSILON_F); }

static vec2 concentric_disk(vec2 u, float *one_minus_r);

/* ---- uniform hemisphere --------------------------------------------------- */

/* p(w) = 1/(2 pi), and dw = sin(theta) dtheta dphi = -d(cos theta) dphi: the
 * density is uniform in (cos theta, phi) as well, so z = cos(theta) = u1 and
 * phi = 2 pi u2 (Archimedes: equal slices in z have equal areas). */
vec3 sample_uniform_hemisphere(vec2 u)
{
    float z = u.x;
    float r = safe_sqrt(1.0f - z * z);
    float sin_phi, cos_phi; /* phi = 2 pi u.y */
    sincos_turns(u.y, &sin_phi, &cos_phi);
    return vec3_make(r * cos_phi, r * sin_phi, z);
}

float uniform_hemisphere_pdf(void) { return INV_TWO_PI_F; }

vec2 invert_uniform_hemisphere(vec3 w) { return vec2_make(clamp_unit(w.z), azimuth_fraction(w.x, w.y)); }

/* ---- cosine-weighted hemisphere ------------------------------------------- */

/* Malley's method: project a uniform point of the unit disk up onto the
 * hemisphere. The disk has density 1/pi per area; the area element at the
 * base is dA = cos(theta) dw, so the density per solid angle is cos(theta)/pi.
 *
 * z = sqrt(1 - r^2) as written loses everything to cancellation near the rim:
 * for r within 3e-8 of 1, r*r rounds to 1 and z to 0, where the pdf is 0 too,
 * and the sample is lost (an estimator drops samples with p = 0). About one
 * sample in 10^7 did that here. z = sqrt((1 - r)(1 + r)) with 1 - r taken
 * straight from u keeps z > 0 for every u in (0, 1)^2. */
vec3 sample_cosine_hemisphere(vec2 u)
{
    float one_minus_r;
    vec2 d = concentric_disk(u, &one_minus_r);
    float z = safe_sqrt(one_minus_r * (2.0f - one_minus_r));
    return vec3_make(d.x, d.y, z);
}

float cosine_hemisphere_pdf(float cos_theta) { return fmaxf(cos_theta, 0.0f) * INV_PI_F; }

vec2 invert_cosine_hemisphere(vec3 w) { return invert_uniform_disk_concentric(vec2_make(w.x, w.y)); }

/* ---- uniform sphere ------------------------------------------------------- */

/* As the hemisphere, with z = cos(theta) uniform in (-1, 1]. */
vec3 sample_uniform_sphere(vec2 u)
{
    float z = 1.0f - 2.0f * u.x;
    float r = safe_sqrt(1.0f - z * z);
    float sin_phi, cos_phi; /* phi = 2 pi u.y */
    sincos_turns(u.y, &sin_phi, &cos_phi);
    return vec3_make(r * cos_phi, r * sin_phi, z);
}

float uniform_sphere_pdf(void) { return 0.25f * INV_PI_F; }

vec2 invert_uniform_sphere(vec3 w) { return vec2_make(clamp_unit(0.5f * (1.0f - w.z)), azimuth_fraction(w.x, w.y)); }

/* ---- unit disk ------------------------------------------------------------ */

/* Concentric map: the square [-1,1]^2 is cut into four triangles by its
 * diagonals; each concentric square of "radius" r goes to the circle of
 * radius r, and the position along the square's side to the angle. Areas are
 * preserved up to the constant pi/4, so the density is uniform. Also returns
 * 1 - r, computed from u without cancellation: r = |2u - 1| of the dominant
 * coordinate, so 1 - r = 2 min(u, 1 - u). */
static vec2 concentric_disk(vec2 u, float *one_minus_r)
{
    float ox = 2.0f * u.x - 1.0f, oy = 2.0f * u.y - 1.0f;
    if (ox == 0.0f && oy == 0.0f) {
        *one_minus_r = 1.0f;
        return vec2_make(0.0f, 0.0f);
    }
    float r, theta;
    if (fabsf(ox) > fabsf(oy)) { /* left and right triangles */
        r = ox;
        theta = PI_OVER_4_F * (oy / ox);
        *one_minus_r = 2.0f * fminf(u.x, 1.0f - u.x);
    } else { /* top and bottom triangles */
        r = oy;
        theta = PI_OVER_2_F - PI_OVER_4_F * (ox / oy);
        *one_minus_r = 2.0f * fminf(u.y, 1.0f - u.y);
    }
    return vec2_make(r * cosf(theta), r * sinf(theta));
}

vec2 sample_uniform_disk_concentric(vec2 u)
{
    float one_minus_r;
    return concentric_disk(u, &one_minus_r);
}

/* The same four triangles backwards: which one the point's angle is in, then
 * its signed radius and its position along the side. */
vec2 invert_uniform_disk_concentric(vec2 p)
{
    float r = hypotf(p.x, p.y);
    if (r == 0.0f)
        return vec2_make(0.5f, 0.5f);
    float ox, oy;
    if (fabsf(p.x) >= fabsf(p.y)) {
        ox = copysignf(r, p.x);
        float theta = atan2f(copysignf(1.0f, p.x) * p.y, fabsf(p.x)); /* in [-pi/4, pi/4] */
        oy = ox * theta / PI_OVER_4_F;
    } else {
        oy = copysignf(r, p.y);
        float theta = atan2f(fabsf(p.y), copysignf(1.0f, p.y) * p.x); /* in [pi/4, 3pi/4] */
        ox = oy * (PI_OVER_2_F - theta) / PI_OVER_4_F;
    }
    return vec2_make(clamp_unit(0.5f * (ox + 1.0f)), clamp_unit(0.5f * (oy + 1.0f)));
}

/* Polar map by inversion: p(r, phi) = r/pi (the Jacobian r of polar
 * coordinates), marginal cdf F(r) = r^2, so r = sqrt(u1); phi = 2 pi u2.
 * Without the sqrt the points crowd the centre (a twin in the tests). */
vec2 sample_uniform_disk_polar(vec2 u)
{
    float r = sqrtf(u.x);
    float sin_phi, cos_phi; /* phi = 2 pi u.y */
    sincos_turns(u.y, &sin_phi, &cos_phi);
    return vec2_make(r * cos_phi, r * sin_phi);
}

vec2 invert_uniform_disk_polar(vec2 p)
{
    return vec2_make(clamp_unit(p.x * p.x + p.y * p.y), azimuth_fraction(p.x, p.y));
}

float uniform_disk_pdf(void) { return INV_PI_F; }

/* ---- triangle ------------------------------------------------------------- */

/* On the reference triangle b1, b2 >= 0, b1 + b2 <= 1 (area 1/2, density 2),
 * let s = b1 + b2 = 1 - b0. The marginal density of s is 2s, its cdf s^2, so
 * s = sqrt(u1); given s, b1 is uniform on [0, s], so b1 = u2 s. The map to any
 * other triangle is affine, which keeps the density uniform. */
vec3 sample_uniform_triangle(vec2 u)
{
    float s = sqrtf(u.x);
    float b1 = u.y * s;
    float b2 = s - b1;
    return vec3_make(1.0f - s, b1, b2);
}

float triangle_area(vec3 p0, vec3 p1, vec3 p2)
{
    return 0.5f * vec3_length(vec3_cross(vec3_sub(p1, p0), vec3_sub(p2, p0)));
}

float uniform_triangle_pdf(vec3 p0, vec3 p1, vec3 p2) { return 1.0f / triangle_area(p0, p1, p2); }

/* s from b1 + b2 rather than 1 - b0: near vertex 0, s is small and 1 - b0
 * would have lost its digits to cancellation. */
vec2 invert_uniform_triangle(vec3 b)
{
    float s = b.y + b.z;
    if (s <= 0.0f)
        return vec2_make(0.0f, 0.0f);
    return vec2_make(clamp_unit(s * s), clamp_unit(b.y / s));
}

vec3 triangle_point(vec3 p0, vec3 p1, vec3 p2, vec3 b)
{
    return vec3_add(vec3_add(vec3_scale(p0, b.x), vec3_scale(p1, b.y)), vec3_scale(p2, b.z));
}

/* ---- cone ----------------------------------------------------------------- */

/* Uniform in solid angle is uniform in cos(theta), now on [cos_theta_max, 1]:
 * cos(theta) = (1 - u1) + u1 cos_theta_max, phi = 2 pi u2. */
vec3 sample_uniform_cone(vec2 u, float cos_theta_max)
{
    float cos_theta = (1.0f - u.x) + u.x * cos_theta_max;
    float sin_theta = safe_sqrt(1.0f - cos_theta * cos_theta);
    float sin_phi, cos_phi; /* phi = 2 pi u.y */
    sincos_turns(u.y, &sin_phi, &cos_phi);
    return vec3_make(sin_theta * cos_phi, sin_theta * sin_phi, cos_theta);
}

float uniform_cone_pdf(float cos_theta_max) { return 1.0f / (TWO_PI_F * (1.0f - cos_theta_max)); }

vec2 invert_uniform_cone(vec3 w, float cos_theta_max)
{
    return vec2_make(clamp_unit((1.0f - w.z) / (1.0f - cos_theta_max)), azimuth_fraction(w.x, w.y));
}

/* ---- 1D piecewise constant ------------------------------------------------ */

bool piecewise_constant_1d_init(piecewise_constant_1d *d, const double *values, int count, double min, double max)
{
    d->count = 0;
    d->func = d->cdf = NULL;
    d->integral = 0.0;
    if (count < 1 || !(min < max) || !isfinite(min) || !isfinite(max))
        return false;
    for (int i = 0; i < count; i++)
        if (!(values[i] >= 0.0) || !isfinite(values[i]))
            return false;
    d->count = count;
    d->min = min;
    d->max = max;
    d->func = memory_allocate((size_t)count, sizeof(double));
    d->cdf = memory_allocate((size_t)count + 1, sizeof(double));
    double width = (max - min) / count;
    /* Running integral of the step function: cdf[i] = sum_{j<i} f_j * width. */
    d->cdf[0] = 0.0;
    for (int i = 0; i < count; i++) {
        d->func[i] = values[i];
        d->cdf[i + 1] = d->cdf[i] + values[i] * width;
    }
    d->integral = d->cdf[count];
    if (d->integral == 0.0) {
        /* Nothing to follow: fall back to uniform rather than divide by 0. */
        for (int i = 0; i < count; i++) {
            d->func[i] = 1.0;
            d->cdf[i + 1] = (double)(i + 1) / count;
        }
        d->integral = max - min;
    } else {
        for (int i = 1; i <= count; i++)
            d->cdf[i] /= d->integral;
    }
    d->cdf[count] = 1.0;
    return true;
}

void piecewise_constant_1d_free(piecewise_constant_1d *d)
{
    free(d->func);
    free(d->cdf);
    d->func = d->cdf = NULL;
    d->count = 0;
}

/* Invert the cdf: find the bin (the last i with cdf[i] <= u, which skips
 * empty bins because their cdf does not rise), then go linearly inside it. */
double sample_piecewise_constant_1d(const piecewise_constant_1d *d, double u, double *pdf)
{
    /* exercise: invert_cdf */
    int lo = 0, hi = d->count; /* invariant: cdf[lo] <= u < cdf[hi] */
    while (hi - lo > 1) {
        int mid = lo + (hi - lo) / 2;
        if (d->cdf[mid] <= u)
            lo = mid;
        else
            hi = mid;
    }
    double mass = d->cdf[lo + 1] - d->cdf[lo];
    double du = mass > 0.0 ? (u - d->cdf[lo]) / mass : 0.0;
    double width = (d->max - d->min) / d->count;
    double x = d->min + (lo + du) * width;
    if (x >= d->max) /* rounding; keep x in [min, max) */
        x = nextafter(d->max, d->min);
    if (pdf != NULL)
        *pdf = d->func[lo] / d->integral;
    return x;
    /* end of exercise invert_cdf */
}

static int piecewise_constant_1d_bin(const piecewise_constant_1d *d, double x)
{
    int i = (int)floor((x - d->min) / (d->max - d->min) * d->count);
    return i < 0 ? 0 : i >= d->count ? d->count - 1 : i;
}

double piecewise_constant_1d_pdf(const piecewise_constant_1d *d, double x)
{
    if (!(x >= d->min && x <= d->max))
        return 0.0;
    return d->func[piecewise_constant_1d_bin(d, x)] / d->integral;
}

double invert_piecewise_constant_1d(const piecewise_constant_1d *d, double x)
{
    int i = piecewise_constant_1d_bin(d, x);
    double width = (d->max - d->min) / d->count;
    double fraction = (x - (d->min + i * width)) / width;
    fraction = fraction < 0.0 ? 0.0 : fraction > 1.0 ? 1.0 : fraction;
    return d->cdf[i] + fraction * (d->cdf[i + 1] - d->cdf[i]);
}
