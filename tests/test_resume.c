/* test_resume.c -- a render in passes with checkpoints, and one resumed
 * from its last checkpoint, make the image of one pass, bit for bit; a
 * checkpoint of another render is refused, naming what differs.
 *
 * The radiance here is a few draws of the pixel's stream (and now and then
 * a NaN, which the loop drops and counts), so a render takes microseconds
 * and any change in the numbers a pixel draws, or their order, shows. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "checkpoint.h"
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

static void test_a_cut_file_is_refused(void **state)
{
    (void)state;
    char path[256], err[4096] = "";
    snprintf(path, sizeof path, "%s/cut.checkpoint", test_dir);
    checkpointing cp = every_pass(path);
    unsigned char payload[64] = {0};
    checkpoint c = {.id = cp.id, .payload_bytes = sizeof payload, .payload = payload};
    assert_true(checkpoint_write(path, &c, err, sizeof err));
    struct stat st;
    assert_int_equal(stat(path, &st), 0);
    assert_int_equal(truncate(path, st.st_size - 10), 0); /* the state cut short */
    checkpoint back;
    assert_false(checkpoint_read(path, &cp.id, sizeof payload, &back, err, sizeof err));
    assert_non_null(strstr(err, "shorter than its header says"));
    assert_null(back.payload);
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
        cmocka_unit_test(test_image_flags_leave_out_what_does_not_change_the_image),
    };
    return cmocka_run_group_tests(tests, make_test_dir, remove_test_dir);
}
