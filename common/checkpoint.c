/* checkpoint.c -- a render's state in a file (see checkpoint.h). */
#include "checkpoint.h"

#include <errno.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "atomic_file.h"
#include "memory.h"
#include "run_record.h"

static const char CHECKPOINT_MAGIC[] = "ray-tracer checkpoint 1";

/* FNV-1a, 64 bits, of a file's bytes: a scene file edited since the
 * checkpoint was made is another scene, whatever its name. 0 if unreadable. */
static uint64_t file_hash(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (f == NULL)
        return 0;
    uint64_t h = 14695981039346656037ULL;
    int c;
    while ((c = fgetc(f)) != EOF) {
        h ^= (uint64_t)(unsigned char)c;
        h *= 1099511628211ULL;
    }
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

bool checkpoint_write(const char *path, const checkpoint *c, char *err, size_t err_size)
{
    atomic_file f;
    if (!atomic_file_open(&f, path, err, err_size))
        return false;
    const checkpoint_identity *id = &c->id;
    const uint64_t *counters = (const uint64_t *)&c->counters;
    fprintf(f.stream,
            "%s\nkind %s\nprogram %s\nversion %s\nscene %s\nscene-hash %016" PRIx64
            "\nwidth %d\nheight %d\nspp %d\nseed %" PRIu64 "\nflags %s\ndone %ld\nspp-done %ld\nseconds %.17g\ncounters",
            CHECKPOINT_MAGIC, id->kind, id->program, id->version, id->scene, id->scene_hash, id->width, id->height,
            id->spp, id->seed, id->flags, c->done, c->spp_done, c->seconds);
    for (int k = 0; k < COUNTER_FIELDS; k++)
        fprintf(f.stream, " %" PRIu64, counters[k]);
    /* The payload is this machine's memory as it is: say which order its
     * bytes are in, so another machine refuses it rather than misread it. */
    uint16_t probe = 1;
    fprintf(f.stream, "\nbyte-order %s\npayload %zu\n", *(unsigned char *)&probe == 1 ? "little" : "big",
            c->payload_bytes);
    if (c->payload_bytes > 0)
        fwrite(c->payload, 1, c->payload_bytes, f.stream);
    return atomic_file_commit(&f, err, err_size);
}

void checkpoint_free(checkpoint *c)
{
    free(c->payload);
    c->payload = NULL;
}

/* One header line "key value" into value (without the newline). */
static bool read_field(FILE *f, const char *key, char *value, size_t size)
{
    char line[CHECKPOINT_FLAGS_SIZE + 64];
    if (fgets(line, sizeof line, f) == NULL)
        return false;
    size_t n = strlen(key), len = strlen(line);
    if (len > 0 && line[len - 1] == '\n')
        line[--len] = '\0';
    if (strncmp(line, key, n) != 0 || (line[n] != ' ' && line[n] != '\0'))
        return false;
    snprintf(value, size, "%s", line[n] == ' ' ? line + n + 1 : "");
    return true;
}

/* The header into c; false if it is not one (err says where it stopped). */
static bool read_header(FILE *f, const char *path, checkpoint *c, size_t *payload_bytes, char *err, size_t err_size)
{
    char v[CHECKPOINT_FLAGS_SIZE], magic[64];
    checkpoint_identity *id = &c->id;
    uint64_t *counters = (uint64_t *)&c->counters;
    const char *bad = NULL;
    if (fgets(magic, sizeof magic, f) == NULL || strncmp(magic, CHECKPOINT_MAGIC, strlen(CHECKPOINT_MAGIC)) != 0)
        bad = "not a checkpoint of this ray tracer (its first line)";
    /* each line in turn, until one is wrong */
#define FIELD(key, ...)                                                                                            \
    if (bad == NULL && !read_field(f, key, v, sizeof v))                                                              \
        bad = "the line '" key "' is missing or malformed";                                                           \
    else if (bad == NULL) {                                                                                           \
        __VA_ARGS__;                                                                                                  \
    }
    FIELD("kind", copy_one_line(id->kind, sizeof id->kind, v))
    FIELD("program", copy_one_line(id->program, sizeof id->program, v))
    FIELD("version", copy_one_line(id->version, sizeof id->version, v))
    FIELD("scene", copy_one_line(id->scene, sizeof id->scene, v))
    FIELD("scene-hash", id->scene_hash = strtoull(v, NULL, 16))
    FIELD("width", id->width = atoi(v))
    FIELD("height", id->height = atoi(v))
    FIELD("spp", id->spp = atoi(v))
    FIELD("seed", id->seed = strtoull(v, NULL, 10))
    FIELD("flags", copy_one_line(id->flags, sizeof id->flags, v))
    FIELD("done", c->done = atol(v))
    FIELD("spp-done", c->spp_done = atol(v))
    FIELD("seconds", c->seconds = strtod(v, NULL))
    FIELD("counters", {
        char *p = v;
        for (int k = 0; k < COUNTER_FIELDS; k++)
            counters[k] = strtoull(p, &p, 10);
    })
    FIELD("byte-order", {
        uint16_t probe = 1;
        if (strcmp(v, *(unsigned char *)&probe == 1 ? "little" : "big") != 0)
            bad = "made on a machine of the other byte order";
    })
    FIELD("payload", *payload_bytes = (size_t)strtoull(v, NULL, 10))
#undef FIELD
    if (bad != NULL)
        snprintf(err, err_size, "%s: %s", path, bad);
    return bad == NULL;
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
    size_t stored = 0;
    char differences[2 * CHECKPOINT_FLAGS_SIZE + 2048];
    bool ok = read_header(f, path, out, &stored, err, err_size);
    if (ok && identity_differences(&out->id, expected, differences, sizeof differences)) {
        snprintf(err, err_size, "%s: a checkpoint of another render, not resumed: %s", path, differences + 2);
        ok = false;
    } else if (ok && stored != payload_bytes) {
        snprintf(err, err_size, "%s: holds %zu bytes of state where this render keeps %zu", path, stored,
                 payload_bytes);
        ok = false;
    }
    if (ok) {
        out->payload_bytes = payload_bytes;
        out->payload = memory_allocate(payload_bytes > 0 ? payload_bytes : 1, 1);
        if (fread(out->payload, 1, payload_bytes, f) != payload_bytes || fgetc(f) != EOF) {
            snprintf(err, err_size, "%s: its state is %s than its header says", path,
                     feof(f) ? "shorter" : "longer");
            checkpoint_free(out);
            ok = false;
        }
    }
    fclose(f);
    return ok;
}
