/* image.h -- a float RGB image, encoded as OpenEXR (the data) and as an
 * sRGB PNG (a preview to look at), and the error between two images.
 *
 * Usage:
 *   image img = image_make(w, h);          pixels start black
 *   image_set(&img, x, y, colour);
 *   image_write(&img, "build/out/ch01.exr", 0.0f, err, sizeof err);   image_file.h
 *   image_free(&img);
 *
 * Values are linear radiance, row 0 at the top. EXR keeps them exactly as
 * 32-bit floats; the PNG is a preview only: scaled by 2^exposure, clamped and
 * sRGB-encoded (gamma applied once, here, and nowhere else).
 *
 * The encoders write onto a descriptor; putting a file in place (a
 * temporary name renamed at the end, so that no half-written file is ever
 * seen) is the program's business, image_file.h.
 */
#ifndef IMAGE_H
#define IMAGE_H

#include <stdbool.h>
#include <stddef.h>
#include "vec3.h"

enum { IMAGE_ERROR_SIZE = 512 };

typedef struct {
    int width, height;
    float *rgb; /* width * height * 3 floats, row-major, top row first */
} image;

/* A black image; rgb is NULL if memory ran out (or the size is not positive). */
image image_make(int width, int height);
void image_free(image *img);

static inline vec3 image_get(const image *img, int x, int y)
{
    const float *p = img->rgb + 3 * ((size_t)y * (size_t)img->width + (size_t)x);
    return vec3_make(p[0], p[1], p[2]);
}

static inline void image_set(image *img, int x, int y, vec3 c)
{
    float *p = img->rgb + 3 * ((size_t)y * (size_t)img->width + (size_t)x);
    p[0] = c.x;
    p[1] = c.y;
    p[2] = c.z;
}

/* The image as EXR (or, below, PNG) bytes onto fd, from its start. True on
 * success; on failure false, with one line naming `path` (the file the
 * bytes are for, in messages only) and the reason in err. */
bool image_encode_exr(const image *img, int fd, const char *path, char *err, size_t err_size);
/* For the tests: how many ZIP chunks image_encode_exr has stored raw
 * because deflating did not shrink them, and how many of those deflated to
 * exactly their raw length (the case older OpenEXR libraries store wrong);
 * and the twin: false stores such chunks with other bytes than the
 * pixels'. Not thread-safe. */
void image_exr_raw_chunks(long *raw, long *deflated_to_raw_length);
void image_exr_raw_fallback(bool on);
bool image_read_exr(image *out, const char *path, char *err, size_t err_size);
/* exposure_stops: the preview shows radiance * 2^exposure_stops. */
bool image_encode_png(const image *img, int fd, const char *path, float exposure_stops, char *err, size_t err_size);

/* Mean squared error over all pixels and channels (NaN if the sizes differ). */
double image_mse(const image *a, const image *reference);
/* Relative MSE: mean of (a - ref)^2 / (ref^2 + IMAGE_RELMSE_EPSILON), which
 * weighs errors in dark regions as much as in bright ones. */
double image_relmse(const image *a, const image *reference);

/* The linear -> sRGB transfer function (IEC 61966-2-1), for one channel in [0,1]. */
float image_srgb_encode(float linear);

#endif
