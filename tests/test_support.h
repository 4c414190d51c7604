/* test_support.h -- what the cmocka suites share. Include after <cmocka.h>.
 *
 * assert_close(actual, expected, tolerance): |actual - expected| <= tolerance
 * in double (cmocka 1.1 compares only floats), printing both values on
 * failure. A NaN never passes.
 *
 * test_seed(fixed): the seed of a random test (see below).
 *
 * exercise_checks(name): this test grades that exercise (make grade). */
#ifndef TEST_SUPPORT_H
#define TEST_SUPPORT_H

#include <math.h>
#include <stdio.h>

static inline void assert_close_at(double actual, double expected, double tolerance, const char *expression,
                                   const char *file, int line)
{
    if (!(fabs(actual - expected) <= tolerance)) {
        print_error("%s = %.10g, expected %.10g within %.3g (off by %.3g)\n", expression, actual, expected,
                    tolerance, fabs(actual - expected));
        _fail(file, line);
    }
}

#define assert_close(actual, expected, tolerance) \
    assert_close_at((actual), (expected), (tolerance), #actual, __FILE__, __LINE__)

/* ---- seeds: one helper, so `make test-seeds` can move every random test --
 * test_seed(fixed) is the seed a random test uses. By default it is `fixed`,
 * so `make test` is reproducible run to run. `make test-seeds` sets
 * TEST_SEED_OFFSET=k (k = 1 .. 200) and reruns the statistical tests: each
 * then draws from a different stream, and a threshold that was tuned to one
 * lucky seed shows up as failures. The offset is multiplied by an odd 64-bit
 * constant (the golden ratio's) so neighbouring fixed seeds (100, 101, ...)
 * never land on each other's streams. */
#include <stdint.h>
#include <stdlib.h>

static inline uint64_t test_seed(uint64_t fixed)
{
    const char *text = getenv("TEST_SEED_OFFSET");
    uint64_t offset = text != NULL ? strtoull(text, NULL, 10) : 0;
    if (getenv("TEST_SEED_TRACE") != NULL) /* how tests/test_seeds.sh finds the random tests */
        print_message("test_seed: used\n");
    return fixed + offset * 0x9E3779B97F4A7C15ull;
}

/* TEST_FILTER=glob runs only the matching tests of a suite (cmocka's own
 * filter, which has no environment variable of its own): the seed sweep
 * runs one statistical test at a time. Set before main() runs. */
__attribute__((constructor)) static void test_filter_from_environment(void)
{
    const char *pattern = getenv("TEST_FILTER");
    if (pattern != NULL && *pattern != '\0')
        cmocka_set_test_filter(pattern);
    /* make grade reads the suite's output as it comes: the lines a test
     * prints must stay between its [ RUN ] and its verdict. */
    if (getenv("EXERCISE_GRADE") != NULL)
        setvbuf(stdout, NULL, _IONBF, 0);
}

/* ---- exercises: the tests that grade a learner's code ----------------------
 * exercise_checks("NAME") as a test's first line says that the test checks
 * exercise NAME (a body marked "exercise: NAME" in a chapter's source, see
 * tools/exercise.py). `make grade` runs the suite with EXERCISE_GRADE set
 * and builds its table from these lines, so the table is the tests' own
 * word. A test may name several exercises; one name per call. */
static inline void exercise_checks(const char *name)
{
    if (getenv("EXERCISE_GRADE") != NULL)
        print_message("exercise: %s\n", name);
}

#endif
