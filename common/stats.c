#include "stats.h"

#include <math.h>

void welford_add(welford *w, double x)
{
    w->count++;
    double delta = x - w->mean;
    w->mean += delta / (double)w->count;
    w->m2 += delta * (x - w->mean);
}

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
