/* mlt_experiments.h -- what Metropolis costs and gains, measured.
 *
 *   mlt_experiments_run(dir, threads, quick)  for the Cornell box and the lamp
 *       scene: a cached path-traced reference, then relMSE against it for
 *       chapter 09's path tracer (MIS) and for MLT at doubling sample
 *       counts, with CPU seconds (DIR/ch12_equal_time_NAME.csv); and on the
 *       Cornell box, short runs started from bootstrap paths and from one
 *       fixed path (DIR/ch12_startup_bias.csv).
 *       Then which method for which scene: the three unbiased methods
 *       (chapter 09's path tracer, chapter 11's BDPT, this chapter's MLT)
 *       on the Cornell box, chapter 11's ceiling lamp and the lamp in a
 *       housing, relMSE against CPU seconds (DIR/ch12_methods_NAME.csv)
 *       and the CPU seconds each needs to reach a target relMSE
 *       (DIR/ch12_methods_time_to_error.csv). 128 x 128 images; `quick`:
 *       32 x 32, shorter runs and smaller references, every table in
 *       seconds (rough: the book's default figures).
 */
#ifndef MLT_EXPERIMENTS_H
#define MLT_EXPERIMENTS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "09-path-tracing/scene_pt.h"
#include "camera.h"
#include "image.h"

typedef enum { MLT_METHOD_PATH_TRACING, MLT_METHOD_BIDIRECTIONAL, MLT_METHOD_METROPOLIS, MLT_METHOD_COUNT } mlt_method;

extern const char *const mlt_method_names[MLT_METHOD_COUNT];

/* One image of sc by one of the three methods, `samples` per pixel: camera
 * paths (path tracing: MIS, Russian roulette on throughput), camera and
 * light path pairs (bidirectional, power heuristic) or mutations
 * (Metropolis, with the bootstrap growing with the run). *out is made
 * here; false if memory ran out. */
bool mlt_method_render(mlt_method method, const pt_scene *sc, const camera *cam, int samples, uint64_t seed,
                       int threads, image *out);

bool mlt_experiments_run(const char *dir, int threads, bool quick, char *err, size_t err_size);

#endif
