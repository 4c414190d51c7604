/* image_file.h -- an image written to a file: the encoders of image.h onto
 * a temporary file beside the target, renamed into place (atomic_file.h),
 * so that a reader finds the old file or the whole new one.
 *
 * Usage:
 *   char err[IMAGE_ERROR_SIZE];
 *   if (!image_write(&img, "build/out/ch01.exr", 0.0f, err, sizeof err)) ...
 */
#ifndef IMAGE_FILE_H
#define IMAGE_FILE_H

#include <stdbool.h>
#include <stddef.h>

#include "image.h"

/* Each returns true on success; on failure false, with one line naming the
 * file and the reason in err, and no file left behind. */
bool image_write_exr(const image *img, const char *path, char *err, size_t err_size);
/* exposure_stops: the preview shows radiance * 2^exposure_stops. */
bool image_write_png(const image *img, const char *path, float exposure_stops, char *err, size_t err_size);
/* By the path's ending: "x.exr" writes x.exr and the preview x.png beside it;
 * "x.png" writes only the preview. */
bool image_write(const image *img, const char *path, float exposure_stops, char *err, size_t err_size);

#endif
