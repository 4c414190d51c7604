/* fuzz_record.c -- a libFuzzer target for the cached-reference record
 * (record_file.h; chapter 09's NAME-record.txt beside a reference), which
 * decides whether a cached reference serves (make fuzz).
 *
 * Each input is a record file on disk (the text up to a line "%%NAME";
 * files after it are written beside it, fuzz_files.h), compared with the
 * record chapter 09 writes for its default reference. It must match if
 * and only if its bytes are that record's, and otherwise say why in words
 * that fit and end in a NUL (each differing line, a file that is no
 * record), without crashing or reading past the file, whatever it holds
 * (NUL bytes, no newline, lines of any length). Seeds: tests/fuzz/record/,
 * chapter 09's record and edits of it. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz_files.h"
#include "record_file.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* In the form chapter 09 writes (experiments.c, reference_record). */
static const char EXPECTED[] = "width 320\nheight 240\nspp 4096\nseed 24301\nmethod path tracing, mis, Russian "
                               "roulette throughput, max depth 16, random samples\nscene-hash 5c1e0f3a9b2d4e61\n"
                               "version fuzz\n";

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char path[FUZZ_PATH_SIZE];
    size_t record_size;
    fuzz_write_files(data, size, "ref-record.txt", path, &record_size);
    char why[4096];
    memset(why, 'x', sizeof why);
    bool same = record_size == strlen(EXPECTED) && memcmp(data, EXPECTED, record_size) == 0;
    bool matches = record_file_matches(path, EXPECTED, why, sizeof why);
    if (matches != same || (!matches && (memchr(why, '\0', sizeof why) == NULL || why[0] == '\0'))) {
        fprintf(stderr, "record of %zu bytes: matches %d, is the same %d, why '%.200s'\n", record_size, matches, same,
                why);
        abort();
    }
    /* A record that names a directory or another file: what is beside it */
    char other[FUZZ_PATH_SIZE];
    snprintf(other, sizeof other, "%s", fuzz_scratch_dir());
    if (record_file_matches(other, EXPECTED, why, sizeof why))
        abort();
    return 0;
}
