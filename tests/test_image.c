/* test_image.c -- tests for common/core/image.c and common/program/image_file.c.
 *
 * EXR: a bit-exact round trip, files that image_write_exr never makes (half
 * channels, extra or missing channels, an offset data window, every
 * lossless compression), and the promise that a write never leaves a
 * half-written or temporary file. PNG: known 8-bit values read back with
 * stb_image. Then the sRGB curve and the error metrics, against numbers
 * worked out by hand.
 *
 * Everything is written under a fresh mkdtemp directory in /tmp, removed at
 * the end.
 *
 * Build: gcc -std=c11 -D_DEFAULT_SOURCE -Icommon/core -Icommon/program -I/usr/include/OpenEXR \
 *          tests/test_image.c common/core/image.c common/program/image_file.c \
 *          common/program/atomic_file.c -lOpenEXRCore -lstb -lcmocka -lm
 */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include "image.h"
#include "image_file.h"
#include "rng.h"
#include "test_support.h"
#include "test_temp_dir.h"

#include <dirent.h>
#include <errno.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <openexr.h>
#include <stb/stb_image.h>

enum { PATH_SIZE = 4096 };

static char test_dir[] = "/tmp/test_image.XXXXXX";

/* ---- helpers ----------------------------------------------------------- */

#define assert_contains(haystack, needle)                                                                 \
    do {                                                                                                  \
        if (strstr((haystack), (needle)) == NULL)                                                         \
            fail_msg("\"%s\" does not contain \"%s\"", (haystack), (needle));                             \
    } while (0)

static const char *in_dir(char *buf, const char *name)
{
    snprintf(buf, PATH_SIZE, "%s/%s", test_dir, name);
    return buf;
}

static bool file_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

static long long file_size(const char *path)
{
    struct stat st;
    assert_int_equal(stat(path, &st), 0);
    return (long long)st.st_size;
}

static void write_text(const char *path, const char *text, int repeat)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    for (int i = 0; i < repeat; i++)
        fputs(text, f);
    assert_int_equal(fclose(f), 0);
}

/* Temporary files are named "<target>.tmp.<...>" by image.c; none may
 * outlive a call, successful or not. */
static int count_temp_files(const char *dir)
{
    DIR *d = opendir(dir);
    assert_non_null(d);
    int count = 0;
    for (struct dirent *e; (e = readdir(d)) != NULL;)
        if (strstr(e->d_name, ".tmp.") != NULL)
            count++;
    closedir(d);
    return count;
}

TEST_TEMP_DIR_FIXTURES(test_dir)

/* Every pixel and channel different (so a swapped row, column or channel
 * shows), signs alternating, magnitudes from 1e-6 to 1e6, and in the top
 * row the awkward values: -0, a denormal, the smallest normal, +-1e30,
 * infinity and a NaN. */
static image varied_image(int width, int height)
{
    image img = image_make(width, height);
    assert_non_null(img.rgb);
    for (int y = 0; y < height; y++)
        for (int x = 0; x < width; x++)
            for (int c = 0; c < 3; c++) {
                float v = (float)((y * width + x) * 3 + c) + 0.1f;
                v *= ((x + y + c) % 2) ? -1.0f : 1.0f;
                v *= powf(10.0f, (float)((x * 7 + y * 3 + c) % 13 - 6));
                img.rgb[((size_t)y * (size_t)width + (size_t)x) * 3 + (size_t)c] = v;
            }
    image_set(&img, 0, 0, vec3_make(-0.0f, 1e-40f, FLT_MIN));
    image_set(&img, 1, 0, vec3_make(1e30f, -1e30f, INFINITY));
    image_set(&img, 2, 0, vec3_make(NAN, -INFINITY, -1e-42f));
    return img;
}

/* A finite image for the metrics (varied_image's inf and NaN would make
 * every difference NaN). */
static image ramp_image(int width, int height)
{
    image img = image_make(width, height);
    assert_non_null(img.rgb);
    for (int y = 0; y < height; y++)
        for (int x = 0; x < width; x++)
            image_set(&img, x, y, vec3_make((float)x * 0.5f, (float)y * 0.25f, (float)(x + y) - 3.0f));
    return img;
}

static size_t image_bytes(const image *img)
{
    return (size_t)img->width * (size_t)img->height * 3 * sizeof(float);
}

/* ---- EXR files made directly with the Core API -------------------------- */

/* Files image_write_exr never makes (other channel sets and types, offset
 * windows, other compressions), so image_read_exr meets them in tests. */
typedef struct {
    const char *name;
    exr_pixel_type_t type;
} test_channel;

static exr_attr_box2i_t make_window(int x0, int y0, int width, int height)
{
    exr_attr_box2i_t w;
    memset(&w, 0, sizeof w);
    w.min.x = x0;
    w.min.y = y0;
    w.max.x = x0 + width - 1;
    w.max.y = y0 + height - 1;
    return w;
}

/* A value exactly representable in half, distinct per channel and pixel,
 * in file coordinates (x, y may be negative). */
