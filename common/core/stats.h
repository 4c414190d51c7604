/* stats.h -- running mean and variance (Welford), the log-log slope fit
 * that convergence tests and plots use, and the chi-square distribution that
 * statistical tests take their p-values from. Everything here is double:
 * float sums of many samples lose the low digits that a variance is made of.
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

/* Inline: the render loop adds three channels per camera sample. */
static inline void welford_add(welford *w, double x)
{
    w->count++;
    double delta = x - w->mean;
    w->mean += delta / (double)w->count;
    w->m2 += delta * (x - w->mean);
}
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

/* The regularized incomplete gamma functions, a > 0, x >= 0:
 *   P(a, x) = (1 / Gamma(a)) * integral_0^x t^(a-1) e^-t dt   (lower)
 *   Q(a, x) = 1 - P(a, x)                                      (upper)
 * Each is computed directly (series for x < a + 1, continued fraction
 * otherwise), so a tail as small as 1e-300 keeps its relative accuracy
 * instead of being 1 minus something close to 1. NaN for bad arguments. */
double stats_gamma_p(double a, double x);
double stats_gamma_q(double a, double x);

/* Chi-square distribution with k degrees of freedom, k >= 1:
 * the upper tail P(X >= chi2) (the p-value of a Pearson test) and the lower
 * tail P(X <= chi2). Both are Q / P at a = k/2, x = chi2/2. */
double stats_chi_square_p_value(double chi2, int degrees_of_freedom);
double stats_chi_square_lower_tail(double chi2, int degrees_of_freedom);

/* Sidak's correction: the significance level for each of k independent tests
 * so that all k together reject a correct implementation with probability
 * alpha_total: 1 - (1 - alpha_total)^(1/k), computed without cancellation. */
double stats_sidak_alpha(double alpha_total, int k);

#endif
