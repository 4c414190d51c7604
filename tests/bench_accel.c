/* bench_accel.c -- what each acceleration structure costs and buys, measured
 * on the same work as the Embree harness in ../shared/anchors/embree_bench.c:
 * the "tori field" mesh (mesh_tori_field, bit-identical to the harness's) and
 * its two ray sets, generated operation for operation as the harness does
 * (accel_harness_rays, chapter 03):
 *   coherent   1024 x 1024 pinhole rays in scanline order
 *   incoherent 2^20 rays, origins uniform in the bounds, directions uniform
 * For every structure and mesh size: build time, bytes per triangle, and
 * Mrays/s for closest hit and any hit on both sets, one thread and all
 * threads. Prints a table and writes CSV. With --embree FILE (the harness's
 * output lines), prints our figures as ratios of Embree's. The row
 * wide-bvh-sah is chapter 13's tree as the renderer builds it (exact nodes);
 * wide-bvh-quantized the same tree with quantized nodes (its child boxes
 * as bytes: the step's payoff, side by side; the row ends with the nodes'
 * count and bytes).
 * wide-bvh-stream is wide-bvh-sah's tree traced through wide_bvh_closest_hit_stream()
 * and wide_bvh_any_hit_stream() in chunks of STREAM_CHUNK rays: the same
 * answers, 16 rays taking turns so that their waits for memory overlap.
 *
 * Every structure traces with the watertight triangle test (chapter 01),
 * what the renderers use. After each mesh size's table, a second one times
 * the same structures with the watertight test and with Moller-Trumbore
 * (accel_use_triangle_test), alternately in the same run (watertight then
 * Moller-Trumbore, then the other way round, rep after rep), on one
 * thread: what watertightness costs each structure, by the wall clock and
 * by this process's CPU time (the two part when other work shares the
 * machine). --compare-only prints that table alone.
 *
 * This is a benchmark, not a test: it prints figures and asserts nothing
 * about time. It does check that every structure finds the same hits (the
 * same count and sum of t as brute force or the BVH), so a fast wrong answer
 * cannot hide in the table. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "03-aabb-slabs/accel_program.h"
#include "04-uniform-grid/grid.h"
#include "05-kd-tree/kdtree.h"
#include "06-bvh/bvh.h"
#include "13-production/wide_bvh.h"
#include "13-production/flat.h"
#include "atomic_file.h"
#include "memory.h"
#include "mesh.h"
#include "timer.h"

typedef struct {
    int count;
    ray *rays;
} ray_set;

/* ---- timing ------------------------------------------------------------------ */

typedef struct {
    double seconds, cpu_seconds; /* by the wall clock, and this process's CPU time */
    long hits;
    double t_sum;
    ray_counters counters;
} trace_result;

static double process_cpu_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Rays handed to a stream kernel at a time (wide-bvh-stream). */
enum { STREAM_CHUNK = 1024 };

static trace_result trace(const accel *a, const ray_set *rays, int count, bool closest, int threads, bool stream)
{
    trace_result result = {0};
    long hits = 0;
    double t_sum = 0.0;
    double start = timer_seconds(), start_cpu = process_cpu_seconds();
#pragma omp parallel num_threads(threads) reduction(+ : hits, t_sum)
    {
        ray_counters mine = {0};
        if (stream) {
            hit_record *chunk_hits = memory_allocate(STREAM_CHUNK, sizeof *chunk_hits);
            bool found[STREAM_CHUNK];
#pragma omp for schedule(dynamic, 1)
            for (int start = 0; start < count; start += STREAM_CHUNK) {
                int n = count - start < STREAM_CHUNK ? count - start : STREAM_CHUNK;
                if (closest)
                    wide_bvh_closest_hit_stream(a, rays->rays + start, n, chunk_hits, found, &mine);
                else
                    wide_bvh_any_hit_stream(a, rays->rays + start, n, found, &mine);
                for (int j = 0; j < n; j++) {
                    hits += found[j];
                    if (closest && found[j])
                        t_sum += chunk_hits[j].t;
                }
            }
            free(chunk_hits);
        }
#pragma omp for schedule(dynamic, 1024)
        for (int k = 0; k < (stream ? 0 : count); k++) {
            if (closest) {
                hit_record hit;
                if (accel_closest_hit(a, rays->rays[k], &hit, &mine)) {
                    hits++;
                    t_sum += hit.t;
                }
            } else {
                hits += accel_any_hit(a, rays->rays[k], &mine);
            }
        }
#pragma omp critical(bench_counters)
        counters_add(&result.counters, &mine);
    }
    result.seconds = timer_seconds() - start;
    result.cpu_seconds = process_cpu_seconds() - start_cpu;
    result.hits = hits;
    result.t_sum = t_sum;
    return result;
}

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Median of `reps` timings of the same trace: robust to a stray slow run. */
static trace_result trace_median(const accel *a, const ray_set *rays, int count, bool closest, int threads, int reps,
                                 bool stream)
{
    double times[16];
    trace_result r = {0};
    if (reps > 16)
        reps = 16;
    for (int i = 0; i < reps; i++) {
        r = trace(a, rays, count, closest, threads, stream);
        times[i] = r.seconds;
    }
    qsort(times, (size_t)reps, sizeof times[0], compare_doubles);
    r.seconds = reps % 2 ? times[reps / 2] : 0.5 * (times[reps / 2 - 1] + times[reps / 2]);
    return r;
}