static float test_value(int x, int y, const char *channel)
{
    float base = (float)x * 0.5f + (float)y * 0.25f;
    switch (channel[0]) {
    case 'R': return base;
    case 'G': return -base - 100.0f;
    case 'B': return base * 2.0f + 1000.0f;
    default: return 7.0f; /* A, Y, Z, ...: must not end up in the image */
    }
}

static void write_test_exr(const char *path, const test_channel *channels, int count, exr_attr_box2i_t window,
                           exr_compression_t compression)
{
    int width = window.max.x - window.min.x + 1, height = window.max.y - window.min.y + 1;
    float *planes = malloc(sizeof(float) * (size_t)(width * height * count));
    assert_non_null(planes);
    for (int c = 0; c < count; c++)
        for (int y = 0; y < height; y++)
            for (int x = 0; x < width; x++)
                planes[(c * height + y) * width + x] = test_value(window.min.x + x, window.min.y + y, channels[c].name);

    exr_context_t ctxt = NULL;
    assert_int_equal(exr_start_write(&ctxt, path, EXR_WRITE_FILE_DIRECTLY, NULL), EXR_ERR_SUCCESS);
    int part = -1;
    assert_int_equal(exr_add_part(ctxt, NULL, EXR_STORAGE_SCANLINE, &part), EXR_ERR_SUCCESS);
    exr_attr_v2f_t center;
    memset(&center, 0, sizeof center);
    assert_int_equal(exr_initialize_required_attr(ctxt, part, &window, &window, 1.0f, &center, 1.0f,
                                                  EXR_LINEORDER_INCREASING_Y, compression),
                     EXR_ERR_SUCCESS);
    for (int c = 0; c < count; c++)
        assert_int_equal(exr_add_channel(ctxt, part, channels[c].name, channels[c].type,
                                         EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1),
                         EXR_ERR_SUCCESS);
    assert_int_equal(exr_write_header(ctxt), EXR_ERR_SUCCESS);

    int32_t lines = 0;
    assert_int_equal(exr_get_scanlines_per_chunk(ctxt, part, &lines), EXR_ERR_SUCCESS);
    exr_encode_pipeline_t encoder = EXR_ENCODE_PIPELINE_INITIALIZER;
    for (int y = window.min.y; y <= window.max.y; y += lines) {
        exr_chunk_info_t chunk;
        assert_int_equal(exr_write_scanline_chunk_info(ctxt, part, y, &chunk), EXR_ERR_SUCCESS);
        bool first = y == window.min.y;
        if (first)
            assert_int_equal(exr_encoding_initialize(ctxt, part, &chunk, &encoder), EXR_ERR_SUCCESS);
        else
            assert_int_equal(exr_encoding_update(ctxt, part, &chunk, &encoder), EXR_ERR_SUCCESS);
        for (int e = 0; e < encoder.channel_count; e++) {
            exr_coding_channel_info_t *ch = &encoder.channels[e];
            int c = 0;
            while (strcmp(channels[c].name, ch->channel_name) != 0)
                c++;
            ch->user_bytes_per_element = (int16_t)sizeof(float);
            ch->user_data_type = (uint16_t)EXR_PIXEL_FLOAT; /* the library converts to half */
            ch->user_pixel_stride = (int32_t)sizeof(float);
            ch->user_line_stride = (int32_t)sizeof(float) * width;
            ch->encode_from_ptr = (const uint8_t *)(planes + (c * height + (chunk.start_y - window.min.y)) * width);
        }
        if (first)
            assert_int_equal(exr_encoding_choose_default_routines(ctxt, part, &encoder), EXR_ERR_SUCCESS);
        assert_int_equal(exr_encoding_run(ctxt, part, &encoder), EXR_ERR_SUCCESS);
    }
    assert_int_equal(exr_encoding_destroy(ctxt, &encoder), EXR_ERR_SUCCESS);
    assert_int_equal(exr_finish(&ctxt), EXR_ERR_SUCCESS);
    free(planes);
}

/* Reads path and checks it holds test_value over window, R G B only. */
static void assert_reads_test_values(const char *path, exr_attr_box2i_t window)
{
    char err[IMAGE_ERROR_SIZE] = "";
    image img;
    if (!image_read_exr(&img, path, err, sizeof err))
        fail_msg("%s", err);
    assert_int_equal(img.width, window.max.x - window.min.x + 1);
    assert_int_equal(img.height, window.max.y - window.min.y + 1);
    for (int y = 0; y < img.height; y++)
        for (int x = 0; x < img.width; x++) {
            vec3 got = image_get(&img, x, y);
            int fx = window.min.x + x, fy = window.min.y + y;
            assert_true(got.x == test_value(fx, fy, "R"));
            assert_true(got.y == test_value(fx, fy, "G"));
            assert_true(got.z == test_value(fx, fy, "B"));
        }
    image_free(&img);
}

/* ---- image_make / image_free ------------------------------------------- */

