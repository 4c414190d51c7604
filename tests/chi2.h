/* chi2.h -- does a sampler draw what its pdf says? Pearson's chi-square
 * goodness-of-fit test of a 2D sampler against its density, and Holm's
 * correction over a family of such tests: what chapters 09 and 10 hold
 * every BSDF, light and lens sampler to. Include after <cmocka.h> and
 * test_support.h.
 *
 *   chi2_case c = {.measure = CHI2_SPHERE, .s_max = PI, .dimensions = 2,
 *                  .sample = sample, .pdf = pdf, .ctx = &ctx};
 *   chi2_table t = chi2_tabulate(&c, 0, 0);       the pdf integrated per bin
 *   chi2_result r = chi2_run(&c, &t, chi2_random_points(&rng), 100000);
 *   chi2_family family = {.count = 0};
 *   chi2_family_add(&family, "GGX, alpha 0.3", &r);
 *   ...
 *   assert_int_equal(chi2_family_holm(&family, CHI2_FAMILY_ALPHA), 0);
 *   chi2_table_free(&t);
 *
 * The test. N attempts are drawn; each gives a sample or none (a sampler
 * may refuse, as GGX does when the reflected direction falls below the
 * horizon). The samples are counted in bins B_k; bin k expects
 * E_k = N P_k, P_k the integral of the pdf over B_k, and the refusals
 * expect N (1 - sum P_k): the pdf's deficit from 1 is the probability of
 * no sample. If the sampler draws what the pdf says, the counts are
 * multinomial and X^2 = sum (O_k - E_k)^2 / E_k follows the chi-square
 * distribution with (cells - 1) degrees of freedom, as long as every cell
 * expects about 5 or more (Cochran's rule): cells expected to hold fewer
 * are pooled, smallest first, until the pool expects 5 (as Mitsuba 3's
 * test does). The p-value is that distribution's upper tail at X^2
 * (stats_chi_square_p_value). A sample where the pdf is 0 is impossible
 * and fails the test outright (p = 0), as does a pdf that integrates to
 * more than 1.
 *
 * The bins. A fixed grid wastes its bins on a narrow lobe: GGX at alpha
 * 0.05 puts nearly all its mass in a few of 16 x 32 (theta, phi) cells,
 * where nothing can be seen. So the bins follow the pdf: the domain is
 * first cut into a fine grid (CHI2_FINE_ROWS x CHI2_FINE_COLS cells), the
 * pdf integrated over each fine cell (2 x 2 Gauss-Legendre points, the
 * measure's Jacobian included); then rows of fine cells are grouped into
 * `rings` bands of about equal probability, and each band's columns into
 * `per_ring` bins of about equal probability. Every bin then expects about
 * N / (rings x per_ring) samples wherever the pdf puts them, and the bins
 * are narrow where the pdf is peaked. Choosing the bins from the pdf is
 * allowed: they are fixed before any sample is drawn.
 *
 * The domains, in coordinates (s, t):
 *   CHI2_SPHERE     directions: s = theta in [0, s_max] from the frame's
 *                   z axis, t = phi in [0, 2 pi); Jacobian sin(theta); the
 *                   pdf per steradian. s_max = pi is the whole sphere.
 *   CHI2_GNOMONIC   directions within 90 degrees of the frame's z axis,
 *                   as the point where they meet the plane z = 1: s = x/z
 *                   in [s_min, s_max], t = y/z in [t_min, t_max];
 *                   Jacobian (1 + s^2 + t^2)^(-3/2); per steradian. The
 *                   projection maps straight lines to straight lines, so
 *                   a polygonal light's image is the polygon of its
 *                   vertices' images, and the rectangle around those holds
 *                   it all: seen at grazing, a thin sliver that this
 *                   rectangle fits (in (theta, phi) it would cross a few
 *                   fine cells and no quadrature would see it).
 *   CHI2_DISK       points of a disk: s = r in [0, s_max], t = phi;
 *                   Jacobian r; the pdf per unit area.
 *   CHI2_PLANE      points (s, t) of [s_min, s_max] x [t_min, t_max];
 *                   Jacobian 1.
 * A case speaks in points (x, y, z): a unit direction in its own frame
 * (CHI2_SPHERE, CHI2_GNOMONIC), a point (x, y) (the others); the header
 * does the coordinates.
 *
 * Points other than independent random ones. chi2_points gives the
 * uniform numbers of attempt i; scrambled Sobol points (chapter 09) are
 * spread more evenly than independent points, so their counts vary less
 * than multinomial ones and X^2 is smaller than the chi-square law says:
 * the test is conservative for them (a correct sampler fails less often),
 * while a sampler that draws the wrong density is still caught (its bias
 * does not shrink with the noise).
 *
 * The family. Each test is one of many (every material at every angle):
 * Holm's step-down correction (chi2_family_holm) keeps the probability
 * that a correct family rejects anything at CHI2_FAMILY_ALPHA. A twin
 * that must fail is held to the strictest threshold of its family,
 * alpha / m: Holm would reject it wherever it stood in the family. */
