/* input_file.c -- reading input files whole, bounded (see input_file.h). */
#include "input_file.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

enum { MB = 1 << 20, PROTECTED_MAX = 8, PROTECTED_PATH_SIZE = 4096, PROTECTED_TEXT_SIZE = 64 };

static uint64_t mesh_limit = (uint64_t)INPUT_DEFAULT_MESH_MB * MB;

uint64_t input_file_mesh_limit(void) { return mesh_limit; }

void input_file_set_mesh_limit(uint64_t bytes) { mesh_limit = bytes; }

/* ---- the files this run writes ------------------------------------------------ */

typedef struct {
    char label[PROTECTED_TEXT_SIZE], flag[PROTECTED_TEXT_SIZE], what[PROTECTED_TEXT_SIZE];
    char flag_value[PROTECTED_PATH_SIZE], path[PROTECTED_PATH_SIZE];
} protected_path;

static protected_path protected_paths[PROTECTED_MAX];
static int protected_count;

void input_file_protect(const char *label, const char *flag, const char *flag_value, const char *path,
                        const char *what)
{
    if (protected_count == PROTECTED_MAX)
        return;
    protected_path *p = &protected_paths[protected_count++];
    snprintf(p->label, sizeof p->label, "%s", label);
    snprintf(p->flag, sizeof p->flag, "%s", flag);
    snprintf(p->flag_value, sizeof p->flag_value, "%s", flag_value);
    snprintf(p->path, sizeof p->path, "%s", path);
    snprintf(p->what, sizeof p->what, "%s", what);
}

void input_file_protect_clear(void) { protected_count = 0; }

/* Stops the program if the open input `info` (read as `path`) is a file
 * the run will write. Same device and inode: the same file whatever the
 * names, so "./x.obj", "dir/../x.obj" and a hard link all match, and stat
 * follows a symbolic link to what it names. An output that does not exist
 * yet cannot be this input. */
static void refuse_if_output(const char *path, const struct stat *info)
{
    for (int i = 0; i < protected_count; i++) {
        const protected_path *p = &protected_paths[i];
        struct stat out;
        if (stat(p->path, &out) != 0 || out.st_dev != info->st_dev || out.st_ino != info->st_ino)
            continue;
        fprintf(stderr, "%s: %s '%s' would overwrite the input '%s'%s%s%s\n", p->label, p->flag, p->flag_value, path,
                p->what[0] ? " (" : "", p->what, p->what[0] ? ")" : "");
        exit(2);
    }
}

void input_file_check_not_output(const char *path)
{
    struct stat info;
    if (protected_count > 0 && stat(path, &info) == 0)
        refuse_if_output(path, &info);
}

/* ---- reading ------------------------------------------------------------------ */

static const char *file_type(mode_t mode)
{
    return S_ISDIR(mode)    ? "a directory"
           : S_ISCHR(mode)  ? "a character device"
           : S_ISBLK(mode)  ? "a block device"
           : S_ISFIFO(mode) ? "a pipe"
           : S_ISSOCK(mode) ? "a socket"
                            : "not a file";
}

/* "123 bytes", "2.0 MB", "6.2 GB" (MB = 2^20 bytes, GB = 2^30). */
static void format_size(uint64_t bytes, char *out, size_t size)
{
    if (bytes < MB)
        snprintf(out, size, "%llu bytes", (unsigned long long)bytes);
    else if (bytes < (uint64_t)1024 * MB)
        snprintf(out, size, "%.1f MB", (double)bytes / MB);
    else
        snprintf(out, size, "%.1f GB", (double)bytes / MB / 1024.0);
}

/* A limit as given: whole MB or GB when it is one, else as format_size. */
static void format_limit(uint64_t bytes, char *out, size_t size)
{
    if (bytes >= (uint64_t)1024 * MB && bytes % ((uint64_t)1024 * MB) == 0)
        snprintf(out, size, "%llu GB", (unsigned long long)(bytes / MB / 1024));
    else if (bytes >= MB && bytes % MB == 0)
        snprintf(out, size, "%llu MB", (unsigned long long)(bytes / MB));
    else
        format_size(bytes, out, size);
}

/* "SIZE is over the LIMIT limit for KIND files (--max-input-mb N raises it)";
 * size 0: the file grew past the limit while being read. */
static void too_large(uint64_t size, const char *kind, uint64_t max_bytes, bool raisable, char *why, size_t why_size)
{
    char shown[32], limit[32];
    /* Just over the limit, rounding would show the limit itself ("16.0 MB
     * is over the 16 MB limit"): exact bytes then. */
    if ((double)size < (double)max_bytes * 1.05)
        snprintf(shown, sizeof shown, "%llu bytes", (unsigned long long)size);
    else
        format_size(size, shown, sizeof shown);
    format_limit(max_bytes, limit, sizeof limit);
    snprintf(why, why_size, "%s%s the %s limit for %s files%s", size > 0 ? shown : "", size > 0 ? " is over" : "it holds more than",
             limit, kind, raisable ? " (" INPUT_LIMIT_FLAG " N raises it)" : "");
}

bool input_file_read(const char *path, const char *kind, uint64_t max_bytes, bool raisable, char **text,
                     size_t *length, char *why, size_t why_size)
{
    *text = NULL;
    *length = 0;
    /* O_NONBLOCK: opening a FIFO must not wait for a writer; it is refused
     * below. It changes nothing for a regular file. */
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        snprintf(why, why_size, "%s", strerror(errno));
        return false;
    }
    struct stat info;
    if (fstat(fd, &info) != 0) {
        snprintf(why, why_size, "%s", strerror(errno));
        close(fd);
        return false;
    }
    if (!S_ISREG(info.st_mode)) {
        snprintf(why, why_size, "not a regular file (%s)", file_type(info.st_mode));
        close(fd);
        return false;
    }
    refuse_if_output(path, &info);
    if (info.st_size < 0 || (uint64_t)info.st_size > max_bytes) {
        too_large((uint64_t)info.st_size, kind, max_bytes, raisable, why, why_size);
        close(fd);
        return false;
    }

    /* Read until EOF rather than trusting st_size, never past the limit:
     * one byte more than it is how we know the file went over. */
    size_t capacity = (size_t)info.st_size + 1 < 65536 ? 65536 : (size_t)info.st_size + 1;
    if ((uint64_t)capacity > max_bytes + 1)
        capacity = (size_t)(max_bytes + 1);
    char *buffer = malloc(capacity + 1);
    size_t used = 0;
    int failure = buffer == NULL ? ENOMEM : 0;
    while (failure == 0) {
        if (used == capacity) {
            if ((uint64_t)used > max_bytes)
                break;
            size_t grown = capacity * 2;
            if ((uint64_t)grown > max_bytes + 1)
                grown = (size_t)(max_bytes + 1);
            char *p = realloc(buffer, grown + 1);
            if (p == NULL) {
                failure = ENOMEM;
                break;
            }
            buffer = p;
            capacity = grown;
        }
        ssize_t n = read(fd, buffer + used, capacity - used);
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0)
            failure = errno;
        else if (n == 0)
            break;
        else
            used += (size_t)n;
    }
    close(fd);
    if (failure != 0) {
        snprintf(why, why_size, "%s", strerror(failure));
        free(buffer);
        return false;
    }
    if ((uint64_t)used > max_bytes) {
        too_large(0, kind, max_bytes, raisable, why, why_size);
        free(buffer);
        return false;
    }
    buffer[used] = '\0';
    *text = buffer;
    *length = used;
    return true;
}
