/* 08-monte-carlo: the Monte Carlo estimator and how fast its error falls.
 *
 * For four integrals with known values (x^2 on [0,1]; cos(theta) over the
 * hemisphere; a Gaussian on the unit square; the indicator of a disk) and
 * each estimator of the catalogue (independent uniform, jittered, importance
 * sampled, Owen-scrambled Sobol), it computes N = 2^0 .. 2^16 sample
 * estimates many times over with independent seeds, and reports the RMSE,
 * the variance, the time per estimate and the efficiency 1 / (variance x
 * time). With --data DIR it writes them as CSV for the plots. Its picture
 * shows 256 points of each point set, on the square and on the disk. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "08-monte-carlo/estimators.h"
#include "atomic_file.h"
#include "cli.h"
#include "image_file.h"
#include "program.h"
#include "image.h"
#include "memory.h"
#include "progress.h"
#include "stats.h"
#include "mpi_split.h"

enum { MAX_LOG2N = 20 };

/* The RMSE slope is fitted from this N on: below it, jittered and Sobol
 * points are not yet in their asymptotic regime (see the chapter text). */
static const int SLOPE_FIT_FIRST_LOG2N = 6;
/* Efficiency is compared at this N (or the largest run, if smaller). */
static const int EFFICIENCY_LOG2N = 12;

/* The whole measurement: every (integral, estimator) pair of the
 * catalogue at N = 2^0 .. 2^max_log2n, `runs` estimates each. */
typedef struct {
    experiment_catalogue catalogue; /* not to be copied (estimators.h) */
    convergence_point results[EXPERIMENT_COUNT][EXPERIMENT_MAX_ESTIMATORS][MAX_LOG2N + 1];
    int runs, max_log2n;
    int k_fit; /* the RMSE slope is fitted over N = 2^k_fit .. 2^max_log2n */
    int k_eff; /* efficiency is compared at N = 2^k_eff */
} study;

typedef struct {
    int experiment, estimator;
} cell;

/* ---- the picture: what the point sets look like ------------------------------ */

static void fill_disc(image *img, double cx, double cy, double radius, vec3 colour)
{
    int x0 = (int)floor(cx - radius), x1 = (int)ceil(cx + radius);
    int y0 = (int)floor(cy - radius), y1 = (int)ceil(cy + radius);
    for (int y = y0; y <= y1; y++)
        for (int x = x0; x <= x1; x++) {
            if (x < 0 || y < 0 || x >= img->width || y >= img->height)
                continue;
            double dx = x + 0.5 - cx, dy = y + 0.5 - cy;
            if (dx * dx + dy * dy <= radius * radius)
                image_set(img, x, y, colour);
        }
}

/* Three columns (independent, jittered, Owen-scrambled Sobol), two rows: 256
 * points on the unit square over the 16 x 16 grid of strata, and the same
 * points through the cosine-hemisphere warp, seen from above (on the disk). */
