/* explain.h -- the path tree of one pixel, printed as it is computed
 * (--explain X,Y).
 *
 * Integrators call explain_line(depth, ...) at each step that decides what
 * a pixel becomes: a ray and what it hit, a light sample with its pdf and
 * contribution, a Russian roulette decision, a sum. The lines go nowhere
 * unless explain_begin() was called, and the check is one load of a
 * pointer, so the full render pays nothing measurable for it.
 *
 * Usage (single-threaded, around one render_pixel call):
 *   explain_begin(stdout);
 *   vec3 c = render_pixel(&job, x, y, &counters, NULL);
 *   explain_end();
 *
 * Only one pixel is explained at a time, from one thread: explain_begin is
 * not for use inside a parallel render.
 */
#ifndef EXPLAIN_H
#define EXPLAIN_H

#include <stdbool.h>
#include <stdio.h>

#include "ray.h"

extern FILE *explain_stream;

static inline bool explain_on(void) { return explain_stream != NULL; }

void explain_begin(FILE *out);
void explain_end(void);
/* One line, indented two spaces per depth. A macro, so that when nothing is
 * being explained neither the call nor its arguments cost anything in the
 * integrators' inner loops. */
#define explain_line(...)                  \
    do {                                   \
        if (explain_on())                  \
            explain_print_line(__VA_ARGS__); \
    } while (0)
void explain_print_line(int depth, const char *format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
/* A ray: "label: from (o) towards (d)". */
void explain_ray(int depth, const char *label, ray r);
/* "x y z" with 4 significant digits, into a small buffer. */
const char *explain_vec3(char buffer[64], vec3 v);

#endif
