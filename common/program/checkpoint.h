/* checkpoint.h -- a long render's work so far, kept in a file, so that a
 * render stopped by a signal, a crash or a lost machine continues where it
 * stopped (--resume FILE) and ends with the image the uninterrupted render
 * makes, bit for bit.
 *
 * Usage (what program_render and progressive_render do):
 *   checkpoint_identity id = checkpoint_identity_of("render", "09-path-tracing", &opts);
 *   checkpoint c = {.id = id, .done = 128, .payload = states, .payload_bytes = n};
 *   checkpoint_write("build/out/ch09.checkpoint", &c, err, sizeof err);        atomically
 *   checkpoint r;
 *   if (!checkpoint_read(path, &id, n, &r, err, sizeof err)) ... err names the file and what differs
 *
 * The file is a few lines of text, "key value", which say what render it
 * belongs to (kind, program, version, scene file and a hash of its bytes,
 * size, samples per pixel, seed, and every other flag that changes the
 * image), how far it got, and its counters; then a line "payload N" and N
 * bytes of the render's own state, in this machine's byte order (the
 * header says which); then a last line "checksum H", H the 64-bit FNV-1a
 * hash of every byte before that line, in 16 hex digits. It is written
 * through atomic_file, so a reader finds the previous checkpoint or the
 * whole new one. A file whose checksum does not match what it holds (one
 * byte changed anywhere: a disk's or a copy's error, an edit) is refused
 * as damaged before anything in it is believed; so is a checkpoint of the
 * format before checksums. A checkpoint of another render (any of the
 * identity's fields differ) is refused, naming each field that differs.
 *
 * Why FNV-1a and not CRC-32: the project links no zlib, FNV-1a is the hash
 * it already keeps of scene files (here, one function for both), and it
 * catches every change of one byte for certain, not by chance: a changed
 * byte changes the state where it is xored in, and every later step (xor
 * with the same byte, multiply by an odd number modulo 2^64) is one to
 * one, so the two states never meet again. Other damage passes with
 * probability 2^-64. It guards against accidents, not against someone who
 * edits a checkpoint and computes its hash anew: such a file is read as
 * any other, its numbers checked, its state bounded by this render's size.
 */
#ifndef CHECKPOINT_H
#define CHECKPOINT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cli.h"
#include "counters.h"

enum { CHECKPOINT_TEXT_SIZE = 1024, CHECKPOINT_FLAGS_SIZE = 2048, CHECKPOINT_HEADER_MAX = 8192 };

/* The checksum: FNV-1a over n bytes, continuing from h (start from
 * CHECKPOINT_CHECKSUM_START); the file's last line is the key, the hash
 * in 16 lowercase hex digits, a newline. */
#define CHECKPOINT_CHECKSUM_START 14695981039346656037ULL
#define CHECKPOINT_CHECKSUM_KEY "checksum "
uint64_t checkpoint_checksum(uint64_t h, const void *data, size_t n);

/* What render a checkpoint belongs to: all of it must match to resume. */
typedef struct {
    char kind[32];     /* "render" (per-pixel state), "progressive" (merged passes) */
    char program[64];
    char version[128]; /* PROJECT_VERSION: another build may trace other paths */
    char scene[CHECKPOINT_TEXT_SIZE]; /* the scene file, or "built-in" */
    uint64_t scene_hash;              /* FNV-1a of the scene file's bytes (0: built-in) */
    int width, height, spp;
    uint64_t seed;
    char flags[CHECKPOINT_FLAGS_SIZE]; /* the other flags that change the image (run_record_image_flags) */
} checkpoint_identity;

/* How far a render got. */
typedef struct {
    checkpoint_identity id;
    long done;       /* samples per pixel done ("render"), passes done ("progressive") */
    long spp_done;   /* samples per pixel in the image so far */
    double seconds;  /* wall seconds spent on it so far */
    ray_counters counters;
    size_t payload_bytes;
    void *payload;   /* checkpoint_read allocates it; checkpoint_free frees it */
} checkpoint;

/* The identity of this run's render of kind `kind`. */
checkpoint_identity checkpoint_identity_of(const char *kind, const char *program, const cli_options *opts);

/* Writes c to path (atomically). False with err naming the file. */
bool checkpoint_write(const char *path, const checkpoint *c, char *err, size_t err_size);
/* Reads path into out, if it is a whole checkpoint (its checksum
 * matches) of the render `expected` with a payload of payload_bytes; else
 * false, with err naming the file and what is wrong: damaged, of the old
 * format, a line malformed, or, for another render's checkpoint, each
 * field that differs ("its seed is 7, this render's 1"). Allocates
 * payload_bytes, the caller's, never what the file says. */
bool checkpoint_read(const char *path, const checkpoint_identity *expected, size_t payload_bytes, checkpoint *out,
                     char *err, size_t err_size);
void checkpoint_free(checkpoint *c);

/* Where a render that writes `image_path` keeps its checkpoint when
 * --checkpoint does not say: the image's name with ".checkpoint" for its
 * extension (build/out/ch09.exr -> build/out/ch09.checkpoint). */
void checkpoint_path_for_image(const char *image_path, char *out, size_t out_size);

/* What a render needs to checkpoint and resume (render_job, progressive).
 * Named, so that render_loop.h can carry a pointer to it unseen. */
typedef struct checkpointing {
    const char *path;        /* where checkpoints go; NULL: none */
    double every_seconds;    /* at least this long between two (0: after every pass) */
    const checkpoint *resume;/* the state to continue from (rank 0 read it), or NULL */
    bool resuming;           /* on every rank: whether there is one (rank 0 sends it) */
    checkpoint_identity id;
    bool quiet;              /* no line per checkpoint */
} checkpointing;

#endif