static void test_make_starts_black_and_rejects_bad_sizes(void **state)
{
    (void)state;
    image img = image_make(37, 23);
    assert_non_null(img.rgb);
    assert_int_equal(img.width, 37);
    assert_int_equal(img.height, 23);
    for (size_t i = 0; i < 37 * 23 * 3; i++)
        assert_true(img.rgb[i] == 0.0f);
    image_free(&img);
    assert_null(img.rgb);
    image_free(&img); /* twice is harmless */

    assert_null(image_make(0, 10).rgb);
    assert_null(image_make(10, 0).rgb);
    assert_null(image_make(-3, 10).rgb);
    /* INT_MAX^2 * 3 floats overflows size_t: must fail, not wrap to a
     * small allocation. */
    assert_null(image_make(INT_MAX, INT_MAX).rgb);
}

/* ---- EXR ---------------------------------------------------------------- */

static void test_exr_round_trip_is_bit_identical(void **state)
{
    (void)state;
    char path[PATH_SIZE], err[IMAGE_ERROR_SIZE] = "";
    in_dir(path, "round_trip.exr");
    /* 37 x 23: not square, and 23 rows make a full 16-line ZIP chunk plus a
     * partial one. */
    image a = varied_image(37, 23);
    if (!image_write_exr(&a, path, err, sizeof err))
        fail_msg("%s", err);

    image b;
    if (!image_read_exr(&b, path, err, sizeof err))
        fail_msg("%s", err);
    assert_int_equal(b.width, 37);
    assert_int_equal(b.height, 23);
    /* memcmp, not ==: -0, the NaN and the denormals must survive bit for bit. */
    assert_memory_equal(a.rgb, b.rgb, image_bytes(&a));
    /* Rows not flipped: the awkward values written into row 0 are in row 0. */
    assert_true(image_get(&b, 1, 0).x == 1e30f);
    assert_true(isnan(image_get(&b, 2, 0).x));
    assert_true(image_get(&b, 0, 22).x == a.rgb[(22 * 37 + 0) * 3]);
    assert_int_equal(count_temp_files(test_dir), 0);
    image_free(&a);
    image_free(&b);
}

/* Round trips of one-chunk images (64 x 16: one ZIP chunk of 12 288
 * bytes) whose noise leaves deflate about as long as the pixels: a few
 * random pixels in a hundred set to one value. Those that do not shrink
 * are stored raw; OpenEXR's Core library before 3.2 stores some of them
 * (deflated to exactly the raw length) as deflated bytes under the raw
 * length, which every reader decodes as garbage pixels: a noisy render's
 * EXR had one 16-row block of values up to 3e38 and NaN. `fallback` false
 * is the twin: raw chunks stored with other bytes than the pixels'.
 * Returns how many images come back different. */
static int noisy_round_trips(const char *path, bool fallback, long *raw, long *library_would_break)
{
    char err[IMAGE_ERROR_SIZE] = "";
    pcg32 rng = pcg32_for_pixel(test_seed(5), 0);
    long raw_before, broken_before;
    image_exr_raw_chunks(&raw_before, &broken_before);
    image_exr_raw_fallback(fallback);
    int different = 0;
    for (int i = 0; i < 400; i++) {
        image a = image_make(64, 16);
        /* the share of repeated pixels, swept over the range where deflate
         * comes out near the raw length, so that some chunks land on it */
        const float repeated_lo = 0.03f, repeated_span = 0.016f;
        float p = repeated_lo + repeated_span * (float)i / 400.0f;
        for (size_t k = 0; k < (size_t)64 * 16 * 3; k++) {
            float u = pcg32_float(&rng);
            a.rgb[k] = u < p ? 0.25f : pcg32_float(&rng);
        }
        image b;
        if (!image_write_exr(&a, path, err, sizeof err) || !image_read_exr(&b, path, err, sizeof err))
            fail_msg("%s", err);
        different += memcmp(a.rgb, b.rgb, image_bytes(&a)) != 0;
        image_free(&a);
        image_free(&b);
    }
    image_exr_raw_fallback(true);
    image_exr_raw_chunks(raw, library_would_break);
    *raw -= raw_before;
    *library_would_break -= broken_before;
    return different;
}

static void test_exr_round_trip_is_bit_identical_where_zip_does_not_shrink(void **state)
{
    (void)state;
    char path[PATH_SIZE];
    in_dir(path, "noisy.exr");
    long raw, broken, twin_raw, twin_broken;
    int different = noisy_round_trips(path, true, &raw, &broken);
    int twin = noisy_round_trips(path, false, &twin_raw, &twin_broken);
    print_message("400 noisy chunks: %ld stored raw (%ld that this OpenEXR would have stored wrong), %d come back "
                  "different; raw chunks with the wrong bytes (twin): %d different\n",
                  raw, broken, different, twin);
    assert_true(raw > 0);
    assert_int_equal(different, 0);
    assert_true(twin > 0);
    assert_int_equal(count_temp_files(test_dir), 0);
}

