/* record_file.h -- a small text file of "key value" lines that says how a
 * cached result was made (chapter 09's references keep NAME-record.txt
 * beside NAME.exr): the cache serves only when the record on disk is, byte
 * for byte, the record this run would write; else each line that differs
 * is named ("its spp 1024, now spp 4096").
 *
 * Usage:
 *   char why[4096];
 *   if (!record_file_matches("build/data/ref-record.txt", expected, why, sizeof why)) ... why says what differs
 *   record_file_write("build/data/ref-record.txt", expected, err, sizeof err);       atomically
 */
#ifndef RECORD_FILE_H
#define RECORD_FILE_H

#include <stdbool.h>
#include <stddef.h>

/* A record is small: a file larger than this is not one. */
enum { RECORD_FILE_MAX = 4096 };

/* Whether the file at path holds exactly `expected`. If not, why says
 * why, in words: no record, a file that is not one (a directory, a FIFO,
 * too large; read through input_file, so nothing blocks or is read
 * without end), or each line that differs. */
bool record_file_matches(const char *path, const char *expected, char *why, size_t why_size);
/* Writes record to path through atomic_file; false with err naming the file. */
bool record_file_write(const char *path, const char *record, char *err, size_t err_size);

#endif