#ifndef CHI2_H
#define CHI2_H

#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rng.h"
#include "stats.h"
#include "vec3.h"

/* The probability that a correct family fails: the suites' budget for a
 * random test (test_seeds.sh: about 1e-6 per test). */
static const double CHI2_FAMILY_ALPHA = 1e-6;
/* Cochran's rule: below about 5 expected samples a cell's (O - E)^2 / E no
 * longer follows the chi-square law, and a cell expecting 0.01 that gets
 * one sample alone adds 100. */
static const double CHI2_MIN_EXPECTED = 5.0;
/* The pdf may integrate to 1 plus its quadrature error (a pdf with a peak
 * or an edge inside fine cells: ~1e-4 measured); beyond this it claims
 * more samples than there are attempts. */
static const double CHI2_TOTAL_ROUNDING = 2e-3;
/* A sample computed in float may land a few float steps beyond the edge
 * of a domain it fills up to (the lens's rim at r = a): it counts in the
 * edge's cells; farther out it is outside the domain. */
static const double CHI2_EDGE_ROUNDING = 1e-6;
/* When a fine cell is cut finer (chi2_cell): its Gauss and midpoint
 * integrals differ by more than this part of it, or by more than the
 * floor (a probability of 1e-10 is 1e-5 of a sample in 1e5). 1e-3 of a
 * cell is far below a bin's noise (8 % at 170 samples). */
static const double CHI2_REFINE_RELATIVE = 1e-3, CHI2_REFINE_FLOOR = 1e-10;

enum {
    CHI2_FINE_ROWS = 256,   /* fine cells along s: 0.7 degrees for the whole sphere */
    CHI2_FINE_COLS = 512,   /* along t */
    CHI2_RINGS = 24,        /* bands of equal probability */
    CHI2_PER_RING = 24,     /* bins of equal probability per band */
    /* A fine cell is cut in four at most this often where the pdf changes
     * fast (0.04 degrees at the finest): what keeps a peaked GGX lobe's
     * integral per bin exact enough that X^2 measures the sampler, not the
     * quadrature, without refining the whole sphere. */
    CHI2_REFINE_DEPTH = 4,
    CHI2_MAX_DIMENSIONS = 4,
    CHI2_NAME_SIZE = 96,
    CHI2_FAMILY_MAX = 128,
};

typedef enum { CHI2_SPHERE, CHI2_GNOMONIC, CHI2_DISK, CHI2_PLANE } chi2_measure;

typedef struct {
    chi2_measure measure;
    /* The domain: s in [s_min, s_max]; t in [t_min, t_max] for
     * CHI2_GNOMONIC and CHI2_PLANE, [0, 2 pi) for the others (which also
     * take s_min = 0). */
    double s_min, s_max, t_min, t_max;
    int dimensions;        /* uniform numbers per attempt */
    /* One attempt from u: the sample's point, or false for no sample. */
    bool (*sample)(const void *ctx, const float *u, double point[3]);
    /* The claimed density at a point (per steradian, per unit area). */
    double (*pdf)(const void *ctx, const double point[3]);
    const void *ctx;
} chi2_case;

/* ---- the pdf per bin ------------------------------------------------------ */

