/* fuzz_checkpoint.c -- a libFuzzer target for the checkpoint reader: what
 * `--resume FILE` does with a crafted file (make fuzz).
 *
 * Each input is a file handed to checkpoint_read twice: as it is (nearly
 * every mutation is then refused by its checksum), and with its last line
 * made anew as the checksum of what comes before it, so that the header's
 * parser and the state's checks are reached by crafted contents too. Every
 * refusal must name the file and say something; nothing is allocated but
 * the state this render keeps (libFuzzer's -malloc_limit_mb holds the
 * target to that: make fuzz sets it far below what a header could claim).
 * What is accepted is resumed as the programs resume it: the plain render
 * (a 4x3 image, 8 samples per pixel) from its pixel states, the
 * progressive one from its image and passes, checked first as
 * program_checkpointing checks them; the render must then make an image
 * with only finite values.
 *
 * Seeds: with FUZZ_SEEDS_DIR set (make fuzz sets it), the target first
 * writes real checkpoints there, through the real writer: the last of a
 * plain render stopped before its end, and a progressive render's. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "checkpoint.h"
#include "fuzz_files.h"
#include "progressive.h"
#include "render.h"

/* The progressive render's stop: a budget, never the target error. A
 * crafted checkpoint may claim an error so large that the target would
 * take hours to meet (a real render of that error would too), so the
 * target is one no render meets and the time stops it: half a millisecond
 * after resuming a crafted file keeps the fuzzer's inputs per second up;
 * 50 ms makes the fresh render behind the seeds long enough to leave
 * checkpoints of several passes. */
static const double RESUMED_BUDGET_SECONDS = 0.0005, FRESH_BUDGET_SECONDS = 0.05;
static const double UNREACHABLE_TARGET_ERROR = 1e-12;

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

enum { WIDTH = 4, HEIGHT = 3, SPP = 8 };

static vec3 flat_radiance(const void *scene, ray r, pcg32 *rng, ray_counters *counters)
{
    (void)scene;
    (void)r;
    (void)counters;
    float u = pcg32_float(rng);
    return vec3_make(u, 0.5f, 1.0f - u);
}

static camera fuzz_camera(void)
{
    return camera_look_at(vec3_make(0, 0, 3), vec3_make(0, 0, 0), vec3_make(0, 1, 0), 40.0f, WIDTH, HEIGHT);
}

/* The identity the render here expects; `kind` "render" or "progressive". */
static checkpoint_identity identity(const char *kind)
{
    checkpoint_identity id;
    memset(&id, 0, sizeof id);
    snprintf(id.kind, sizeof id.kind, "%s", kind);
    snprintf(id.program, sizeof id.program, "fuzz");
    snprintf(id.version, sizeof id.version, "fuzz");
    snprintf(id.scene, sizeof id.scene, "built-in");
    id.width = WIDTH;
    id.height = HEIGHT;
    id.spp = SPP;
    id.seed = 1;
    return id;
}

static size_t state_bytes(const char *kind)
{
    return strcmp(kind, "render") == 0 ? (size_t)WIDTH * HEIGHT * sizeof(render_pixel_state)
                                       : (size_t)WIDTH * HEIGHT * 3 * 2 * sizeof(float);
}

static void check_image(const image *img)
{
    for (size_t i = 0; i < (size_t)WIDTH * HEIGHT * 3; i++)
        if (!isfinite(img->rgb[i])) {
            fprintf(stderr, "a resumed render made a value that is not finite\n");
            abort();
        }
}

/* The render of `kind` resumed from c (or from nothing), checkpointing to
 * `path` after every pass when it is not NULL. */
