/* mlt_experiments.h -- what Metropolis costs and gains, measured.
 *
 *   mlt_experiments_run(dir, threads)  for the Cornell box and the lamp
 *       scene: a cached path-traced reference, then relMSE against it for
 *       chapter 09's path tracer (MIS) and for MLT at doubling sample
 *       counts, with CPU seconds (DIR/ch12_equal_time_NAME.csv); and on the
 *       Cornell box, short runs started from bootstrap paths and from one
 *       fixed path (DIR/ch12_startup_bias.csv).
 */
#ifndef MLT_EXPERIMENTS_H
#define MLT_EXPERIMENTS_H

#include <stdbool.h>
#include <stddef.h>

bool mlt_experiments_run(const char *dir, int threads, char *err, size_t err_size);

#endif
