/* progress.h -- a one-line progress report on stderr for long work.
 *
 * Shown only when stderr is a terminal and not --quiet, so logs and CI stay
 * clean. Safe to call progress_advance() from many threads.
 *
 * Usage: progress p; progress_begin(&p, "ch01", height, quiet);
 *        ... progress_advance(&p, 1) per row ...; progress_end(&p);
 */
#ifndef PROGRESS_H
#define PROGRESS_H

#include <stdbool.h>
#include <stdint.h>

typedef struct {
    const char *label;
    int64_t total;
    int64_t done;
    double start_seconds;
    double last_print_seconds;
    bool enabled;
} progress;

void progress_begin(progress *p, const char *label, int64_t total, bool quiet);
void progress_advance(progress *p, int64_t amount);
void progress_end(progress *p);

#endif