typedef struct {
    int rows, cols;      /* the fine grid */
    int *bin;            /* rows x cols: the bin of each fine cell */
    double *probability; /* bin_count: the pdf's integral over each bin */
    int bin_count;
    double total;        /* the pdf's integral over the domain */
} chi2_table;

/* t's range. */
static inline bool chi2_t_is_phi(const chi2_case *c) { return c->measure == CHI2_SPHERE || c->measure == CHI2_DISK; }
static inline double chi2_t_min(const chi2_case *c) { return chi2_t_is_phi(c) ? 0.0 : c->t_min; }
static inline double chi2_t_max(const chi2_case *c) { return chi2_t_is_phi(c) ? 2.0 * PI : c->t_max; }

static inline double chi2_jacobian(chi2_measure measure, double s, double t)
{
    switch (measure) {
    case CHI2_SPHERE:
        return sin(s);
    case CHI2_GNOMONIC: {
        double q = 1.0 + s * s + t * t;
        return 1.0 / (q * sqrt(q));
    }
    case CHI2_DISK:
        return s;
    case CHI2_PLANE:
        break;
    }
    return 1.0;
}

static inline void chi2_point_at(chi2_measure measure, double s, double t, double point[3])
{
    switch (measure) {
    case CHI2_SPHERE:
        point[0] = sin(s) * cos(t), point[1] = sin(s) * sin(t), point[2] = cos(s);
        return;
    case CHI2_GNOMONIC: {
        double l = sqrt(1.0 + s * s + t * t);
        point[0] = s / l, point[1] = t / l, point[2] = 1.0 / l;
        return;
    }
    case CHI2_DISK:
        point[0] = s * cos(t), point[1] = s * sin(t), point[2] = 0.0;
        return;
    case CHI2_PLANE:
        point[0] = s, point[1] = t, point[2] = 0.0;
        return;
    }
}

/* (s, t) of a point; phi in [0, 2 pi); NaN for a direction the
 * gnomonic plane does not see. */
static inline void chi2_coordinates(chi2_measure measure, const double point[3], double *s, double *t)
{
    if (measure == CHI2_PLANE) {
        *s = point[0], *t = point[1];
        return;
    }
    if (measure == CHI2_GNOMONIC) {
        *s = point[2] > 0.0 ? point[0] / point[2] : NAN;
        *t = point[2] > 0.0 ? point[1] / point[2] : NAN;
        return;
    }
    double phi = atan2(point[1], point[0]);
    *t = phi < 0.0 ? phi + 2.0 * PI : phi;
    if (*t >= 2.0 * PI)
        *t = 0.0;
    if (measure == CHI2_SPHERE) {
        double length = sqrt(point[0] * point[0] + point[1] * point[1] + point[2] * point[2]);
        *s = acos(fmin(1.0, fmax(-1.0, point[2] / length)));
    } else {
        *s = hypot(point[0], point[1]);
    }
}

/* Labels n consecutive cells of the given masses with `parts` runs of
 * about equal mass: each cell joins the part its start falls in (a run of
 * empty cells joins its neighbour), numbered from `first` without gaps.
 * Returns the number of labels used. */
static inline int chi2_split(const double *mass, int n, int parts, int *label, int first)
{
    double total = 0.0;
    for (int i = 0; i < n; i++)
        total += mass[i];
    int used = 0, previous = -1;
    double before = 0.0;
    for (int i = 0; i < n; i++) {
        int part = total > 0.0 ? (int)(before / total * parts) : 0;
        part = part < parts ? part : parts - 1;
        if (part != previous)
            used++, previous = part;
        label[i] = first + used - 1;
        before += mass[i];
    }
    return used;
}

/* The pdf's integral over the cell [s0, s1] x [t0, t1], Jacobian
 * included: 2 x 2 Gauss-Legendre points (exact for cubics), checked
 * against the midpoint rule; where the two disagree, the pdf changes
 * within the cell faster than either follows (a narrow lobe, the edge of
 * a light), and the cell is cut in four, down to CHI2_REFINE_DEPTH
 * levels. GGX at alpha 0.05 seen at cos(theta_o) = 0.05 puts its lobe
 * in a band thinner than one fine cell against the horizon: without the
 * refinement its bins were 2 % off, X^2 3000 on 177 degrees of freedom. */
