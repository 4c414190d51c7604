/* stats.h -- running mean and variance (Welford), and the log-log slope fit
 * that convergence tests and plots use. Everything here is double: float sums
 * of many samples lose the low digits that a variance is made of.
 *
 * Usage: welford w = {0}; welford_add(&w, x); ... welford_mean(&w), welford_variance(&w)
 */
#ifndef STATS_H
#define STATS_H

#include <stdint.h>

typedef struct {
    uint64_t count;
    double mean;
    double m2; /* sum of squared differences from the current mean */
} welford;

void welford_add(welford *w, double x);
/* Combine two partial results (Chan et al.), e.g. from two threads. */
void welford_merge(welford *into, const welford *other);
double welford_mean(const welford *w);
/* Unbiased sample variance (divides by count - 1); 0 for fewer than 2 samples. */
double welford_variance(const welford *w);
/* Standard error of the mean: sqrt(variance / count). */
double welford_standard_error(const welford *w);

/* Least-squares slope of log(y) against log(x) over n points (all positive).
 * Variance ~ N^-1 shows as slope -1. */
double stats_loglog_slope(const double *x, const double *y, int n);

#endif
