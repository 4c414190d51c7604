/* test_resume.c -- a render in passes with checkpoints, and one resumed
 * from its last checkpoint, make the image of one pass, bit for bit; a
 * checkpoint of another render is refused, naming what differs.
 *
 * The radiance here is a few draws of the pixel's stream (and now and then
 * a NaN, which the loop drops and counts), so a render takes microseconds
 * and any change in the numbers a pixel draws, or their order, shows.
 * A checkpoint cut short, changed in any one byte, or of the format
 * before checksums is refused with a message; one edited with its
 * checksum made anew is checked as any other. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "checkpoint.h"
#include "progressive.h"
#include "render.h"
#include "run_record.h"
#include "test_temp_dir.h"

static char test_dir[] = "/tmp/test_resume.XXXXXX";

enum { WIDTH = 16, HEIGHT = 12, SPP = 37 };

static vec3 noisy_radiance(const void *scene, ray r, pcg32 *rng, ray_counters *counters)
{
    (void)scene;
    (void)r;
    (void)counters;
    float u = pcg32_float(rng), v = pcg32_float(rng);
    if (u < 0.02f)
        return vec3_make(NAN, 0.0f, 0.0f); /* dropped and counted */
    return vec3_make(u, v * v, u * v);
}

static camera test_camera(void)
{
    return camera_look_at(vec3_make(0, 0, 3), vec3_make(0, 0, 0), vec3_make(0, 1, 0), 40.0f, WIDTH, HEIGHT);
}

/* A render of the test's job; cp may be NULL (one pass). */
static void render(const camera *cam, const checkpointing *cp, image *mean, image *error, render_stats *stats)
{
    *mean = image_make(WIDTH, HEIGHT);
    *error = image_make(WIDTH, HEIGHT);
    render_job job = {.cam = cam, .spp = SPP, .seed = 7, .threads = 2, .quiet = true, .radiance = noisy_radiance,
                      .standard_error = error, .jitter = true, .checkpoints = cp};
    render_image(&job, mean, stats);
}

static bool same_image(const image *a, const image *b)
{
    return memcmp(a->rgb, b->rgb, (size_t)WIDTH * HEIGHT * 3 * sizeof(float)) == 0;
}

static checkpointing every_pass(const char *path)
{
    checkpointing cp;
    memset(&cp, 0, sizeof cp);
    cp.path = path;
    cp.every_seconds = 0.0; /* a pass of one sample, and a checkpoint after each */
    cp.quiet = true;
    snprintf(cp.id.kind, sizeof cp.id.kind, "render");
    cp.id.width = WIDTH;
    cp.id.height = HEIGHT;
    cp.id.spp = SPP;
    cp.id.seed = 7;
    return cp;
}

static void test_passes_make_the_one_pass_image(void **state)
{
    (void)state;
    camera cam = test_camera();
    char path[256];
    snprintf(path, sizeof path, "%s/passes.checkpoint", test_dir);
    checkpointing cp = every_pass(path);
    image whole, whole_error, passes, passes_error;
    render_stats a, b;
    render(&cam, NULL, &whole, &whole_error, &a);
    render(&cam, &cp, &passes, &passes_error, &b);
    assert_true(same_image(&whole, &passes));
    assert_true(same_image(&whole_error, &passes_error));
    assert_memory_equal(&a.counters, &b.counters, sizeof a.counters);
    assert_true(a.counters.nonfinite_samples > 0); /* the NaN path was taken */
    image_free(&whole);
    image_free(&whole_error);
    image_free(&passes);
    image_free(&passes_error);
}

/* The last checkpoint (after SPP - 1 samples), resumed; and its twin, the
 * same checkpoint with every pixel's stream started again, as a resume
 * that did not keep the streams would: another image. */
