/* checkpoint.c -- a render's state in a file (see checkpoint.h). */
#include "checkpoint.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <inttypes.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "atomic_file.h"
#include "memory.h"
#include "run_record.h"

/* The first line, and the format it names: format 1 had no checksum. */
static const char CHECKPOINT_MAGIC_STEM[] = "ray-tracer checkpoint ";
static const char CHECKPOINT_MAGIC[] = "ray-tracer checkpoint 2";

uint64_t checkpoint_checksum(uint64_t h, const void *data, size_t n)
{
    const unsigned char *p = data;
    for (size_t i = 0; i < n; i++) {
        h ^= p[i];
        h *= 1099511628211ULL;
    }
    return h;
}

/* FNV-1a, 64 bits, of a file's bytes: a scene file edited since the
 * checkpoint was made is another scene, whatever its name. 0 if unreadable. */
static uint64_t file_hash(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (f == NULL)
        return 0;
    uint64_t h = CHECKPOINT_CHECKSUM_START;
    unsigned char block[1 << 16];
    size_t n;
    while ((n = fread(block, 1, sizeof block, f)) > 0)
        h = checkpoint_checksum(h, block, n);
    fclose(f);
    return h;
}

/* A value on one line of the header: newlines would end it early. */
static void copy_one_line(char *out, size_t size, const char *s)
{
    size_t n = strnlen(s, size - 1);
    memmove(out, s, n); /* s may be out itself */
    out[n] = '\0';
    for (char *p = out; *p != '\0'; p++)
        if (*p == '\n' || *p == '\r')
            *p = '?';
}

checkpoint_identity checkpoint_identity_of(const char *kind, const char *program, const cli_options *opts)
{
    checkpoint_identity id;
    memset(&id, 0, sizeof id);
    copy_one_line(id.kind, sizeof id.kind, kind);
    copy_one_line(id.program, sizeof id.program, program);
    copy_one_line(id.version, sizeof id.version, PROJECT_VERSION);
    copy_one_line(id.scene, sizeof id.scene, opts->scene != NULL ? opts->scene : "built-in");
    id.scene_hash = opts->scene != NULL ? file_hash(opts->scene) : 0;
    id.width = opts->width;
    id.height = opts->height;
    id.spp = opts->spp;
    id.seed = opts->seed;
    run_record_image_flags(id.flags, sizeof id.flags);
    copy_one_line(id.flags, sizeof id.flags, id.flags);
    return id;
}

void checkpoint_path_for_image(const char *image_path, char *out, size_t out_size)
{
    const char *dot = strrchr(image_path, '.'), *slash = strrchr(image_path, '/');
    size_t stem = dot != NULL && (slash == NULL || dot > slash) ? (size_t)(dot - image_path) : strlen(image_path);
    snprintf(out, out_size, "%.*s.checkpoint", (int)stem, image_path);
}

enum { COUNTER_FIELDS = sizeof(ray_counters) / sizeof(uint64_t) };

/* Appends to a header being built in memory (it is hashed before it is
 * written); false once it no longer fits. */
static bool append(char *out, size_t size, size_t *n, const char *format, ...)
{
    va_list args;
    va_start(args, format);
    int k = *n < size ? vsnprintf(out + *n, size - *n, format, args) : -1;
    va_end(args);
    if (k < 0 || (size_t)k >= size - *n) {
        *n = size;
        return false;
    }
    *n += (size_t)k;
    return true;
}

bool checkpoint_write(const char *path, const checkpoint *c, char *err, size_t err_size)
{
    const checkpoint_identity *id = &c->id;
    const uint64_t *counters = (const uint64_t *)&c->counters;
    char header[CHECKPOINT_HEADER_MAX];
    size_t n = 0;
    append(header, sizeof header, &n,
           "%s\nkind %s\nprogram %s\nversion %s\nscene %s\nscene-hash %016" PRIx64
           "\nwidth %d\nheight %d\nspp %d\nseed %" PRIu64 "\nflags %s\ndone %ld\nspp-done %ld\nseconds %.17g\ncounters",
           CHECKPOINT_MAGIC, id->kind, id->program, id->version, id->scene, id->scene_hash, id->width, id->height,
           id->spp, id->seed, id->flags, c->done, c->spp_done, c->seconds);
    for (int k = 0; k < COUNTER_FIELDS; k++)
        append(header, sizeof header, &n, " %" PRIu64, counters[k]);
    /* The payload is this machine's memory as it is: say which order its
     * bytes are in, so another machine refuses it rather than misread it. */
    uint16_t probe = 1;
    if (!append(header, sizeof header, &n, "\nbyte-order %s\npayload %zu\n",
                *(unsigned char *)&probe == 1 ? "little" : "big", c->payload_bytes)) {
        snprintf(err, err_size, "%s: its header would be longer than %d bytes", path, CHECKPOINT_HEADER_MAX);
        return false;
    }
    uint64_t sum = checkpoint_checksum(checkpoint_checksum(CHECKPOINT_CHECKSUM_START, header, n), c->payload,
                                       c->payload_bytes);
    atomic_file f;
    if (!atomic_file_open(&f, path, err, err_size))
        return false;
    fwrite(header, 1, n, f.stream);
    if (c->payload_bytes > 0)
        fwrite(c->payload, 1, c->payload_bytes, f.stream);
    fprintf(f.stream, "%s%016" PRIx64 "\n", CHECKPOINT_CHECKSUM_KEY, sum);
    return atomic_file_commit(&f, err, err_size);
}

