/* program.h -- the end of every chapter program's main(): render the scene
 * with the options from the command line, write the image and its counters,
 * report; or, with --explain X,Y, print the path tree of one pixel instead.
 *
 * Usage (after cli_parse_or_exit and building the scene):
 *   scene_desc desc;
 *   if (program_load_scene(&opts, "01-ray-casting", &desc)) ... convert desc into the chapter's scene
 *   return program_render(&opts, "01-ray-casting", ray_cast_radiance, &sc, &cam, NULL);
 */
#ifndef PROGRAM_H
#define PROGRAM_H

#include "checkpoint.h"
#include "cli.h"
#include "effects.h"
#include "render.h"
#include "scene_file.h"

/* Returns the process exit status: 0, or 1 if the image could not be written
 * (the message names the file). On success, unless opts->quiet, prints where
 * the image went, the time, and the ray counters, and writes the counters
 * beside the image (counters_path_for_image). If stats is not NULL it
 * receives the render's time and counters. With opts->explain, renders only
 * that pixel, printing its path tree, writes nothing, and stats (if not
 * NULL) receives that pixel's counters and a time of 0. */
int program_render(const cli_options *opts, const char *label, radiance_fn radiance, const void *scene,
                   const camera *cam, render_stats *stats);
/* The same, each sample by `sample` when it is not NULL (render.h's
 * render_sample_fn: a sampler that knows which sample of the pixel it
 * draws). */
int program_render_sampled(const cli_options *opts, const char *label, radiance_fn radiance, render_sample_fn sample,
                           const void *scene, const camera *cam, render_stats *stats);

/* A program that offers --resume (CLI_CHECKPOINT_FLAGS): fills cp for a
 * render of `kind` whose state is payload_bytes, and, with --resume, reads
 * the checkpoint into *resumed (rank 0) for cp->resume. False, after a
 * message naming the file and what differs, if it cannot be resumed (every
 * rank returns false). Without the flags, cp keeps no checkpoints. */
bool program_checkpointing(const cli_options *opts, const char *label, const char *kind, size_t payload_bytes,
                           checkpointing *cp, checkpoint *resumed);
/* After the image is written: the checkpoint has served, and goes. */
void program_checkpoint_done(const cli_options *opts, const checkpointing *cp);
/* Before a progressive render (--time-budget seconds, --target-error e,
 * either 0 when not used; spp_done already done by a resumed one): the
 * same warning as before a plain render of more than a minute, from a
 * pilot at 16 spp that estimates both the time per sample and the error. */
void program_warn_if_long_progressive(const cli_options *opts, const char *label, const render_job *job,
                                      double seconds, double target_error, long spp_done);
/* Under mpirun, one line: the ranks, and the gather's share of the render. */
void program_print_ranks(const render_stats *stats);

/* With --scene FILE: loads it into d (exits with status 1 and the parser's
 * "file:line:col: message" on error), applies its image statement to the
 * options the command line did not set, and returns true. Without --scene:
 * d is left empty and the result is false. */
bool program_load_scene(cli_options *opts, const char *label, scene_desc *d);

/* The counters file beside the image (counters_path_for_image): c, the
 * seconds, the program's name and the run's record (run_record.h). For
 * programs that make their picture without program_render(). */
bool program_write_record(const cli_options *opts, const char *label, const ray_counters *c, double seconds,
                          char *err, size_t err_size);

/* Records which effects the render simulates, for the counters file. */
void program_note_effects(const effects_report *e);
/* Records the acceleration structure the rays go through (its
 * accel_stats name), for the report and the counters file. */
void program_note_accel(const char *name);

/* A warning before a long render. A pilot renders 64 pixels spread over
 * the image at the full spp, on one thread, through the job's own radiance
 * or sample function (their own counters and the pixels' own streams: the
 * image is untouched if the job's scene keeps no state), and scales the
 * time to the image: program_pilot_seconds() returns that one-thread
 * estimate (0 for images under 16,384 pixels, which end before a warning
 * would help). program_warn_if_long() divides it by the threads and warns
 * on stderr above a minute. program_render() does both; programs with a
 * loop of their own (bidirectional, Metropolis, eight paths at a time)
 * call them before theirs. */
double program_pilot_seconds(const render_job *job);
void program_warn_if_long(const cli_options *opts, const char *label, double one_thread_seconds);

/* After a render, a warning (unless --quiet) when every pixel is exactly
 * black: almost never what was asked for, and most often a camera placed
 * in another program's coordinates (inside an object, under the floor). */
void program_warn_if_black(const cli_options *opts, const char *label, const image *img);

/* A chapter's warning about something in the scene file it cannot show:
 * "label: file:line:col: warning: message". */
void program_warn(const char *label, const scene_desc *d, int line, int column, const char *format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 5, 6)))
#endif
    ;

#endif