static void draw_point_sets(image *img, uint64_t seed)
{
    enum { POINTS = 256, GRID = 16 };
    const point_set kinds[3] = {POINTS_INDEPENDENT, POINTS_JITTERED, POINTS_SOBOL_OWEN};
    const vec3 background = vec3_splat(1.0f), panel = vec3_splat(0.93f), line = vec3_splat(0.3f);
    const vec3 dot = vec3_make(0.02f, 0.08f, 0.35f);
    for (int y = 0; y < img->height; y++)
        for (int x = 0; x < img->width; x++)
            image_set(img, x, y, background);
    double size = fmin(img->width / 3.0, img->height / 2.0);
    double margin = 0.06 * size, side = size - 2 * margin;
    double radius = fmax(1.0, side / 90.0);
    double u[2 * POINTS];
    for (int column = 0; column < 3; column++) {
        pcg32 rng = pcg32_for_pixel(seed, (uint64_t)column);
        points_generate(kinds[column], &rng, POINTS, 2, u);
        for (int row = 0; row < 2; row++) {
            double left = column * size + margin, top = row * size + margin;
            for (int y = (int)top; y < (int)(top + side); y++)
                for (int x = (int)left; x < (int)(left + side); x++) {
                    if (x >= img->width || y >= img->height)
                        continue;
                    double s = (x + 0.5 - left) / side, t = (y + 0.5 - top) / side;
                    bool inside = row == 0 || (2 * s - 1) * (2 * s - 1) + (2 * t - 1) * (2 * t - 1) <= 1.0;
                    bool on_line = row == 0 && (fabs(s * GRID - floor(s * GRID + 0.5)) * side / GRID < 0.5 ||
                                                fabs(t * GRID - floor(t * GRID + 0.5)) * side / GRID < 0.5);
                    if (inside)
                        image_set(img, x, y, on_line ? line : panel);
                }
            for (int i = 0; i < POINTS; i++) {
                double px = u[2 * i], py = u[2 * i + 1];
                if (row == 1) { /* cosine hemisphere from above: (x, y) on the unit disk */
                    vec3 w = sample_cosine_hemisphere(vec2_make((float)px, (float)py));
                    px = 0.5 * (w.x + 1.0);
                    py = 0.5 * (w.y + 1.0);
                }
                fill_disc(img, left + px * side, top + (1.0 - py) * side, radius, dot);
            }
        }
    }
}

/* ---- the measurement ---------------------------------------------------------- */

/* Each (integral, estimator) pair is one job; a thread runs all its N in
 * turn. Every estimate has its own random stream, so the numbers do not
 * depend on the thread count (the timings do, a little). */
static void study_run(study *st, uint64_t seed, int threads, bool quiet)
{
    cell cells[EXPERIMENT_COUNT * EXPERIMENT_MAX_ESTIMATORS];
    int cell_count = 0;
    for (int e = 0; e < EXPERIMENT_COUNT; e++)
        for (int j = 0; j < st->catalogue.experiments[e].estimator_count; j++)
            cells[cell_count++] = (cell){e, j};
    progress bar;
    progress_begin(&bar, "ch08", cell_count, quiet);
#pragma omp parallel num_threads(threads)
    {
        double *scratch = memory_allocate((size_t)2 << st->max_log2n, sizeof(double));
#pragma omp for schedule(dynamic, 1)
        for (int c = 0; c < cell_count; c++) {
            const experiment *ex = &st->catalogue.experiments[cells[c].experiment];
            const estimator *es = &ex->estimators[cells[c].estimator];
            for (int k = 0; k <= st->max_log2n; k++) {
                int n = 1 << k;
                uint64_t stream = experiment_stream_seed(seed, cells[c].experiment, cells[c].estimator, n);
                st->results[cells[c].experiment][cells[c].estimator][k] =
                    estimator_run(ex->integrand, es, n, st->runs, stream, scratch);
            }
            progress_advance(&bar, 1);
        }
        free(scratch);
    }
    progress_end(&bar);
}

/* 1 / (variance x CPU seconds per estimate) */
static double efficiency(const convergence_point *r) { return 1.0 / (r->variance * r->cpu_seconds); }

/* One integral's table: RMSE at three N, the slope, the time and the
 * efficiency relative to the first estimator (independent uniform). */
static void print_experiment(const study *st, int e)
{
    const experiment *ex = &st->catalogue.experiments[e];
    printf("\n%s (exact %.10g)\n", ex->integrand->description, ex->integrand->exact);
    printf("  %-44s %11s %11s %11s %7s %12s %9s\n", "estimator", "RMSE N=1", "RMSE N=2^8", "RMSE N=max", "slope",
           "CPU us/est", "rel.eff.");
    double base = efficiency(&st->results[e][0][st->k_eff]);
    for (int j = 0; j < ex->estimator_count; j++) {
        const convergence_point *r = st->results[e][j];
        double ns[MAX_LOG2N + 1], rmse[MAX_LOG2N + 1];
        int m = 0;
        for (int k = st->k_fit; k <= st->max_log2n; k++) {
            ns[m] = r[k].n;
            rmse[m] = r[k].rmse;
            m++;
        }
        double slope = m >= 2 ? stats_loglog_slope(ns, rmse, m) : NAN;
        printf("  %-44s %11.3e %11.3e %11.3e %7.2f %12.3f %9.3g\n", ex->estimators[j].description, r[0].rmse,
               r[8 < st->max_log2n ? 8 : st->max_log2n].rmse, r[st->max_log2n].rmse, slope,
               1e6 * r[st->k_eff].cpu_seconds, efficiency(&r[st->k_eff]) / base);
    }
}

