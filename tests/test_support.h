/* test_support.h -- what the cmocka suites share. Include after <cmocka.h>.
 *
 * assert_close(actual, expected, tolerance): |actual - expected| <= tolerance
 * in double (cmocka 1.1 compares only floats), printing both values on
 * failure. A NaN never passes. */
#ifndef TEST_SUPPORT_H
#define TEST_SUPPORT_H

#include <math.h>

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

#endif