static void test_exr_overwrite_replaces_the_whole_file(void **state)
{
    (void)state;
    char path[PATH_SIZE], fresh[PATH_SIZE], err[IMAGE_ERROR_SIZE] = "";
    in_dir(path, "overwrite.exr");
    in_dir(fresh, "overwrite_fresh.exr");
    /* Much longer than the EXR that replaces it: writing in place without
     * truncating would leave a tail of text. */
    write_text(path, "old contents, not an image. ", 10000);

    image small = varied_image(5, 4);
    assert_true(image_write_exr(&small, path, err, sizeof err));
    assert_true(image_write_exr(&small, fresh, err, sizeof err));
    assert_int_equal(file_size(path), file_size(fresh));
    image back;
    assert_true(image_read_exr(&back, path, err, sizeof err));
    assert_int_equal(back.width, 5);
    assert_int_equal(back.height, 4);
    assert_memory_equal(back.rgb, small.rgb, image_bytes(&small));
    image_free(&back);

    /* And an EXR over an EXR of another size. */
    image other = ramp_image(9, 17);
    assert_true(image_write_exr(&other, path, err, sizeof err));
    assert_true(image_read_exr(&back, path, err, sizeof err));
    assert_int_equal(back.width, 9);
    assert_int_equal(back.height, 17);
    assert_memory_equal(back.rgb, other.rgb, image_bytes(&other));
    assert_int_equal(count_temp_files(test_dir), 0);
    image_free(&back);
    image_free(&other);
    image_free(&small);
}

static void test_write_into_missing_directory_fails_cleanly(void **state)
{
    (void)state;
    char path[PATH_SIZE], err[IMAGE_ERROR_SIZE] = "";
    image img = varied_image(4, 3);

    in_dir(path, "no/such/dir/x.exr");
    assert_false(image_write_exr(&img, path, err, sizeof err));
    assert_contains(err, path);
    assert_contains(err, strerror(ENOENT));
    assert_false(file_exists(path));

    in_dir(path, "no/such/dir/x.png");
    err[0] = '\0';
    assert_false(image_write_png(&img, path, 0.0f, err, sizeof err));
    assert_contains(err, path);
    assert_contains(err, strerror(ENOENT));
    assert_false(file_exists(path));

    assert_int_equal(count_temp_files(test_dir), 0);
    image_free(&img);
}

static void test_write_into_read_only_directory_fails_cleanly(void **state)
{
    (void)state;
    if (geteuid() == 0)
        skip(); /* root writes anywhere, so there is nothing to observe */
    char dir[PATH_SIZE], path[PATH_SIZE], err[IMAGE_ERROR_SIZE] = "";
    in_dir(dir, "read_only");
    in_dir(path, "read_only/x.exr");
    assert_int_equal(mkdir(dir, 0500), 0);
    image img = varied_image(4, 3);
    bool ok = image_write(&img, path, 0.0f, err, sizeof err);
    chmod(dir, 0700);
    assert_false(ok);
    assert_contains(err, path);
    assert_contains(err, strerror(EACCES));
    assert_false(file_exists(path));
    assert_int_equal(count_temp_files(dir), 0);
    image_free(&img);
}

/* A write that fails half way (here: the file size limit, EFBIG) must leave
 * the previous file exactly as it was and no temporary file. */
static void test_failed_write_keeps_the_old_file(void **state)
{
    (void)state;
    char exr_path[PATH_SIZE], png_path[PATH_SIZE], err_exr[IMAGE_ERROR_SIZE] = "",
                                                   err_png[IMAGE_ERROR_SIZE] = "";
    in_dir(exr_path, "keep.exr");
    in_dir(png_path, "keep.png");
    image old = varied_image(6, 5);
    assert_true(image_write(&old, exr_path, 0.0f, err_exr, sizeof err_exr));
    long long old_png_size = file_size(png_path);

    /* Noise compresses badly, so both files would be far over the limit. */
    image big = image_make(200, 150);
    assert_non_null(big.rgb);
    unsigned state_bits = 12345u;
    for (size_t i = 0; i < 200 * 150 * 3; i++) {
        state_bits = state_bits * 1664525u + 1013904223u;
        big.rgb[i] = (float)(state_bits >> 8) / 16777216.0f;
    }

    struct rlimit saved, limited;
    assert_int_equal(getrlimit(RLIMIT_FSIZE, &saved), 0);
    limited = saved;
    limited.rlim_cur = 4096;
    void (*saved_handler)(int) = signal(SIGXFSZ, SIG_IGN); /* get EFBIG, not a signal */
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &limited), 0);
    /* Nothing is asserted (or printed) until the limit is lifted again. */
    bool exr_ok = image_write_exr(&big, exr_path, err_exr, sizeof err_exr);
    bool png_ok = image_write_png(&big, png_path, 0.0f, err_png, sizeof err_png);
    setrlimit(RLIMIT_FSIZE, &saved);
    signal(SIGXFSZ, saved_handler);

    assert_false(exr_ok);
    assert_contains(err_exr, exr_path);
    assert_contains(err_exr, strerror(EFBIG));
    assert_false(png_ok);
    assert_contains(err_png, png_path);
    assert_contains(err_png, strerror(EFBIG));

    image back;
    char err[IMAGE_ERROR_SIZE] = "";
    assert_true(image_read_exr(&back, exr_path, err, sizeof err));
    assert_int_equal(back.width, 6);
    assert_memory_equal(back.rgb, old.rgb, image_bytes(&old));
    assert_int_equal(file_size(png_path), old_png_size);
    assert_int_equal(count_temp_files(test_dir), 0);
    image_free(&back);
    image_free(&big);
    image_free(&old);
}

