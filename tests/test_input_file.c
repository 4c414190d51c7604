/* test_input_file.c -- tests for common/program/input_file.c: inputs are read whole
 * only when they are regular files within their limit, and a run never reads
 * as input a file it is about to write (--out and its sidecars).
 *
 * Files live in a fresh mkdtemp directory under /tmp, removed at the end.
 * The limit is tested with small limits and a sparse file (ftruncate), so
 * nothing large is ever written. The refusal of an output stops the
 * program, so it is tested in a child process (fork), whose exit status and
 * stderr are checked.
 */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include "cli.h"
#include "input_file.h"
#include "obj.h"
#include "record_file.h"
#include "mesh.h"
#include "scene_file.h"
#include "test_support.h"
#include "test_temp_dir.h"

#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

enum { PATH_SIZE = 4096 };

static char test_dir[] = "/tmp/test_input_file.XXXXXX";

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

static void write_bytes(const char *path, const char *bytes, size_t length)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(bytes, 1, length, f), length);
    assert_int_equal(fclose(f), 0);
}

static void write_text(const char *path, const char *text) { write_bytes(path, text, strlen(text)); }

TEST_TEMP_DIR_FIXTURES(test_dir)

/* Each test starts from the defaults: no protected outputs, the 1 GB limit. */
static int reset(void **state)
{
    (void)state;
    input_file_protect_clear();
    input_file_set_mesh_limit((uint64_t)INPUT_DEFAULT_MESH_MB << 20);
    return 0;
}

/* ---- reading ------------------------------------------------------------------ */

static void test_reads_a_regular_file_whole(void **state)
{
    reset(state);
    char path[PATH_SIZE], why[INPUT_ERROR_SIZE] = "";
    /* Bytes of every value, a NUL among them: the length, not a NUL, ends it. */
    char bytes[300];
    for (size_t i = 0; i < sizeof bytes; i++)
        bytes[i] = (char)(i * 7);
    write_bytes(in_dir(path, "bytes"), bytes, sizeof bytes);
    char *text;
    size_t length;
    assert_true(input_file_read(path, "OBJ", 1000, true, &text, &length, why, sizeof why));
    assert_int_equal(length, sizeof bytes);
    assert_memory_equal(text, bytes, sizeof bytes);
    assert_int_equal(text[length], '\0');
    free(text);

    write_text(in_dir(path, "empty"), "");
    assert_true(input_file_read(path, "OBJ", 1000, true, &text, &length, why, sizeof why));
    assert_int_equal(length, 0);
    free(text);
}

/* A file of exactly the limit is read; one byte more is refused, and the
 * message says by how much, the kind, and (when it can be raised) the flag. */
static void test_the_limit_is_inclusive_and_named(void **state)
{
    reset(state);
    char path[PATH_SIZE], why[INPUT_ERROR_SIZE] = "";
    char bytes[1001];
    memset(bytes, 'x', sizeof bytes);
    write_bytes(in_dir(path, "thousand"), bytes, 1000);
    char *text;
    size_t length;
    assert_true(input_file_read(path, "OBJ", 1000, true, &text, &length, why, sizeof why));
    assert_int_equal(length, 1000);
    free(text);
    write_bytes(path, bytes, 1001);
    assert_false(input_file_read(path, "OBJ", 1000, true, &text, &length, why, sizeof why));
    assert_null(text);
    assert_string_equal(why, "1001 bytes is over the 1000 bytes limit for OBJ files (--max-input-mb N raises it)");
    assert_false(input_file_read(path, "scene", 1000, false, &text, &length, why, sizeof why));
    assert_string_equal(why, "1001 bytes is over the 1000 bytes limit for scene files");
}

/* A 6 GB sparse file takes no disk and is refused from its size alone,
 * before anything is allocated or read (this test would otherwise need 6 GB
 * of memory and a minute). */