void checkpoint_free(checkpoint *c)
{
    free(c->payload);
    c->payload = NULL;
}

/* One header line "key value" into value (without the newline). A line
 * longer than the buffer is malformed (its rest would be read as the next). */
static bool read_field(FILE *f, const char *key, char *value, size_t size)
{
    char line[CHECKPOINT_FLAGS_SIZE + 64];
    if (fgets(line, sizeof line, f) == NULL)
        return false;
    size_t n = strlen(key), len = strlen(line);
    if (len == 0 || line[len - 1] != '\n')
        return false;
    line[--len] = '\0';
    if (strncmp(line, key, n) != 0 || (line[n] != ' ' && line[n] != '\0'))
        return false;
    snprintf(value, size, "%s", line[n] == ' ' ? line + n + 1 : "");
    return true;
}

/* A whole decimal integer in [min, max], nothing around it (atoi would
 * take "12x" for 12 and overflow on a long run of digits). */
static bool parse_long(const char *v, long min, long max, long *out)
{
    char *end;
    errno = 0;
    long x = strtol(v, &end, 10);
    if (end == v || *end != '\0' || errno != 0 || x < min || x > max)
        return false;
    *out = x;
    return true;
}

/* A whole unsigned integer in the given base; *end_out (if not NULL) gets
 * where it stopped, which must then be a space or the end. */
static bool parse_u64(const char *v, int base, uint64_t *out, const char **end_out)
{
    char *end;
    errno = 0;
    while (*v == ' ')
        v++;
    if (*v == '-' || *v == '+' || *v == '\0')
        return false;
    unsigned long long x = strtoull(v, &end, base);
    if (end == v || errno != 0 || (end_out == NULL ? *end != '\0' : (*end != '\0' && *end != ' ')))
        return false;
    *out = (uint64_t)x;
    if (end_out != NULL)
        *end_out = end;
    return true;
}

/* The header after its first line into c; false if it is not whole (err
 * says which line is wrong). */