/* ---- the structures ------------------------------------------------------------ */

typedef struct {
    const char *name;
    accel *(*build)(const triangle_set *set);
    long max_triangles; /* larger meshes are skipped (brute force) */
    int max_rays;       /* rays per set (brute force uses a strided subset) */
    bool stream;        /* traced as streams of rays taking turns (wide_bvh_closest_hit_stream) */
} structure;

static accel *build_brute(const triangle_set *s) { return brute_force_build(s); }
static accel *build_grid(const triangle_set *s) { return grid_build(s, GRID_DEFAULT_DENSITY); }
static accel *build_kdtree(const triangle_set *s) { return kdtree_build(s); }
static accel *build_bvh_median(const triangle_set *s) { return bvh_build(s, BVH_SPLIT_MEDIAN); }
static accel *build_bvh_sah(const triangle_set *s) { return bvh_build(s, BVH_SPLIT_SAH); }
static accel *build_wide_bvh_sah(const triangle_set *s) { return wide_bvh_build(s, BVH_SPLIT_SAH); }
static accel *build_wide_bvh_quantized(const triangle_set *s)
{
    return wide_bvh_build_layout(s, BVH_SPLIT_SAH, WIDE_BVH_QUANTIZED);
}
static accel *build_flat(const triangle_set *s) { return flat_build(s); }

static const structure structures[] = {
    {"brute", build_brute, 10240, 1 << 14, false},
    {"flat", build_flat, 10240, 1 << 14, false},
    {"grid", build_grid, 1L << 30, 1 << 20, false},
    {"kdtree", build_kdtree, 1L << 30, 1 << 20, false},
    {"bvh-median", build_bvh_median, 1L << 30, 1 << 20, false},
    {"bvh-sah", build_bvh_sah, 1L << 30, 1 << 20, false},
    {"wide-bvh-sah", build_wide_bvh_sah, 1L << 30, 1 << 20, false},
    {"wide-bvh-quantized", build_wide_bvh_quantized, 1L << 30, 1 << 20, false},
    {"wide-bvh-stream", build_wide_bvh_sah, 1L << 30, 1 << 20, true},
};
enum { STRUCTURE_COUNT = sizeof structures / sizeof structures[0] };

/* A strided subset of a ray set (every k-th ray), as the harness does for
 * brute force. */
static ray_set ray_subset(const ray_set *all, int count)
{
    if (count >= all->count)
        return *all;
    ray_set s = {count, memory_allocate((size_t)count, sizeof(ray))};
    int stride = all->count / count;
    for (int k = 0; k < count; k++)
        s.rays[k] = all->rays[(size_t)k * (size_t)stride];
    return s;
}

/* ---- the watertight test against Moller-Trumbore ------------------------------------
 * One structure, one thread, the four workloads (coherent and incoherent
 * rays, closest and any hit) with each triangle test in turn: rep k times
 * the watertight test first when k is even and Moller-Trumbore first when
 * it is odd, so that a machine that slows down or speeds up during the
 * run weighs on both alike. The medians of reps, by the wall clock and by
 * the process's CPU time. Also counts the rays whose answer (hit or not)
 * differs between the tests: Moller-Trumbore's leaks, and rays through
 * edges where either may round the other way. */