/* A disk that is full from the first byte (file size limit 0): the write
 * fails inside the EXR header, where OpenEXR holds its context lock while it
 * reports the error. An error handler that asked the context for its user
 * data there waited for that lock forever. The write runs in a child
 * process with an alarm, so a deadlock fails this test instead of hanging
 * the suite; the child reports through its exit status. */
enum { FULL_DISK_OK = 0, FULL_DISK_WROTE = 1, FULL_DISK_NO_PATH = 2, FULL_DISK_LEFT_FILES = 3 };

static int write_on_a_full_disk(const char *path, rlim_t limit)
{
    image img = varied_image(64, 48);
    char err[IMAGE_ERROR_SIZE] = "";
    struct rlimit limited;
    getrlimit(RLIMIT_FSIZE, &limited);
    limited.rlim_cur = limit;
    signal(SIGXFSZ, SIG_IGN); /* get EFBIG, not a signal */
    setrlimit(RLIMIT_FSIZE, &limited);
    bool ok = image_write(&img, path, 0.0f, err, sizeof err);
    image_free(&img);
    if (ok)
        return FULL_DISK_WROTE;
    if (strstr(err, path) == NULL)
        return FULL_DISK_NO_PATH;
    return count_temp_files(test_dir) == 0 && !file_exists(path) ? FULL_DISK_OK : FULL_DISK_LEFT_FILES;
}

static void test_write_to_a_disk_full_from_the_first_byte_fails_cleanly(void **state)
{
    (void)state;
    const char *names[] = {"full.exr", "full.png"};
    /* Nothing at all; one byte; past the PNG signature but inside the EXR
     * header; past the EXR header (both files are several KB). */
    const rlim_t limits[] = {0, 1, 100, 1000};
    for (int n = 0; n < 2; n++)
        for (int l = 0; l < 4; l++) {
            char path[PATH_SIZE];
            in_dir(path, names[n]);
            fflush(NULL);
            pid_t child = fork();
            assert_true(child >= 0);
            if (child == 0) {
                alarm(20); /* a deadlock ends here, as SIGALRM */
                _exit(write_on_a_full_disk(path, limits[l]));
            }
            int status = 0;
            assert_int_equal(waitpid(child, &status, 0), child);
            if (WIFSIGNALED(status))
                fail_msg("%s with a %ld-byte limit: killed by signal %d (%s)", names[n], (long)limits[l],
                         WTERMSIG(status), WTERMSIG(status) == SIGALRM ? "hung: deadlock" : "crash");
            if (WEXITSTATUS(status) != FULL_DISK_OK)
                fail_msg("%s with a %ld-byte limit: %s", names[n], (long)limits[l],
                         WEXITSTATUS(status) == FULL_DISK_WROTE     ? "the write reported success"
                         : WEXITSTATUS(status) == FULL_DISK_NO_PATH ? "the message does not name the file"
                                                                    : "a file was left behind");
            char exr_path[PATH_SIZE], png_path[PATH_SIZE];
            assert_false(file_exists(in_dir(exr_path, "full.exr")));
            assert_false(file_exists(in_dir(png_path, "full.png")));
            assert_int_equal(count_temp_files(test_dir), 0);
        }
}

static void test_read_missing_file_fails(void **state)
{
    (void)state;
    char path[PATH_SIZE], err[IMAGE_ERROR_SIZE] = "";
    in_dir(path, "does_not_exist.exr");
    float sentinel = 0.0f;
    image img = {7, 7, &sentinel};
    assert_false(image_read_exr(&img, path, err, sizeof err));
    assert_contains(err, path);
    assert_contains(err, strerror(ENOENT));
    /* A failed read leaves an empty image, safe to image_free. */
    assert_null(img.rgb);
    assert_int_equal(img.width, 0);
    image_free(&img);
}

static void test_read_non_exr_fails(void **state)
{
    (void)state;
    char path[PATH_SIZE], err[IMAGE_ERROR_SIZE] = "";
    in_dir(path, "not_an_image.exr");
    write_text(path, "P3\n# this is text, not OpenEXR\n1 1 255\n0 0 0\n", 1);
    image img;
    assert_false(image_read_exr(&img, path, err, sizeof err));
    assert_contains(err, path);
    assert_null(img.rgb);

    /* An empty file too (the library can't even read the magic number). */
    in_dir(path, "empty.exr");
    write_text(path, "", 1);
    err[0] = '\0';
    assert_false(image_read_exr(&img, path, err, sizeof err));
    assert_contains(err, path);
    assert_null(img.rgb);
}

