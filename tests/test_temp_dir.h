/* test_temp_dir.h -- a scratch directory for the suites that write files
 * (test_image, test_obj, test_input_file, test_atomic_file, test_resume):
 * made with mkdtemp before the tests, removed with everything in it after,
 * even what a test made read-only. POSIX: include it from a file compiled
 * with _DEFAULT_SOURCE (the Makefile does). */
#ifndef TEST_TEMP_DIR_H
#define TEST_TEMP_DIR_H

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static inline void test_remove_tree(const char *path)
{
    struct stat st;
    if (lstat(path, &st) != 0)
        return;
    if (S_ISDIR(st.st_mode)) {
        chmod(path, 0700); /* a test may have made it read-only */
        DIR *d = opendir(path);
        if (d != NULL) {
            for (struct dirent *e; (e = readdir(d)) != NULL;) {
                if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0)
                    continue;
                char child[4096];
                int n = snprintf(child, sizeof child, "%s/%s", path, e->d_name);
                if (n > 0 && (size_t)n < sizeof child) /* our own short names */
                    test_remove_tree(child);
            }
            closedir(d);
        }
        rmdir(path);
    } else {
        unlink(path);
    }
}

/* The group setup and teardown (cmocka_run_group_tests' last two
 * arguments) of a suite whose scratch directory is `dir`, a char array
 * holding a mkdtemp template: make_test_dir() and remove_test_dir(). */
#define TEST_TEMP_DIR_FIXTURES(dir)                                                                                   \
    static int make_test_dir(void **state)                                                                             \
    {                                                                                                                  \
        (void)state;                                                                                                   \
        return mkdtemp(dir) != NULL ? 0 : -1;                                                                          \
    }                                                                                                                  \
    static int remove_test_dir(void **state)                                                                           \
    {                                                                                                                  \
        (void)state;                                                                                                   \
        test_remove_tree(dir);                                                                                         \
        return 0;                                                                                                      \
    }

#endif