static void test_resumed_render_is_the_uninterrupted_one(void **state)
{
    (void)state;
    camera cam = test_camera();
    char path[256], err[4096] = "";
    snprintf(path, sizeof path, "%s/resume.checkpoint", test_dir);
    checkpointing cp = every_pass(path);
    image whole, whole_error, img, img_error;
    render_stats stats;
    render(&cam, &cp, &whole, &whole_error, &stats);

    checkpoint resumed;
    size_t bytes = (size_t)WIDTH * HEIGHT * sizeof(render_pixel_state);
    if (!checkpoint_read(path, &cp.id, bytes, &resumed, err, sizeof err))
        fail_msg("%s", err);
    assert_int_equal(resumed.done, SPP - 1);
    cp.resume = &resumed;
    cp.resuming = true;
    cp.path = NULL; /* write no more */
    render_stats resumed_stats;
    render(&cam, &cp, &img, &img_error, &resumed_stats);
    assert_true(same_image(&whole, &img));
    assert_true(same_image(&whole_error, &img_error));
    assert_memory_equal(&stats.counters, &resumed_stats.counters, sizeof stats.counters);
    image_free(&img);
    image_free(&img_error);

    render_pixel_state *states = resumed.payload;
    for (int i = 0; i < WIDTH * HEIGHT; i++)
        states[i].rng = pcg32_for_pixel(7, (uint64_t)i);
    render(&cam, &cp, &img, &img_error, &resumed_stats);
    assert_false(same_image(&whole, &img));
    checkpoint_free(&resumed);
    image_free(&img);
    image_free(&img_error);
    image_free(&whole);
    image_free(&whole_error);
}

static void test_another_renders_checkpoint_is_refused(void **state)
{
    (void)state;
    char path[256], err[8192] = "";
    snprintf(path, sizeof path, "%s/other.checkpoint", test_dir);
    checkpointing cp = every_pass(path);
    unsigned char payload[64] = {1, 2, 3};
    checkpoint c = {.id = cp.id, .done = 3, .spp_done = 3, .seconds = 1.5, .payload_bytes = sizeof payload,
                    .payload = payload};
    c.counters.camera_rays = 12345;
    if (!checkpoint_write(path, &c, err, sizeof err))
        fail_msg("%s", err);

    checkpoint back;
    assert_true(checkpoint_read(path, &cp.id, sizeof payload, &back, err, sizeof err));
    assert_int_equal(back.done, 3);
    assert_true(back.seconds == 1.5);
    assert_int_equal(back.counters.camera_rays, 12345);
    assert_memory_equal(back.payload, payload, sizeof payload);
    checkpoint_free(&back);

    checkpoint_identity other = cp.id;
    other.seed = 8;
    other.width = 20;
    snprintf(other.flags, sizeof other.flags, "--integrator mis");
    assert_false(checkpoint_read(path, &other, sizeof payload, &back, err, sizeof err));
    assert_non_null(strstr(err, "its seed is 7, this render's 8"));
    assert_non_null(strstr(err, "its size is 16x12, this render's 20x12"));
    assert_non_null(strstr(err, "its other flags are '', this render's '--integrator mis'"));
    assert_null(strstr(err, "spp")); /* only what differs */

    assert_false(checkpoint_read(path, &cp.id, sizeof payload + 1, &back, err, sizeof err));
    assert_non_null(strstr(err, "holds 64 bytes of state where this render keeps 65"));
}

/* A checkpoint file's bytes, and writing them back. */
static unsigned char *read_bytes(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    static unsigned char bytes[4096];
    *size = fread(bytes, 1, sizeof bytes, f);
    assert_true(feof(f));
    fclose(f);
    return bytes;
}

static void write_bytes(const char *path, const unsigned char *bytes, size_t size)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(bytes, 1, size, f), size);
    assert_int_equal(fclose(f), 0);
}

/* The last line made anew: the checksum of what the bytes now hold, as
 * the writer would have made it. */