static inline double chi2_cell(const chi2_case *c, double s0, double s1, double t0, double t1, int depth)
{
    const double node = 0.5 / sqrt(3.0); /* nodes at the centre -+ h / (2 sqrt 3), weights h / 2 */
    double hs = s1 - s0, ht = t1 - t0, point[3], gauss = 0.0;
    for (int a = -1; a <= 1; a += 2)
        for (int b = -1; b <= 1; b += 2) {
            double s = s0 + (0.5 + a * node) * hs, t = t0 + (0.5 + b * node) * ht;
            chi2_point_at(c->measure, s, t, point);
            gauss += c->pdf(c->ctx, point) * chi2_jacobian(c->measure, s, t);
        }
    gauss *= 0.25 * hs * ht;
    double sm = 0.5 * (s0 + s1), tm = 0.5 * (t0 + t1);
    chi2_point_at(c->measure, sm, tm, point);
    double midpoint = c->pdf(c->ctx, point) * chi2_jacobian(c->measure, sm, tm) * hs * ht;
    if (depth >= CHI2_REFINE_DEPTH || fabs(gauss - midpoint) <= CHI2_REFINE_RELATIVE * gauss + CHI2_REFINE_FLOOR)
        return gauss;
    return chi2_cell(c, s0, sm, t0, tm, depth + 1) + chi2_cell(c, sm, s1, t0, tm, depth + 1) +
           chi2_cell(c, s0, sm, tm, t1, depth + 1) + chi2_cell(c, sm, s1, tm, t1, depth + 1);
}

/* rows, cols: the fine grid, 0 for CHI2_FINE_ROWS x CHI2_FINE_COLS. */
static inline chi2_table chi2_tabulate(const chi2_case *c, int rows, int cols)
{
    chi2_table tab;
    tab.rows = rows > 0 ? rows : CHI2_FINE_ROWS;
    tab.cols = cols > 0 ? cols : CHI2_FINE_COLS;
    size_t cells = (size_t)tab.rows * (size_t)tab.cols;
    double *mass = malloc(cells * sizeof *mass);
    tab.bin = malloc(cells * sizeof *tab.bin);
    double s0 = c->s_min, t0 = chi2_t_min(c);
    double hs = (c->s_max - s0) / tab.rows, ht = (chi2_t_max(c) - t0) / tab.cols;
    for (int i = 0; i < tab.rows; i++)
        for (int j = 0; j < tab.cols; j++)
            mass[(size_t)i * tab.cols + j] =
                chi2_cell(c, s0 + i * hs, s0 + (i + 1) * hs, t0 + j * ht, t0 + (j + 1) * ht, 0);
    /* bands of rows, then bins within each band */
    double *row_mass = calloc((size_t)tab.rows, sizeof *row_mass);
    int *ring = malloc((size_t)tab.rows * sizeof *ring);
    tab.total = 0.0;
    for (int i = 0; i < tab.rows; i++) {
        for (int j = 0; j < tab.cols; j++)
            row_mass[i] += mass[(size_t)i * tab.cols + j];
        tab.total += row_mass[i];
    }
    int rings = chi2_split(row_mass, tab.rows, CHI2_RINGS, ring, 0);
    double *ring_cols = malloc((size_t)tab.cols * sizeof *ring_cols);
    int *col_bin = malloc((size_t)tab.cols * sizeof *col_bin);
    tab.bin_count = 0;
    for (int r = 0, i0 = 0; r < rings; r++) {
        int i1 = i0;
        while (i1 < tab.rows && ring[i1] == r)
            i1++;
        for (int j = 0; j < tab.cols; j++) {
            ring_cols[j] = 0.0;
            for (int i = i0; i < i1; i++)
                ring_cols[j] += mass[(size_t)i * tab.cols + j];
        }
        int bins = chi2_split(ring_cols, tab.cols, CHI2_PER_RING, col_bin, tab.bin_count);
        for (int i = i0; i < i1; i++)
            for (int j = 0; j < tab.cols; j++)
                tab.bin[(size_t)i * tab.cols + j] = col_bin[j];
        tab.bin_count += bins;
        i0 = i1;
    }
    tab.probability = calloc((size_t)tab.bin_count, sizeof *tab.probability);
    for (size_t k = 0; k < cells; k++)
        tab.probability[tab.bin[k]] += mass[k];
    free(mass);
    free(row_mass);
    free(ring);
    free(ring_cols);
    free(col_bin);
    return tab;
}