static void test_read_exr_without_rgb_fails(void **state)
{
    (void)state;
    char path[PATH_SIZE], err[IMAGE_ERROR_SIZE] = "";
    in_dir(path, "luminance_only.exr");
    const test_channel y_only[] = {{"Y", EXR_PIXEL_FLOAT}};
    write_test_exr(path, y_only, 1, make_window(0, 0, 4, 3), EXR_COMPRESSION_ZIP);
    image img;
    assert_false(image_read_exr(&img, path, err, sizeof err));
    assert_contains(err, path);
    assert_contains(err, "'R'");
    assert_null(img.rgb);

    in_dir(path, "no_green.exr");
    const test_channel no_green[] = {{"R", EXR_PIXEL_FLOAT}, {"B", EXR_PIXEL_FLOAT}};
    write_test_exr(path, no_green, 2, make_window(0, 0, 4, 3), EXR_COMPRESSION_ZIP);
    err[0] = '\0';
    assert_false(image_read_exr(&img, path, err, sizeof err));
    assert_contains(err, path);
    assert_contains(err, "'G'");
    assert_null(img.rgb);
}

/* Half channels converted to float, an alpha and a depth channel to skip,
 * and a data window that starts at (5, -3), not the origin. Uncompressed:
 * one scanline per chunk, so the decoder is updated many times. */
static void test_read_half_rgba_with_offset_window(void **state)
{
    (void)state;
    char path[PATH_SIZE];
    in_dir(path, "half_rgba.exr");
    const test_channel channels[] = {
        {"A", EXR_PIXEL_HALF}, {"B", EXR_PIXEL_HALF}, {"G", EXR_PIXEL_HALF},
        {"R", EXR_PIXEL_HALF}, {"Z", EXR_PIXEL_FLOAT},
    };
    exr_attr_box2i_t window = make_window(5, -3, 13, 9);
    write_test_exr(path, channels, 5, window, EXR_COMPRESSION_NONE);
    assert_reads_test_values(path, window);
}

static void test_read_float_with_every_lossless_compression(void **state)
{
    (void)state;
    const exr_compression_t methods[] = {EXR_COMPRESSION_NONE, EXR_COMPRESSION_RLE, EXR_COMPRESSION_ZIPS,
                                         EXR_COMPRESSION_ZIP, EXR_COMPRESSION_PIZ};
    const test_channel channels[] = {{"R", EXR_PIXEL_FLOAT}, {"G", EXR_PIXEL_FLOAT}, {"B", EXR_PIXEL_FLOAT}};
    for (size_t m = 0; m < sizeof methods / sizeof methods[0]; m++) {
        char name[64], path[PATH_SIZE];
        snprintf(name, sizeof name, "compression_%d.exr", (int)methods[m]);
        in_dir(path, name);
        /* 40 rows: more than one chunk for every method (PIZ has 32 lines). */
        exr_attr_box2i_t window = make_window(0, 0, 19, 40);
        write_test_exr(path, channels, 3, window, methods[m]);
        assert_reads_test_values(path, window);
    }
}

/* ---- PNG ---------------------------------------------------------------- */

/* Loads an 8-bit RGB PNG with stb_image; the caller frees with stbi_image_free. */
static unsigned char *load_png(const char *path, int expect_width, int expect_height)
{
    int width = 0, height = 0, channels_in_file = 0;
    unsigned char *pixels = stbi_load(path, &width, &height, &channels_in_file, 3);
    if (pixels == NULL)
        fail_msg("stbi_load('%s'): %s", path, stbi_failure_reason());
    assert_int_equal(width, expect_width);
    assert_int_equal(height, expect_height);
    assert_int_equal(channels_in_file, 3);
    return pixels;
}

static void test_png_known_values(void **state)
{
    (void)state;
    char path[PATH_SIZE], err[IMAGE_ERROR_SIZE] = "";
    in_dir(path, "known.png");
    image img = image_make(3, 2);
    assert_non_null(img.rgb);
    image_set(&img, 0, 0, vec3_make(0.5f, 1.0f, 0.0f));       /* sRGB(0.5) = 0.7354 -> 188 */
    image_set(&img, 1, 0, vec3_make(5.0f, NAN, -1.0f));       /* clamp, NaN, negative */
    image_set(&img, 2, 0, vec3_make(INFINITY, -INFINITY, 1e-9f));
    image_set(&img, 0, 1, vec3_make(1.0f, 0.0f, 0.0f));       /* row 1 must stay row 1 */
    image_set(&img, 1, 1, vec3_make(0.0f, 0.0f, 0.5f));
    image_set(&img, 2, 1, vec3_make(0.0031308f, 0.25f, 0.0f)); /* 10.3 -> 10; 0.5371 -> 137 */
    if (!image_write_png(&img, path, 0.0f, err, sizeof err))
        fail_msg("%s", err);

    unsigned char *p = load_png(path, 3, 2);
    const unsigned char expected[2][3][3] = {
        {{188, 255, 0}, {255, 0, 0}, {255, 0, 0}},
        {{255, 0, 0}, {0, 0, 188}, {10, 137, 0}},
    };
    assert_memory_equal(p, expected, sizeof expected);
    stbi_image_free(p);
    assert_int_equal(count_temp_files(test_dir), 0);
    image_free(&img);
}

/* Writes img as a PNG preview and loads it back (free with stbi_image_free). */
static unsigned char *png_round_trip(const image *img, float exposure_stops)
{
    char path[PATH_SIZE], err[IMAGE_ERROR_SIZE] = "";
    in_dir(path, "exposure.png");
    if (!image_write_png(img, path, exposure_stops, err, sizeof err))
        fail_msg("%s", err);
    return load_png(path, img->width, img->height);
}

