/* fuzz_files.h -- what the fuzz targets share to go through the loaders'
 * file paths (open, fstat, the size limit, mtllib and mesh paths resolved
 * beside the file), not only through the parsers in memory.
 *
 * One input holds several files: the text up to a line "%%NAME" is the
 * first file, the text after it (up to the next such line) the file NAME,
 * and so on: "v 0 0 0 ...\n%%m.mtl\nnewmtl a\n" is an OBJ file and m.mtl
 * beside it. Each is written into one scratch directory per process (made
 * with mkdtemp at the first input, removed at exit), so an mtllib or a mesh
 * path in the input can name them, as well as any other path on the
 * machine ("/dev/zero", "/proc/self/status", the input itself): what the
 * loaders must refuse without hanging, and without printing its content.
 */
#ifndef FUZZ_FILES_H
#define FUZZ_FILES_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "input_file.h"

enum { FUZZ_PATH_SIZE = 256, FUZZ_MAX_FILES = 4 };

static char fuzz_dir[FUZZ_PATH_SIZE];
static char fuzz_written[FUZZ_MAX_FILES][FUZZ_PATH_SIZE];
static int fuzz_written_count;

static void fuzz_remove_files(void)
{
    for (int i = 0; i < fuzz_written_count; i++)
        unlink(fuzz_written[i]);
    fuzz_written_count = 0;
}

static void fuzz_remove_dir(void)
{
    fuzz_remove_files();
    if (fuzz_dir[0] != '\0')
        rmdir(fuzz_dir);
}

/* The scratch directory, made once; the mesh limit is set to 1 MB so that a
 * path to a large file is refused at once rather than read. */
static const char *fuzz_scratch_dir(void)
{
    if (fuzz_dir[0] == '\0') {
        snprintf(fuzz_dir, sizeof fuzz_dir, "%s/fuzz_files.XXXXXX", getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
        if (mkdtemp(fuzz_dir) == NULL) {
            perror("mkdtemp");
            abort();
        }
        atexit(fuzz_remove_dir);
        input_file_set_mesh_limit(1 << 20);
    }
    return fuzz_dir;
}

static void fuzz_write(const char *path, const unsigned char *data, size_t size)
{
    FILE *f = fopen(path, "wb");
    if (f == NULL || fwrite(data, 1, size, f) != size || fclose(f) != 0) {
        perror(path);
        abort();
    }
    if (fuzz_written_count < FUZZ_MAX_FILES)
        snprintf(fuzz_written[fuzz_written_count++], FUZZ_PATH_SIZE, "%s", path);
}

/* Where the next "\n%%" that starts a line is, at or after `from` (size if none). */
static size_t fuzz_next_marker(const unsigned char *data, size_t size, size_t from)
{
    for (size_t i = from; i + 3 <= size; i++)
        if (data[i] == '\n' && data[i + 1] == '%' && data[i + 2] == '%')
            return i;
    return size;
}

/* Splits the input into files as above: the first is written as
 * dir/first_name and its length returned in *first_size (its bytes are
 * data[0 .. *first_size)); the rest under their own names, when a name is
 * a plain file name (letters, digits, '.', '_', '-'; at most 32). */
static void fuzz_write_files(const unsigned char *data, size_t size, const char *first_name, char *first_path,
                             size_t *first_size)
{
    const char *dir = fuzz_scratch_dir();
    fuzz_remove_files();
    size_t end = fuzz_next_marker(data, size, 0);
    *first_size = end;
    snprintf(first_path, FUZZ_PATH_SIZE, "%s/%s", dir, first_name);
    fuzz_write(first_path, data, end);
    while (end < size && fuzz_written_count < FUZZ_MAX_FILES) {
        size_t name_start = end + 3, name_end = name_start;
        while (name_end < size && data[name_end] != '\n')
            name_end++;
        size_t next = fuzz_next_marker(data, size, name_end);
        size_t body = name_end < size ? name_end + 1 : size;
        size_t length = name_end - name_start;
        bool plain = length > 0 && length <= 32 && data[name_start] != '.';
        for (size_t i = name_start; plain && i < name_end; i++) {
            unsigned char c = data[i];
            plain = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
                    c == '_' || c == '-';
        }
        if (plain && (length != strlen(first_name) || memcmp(data + name_start, first_name, length) != 0)) {
            char path[FUZZ_PATH_SIZE];
            snprintf(path, sizeof path, "%s/%.*s", dir, (int)length, (const char *)data + name_start);
            fuzz_write(path, data + body, next > body ? next - body : 0);
        }
        end = next;
    }
}

#endif