static inline void chi2_table_free(chi2_table *tab)
{
    free(tab->bin);
    free(tab->probability);
    tab->bin = NULL;
    tab->probability = NULL;
}

/* ---- the samples --------------------------------------------------------- */

/* The uniform numbers of attempt `index`: u[0 .. count-1] in [0, 1). */
typedef struct {
    const char *name;
    void (*fill)(void *state, uint32_t index, float *u, int count);
    void *state;
} chi2_points;

static inline void chi2_fill_random(void *state, uint32_t index, float *u, int count)
{
    (void)index;
    for (int k = 0; k < count; k++)
        u[k] = pcg32_float(state);
}

/* Independent uniform numbers from rng (seed it with test_seed). */
static inline chi2_points chi2_random_points(pcg32 *rng) { return (chi2_points){"random", chi2_fill_random, rng}; }

/* Pearson's X^2 over `cells` cells, pooling those that expect fewer than
 * CHI2_MIN_EXPECTED, smallest first, until the pool expects that many
 * (what is left of the pool at the end joins the last cell made). *dof:
 * the cells after pooling, less one (the counts sum to N). */
static inline double chi2_pearson(const double *observed, const double *expected, int cells, int *dof)
{
    int *order = malloc((size_t)cells * sizeof *order);
    for (int i = 0; i < cells; i++)
        order[i] = i;
    for (int i = 1; i < cells; i++) { /* insertion sort by expected count: a few hundred cells */
        int k = order[i], j = i;
        for (; j > 0 && expected[order[j - 1]] > expected[k]; j--)
            order[j] = order[j - 1];
        order[j] = k;
    }
    double statistic = 0.0, pool_o = 0.0, pool_e = 0.0, last_o = 0.0, last_e = 0.0;
    int used = 0;
    for (int k = 0; k < cells; k++) {
        pool_o += observed[order[k]];
        pool_e += expected[order[k]];
        if (pool_e >= CHI2_MIN_EXPECTED) {
            statistic += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
            last_o = pool_o, last_e = pool_e;
            used++;
            pool_o = pool_e = 0.0;
        }
    }
    if (pool_e > 0.0 || pool_o > 0.0) {
        if (used > 0) { /* merge the rest into the last cell made */
            statistic -= (last_o - last_e) * (last_o - last_e) / last_e;
            last_o += pool_o, last_e += pool_e;
            statistic += (last_o - last_e) * (last_o - last_e) / last_e;
        } else {
            used = 1;
        }
    }
    free(order);
    *dof = used - 1;
    return statistic;
}

typedef struct {
    double statistic, p_value;
    int dof;
    long samples, refused;
    long impossible; /* samples where the pdf is 0 */
    long outside;    /* samples outside the domain */
    double total;    /* the pdf's integral */
} chi2_result;

/* The verdict of a table of counts against probabilities: cells
 * probabilities (the last may be the refusals), `attempts` draws. */
static inline chi2_result chi2_verdict(const double *observed, const double *probability, int cells, long attempts)
{
    chi2_result r = {0};
    double *expected = malloc((size_t)cells * sizeof *expected);
    for (int k = 0; k < cells; k++)
        expected[k] = fmax(0.0, probability[k]) * (double)attempts;
    r.statistic = chi2_pearson(observed, expected, cells, &r.dof);
    r.p_value = r.dof > 0 ? stats_chi_square_p_value(r.statistic, r.dof) : 1.0;
    free(expected);
    return r;
}