static bool read_header(FILE *f, const char *path, checkpoint *c, size_t *payload_bytes, char *err, size_t err_size)
{
    char v[CHECKPOINT_FLAGS_SIZE];
    checkpoint_identity *id = &c->id;
    uint64_t *counters = (uint64_t *)&c->counters;
    const char *bad = NULL;
    long x = 0;
    uint64_t u = 0;
    /* each line in turn, until one is wrong; `check` is the value's test */
#define FIELD(key, check, ...)                                                                                     \
    if (bad == NULL && (!read_field(f, key, v, sizeof v) || !(check)))                                                \
        bad = "the line '" key "' is missing or malformed";                                                           \
    else if (bad == NULL) {                                                                                           \
        __VA_ARGS__;                                                                                                  \
    }
    FIELD("kind", true, copy_one_line(id->kind, sizeof id->kind, v))
    FIELD("program", true, copy_one_line(id->program, sizeof id->program, v))
    FIELD("version", true, copy_one_line(id->version, sizeof id->version, v))
    FIELD("scene", true, copy_one_line(id->scene, sizeof id->scene, v))
    FIELD("scene-hash", parse_u64(v, 16, &u, NULL), id->scene_hash = u)
    FIELD("width", parse_long(v, 0, INT_MAX, &x), id->width = (int)x)
    FIELD("height", parse_long(v, 0, INT_MAX, &x), id->height = (int)x)
    FIELD("spp", parse_long(v, 0, INT_MAX, &x), id->spp = (int)x)
    FIELD("seed", parse_u64(v, 10, &u, NULL), id->seed = u)
    FIELD("flags", true, copy_one_line(id->flags, sizeof id->flags, v))
    /* (how far it got: not negative, within an int, as the renders count) */
    FIELD("done", parse_long(v, 0, INT_MAX, &x), c->done = x)
    FIELD("spp-done", parse_long(v, 0, LONG_MAX, &x), c->spp_done = x)
    FIELD("seconds", (c->seconds = strtod(v, NULL), isfinite(c->seconds) && c->seconds >= 0.0), (void)0)
    FIELD("counters", true, {
        const char *p = v;
        for (int k = 0; k < COUNTER_FIELDS && bad == NULL; k++)
            if (!parse_u64(p, 10, &counters[k], &p))
                bad = "the line 'counters' is missing or malformed";
        if (bad == NULL && *p != '\0')
            bad = "the line 'counters' is missing or malformed";
    })
    FIELD("byte-order", strcmp(v, "little") == 0 || strcmp(v, "big") == 0, {
        uint16_t probe = 1;
        if (strcmp(v, *(unsigned char *)&probe == 1 ? "little" : "big") != 0)
            bad = "made on a machine of the other byte order";
    })
    FIELD("payload", parse_u64(v, 10, &u, NULL), *payload_bytes = (size_t)u)
#undef FIELD
    if (bad != NULL)
        snprintf(err, err_size, "%s: %s", path, bad);
    return bad == NULL;
}

/* What is wrong with the first line, or NULL: it names this ray tracer's
 * checkpoint format 2. Format 1 (before checkpoints had a checksum) is
 * named as such: a render stopped by that version cannot go on here. */
static const char *magic_problem(FILE *f)
{
    char line[64];
    size_t stem = strlen(CHECKPOINT_MAGIC_STEM);
    if (fgets(line, sizeof line, f) == NULL || strncmp(line, CHECKPOINT_MAGIC_STEM, stem) != 0)
        return "not a checkpoint of this ray tracer (its first line)";
    if (strcmp(line + stem, "1\n") == 0)
        return "a checkpoint of an older version of this ray tracer, which kept no checksum of what it holds: a "
               "render stopped by that version cannot resume in this one (render it again without --resume)";
    if (strncmp(line, CHECKPOINT_MAGIC, sizeof CHECKPOINT_MAGIC - 1) != 0 || line[sizeof CHECKPOINT_MAGIC - 1] != '\n')
        return "a checkpoint of a format this version does not read (its first line is not 'ray-tracer checkpoint 2')";
    return NULL;
}

/* The checksum line: its key, 16 lowercase hex digits (the writer's; an
 * upper-case digit would read as the same number, so a changed byte would
 * pass), a newline. */
enum { CHECKSUM_KEY_LENGTH = sizeof CHECKPOINT_CHECKSUM_KEY - 1, CHECKSUM_LINE = CHECKSUM_KEY_LENGTH + 16 + 1 };

/* What is wrong with the file as a whole, or NULL: its last line must be
 * the checksum of every byte before it, so that a checkpoint changed in
 * any byte since it was written (a disk's or a copy's error, an edit) is
 * refused before anything in it is believed. Reads the file once, in
 * blocks: no allocation, whatever its size. */
static const char *checksum_problem(FILE *f, off_t size)
{
    if (size < CHECKSUM_LINE)
        return "it ends without its checksum line (the file was cut short)";
    rewind(f);
    uint64_t h = CHECKPOINT_CHECKSUM_START;
    unsigned char block[1 << 16];
    for (off_t left = size - CHECKSUM_LINE; left > 0;) {
        size_t want = left < (off_t)sizeof block ? (size_t)left : sizeof block;
        if (fread(block, 1, want, f) != want)
            return "it could not be read whole";
        h = checkpoint_checksum(h, block, want);
        left -= (off_t)want;
    }
    char line[CHECKSUM_LINE];
    if (fread(line, 1, CHECKSUM_LINE, f) != CHECKSUM_LINE)
        return "it could not be read whole";
    bool hex = line[CHECKSUM_LINE - 1] == '\n';
    for (int i = CHECKSUM_KEY_LENGTH; i < CHECKSUM_LINE - 1; i++)
        hex = hex && ((line[i] >= '0' && line[i] <= '9') || (line[i] >= 'a' && line[i] <= 'f'));
    if (memcmp(line, CHECKPOINT_CHECKSUM_KEY, CHECKSUM_KEY_LENGTH) != 0 || !hex)
        return "its last line is not its checksum (the file was cut short, or something was added after it)";
    if (strtoull(line + CHECKSUM_KEY_LENGTH, NULL, 16) != h)
        return "damaged: what it holds does not match its checksum (a byte has changed since it was written)";
    return NULL;
}