enum { CHECKSUM_LINE = sizeof CHECKPOINT_CHECKSUM_KEY - 1 + 16 + 1 };
static void checksum_anew(unsigned char *bytes, size_t size)
{
    uint64_t h = checkpoint_checksum(CHECKPOINT_CHECKSUM_START, bytes, size - CHECKSUM_LINE);
    char line[CHECKSUM_LINE + 1];
    snprintf(line, sizeof line, "%s%016llx\n", CHECKPOINT_CHECKSUM_KEY, (unsigned long long)h);
    memcpy(bytes + size - CHECKSUM_LINE, line, CHECKSUM_LINE);
}

/* A small checkpoint of the test's render, at path; its payload is 64 bytes. */
static checkpointing small_checkpoint(const char *path)
{
    checkpointing cp = every_pass(path);
    unsigned char payload[64];
    for (int i = 0; i < 64; i++)
        payload[i] = (unsigned char)(i * 37);
    checkpoint c = {.id = cp.id, .done = 5, .spp_done = 5, .seconds = 2.25, .payload_bytes = sizeof payload,
                    .payload = payload};
    c.counters.camera_rays = 987;
    char err[1024];
    if (!checkpoint_write(path, &c, err, sizeof err))
        fail_msg("%s", err);
    return cp;
}

/* Cut short anywhere (a disk full, a copy stopped), it is refused: it
 * ends without its checksum line, or that line is not whole. */
static void test_a_cut_file_is_refused(void **state)
{
    (void)state;
    char path[256], err[4096] = "";
    snprintf(path, sizeof path, "%s/cut.checkpoint", test_dir);
    checkpointing cp = small_checkpoint(path);
    size_t size;
    const unsigned char *bytes = read_bytes(path, &size);
    unsigned char whole[4096] = {0};
    memcpy(whole, bytes, size);
    for (size_t cut = 0; cut < size; cut++) {
        write_bytes(path, whole, cut);
        checkpoint back;
        if (checkpoint_read(path, &cp.id, 64, &back, err, sizeof err))
            fail_msg("cut to %zu of %zu bytes, it was read", cut, size);
        assert_null(back.payload);
        if (cut > 30 && strstr(err, "checksum") == NULL)
            fail_msg("cut to %zu bytes: '%s'", cut, err);
    }
    write_bytes(path, whole, size - 10);
    checkpoint back;
    assert_false(checkpoint_read(path, &cp.id, 64, &back, err, sizeof err));
    assert_non_null(strstr(err, "its last line is not its checksum"));
}

/* One byte changed anywhere (header, state or the checksum itself; two
 * ways: its lowest bit, and its 0x20 bit, which turns a hex digit's case
 * and would read as the same number) is refused with a message, and the
 * state is never handed over. The twin: the same change in the state with
 * the checksum made anew is read, and holds the changed byte: it is the
 * checksum that refuses, nothing else would. */
static void test_one_changed_byte_anywhere_is_refused(void **state)
{
    (void)state;
    char path[256], err[4096] = "";
    snprintf(path, sizeof path, "%s/changed.checkpoint", test_dir);
    checkpointing cp = small_checkpoint(path);
    size_t size;
    const unsigned char *bytes = read_bytes(path, &size);
    unsigned char whole[4096], changed[4096];
    memcpy(whole, bytes, size);
    checkpoint back;
    assert_true(checkpoint_read(path, &cp.id, 64, &back, err, sizeof err));
    checkpoint_free(&back);
    size_t payload_at = size - CHECKSUM_LINE - 64;
    int damaged = 0;
    for (size_t i = 0; i < size; i++)
        for (int flip = 0x01; flip <= 0x20; flip += 0x1f) {
            memcpy(changed, whole, size);
            changed[i] ^= (unsigned char)flip;
            write_bytes(path, changed, size);
            if (checkpoint_read(path, &cp.id, 64, &back, err, sizeof err))
                fail_msg("byte %zu of %zu xor 0x%02x was read", i, size, flip);
            assert_null(back.payload);
            assert_true(strncmp(err, path, strlen(path)) == 0 && strlen(err) > strlen(path) + 10);
            damaged += strstr(err, "damaged: what it holds does not match its checksum") != NULL;
        }
    /* all but the first line's stem and the checksum line's key and newline
     * are caught by the checksum itself */
    assert_true(damaged >= 2 * (int)(size - CHECKSUM_LINE - 23));

    for (size_t i = payload_at; i < payload_at + 64; i++) { /* the twin */
        memcpy(changed, whole, size);
        changed[i] ^= 0x01;
        checksum_anew(changed, size);
        write_bytes(path, changed, size);
        if (!checkpoint_read(path, &cp.id, 64, &back, err, sizeof err))
            fail_msg("byte %zu changed, checksum made anew: '%s'", i, err);
        assert_int_equal(((unsigned char *)back.payload)[i - payload_at], whole[i] ^ 0x01);
        checkpoint_free(&back);
    }
}