static void test_png_exposure_scales_in_stops(void **state)
{
    (void)state;
    image img = image_make(2, 1);
    assert_non_null(img.rgb);
    image_set(&img, 0, 0, vec3_make(0.25f, 0.5f, 0.0625f));
    image_set(&img, 1, 0, vec3_make(0.75f, 0.01f, 0.003f));

    /* +1 stop on 0.25 shows as 0.5 does: 188. And 0.5 becomes 1.0: 255. */
    unsigned char *up = png_round_trip(&img, 1.0f);
    assert_int_equal(up[0], 188);
    assert_int_equal(up[1], 255);
    stbi_image_free(up);

    /* In general, exposure k on v gives the bytes of v * 2^k at exposure 0
     * (the scaling by powers of two is exact in float). */
    const float stops[] = {1.0f, -1.0f, 3.0f, -4.0f};
    for (size_t k = 0; k < sizeof stops / sizeof stops[0]; k++) {
        image scaled = image_make(2, 1);
        assert_non_null(scaled.rgb);
        for (size_t i = 0; i < 6; i++)
            scaled.rgb[i] = ldexpf(img.rgb[i], (int)stops[k]);
        unsigned char *exposed = png_round_trip(&img, stops[k]);
        unsigned char *plain = png_round_trip(&scaled, 0.0f);
        assert_memory_equal(exposed, plain, 6);
        stbi_image_free(exposed);
        stbi_image_free(plain);
        image_free(&scaled);
    }
    image_free(&img);
}

/* ---- image_write by extension ------------------------------------------- */

static void test_image_write_exr_also_writes_png(void **state)
{
    (void)state;
    char exr_path[PATH_SIZE], png_path[PATH_SIZE], err[IMAGE_ERROR_SIZE] = "";
    in_dir(exr_path, "shot.exr");
    in_dir(png_path, "shot.png");
    image img = ramp_image(8, 5);
    if (!image_write(&img, exr_path, 0.0f, err, sizeof err))
        fail_msg("%s", err);
    image back;
    assert_true(image_read_exr(&back, exr_path, err, sizeof err));
    assert_memory_equal(back.rgb, img.rgb, image_bytes(&img));
    unsigned char *p = load_png(png_path, 8, 5);
    /* Pixel (2, 0) = (1.0, 0, -1): full red, blue clamped to 0. */
    assert_int_equal(p[2 * 3 + 0], 255);
    assert_int_equal(p[2 * 3 + 1], 0);
    assert_int_equal(p[2 * 3 + 2], 0);
    stbi_image_free(p);
    assert_int_equal(count_temp_files(test_dir), 0);
    image_free(&back);
    image_free(&img);
}

static void test_image_write_png_writes_only_png(void **state)
{
    (void)state;
    char png_path[PATH_SIZE], exr_path[PATH_SIZE], err[IMAGE_ERROR_SIZE] = "";
    in_dir(png_path, "preview_only.png");
    in_dir(exr_path, "preview_only.exr");
    image img = ramp_image(4, 4);
    assert_true(image_write(&img, png_path, 0.0f, err, sizeof err));
    assert_true(file_exists(png_path));
    assert_false(file_exists(exr_path));
    image_free(&img);
}

static void test_image_write_rejects_other_extensions(void **state)
{
    (void)state;
    char path[PATH_SIZE], err[IMAGE_ERROR_SIZE] = "", expected[PATH_SIZE + 64];
    image img = ramp_image(2, 2);
    const char *names[] = {"x.txt", "x.exr.bak", "exr", "x.ppm"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        in_dir(path, names[i]);
        assert_false(image_write(&img, path, 0.0f, err, sizeof err));
        snprintf(expected, sizeof expected, "'%s': output must end in .exr or .png", path);
        assert_string_equal(err, expected);
        assert_false(file_exists(path));
    }
    image_free(&img);
}

/* ---- sRGB ----------------------------------------------------------------- */

static void test_srgb_encode_matches_iec_61966_2_1(void **state)
{
    (void)state;
    assert_true(image_srgb_encode(0.0f) == 0.0f);
    assert_float_equal(image_srgb_encode(1.0f), 1.0f, 1e-6f);
    assert_float_equal(image_srgb_encode(0.5f), 0.735357f, 1e-5f);
    /* The two pieces meet at 0.0031308: the last point of the linear toe
     * and the first float of the power curve agree. */
    float edge = 0.0031308f;
    float above = nextafterf(edge, 1.0f);
    assert_float_equal(image_srgb_encode(edge), 12.92f * edge, 1e-9f);
    assert_float_equal(image_srgb_encode(above), image_srgb_encode(edge), 1e-6f);
    /* Each piece is the right formula away from the joint. */
    assert_close(image_srgb_encode(0.001f), 12.92 * 0.001, 1e-7);
    assert_close(image_srgb_encode(0.2f), 1.055 * pow(0.2, 1.0 / 2.4) - 0.055, 1e-6);
}

/* ---- error metrics -------------------------------------------------------- */

