/* record_file.c -- how a cached result was made (see record_file.h). */
#include "record_file.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "atomic_file.h"
#include "input_file.h"

bool record_file_matches(const char *path, const char *expected, char *why, size_t why_size)
{
    char *stored, reason[INPUT_ERROR_SIZE];
    size_t length;
    why[0] = '\0';
    if (!input_file_read(path, "record", RECORD_FILE_MAX, false, &stored, &length, reason, sizeof reason)) {
        if (strcmp(reason, strerror(ENOENT)) == 0)
            snprintf(why, why_size, "it has no record of how it was made, %.1000s", path);
        else
            snprintf(why, why_size, "its record %.1000s cannot be read: %s", path, reason);
        return false;
    }
    /* byte for byte: a NUL inside the file does not end the comparison */
    size_t n = strlen(expected);
    if (length == n && memcmp(stored, expected, n) == 0) {
        free(stored);
        return true;
    }
    /* Name each line that differs: "its KEY VALUE, now VALUE". What is
     * shown of the file stops at a control byte (it may hold anything),
     * and every line is shown at most 200 bytes long. */
    size_t used = 0;
    const char *a = stored, *a_end = stored + length, *b = expected;
    while ((a < a_end || *b != '\0') && used < why_size) {
        size_t la = 0, lb = strcspn(b, "\n");
        while (a + la < a_end && a[la] != '\n')
            la++;
        if (la != lb || memcmp(a, b, la) != 0) {
            size_t shown = 0;
            while (shown < la && shown < 200 && (unsigned char)a[shown] >= 0x20 && a[shown] != 0x7f)
                shown++;
            size_t key = strcspn(b, " \n");
            size_t value = key < lb ? key + 1 : lb;
            used += (size_t)snprintf(why + used, why_size - used, "%sits %.*s%s, now %.*s", used > 0 ? "; " : "",
                                     (int)shown, a, shown < la ? "..." : "", (int)(lb - value > 200 ? 200 : lb - value),
                                     b + value);
        }
        a += la + (a + la < a_end);
        b += lb + (b[lb] == '\n');
    }
    free(stored);
    return false;
}

bool record_file_write(const char *path, const char *record, char *err, size_t err_size)
{
    atomic_file f;
    if (!atomic_file_open(&f, path, err, err_size))
        return false;
    fputs(record, f.stream);
    return atomic_file_commit(&f, err, err_size);
}