static void print_summary(const study *st)
{
    printf("%d runs per N; RMSE slope fitted over N = 2^%d .. 2^%d; efficiency = 1/(variance x CPU seconds) "
           "at N = 2^%d,\nrelative to independent uniform sampling of the same integral.\n",
           st->runs, st->k_fit, st->max_log2n, st->k_eff);
    for (int e = 0; e < EXPERIMENT_COUNT; e++)
        print_experiment(st, e);
    printf("\n(slope: of log RMSE against log N. Independent samples: -0.5. A zero-variance estimator\n"
           "shows float rounding, not noise.)\n");
}

/* ---- CSV for the plots (each written whole or not at all: atomic_file.h) ---- */

static bool write_convergence_csv(const study *st, const char *dir, char *err, size_t err_size)
{
    atomic_file f;
    if (!atomic_file_open_in(&f, dir, "ch08_convergence.csv", err, err_size))
        return false;
    fprintf(f.stream, "integral,estimator,log2n,n,runs,mean,rmse,variance,cpu_seconds_per_estimate,"
                      "wall_seconds_per_estimate,efficiency\n");
    for (int e = 0; e < EXPERIMENT_COUNT; e++)
        for (int j = 0; j < st->catalogue.experiments[e].estimator_count; j++)
            for (int k = 0; k <= st->max_log2n; k++) {
                const convergence_point *r = &st->results[e][j][k];
                fprintf(f.stream, "%s,%s,%d,%d,%d,%.17g,%.6e,%.6e,%.6e,%.6e,%.6e\n",
                        st->catalogue.experiments[e].integrand->name, st->catalogue.experiments[e].estimators[j].name,
                        k, r->n, r->runs, r->mean, r->rmse, r->variance, r->cpu_seconds, r->seconds, efficiency(r));
            }
    return atomic_file_commit(&f, err, err_size);
}

static bool write_efficiency_csv(const study *st, const char *dir, char *err, size_t err_size)
{
    atomic_file f;
    if (!atomic_file_open_in(&f, dir, "ch08_efficiency.csv", err, err_size))
        return false;
    fprintf(f.stream, "integral,estimator,index,n,variance,cpu_seconds_per_estimate,efficiency,relative\n");
    for (int e = 0; e < EXPERIMENT_COUNT; e++) {
        double base = efficiency(&st->results[e][0][st->k_eff]);
        for (int j = 0; j < st->catalogue.experiments[e].estimator_count; j++) {
            const convergence_point *r = &st->results[e][j][st->k_eff];
            fprintf(f.stream, "%s,%s,%d,%d,%.6e,%.6e,%.6e,%.6e\n", st->catalogue.experiments[e].integrand->name,
                    st->catalogue.experiments[e].estimators[j].name, e, r->n, r->variance, r->cpu_seconds,
                    efficiency(r), efficiency(r) / base);
        }
    }
    return atomic_file_commit(&f, err, err_size);
}

/* ---- the program ----------------------------------------------------------------- */

static bool write_picture(const cli_options *opts, const char *program)
{
    image img = image_make(opts->width, opts->height);
    if (img.rgb == NULL) {
        fprintf(stderr, "%s: out of memory for a %dx%d image\n", program, opts->width, opts->height);
        return false;
    }
    draw_point_sets(&img, opts->seed);
    char err[IMAGE_ERROR_SIZE];
    ray_counters none = {0}; /* points drawn, not rays traced: the record is the run's */
    bool ok = image_write(&img, opts->out, opts->exposure, err, sizeof err) &&
              program_write_record(opts, program, &none, 0.0, err, sizeof err);
    if (!ok)
        fprintf(stderr, "%s: %s\n", program, err);
    else if (!opts->quiet)
        printf("wrote %s (256 points: independent, jittered, Owen-scrambled Sobol; square and disk)\n", opts->out);
    image_free(&img);
    return ok;
}

