/* counters_file.h -- a render's counters (counters.h) in a file beside its
 * image, with the run's record (run_record.h): what the programs leave for
 * the plots and the tables to read.
 */
#ifndef COUNTERS_FILE_H
#define COUNTERS_FILE_H

#include <stdbool.h>
#include <stddef.h>

#include "counters.h"

/* The counters as a small JSON object (rays by kind, tests, dropped samples,
 * seconds, and `extra`: more "key": value pairs, or NULL), written to a
 * temporary file beside `path` and renamed into place, so a reader never
 * sees half a file. False with err naming the file on failure. */
bool counters_write_json(const char *path, const ray_counters *c, double seconds, const char *extra, char *err,
                         size_t err_size);
/* "build/out/ch01.exr" -> "build/out/ch01.counters.json": where the
 * programs put the counters of an image. */
void counters_path_for_image(const char *image_path, char *out, size_t out_size);

#endif