static void test_a_huge_file_is_refused_without_reading(void **state)
{
    reset(state);
    char path[PATH_SIZE], why[INPUT_ERROR_SIZE] = "";
    int fd = open(in_dir(path, "huge.obj"), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    assert_true(fd >= 0);
    if (ftruncate(fd, (off_t)6 << 30) != 0) {
        close(fd);
        skip(); /* a filesystem without sparse files or large sizes */
    }
    close(fd);
    char *text;
    size_t length;
    assert_false(input_file_read(path, "OBJ", input_file_mesh_limit(), true, &text, &length, why, sizeof why));
    assert_string_equal(why, "6.0 GB is over the 1 GB limit for OBJ files (--max-input-mb N raises it)");
    /* The same through the OBJ loader, naming the file. */
    mesh m;
    mesh_init(&m);
    char err[MESH_ERROR_SIZE], expected[PATH_SIZE + 128];
    assert_false(mesh_load_obj(&m, path, err, sizeof err));
    snprintf(expected, sizeof expected, "%s: 6.0 GB is over the 1 GB limit for OBJ files (--max-input-mb N raises it)",
             path);
    assert_string_equal(err, expected);
    mesh_free(&m);
    unlink(path);
}

/* A file in /proc reports size 0 and still has content: it is read to its
 * end, and the limit still holds while reading. */
static void test_a_file_that_reports_size_zero_is_read_to_its_end(void **state)
{
    reset(state);
    char why[INPUT_ERROR_SIZE] = "";
    struct stat info;
    if (stat("/proc/self/status", &info) != 0 || info.st_size != 0)
        skip();
    char *text;
    size_t length;
    assert_true(input_file_read("/proc/self/status", "OBJ", 1 << 20, true, &text, &length, why, sizeof why));
    assert_true(length > 100);
    assert_non_null(strstr(text, "Pid:"));
    free(text);
    assert_false(input_file_read("/proc/self/status", "OBJ", 50, true, &text, &length, why, sizeof why));
    assert_null(text);
    assert_string_equal(why, "it holds more than the 50 bytes limit for OBJ files (--max-input-mb N raises it)");
}

/* A directory, a device that never ends, a FIFO with no writer (which a
 * plain open() would wait on forever): each refused at once, by its kind. */
static void test_only_regular_files_are_read(void **state)
{
    reset(state);
    char path[PATH_SIZE], why[INPUT_ERROR_SIZE] = "";
    char *text;
    size_t length;
    assert_false(input_file_read(test_dir, "OBJ", 1000, true, &text, &length, why, sizeof why));
    assert_string_equal(why, "not a regular file (a directory)");
    assert_false(input_file_read("/dev/zero", "OBJ", 1000, true, &text, &length, why, sizeof why));
    assert_string_equal(why, "not a regular file (a character device)");
    assert_int_equal(mkfifo(in_dir(path, "fifo"), 0644), 0);
    assert_false(input_file_read(path, "OBJ", 1000, true, &text, &length, why, sizeof why));
    assert_string_equal(why, "not a regular file (a pipe)");
    assert_null(text);
    assert_false(input_file_read(in_dir(path, "missing"), "OBJ", 1000, true, &text, &length, why, sizeof why));
    assert_string_equal(why, "No such file or directory");
}

/* The loaders use it: an OBJ, its MTL and a scene file, each named in the
 * message with the line that asked for it. */
static void test_loaders_refuse_what_is_not_a_regular_file_or_too_large(void **state)
{
    reset(state);
    char path[PATH_SIZE], expected[PATH_SIZE + 256], err[SCENE_ERROR_SIZE] = "";
    mesh m;
    mesh_init(&m);
    assert_false(mesh_load_obj(&m, "/dev/zero", err, sizeof err));
    assert_string_equal(err, "/dev/zero: not a regular file (a character device)");

    write_text(in_dir(path, "dev.obj"), "v 0 0 0\nmtllib /dev/zero\n");
    assert_false(mesh_load_obj(&m, path, err, sizeof err));
    snprintf(expected, sizeof expected,
             "%s:2: cannot read material library '/dev/zero': not a regular file (a character device)", path);
    assert_string_equal(err, expected);

    /* The mesh limit applies to OBJ and MTL files alike. */
    input_file_set_mesh_limit(100);
    char big[200];
    memset(big, '#', sizeof big - 1);
    big[sizeof big - 1] = '\n';
    write_bytes(in_dir(path, "big.mtl"), big, sizeof big);
    write_text(in_dir(path, "small.obj"), "mtllib big.mtl\n");
    assert_false(mesh_load_obj(&m, path, err, sizeof err));
    snprintf(expected, sizeof expected, "%s:1: cannot read material library '%s/big.mtl': 200 bytes is over the 100 "
                                        "bytes limit for MTL files (--max-input-mb N raises it)", path, test_dir);
    assert_string_equal(err, expected);
    write_bytes(in_dir(path, "big.obj"), big, sizeof big);
    assert_false(mesh_load_obj(&m, path, err, sizeof err));
    assert_contains(err, "200 bytes is over the 100 bytes limit for OBJ files");
    /* Raised, the same file loads. */
    input_file_set_mesh_limit(200);
    assert_true(mesh_load_obj(&m, path, err, sizeof err));
    assert_int_equal(m.position_count, 0);
    mesh_free(&m);

    scene_desc d;
    assert_false(scene_desc_load(&d, "/dev/zero", err, sizeof err));
    assert_string_equal(err, "/dev/zero: not a regular file (a character device)");
    assert_false(scene_desc_load(&d, test_dir, err, sizeof err));
    assert_contains(err, "not a regular file (a directory)");
    /* Scene files keep their own fixed limit, which the flag does not raise. */
    int fd = open(in_dir(path, "big.scene"), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    assert_true(fd >= 0);
    assert_int_equal(ftruncate(fd, (off_t)SCENE_MAX_FILE_BYTES + 1), 0);
    close(fd);
    input_file_set_mesh_limit((uint64_t)1 << 40);
    assert_false(scene_desc_load(&d, path, err, sizeof err));
    snprintf(expected, sizeof expected, "%s: 16777217 bytes is over the 16 MB limit for scene files", path);
    assert_string_equal(err, expected);
    assert_int_equal(d.shape_count, 0);
}

/* --max-input-mb sets the limit of the run, in MB of 2^20 bytes. */
static void test_the_flag_sets_the_limit(void **state)
{
    reset(state);
    cli_spec spec = {"t", "t", NULL, 0, "the path of a pixel"};
    cli_options o = cli_defaults("/tmp/x.png", 64, 48, 1);
    char err[512];
    assert_int_equal(o.max_input_mb, INPUT_DEFAULT_MESH_MB);
    char *argv[] = {"t", "--max-input-mb", "3"};
    assert_int_equal(cli_parse(3, argv, &spec, &o, err, sizeof err), CLI_OK);
    assert_int_equal(o.max_input_mb, 3);
    const char *bad[] = {"0", "-1", "abc", "1.5", "", "2000000"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        cli_options p = cli_defaults("/tmp/x.png", 64, 48, 1);
        char *args[] = {"t", "--max-input-mb", (char *)bad[i]};
        assert_int_equal(cli_parse(3, args, &spec, &p, err, sizeof err), CLI_ERROR);
        assert_contains(err, "--max-input-mb");
    }
}

/* ---- outputs are not inputs --------------------------------------------------- */

/* Runs input_file_read(path) in a child that has protected `out` as
 * cli_parse_or_exit would (with its preview and counters file); returns the
 * child's exit status and what it printed on stderr. Status 0: read. */
static int read_in_child(const char *out, const char *path, char *message, size_t message_size)
{
    char err_path[PATH_SIZE];
    in_dir(err_path, "child.stderr");
    fflush(NULL);
    pid_t child = fork();
    assert_true(child >= 0);
    if (child == 0) {
        if (freopen(err_path, "w", stderr) == NULL)
            _exit(99);
        cli_spec spec = {"prog", "t", NULL, 0, "the path of a pixel"};
        cli_options o = cli_defaults(out, 8, 8, 1);
        char *argv[] = {"prog"};
        cli_parse_or_exit(1, argv, &spec, &o);
        char *text, why[INPUT_ERROR_SIZE];
        size_t length;
        bool ok = input_file_read(path, "OBJ", 1000, true, &text, &length, why, sizeof why);
        _exit(ok ? 0 : 1);
    }
    int status;
    assert_int_equal(waitpid(child, &status, 0), child);
    assert_true(WIFEXITED(status));
    FILE *f = fopen(err_path, "r");
    assert_non_null(f);
    size_t n = fread(message, 1, message_size - 1, f);
    message[n] = '\0';
    fclose(f);
    return WEXITSTATUS(status);
}

/* The image, its .png preview and its counters file, however the input is
 * named: the same path, "./" and "dir/../", a hard link, a symbolic link.
 * The input is left as it was; the program says which flag and which file. */
static void test_an_output_is_never_read_as_input(void **state)
{
    reset(state);
    char out[PATH_SIZE], in[PATH_SIZE], message[1024], expected[3 * PATH_SIZE];
    write_text(in_dir(out, "o.png"), "v 0 0 0\n");
    assert_int_equal(read_in_child(out, out, message, sizeof message), 2);
    snprintf(expected, sizeof expected, "prog: --out '%s' would overwrite the input '%s'\n", out, out);
    assert_string_equal(message, expected);

    snprintf(in, sizeof in, "%s/./sub/../o.png", test_dir);
    assert_int_equal(mkdir(in_dir(expected, "sub"), 0755), 0);
    assert_int_equal(read_in_child(out, in, message, sizeof message), 2);
    assert_contains(message, "--out");

    assert_int_equal(link(out, in_dir(in, "hard.obj")), 0);
    assert_int_equal(read_in_child(out, in, message, sizeof message), 2);
    snprintf(expected, sizeof expected, "would overwrite the input '%s'", in);
    assert_contains(message, expected);
    assert_int_equal(symlink(out, in_dir(in, "soft.obj")), 0);
    assert_int_equal(read_in_child(out, in, message, sizeof message), 2);

    /* The sidecars of an .exr: its preview and its counters file. */
    in_dir(out, "o.exr");
    assert_int_equal(read_in_child(out, in_dir(in, "o.png"), message, sizeof message), 2);
    snprintf(expected, sizeof expected, "prog: --out '%s' would overwrite the input '%s' (its .png preview)\n", out, in);
    assert_string_equal(message, expected);
    write_text(in_dir(in, "o.counters.json"), "v 0 0 0\n");
    assert_int_equal(read_in_child(out, in, message, sizeof message), 2);
    assert_contains(message, "(its counters file)");
    in_dir(in, "o.png");
    FILE *f = fopen(in, "r");
    char first[16] = "";
    assert_non_null(fgets(first, sizeof first, f));
    fclose(f);
    assert_string_equal(first, "v 0 0 0\n");
}

/* Nothing is refused that is not an output: another file, an output that
 * does not exist yet, a file with the output's contents, and any file at
 * all when no program has protected its outputs (a library, a test). */
static void test_other_files_are_read_as_usual(void **state)
{
    reset(state);
    char out[PATH_SIZE], in[PATH_SIZE], message[1024];
    write_text(in_dir(in, "model.obj"), "v 0 0 0\n");
    assert_int_equal(read_in_child(in_dir(out, "fresh.exr"), in, message, sizeof message), 0);
    assert_string_equal(message, "");
    write_text(in_dir(out, "copy.png"), "v 0 0 0\n");
    assert_int_equal(read_in_child(out, in, message, sizeof message), 0);
    char *text, why[INPUT_ERROR_SIZE];
    size_t length;
    assert_true(input_file_read(out, "OBJ", 1000, true, &text, &length, why, sizeof why));
    free(text);
}

/* A cached reference's record (record_file.h) serves only when it is the
 * expected record byte for byte: a NUL inside it (which a string compare
 * would stop at) or a cut does not match, and each differing line is
 * named; a directory or a missing file is no record. The twin: the same
 * bytes match. */
static void test_a_record_matches_only_byte_for_byte(void **state)
{
    (void)state;
    char path[PATH_SIZE], why[1024], err[256];
    const char *expected = "width 16\nspp 64\nversion v1\n";
    in_dir(path, "ref-record.txt");
    assert_false(record_file_matches(path, expected, why, sizeof why));
    assert_non_null(strstr(why, "it has no record of how it was made"));
    assert_true(record_file_write(path, expected, err, sizeof err));
    assert_true(record_file_matches(path, expected, why, sizeof why));
    write_bytes(path, "width 16\nspp 64\0junk\nversion v1\n", 30);
    assert_false(record_file_matches(path, expected, why, sizeof why));
    assert_non_null(strstr(why, "its spp 64..., now 64"));
    write_text(path, "width 16\nspp 32\n");
    assert_false(record_file_matches(path, expected, why, sizeof why));
    assert_string_equal(why, "its spp 32, now 64; its , now v1");
    assert_false(record_file_matches(test_dir, expected, why, sizeof why));
    assert_non_null(strstr(why, "cannot be read: not a regular file"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_reads_a_regular_file_whole),
        cmocka_unit_test(test_the_limit_is_inclusive_and_named),
        cmocka_unit_test(test_a_huge_file_is_refused_without_reading),
        cmocka_unit_test(test_a_file_that_reports_size_zero_is_read_to_its_end),
        cmocka_unit_test(test_only_regular_files_are_read),
        cmocka_unit_test(test_loaders_refuse_what_is_not_a_regular_file_or_too_large),
        cmocka_unit_test(test_the_flag_sets_the_limit),
        cmocka_unit_test(test_an_output_is_never_read_as_input),
        cmocka_unit_test(test_other_files_are_read_as_usual),
        cmocka_unit_test(test_a_record_matches_only_byte_for_byte),
    };
    return cmocka_run_group_tests(tests, make_test_dir, remove_test_dir);
}
