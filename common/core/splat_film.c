/* splat_film.c -- see splat_film.h: fixed-point sums, added atomically. */
#include "splat_film.h"

#include <math.h>
#include <stdlib.h>

static const double fixed_point_one = (double)(1LL << SPLAT_FILM_FRACTION_BITS);

bool splat_film_init(splat_film *film, int width, int height)
{
    film->width = film->height = 0;
    film->sum = NULL;
    if (width <= 0 || height <= 0)
        return false;
    film->sum = calloc((size_t)width * (size_t)height * 3, sizeof *film->sum);
    if (film->sum == NULL)
        return false;
    film->width = width;
    film->height = height;
    return true;
}

void splat_film_free(splat_film *film)
{
    free(film->sum);
    film->sum = NULL;
    film->width = film->height = 0;
}

/* Within range and a number: NaN fails both comparisons. */
static bool splat_value_ok(float v) { return v >= -SPLAT_FILM_MAX_VALUE && v <= SPLAT_FILM_MAX_VALUE; }

void splat_film_add(splat_film *film, float x, float y, vec3 value, ray_counters *counters)
{
    if (!(x >= 0.0f && y >= 0.0f)) /* NaN coordinates too */
        return;
    int px = (int)x, py = (int)y; /* x >= 0: truncation is floor */
    if (px >= film->width || py >= film->height)
        return;
    /* NaN, Inf or a value too large for the fixed point: dropped and
     * counted. That biases the pixel towards 0 (its sum is divided by the
     * count of all samples, the dropped too); the counters report how many. */
    if (!splat_value_ok(value.x) || !splat_value_ok(value.y) || !splat_value_ok(value.z)) {
        if (counters != NULL)
            counters->nonfinite_samples++;
        return;
    }
    if (value.x == 0.0f && value.y == 0.0f && value.z == 0.0f)
        return; /* nothing to add: skip the three atomic operations */
    int64_t *pixel = &film->sum[((size_t)py * (size_t)film->width + (size_t)px) * 3];
    const float channel[3] = {value.x, value.y, value.z};
    for (int c = 0; c < 3; c++) {
        int64_t fixed = llrint((double)channel[c] * fixed_point_one);
#pragma omp atomic
        pixel[c] += fixed;
    }
}

vec3 splat_film_get(const splat_film *film, int x, int y, double scale)
{
    const int64_t *pixel = &film->sum[((size_t)y * (size_t)film->width + (size_t)x) * 3];
    double s = scale / fixed_point_one;
    return vec3_make((float)((double)pixel[0] * s), (float)((double)pixel[1] * s), (float)((double)pixel[2] * s));
}

void splat_film_resolve(const splat_film *film, double scale, image *out)
{
    for (int y = 0; y < film->height; y++)
        for (int x = 0; x < film->width; x++)
            image_set(out, x, y, splat_film_get(film, x, y, scale));
}