enum { WORKLOADS = 4 };
static const char *const workload_names[WORKLOADS] = {"coherent closest", "coherent any", "incoherent closest",
                                                      "incoherent any"};

typedef struct {
    double mrays[2][WORKLOADS], cpu_mrays[2][WORKLOADS]; /* [test][workload] */
    long hits[2][WORKLOADS];
} test_comparison;

static double median_of(double *values, int n)
{
    qsort(values, (size_t)n, sizeof *values, compare_doubles);
    return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

static test_comparison compare_triangle_tests(accel *a, const ray_set *coherent, const ray_set *incoherent, int reps,
                                              bool stream)
{
    test_comparison c = {0};
    double seconds[2][WORKLOADS][16], cpu[2][WORKLOADS][16];
    if (reps > 16)
        reps = 16;
    for (int test = 0; test < 2; test++) { /* warm-up, not counted */
        accel_use_triangle_test(a, (triangle_test)test);
        trace(a, coherent, coherent->count, true, 1, stream);
    }
    for (int rep = 0; rep < reps; rep++)
        for (int turn = 0; turn < 2; turn++) {
            int test = rep % 2 ? 1 - turn : turn;
            accel_use_triangle_test(a, (triangle_test)test);
            for (int w = 0; w < WORKLOADS; w++) {
                const ray_set *rays = w < 2 ? coherent : incoherent;
                trace_result r = trace(a, rays, rays->count, w % 2 == 0, 1, stream);
                seconds[test][w][rep] = r.seconds;
                cpu[test][w][rep] = r.cpu_seconds;
                c.hits[test][w] = r.hits;
            }
        }
    for (int test = 0; test < 2; test++)
        for (int w = 0; w < WORKLOADS; w++) {
            int count = w < 2 ? coherent->count : incoherent->count;
            c.mrays[test][w] = count / median_of(seconds[test][w], reps) * 1e-6;
            c.cpu_mrays[test][w] = count / median_of(cpu[test][w], reps) * 1e-6;
        }
    accel_use_triangle_test(a, TRIANGLE_TEST_WATERTIGHT);
    return c;
}

static void print_comparison_header(int reps)
{
    printf("\nthe watertight triangle test (wt) against Moller-Trumbore (mt), the same structures, 1 thread, "
           "alternating, median of %d:\nMrays/s by the wall clock; cost = mt / wt - 1, the watertight test's extra "
           "time per ray, by the wall clock [by this process's CPU time]\n", reps);
    printf("%-11s %9s", "structure", "triangles");
    for (int w = 0; w < WORKLOADS; w++)
        printf(" | %-38s", workload_names[w]);
    printf(" | hits differ\n");
}

static void print_comparison(const char *name, int triangles, const test_comparison *c, FILE *csv)
{
    printf("%-11s %9d", name, triangles);
    long differ = 0;
    for (int w = 0; w < WORKLOADS; w++) {
        double cost = c->mrays[1][w] / c->mrays[0][w] - 1.0;
        double cpu_cost = c->cpu_mrays[1][w] / c->cpu_mrays[0][w] - 1.0;
        printf(" | wt %7.3f mt %7.3f %+5.1f%% [%+5.1f%%]", c->mrays[0][w], c->mrays[1][w], 100.0 * cost,
               100.0 * cpu_cost);
        long d = c->hits[0][w] - c->hits[1][w];
        differ += d < 0 ? -d : d;
    }
    printf(" | %ld\n", differ);
    if (csv != NULL)
        for (int w = 0; w < WORKLOADS; w++)
            fprintf(csv, "%s,%d,%s,%.4f,%.4f,%.4f,%.4f,%ld,%ld\n", name, triangles, workload_names[w], c->mrays[0][w],
                    c->mrays[1][w], c->cpu_mrays[0][w], c->cpu_mrays[1][w], c->hits[0][w], c->hits[1][w]);
    fflush(stdout);
}

/* ---- Embree's figures ------------------------------------------------------------ */

typedef struct {
    int triangles, threads; /* threads: of Embree's build (its rays are traced on one) */
    double build_ms, coherent_closest, coherent_any, incoherent_closest, incoherent_any;
    double coherent_t_sum, incoherent_t_sum;
} embree_figures;

static int embree_load(const char *path, embree_figures *out, int max)
{
    FILE *f = fopen(path, "r");
    if (f == NULL) {
        fprintf(stderr, "bench_accel: cannot read '%s' (Embree figures); comparing without them\n", path);
        return 0;
    }
    char line[1024];
    int n = 0;
    while (n < max && fgets(line, sizeof line, f)) {
        embree_figures e;
        const char *p;
        if (strncmp(line, "EMBREE ", 7) != 0)
            continue;
        if (sscanf(line, "EMBREE tris=%d", &e.triangles) != 1)
            continue;
        p = strstr(line, " threads=");
        if (p == NULL || sscanf(p + 9, "%d", &e.threads) != 1)
            e.threads = 1;
#define FIELD(name, dst) ((p = strstr(line, name "=")) != NULL && sscanf(p + strlen(name) + 1, "%lf", &(dst)) == 1)
        if (FIELD("build_ms", e.build_ms) && FIELD("coh_isect_Mrays", e.coherent_closest) &&
            FIELD("coh_occl_Mrays", e.coherent_any) && FIELD("inc_isect_Mrays", e.incoherent_closest) &&
            FIELD("inc_occl_Mrays", e.incoherent_any) && FIELD("coh_tsum", e.coherent_t_sum) &&
            FIELD("inc_tsum", e.incoherent_t_sum))
            out[n++] = e;
#undef FIELD
    }
    fclose(f);
    return n;
}

static const embree_figures *embree_find(const embree_figures *e, int n, int triangles)
{
    for (int i = 0; i < n; i++)
        if (e[i].triangles == triangles)
            return &e[i];
    return NULL;
}

/* ---- the teapot in a stadium ----------------------------------------------------
 * The uniform grid's failure case (lecture 14): a dense mesh (the "teapot",
 * 81920 triangles of a unit sphere) in a huge, nearly empty scene (the
 * stadium, 10 triangles 200 x 50 x 200 units). Cells sized for the average
 * density are enormous beside the teapot, so the teapot falls into one or a
 * few cells and every ray that reaches it tests thousands of triangles. The
 * tori field of about the same size, where triangles are spread evenly, is
 * the control. Rays are aimed at random triangles (accel_aimed_rays), so
 * almost all of them go to the teapot. The grid is run at several cell
 * densities C: a finer grid helps only slowly, and costs memory. */
static void stadium_study(const char *path, int reps, int max_rays)
{
    /* Put in place only when complete (atomic_file.h). */
    char err[1024];
    atomic_file out;
    if (!atomic_file_open(&out, path, err, sizeof err)) {
        fprintf(stderr, "bench_accel: %s\n", err);
        exit(1);
    }
    FILE *csv = out.stream;
    fprintf(csv, "mesh,structure,density,triangles,build_ms,bytes_per_triangle,boxes_per_ray,triangles_per_ray,"
                 "mrays\n");
    printf("\nteapot in a stadium: rays aimed at random triangles, closest hit, 1 thread\n");
    printf("%-8s %-10s %7s %9s %9s %9s %12s %12s %9s\n", "mesh", "structure", "C", "triangles", "build ms", "B/tri",
           "boxes/ray", "tris/ray", "Mrays/s");
    static const float densities[] = {1, 3, 9, GRID_DEFAULT_DENSITY, 81, 243};
    enum { DENSITIES = sizeof densities / sizeof densities[0], RAYS = 1 << 13 };
    for (int which = 0; which < 2; which++) {
        const char *mesh_name = which == 0 ? "tori" : "stadium";
        mesh m;
        mesh_init(&m);
        if (which == 0)
            mesh_tori_field(&m, 81920);
        else
            mesh_teapot_in_stadium(&m, 6, 200.0f);
        triangle_set set;
        triangle_set_from_mesh(&set, &m);
        int ray_count = RAYS < max_rays ? RAYS : max_rays;
        ray_set rays = {ray_count, accel_aimed_rays(&set, ray_count, 2026)};
        /* the grid at every density, then the hierarchies at their defaults */
        for (int k = 0; k < DENSITIES + STRUCTURE_COUNT; k++) {
            accel *a;
            float density = 0.0f;
            bool stream = false;
            const char *name;
            if (k < DENSITIES) {
                density = densities[k];
                a = grid_build(&set, density);
                name = "grid";
            } else {
                const structure *st = &structures[k - DENSITIES];
                if (strcmp(st->name, "brute") == 0 || strcmp(st->name, "flat") == 0 || strcmp(st->name, "grid") == 0)
                    continue;
                a = st->build(&set);
                name = st->name;
                stream = st->stream;
            }
            trace(a, &rays, rays.count, true, 1, stream); /* warm-up */
            trace_result r = trace_median(a, &rays, rays.count, true, 1, reps, stream);
            double boxes = (double)r.counters.box_tests / rays.count;
            double tris = (double)r.counters.primitive_tests / rays.count;
            double mrays = rays.count / r.seconds * 1e-6;
            double bytes = (double)a->stats.bytes / set.count;
            printf("%-8s %-10s %7.0f %9d %9.1f %9.1f %12.1f %12.1f %9.3f\n", mesh_name, name, (double)density,
                   set.count, a->stats.build_seconds * 1e3, bytes, boxes, tris, mrays);
            fprintf(csv, "%s,%s,%g,%d,%.3f,%.2f,%.3f,%.3f,%.5f\n", mesh_name, name, (double)density, set.count,
                    a->stats.build_seconds * 1e3, bytes, boxes, tris, mrays);
            fflush(stdout);
            accel_destroy(a);
        }
        free(rays.rays);
        triangle_set_free(&set);
        mesh_free(&m);
    }
    if (!atomic_file_commit(&out, err, sizeof err)) {
        fprintf(stderr, "bench_accel: %s\n", err);
        exit(1);
    }
    printf("wrote %s\n", path);
}

/* ---- main ---------------------------------------------------------------------- */

static void usage(void)
{
    printf("usage: bench_accel [--sizes 1024,10240,102400,1048576] [--only NAME,...] [--reps N]\n"
           "                   [--threads N] [--out FILE.csv] [--embree FILE] [--stadium FILE.csv]\n"
           "                   [--compare-only] [--tests-csv FILE.csv] [--max-rays N]\n\n"
           "Times every acceleration structure on the tori field of ../shared/anchors/embree_bench.c,\n"
           "with the harness's coherent and incoherent ray sets: build ms, bytes per triangle, and\n"
           "Mrays/s for closest hit and any hit, on one thread and on all; --out also writes them as\n"
           "CSV (make bench: build/data/accel.csv, which make plots draws). --embree reads the\n"
           "harness's output ('embree_bench embree N medium T R' lines) and prints ratios.\n"
           "--stadium also runs the teapot in a stadium (the grid at several C, every hierarchy)\n"
           "and writes its figures to FILE.csv.\n"
           "After each size's table, every structure is timed again with the watertight triangle test and\n"
           "with Moller-Trumbore, alternately, on one thread (--compare-only: that table alone; --tests-csv\n"
           "writes it as CSV).\n"
           "--max-rays N traces at most N rays of each set (a strided subset, as brute force gets):\n"
           "a rough run in seconds, which make plots uses when make bench has not run.\n"
           "structures: brute flat grid kdtree bvh-median bvh-sah wide-bvh-sah wide-bvh-quantized wide-bvh-stream\n"
           "(flat: brute force, 8 triangles per AVX instruction; wide-bvh-sah: chapter 13's tree, exact nodes;\n"
           "wide-bvh-quantized: the same tree with its child boxes as bytes on a grid; wide-bvh-stream:\n"
           "wide-bvh-sah's tree, rays traced 16 at a time, taking turns: wide_bvh_closest_hit_stream)\n");
}

int main(int argc, char **argv)
{
    long sizes[8] = {1024, 10240, 102400, 1048576};
    int size_count = 4, reps = 3, threads = 1, build_threads = 1, max_rays = 1 << 30; /* builds use every thread */
    const char *out_path = NULL, *embree_path = NULL, *only = NULL, *stadium_path = NULL, *tests_path = NULL;
    bool compare_only = false;
#ifdef _OPENMP
    threads = build_threads = omp_get_max_threads();
#endif
    for (int i = 1; i < argc; i++) {
        const char *value = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(argv[i], "--help") == 0) {
            usage();
            return 0;
        } else if (strcmp(argv[i], "--sizes") == 0 && value) {
            size_count = 0;
            char *copy = strdup(value), *save = NULL;
            for (char *tok = strtok_r(copy, ",", &save); tok && size_count < 8; tok = strtok_r(NULL, ",", &save))
                sizes[size_count++] = atol(tok);
            free(copy);
            i++;
        } else if (strcmp(argv[i], "--only") == 0 && value) {
            only = value;
            i++;
        } else if (strcmp(argv[i], "--reps") == 0 && value && atoi(value) > 0) {
            reps = atoi(value);
            i++;
        } else if (strcmp(argv[i], "--max-rays") == 0 && value && atoi(value) > 0) {
            max_rays = atoi(value);
            i++;
        } else if (strcmp(argv[i], "--threads") == 0 && value && atoi(value) > 0) {
            threads = atoi(value);
            i++;
        } else if (strcmp(argv[i], "--out") == 0 && value) {
            out_path = value;
            i++;
        } else if (strcmp(argv[i], "--stadium") == 0 && value) {
            stadium_path = value;
            i++;
        } else if (strcmp(argv[i], "--compare-only") == 0) {
            compare_only = true;
        } else if (strcmp(argv[i], "--tests-csv") == 0 && value) {
            tests_path = value;
            i++;
        } else if (strcmp(argv[i], "--embree") == 0 && value) {
            embree_path = value;
            i++;
        } else {
            fprintf(stderr, "bench_accel: unknown or incomplete argument '%s' (try --help)\n", argv[i]);
            return 2;
        }
    }
    embree_figures embree[8];
    int embree_count = embree_path ? embree_load(embree_path, embree, 8) : 0;
    FILE *tests_csv = NULL;
    char tests_temp[4096] = "";
    if (tests_path != NULL) {
        snprintf(tests_temp, sizeof tests_temp, "%s.part", tests_path);
        if ((tests_csv = fopen(tests_temp, "w")) == NULL) {
            fprintf(stderr, "bench_accel: cannot write '%s'\n", tests_path);
            return 1;
        }
        fprintf(tests_csv, "structure,triangles,workload,watertight_mrays,moller_trumbore_mrays,"
                           "watertight_cpu_mrays,moller_trumbore_cpu_mrays,watertight_hits,moller_trumbore_hits\n");
    }

    /* The CSV only with --out: a quick run of one structure must not replace
     * the full benchmark's figures that `make plots` draws. Written to a
     * temporary file and renamed at the end (atomic_file.h), so an
     * interrupted run leaves the old file whole. */
    char err[1024];
    atomic_file out;
    FILE *csv = NULL;
    if (out_path != NULL) {
        if (!atomic_file_open(&out, out_path, err, sizeof err)) {
            fprintf(stderr, "bench_accel: %s\n", err);
            return 1;
        }
        csv = out.stream;
    }
    if (csv != NULL)
        fprintf(csv, "structure,triangles,build_ms,bytes_per_triangle,nodes,leaves,max_depth,threads,"
                 "coherent_closest_mrays,coherent_any_mrays,incoherent_closest_mrays,incoherent_any_mrays,"
                 "coherent_closest_mrays_all,incoherent_closest_mrays_all,"
                 "boxes_per_ray,triangles_per_ray,coherent_hits,incoherent_hits,node_bytes\n");
    /* Embree's own figures go into the same CSV, so plots draw it beside ours. */
    for (int i = 0; i < embree_count; i++)
        if (csv != NULL)
            fprintf(csv, "embree,%d,%.3f,,,,,%d,%.4f,%.4f,%.4f,%.4f,,,,,,,\n", embree[i].triangles,
                    embree[i].build_ms, embree[i].threads, embree[i].coherent_closest, embree[i].coherent_any,
                    embree[i].incoherent_closest, embree[i].incoherent_any);
    printf("%-10s %9s %9s %7s | %-23s | %-23s | %-15s | %s\n", "structure", "triangles", "build ms", "B/tri",
           "coherent Mrays/s 1 thr", "incoherent Mrays/s 1 thr", "closest, all thr", "tests/ray (inc.)");
    printf("%-10s %9s %9s %7s | %11s %11s | %11s %11s | %7s %7s |\n", "", "", "", "", "closest", "any", "closest",
           "any", "coh", "inc");

    for (int s = 0; s < size_count; s++) {
        mesh m;
        mesh_init(&m);
        mesh_tori_field(&m, sizes[s]);
        triangle_set set;
        triangle_set_from_mesh(&set, &m);
        ray_set coherent, incoherent;
        coherent.rays = accel_harness_rays(set.bounds, true, &coherent.count);
        incoherent.rays = accel_harness_rays(set.bounds, false, &incoherent.count);
        const embree_figures *e = embree_find(embree, embree_count, set.count);
        double closest_mrays[STRUCTURE_COUNT][2] = {{0}}; /* coherent, incoherent, one thread */
        test_comparison comparisons[STRUCTURE_COUNT];
        bool compared[STRUCTURE_COUNT] = {false};

        for (int k = 0; k < STRUCTURE_COUNT; k++) {
            const structure *st = &structures[k];
            if (only != NULL && strstr(only, st->name) == NULL)
                continue;
            if (set.count > st->max_triangles)
                continue;
            /* Build: the median of `reps` builds, keeping the last. */
            double build_times[16];
            accel *a = NULL;
            for (int r = 0; r < reps && r < 16; r++) {
                accel_destroy(a);
                a = st->build(&set);
                build_times[r] = a->stats.build_seconds;
            }
            int build_reps = reps < 16 ? reps : 16;
            qsort(build_times, (size_t)build_reps, sizeof(double), compare_doubles);
            double build_ms = 1e3 * build_times[build_reps / 2];

            /* every structure on the whole set (up to --max-rays) but brute force */
            int ray_count = st->max_rays < max_rays ? st->max_rays : max_rays;
            bool whole = ray_count >= coherent.count || ray_count == max_rays;
            ray_set coh = ray_subset(&coherent, ray_count), inc = ray_subset(&incoherent, ray_count);
            bool stream = st->stream;
            comparisons[k] = compare_triangle_tests(a, &coh, &inc, reps, stream);
            compared[k] = true;
            if (compare_only) {
                if (coh.rays != coherent.rays)
                    free(coh.rays);
                if (inc.rays != incoherent.rays)
                    free(inc.rays);
                accel_destroy(a);
                continue;
            }
            trace(a, &coh, coh.count, true, 1, stream); /* warm-up, not counted */
            trace_result cc = trace_median(a, &coh, coh.count, true, 1, reps, stream);
            trace_result ca = trace_median(a, &coh, coh.count, false, 1, reps, stream);
            trace_result ic = trace_median(a, &inc, inc.count, true, 1, reps, stream);
            trace_result ia = trace_median(a, &inc, inc.count, false, 1, reps, stream);
            trace_result cc_all = trace_median(a, &coh, coh.count, true, threads, reps, stream);
            trace_result ic_all = trace_median(a, &inc, inc.count, true, threads, reps, stream);
            double mrays_cc = coh.count / cc.seconds * 1e-6, mrays_ca = coh.count / ca.seconds * 1e-6;
            double mrays_ic = inc.count / ic.seconds * 1e-6, mrays_ia = inc.count / ia.seconds * 1e-6;
            double mrays_cc_all = coh.count / cc_all.seconds * 1e-6, mrays_ic_all = inc.count / ic_all.seconds * 1e-6;
            /* The counters of one trace of the incoherent set (every rep counts the same). */
            double boxes = (double)ic.counters.box_tests / inc.count;
            double tris = (double)ic.counters.primitive_tests / inc.count;
            double bytes_per_triangle = (double)a->stats.bytes / set.count;
            /* a node's bytes: the wide BVH's by layout (chapter 13), else 0 */
            size_t node_bytes = !wide_bvh_is(a)                                           ? 0
                                : ((const wide_bvh *)a)->layout == WIDE_BVH_QUANTIZED ? sizeof(wide_bvh_qnode)
                                                                                      : sizeof(wide_bvh_node);

            printf("%-10s %9d %9.2f %7.1f | %11.3f %11.3f | %11.3f %11.3f | %7.3f %7.3f | %.1f boxes, %.1f tris",
                   st->name, set.count, build_ms, bytes_per_triangle, mrays_cc, mrays_ca, mrays_ic, mrays_ia,
                   mrays_cc_all, mrays_ic_all, boxes, tris);
            if (node_bytes > 0)
                printf(", %d nodes of %zu B", a->stats.nodes, node_bytes);
            printf("\n");
            if (e != NULL && ray_count >= coherent.count)
                /* Ratios to Embree, and a check that both did the same work:
                 * the sums of closest-hit t agree to a few parts per million
                 * (Embree's watertight triangle test and ours differ only at
                 * edges). */
                printf("%-10s %9s %8.2fx %7s | %10.2fx %10.2fx | %10.2fx %10.2fx | ratio to Embree "
                       "(build: time, %d threads and Embree's %d; trace: speed, one thread each) | t-sum differs by "
                       "%.1e / %.1e\n",
                       "", "", build_ms / e->build_ms, "", mrays_cc / e->coherent_closest, mrays_ca / e->coherent_any,
                       mrays_ic / e->incoherent_closest, mrays_ia / e->incoherent_any, build_threads, e->threads,
                       fabs(cc.t_sum - e->coherent_t_sum) / e->coherent_t_sum,
                       fabs(ic.t_sum - e->incoherent_t_sum) / e->incoherent_t_sum);
            if (csv != NULL)
                fprintf(csv, "%s,%d,%.3f,%.2f,%d,%d,%d,%d,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.3f,%.3f,%ld,%ld,%zu\n", st->name,
                    set.count, build_ms, bytes_per_triangle, a->stats.nodes, a->stats.leaves, a->stats.max_depth,
                    threads, mrays_cc, mrays_ca, mrays_ic, mrays_ia, mrays_cc_all, mrays_ic_all, boxes, tris, cc.hits,
                    ic.hits, node_bytes);
            if (whole) {
                closest_mrays[k][0] = mrays_cc;
                closest_mrays[k][1] = mrays_ic;
            }
            fflush(stdout);
            if (coh.rays != coherent.rays)
                free(coh.rays);
            if (inc.rays != incoherent.rays)
                free(inc.rays);
            accel_destroy(a);
        }
        /* The targets for the grid and the kd-tree are ratios to "our
         * BVH": the lecture's binary SAH BVH (bvh-sah), which like them is
         * scalar code testing one box or cell and one triangle at a time, so
         * the ratio compares the partitions, not the use of SIMD. */
        int reference = -1;
        for (int k = 0; k < STRUCTURE_COUNT; k++)
            if (strcmp(structures[k].name, "bvh-sah") == 0 && closest_mrays[k][0] > 0.0)
                reference = k;
        if (reference >= 0) {
            printf("closest hit, 1 thread, as a ratio to bvh-sah at %d triangles (coherent / incoherent):", set.count);
            for (int k = 0; k < STRUCTURE_COUNT; k++)
                if (closest_mrays[k][0] > 0.0)
                    printf(" %s %.2fx / %.2fx;", structures[k].name, closest_mrays[k][0] / closest_mrays[reference][0],
                           closest_mrays[k][1] / closest_mrays[reference][1]);
            printf("\n");
        }
        bool header = false;
        for (int k = 0; k < STRUCTURE_COUNT; k++)
            if (compared[k]) {
                if (!header)
                    print_comparison_header(reps);
                header = true;
                print_comparison(structures[k].name, set.count, &comparisons[k], tests_csv);
            }
        if (header)
            printf("\n");
        free(coherent.rays);
        free(incoherent.rays);
        triangle_set_free(&set);
        mesh_free(&m);
    }
    if (csv != NULL) {
        if (!atomic_file_commit(&out, err, sizeof err)) {
            fprintf(stderr, "bench_accel: %s\n", err);
            return 1;
        }
        printf("wrote %s\n", out_path);
    }
    if (tests_csv != NULL) {
        if (fclose(tests_csv) != 0 || rename(tests_temp, tests_path) != 0) {
            fprintf(stderr, "bench_accel: cannot write '%s'\n", tests_path);
            remove(tests_temp);
            return 1;
        }
        printf("wrote %s\n", tests_path);
    }
    if (stadium_path != NULL)
        stadium_study(stadium_path, reps, max_rays);
    return 0;
}