/* N attempts of c's sampler with `points`, counted in t's bins. */
static inline chi2_result chi2_run(const chi2_case *c, const chi2_table *tab, chi2_points points, long attempts)
{
    double *observed = calloc((size_t)tab->bin_count + 1, sizeof *observed);
    double *probability = malloc(((size_t)tab->bin_count + 1) * sizeof *probability);
    long impossible = 0, outside = 0, refused = 0;
    double s0 = c->s_min, t0 = chi2_t_min(c), ds = c->s_max - s0, dt = chi2_t_max(c) - t0;
    for (long n = 0; n < attempts; n++) {
        float u[CHI2_MAX_DIMENSIONS];
        points.fill(points.state, (uint32_t)n, u, c->dimensions);
        double point[3], s, t;
        if (!c->sample(c->ctx, u, point)) {
            refused++;
            continue;
        }
        if (!(c->pdf(c->ctx, point) > 0.0)) {
            impossible++;
            continue;
        }
        chi2_coordinates(c->measure, point, &s, &t);
        double fs = (s - s0) / ds, ft = (t - t0) / dt; /* the fraction of the way across */
        if (!(fs >= -CHI2_EDGE_ROUNDING && fs <= 1.0 + CHI2_EDGE_ROUNDING && ft >= -CHI2_EDGE_ROUNDING &&
              ft <= 1.0 + CHI2_EDGE_ROUNDING)) {
            outside++;
            continue;
        }
        int i = (int)(fs * tab->rows), j = (int)(ft * tab->cols);
        i = i < 0 ? 0 : i < tab->rows ? i : tab->rows - 1;
        j = j < 0 ? 0 : j < tab->cols ? j : tab->cols - 1;
        observed[tab->bin[(size_t)i * tab->cols + j]] += 1.0;
    }
    memcpy(probability, tab->probability, (size_t)tab->bin_count * sizeof *probability);
    probability[tab->bin_count] = 1.0 - tab->total; /* no sample */
    observed[tab->bin_count] = (double)refused;
    chi2_result r = chi2_verdict(observed, probability, tab->bin_count + 1, attempts);
    r.samples = attempts - refused;
    r.refused = refused;
    r.impossible = impossible;
    r.outside = outside;
    r.total = tab->total;
    if (impossible > 0 || outside > 0 || tab->total > 1.0 + CHI2_TOTAL_ROUNDING)
        r.p_value = 0.0;
    free(observed);
    free(probability);
    return r;
}

static inline void chi2_print(const char *name, const chi2_result *r)
{
    print_message("chi2 %-52s X^2 %9.1f dof %4d p %-9.3g pdf total %.5f refused %ld%s%s\n", name, r->statistic,
                  r->dof, r->p_value, r->total, r->refused, r->impossible > 0 ? " IMPOSSIBLE SAMPLES" : "",
                  r->outside > 0 ? " SAMPLES OUTSIDE THE DOMAIN" : "");
}

/* ---- the family: Holm's step-down ----------------------------------------- */

typedef struct {
    char name[CHI2_NAME_SIZE];
    double p_value;
} chi2_entry;

typedef struct {
    chi2_entry entries[CHI2_FAMILY_MAX];
    int count;
} chi2_family;

static inline void chi2_family_add(chi2_family *f, const char *name, const chi2_result *r)
{
    chi2_print(name, r);
    if (f->count >= CHI2_FAMILY_MAX)
        fail_msg("chi2 family: more than %d tests", CHI2_FAMILY_MAX);
    snprintf(f->entries[f->count].name, CHI2_NAME_SIZE, "%s", name);
    f->entries[f->count].p_value = r->p_value;
    f->count++;
}

/* Holm-Bonferroni: sort the m p-values, p_(1) <= ... <= p_(m); reject
 * H_(1) .. H_(k) for the largest k with p_(j) < alpha / (m - j + 1) for
 * every j <= k. The probability of rejecting any true hypothesis is at
 * most alpha, whatever the tests' dependence. Prints each rejection;
 * returns how many. */
static inline int chi2_family_holm(const chi2_family *f, double alpha)
{
    int m = f->count, order[CHI2_FAMILY_MAX];
    for (int i = 0; i < m; i++)
        order[i] = i;
    for (int i = 1; i < m; i++) {
        int k = order[i], j = i;
        for (; j > 0 && f->entries[order[j - 1]].p_value > f->entries[k].p_value; j--)
            order[j] = order[j - 1];
        order[j] = k;
    }
    int rejected = 0;
    while (rejected < m && f->entries[order[rejected]].p_value < alpha / (m - rejected)) {
        const chi2_entry *e = &f->entries[order[rejected]];
        print_error("chi2 family: '%s' rejected, p = %.3g < %.3g (Holm, step %d of %d)\n", e->name, e->p_value,
                    alpha / (m - rejected), rejected + 1, m);
        rejected++;
    }
    if (m > 0)
        print_message("chi2 family of %d: smallest p %.3g against Holm's first threshold %.3g; %d rejected\n", m,
                      f->entries[order[0]].p_value, alpha / m, rejected);
    return rejected;
}