static void render(const char *kind, const checkpoint *c, const char *path)
{
    camera cam = fuzz_camera();
    checkpointing cp;
    memset(&cp, 0, sizeof cp);
    cp.path = path;
    cp.quiet = true;
    cp.id = identity(kind);
    cp.resume = c;
    cp.resuming = c != NULL;
    if (strcmp(kind, "render") == 0) {
        image img = image_make(WIDTH, HEIGHT);
        render_job job = {.cam = &cam, .spp = SPP, .seed = 1, .threads = 1, .quiet = true,
                          .radiance = flat_radiance, .jitter = true, .checkpoints = &cp};
        render_image(&job, &img, NULL);
        check_image(&img);
        image_free(&img);
    } else {
        /* A target it never meets and a budget that stops it after some
         * passes (half a ms resumed: a crafted error as large as a float
         * allows halves pass after pass, and would keep a target waiting
         * for hours, as a real render of that error would). */
        double seconds = c != NULL ? RESUMED_BUDGET_SECONDS : FRESH_BUDGET_SECONDS;
        estimate_image e = progressive_render_resumable(flat_radiance, NULL, NULL, &cam, 1, 1, seconds,
                                                        UNREACHABLE_TARGET_ERROR, NULL, &cp);
        check_image(&e.mean);
        check_image(&e.standard_error);
        estimate_image_free(&e);
    }
}

/* Real checkpoints as seeds, through the real writer: a plain render's
 * last (after 7 of 8 samples; render_image leaves it, the program would
 * remove it) and a progressive render's last. */
static void write_seeds(const char *dir)
{
    static const char *const kinds[] = {"render", "progressive"};
    for (int k = 0; k < 2; k++) {
        char path[FUZZ_PATH_SIZE];
        snprintf(path, sizeof path, "%s/%s.checkpoint", dir, kinds[k]);
        render(kinds[k], NULL, path);
    }
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    const char *dir = getenv("FUZZ_SEEDS_DIR");
    if (dir != NULL && dir[0] != '\0')
        write_seeds(dir);
    return 0;
}

/* Reads the file at path as both kinds of render; resumes what is read. */
static void read_and_resume(const char *path)
{
    static const char *const kinds[] = {"render", "progressive"};
    for (int k = 0; k < 2; k++) {
        checkpoint_identity id = identity(kinds[k]);
        checkpoint c;
        char err[8192] = "";
        size_t bytes = state_bytes(kinds[k]);
        if (!checkpoint_read(path, &id, bytes, &c, err, sizeof err)) {
            if (strncmp(err, path, strlen(path)) != 0 || strlen(err) < strlen(path) + 8 || c.payload != NULL) {
                fprintf(stderr, "bad refusal: '%s'\n", err);
                abort();
            }
            continue;
        }
        if (c.payload == NULL || c.payload_bytes != bytes)
            abort();
        const char *problem = k == 0 ? render_resume_problem(&c) : progressive_resume_problem(&c);
        /* (a progressive render of 2^30 samples so far goes on with a pass
         * of as many: long by design, not resumed here) */
        if (problem == NULL && (k == 0 || c.spp_done <= 256))
            render(kinds[k], &c, NULL);
        checkpoint_free(&c);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char path[FUZZ_PATH_SIZE];
    snprintf(path, sizeof path, "%s/fuzz.checkpoint", fuzz_scratch_dir());
    fuzz_remove_files();
    fuzz_write(path, data, size);
    read_and_resume(path);

    /* The same with its checksum made anew: the input less its last 26
     * bytes (where a checkpoint's checksum line is), then the line. */
    enum { CHECKSUM_LINE = sizeof CHECKPOINT_CHECKSUM_KEY - 1 + 16 + 1 };
    size_t body = size > CHECKSUM_LINE ? size - CHECKSUM_LINE : 0;
    unsigned char *remade = malloc(body + CHECKSUM_LINE + 1);
    if (remade == NULL)
        abort();
    if (body > 0)
        memcpy(remade, data, body);
    snprintf((char *)remade + body, CHECKSUM_LINE + 1, "%s%016llx\n", CHECKPOINT_CHECKSUM_KEY,
             (unsigned long long)checkpoint_checksum(CHECKPOINT_CHECKSUM_START, data, body));
    fuzz_write(path, remade, body + CHECKSUM_LINE);
    free(remade);
    read_and_resume(path);
    return 0;
}