/* A render stopped by the version before checksums (format 1: its first
 * line, no checksum line) is refused, saying so. */
static void test_a_checkpoint_without_checksum_is_refused(void **state)
{
    (void)state;
    char path[256], err[4096] = "";
    snprintf(path, sizeof path, "%s/old.checkpoint", test_dir);
    checkpointing cp = small_checkpoint(path);
    size_t size;
    unsigned char *bytes = read_bytes(path, &size);
    unsigned char *two = (unsigned char *)memchr(bytes, '\n', size) - 1;
    assert_int_equal(*two, '2');
    *two = '1';
    write_bytes(path, bytes, size - CHECKSUM_LINE);
    checkpoint back;
    assert_false(checkpoint_read(path, &cp.id, 64, &back, err, sizeof err));
    assert_non_null(strstr(err, "an older version of this ray tracer, which kept no checksum"));
    assert_non_null(strstr(err, "cannot resume in this one"));
}

/* A file edited with its checksum made anew is read as any other: each
 * number whole and in range, the state what a render makes, its size this
 * render's (never the file's word). */
static void test_a_crafted_checkpoint_is_checked(void **state)
{
    (void)state;
    char path[256], err[4096] = "";
    snprintf(path, sizeof path, "%s/crafted.checkpoint", test_dir);
    checkpointing cp = small_checkpoint(path);
    size_t size;
    const unsigned char *bytes = read_bytes(path, &size);
    unsigned char whole[4096] = {0};
    memcpy(whole, bytes, size);
    const struct {
        const char *from, *to, *message;
    } edits[] = {
        {"\ndone 5\n", "\ndone -5\n", "the line 'done' is missing or malformed"},
        {"\nwidth 16\n", "\nwidth 16x\n", "the line 'width' is missing or malformed"},
        {"\nheight 12\n", "\nheight 99999999999999999999\n", "the line 'height' is missing or malformed"},
        {"\nseconds 2.25\n", "\nseconds nan\n", "the line 'seconds' is missing or malformed"},
        {"\ncounters ", "\ncounters -", "the line 'counters' is missing or malformed"},
        {"\npayload 64\n", "\npayload 18446744073709551615\n", "holds 18446744073709551615 bytes of state"},
    };
    for (size_t e = 0; e < sizeof edits / sizeof edits[0]; e++) {
        unsigned char edited[4200];
        const char *at = strstr((const char *)whole, edits[e].from);
        assert_non_null(at);
        size_t before = (size_t)(at - (const char *)whole), from = strlen(edits[e].from), to = strlen(edits[e].to);
        memcpy(edited, whole, before);
        memcpy(edited + before, edits[e].to, to);
        memcpy(edited + before + to, whole + before + from, size - before - from);
        size_t n = size - from + to;
        checksum_anew(edited, n);
        write_bytes(path, edited, n);
        checkpoint back;
        assert_false(checkpoint_read(path, &cp.id, 64, &back, err, sizeof err));
        if (strstr(err, edits[e].message) == NULL)
            fail_msg("'%s' -> '%s': '%s'", edits[e].from, edits[e].to, err);
        assert_null(back.payload);
    }

    /* The state of a render: finite sums of at most the samples done. */
    render_pixel_state states[WIDTH * HEIGHT];
    memset(states, 0, sizeof states);
    checkpoint c = {.id = cp.id, .done = 5, .spp_done = 5, .payload_bytes = sizeof states, .payload = states};
    assert_null(render_resume_problem(&c));
    states[7].channel[1].m2 = NAN;
    assert_non_null(render_resume_problem(&c));
    states[7].channel[1].m2 = -1.0;
    assert_non_null(render_resume_problem(&c));
    states[7].channel[1].m2 = 0.0;
    states[7].channel[0].mean = 1e300; /* finite, but infinite as the image's float (found by fuzz_checkpoint) */
    assert_non_null(render_resume_problem(&c));
    states[7].channel[0].mean = 0.0;
    states[7].channel[0].count = 3;
    states[7].channel[0].m2 = 1e300; /* a standard error of 2.9e149 */
    assert_non_null(render_resume_problem(&c));
    states[7].channel[0].m2 = 0.0;
    states[7].channel[2].count = 6;
    assert_non_null(render_resume_problem(&c));
    states[7].channel[2].count = 5;
    c.done = SPP + 1;
    c.spp_done = SPP + 1;
    assert_non_null(render_resume_problem(&c));

    /* A progressive render's: 2^k samples after k passes, a finite image,
     * a standard error not negative. */
    float image[2 * WIDTH * HEIGHT * 3] = {0};
    checkpoint p = {.done = 5, .spp_done = 32, .payload_bytes = sizeof image, .payload = image};
    assert_null(progressive_resume_problem(&p));
    p.spp_done = 33;
    assert_non_null(progressive_resume_problem(&p));
    p.done = 31;
    p.spp_done = 1L << 31;
    assert_non_null(progressive_resume_problem(&p));
    p.done = 5;
    p.spp_done = 32;
    image[3] = INFINITY;
    assert_non_null(progressive_resume_problem(&p));
    image[3] = 0.0f;
    image[WIDTH * HEIGHT * 3 + 2] = -1.0f;
    assert_non_null(progressive_resume_problem(&p));
}

