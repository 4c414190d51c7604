#include "stats.h"

#include <math.h>

void welford_merge(welford *into, const welford *other)
{
    if (other->count == 0)
        return;
    if (into->count == 0) {
        *into = *other;
        return;
    }
    double n_a = (double)into->count, n_b = (double)other->count, n = n_a + n_b;
    double delta = other->mean - into->mean;
    into->mean += delta * n_b / n;
    into->m2 += other->m2 + delta * delta * n_a * n_b / n;
    into->count += other->count;
}

double welford_mean(const welford *w) { return w->mean; }

double welford_variance(const welford *w)
{
    return w->count < 2 ? 0.0 : w->m2 / (double)(w->count - 1);
}

double welford_standard_error(const welford *w)
{
    return w->count == 0 ? 0.0 : sqrt(welford_variance(w) / (double)w->count);
}

double stats_loglog_slope(const double *x, const double *y, int n)
{
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (int i = 0; i < n; i++) {
        double lx = log(x[i]), ly = log(y[i]);
        sx += lx;
        sy += ly;
        sxx += lx * lx;
        sxy += lx * ly;
    }
    return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

/* ---- the incomplete gamma function --------------------------------------- */

/* Both expansions stop when a term changes the sum by less than this
 * (relative): double's own resolution, 2^-52 ~ 2.2e-16. */
static const double GAMMA_RELATIVE_EPSILON = 2.220446049250313e-16;
/* Iterations before giving up. The series needs about sqrt(a) * 10 terms near
 * x = a, the continued fraction fewer; 100000 covers a up to 10^8. */
static const int GAMMA_MAX_ITERATIONS = 100000;
/* Lentz's method replaces an exact zero denominator by this tiny number
 * (Numerical Recipes, 3rd ed., section 5.2): small enough never to matter. */
static const double GAMMA_LENTZ_TINY = 1e-300;

/* x^a e^-x / Gamma(a), the factor both expansions share, via logarithms so
 * that it neither overflows nor underflows early for large a and x. */
static double gamma_prefactor(double a, double x)
{
    return exp(a * log(x) - x - lgamma(a));
}

/* P(a, x) = x^a e^-x / Gamma(a+1) * sum_n x^n / ((a+1)(a+2)...(a+n)).
 * Converges for every x; fast when x < a + 1. */
static double gamma_p_series(double a, double x)
{
    double term = 1.0 / a, sum = term;
    for (int n = 1; n < GAMMA_MAX_ITERATIONS; n++) {
        term *= x / (a + n);
        sum += term;
        if (fabs(term) < fabs(sum) * GAMMA_RELATIVE_EPSILON)
            break;
    }
    return sum * gamma_prefactor(a, x);
}

/* Q(a, x) = x^a e^-x / Gamma(a) * 1/(x+1-a- 1(1-a)/(x+3-a- 2(2-a)/(x+5-a- ...)))
 * evaluated by the modified Lentz method. Fast when x > a + 1. */
static double gamma_q_continued_fraction(double a, double x)
{
    double b = x + 1.0 - a;
    double c = 1.0 / GAMMA_LENTZ_TINY;
    double d = 1.0 / b;
    double h = d;
    for (int i = 1; i < GAMMA_MAX_ITERATIONS; i++) {
        double an = -i * (i - a);
        b += 2.0;
        d = an * d + b;
        if (fabs(d) < GAMMA_LENTZ_TINY)
            d = GAMMA_LENTZ_TINY;
        c = b + an / c;
        if (fabs(c) < GAMMA_LENTZ_TINY)
            c = GAMMA_LENTZ_TINY;
        d = 1.0 / d;
        double delta = d * c;
        h *= delta;
        if (fabs(delta - 1.0) < GAMMA_RELATIVE_EPSILON)
            break;
    }
    return h * gamma_prefactor(a, x);
}

double stats_gamma_p(double a, double x)
{
    if (!(a > 0.0) || !(x >= 0.0))
        return NAN;
    if (x == 0.0)
        return 0.0;
    if (isinf(x))
        return 1.0;
    return x < a + 1.0 ? gamma_p_series(a, x) : 1.0 - gamma_q_continued_fraction(a, x);
}

double stats_gamma_q(double a, double x)
{
    if (!(a > 0.0) || !(x >= 0.0))
        return NAN;
    if (x == 0.0)
        return 1.0;
    if (isinf(x))
        return 0.0;
    return x < a + 1.0 ? 1.0 - gamma_p_series(a, x) : gamma_q_continued_fraction(a, x);
}

double stats_chi_square_p_value(double chi2, int degrees_of_freedom)
{
    if (degrees_of_freedom < 1)
        return NAN;
    return stats_gamma_q(0.5 * degrees_of_freedom, 0.5 * chi2);
}

double stats_chi_square_lower_tail(double chi2, int degrees_of_freedom)
{
    if (degrees_of_freedom < 1)
        return NAN;
    return stats_gamma_p(0.5 * degrees_of_freedom, 0.5 * chi2);
}

double stats_sidak_alpha(double alpha_total, int k)
{
    if (k < 1 || !(alpha_total >= 0.0 && alpha_total <= 1.0))
        return NAN;
    /* 1 - (1 - alpha)^(1/k) = -expm1(log1p(-alpha) / k): no cancellation for small alpha. */
    return -expm1(log1p(-alpha_total) / k);
}
