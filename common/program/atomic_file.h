/* atomic_file.h -- write a file so that a reader finds the old one or the
 * whole new one, never a half-written one.
 *
 * The bytes go to a temporary file beside the target ("<path>.tmp.<pid>.<n>",
 * in the same directory so that rename(2) stays within one filesystem and
 * replaces the target in one step). Commit flushes it, fsyncs it, closes it
 * and renames it over the target; any failure, there or before, unlinks the
 * temporary file and leaves the target as it was. Every image, table,
 * counters file and mesh the programs write goes through here.
 *
 * Usage:
 *   atomic_file f;
 *   if (!atomic_file_open(&f, "build/data/x.csv", err, sizeof err))
 *       return false;                      err: "cannot write '...': reason"
 *   fprintf(f.stream, "...");              or write(fileno(f.stream), ...)
 *   if (!atomic_file_commit(&f, err, sizeof err))   (or atomic_file_abandon(&f))
 *       return false;
 */
#ifndef ATOMIC_FILE_H
#define ATOMIC_FILE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

typedef struct {
    FILE *stream;    /* write here (or to its descriptor) */
    char *path;      /* the target, copied */
    char *temp_path; /* where the bytes are until commit */
} atomic_file;

/* Creates the temporary file beside `path`, with the mode any new file
 * gets (0666 & ~umask). False with err naming path if it cannot. */
bool atomic_file_open(atomic_file *f, const char *path, char *err, size_t err_size);
/* The same for the file DIR/NAME. */
bool atomic_file_open_in(atomic_file *f, const char *dir, const char *name, char *err, size_t err_size);
/* Puts the file in place: fflush, fsync, fclose and rename, each checked
 * (a full disk may show only at the flush or the close, and a write error
 * earlier leaves the stream's error flag). On failure the temporary file
 * is removed and err names the target. Either way f is finished. */
bool atomic_file_commit(atomic_file *f, char *err, size_t err_size);
/* Gives up: the temporary file is removed, the target untouched. */
void atomic_file_abandon(atomic_file *f);

#endif
