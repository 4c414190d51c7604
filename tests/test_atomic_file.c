/* test_atomic_file.c -- the one way every file is written: the new file
 * appears whole or not at all, the old one stays until then, and no
 * temporary file outlives a call.
 *
 * Everything is written under a fresh mkdtemp directory in /tmp, removed at
 * the end. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <sys/resource.h>

#include "atomic_file.h"
#include "test_temp_dir.h"

static char test_dir[] = "/tmp/test_atomic_file.XXXXXX";

enum { PATH_SIZE = 256, ERROR_SIZE = 512 };

static const char *in_dir(char *buf, const char *name)
{
    snprintf(buf, PATH_SIZE, "%s/%s", test_dir, name);
    return buf;
}

/* Entries of the test directory, "." and ".." aside. */
static int count_entries(void)
{
    DIR *d = opendir(test_dir);
    assert_non_null(d);
    int count = 0;
    for (struct dirent *e; (e = readdir(d)) != NULL;)
        count += strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0;
    closedir(d);
    return count;
}

static void read_text(const char *path, char *out, size_t size)
{
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    size_t n = fread(out, 1, size - 1, f);
    out[n] = '\0';
    fclose(f);
}

static void write_file(const char *path, const char *text)
{
    char err[ERROR_SIZE] = "";
    atomic_file f;
    assert_true(atomic_file_open(&f, path, err, sizeof err));
    fputs(text, f.stream);
    if (!atomic_file_commit(&f, err, sizeof err))
        fail_msg("%s", err);
}

static void expect_contains(const char *text, const char *needle)
{
    if (strstr(text, needle) == NULL)
        fail_msg("\"%s\" does not contain \"%s\"", text, needle);
}

static void test_commit_replaces_the_target_and_leaves_nothing_else(void **state)
{
    (void)state;
    char path[PATH_SIZE], text[64];
    int before = count_entries();
    write_file(in_dir(path, "table.csv"), "old\n");
    write_file(path, "new\n");
    read_text(path, text, sizeof text);
    assert_string_equal(text, "new\n");
    assert_int_equal(count_entries(), before + 1);
    unlink(path);
}

/* Until commit the target is the old file; abandon keeps it so. */
static void test_abandon_keeps_the_old_file(void **state)
{
    (void)state;
    char path[PATH_SIZE], text[64], err[ERROR_SIZE] = "";
    write_file(in_dir(path, "kept.csv"), "old\n");
    int before = count_entries();
    atomic_file f;
    assert_true(atomic_file_open(&f, path, err, sizeof err));
    fputs("half of a new", f.stream);
    fflush(f.stream);
    assert_int_equal(count_entries(), before + 1); /* the temporary file, beside the target */
    read_text(path, text, sizeof text);
    assert_string_equal(text, "old\n");
    atomic_file_abandon(&f);
    assert_int_equal(count_entries(), before);
    read_text(path, text, sizeof text);
    assert_string_equal(text, "old\n");
    unlink(path);
}

static void test_open_in_a_missing_directory_names_the_file(void **state)
{
    (void)state;
    char path[PATH_SIZE], err[ERROR_SIZE] = "";
    int before = count_entries();
    atomic_file f;
    assert_false(atomic_file_open(&f, in_dir(path, "missing/x.csv"), err, sizeof err));
    char expected[PATH_SIZE + 64];
    snprintf(expected, sizeof expected, "cannot write '%s': %s", path, strerror(ENOENT));
    assert_string_equal(err, expected);
    assert_false(atomic_file_open_in(&f, test_dir, "missing/y.csv", err, sizeof err));
    expect_contains(err, "missing/y.csv");
    assert_int_equal(count_entries(), before);
}

/* The rename fails (the target is a directory): the temporary file goes,
 * the directory and what is in it stay. */
static void test_failed_rename_removes_the_temporary_file(void **state)
{
    (void)state;
    char path[PATH_SIZE], inside[PATH_SIZE + 16], err[ERROR_SIZE] = "";
    assert_int_equal(mkdir(in_dir(path, "taken"), 0777), 0);
    snprintf(inside, sizeof inside, "%s/keep", path);
    write_file(inside, "x");
    int before = count_entries();
    atomic_file f;
    assert_true(atomic_file_open(&f, path, err, sizeof err));
    fputs("data", f.stream);
    assert_false(atomic_file_commit(&f, err, sizeof err));
    expect_contains(err, path);
    assert_int_equal(count_entries(), before);
    assert_int_equal(access(inside, F_OK), 0);
    test_remove_tree(path);
}

/* A full disk (a file size limit: write fails with EFBIG) shows at the
 * flush inside commit: false, the file named, nothing left. */
static void test_full_disk_fails_at_commit(void **state)
{
    (void)state;
    char path[PATH_SIZE], err[ERROR_SIZE] = "";
    in_dir(path, "full.csv");
    int before = count_entries();
    struct rlimit saved, limited;
    assert_int_equal(getrlimit(RLIMIT_FSIZE, &saved), 0);
    limited = saved;
    limited.rlim_cur = 1024;
    void (*saved_handler)(int) = signal(SIGXFSZ, SIG_IGN); /* get EFBIG, not a signal */
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &limited), 0);
    atomic_file f;
    bool opened = atomic_file_open(&f, path, err, sizeof err), committed = false;
    if (opened) {
        for (int i = 0; i < 1000; i++)
            fprintf(f.stream, "row %d of a table that does not fit\n", i);
        committed = atomic_file_commit(&f, err, sizeof err);
    }
    setrlimit(RLIMIT_FSIZE, &saved);
    signal(SIGXFSZ, saved_handler);
    assert_true(opened);
    assert_false(committed);
    expect_contains(err, path);
    assert_int_equal(count_entries(), before);
}

TEST_TEMP_DIR_FIXTURES(test_dir)

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_commit_replaces_the_target_and_leaves_nothing_else),
        cmocka_unit_test(test_abandon_keeps_the_old_file),
        cmocka_unit_test(test_open_in_a_missing_directory_names_the_file),
        cmocka_unit_test(test_failed_rename_removes_the_temporary_file),
        cmocka_unit_test(test_full_disk_fails_at_commit),
    };
    return cmocka_run_group_tests(tests, make_test_dir, remove_test_dir);
}
