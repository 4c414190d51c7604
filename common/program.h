/* program.h -- the end of every chapter program's main(): render the scene
 * with the options from the command line, write the image, report.
 *
 * Usage (after cli_parse_or_exit and building the scene):
 *   return program_render(&opts, "01-ray-casting", ray_cast_radiance, &sc, &cam, NULL);
 */
#ifndef PROGRAM_H
#define PROGRAM_H

#include "cli.h"
#include "render.h"

/* Returns the process exit status: 0, or 1 if the image could not be written
 * (the message names the file). On success, unless opts->quiet, prints where
 * the image went, the time, and the ray counters. If stats is not NULL it
 * receives the render's time and counters. */
int program_render(const cli_options *opts, const char *label, radiance_fn radiance, const void *scene,
                   const camera *cam, render_stats *stats);

#endif
