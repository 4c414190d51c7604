/* image_file.c -- the image's encoders (image.c) onto a temporary file,
 * renamed over the target only when the whole image is written. */
#include "image_file.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "atomic_file.h"

bool image_write_exr(const image *img, const char *path, char *err, size_t err_size)
{
    atomic_file out;
    if (!atomic_file_open(&out, path, err, err_size))
        return false;
    if (!image_encode_exr(img, fileno(out.stream), path, err, err_size)) {
        atomic_file_abandon(&out);
        return false;
    }
    return atomic_file_commit(&out, err, err_size);
}

bool image_write_png(const image *img, const char *path, float exposure_stops, char *err, size_t err_size)
{
    atomic_file out;
    if (!atomic_file_open(&out, path, err, err_size))
        return false;
    if (!image_encode_png(img, fileno(out.stream), path, exposure_stops, err, err_size)) {
        atomic_file_abandon(&out);
        return false;
    }
    return atomic_file_commit(&out, err, err_size);
}

static bool ends_with(const char *s, const char *suffix)
{
    size_t n = strlen(s), k = strlen(suffix);
    return n >= k && strcmp(s + n - k, suffix) == 0;
}

bool image_write(const image *img, const char *path, float exposure_stops, char *err, size_t err_size)
{
    if (ends_with(path, ".png"))
        return image_write_png(img, path, exposure_stops, err, err_size);
    if (!ends_with(path, ".exr")) {
        snprintf(err, err_size, "'%s': output must end in .exr or .png", path);
        return false;
    }
    /* The data first: if only the preview fails, the finished EXR stays
     * (it is complete, and the expensive part). */
    if (!image_write_exr(img, path, err, err_size))
        return false;
    size_t n = strlen(path);
    char *png_path = malloc(n + 1);
    if (png_path == NULL) {
        snprintf(err, err_size, "cannot write the preview of '%s': %s", path, strerror(ENOMEM));
        return false;
    }
    memcpy(png_path, path, n - 3);
    memcpy(png_path + n - 3, "png", 4);
    bool ok = image_write_png(img, png_path, exposure_stops, err, err_size);
    free(png_path);
    return ok;
}