/* The measurement, its table, its CSV (with --data) and the picture. */
static int run(const cli_options *opts, const char *program, int runs, int max_log2n, const char *data_dir)
{
    static study st; /* about 30 KB of results: not on the stack */
    experiment_catalogue_init(&st.catalogue);
    st.runs = runs;
    st.max_log2n = max_log2n;
    st.k_fit = SLOPE_FIT_FIRST_LOG2N < max_log2n ? SLOPE_FIT_FIRST_LOG2N : 0;
    st.k_eff = EFFICIENCY_LOG2N < max_log2n ? EFFICIENCY_LOG2N : max_log2n;
    study_run(&st, opts->seed, opts->threads, opts->quiet);
    if (!opts->quiet)
        print_summary(&st);
    int status = 0;
    char err[1024];
    if (data_dir != NULL) {
        if (!write_convergence_csv(&st, data_dir, err, sizeof err) ||
            !write_efficiency_csv(&st, data_dir, err, sizeof err)) {
            fprintf(stderr, "%s: %s\n", program, err);
            status = 1;
        } else if (!opts->quiet) {
            printf("wrote %s/ch08_convergence.csv and %s/ch08_efficiency.csv\n", data_dir, data_dir);
        }
    }
    if (!write_picture(opts, program))
        status = 1;
    experiment_catalogue_free(&st.catalogue);
    return status;
}

int main(int argc, char **argv)
{
    cli_options opts = cli_defaults("build/out/ch08.exr", 960, 640, 1);
    int runs = 256, max_log2n = 16;
    bool quick = false;
    const char *data_dir = NULL;
    const cli_flag extras[] = {
        {"--runs", CLI_INT, &runs, "N", "independent estimates per N, for the RMSE (default 256)", 2, 1000000},
        {"--max-log2n", CLI_INT, &max_log2n, "K", "largest N is 2^K (default 16)", 0, MAX_LOG2N},
        {"--quick", CLI_BOOL, &quick, NULL, "a rough run in under a second: 64 runs, N up to 2^12 (overrides --runs)", 0, 0},
        {"--data", CLI_DIR, &data_dir, "DIR", "write DIR/ch08_convergence.csv and DIR/ch08_efficiency.csv", 0, 0},
    };
    cli_spec spec = {"08-monte-carlo",
                     "Monte Carlo integration (GAMES101 lecture 16): the estimator (1/N) sum f(X)/p(X) on four\n"
                     "integrals with known values, with independent, jittered, importance-sampled and\n"
                     "Owen-scrambled Sobol samples; RMSE, time and efficiency for N = 1 .. 2^16. The picture\n"
                     "shows 256 points of each point set on the square and warped onto the disk.",
                     extras, 4, NULL};
    cli_parse_or_exit(argc, argv, &spec, &opts);
    if (mpi_split_refuse(spec.program, "this program (its measurements are not a render)"))
        return 2;
    /* The shared flags --scene and --explain have nothing to act on here:
     * this chapter integrates four functions with known integrals, not a
     * scene. Say so rather than ignore them. */
    if (opts.scene != NULL) {
        fprintf(stderr, "%s: --scene: this chapter has no scene; it estimates integrals with known values (the\n"
                        "irradiance from a scene's lights by quadrature is chapter 07: 07-radiometry --scene FILE;\n"
                        "the Monte Carlo render of a scene is chapter 09: 09-path-tracing --scene FILE)\n",
                spec.program);
        return 2;
    }
    if (opts.explain) {
        fprintf(stderr, "%s: --explain: this chapter traces no rays, so there is no path to explain\n", spec.program);
        return 2;
    }
    if (quick) {
        runs = 64;
        max_log2n = max_log2n < 12 ? max_log2n : 12;
    }
    return run(&opts, spec.program, runs, max_log2n, data_dir);
}