/* What must match to resume: the flags that change the image, not where
 * it goes, how many threads, how long to go on. */
static void test_image_flags_leave_out_what_does_not_change_the_image(void **state)
{
    (void)state;
    char *argv[] = {"prog",      "--out",  "x.exr", "--threads=3", "--integrator", "mis", "--quiet",
                    "--resume",  "a.ckpt", "--spp", "64",          "--max-depth=5", "--target-error", "0.1"};
    cli_options opts = cli_defaults("x.exr", 8, 8, 1);
    run_record_command((int)(sizeof argv / sizeof argv[0]), argv, &opts);
    char flags[256];
    run_record_image_flags(flags, sizeof flags);
    assert_string_equal(flags, "--integrator mis --max-depth=5");
}

TEST_TEMP_DIR_FIXTURES(test_dir)

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_passes_make_the_one_pass_image),
        cmocka_unit_test(test_resumed_render_is_the_uninterrupted_one),
        cmocka_unit_test(test_another_renders_checkpoint_is_refused),
        cmocka_unit_test(test_a_cut_file_is_refused),
        cmocka_unit_test(test_one_changed_byte_anywhere_is_refused),
        cmocka_unit_test(test_a_checkpoint_without_checksum_is_refused),
        cmocka_unit_test(test_a_crafted_checkpoint_is_checked),
        cmocka_unit_test(test_image_flags_leave_out_what_does_not_change_the_image),
    };
    return cmocka_run_group_tests(tests, make_test_dir, remove_test_dir);
}
