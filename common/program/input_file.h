/* input_file.h -- reading the files a run is given: bounded, and never one
 * the run is about to overwrite.
 *
 * Usage:
 *   char *text; size_t length; char why[INPUT_ERROR_SIZE];
 *   if (!input_file_read(path, "OBJ", input_file_mesh_limit(), true, &text, &length, why, sizeof why))
 *       printf("%s: %s\n", path, why);   "x.obj: not a regular file (a character device)"
 *   ... free(text);
 *
 * Every file a program reads as input (the scene file, OBJ files, their MTL
 * libraries) goes through input_file_read, so each is refused the same way:
 *   - anything but a regular file (a directory, /dev/zero, a pipe, a
 *     socket), at once and without reading: /dev/zero never ends and a FIFO
 *     with no writer would block forever;
 *   - a file over `max_bytes`: checked against fstat's size before anything
 *     is allocated, and again while reading (a file may grow, and some
 *     regular files, those in /proc, report size 0);
 *   - a file the run will write (input_file_protect): the program stops.
 */
#ifndef INPUT_FILE_H
#define INPUT_FILE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

enum {
    INPUT_ERROR_SIZE = 256,
    /* The default limit for OBJ and MTL files, in MB (2^20 bytes): real
     * meshes of tens of millions of triangles fit; /dev/zero or a mistyped
     * path to a disk image do not take the machine's memory. */
    INPUT_DEFAULT_MESH_MB = 1024,
    /* The largest value --max-input-mb takes (1 TB). */
    INPUT_MAX_MESH_MB = 1 << 20,
};

/* The flag that raises the mesh limit, as the messages name it. */
#define INPUT_LIMIT_FLAG "--max-input-mb"

/* The limit for OBJ and MTL files in bytes (INPUT_DEFAULT_MESH_MB unless set). */
uint64_t input_file_mesh_limit(void);
void input_file_set_mesh_limit(uint64_t bytes);

/* Reads all of `path` into a malloc'ed buffer (*text, NUL-terminated
 * after *length bytes; the caller frees it). `kind` names the format in
 * messages ("OBJ", "MTL", "scene"); `raisable` says whether the message
 * should point at INPUT_LIMIT_FLAG. On failure: false, *text NULL, and why
 * holds the reason without the path ("No such file or directory", "not a
 * regular file (a directory)", "2.0 MB is over the 1 MB limit for OBJ
 * files (--max-input-mb N raises it)"). */
bool input_file_read(const char *path, const char *kind, uint64_t max_bytes, bool raisable, char **text,
                     size_t *length, char *why, size_t why_size);

/* Declares that this run will write `path` (which need not exist yet):
 * `flag` and `flag_value` are what the user typed ("--out", "x.exr") and
 * `what` says how path follows from it ("" for the file itself, "its .png
 * preview"). From then on, when input_file_read is asked for a file that
 * is one of these (the same file, however named: "./x.obj", a hard or
 * symbolic link), the program stops before reading it, as for a bad flag:
 *   "label: --out 'x.exr' would overwrite the input 'x.png' (its .png preview)"
 * on stderr and exit status 2. Programs call it once, when their flags are
 * read (cli_parse_or_exit); a library or a test that never does keeps
 * input_file_read free of side effects. Up to 8 paths. */
void input_file_protect(const char *label, const char *flag, const char *flag_value, const char *path,
                        const char *what);
/* The same check for a file named as input that this program will not
 * read itself (a scene's mesh in a chapter that ignores meshes): stops the
 * program if `path` exists and is a protected output. */
void input_file_check_not_output(const char *path);
/* Forgets every protected path (for tests). */
void input_file_protect_clear(void);

#endif
