/* run_record.h -- what a run was, written into the counters file beside
 * its image, so that the run can be made again from its record: the
 * command line, the project's version (git describe at build time), the
 * seed, the threads, the image size and samples, the scene file, and what
 * the program notes (the integrator, the roulette, the structure the rays
 * went through, the effects simulated).
 *
 * Usage: cli_parse_or_exit() records the command line and the options;
 * a program adds notes, run_record_note("integrator", "mis"); every
 * counters_write_json() then writes the record (run_record_json). */
#ifndef RUN_RECORD_H
#define RUN_RECORD_H

#include <stddef.h>

#include "cli.h"

/* The project's version, made at build time (mk/chapters.mk). */
extern const char *const PROJECT_VERSION;

/* opts is main()'s: it is read when the record is written, so what a scene
 * file's image statement set after parsing is recorded too. */
void run_record_command(int argc, char **argv, const cli_options *opts);
/* The command line's flags that change the image, as given, less the
 * size, samples, seed and scene file (checkpoint.h names those apart):
 * what must be the same for a checkpoint to be resumed. */
void run_record_image_flags(char *out, size_t size);
/* A note "key": "value" (a later note of the same key replaces it). */
void run_record_note(const char *key, const char *value);
/* The record as JSON members, without braces ("" before anything is
 * recorded), into out; false if it did not fit. */
bool run_record_json(char *out, size_t size);

#endif