/* "its seed is 7, this render's 1; ..." for each field that differs. */
static bool identity_differences(const checkpoint_identity *a, const checkpoint_identity *b, char *out, size_t size)
{
    size_t n = 0;
    out[0] = '\0';
#define DIFF(cond, ...)                                                                                               \
    if ((cond) && n < size)                                                                                           \
        n += (size_t)snprintf(out + n, size - n, __VA_ARGS__);
    DIFF(strcmp(a->kind, b->kind) != 0, "; it is of a %s render, this is a %s one", a->kind, b->kind)
    DIFF(strcmp(a->program, b->program) != 0, "; its program is %s, this is %s", a->program, b->program)
    DIFF(strcmp(a->scene, b->scene) != 0, "; its scene is %s, this render's %s", a->scene, b->scene)
    DIFF(strcmp(a->scene, b->scene) == 0 && a->scene_hash != b->scene_hash,
         "; its scene file %s has changed since (another hash of its bytes)", a->scene)
    DIFF(a->width != b->width || a->height != b->height, "; its size is %dx%d, this render's %dx%d", a->width,
         a->height, b->width, b->height)
    DIFF(a->spp != b->spp, "; its spp is %d, this render's %d", a->spp, b->spp)
    DIFF(a->seed != b->seed, "; its seed is %" PRIu64 ", this render's %" PRIu64, a->seed, b->seed)
    DIFF(strcmp(a->flags, b->flags) != 0, "; its other flags are '%s', this render's '%s'", a->flags, b->flags)
    DIFF(strcmp(a->version, b->version) != 0, "; it was made by version %s, this is %s", a->version, b->version)
#undef DIFF
    return n > 0;
}

bool checkpoint_read(const char *path, const checkpoint_identity *expected, size_t payload_bytes, checkpoint *out,
                     char *err, size_t err_size)
{
    memset(out, 0, sizeof *out);
    FILE *f = fopen(path, "rb");
    struct stat st;
    if (f == NULL || fstat(fileno(f), &st) != 0 || !S_ISREG(st.st_mode)) {
        snprintf(err, err_size, "%s: %s", path, f == NULL ? strerror(errno) : "not a regular file");
        if (f != NULL)
            fclose(f);
        return false;
    }
    const char *problem = magic_problem(f);
    if (problem == NULL)
        problem = checksum_problem(f, st.st_size);
    if (problem != NULL) {
        snprintf(err, err_size, "%s: %s, not resumed", path, problem);
        fclose(f);
        return false;
    }
    /* Whole and as written: now its header is read and believed. */
    rewind(f);
    char magic[64];
    size_t stored = 0;
    char differences[2 * CHECKPOINT_FLAGS_SIZE + 2048];
    bool ok = fgets(magic, sizeof magic, f) != NULL && read_header(f, path, out, &stored, err, err_size);
    if (ok && identity_differences(&out->id, expected, differences, sizeof differences)) {
        snprintf(err, err_size, "%s: a checkpoint of another render, not resumed: %s", path, differences + 2);
        ok = false;
    } else if (ok && stored != payload_bytes) {
        snprintf(err, err_size, "%s: holds %zu bytes of state where this render keeps %zu", path, stored,
                 payload_bytes);
        ok = false;
    }
    if (ok) {
        /* payload_bytes is this render's (its image's size), never the file's word */
        long at = ftell(f);
        off_t state = st.st_size - CHECKSUM_LINE - (off_t)at;
        if (at < 0 || state != (off_t)payload_bytes) {
            snprintf(err, err_size, "%s: its state is %s than its header says", path,
                     at >= 0 && state < (off_t)payload_bytes ? "shorter" : "longer");
            ok = false;
        }
    }
    if (ok) {
        out->payload_bytes = payload_bytes;
        out->payload = memory_allocate(payload_bytes > 0 ? payload_bytes : 1, 1);
        if (fread(out->payload, 1, payload_bytes, f) != payload_bytes) {
            snprintf(err, err_size, "%s: it could not be read whole", path);
            checkpoint_free(out);
            ok = false;
        }
    }
    fclose(f);
    return ok;
}