/* A twin must fail: its p-value below the family's strictest threshold,
 * alpha / m, where Holm rejects it first. */
static inline void chi2_assert_twin_fails(const char *name, const chi2_result *r, int family_size)
{
    double threshold = CHI2_FAMILY_ALPHA / family_size;
    print_message("chi2 twin %-47s X^2 %9.1f dof %4d p %.3g (must be below %.3g)%s\n", name, r->statistic, r->dof,
                  r->p_value, threshold, r->impossible > 0 ? ", impossible samples" : "");
    if (!(r->p_value < threshold))
        fail_msg("the twin '%s' passed the chi-square test (p = %.3g)", name, r->p_value);
}

/* ---- frames --------------------------------------------------------------- */

/* An orthonormal frame about an axis, in double, made here (Gram-Schmidt)
 * rather than with the renderer's vec3_basis, so that a wrong basis there
 * shows as a mismatch. */
typedef struct {
    double x[3], y[3], z[3];
} chi2_frame;

/* z along `axis`, x as near `toward` as that allows (toward must not be
 * parallel to axis). */
static inline chi2_frame chi2_frame_toward(vec3 axis, vec3 toward)
{
    chi2_frame f;
    double a[3] = {axis.x, axis.y, axis.z}, e[3] = {toward.x, toward.y, toward.z};
    double al = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    for (int k = 0; k < 3; k++)
        f.z[k] = a[k] / al;
    double d = e[0] * f.z[0] + e[1] * f.z[1] + e[2] * f.z[2], xl = 0.0;
    for (int k = 0; k < 3; k++)
        f.x[k] = e[k] - d * f.z[k], xl += f.x[k] * f.x[k];
    for (int k = 0; k < 3; k++)
        f.x[k] /= sqrt(xl);
    f.y[0] = f.z[1] * f.x[2] - f.z[2] * f.x[1];
    f.y[1] = f.z[2] * f.x[0] - f.z[0] * f.x[2];
    f.y[2] = f.z[0] * f.x[1] - f.z[1] * f.x[0];
    return f;
}

/* x towards the world axis least aligned with `axis`. */
static inline chi2_frame chi2_frame_around(vec3 axis)
{
    float ax = fabsf(axis.x), ay = fabsf(axis.y), az = fabsf(axis.z);
    vec3 least = ax <= ay && ax <= az ? vec3_make(1, 0, 0) : ay <= az ? vec3_make(0, 1, 0) : vec3_make(0, 0, 1);
    return chi2_frame_toward(axis, least);
}

/* World vector -> the frame's coordinates: a rotation only, so that a
 * sampler's float direction, taken to the frame and back with
 * chi2_frame_world, rounds to the very same floats. (Normalizing it on
 * the way, as this once did, moved a direction drawn within 1e-8 of the
 * horizon below it: GGX's pdf there is 0, and a correct sample counted as
 * impossible, once in 200 seeds.) */
static inline void chi2_frame_local(const chi2_frame *f, const double w[3], double local[3])
{
    local[0] = w[0] * f->x[0] + w[1] * f->x[1] + w[2] * f->x[2];
    local[1] = w[0] * f->y[0] + w[1] * f->y[1] + w[2] * f->y[2];
    local[2] = w[0] * f->z[0] + w[1] * f->z[1] + w[2] * f->z[2];
}

static inline void chi2_normalize(double w[3])
{
    double l = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    w[0] /= l, w[1] /= l, w[2] /= l;
}

static inline void chi2_frame_world(const chi2_frame *f, const double local[3], double w[3])
{
    for (int k = 0; k < 3; k++)
        w[k] = local[0] * f->x[k] + local[1] * f->y[k] + local[2] * f->z[k];
}

#endif