static void test_mse_hand_example(void **state)
{
    (void)state;
    image a = image_make(2, 1), ref = image_make(2, 1);
    assert_non_null(a.rgb);
    assert_non_null(ref.rgb);
    image_set(&a, 0, 0, vec3_make(1.0f, 2.0f, 3.0f));
    image_set(&a, 1, 0, vec3_make(0.0f, 0.0f, 0.0f));
    image_set(&ref, 0, 0, vec3_make(1.0f, 2.0f, 4.0f));  /* differs by 1 */
    image_set(&ref, 1, 0, vec3_make(0.5f, 0.0f, -1.0f)); /* by 0.5 and 1 */
    /* (0 + 0 + 1 + 0.25 + 0 + 1) / 6 = 2.25 / 6 = 0.375 */
    assert_close(image_mse(&a, &ref), 0.375, 1e-12);
    assert_close(image_mse(&ref, &a), 0.375, 1e-12);
    image_free(&a);
    image_free(&ref);
}

static void test_mse_of_image_with_itself_is_zero(void **state)
{
    (void)state;
    image a = ramp_image(37, 23);
    assert_true(image_mse(&a, &a) == 0.0);
    assert_true(image_relmse(&a, &a) == 0.0);
    image_free(&a);
}

static void test_relmse_weighs_dark_errors(void **state)
{
    (void)state;
    image ref = image_make(2, 1), dark_error = image_make(2, 1), bright_error = image_make(2, 1);
    assert_non_null(ref.rgb);
    assert_non_null(dark_error.rgb);
    assert_non_null(bright_error.rgb);
    /* Reference: a black pixel and a bright one (8). */
    image_set(&ref, 1, 0, vec3_splat(8.0f));
    /* Off by 0.125 in the black pixel's red. */
    image_set(&dark_error, 0, 0, vec3_make(0.125f, 0.0f, 0.0f));
    image_set(&dark_error, 1, 0, vec3_splat(8.0f));
    /* Off by 0.5 in the bright pixel's red. */
    image_set(&bright_error, 1, 0, vec3_make(8.5f, 8.0f, 8.0f));

    /* By hand, with epsilon = 0.01:
     *   dark:   0.125^2 / (0 + 0.01)   = 0.015625 / 0.01 = 1.5625, / 6 channels
     *   bright: 0.5^2   / (64 + 0.01)  = 0.25 / 64.01,             / 6 */
    assert_close(image_relmse(&dark_error, &ref), 1.5625 / 6.0, 1e-9);
    assert_close(image_relmse(&bright_error, &ref), 0.25 / 64.01 / 6.0, 1e-9);
    /* MSE ranks them the other way round. */
    assert_close(image_mse(&dark_error, &ref), 0.015625 / 6.0, 1e-12);
    assert_close(image_mse(&bright_error, &ref), 0.25 / 6.0, 1e-12);
    assert_true(image_relmse(&dark_error, &ref) > image_relmse(&bright_error, &ref));
    image_free(&ref);
    image_free(&dark_error);
    image_free(&bright_error);
}

static void test_metrics_of_different_sizes_are_nan(void **state)
{
    (void)state;
    image a = ramp_image(4, 3), b = ramp_image(3, 4);
    assert_true(isnan(image_mse(&a, &b)));
    assert_true(isnan(image_relmse(&a, &b)));
    image_free(&a);
    image_free(&b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_make_starts_black_and_rejects_bad_sizes),
        cmocka_unit_test(test_exr_round_trip_is_bit_identical),
        cmocka_unit_test(test_exr_round_trip_is_bit_identical_where_zip_does_not_shrink),
        cmocka_unit_test(test_exr_overwrite_replaces_the_whole_file),
        cmocka_unit_test(test_write_into_missing_directory_fails_cleanly),
        cmocka_unit_test(test_write_into_read_only_directory_fails_cleanly),
        cmocka_unit_test(test_failed_write_keeps_the_old_file),
        cmocka_unit_test(test_write_to_a_disk_full_from_the_first_byte_fails_cleanly),
        cmocka_unit_test(test_read_missing_file_fails),
        cmocka_unit_test(test_read_non_exr_fails),
        cmocka_unit_test(test_read_exr_without_rgb_fails),
        cmocka_unit_test(test_read_half_rgba_with_offset_window),
        cmocka_unit_test(test_read_float_with_every_lossless_compression),
        cmocka_unit_test(test_png_known_values),
        cmocka_unit_test(test_png_exposure_scales_in_stops),
        cmocka_unit_test(test_image_write_exr_also_writes_png),
        cmocka_unit_test(test_image_write_png_writes_only_png),
        cmocka_unit_test(test_image_write_rejects_other_extensions),
        cmocka_unit_test(test_srgb_encode_matches_iec_61966_2_1),
        cmocka_unit_test(test_mse_hand_example),
        cmocka_unit_test(test_mse_of_image_with_itself_is_zero),
        cmocka_unit_test(test_relmse_weighs_dark_errors),
        cmocka_unit_test(test_metrics_of_different_sizes_are_nan),
    };
    return cmocka_run_group_tests(tests, make_test_dir, remove_test_dir);
}
